"""docs/constraints.md is what the generator produces from the registry, its equations are
typeset, and the API shows real signatures. (The ```python blocks of README.md and of every
page docs/*.md run in test_docs_pages.py.)"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_constraint_reference_is_current():
    from mechsys._docgen import render

    committed = (ROOT / "docs" / "constraints.md").read_text(encoding="utf-8")
    assert committed == render(), (
        "docs/constraints.md differs from the constraint registry: run make docs")


def test_docgen_main_writes_the_page(tmp_path):
    from mechsys._docgen import main, render

    out = tmp_path / "c.md"
    assert main([str(out)]) == 0
    assert out.read_text(encoding="utf-8") == render()


def test_docgen_lists_every_registered_type():
    from mechsys._docgen import render
    from mechsys.constraints import REGISTRY

    page = render()
    for name, cls in REGISTRY.items():
        assert f"\n## {name}\n" in page
        kinds = {"planar": "2D", "spatial": "3D"}
        assert ", ".join(kinds[s] for s in cls.spaces) in page


def test_rst_literal_blocks_become_fenced_code():
    from mechsys._docgen import rst_to_markdown

    md = rst_to_markdown("""Title ``x``.

    ``F(a, b)``::

        m.add(c)

    After :class:`~mechsys.Point`.
    """)
    assert md == "Title `x`.\n\n`F(a, b)`:\n\n```text\nm.add(c)\n```\n\nAfter `Point`.\n"


def test_equation_blocks_become_typeset_maths():
    """A literal block of equations becomes a displayed ``aligned`` block of LaTeX."""
    from mechsys._docgen import equation_to_latex, rst_to_markdown

    md = rst_to_markdown("""Equations::

        u_1 . (r_2 - r_1) = 0
        u x d - dist |u| = 0      (three equations)

    End.
    """)
    assert md == ("Equations:\n\n$$\n\\begin{aligned}\n"
                  "u_{1} \\cdot (r_{2} - r_{1}) &= 0 \\\\\n"
                  "u \\times d - \\mathit{dist}\\, \\lvert u \\rvert &= 0 \\qquad "
                  "\\text{(three equations)}\n\\end{aligned}\n$$\n\nEnd.\n")
    assert equation_to_latex("theta_1 - theta_2 - angle = 0") == (
        r"\theta_{1} - \theta_{2} - \mathit{angle} &= 0")
    assert equation_to_latex("k_1 . g_2' - u_2^ . d = 0") == (
        r"k_{1} \cdot g_{2}^{\prime} - \hat{u}_{2} \cdot d &= 0")
    assert equation_to_latex("s - pitch alpha / (2 pi) = 0") == (     # products: thin spaces
        r"s - \mathit{pitch}\, \alpha / (2\, \pi) &= 0")
    assert equation_to_latex("s = sp.Symbol('s')") is None          # code stays code


def test_constraint_page_typesets_every_equation_block():
    """Every block of equations of the constraint reference is displayed maths (no plain
    ``= 0`` line is left in a code block), and its dollars pair up."""
    page = (ROOT / "docs" / "constraints.md").read_text(encoding="utf-8")
    code = re.findall(r"^```text\n(.*?)^```", page, flags=re.M | re.S)
    assert not [c for c in code if re.search(r"=\s*0\b", c)], code
    fences = re.findall(r"^\$\$$", page, flags=re.M)
    assert len(fences) >= 100 and len(fences) % 2 == 0


def _api_docstrings() -> dict[str, str]:
    """The docstrings the API pages show for the constraint, load and analysis groups: every
    public name defined there, with its public methods and properties."""
    import inspect

    import mechsys

    out = {}
    for name in mechsys.__all__:
        obj = getattr(mechsys, name)
        if not (getattr(obj, "__module__", "") or "").startswith(
                ("mechsys.constraints", "mechsys.loads", "mechsys.analyses")):
            continue
        out[name] = obj.__doc__ or ""           # as written: getdoc would expand a tab
        if isinstance(obj, type):
            for attr, member in vars(obj).items():
                if not attr.startswith("_") and (inspect.isfunction(member)
                                                 or isinstance(member, property)):
                    out[f"{name}.{attr}"] = member.__doc__ or ""
    return out


def test_api_equations_are_typeset():
    """Equations in the docstrings the API pages show are reST maths (``.. math::``,
    ``:math:``), not plain literal blocks; their braces pair up; and a docstring with maths is a
    raw string (else ``\\times`` would hold a tab and ``\\frac`` a form feed)."""
    import inspect

    from mechsys._docgen import _math_block

    docs = _api_docstrings()
    assert len(docs) > 150
    plain, unbalanced, not_raw, lone_amp = [], [], [], []
    for name, raw in docs.items():
        doc = inspect.cleandoc(raw)
        for block in _literal_blocks(doc):
            if _math_block(block.splitlines()) is not None:
                plain.append(name)
        if ":math:" in doc or ".. math::" in doc:
            if re.search(r"[\t\x07\x08\x0b\x0c\r]", raw):
                not_raw.append(name)
            pieces = re.findall(r":math:`([^`]+)`", doc)
            blocks = re.findall(r"^\.\. math::\n\n((?:[ \t]+.*\n?|\n)+)", doc, flags=re.M)
            # Sphinx hands MathJax a block with ``\\`` inside ``split``, any other as is:
            # an ``&`` there is "Misplaced &" (an error box on the page)
            lone_amp += [(name, b) for b in blocks if "&" in b and "\\\\" not in b]
            pieces += blocks
            for tex in pieces:
                depth = 0
                for ch in tex.replace(r"\{", "").replace(r"\}", ""):
                    depth += {"{": 1, "}": -1}.get(ch, 0)
                    if depth < 0:
                        break
                if depth != 0:
                    unbalanced.append((name, tex))
    assert plain == [], f"plain-text equation blocks (write .. math::): {plain}"
    assert unbalanced == []
    assert not_raw == []
    assert lone_amp == []
    typeset = [n for n, d in docs.items() if ".. math::" in d]
    print(f"{len(docs)} docstrings, {len(typeset)} with displayed maths")
    assert len(typeset) >= 70, len(typeset)      # every constraint type, loads, analyses


def _public_classes():
    import mechsys
    import mechsys.draw
    from mechsys.constraints import ConstraintBase
    from mechsys.draw._primitives import Primitive
    from mechsys.loads._loads import LoadBase

    bases = (ConstraintBase, LoadBase, Primitive)
    out = {}
    for mod in (mechsys, mechsys.draw):
        for name in mod.__all__:
            obj = getattr(mod, name)
            if isinstance(obj, type) and issubclass(obj, bases) and obj not in bases:
                out[name] = obj
    return out


def test_constraints_and_loads_show_their_real_signatures():
    """Their bases keep the constructor's arguments through ``__new__(cls, *args, **kwargs)``;
    autodoc reads a class's ``__new__`` before its ``__init__``, so the API reference showed
    ``(*args, **kwargs)`` for all of them. ``__signature__`` (read first by autodoc and
    inspect) must be ``__init__``'s."""
    import inspect

    classes = _public_classes()
    assert len(classes) > 90
    generic = []
    for name, cls in classes.items():
        sig = cls.__signature__                       # what autodoc takes first
        assert isinstance(sig, inspect.Signature), name
        init = inspect.signature(cls.__init__)
        assert list(sig.parameters.values()) == list(init.parameters.values())[1:], name
        assert inspect.signature(cls) == sig, name
        if any(p.name in ("args", "kwargs") and p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
               for p in sig.parameters.values()):
            generic.append(name)
    # the cam constraints parse Mech's variable argument list themselves; the site shows
    # their documented call (``_call``) instead (docs/conf.py, checked on the built HTML)
    assert all(getattr(classes[n], "_call", "").startswith("(") for n in generic), generic
    import mechsys as ms

    assert str(inspect.signature(ms.Revolute2)) == "(point1, point2)"
    assert str(inspect.signature(ms.Spring)).startswith("(point1, point2, stiffness=0")


def _literal_blocks(doc: str) -> list[str]:
    """The ``::`` literal blocks of a reStructuredText docstring, dedented."""
    import inspect
    import textwrap

    lines = inspect.cleandoc(doc).splitlines()
    blocks, i = [], 0
    while i < len(lines):
        # a directive (``.. math::``) is not a literal block
        if lines[i].rstrip().endswith("::") and not lines[i].lstrip().startswith(".. "):
            i += 1
            block = []
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith(" ")):
                block.append(lines[i])
                i += 1
            blocks.append(textwrap.dedent("\n".join(block)).strip() + "\n")
            continue
        i += 1
    return blocks


def test_drawing_quick_start_runs_as_written(tmp_path, monkeypatch):
    """The quick start of ``mechsys.draw`` (``help(mechsys.draw)``) runs in a fresh
    namespace: it used ``np`` without importing it."""
    import mechsys.draw

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    quick = _literal_blocks(mechsys.draw.__doc__)[0]
    assert "ms.draw.animate" in quick
    exec(compile(quick, "mechsys.draw quick start", "exec"), {"__name__": "__docs__"})  # noqa: S102
    assert (tmp_path / "slider_crank.gif").stat().st_size > 0
    assert (tmp_path / "slider_crank.html").stat().st_size > 0
