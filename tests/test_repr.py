"""Jupyter rich displays: Model (bodies, constraints, DOF, LaTeX equations), Solution (a
summary table whose numbers are the solution's), the inline viewer and animation player."""

import html
import re
from html.parser import HTMLParser

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import models
from mechsys.results import _repr


class _Tables(HTMLParser):
    """Rows of every <table> as lists of cell texts."""

    def __init__(self):
        super().__init__()
        self.tables, self._cell = [], None

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.tables[-1][-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _tables(text):
    p = _Tables()
    p.feed(text)
    return p.tables


@pytest.fixture(scope="module")
def crank():
    m = models.slider_crank()
    return m, m.solve(np.linspace(0, 0.8, 9))


def test_model_html_lists_bodies_constraints_and_dof(crank):
    m, _ = crank
    text = m._repr_html_()
    bodies, constraints = _tables(text)[:2]
    assert [r[1] for r in bodies[1:]] == [b.name for b in m.bodies]
    assert bodies[2][2] == ", ".join(str(s) for s in m.body("crank").q)
    assert [r[1] for r in constraints[1:]] == [c.name for c in m.constraints]
    assert [r[2] for r in constraints[1:]] == [type(c).__name__ for c in m.constraints]
    d = m.dof()
    assert f"{d.coordinates} coordinates, {d.equations} equations, 0 degrees of freedom" in text
    # each equation as LaTeX, in the notebook's inline-math delimiters
    for c in m.constraints:
        for e in c.equations(m.space):
            assert f"\\({html.escape(sp.latex(e))} = 0\\)" in text


def test_model_latex_is_every_equation_once(crank):
    m, _ = crank
    tex = m._repr_latex_()
    assert tex.startswith("$$\\begin{aligned}") and tex.endswith("\\end{aligned}$$")
    eqs = [e for c in m.constraints for e in c.equations(m.space)]
    rows = tex.split("\\\\\n")
    assert len(rows) == len(eqs) == m.dof().equations
    for row, e, tag in zip(rows, eqs, ["1.1", "1.2", "2.1", "2.2", "3.1", "3.2", "4.1", "4.2", "5.1"]):
        assert sp.latex(e) in row and f"\\text{{({tag})}}" in row


def test_model_markdown_and_underconstrained_dof():
    m = models.slider_crank()
    m.remove("drive")
    md = m._repr_markdown_()
    assert "1 degree of freedom" in md and "4 constraints" in md
    assert md.count("| Revolute2 |") == 3
    assert "$- x_{2} = 0$" in md                    # the crank pin's first equation


def test_dof_is_computed_once_per_model_version(monkeypatch):
    m = models.slider_crank()
    calls = []
    real = m.dof
    monkeypatch.setattr(m, "dof", lambda: calls.append(1) or real())
    m._repr_html_()
    m._repr_markdown_()
    assert len(calls) == 1                           # IPython asks for several formats
    m.remove("drive")                                # a new model version: recounted
    assert "1 degree of freedom" in m._repr_html_()
    assert len(calls) == 2


def test_model_display_does_not_raise_when_dof_fails(monkeypatch):
    m = models.slider_crank()

    def broken():
        raise ms.ModelError("body 'rod' has no guess")

    monkeypatch.setattr(m, "dof", broken)
    text = m._repr_html_()
    assert "degrees of freedom: not available (ModelError: body &#x27;rod&#x27; has no guess)" in text


def test_solution_table_holds_the_solution_numbers(crank):
    _, sol = crank
    (table,) = _tables(sol._repr_html_())
    assert table[0] == ["coordinate", "first", "last", "min", "max", "max |velocity|",
                        "max |acceleration|"]
    assert [r[0] for r in table[1:]] == list(sol.names)
    for j, row in enumerate(table[1:]):
        got = np.array([float(v) for v in row[1:]])
        want = [sol.q[0, j], sol.q[-1, j], sol.q[:, j].min(), sol.q[:, j].max(),
                np.abs(sol.qd[:, j]).max(), np.abs(sol.qdd[:, j]).max()]
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-12)
    head = sol._repr_html_()
    assert "9 time points, t in [0, 0.8]; solved: location, velocity, acceleration" in head


def test_solution_markdown_location_only():
    m = models.slider_crank()
    sol = m.solve(np.linspace(0, 0.5, 3), solution="location")
    md = sol._repr_markdown_()
    assert "solved: location;" in md
    row = next(r for r in md.splitlines() if r.startswith("| piston.x |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    x = sol.q[:, sol.names.index("piston.x")]
    np.testing.assert_allclose([float(c) for c in cells[1:5]], [x[0], x[-1], x.min(), x.max()],
                               rtol=1e-5)
    assert cells[5:] == ["", ""]                     # no velocity or acceleration solved


def test_long_tables_are_cut(monkeypatch):
    monkeypatch.setattr(_repr, "MAX_ROWS", 2)
    m = models.slider_crank()
    sol = m.solve(0.1, solution="location")
    assert "... 7 more coordinates" in sol._repr_html_()
    assert "... 2 more bodies" in m._repr_html_()


def test_viewer_shows_itself_inline(crank):
    _, sol = crank
    v = ms.draw.viewer(sol, size=(400, 250), title="crank <demo>")
    assert isinstance(v, str) and v.startswith("<!DOCTYPE html>")
    frame = v._repr_html_()
    m = re.fullmatch(r'<iframe class="mechsys-viewer" srcdoc="([^"]*)" title="mechsys viewer" '
                     r'style="width: 420px; height: 310px; [^"]*" sandbox="allow-scripts"></iframe>',
                     frame)
    assert m, frame[:300]
    assert html.unescape(m.group(1)) == str(v)       # the whole page, escaped once
    assert len(repr(v)) < 120                        # the text form is not the page
    full = ms.draw.viewer(sol)._repr_html_()
    assert "width: 100%; height: 440px" in full


def test_animation_is_an_inline_javascript_player(crank):
    _, sol = crank
    anim = ms.draw.animate(sol, frames=5, dpi=30)
    player = anim._repr_html_()
    assert player.count("data:image/png;base64") == 5     # one embedded frame each
    assert "<script" in player and "Animation" in player
    anim.close()


def test_spatial_model_lists_the_euler_normalisations():
    m = ms.Model3D()
    top = m.add_body("top", points={"tip": (0, 0, 0)}, guess=((0, 0, 0), (1, 0, 0, 0)))
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), top.point("tip")), name="ball")
    d = m.dof()
    assert (d.coordinates, d.equations, int(d)) == (7, 4, 3)
    text = m._repr_html_()
    assert "7 coordinates, 4 equations, 3 degrees of freedom" in text
    rows = _tables(text)[1][1:]
    assert [r[1:3] for r in rows] == [["ball", "Spherical3"], ["body top", "Euler normalisation"]]
    tex = m._repr_latex_()
    assert len(tex.split("\\\\\n")) == d.equations            # every equation of the system
    (norm,) = m.space.body_normalization(top.q[3:])
    assert f"{sp.latex(norm)} &= 0 &&\\text{{(body top)}}" in tex
