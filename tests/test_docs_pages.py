"""Every ```python block of the other pages under docs/ runs (README.md and docs/guide.md
are covered by test_docs.py)."""

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SKIP = {"guide.md", "constraints.md", "drawing.md"}  # run by their own tests
PAGES = sorted(p for p in (ROOT / "docs").glob("*.md") if p.name not in SKIP)


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_page_code_runs(page, tmp_path, monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", page.read_text(), re.S)
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    for block in blocks:
        exec(compile(block, str(page), "exec"), ns)
