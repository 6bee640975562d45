"""The documentation site: the Mech-to-mechsys table, the gallery, the Sphinx build with
warnings as errors, and every gallery page opened in headless Chromium with its pictures.

The site is built once per session in a temporary copy of docs/ (the committed picture
cache included, so no example runs unless an example changed since `make docs`)."""

import functools
import http.server
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import threading
from html.parser import HTMLParser
from pathlib import Path

import pytest

from mechsys import MechError
from mechsys.constraints import REGISTRY

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _load(name: str):
    """A documentation generator of docs/_gen/ (tools of the checkout, not of the package)."""
    spec = importlib.util.spec_from_file_location(name, DOCS / "_gen" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod                  # dataclasses look their module up by name
    spec.loader.exec_module(mod)
    return mod


_gallery = _load("gen_gallery")
_mech_map = _load("gen_mech_map")
SEED = "mech-manual-toc-and-function-reference.txt"


# -- the Mech-to-mechsys table -----------------------------------------------------------

def test_mech_map_page_is_generated_from_code():
    committed = (DOCS / "mech_to_mechsys.md").read_text(encoding="utf-8")
    assert committed == _mech_map.render(), (
        "docs/mech_to_mechsys.md is stale: run `python docs/_gen/gen_mech_map.py "
        "docs/mech_to_mechsys.md` (make docs)")


def test_every_named_counterpart_exists():
    rows = _mech_map.entries()
    n = 0
    for e in rows:
        for t in e.targets:
            _mech_map.resolve(t)
            n += 1
    assert n > 180
    # every registered constraint type is a row pointing at its class
    by_name = {e.mech: e for e in rows}
    for name, cls in REGISTRY.items():
        assert _mech_map.resolve(by_name[name].targets[0]) is cls
    # a "not yet" row names nothing, an "n/a" row says why
    for e in rows:
        if e.status == "n/a":
            assert e.note and not e.targets


def test_resolve_rejects_missing_names_and_keywords():
    assert _mech_map.resolve("mechsys.Model.solve(solution=)") is not None
    assert _mech_map.resolve("mechsys.Model.last_solution") is not None   # set in __init__
    with pytest.raises(MechError, match="does not exist"):
        _mech_map.resolve("mechsys.Model.no_such_method")
    with pytest.raises(MechError, match="no keyword 'nokw'"):
        _mech_map.resolve("mechsys.Model.solve(nokw=)")
    with pytest.raises(MechError, match="malformed"):
        _mech_map.resolve("mechsys.Model.solve(")


def _seed() -> Path | None:
    for base in (ROOT.parent / "shared", ROOT.parent.parent / "shared", Path("/work/shared")):
        p = base / "seeds" / SEED
        if p.exists():
            return p
    return None


def test_mech_map_covers_every_symbol_of_the_manuals_function_reference():
    """Every Mech symbol the manual's text uses (calls, options, settings, See-also lists,
    option tables, not only the entry headings) is a row of the table (issue 34)."""
    seed = _seed()
    if seed is None:
        pytest.skip(f"the manual's function reference ({SEED}) is not beside this checkout")
    text = seed.read_text(encoding="utf-8", errors="replace")
    names = _mech_map.manual_names(text)
    headings = {n for n, how in names.items() if "heading" in how}
    assert len(headings) > 80 and len(names) > 200
    # names that head no entry of the excerpt are read too
    assert {"SetSymbols", "ClearParameters", "TimeInterpolate", "ZeroTest", "DampingFactor",
            "CheckRules", "PolarToXY", "PointToLocal", "CompositeInertia", "Rest",
            "Sum"} <= set(names) - headings
    missing = _mech_map.uncovered(names)
    assert not missing, f"Mech symbols of the manual missing from the table: {missing}"


def test_mech_map_lists_the_online_names_and_reports_missing_ones():
    assert not _mech_map.uncovered(_mech_map.ONLINE_NAMES)
    sample = ("Foo 2D/3D \u2020 Foo[x, Rest] returns Location[p]. \u2020 The default is "
              "Baz->Qux. \u2020 See also: Spam, Location.")
    names = _mech_map.manual_names(sample)
    assert set(names) == {"Foo", "Rest", "Location", "Baz", "Qux", "Spam"}
    assert _mech_map.uncovered(names) == ["Baz", "Foo", "Qux", "Spam"]


# -- gallery --------------------------------------------------------------------------------

def test_gallery_reads_title_and_manual_section():
    ex = {e.name: e for e in _gallery.examples()}
    assert ex["slider_crank_2d"].section == "1.2"
    assert ex["gear_planetary"].section == "6.2.1"
    assert ex["gear_planetary"].title.endswith("(Mech manual, ch. 6.2.1)")   # no cut at "ch."
    assert ex["four_bar"].section is None
    assert _gallery._first_sentence("A screw jack: a motor (see ch. 6) drives. More") == "A screw jack"


def test_gallery_cache_is_current():
    """The committed pictures belong to the committed scripts (`make docs` refreshes them)."""
    manifest = _gallery.update_media(_gallery.examples(), check=True)   # runs nothing
    assert set(manifest) == {e.name for e in _gallery.examples()}


def test_gallery_check_reports_a_changed_example(tmp_path):
    media = tmp_path / "_media"
    shutil.copytree(_gallery.MEDIA, media)
    manifest = json.loads((media / "manifest.json").read_text())
    manifest["four_bar"]["sha256"] = "0" * 64                   # as if the script changed
    (media / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(MechError, match=r"four_bar\.py.*make docs"):
        _gallery.update_media(_gallery.examples(), media=media, check=True)


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.imgs, self.iframes = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append(a.get("src"))
        elif tag == "iframe":
            self.iframes.append(a.get("src"))


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """Build the site in a copy of docs/ with warnings as errors; returns the HTML folder."""
    base = tmp_path_factory.mktemp("site")
    src = base / "docs"
    shutil.copytree(DOCS, src, ignore=shutil.ignore_patterns("_build"))
    for gen in (src / "gallery").glob("*.md"):
        gen.unlink()
    os.symlink(ROOT / "examples", base / "examples")
    os.symlink(ROOT / "src", base / "src")
    pages = _gallery.build(gallery=src / "gallery", media=src / "gallery" / "_media",
                           log=lambda *a: None)
    assert len(pages) == len(_gallery.examples()) + 1
    out = base / "html"
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                           "html", str(src), str(out)], capture_output=True, text=True, env=env)
    assert proc.returncode == 0, f"sphinx failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-5000:]}"
    assert "WARNING" not in proc.stderr and "ERROR" not in proc.stderr, proc.stderr[-5000:]
    return out


API_PAGES = ("model", "constraints", "loads", "geometry", "analyses", "results", "errors")


def _api_entries(site: Path) -> dict[str, tuple[str, str]]:
    """``{id: (page, signature text)}`` of every top-level entry of the API pages."""
    out = {}
    for page in API_PAGES:
        html = (site / "api" / f"{page}.html").read_text(encoding="utf-8")
        for m in re.finditer(r'<dt class="sig sig-object py" id="(mechsys\.[^"]+)">(.*?)</dt>',
                             html, flags=re.S):
            text = _html_unescape(re.sub(r"<[^>]+>", "", m.group(2)))
            out[m.group(1)] = (page, " ".join(text.split()))
    return out


def _html_unescape(text: str) -> str:
    import html as _html

    return _html.unescape(text)


def test_site_has_guides_api_gallery_and_mech_table(site):
    for page in ("index", "install", "tutorial", "changelog", "guide", "constraints", "drawing",
                 "jupyter", "mech_to_mechsys", "api/index", "api/draw", "gallery/index",
                 "decisions/index", *(f"api/{p}" for p in API_PAGES)):
        assert (site / f"{page}.html").exists(), page
    entries = _api_entries(site)
    for name, page in (("Model2D", "model"), ("Solution", "results"), ("Revolute2", "constraints"),
                       ("Spring", "loads"), ("FreeSystem", "analyses"), ("ModelError", "errors"),
                       ("Point", "geometry")):
        assert entries[f"mechsys.{name}"][0] == page, name      # from the docstrings
    # every public name is on exactly one page, and no page is the old 860 KB one
    import mechsys

    public = {f"mechsys.{n}" for n in mechsys.__all__} - {"mechsys.__version__", "mechsys.REGISTRY"}
    assert public <= set(entries), sorted(public - set(entries))
    for page in API_PAGES:
        assert (site / "api" / f"{page}.html").stat().st_size < 600_000, page


def test_api_shows_real_signatures(site):
    """Every public constraint and load class shows its own arguments, not the
    ``(*args, **kwargs)`` of the base class's ``__new__`` (78 entries did)."""
    import mechsys
    from mechsys.constraints import ConstraintBase, RollingContact
    from mechsys.loads._loads import LoadBase

    entries = _api_entries(site)
    checked = 0
    for name in mechsys.__all__:
        obj = getattr(mechsys, name)
        if not (isinstance(obj, type) and issubclass(obj, (ConstraintBase, LoadBase))):
            continue
        if obj in (ConstraintBase, LoadBase, RollingContact):   # abstract bases, not built
            continue
        page, sig = entries[f"mechsys.{name}"]
        assert "*args" not in sig and "**kwargs" not in sig, (name, sig)
        assert "(" in sig, (name, sig)
        checked += 1
    assert checked > 75
    assert "Revolute2(point1, point2)" in entries["mechsys.Revolute2"][1]
    assert "CamToPoint1(locuspoint, (sym, guess)..., point)" in entries["mechsys.CamToPoint1"][1]


def test_site_loads_nothing_from_other_sites(site):
    """No script, style sheet or font from a CDN: the site works offline (MathJax is
    shipped in _static/mathjax)."""
    assert (site / "_static" / "mathjax" / "tex-chtml.js").is_file()
    assert list((site / "_static" / "mathjax" / "output" / "chtml" / "fonts").rglob("*.woff"))
    remote = re.compile(r'<(?:script|link|img|iframe)\b[^>]*\b(?:src|href)="(?:https?:)?//', re.I)
    for page in site.rglob("*.html"):
        if "_media" in page.parts or "_modules" in page.parts:
            continue
        html = page.read_text(encoding="utf-8")
        m = remote.search(html)
        assert m is None, (page.relative_to(site), html[m.start():m.start() + 200])
        if 'class="math' in html:
            assert "_static/mathjax/tex-chtml.js" in html, page.relative_to(site)
    table = (site / "mech_to_mechsys.html").read_text(encoding="utf-8")
    assert "SolveMech" in table and "Model.solve" in table


def test_every_example_has_a_page_with_its_pictures(site):
    manifest = json.loads((DOCS / "gallery" / "_media" / "manifest.json").read_text())
    index = (site / "gallery" / "index.html").read_text(encoding="utf-8")
    for ex in _gallery.examples():
        page = site / "gallery" / f"{ex.name}.html"
        assert page.exists(), ex.name
        assert f'href="{ex.name}.html"' in index, ex.name
        html = page.read_text(encoding="utf-8")
        links = _Links()
        links.feed(html)
        files = manifest[ex.name]["files"]
        pictures = [f for f in files if f.endswith(_gallery.PICTURES)]
        assert pictures, f"{ex.name} has no picture"
        assert len(links.imgs) >= len(pictures), ex.name
        for src in links.imgs:
            assert (page.parent / src).resolve().is_file(), (ex.name, src)
        for src in links.iframes:
            assert (page.parent / src).resolve().is_file(), (ex.name, src)
        # the script itself is on its page
        first_code_line = next(line for line in ex.path.read_text().splitlines()
                               if line.startswith(("import ", "from ")))
        assert first_code_line.split()[1] in html, ex.name
    manual = [e for e in _gallery.examples() if e.section]
    assert {"1.2", "1.3"} <= {e.section for e in manual}    # the manual's first two models


# -- in a browser ---------------------------------------------------------------------------

HANG_GUARD_S = 900      # only guards against a hung browser; not a speed requirement
# the network is closed: every host name but the loopback address fails to resolve, so a
# resource fetched from a CDN would be missing (and is listed by the probe)
BROWSER_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage"]

CHECKER = """<!DOCTYPE html><html><head><meta charset="utf-8"><title>probe</title></head>
<body><script>
const pages = %s;
async function probe(url) {
  const r = await fetch(url);
  const out = {status: r.status};
  if (!r.ok) return out;
  const f = document.createElement("iframe");
  f.style.width = "1200px"; f.style.height = "900px";
  await new Promise(res => { f.onload = res; f.src = url; document.body.appendChild(f); });
  const d = f.contentDocument;
  const w = f.contentWindow;
  // typeset maths: wait for MathJax's first pass, then count what it produced
  if (w.MathJax && w.MathJax.startup && w.MathJax.startup.promise) {
    try { await w.MathJax.startup.promise; } catch (e) { out.mathjax_error = String(e); }
  }
  out.math = {sources: d.querySelectorAll(".math").length,
              rendered: d.querySelectorAll("mjx-container").length,
              errors: d.querySelectorAll("mjx-merror, [data-mjx-error]").length,
              glyphs: d.querySelectorAll("mjx-c").length,
              fonts: Array.from(d.fonts || []).filter(x => x.family.startsWith("MJX")
                                                     && x.status === "loaded").length};
  out.resources = w.performance.getEntriesByType("resource").map(e => e.name)
      .filter(n => !n.startsWith(location.origin));
  if (url.startsWith("search.html")) {
    // the search runs after the index loads: wait for its summary line
    for (let i = 0; i < 200 && !(d.querySelector(".search-summary") &&
         d.querySelector(".search-summary").textContent.trim()); i++)
      await new Promise(res => setTimeout(res, 100));
    out.hits = Array.from(d.querySelectorAll("#search-results ul.search li a"))
        .map(a => a.getAttribute("href"));
  }
  const imgs = Array.from(d.images);
  await Promise.all(imgs.map(i => i.complete ? null :
      new Promise(res => { i.onload = res; i.onerror = res; })));
  out.title = d.title;
  const h1 = d.querySelector(".body h1") || d.querySelector("h1");
  out.h1 = h1 ? h1.textContent : null;
  out.images = imgs.map(i => [i.getAttribute("src"), i.naturalWidth, i.naturalHeight]);
  out.frames = [];
  for (const fr of Array.from(d.querySelectorAll("iframe"))) {
    const src = new URL(fr.getAttribute("src"), new URL(url, location.href)).href;
    const rr = await fetch(src);
    const text = rr.ok ? await rr.text() : "";
    out.frames.push([fr.getAttribute("src"), rr.status, text.includes("<canvas")]);
  }
  f.remove();
  return out;
}
(async () => {
  const res = {};
  for (const p of pages) {
    try { res[p] = await probe(p); } catch (e) { res[p] = {error: String(e)}; }
  }
  const pre = document.createElement("pre");
  pre.id = "result";
  pre.textContent = JSON.stringify(res);
  document.body.appendChild(pre);
})();
</script></body></html>
"""


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="module")
def served(site):
    """The built site over HTTP on the loopback interface (a page's fetches and frames need
    one origin; file:// pages are each their own)."""
    handler = functools.partial(_QuietHandler, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def test_gallery_pages_open_in_headless_chromium(site, served, tmp_path):
    browser = _chromium()
    if browser is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is not installed on CI: .ci/run installs Debian's chromium "
                        "before `make test`")
        pytest.skip("chromium is not installed (apt-get install -y chromium): the gallery's "
                    "browser check did not run")
    # the guides' maths, and the API pages' (every page whose docstrings hold maths)
    maths = ["constraints.html", "loads.html", "free_motion.html", "guide.html",
             "vibration.html", "spatial.html", "multistage.html", "generalized.html",
             "api/constraints.html", "api/loads.html", "api/analyses.html",
             "api/geometry.html", "api/results.html", "api/model.html", "api/models.html"]
    search = "search.html?q=reaction+force"
    pages = ["gallery/index.html", "mech_to_mechsys.html", "index.html", "jupyter.html",
             *maths, search] + [f"gallery/{e.name}.html" for e in _gallery.examples()]
    (site / "probe.html").write_text(CHECKER % json.dumps(pages), encoding="utf-8")
    profile = tmp_path / "profile"
    proc = subprocess.run([browser, *BROWSER_FLAGS, f"--user-data-dir={profile}",
                           "--virtual-time-budget=60000", "--dump-dom", served + "probe.html"],
                          capture_output=True, text=True, timeout=HANG_GUARD_S)
    m = re.search(r'<pre id="result">(.*?)</pre>', proc.stdout, flags=re.DOTALL)
    assert m, f"no probe result from chromium (exit {proc.returncode}):\n{proc.stderr[-3000:]}"
    import html as _html

    results = json.loads(_html.unescape(m.group(1)))
    manifest = json.loads((DOCS / "gallery" / "_media" / "manifest.json").read_text())
    assert set(results) == set(pages)
    for page, r in results.items():
        assert "error" not in r, (page, r)
        assert r["status"] == 200, (page, r)
        assert r["h1"] or page == search, (page, r)       # Furo's search page has no h1
        for src, w, h in r["images"]:
            assert w > 0 and h > 0, f"{page}: picture {src} did not load"
        for src, status, canvas in r["frames"]:
            assert status == 200 and canvas, f"{page}: viewer {src} did not load"
    for ex in _gallery.examples():
        r = results[f"gallery/{ex.name}.html"]
        words = " ".join(re.sub(r"[`*]", "", ex.title).split()[:3])
        assert r["h1"].startswith(words), (ex.name, r["h1"])
        n_pic = sum(f.endswith(_gallery.PICTURES) for f in manifest[ex.name]["files"])
        n_view = sum(f.endswith(_gallery.VIEWERS) for f in manifest[ex.name]["files"])
        assert len(r["images"]) >= n_pic >= 1, (ex.name, r["images"])
        assert len(r["frames"]) == n_view, (ex.name, r["frames"])
    thumbs = results["gallery/index.html"]["images"]
    assert len(thumbs) == len(_gallery.examples())
    # nothing came from another site (the resolver fails every other host)
    for page, r in results.items():
        assert not r["resources"], (page, r["resources"])
    # the front page shows pictures: the animation and the gallery strip, each loaded
    front = results["index.html"]["images"]
    assert len(front) >= 9 and any(src.endswith(".gif") for src, _, _ in front), front
    # equations are typeset offline: MathJax turned every maths source into its output,
    # with its own fonts loaded from the site, and reported no error
    for page in [*maths, "index.html"]:
        m = results[page]["math"]
        assert m["sources"] > 0 and m["rendered"] >= m["sources"], (page, m)
        assert m["errors"] == 0 and m["glyphs"] > 0 and m["fonts"] > 0, (page, m)
    assert results["constraints.html"]["math"]["rendered"] > 60     # one per equation block
    assert results["api/constraints.html"]["math"]["rendered"] > 60   # the docstrings' too
    # a search for "reaction force" lists guides and API first, the decision records last
    hits = results[search]["hits"]
    assert len(hits) >= 10, hits
    assert not [h for h in hits[:10] if "decisions/" in h], hits[:10]


def test_docs_tools_are_ruff_clean():
    """docs/conf.py and the generators in docs/_gen/ (outside test_lint's folders)."""
    ruff = shutil.which("ruff") or str(Path(sys.executable).with_name("ruff"))
    if not Path(ruff).exists():
        pytest.skip("ruff is not installed (it comes with the test extra)")
    res = subprocess.run([ruff, "check", "docs/conf.py", "docs/_gen"], cwd=ROOT,
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr
