"""The example notebook runs top to bottom in a Jupyter kernel and shows the rich displays."""

import os
from pathlib import Path

import nbclient
import nbformat
import pytest

pytestmark = pytest.mark.jupyter_kernel

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "notebooks" / "first_model.ipynb"


@pytest.fixture(scope="module")
def executed(tmp_path_factory):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(nb)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), (
        "commit the notebook without outputs")
    cwd = tmp_path_factory.mktemp("nb")
    src = str(Path(__file__).resolve().parents[1] / "src")
    path = os.pathsep.join([src] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))
    env = dict(os.environ, PYTHONPATH=path, MPLBACKEND="Agg")
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(cwd)}})
    client.execute(env=env)           # raises CellExecutionError if any cell fails
    return [c for c in nb.cells if c.cell_type == "code"]


def _data(cell):
    (out,) = [o for o in cell.outputs if o.output_type == "execute_result"]
    return out["data"]


def test_model_cell_shows_tables_and_latex(executed):
    data = _data(executed[0])
    assert {"text/html", "text/markdown", "text/latex"} <= set(data)
    assert "Model2D: 3 moving bodies, 5 constraints" in data["text/html"]
    assert "9 coordinates, 9 equations, 0 degrees of freedom" in data["text/html"]
    assert data["text/latex"].count("&= 0") == 9


def test_solution_cell_shows_the_summary(executed):
    html = _data(executed[1])["text/html"]
    assert "41 time points, t in [0, 1]" in html and "piston.x" in html


def test_stroke_cell_prints_the_closed_form(executed):
    (out,) = executed[2].outputs
    assert out["text"].strip() == "piston stroke 4.000000 (twice the crank: 4)"


def test_animation_and_viewer_are_inline(executed):
    anim = _data(executed[3])["text/html"]
    assert anim.count("data:image/png;base64") == 12
    view = _data(executed[4])
    assert view["text/html"].startswith('<iframe class="mechsys-viewer" srcdoc="&lt;!DOCTYPE html&gt;')
    assert view["text/plain"].startswith("<ViewerHTML:")
