"""The documentation runs: every ```python block of README.md and docs/guide.md executes, and
docs/constraints.md is what the generator produces from the registry."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS_WITH_CODE = ["README.md", "docs/guide.md"]

_FENCE = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)


def python_blocks(text: str) -> list[tuple[int, str]]:
    """``(first line number, code)`` of every fenced ```python block."""
    return [(text.count("\n", 0, m.start(1)) + 1, m.group(1)) for m in _FENCE.finditer(text)]


def test_block_extraction():
    text = "intro\n```python\nx = 1\n```\n\n```text\nnot code\n```\n```python\ny = x\n```\n"
    assert python_blocks(text) == [(3, "x = 1\n"), (10, "y = x\n")]


@pytest.mark.parametrize("name", DOCS_WITH_CODE)
def test_code_blocks_run(name, tmp_path, monkeypatch):
    """The blocks of one file run in order in one namespace, like a session; a failure
    points at the Markdown line of its block."""
    path = ROOT / name
    blocks = python_blocks(path.read_text(encoding="utf-8"))
    assert blocks, f"{name} has no ```python blocks"
    monkeypatch.chdir(tmp_path)  # snippets that write files write them here
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict = {"__name__": "__docs__"}
    for line, code in blocks:
        # pad so that line numbers in tracebacks are those of the Markdown file
        source = "\n" * (line - 1) + code
        exec(compile(source, str(path), "exec"), namespace)  # noqa: S102


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

        a - b = 0

    After :class:`~mechsys.Point`.
    """)
    assert md == "Title `x`.\n\n`F(a, b)`:\n\n```text\na - b = 0\n```\n\nAfter `Point`.\n"



def test_relative_links_resolve():
    """Links between the Markdown pages point at files that exist."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    broken = []
    for page in pages:
        text = page.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue
            path = target.split("#", 1)[0]
            if not (page.parent / path).exists():
                broken.append(f"{page.relative_to(ROOT)} -> {target}")
    assert not broken, f"broken links: {broken}"
