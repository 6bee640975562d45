"""Every quick start runs as written: each ```python block of README.md and of every page
docs/*.md executes, in order, in a fresh namespace per page (a session of its own), with
the Agg backend and a temporary working directory.

A block that must not run says so on its fence line (docs/contributing.md):

* ```` ```python fragment ```` -- not a program: a call signature, or an excerpt of an
  example script that names objects defined elsewhere. Never run.
* ```` ```python slow ```` -- runs, but costs too much for the unit suite; run with
  ``MECHSYS_DOCS_SLOW=1``.

Any other word after ``python`` is an error, and so is a Python block written with another
language name (```` ```py ````, ```` ```python3 ````): an unmarked block always runs, and
the test fails when it does not.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from markdown_it import MarkdownIt

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
MARKERS = {"fragment", "slow"}
# language names a reader (or Pygments) takes for Python: only ``python`` is allowed, so
# that no block leaves the test by a change of spelling
_PYTHON_ALIASES = {"py", "python3", "py3", "ipython", "ipython3", "pycon", "pytb"}
_SLOW = os.environ.get("MECHSYS_DOCS_SLOW", "") not in ("", "0")


@dataclass(frozen=True)
class Block:
    line: int            # 1-based line of the fence in the Markdown file
    code: str
    marker: str | None   # None, "fragment" or "slow"


def python_blocks(text: str, where: str = "<text>") -> list[Block]:
    """The fenced Python blocks of a Markdown text, as the site's parser (markdown-it, what
    MyST uses) reads them: fences inside other fences, and backticks in a paragraph, are not
    blocks. Raises ``ValueError`` on an unknown marker or another spelling of Python."""
    blocks = []
    for tok in MarkdownIt("commonmark").parse(text):
        if tok.type != "fence":
            continue
        words = tok.info.split()
        line = tok.map[0] + 1
        if not words:
            continue
        lang, markers = words[0], words[1:]
        if lang.lower() in _PYTHON_ALIASES:
            raise ValueError(f"{where}:{line}: a Python block written ```{lang}: write "
                             "```python, with a marker (fragment, slow) if it must not run")
        if lang != "python":
            continue
        unknown = [w for w in markers if w not in MARKERS]
        if unknown or len(markers) > 1:
            raise ValueError(f"{where}:{line}: unknown marker(s) {' '.join(markers)!r} on a "
                             f"```python fence; allowed: one of {sorted(MARKERS)}")
        blocks.append(Block(line, tok.content, markers[0] if markers else None))
    return blocks


def test_block_extraction():
    text = ("intro\n```python\nx = 1\n```\n\n```text\nnot code\n```\n"
            "```` ```python ```` in a sentence\n"
            "````markdown\n```python\nnot a block\n```\n````\n"
            "```python fragment\nf(a, ...)\n```\n"
            "- a list item\n\n  ```python\n  y = x\n  ```\n")
    blocks = python_blocks(text)
    assert [(b.line, b.code, b.marker) for b in blocks] == [
        (2, "x = 1\n", None), (15, "f(a, ...)\n", "fragment"), (20, "y = x\n", None)]


@pytest.mark.parametrize("fence", ["```py\nx\n```\n", "```python3\nx\n```\n",
                                   "```python skip\nx\n```\n", "```python slow fragment\nx\n```\n"])
def test_unmarked_spellings_are_refused(fence):
    with pytest.raises(ValueError, match="```"):
        python_blocks(fence, "page.md")


def run_page(path: Path, tmp_path: Path, monkeypatch, slow: bool = _SLOW) -> dict:
    """Run the blocks of one page in a fresh namespace; ``{"ran", "fragment", "slow",
    "seconds"}``. A failing block fails with the page and the Markdown line of its block."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.chdir(tmp_path)            # snippets that write files write them here
    name = str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else path.name
    counts = {"ran": 0, "fragment": 0, "slow": 0}
    namespace: dict = {"__name__": "__docs__"}
    start = time.perf_counter()
    try:
        for block in python_blocks(path.read_text(encoding="utf-8"), name):
            if block.marker == "fragment" or (block.marker == "slow" and not slow):
                counts[block.marker] += 1
                continue
            # pad so that tracebacks give the lines of the Markdown file
            source = "\n" * block.line + block.code
            try:
                exec(compile(source, name, "exec"), namespace)  # noqa: S102
            except Exception as exc:
                raise AssertionError(
                    f"{name}, the ```python block at line {block.line} fails: "
                    f"{type(exc).__name__}: {exc}\n(mark it on its fence line only if it "
                    "is not meant to run as written; see docs/contributing.md)") from exc
            counts["ran"] += 1
    finally:
        plt.close("all")
    counts["seconds"] = time.perf_counter() - start
    return counts


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_page_code_runs(page, tmp_path, monkeypatch):
    counts = run_page(page, tmp_path, monkeypatch)
    assert counts["ran"] + counts["fragment"] + counts["slow"] == len(
        python_blocks(page.read_text(encoding="utf-8"), page.name))


def test_a_failing_block_fails_with_its_line(tmp_path, monkeypatch):
    page = tmp_path / "page.md"
    page.write_text("# t\n\n```python\nx = 1\n```\n\n```python\nx = undefined_name\n```\n"
                    "```python fragment\nnot python at all (...)\n```\n")
    with pytest.raises(AssertionError, match=r"page.md, the ```python block at line 7 "
                                             r"fails: NameError"):
        run_page(page, tmp_path, monkeypatch)
    page.write_text("```python\nx = 1\n```\n```python fragment\n(...)\n```\n"
                    "```python slow\nraise SystemError\n```\n")
    assert run_page(page, tmp_path, monkeypatch, slow=False)["slow"] == 1
    with pytest.raises(AssertionError, match="line 7 fails: SystemError"):
        run_page(page, tmp_path, monkeypatch, slow=True)


if __name__ == "__main__":   # the cost of each page: python tests/test_docs_pages.py
    import tempfile

    class _Env:                                      # what monkeypatch does, for a script
        def setenv(self, k, v):
            os.environ[k] = v

        def chdir(self, p):
            os.chdir(p)

    total = 0.0
    for p in PAGES:
        with tempfile.TemporaryDirectory() as d:
            try:
                c = run_page(p, Path(d), _Env())
            except (AssertionError, ValueError) as exc:
                print(f"{p.name:28s} FAILS: {exc}".splitlines()[0])
                continue
        total += c["seconds"]
        print(f"{p.name:28s} ran {c['ran']:3d}  fragment {c['fragment']:3d}  "
              f"slow {c['slow']:2d}  {c['seconds']:7.2f} s")
    print(f"total {total:.1f} s")
