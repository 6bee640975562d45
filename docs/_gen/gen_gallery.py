r"""Build the documentation gallery: one page per example script, with its pictures.

Usage: ``python docs/_gen/gen_gallery.py`` (``make docs`` runs it before Sphinx). For every
``examples/*.py`` it

1. runs the script (a fresh interpreter, working directory ``docs/gallery/_media/<name>/``,
   matplotlib's ``Agg`` backend) unless the cache already holds the pictures of this very
   script text (``docs/gallery/_media/manifest.json`` records each script's SHA-256);
   the pictures a script writes (``.png``, ``.gif``, ``.svg``, ``.jpg``) and its HTML
   viewers and players (``.html``) are kept, with what it printed; a script that writes no
   picture gets one: its open matplotlib figures, else an overlay of the last
   :class:`~mechsys.Solution` left in its namespace (``<name>_overlay.png``);
2. writes ``docs/gallery/<name>.md``: the title and summary from the script's docstring,
   the Mech manual section it reproduces (when its docstring names one), the pictures, the
   viewers (inline frames), the printed output and the whole script;
3. writes ``docs/gallery/index.md``: the manual's worked examples in section order, then
   the others, each with a thumbnail.

The cache makes the documentation build fast (no example runs when nothing changed) and is
committed, so a clean checkout builds the site without running twenty scripts; ``--refresh``
reruns them all (do that after a change that alters the pictures). ``--check`` runs nothing
and fails when a script has no up-to-date pictures.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import runpy
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mechsys import MechError

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
GALLERY = ROOT / "docs" / "gallery"
MEDIA = GALLERY / "_media"
MANIFEST = MEDIA / "manifest.json"

PICTURES = (".png", ".gif", ".svg", ".jpg", ".jpeg")
VIEWERS = (".html",)
# "section 1.2", "Mech section 5.1.2", "manual 10.5", "ch. 6.2.1", "chapter 5"
_SECTION = re.compile(r"(?:section|manual|ch\.|chapter)\s+(\d+(?:\.\d+)*)", re.IGNORECASE)
_HANG_GUARD_S = 900


@dataclass(frozen=True)
class Example:
    """One example script as the gallery sees it."""

    path: Path
    title: str
    summary: str
    section: str | None

    @property
    def name(self) -> str:
        return self.path.stem

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.path.read_bytes()).hexdigest()

    def section_key(self) -> tuple:
        return tuple(int(x) for x in self.section.split(".")) if self.section else ()


def _docstring(path: Path) -> str:
    import ast

    tree = ast.parse(path.read_text(encoding="utf-8"))
    return ast.get_docstring(tree) or ""


def _first_sentence(text: str) -> str:
    """Up to the first ``.`` or ``:`` followed by a space outside parentheses."""
    depth = 0
    for k, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if ch in ".:" and depth == 0 and (k + 1 == len(text) or text[k + 1] == " "):
            return text[:k]
    return text.rstrip(".")


def read_example(path: Path) -> Example:
    """Title (first sentence of the docstring), summary (first paragraph) and the manual
    section the script's docstring names (its first line or two), if any."""
    doc = _docstring(path)
    if not doc:
        raise MechError(f"example {path.name} has no module docstring; the gallery takes its "
                        "title and summary from it: add one")
    paragraphs = [p.strip() for p in re.split(r"\n\s*\n", doc) if p.strip()]
    first = " ".join(paragraphs[0].split())
    m = _SECTION.search(first)
    title = _first_sentence(first)
    summary = " ".join(paragraphs[1].split()) if len(paragraphs) > 1 else ""
    return Example(path=path, title=title, summary=summary, section=m.group(1) if m else None)


def examples(folder: Path = EXAMPLES) -> list[Example]:
    """The example scripts of a source checkout, by file name."""
    if not folder.is_dir():
        raise MechError(f"no examples folder at {folder}: the gallery is built from a source "
                        "checkout of mechsys (pip install -e .)")
    return [read_example(p) for p in sorted(folder.glob("*.py"))]


# -- running one example ------------------------------------------------------------------

def _record_solutions(cls) -> list:
    """Keep every instance of ``cls`` made from now on (in the gallery's own interpreter
    only): an example's solutions usually live inside its ``main()``."""
    made: list = []
    base_new = cls.__new__

    def new(klass, *args, **kw):
        obj = base_new(klass) if base_new is object.__new__ else base_new(klass, *args, **kw)
        made.append(obj)
        return obj

    cls.__new__ = new
    return made


def _run_one(script: str, outdir: str) -> None:
    """In a fresh interpreter (``gen_gallery.py --run-one``): run ``script``
    as ``__main__`` in ``outdir`` and make sure it leaves at least one picture there."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(script).resolve()
    os.chdir(outdir)
    argv = [str(path)]
    if "sys.argv[1]" in path.read_text(encoding="utf-8"):
        argv.append(f"{path.stem}.png")         # scripts that draw only when given a file
    sys.argv = argv
    from mechsys import Solution

    made = _record_solutions(Solution)
    runpy.run_path(str(path), run_name="__main__")
    if any(p.suffix.lower() in PICTURES for p in Path(outdir).iterdir()):
        return
    figs = plt.get_fignums()
    for k, num in enumerate(figs):
        plt.figure(num).savefig(f"{path.stem}_figure{k + 1}.png", dpi=80)
    if figs or not made:
        return
    from mechsys import draw

    # the last motion the script computed (a solution over several times), else its last
    moving = [s for s in made if np.ndim(s.t) == 1 and len(s.t) > 1]
    sol = moving[-1] if moving else made[-1]
    if np.ndim(sol.t) == 1 and len(sol.t) > 1:
        fig = draw.overlay(sol, frames=min(6, len(sol.t)), title=path.stem)
    else:
        fig = draw.snapshot(sol, title=path.stem)
    fig.savefig(f"{path.stem}_overlay.png", dpi=80)


def run_example(ex: Example, outdir: Path) -> dict:
    """Run one example into ``outdir`` (emptied first); returns its manifest entry."""
    if outdir.exists():
        shutil.rmtree(outdir)
    outdir.mkdir(parents=True)
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONDONTWRITEBYTECODE="1")
    src = str(ROOT / "src")
    env["PYTHONPATH"] = src + os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else src
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--run-one",
                           str(ex.path), str(outdir)], cwd=outdir, env=env,
                          capture_output=True, text=True, timeout=_HANG_GUARD_S)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise MechError(f"example {ex.path.name} failed (exit {proc.returncode}); the gallery "
                        f"needs it to run:\n{proc.stderr[-3000:]}")
    (outdir / "output.txt").write_text(proc.stdout, encoding="utf-8")
    files = sorted(p.name for p in outdir.iterdir()
                   if p.suffix.lower() in PICTURES + VIEWERS)
    return {"sha256": ex.sha256, "files": files, "seconds": round(seconds, 2)}


def _load_manifest(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else {}


def _fresh(ex: Example, entry: dict | None, media: Path) -> bool:
    return (entry is not None and entry.get("sha256") == ex.sha256
            and all((media / ex.name / f).exists() for f in entry.get("files", [])))


def update_media(exs: list[Example], media: Path = MEDIA, refresh: bool = False,
                 check: bool = False, log=print) -> dict:
    """Bring the picture cache up to date; returns the manifest. ``check``: run nothing,
    raise when an example's pictures are missing or stale."""
    manifest = _load_manifest(media / "manifest.json")
    stale = [ex for ex in exs if refresh or not _fresh(ex, manifest.get(ex.name), media)]
    gone = sorted(set(manifest) - {ex.name for ex in exs})       # examples that were removed
    if check:
        if stale or gone:
            raise MechError("gallery pictures missing or out of date for "
                            + ", ".join([ex.path.name for ex in stale] + [f"{g} (removed)" for g in gone])
                            + ": run `make docs` (python docs/_gen/gen_gallery.py) and commit "
                            "docs/gallery/_media")
        return manifest
    for ex in stale:
        log(f"gallery: running {ex.path.name}")
        manifest[ex.name] = run_example(ex, media / ex.name)
    for name in gone:
        manifest.pop(name)
        shutil.rmtree(media / name, ignore_errors=True)
    media.mkdir(parents=True, exist_ok=True)
    (media / "manifest.json").write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n",
                                         encoding="utf-8")
    return manifest


# -- pages --------------------------------------------------------------------------------

def _inline(text: str) -> str:
    from mechsys._docgen import _inline as rst_inline

    return rst_inline(text)


def page(ex: Example, entry: dict, media_rel: str = "_media") -> str:
    """The Markdown (MyST) page of one example."""
    lines = [f"# {_inline(ex.title)}", ""]
    if ex.section:
        lines += [f"*Mech manual, section {ex.section}* · script "
                  f"`examples/{ex.path.name}`", ""]
    else:
        lines += [f"Script `examples/{ex.path.name}`", ""]
    if ex.summary:
        lines += [_inline(ex.summary), ""]
    pictures = [f for f in entry["files"] if f.lower().endswith(PICTURES)]
    viewers = [f for f in entry["files"] if f.lower().endswith(VIEWERS)]
    if pictures:
        lines += ["## Pictures", ""]
        for f in pictures:
            lines += [f"![{ex.name}: {f}]({media_rel}/{ex.name}/{f})", ""]
    for f in viewers:
        lines += [f"## Interactive: `{f}`", "",
                  "```{raw} html",
                  f'<iframe class="mechsys-viewer" src="{media_rel}/{ex.name}/{f}" '
                  f'title="{ex.name}: {f}" loading="lazy" '
                  'style="width: 100%; height: 440px; border: 1px solid #ccc;"></iframe>',
                  "```", ""]
    lines += ["## What it prints", "",
              f"```{{literalinclude}} {media_rel}/{ex.name}/output.txt", ":language: text", "```", "",
              "## The script", "",
              f"```{{literalinclude}} ../../examples/{ex.path.name}", ":language: python",
              ":linenos:", "```", ""]
    return "\n".join(lines)


def _thumb(ex: Example, entry: dict, rel: str) -> str:
    pics = [f for f in entry["files"] if f.lower().endswith(PICTURES)]
    if not pics:
        return "(HTML viewer)"
    return f'<img src="{rel}/{ex.name}/{pics[0]}" alt="{ex.name}" width="180">'


#: The manual's chapters, for grouping its worked examples.
CHAPTERS = {1: "Getting started", 2: "Kinematic modeling", 3: "Output functions",
            4: "Velocity and acceleration", 5: "Multistage mechanisms", 6: "Cams and gears",
            7: "Loads and reactions", 8: "Inverse dynamics", 9: "Parametric design",
            10: "Underconstrained systems", 11: "Generalized coordinates",
            12: "Performance improvement", 13: "Debugging models"}


def _table(group: list[Example], manifest: dict, rel: str, first: str) -> list[str]:
    lines = [f"| {first} | example | picture |", "| --- | --- | --- |"]
    for e in group:
        where = e.section or ""
        lines.append(f"| {where} | [{_inline(e.title)}]({e.name}.md) | "
                     f"{_thumb(e, manifest[e.name], rel)} |")
    return lines + [""]


def index_page(exs: list[Example], manifest: dict, rel: str = "_media") -> str:
    manual = sorted((e for e in exs if e.section), key=Example.section_key)
    other = [e for e in exs if not e.section]
    lines = ["# Gallery", "",
             "<!-- Generated by `python docs/_gen/gen_gallery.py` (`make docs`); do not edit. -->", "",
             "Every script in `examples/`, with the pictures and animations it draws, what it "
             "prints and its source. Each runs as it is (`python examples/<name>.py`), and the "
             "test suite runs them all.", ""]
    if manual:
        lines += ["## The manual's worked examples", "",
                  "The examples that rebuild a worked example of Mech's manual, by chapter and "
                  "section.", ""]
        for ch in sorted({e.section_key()[0] for e in manual}):
            group = [e for e in manual if e.section_key()[0] == ch]
            lines += [f"### Chapter {ch}: {CHAPTERS.get(ch, '')}".rstrip(": "), ""]
            lines += _table(group, manifest, rel, "section")
    if other:
        lines += ["## More examples", ""] + _table(other, manifest, rel, "")
    lines += ["```{toctree}", ":hidden:", ""] + [e.name for e in manual + other] + ["```", ""]
    return "\n".join(lines)


def build(refresh: bool = False, check: bool = False, gallery: Path = GALLERY,
          media: Path = MEDIA, log=print) -> list[Path]:
    """Update the picture cache and write the gallery pages; returns the pages written."""
    exs = examples()
    manifest = update_media(exs, media=media, refresh=refresh, check=check, log=log)
    rel = os.path.relpath(media, gallery)
    written = []
    for old in gallery.glob("*.md"):
        old.unlink()
    for ex in exs:
        p = gallery / f"{ex.name}.md"
        p.write_text(page(ex, manifest[ex.name], media_rel=rel), encoding="utf-8")
        written.append(p)
    idx = gallery / "index.md"
    idx.write_text(index_page(exs, manifest, rel), encoding="utf-8")
    return [idx, *written]


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["--run-one"]:
        _run_one(argv[1], argv[2])
        return 0
    pages = build(refresh="--refresh" in argv, check="--check" in argv)
    print(f"gallery: {len(pages) - 1} example pages in {GALLERY.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
