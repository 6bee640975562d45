r"""Rich displays for Jupyter: models and solutions show themselves as tables.

IPython asks an object for ``_repr_html_``, ``_repr_markdown_`` and ``_repr_latex_`` and
shows the richest one its front end supports. :class:`~mechsys.Model` gives

* HTML: a summary line (kind, bodies, constraints, coordinates, equations, degrees of
  freedom from the Jacobian rank at the guess), a table of the bodies (number, name,
  coordinates, mass, points), a table of the constraints with their equations in LaTeX
  (``\(...\)``, typeset by the notebook's MathJax), the parameters and the loads;
* Markdown: the same as Markdown tables (for front ends without HTML);
* LaTeX: the constraint equations :math:`\Phi(q, T, p) = 0` as one ``aligned`` block.

:class:`~mechsys.Solution` gives a summary table: the time span, what was solved, the
iterations, and per coordinate its first and last value, range, and largest speed and
acceleration. Long models and solutions are cut (``MAX_ROWS`` rows, ``MAX_EQUATIONS``
equations) with a line saying how many were left out. Example::

    m = ms.models.slider_crank()
    m                       # in a notebook: the tables below the cell
    html = m._repr_html_()  # the same, as a string

A display never raises: what cannot be computed (the DOF of a model whose guess is
unusable, say) is shown as the error message in its cell.
"""

from __future__ import annotations

import html
import weakref

import numpy as np
import sympy as sp

from .._errors import MechError

MAX_ROWS = 60
MAX_EQUATIONS = 80

_dof_cache: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

_CSS = ("<style>.mechsys-repr table{border-collapse:collapse;margin:.3em 0}"
        ".mechsys-repr th,.mechsys-repr td{border:1px solid #ccc;padding:2px 8px;"
        "text-align:left;vertical-align:top}.mechsys-repr caption{text-align:left;"
        "font-weight:bold}</style>")


def _esc(x) -> str:
    return html.escape(str(x), quote=True)


def _num(v) -> str:
    return f"{float(v):.6g}"


def _model_dof(m):
    """``(DOF or None, error text)``, cached per model version (IPython asks for several
    representations of one object in a row; each would otherwise recompile)."""
    version = getattr(m, "_version", None)
    hit = _dof_cache.get(m)
    if hit is not None and hit[0] == version:
        return hit[1], hit[2]
    try:
        d, err = m.dof(), ""
    except (MechError, ValueError, ZeroDivisionError) as exc:
        d, err = None, f"{type(exc).__name__}: {exc}"
    _dof_cache[m] = (version, d, err)
    return d, err


def _equations(m):
    """``[(number, name, type, [equations] or error text)]``: each constraint, then in 3D
    each body's Euler-parameter normalisation (also an equation of the system)."""
    out = []
    for c in m.constraints:
        try:
            eqs = c.equations(m.space)
        except MechError as exc:
            eqs = f"{type(exc).__name__}: {exc}"
        out.append((c.number, c.name if c.name is not None else "", type(c).__name__, eqs))
    dim = m.space.dim
    for b in m.bodies[1:]:
        norm = list(m.space.body_normalization(b.q[dim:]))
        if norm:
            out.append(("", f"body {b.name}", "Euler normalisation", norm))
    return out


def _latex(e) -> str:
    return sp.latex(sp.sympify(e))


def _summary(m) -> tuple[str, str]:
    """The headline and the DOF line of a model."""
    kind = type(m).__name__
    nb, nc = len(m.bodies) - 1, len(m.constraints)
    head = f"{kind}: {nb} moving bod{'y' if nb == 1 else 'ies'}, {nc} constraint{'s' * (nc != 1)}"
    d, err = _model_dof(m)
    if d is None:
        return head, f"degrees of freedom: not available ({err})"
    line = (f"{d.coordinates} coordinates, {d.equations} equations, "
            f"{int(d)} degree{'s' * (int(d) != 1)} of freedom (Jacobian rank {d.rank} at the guess)")
    if d.redundant:
        line += "; redundant: " + ", ".join(c.label() for c in d.redundant)
    return head, line


def _body_rows(m):
    for b in m.bodies:
        coords = ", ".join(str(s) for s in b.q) if b.q else "fixed"
        pts = ", ".join(f"{k}" for k in b.points) if b.points else ""
        yield b.number, b.name, coords, b.mass, pts


def model_html(m) -> str:
    head, dof = _summary(m)
    out = [_CSS, '<div class="mechsys-repr">', f"<b>{_esc(head)}</b><br>{_esc(dof)}"]
    out += ["<table><caption>Bodies</caption><tr><th>#</th><th>name</th><th>coordinates</th>"
            "<th>mass</th><th>points</th></tr>"]
    rows = list(_body_rows(m))
    for num, name, coords, mass, pts in rows[:MAX_ROWS]:
        out.append(f"<tr><td>{num}</td><td>{_esc(name)}</td><td>{_esc(coords)}</td>"
                   f"<td>{_esc(mass)}</td><td>{_esc(pts)}</td></tr>")
    out.append("</table>")
    if len(rows) > MAX_ROWS:
        out.append(f"<i>... {len(rows) - MAX_ROWS} more bodies</i>")
    out += ["<table><caption>Constraints</caption><tr><th>#</th><th>name</th><th>type</th>"
            "<th>equations \\(\\Phi = 0\\)</th></tr>"]
    shown = 0
    for num, name, kind, eqs in _equations(m):
        if isinstance(eqs, str):
            cell = _esc(eqs)
        else:
            take = eqs[:max(0, MAX_EQUATIONS - shown)]
            shown += len(take)
            cell = "<br>".join(f"\\({_esc(_latex(e))} = 0\\)" for e in take)
            if len(take) < len(eqs):
                cell += f"<br><i>... {len(eqs) - len(take)} more</i>"
        out.append(f"<tr><td>{num}</td><td>{_esc(name)}</td>"
                   f"<td>{_esc(kind)}</td><td>{cell}</td></tr>")
    out.append("</table>")
    params = m.parameters
    if params:
        out.append("<table><caption>Parameters</caption><tr><th>name</th><th>value</th></tr>")
        out += [f"<tr><td>{_esc(k)}</td><td>{_num(v)}</td></tr>" for k, v in params.items()]
        out.append("</table>")
    loads = m.load_list
    if loads:
        out.append("<table><caption>Loads</caption><tr><th>load</th></tr>")
        out += [f"<tr><td>{_esc(_load_label(ld))}</td></tr>" for ld in loads]
        out.append("</table>")
    out.append("</div>")
    return "\n".join(out)


def _load_label(ld) -> str:
    label = getattr(ld, "label", None)
    return label() if callable(label) else repr(ld)


def _md_cell(x) -> str:
    return str(x).replace("|", "\\|").replace("\n", " ")


def model_markdown(m) -> str:
    head, dof = _summary(m)
    out = [f"**{head}**  ", dof, "", "| # | body | coordinates | mass | points |",
           "| --- | --- | --- | --- | --- |"]
    for num, name, coords, mass, pts in list(_body_rows(m))[:MAX_ROWS]:
        out.append(f"| {num} | {_md_cell(name)} | {_md_cell(coords)} | {_md_cell(mass)} | "
                   f"{_md_cell(pts)} |")
    out += ["", "| # | constraint | type | equations |", "| --- | --- | --- | --- |"]
    for num, name, kind, eqs in _equations(m)[:MAX_ROWS]:
        cell = eqs if isinstance(eqs, str) else "<br>".join(
            f"${_latex(e)} = 0$" for e in eqs[:MAX_EQUATIONS])
        out.append(f"| {num} | {_md_cell(name)} | {kind} | {_md_cell(cell)} |")
    if m.parameters:
        out += ["", "Parameters: " + ", ".join(f"`{k} = {_num(v)}`" for k, v in m.parameters.items())]
    return "\n".join(out)


def model_latex(m) -> str:
    r"""The equations of the system as ``$$\begin{aligned} ... \end{aligned}$$``, each
    labelled with its constraint number and equation (``(2.1)``), in 3D followed by each
    body's Euler-parameter normalisation (labelled with the body)."""
    lines = []
    for num, name, _kind, eqs in _equations(m):
        if isinstance(eqs, str):
            continue
        for k, e in enumerate(eqs):
            if len(lines) >= MAX_EQUATIONS:
                break
            tag = f"{num}.{k + 1}" if num != "" else name
            lines.append(f"{_latex(e)} &= 0 &&\\text{{({tag})}}")
    if not lines:
        return "$\\text{no constraints}$"
    return "$$\\begin{aligned}\n" + " \\\\\n".join(lines) + "\n\\end{aligned}$$"


# -- solutions ----------------------------------------------------------------------------

def _solved(sol) -> str:
    orders = ["location"]
    if sol.qd is not None:
        orders.append("velocity")
    if sol.qdd is not None:
        orders.append("acceleration")
    if getattr(sol, "lam", None) is not None:
        orders.append("multipliers")
    return ", ".join(orders)


def _solution_rows(sol):
    """Per coordinate: name, first, last, min, max, max |qd|, max |qdd|."""
    q = np.atleast_2d(sol.q)
    qd = None if sol.qd is None else np.atleast_2d(sol.qd)
    qdd = None if sol.qdd is None else np.atleast_2d(sol.qdd)
    for j, name in enumerate(sol.names):
        col = q[:, j]
        yield (name, col[0], col[-1], col.min(), col.max(),
               None if qd is None else np.abs(qd[:, j]).max(),
               None if qdd is None else np.abs(qdd[:, j]).max())


def _solution_head(sol) -> str:
    t = np.atleast_1d(sol.t)
    span = f"t in [{_num(t.min())}, {_num(t.max())}]" if len(t) else "no time points"
    its = int(np.sum(sol.iterations)) if sol.iterations is not None else 0
    return (f"Solution: {len(t)} time point{'s' * (len(t) != 1)}, {span}; solved: {_solved(sol)}; "
            f"{len(sol.names)} coordinates; Newton iterations {its}; {sol.message}")


def solution_html(sol) -> str:
    out = [_CSS, '<div class="mechsys-repr">', f"<b>{_esc(_solution_head(sol))}</b>",
           "<table><tr><th>coordinate</th><th>first</th><th>last</th><th>min</th><th>max</th>"
           "<th>max |velocity|</th><th>max |acceleration|</th></tr>"]
    rows = list(_solution_rows(sol))
    for name, *vals in rows[:MAX_ROWS]:
        cells = "".join(f"<td>{'' if v is None else _num(v)}</td>" for v in vals)
        out.append(f"<tr><td>{_esc(name)}</td>{cells}</tr>")
    out.append("</table>")
    if len(rows) > MAX_ROWS:
        out.append(f"<i>... {len(rows) - MAX_ROWS} more coordinates</i>")
    out.append("</div>")
    return "\n".join(out)


def solution_markdown(sol) -> str:
    out = [f"**{_solution_head(sol)}**", "",
           "| coordinate | first | last | min | max | max \\|velocity\\| | max \\|acceleration\\| |",
           "| --- | --- | --- | --- | --- | --- | --- |"]
    for name, *vals in list(_solution_rows(sol))[:MAX_ROWS]:
        out.append(f"| {_md_cell(name)} | " + " | ".join(
            "" if v is None else _num(v) for v in vals) + " |")
    return "\n".join(out)
