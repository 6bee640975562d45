"""Sphinx configuration of the mechsys documentation site (``make docs``).

Sources are the Markdown pages of ``docs/`` as they are (MyST), an API reference generated
from the docstrings (autodoc + napoleon) and a gallery of the example scripts, whose pages
``docs/_gen/gen_gallery.py`` writes into ``docs/gallery/`` before the build. The build runs with
warnings as errors (``-W``), in ``make docs`` and in ``tests/test_docs_site.py``. Why Sphinx:
docs/decisions/0011-docs-site.md.
"""

import re
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import mechsys  # noqa: E402

project = "mechsys"
author = "the mechsys authors"
copyright = "the mechsys authors, MIT licence"
version = release = mechsys.__version__ if hasattr(mechsys, "__version__") else "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "sphinx.ext.mathjax",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "_gen", "_static", "gallery/_media/**"]
myst_heading_anchors = 4
# $...$ and $$...$$ in the Markdown pages, and amsmath environments (align, cases) as maths
myst_enable_extensions = ["deflist", "dollarmath", "amsmath"]

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True

# Furo: a maintained theme with a sidebar of the whole table of contents, a search box on
# every page, light and dark modes, and no resource loaded from another site
html_theme = "furo"
html_title = "mechsys"
html_static_path = ["_static"]
html_css_files = ["mechsys.css"]
html_theme_options = {"sidebar_hide_name": False, "navigation_with_keys": True}

# MathJax served with the site, never from a CDN: the files come with the pip package
# sphinx-mathjax-offline (MathJax 3, CommonHTML output); _copy_mathjax copies the parts the
# pages use (about 3 MB) into _static/mathjax after the build.
MATHJAX_DIR = "mathjax"
mathjax_path = f"{MATHJAX_DIR}/tex-chtml.js"
mathjax3_config = {"tex": {"tags": "ams"}, "options": {"enableMenu": True}}
MATHJAX_PARTS = ("tex-chtml.js", "output/chtml", "input/tex", "ui", "a11y")

# the decision records stay searchable but sink below every guide and API page
html_search_scorer = str(Path(__file__).resolve().parent / "_static" / "search_scorer.js")

myst_enable_extensions.append("html_image")


def _guides_in_toctree(app, docname, source):
    """Every page of docs/ outside api/, decisions/ and gallery/ is in the index's Guides
    toctree: pages added later (by any change) join it at the end instead of breaking the
    build with a "not in any toctree" warning."""
    if docname != "index":
        return
    text = source[0]
    here = Path(app.srcdir)
    listed = set(re.findall(r"^([\w\-/]+)\s*$", text, flags=re.MULTILINE))
    own_index = {"api", "decisions", "gallery"}          # folders with their own toctree
    pages = [p.relative_to(here).with_suffix("").as_posix() for p in here.rglob("*.md")]
    extra = sorted(d for d in pages if d not in listed and d not in {"index", "README"}
                   and d.split("/")[0] not in own_index and not d.startswith(("_", ".")))
    if extra:
        marker = ":caption: Guides\n\n"
        head, tail = text.split(marker, 1)
        block_end = tail.index("```")
        tail = tail[:block_end] + "".join(f"{e}\n" for e in extra) + tail[block_end:]
        source[0] = head + marker + tail


MEDIA_COPIED = (".html", ".png", ".gif", ".jpg", ".svg")


def _copy_viewers(app, exception):
    """The gallery's HTML viewers and players are shown in inline frames, and the front
    page shows pictures in raw HTML: copy them beside the pages (Sphinx copies only the
    pictures its image directives name)."""
    if exception is not None or app.builder.format != "html":
        return
    media = Path(app.srcdir) / "gallery" / "_media"
    for f in media.glob("*/*"):
        if f.suffix not in MEDIA_COPIED:
            continue
        dest = Path(app.outdir) / "gallery" / "_media" / f.parent.name / f.name
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(f, dest)


# -- the API reference, one page per part of the package ---------------------------------
# Everything public is importable from the top level (``ms.Revolute2``); its entries keep
# those names (ids ``mechsys.Revolute2``) and are grouped by the subpackage that defines them.
API_GROUPS = {
    "model": ("model", "io", "solvers._position", "_symbols"),
    "constraints": ("constraints",),
    "loads": ("loads",),
    "geometry": ("geometry",),
    "analyses": ("analyses",),
    "results": ("results", "solvers._diagnostics"),
    "errors": ("_errors",),
}
API_SKIP = {"__version__", "REGISTRY"}      # the version string; the registry is a dict
# public data objects whose own docstring is not ours (T is a SymPy Symbol): their entry
DATA_DOCS = {"T": "The time symbol (a SymPy ``Symbol``): drivers are expressions of it, e.g. "
                  "``ms.RotationLock1(crank, 2 * sp.pi * T)``; ``from mechsys import T``."}


def _home(name: str) -> str:
    """The part of the package that defines public name ``name`` (``"constraints"``...)."""
    obj = getattr(mechsys, name)
    module = getattr(obj, "__module__", None) or ""
    if name == "T":
        module = "mechsys._symbols"         # a SymPy symbol reports sympy's module
    rel = module.removeprefix("mechsys.")
    for group, prefixes in API_GROUPS.items():
        if any(rel == p or rel.startswith(p + ".") for p in prefixes):
            return group
    return ""


def api_names(group: str) -> list[str]:
    """The public names of ``mechsys`` documented on page ``api/<group>``, sorted."""
    return sorted((n for n in mechsys.__all__ if n not in API_SKIP and _home(n) == group),
                  key=str.lower)


def _api_directive():
    from docutils import nodes
    from docutils.statemachine import StringList
    from sphinx.util.docutils import SphinxDirective

    class PublicNames(SphinxDirective):
        """``mechsys-api GROUP``: autodoc entries of every public name of the group."""

        required_arguments = 1

        def run(self):
            group = self.arguments[0]
            if group not in API_GROUPS:
                raise self.error(f"unknown API group {group!r}; known: {sorted(API_GROUPS)}")
            lines = [".. currentmodule:: mechsys", ""]
            for name in api_names(group):
                obj = getattr(mechsys, name)
                if isinstance(obj, type):
                    kind = "autoexception" if issubclass(obj, BaseException) else "autoclass"
                elif callable(obj):
                    kind = "autofunction"
                else:
                    kind = "autodata"
                if name in DATA_DOCS:
                    lines += [f".. data:: {name}", "", f"   {DATA_DOCS[name]}", ""]
                elif kind == "autodata":
                    lines += [f".. autodata:: {name}", "   :no-value:", ""]
                else:
                    lines += [f".. {kind}:: {name}", ""]
            if type(self.state).__module__.startswith("myst_parser"):
                # a MyST page parses nested text as Markdown: hand the entries to rST
                lines = ["```{eval-rst}", *lines, "```"]
            holder = nodes.section()
            holder.document = self.state.document
            self.state.nested_parse(StringList(lines, source=f"<mechsys-api {group}>"),
                                    self.content_offset, holder)
            return holder.children

    return PublicNames


def _mech_call_signature(app, what, name, obj, options, signature, return_annotation):
    """Cam constraints parse Mech's variable argument list themselves (a curve takes one
    ``(sym, guess)`` pair, a surface two): show their documented call, ``_call``, instead of
    ``(*args)``."""
    call = getattr(obj, "_call", None) if what == "class" else None
    if isinstance(call, str) and signature == "(*args)":
        return call, return_annotation
    return None


def _check_api_groups(app):
    """A public name that no API page shows is an error of the build (-W), not a gap."""
    from sphinx.util import logging

    lost = [n for n in mechsys.__all__ if n not in API_SKIP and not _home(n)]
    if lost:
        logging.getLogger(__name__).warning(
            "public names in no API page (add their module to API_GROUPS in docs/conf.py): %s",
            ", ".join(lost))


def _mathjax_source() -> Path:
    """The MathJax files of the sphinx-mathjax-offline package (its module name has dashes,
    so it is found through importlib)."""
    import importlib.util

    spec = importlib.util.find_spec("sphinx-mathjax-offline")
    if spec is None or spec.origin is None:
        raise RuntimeError("the documentation needs MathJax shipped with the site: "
                           "pip install sphinx-mathjax-offline (the docs extra)")
    return Path(spec.origin).parent / "static" / "mathjax"


def _copy_mathjax(app, exception):
    """MathJax beside the pages, so that equations render with no network."""
    if exception is not None or app.builder.format != "html":
        return
    src = _mathjax_source()
    dest = Path(app.outdir) / "_static" / MATHJAX_DIR
    for part in MATHJAX_PARTS:
        s, d = src / part, dest / part
        if s.is_dir():
            shutil.copytree(s, d, dirs_exist_ok=True)
        else:
            d.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(s, d)


def setup(app):
    _mathjax_source()                       # fail early, naming the package, when it is absent
    app.add_directive("mechsys-api", _api_directive())
    app.connect("builder-inited", _check_api_groups)
    app.connect("autodoc-process-signature", _mech_call_signature)
    app.connect("source-read", _guides_in_toctree)
    app.connect("build-finished", _copy_viewers)
    app.connect("build-finished", _copy_mathjax)
    return {"parallel_read_safe": True}
