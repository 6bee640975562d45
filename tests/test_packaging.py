"""Packaging (issue 38, item 2; decision 0041): one source for the version, an SPDX licence
with its file, ``py.typed`` with hints that mypy accepts on the examples, an sdist that carries
its tests, and numba/symengine as core dependencies with a warning (never a different answer)
where they cannot be imported."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tarfile
import textwrap
import tomllib
from pathlib import Path

import pytest

import mechsys

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_version_has_one_source():
    project = PYPROJECT["project"]
    assert "version" not in project and "version" in project["dynamic"]
    attr = PYPROJECT["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "mechsys._version.__version__"
    from mechsys import _version

    assert mechsys.__version__ == _version.__version__
    # nowhere else in the package is a version string written
    written = re.compile(r"^__version__\s*=\s*[\"']", re.M)
    hits = [p for p in (ROOT / "src" / "mechsys").rglob("*.py")
            if written.search(p.read_text()) and p.name != "_version.py"]
    assert hits == []


def test_spdx_licence_and_its_file():
    assert PYPROJECT["project"]["license"] == "MIT"
    assert PYPROJECT["project"]["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License") and "WITHOUT WARRANTY OF ANY KIND" in text


def test_numba_and_symengine_are_core():
    deps = " ".join(PYPROJECT["project"]["dependencies"])
    assert "numba>=" in deps and "symengine>=" in deps
    assert PYPROJECT["project"]["optional-dependencies"]["fast"] == []


def test_py_typed_is_shipped():
    assert (ROOT / "src" / "mechsys" / "py.typed").is_file()
    assert "py.typed" in PYPROJECT["tool"]["setuptools"]["package-data"]["mechsys"]


def test_mypy_passes_on_the_examples(tmp_path):
    """mechsys is typed (py.typed): mypy checks the examples' calls against its hints and
    finds nothing wrong; a wrong argument type is caught (so the check is not vacuous)."""
    api = pytest.importorskip("mypy.api")
    common = ["--config-file", str(ROOT / "pyproject.toml"), "--cache-dir", str(tmp_path / "c")]
    out, err, status = api.run([str(ROOT / "examples"), *common])
    assert status == 0, out + err
    bad = tmp_path / "bad.py"
    bad.write_text("import mechsys as ms\nms.Model2D().add_body(3)\n")
    out, _, status = api.run([str(bad), *common])
    assert status == 1 and '"add_body"' in out and "expected \"str\"" in out


_BLOCKED = textwrap.dedent("""
    import sys, warnings
    for name in {blocked!r}:
        sys.modules[name] = None          # the import fails, as where it is not installed
    import numpy as np
    import mechsys as ms
    from mechsys.models import slider_crank
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = slider_crank()
        sol = m.solve(t=np.linspace(0, 1, 1200))
        m.solve(t=np.linspace(0, 1, 1200))
    slow = [w for w in caught if issubclass(w.category, ms.SlowPathWarning)]
    print(len(slow), "|".join(str(w.message) for w in slow))
    np.save({out!r}, sol.q)
""")


def _run_blocked(blocked, out):
    code = _BLOCKED.format(blocked=blocked, out=str(out))
    env = {"MECHSYS_CACHE": "0", "MECHSYS_JIT": "auto", "PATH": "/usr/bin:/bin"}
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=ROOT, timeout=900)
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stdout.strip().splitlines()[-1]


@pytest.mark.parametrize("blocked", [("numba",), ("symengine",)])
def test_missing_core_dependency_warns_once_and_answers_the_same(blocked, tmp_path):
    """Where numba or symengine cannot be imported, a SlowPathWarning names the package once
    per process; the positions of a 1200-point sweep are those of the compiled library."""
    import numpy as np

    line = _run_blocked(blocked, tmp_path / "slow.npy")
    count, message = line.split(" ", 1)
    assert count == "1", line
    assert blocked[0] in message and "core dependency" in message
    from mechsys.models import slider_crank

    fast = slider_crank().solve(t=np.linspace(0, 1, 1200)).q
    assert np.allclose(np.load(tmp_path / "slow.npy"), fast, rtol=0, atol=1e-10)


def test_sdist_carries_its_tests(tmp_path):
    """The sdist holds what its tests read (tests with conftest, examples, docs, benchmarks,
    LICENSE, py.typed), and the public-API tests collect and pass in the unpacked tree."""
    pytest.importorskip("build")
    if shutil.which("git") is None:
        pytest.skip("git is needed to copy the tree")
    src = tmp_path / "tree"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".venv", ".git", "out", "build", "dist", "__pycache__", "*.egg-info", ".pytest_cache",
        ".mypy_cache", ".ruff_cache", "_media"))
    res = subprocess.run([sys.executable, "-m", "build", "--sdist", "--no-isolation",
                          "--outdir", str(tmp_path / "dist"), str(src)],
                         capture_output=True, text=True)
    if res.returncode != 0 and "setuptools" in res.stdout + res.stderr and "77" in res.stderr:
        pytest.skip("the environment's setuptools is older than the build requires")
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    (sdist,) = (tmp_path / "dist").glob("mechsys-*.tar.gz")
    assert sdist.name == f"mechsys-{mechsys.__version__}.tar.gz"
    with tarfile.open(sdist) as tar:
        names = {n.split("/", 1)[1] for n in tar.getnames() if "/" in n}
        tar.extractall(tmp_path / "x", filter="data")
    for needed in ("LICENSE", "README.md", "tests/conftest.py", "tests/test_public_api.py",
                   "examples/four_bar.py", "docs/errors.md", "src/mechsys/py.typed",
                   "benchmarks/_machine.py"):
        assert needed in names, needed
    assert not any("__pycache__" in n or n.endswith((".nbi", ".nbc")) for n in names)
    (unpacked,) = (tmp_path / "x").iterdir()
    res = subprocess.run([sys.executable, "-m", "pytest", "-o", "addopts=", "-q", "-p", "no:cacheprovider",
                          "tests/test_public_api.py", "tests/test_four_bar.py"],
                         cwd=unpacked, capture_output=True, text=True,
                         env={"PYTHONPATH": str(unpacked / "src"), "PATH": "/usr/bin:/bin",
                              "MECHSYS_CACHE": "0"})
    assert res.returncode == 0, res.stdout[-3000:]
    assert " passed" in res.stdout


def test_readme_has_no_link_that_breaks_on_the_package_index():
    """README.md is the package's description on the index, where a relative link (or an
    anchor: the index gives headings no ids) leads nowhere; the project has no public address
    yet, so the README names documents by their paths (decision 0049)."""
    from markdown_it import MarkdownIt

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = []
    for tok in MarkdownIt("commonmark").parse(text):
        for child in tok.children or []:
            if child.type in ("link_open", "image"):
                targets.append(child.attrs.get("href") or child.attrs.get("src"))
    targets += re.findall(r"<(?:a|img)\b[^>]*?(?:href|src)\s*=\s*[\"']([^\"']*)", text, re.I)
    assert targets == [] or all(t.startswith("https://") for t in targets), [
        t for t in targets if not t.startswith("https://")]
    # the documents it names exist
    for path in set(re.findall(r"`((?:docs|examples)/[\w./-]*)`", text)):
        assert (ROOT / path).exists(), f"README names {path}, which does not exist"


def test_make_demo_installs_the_library_alone_and_the_demo_needs_nothing_more(tmp_path):
    """``make demo`` installs ``pip install -e .`` (no extra), and the demo runs with every
    optional package unimportable, writing its table, plots, animation and 3D viewer."""
    make = (ROOT / "Makefile").read_text(encoding="utf-8")
    demo = re.search(r"^demo: (.*)$", make, flags=re.M).group(1).split()
    assert demo == ["$(CORE)"], demo
    core = re.search(r"^\$\(CORE\):.*\n((?:\t.*\n)+)", make, flags=re.M).group(1)
    installs = re.findall(r"pip install[^\n]*", core)
    assert installs == ["pip install --quiet -e ."], installs
    optional = sorted({re.split(r"[<>=\[ ]", d)[0] for extra, deps
                       in PYPROJECT["project"]["optional-dependencies"].items()
                       if extra != "fast" for d in deps} - {"setuptools", "build"})
    code = (f"import sys\nfor name in {optional!r}:\n    sys.modules[name.replace('-', '_')] = None\n"
            "from mechsys.cli import main\nsys.exit(main(['demo', '--out', sys.argv[1]]))\n")
    res = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True,
                         text=True, cwd=ROOT, timeout=900,
                         env={**os.environ, "MPLBACKEND": "Agg"})
    assert res.returncode == 0, res.stderr[-3000:]
    for name in ("slider_crank_kinematics.png", "slider_crank_loads.png", "slider_crank.gif",
                 "slider_crank_3d.html"):
        assert (tmp_path / name).stat().st_size > 1000, name
    assert "x [m]" in res.stdout and "torque [N m]" in res.stdout
