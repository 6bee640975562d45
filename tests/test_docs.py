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
    """The docstrings a reader meets: every public name of ``mechsys`` (all API pages) with its
    public methods and properties, the public members of ``mechsys.draw``, ``mechsys.models``
    and ``mechsys.testing`` (their own API pages), and every module's docstring (``help()`` of
    the module; the reference for the internals)."""
    import importlib
    import inspect
    import pkgutil

    import mechsys
    import mechsys.draw
    import mechsys.models
    import mechsys.testing

    out = {}

    def add(key, obj):
        out[key] = obj.__doc__ or ""            # as written: getdoc would expand a tab
        if isinstance(obj, type):
            for attr, member in vars(obj).items():
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                if not attr.startswith("_") and (inspect.isfunction(member)
                                                 or isinstance(member, property)):
                    out[f"{key}.{attr}"] = member.__doc__ or ""

    for name in mechsys.__all__:
        obj = getattr(mechsys, name)
        if isinstance(obj, type) or inspect.isfunction(obj):
            add(name, obj)
    for mod in (mechsys.draw, mechsys.models, mechsys.testing):
        names = getattr(mod, "__all__", None) or [
            n for n, o in vars(mod).items() if not n.startswith("_")
            and (isinstance(o, type) or inspect.isfunction(o)) and o.__module__ == mod.__name__]
        for name in names:
            obj = getattr(mod, name)
            if isinstance(obj, type) or inspect.isfunction(obj):
                add(f"{mod.__name__}.{name}", obj)
    for info in pkgutil.walk_packages(mechsys.__path__, "mechsys."):
        if not info.name.endswith("__main__"):
            out[f"module {info.name}"] = importlib.import_module(info.name).__doc__ or ""
    out["module mechsys"] = mechsys.__doc__ or ""
    return out


#: names of the plain-text notation of equations (``Phi_q qd``, ``M qdd``, ``E^T``, ``|v|^2``)
_PLAIN_TOKENS = re.compile(r"\^T\b|\^-1|\bPhi_\w|\bqdd\b|\bqd\b|\be_dot\b|\bsum_\w|\bintegral\b"
                           r"|\bd/dt\b|\bd\^2|\|\w+\|\^2")


def _parses(src: str) -> bool:
    import ast

    try:
        ast.parse(src)
        return True
    except SyntaxError:
        return False


def _not_maths(lit: str) -> bool:
    """An inline literal holding ``=`` without being an equation: markup, a call with keyword
    arguments, a grammar, an update in code, LaTeX itself, a lone sign, a quoted message (more
    than eight words)."""
    return bool(lit.startswith("<") or "\\" in lit or ":=" in lit or re.search(r"[-+*/]=", lit)
                or len(re.findall(r"[A-Za-z]{3,}", lit)) > 8
                or (re.fullmatch(r"[\w.]+\(.*\)", lit) and "=" in lit and " = " not in lit)
                or re.fullmatch(r"[&=\s0]*", lit))


def plain_equations(doc: str) -> list[str]:
    """The equations of a reST docstring written in plain text rather than as maths: literal
    blocks and ``inline literals`` that are not Python but hold an equation or the notation of
    one (``M qdd + Phi_q^T lambda = Q``), and notation in running text. ``.. math::`` blocks,
    ``:math:`` roles and doctest lines are maths or code already."""
    import inspect
    import textwrap

    doc = re.sub(r":math:`[^`]*`", "MATH", inspect.cleandoc(doc))
    lines = doc.splitlines()
    found, prose, i = [], [], 0

    def body(start: int, indent: int) -> tuple[list[str], int]:
        """The lines indented deeper than ``indent`` after line ``start``, and the next line."""
        k = start + 1
        while k < len(lines) and (not lines[k].strip()
                                  or len(lines[k]) - len(lines[k].lstrip()) > indent):
            k += 1
        return lines[start + 1:k], k

    while i < len(lines):
        line, s = lines[i], lines[i].strip()
        indent = len(line) - len(line.lstrip())

        if s.startswith((">>>", "... ")) or s == "...":
            i += 1
        elif s.startswith(".. "):                  # a directive (math, note, code) and its body
            content, i = body(i, indent)
            if not s.startswith((".. math::", ".. code", ".. doctest")):
                prose += content
        elif s.endswith("::"):                     # a literal block: code, or plain equations
            prose.append(line[:-2])
            content, i = body(i, indent)
            block = textwrap.dedent("\n".join(content)).strip()
            if (block and not _parses(block) and ":=" not in block
                    and ("=" in block or _PLAIN_TOKENS.search(block))):
                found.append(block)
        else:
            prose.append(line)
            i += 1
    text = "\n".join(prose)
    for lit in re.findall(r"``(.+?)``", text, flags=re.S):
        lit = " ".join(lit.split())
        if _not_maths(lit):
            continue
        equation = re.search(r"(?<![=<>!])=(?!=)", lit) and not re.match(r"\w+=", lit)
        if (equation or _PLAIN_TOKENS.search(lit)) and not _parses(lit):
            found.append(lit)
    for line in re.sub(r"``.+?``", " ", text, flags=re.S).splitlines():
        if _PLAIN_TOKENS.search(line):
            found.append(line.strip())
    return found


def test_plain_equations_are_found_and_maths_is_not():
    """The detector behind :func:`test_api_equations_are_typeset`: the issue's own example, a
    literal block of equations and notation in running text are found; maths, code and
    keyword calls are not."""
    found = plain_equations("""Motion.

    The equations ``M qdd + Phi_q^T lambda = Q`` hold, and so does::

        Phi_q qd = -Phi_t

    with Phi_q^T in a sentence.
    """)
    assert found == ["Phi_q qd = -Phi_t", "M qdd + Phi_q^T lambda = Q", "with Phi_q^T in a sentence."]
    assert plain_equations(r"""Motion :math:`M \ddot q = Q`, ``m.free(initial_condition=...)``,
    ``x = np.zeros(3)``::

        sol = m.solve(t)

    .. math::

        \Phi_q \dot q = -\Phi_t
    """) == []


def test_api_equations_are_typeset():
    """Equations in the docstrings a reader meets (every API page, every module's docstring)
    are reST maths (``.. math::``, ``:math:``), not plain text (:func:`plain_equations`); their
    braces pair up; and a docstring with maths is a raw string (else ``\\times`` would hold a
    tab and ``\\frac`` a form feed)."""
    import inspect

    from mechsys._docgen import _math_block

    docs = _api_docstrings()
    assert len(docs) > 600
    plain, unbalanced, not_raw, lone_amp = [], [], [], []
    for name, raw in docs.items():
        doc = inspect.cleandoc(raw)
        for block in _literal_blocks(doc):
            if _math_block(block.splitlines()) is not None:
                plain.append(name)
        plain += [(name, eq) for eq in plain_equations(raw)]
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


def _markdown_plain_equations(text: str) -> list[str]:
    """:func:`plain_equations` for a Markdown page, read as MyST reads it (markdown-it): fenced
    blocks without a language (or ``text``) that hold equations, and code spans holding an
    equation or its notation, where ``$...$`` maths belongs."""
    from markdown_it import MarkdownIt

    found = []
    for tok in MarkdownIt("commonmark").enable("table").parse(text):
        if tok.type == "fence":
            body = tok.content
            if (tok.info.strip().split(" ")[0] in ("", "text") and body.strip()
                    and not _parses(body) and ":=" not in body
                    and not body.lstrip().startswith(("<", "{", "|"))
                    and ("=" in body or _PLAIN_TOKENS.search(body))):
                found.append(body)
        for child in tok.children or []:
            lit = child.content
            if child.type != "code_inline" or _not_maths(lit):
                continue
            equation = re.search(r"(?<![=<>!])=(?!=)", lit) and not re.match(r"\w+=", lit)
            if (equation or _PLAIN_TOKENS.search(lit)) and not _parses(lit):
                found.append(lit)
    return found


def test_guides_typeset_their_equations():
    """Every page of the site and the README writes its equations as maths (``$...$``,
    ``$$...$$``), not as code (`` `M qdd + Phi_q^T lambda = Q` ``). The error catalogue quotes
    messages as printed and is left out."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    assert len(pages) > 30
    plain = {p.name: eqs for p in pages if p.name != "errors.md"
             for eqs in [_markdown_plain_equations(p.read_text(encoding="utf-8"))] if eqs}
    assert plain == {}, plain
    assert _markdown_plain_equations("Then `Phi_q qd = -Phi_t` and `x = 1` and $a = b$.\n") == [
        "Phi_q qd = -Phi_t"]
