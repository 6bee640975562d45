"""Generate ``docs/constraints.md`` from the constraint registry.

Usage: ``python -m mechsys._docgen docs/constraints.md`` (what ``make docs`` runs); without an
argument the page is printed. The page lists every type in
:data:`mechsys.constraints.REGISTRY`: its Mech name, the model kinds it works in (from
``cls.spaces``), the degrees of freedom it removes, its call signature (from ``__init__``)
and its docstring, which carries the equations. A test compares the committed page with
freshly generated output, so a new constraint type shows up in the docs by registering it.
"""

from __future__ import annotations

import inspect
import re
import sys
import textwrap
from pathlib import Path

_KINDS = {"planar": "2D", "spatial": "3D"}

HEADER = """\
# Constraint reference

<!-- Generated from mechsys.constraints.REGISTRY by `python -m mechsys._docgen
docs/constraints.md` (`make docs`). Do not edit by hand: edit the docstrings. -->

Every constraint type of mechsys, under its Mech name. Each is a small set of scalar
equations `Phi(q, T, p) = 0` built from the geometry of (usually) two bodies, listed in
Mech's order. Add one to a model with `m.add(constraint, name=...)`; see the
[user guide](guide.md#constraints) for how points, vectors and axes are given.

Notation in the equations: `r_1`, `r_2` global positions of the points, `u_1`, `u_2` global
directions of the vectors or axes, `d` a difference of positions, `a x b = a_x b_y - a_y b_x`
the scalar cross product in 2D, `theta` a planar body angle. A plain coordinate tuple where a
point is expected is a point on ground; where a vector is expected, a global direction.

"DOF removed" is the number of equations minus the number of new variables the constraint
introduces; a driver (an expression of `T` in any scalar argument) removes the same number.
"""


def _kinds(cls) -> str:
    return ", ".join(_KINDS.get(s, s) for s in cls.spaces)


def _dof(cls) -> str:
    n = getattr(cls, "dof_removed", None)
    return str(n) if n is not None else "equations - new variables"


def _signature(name: str, cls) -> str:
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
    """reStructuredText inline markup -> Markdown."""
    text = re.sub(r":(?:class|func|meth|attr|data|mod):`~?([^`]+)`",
                  lambda m: f"`{m.group(1).split('.')[-1]}`", text)
    return text.replace("``", "`")


def rst_to_markdown(doc: str) -> str:
    """Convert a docstring's reStructuredText subset (paragraphs, ``::`` literal blocks,
    inline literals and roles) to Markdown."""
    lines = inspect.cleandoc(doc).splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
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
        parts.append(f"```python\n{_signature(cls.__name__, cls)}\n```\n")
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
