r"""Generate ``docs/constraints.md`` from the constraint registry.

Usage: ``python -m mechsys._docgen docs/constraints.md`` (what ``make docs`` runs); without an
argument the page is printed. The page lists every type in
:data:`mechsys.constraints.REGISTRY`: its Mech name, the model kinds it works in (from
``cls.spaces``), the degrees of freedom it removes, its call signature (from ``__init__``)
and its docstring, which carries the equations. A test compares the committed page with
freshly generated output, so a new constraint type shows up in the docs by registering it.

The docstrings write their equations as reStructuredText maths (a ``.. math::`` block of
LaTeX, one equation a line aligned on ``&=``, and ``:math:`` in sentences), which the API
pages typeset (decision 0049); this page shows each block as displayed maths
(``$$ \begin{aligned} ... $$``, rendered by MathJax on the site and by GitHub). A docstring
still written in the older plain-text notation (``u_1 . (r_2 - r_1) = 0``, ``u x d - dist
|u| = 0``: a constraint type registered by a user, say) is typeset by
:func:`equation_to_latex`.
"""

from __future__ import annotations

import inspect
import re
import sys
import textwrap
from pathlib import Path

_KINDS = {"planar": "2D", "spatial": "3D"}

HEADER = r"""# Constraint reference

<!-- Generated from mechsys.constraints.REGISTRY by `python -m mechsys._docgen
docs/constraints.md` (`make docs`). Do not edit by hand: edit the docstrings. -->

Every constraint type of mechsys, under its Mech name. Each is a small set of scalar
equations $\Phi(q, T, p) = 0$ built from the geometry of (usually) two bodies, listed in
Mech's order. Add one to a model with `m.add(constraint, name=...)`; see the
[user guide](guide.md#constraints) for how points, vectors and axes are given.

Notation in the equations: $r_1$, $r_2$ global positions of the points, $u_1$, $u_2$ global
directions of the vectors or axes, $d$ a difference of positions, $a \cdot b$ the dot
product, $a \times b$ the cross product ($a_x b_y - a_y b_x$, a scalar, in 2D), $\lvert u \rvert$
a length, $\hat u$ a unit vector, $\theta$ a planar body angle. A plain coordinate tuple
where a point is expected is a point on ground; where a vector is expected, a global
direction. The docstrings (`help(ms.Revolute2)`) and the API pages carry the same equations.

"DOF removed" is the number of equations minus the number of new variables the constraint
introduces; a driver (an expression of `T` in any scalar argument) removes the same number.
The rolling constraints (`RollingDisk2`, `RollingSphere2`, `RollingCircle1`) are *velocity*
constraints, linear in the velocities: their equations go to a path system
([nonholonomic.md](nonholonomic.md)), and their position part is `roll.holonomic()`.
"""


def _kinds(cls) -> str:
    return ", ".join(_KINDS.get(s, s) for s in cls.spaces)


def _dof(cls) -> str:
    n = getattr(cls, "dof_removed", None)
    return str(n) if n is not None else "equations - new variables"


def _signature(name: str, cls) -> str:
    call = getattr(cls, "_call", None)        # cams parse Mech's variable argument list
    if isinstance(call, str) and call.startswith("("):
        return f"{name}{call}"
    sig = inspect.signature(cls.__init__)
    params = [p for p in sig.parameters.values() if p.name != "self"]
    return f"{name}{sig.replace(parameters=params, return_annotation=inspect.Signature.empty)}"


def _public_path(cls) -> str:
    """``mechsys.Name`` when exported at the top level, else its public package."""
    import mechsys

    if getattr(mechsys, cls.__name__, None) is cls:
        return f"mechsys.{cls.__name__}"
    public = []
    for part in cls.__module__.split("."):
        if part.startswith("_"):
            break
        public.append(part)
    return ".".join([*public, cls.__name__])


def _inline(text: str) -> str:
    """reStructuredText inline markup -> Markdown (``:math:`x``` -> ``$x$``)."""
    text = re.sub(r":math:`([^`]+)`", r"$\1$", text)
    text = re.sub(r":(?:class|func|meth|attr|data|mod):`~?([^`]+)`",
                  lambda m: f"`{m.group(1).split('.')[-1]}`", text)
    return text.replace("``", "`")


_GREEK = {"alpha", "beta", "gamma", "delta", "theta", "Theta", "phi", "Phi", "psi", "omega",
          "pi", "lambda", "mu", "rho", "sigma", "tau"}
_FUNCS = {"cos", "sin", "tan", "sqrt", "atan2"}
_OPERATORS = {"+", "-", "/", "=", r"\cdot", r"\times"}
_EQUATION = re.compile(r"^(?P<eq>.*?=\s*0)(?P<note>\s+\(.*\))?\s*$")
_NAME = re.compile(r"(?<![A-Za-z0-9_])(?P<base>[A-Za-z]+)(?P<digits>\d*)"
                   r"(?:_(?P<sub>[A-Za-z0-9]+))?(?P<hat>\^(?![\d(]))?")


def _name_to_latex(m: re.Match) -> str:
    base, digits, sub, hat = m.group("base", "digits", "sub", "hat")
    if base == "x" and not (digits or sub):
        return r"\times"                  # the cross product: ``u x d``
    if base in _GREEK:
        tex = "\\" + base
    elif base in _FUNCS:
        tex = "\\" + base
    elif len(base) == 1:
        tex = base
    else:
        tex = rf"\mathit{{{base}}}"
    if hat:
        tex = rf"\hat{{{tex}}}"
    subs = "".join(x for x in (digits, sub) if x)
    if digits and sub:
        subs = f"{digits},{sub}"
    return tex + (f"_{{{subs}}}" if subs else "")


def equation_to_latex(line: str) -> str | None:
    """One equation of the docstring notation (``lhs = 0``, optionally followed by a
    parenthesised note) as LaTeX, for an ``aligned`` environment (``&= 0``); ``None`` when the
    line is not such an equation.

    Dots between spaces are dot products, a lone ``x`` a cross product, ``|a|`` a length,
    ``u^`` a unit vector, ``name_sub`` a subscript, Greek names Greek letters, and longer
    names (``dist``, ``rad1``) italic words."""
    m = _EQUATION.match(line.strip())
    if m is None:
        return None
    eq = m.group("eq")
    lhs = re.sub(r"\s*=\s*0$", "", eq)
    tex = _NAME.sub(_name_to_latex, lhs)
    tex = tex.replace(" . ", r" \cdot ").replace("'", "^{\\prime}")
    parts = tex.split("|")
    if len(parts) % 2 == 1:                        # |a| pairs: lengths
        tex = "".join(p if k % 2 == 0 else rf"\lvert {p} \rvert" for k, p in enumerate(parts))
    tex = re.sub(r"\s+", " ", tex).strip()
    # a product written with a space (``rad alpha``, ``dist |u|``): LaTeX ignores spaces,
    # so a thin space keeps ``\mathit{rad}\,\alpha`` from reading as one word
    words = tex.split(" ")
    tex = words[0]
    for a, b in zip(words, words[1:]):
        product = not (a in _OPERATORS or a.endswith("(") or b in _OPERATORS
                       or b.startswith((")", "/", "^", "\\rvert")) or a.endswith("\\lvert"))
        tex += (r"\, " if product else " ") + b
    tex += " &= 0"
    note = m.group("note")
    if note:
        tex += rf" \qquad \text{{{note.strip()}}}"
    return tex


def _math_block(block: list[str]) -> list[str] | None:
    """A literal block whose every line is an equation, as a displayed ``aligned`` block."""
    lines = [ln for ln in block if ln.strip()]
    tex = [equation_to_latex(ln) for ln in lines]
    if not lines or any(t is None for t in tex):
        return None
    return ["$$", r"\begin{aligned}", *(t + r" \\" for t in tex[:-1]), tex[-1],
            r"\end{aligned}", "$$"]


def rst_to_markdown(doc: str) -> str:
    """Convert a docstring's reStructuredText subset (paragraphs, ``::`` literal blocks,
    inline literals and roles) to Markdown."""
    # a :math: role may run over a line break; as Markdown it is kept on one line
    doc = re.sub(r":math:`([^`]+)`", lambda m: "$" + " ".join(m.group(1).split()) + "$",
                 inspect.cleandoc(doc))
    lines = doc.splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.strip() == ".. math::":
            i += 1
            block = []
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith((" ", "\t"))):
                block.append(lines[i])
                i += 1
            # Sphinx reads the block as one ``split`` environment: ``aligned`` is its
            # displayed-maths twin, and a blank line inside ``$$`` would end the maths
            # one equation a line (a docstring may break a long one after an operator, and
            # Markdown would read a line starting with "- " inside the maths as a list item)
            joined = " ".join(ln.strip() for ln in block if ln.strip())
            eqs = [e.strip() for e in joined.split(r"\\")]
            tex = [e + r" \\" for e in eqs[:-1]] + eqs[-1:]
            out += ["", "$$", r"\begin{aligned}", *tex, r"\end{aligned}", "$$", ""]
            continue
        if line.rstrip().endswith("::"):
            head = line.rstrip()[:-2].rstrip()
            if head:
                out.append(_inline(head) + ":")
            i += 1
            block: list[str] = []
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith((" ", "\t"))):
                block.append(lines[i])
                i += 1
            while block and not block[-1].strip():
                block.pop()
            maths = _math_block(block)
            if maths is not None:
                out += ["", *maths, ""]
                continue
            out += ["", "```text", *textwrap.dedent("\n".join(block)).strip("\n").splitlines(),
                    "```", ""]
            continue
        out.append(_inline(line))
        i += 1
    text = "\n".join(out)
    return re.sub(r"\n{3,}", "\n\n", text).strip() + "\n"


def render(registry=None) -> str:
    """The Markdown page for ``registry`` (default: ``mechsys.constraints.REGISTRY``)."""
    if registry is None:
        from .constraints import REGISTRY as registry
    names = sorted(registry, key=str.lower)
    parts = [HEADER, "| Mech name | models | DOF removed | what it does |",
             "| --- | --- | --- | --- |"]
    for name in names:
        cls = registry[name]
        summary = _inline(inspect.cleandoc(cls.__doc__ or "").split("\n\n")[0].replace("\n", " "))
        summary = summary.replace("|", "\\|")
        parts.append(f"| [`{name}`](#{name.lower()}) | {_kinds(cls)} | {_dof(cls)} | {summary} |")
    parts.append("")
    for name in names:
        cls = registry[name]
        parts.append(f"## {name}\n")
        parts.append(f"**Models:** {_kinds(cls)} · **DOF removed:** {_dof(cls)} · "
                     f"**Python:** `{_public_path(cls)}`\n")
        # a call signature, not a program: the marker keeps the page's code test from running it
        parts.append(f"```python fragment\n{_signature(cls.__name__, cls)}\n```\n")
        parts.append(rst_to_markdown(cls.__doc__ or "(undocumented)"))
    return "\n".join(parts).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    text = render()
    if not argv:
        sys.stdout.write(text)
        return 0
    path = Path(argv[0])
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
