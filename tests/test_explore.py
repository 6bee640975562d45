"""The design loop (issue 38, item 4): parameter sliders that re-solve and redraw. The four-bar
example checks each redrawn coupler curve against its closed form (tests/test_examples.py runs
it); here the panel is driven in a real Jupyter kernel (headless, nbclient), where the
picture lands in the widget's output area, and bad input meets named errors."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import mechsys as ms

pytest.importorskip("ipywidgets")
ROOT = Path(__file__).resolve().parents[1]


def _example():
    import importlib.util

    spec = importlib.util.spec_from_file_location("fbs", ROOT / "examples" / "four_bar_sliders.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_sliders_follow_the_closed_form_and_keep_the_branch():
    fbs = _example()
    m = fbs.build()
    t = np.linspace(0, 2 * np.pi, 37)
    P = m.body("coupler").point("P")
    ex = ms.draw.explore(m, t, parameters={"crank": (0.5, 2.5), "coupler": (3.0, 5.0, 0.1)})
    assert ex.sliders["coupler"].step == pytest.approx(0.1) and ex.redraws == 1
    ex.sliders["crank"].value = 1.2          # as a drag would: one solve, one picture
    assert ex.redraws == 2 and m.parameters["crank"] == 1.2
    assert np.abs(ex.solution.location(P) - fbs.coupler_curve(1.2, 4.0, t)).max() < 1e-9


@pytest.mark.parametrize("kw, match", [
    ({"parameters": {"rocker": (1, 2)}}, "'rocker' is not a parameter"),
    ({"parameters": {"crank": (2, 3)}}, "outside its range"),
    ({"parameters": {"crank": (1.5, 0.5)}}, "min < max"),
    ({"parameters": {"crank": (0.5, np.nan)}}, "finite"),
    ({"parameters": {"crank": "wide"}}, "range of 'crank'"),
])
def test_bad_ranges_are_named(kw, match):
    m = _example().build()
    with pytest.raises(ms.ModelError, match=match):
        ms.draw.explore(m, [0.0, 1.0], **kw)


def test_a_model_without_parameters_is_refused():
    from mechsys import models

    with pytest.raises(ms.ModelError, match="no parameters"):
        ms.draw.explore(models.slider_crank(), [0.0])


@pytest.mark.jupyter_kernel
def test_panel_in_a_jupyter_kernel(tmp_path):
    nbclient = pytest.importorskip("nbclient")
    nbformat = pytest.importorskip("nbformat")
    code = [
        "import sys, numpy as np, mechsys as ms\n"
        f"sys.path.insert(0, {str(ROOT / 'examples')!r})\n"
        "import four_bar_sliders as fbs\n"
        "m = fbs.build()\n"
        "ex = ms.draw.explore(m, np.linspace(0, 6.3, 37), parameters={'crank': (0.5, 2.5)},\n"
        "                     graphics=[ms.draw.LocusPlot(m.body('coupler').point('P'))])\n"
        "ex",
        "ex.set(crank=1.4)\nprint(ex.redraws, len(ex.output.outputs), ex.message[:6])",
    ]
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in code])
    src = str(ROOT / "src")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [src, os.environ.get("PYTHONPATH")])),
               MPLBACKEND="Agg")
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute(env=env)
    (shown,) = [o for o in nb.cells[0].outputs if o.output_type == "execute_result"]
    assert "application/vnd.jupyter.widget-view+json" in shown["data"]
    printed = "".join(o.get("text", "") for o in nb.cells[1].outputs)
    assert printed.split() == ["2", "1", "solved"]   # two pictures, the output area holds one
