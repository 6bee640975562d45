"""The package's tiers as folders, and imports that run one way (docs/decisions/0007).

Module-level imports between parts must follow the layer order below, and no module may
import one that (directly or not) imports it back. Imports inside functions are allowed only
where listed in ``LAZY_UP`` (call-time conveniences that reach up to ``draw``).

Inside ``solvers/`` every import counts, the ones inside functions too (a call-time import
that dodges a circle is still an arrow): its modules sit in the tiers of ``SOLVERS_TIER``,
import only their own tier or lower ones, and form no circle (decision 0058).
"""

from __future__ import annotations

import ast
from pathlib import Path

import mechsys

PKG = Path(mechsys.__file__).parent

# lower number = lower layer; a part may import its own layer's parts or lower ones
LAYER = {
    "_errors": 0, "_symbols": 0, "_version": 0, "_private": 0, "_signature": 0, "_progress": 0,
    "solvers": 0,
    "geometry": 1,
    "constraints": 2, "loads": 2, "results": 2, "compile": 2,
    "model": 3, "analyses": 3,
    "models": 4, "testing": 4, "draw": 4, "io": 4, "cli": 5, "_docgen": 5, "__init__": 5, "__main__": 5,
}

# (importing module, imported part): call-time imports that go up, each a documented convenience
LAZY_UP = {
    ("mechsys.results._solution", "draw"),   # Solution.plot
    ("mechsys.model", "draw"),               # Model.add_graphics
    ("mechsys.analyses._vibration", "draw"),  # VibrationModes.animate
    ("mechsys.model", "io"),                 # Model.save (model files)
}


# solvers/ by what its modules hold (decision 0058); a module imports its own tier or lower ones
SOLVERS_TIER = {
    # 0 constants, tables and the compile machinery, importing no other module of the folder
    "_tolerances": 0, "_methods": 0, "_tableaus": 0, "_tree": 0,
    "_jit_cache": 0, "_jit_modes": 0, "_jit_background": 0, "_jit_borrow": 0,
    # 1 compiled primitives: LAPACK's algorithms, calls into C, the sparse LU, the Gen tree
    "_jit_lapack": 1, "_jit_calls": 1, "_jit_sparse": 1, "_jit_tree": 1,
    # 2 linear algebra (Python and compiled), fixed patterns, what every compiled loop needs
    "_linalg": 2, "_patterns": 2, "_jit_linalg": 2, "_jit_runtime": 2,
    # (runs a compiled loop's code interpreted: imports only the intrinsics it replaces)
    "_jit_interp": 2,
    # (Mech's Adams step, the compiled loop's and the Python driver's: decision 0088)
    "_jit_adams": 2,
    # 3 the compiled loops
    "_jit_sweep_loop": 3, "_jit_multipliers_loop": 3, "_jit_free_loop": 3,
    # 4 the Python solvers and the drivers of the compiled loops
    "_position": 4, "_rank": 4, "_diagnostics": 4, "_free": 4, "_sensitivity": 4,
    "_jit_sweep": 4, "_jit_multipliers": 4, "_jit_free": 4, "_jit_gen_points": 4,
    # 5 what the analyses call: sweeps, multipliers, the integrator registry, the package
    "_kinematics": 5, "_statics": 5, "_integrators": 5, "__init__": 5,
}


def _modules():
    for f in sorted(PKG.rglob("*.py")):
        rel = f.relative_to(PKG.parent).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), f, is_pkg


def _part(mod: str) -> str:
    bits = mod.split(".")
    return bits[1] if len(bits) > 1 else "__init__"


def _imports(mod: str, f: Path, is_pkg: bool):
    """(target module, at module level?) for every mechsys import of a file."""
    tree = ast.parse(f.read_text())
    pkg = mod if is_pkg else mod.rsplit(".", 1)[0]
    top = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names = [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            target, names = None, [a.name for a in node.names]
        else:
            continue
        module_level = id(node) in top or _under_type_checking(tree, node)
        targets = [target] if target else names
        for t in targets:
            if t and t.startswith("mechsys"):
                # "from . import draw" names a submodule
                if isinstance(node, ast.ImportFrom) and t == "mechsys":
                    for n in names:
                        yield f"mechsys.{n}", module_level
                else:
                    yield t, module_level


def _under_type_checking(tree, node) -> bool:
    for n in tree.body:
        if isinstance(n, ast.If) and "TYPE_CHECKING" in ast.dump(n.test):
            if any(node is c for c in ast.walk(n)):
                return True
    return False


def _graph():
    edges = []
    for mod, f, is_pkg in _modules():
        for target, top in _imports(mod, f, is_pkg):
            edges.append((mod, target, top))
    return edges


def test_every_part_has_a_layer():
    parts = {_part(m) for m, _, _ in _modules()}
    assert parts <= set(LAYER), f"parts without a layer: {parts - set(LAYER)}"


def test_imports_run_down():
    bad = []
    for src, dst, top in _graph():
        a, b = _part(src), _part(dst)
        if a == b or LAYER[b] <= LAYER[a]:
            continue
        if not top and (src, b) in LAZY_UP:
            continue
        bad.append(f"{src} -> {dst} ({'module level' if top else 'in a function'})")
    assert not bad, "imports that go up a layer:\n" + "\n".join(bad)


def test_no_import_circles_between_parts():
    """Between different parts, module-level and call-time imports together form no cycle
    (apart from the listed call-time conveniences)."""
    graph: dict[str, set[str]] = {}
    for src, dst, _top in _graph():
        a, b = _part(src), _part(dst)
        if a != b and (src, b) not in LAZY_UP:
            graph.setdefault(a, set()).add(b)
    _assert_acyclic(graph)


def test_no_import_circles_between_modules():
    """Module-level imports between modules form no cycle (a package ``__init__`` re-exporting
    its modules is not a cycle: it is not imported by them)."""
    graph: dict[str, set[str]] = {}
    for src, dst, top in _graph():
        if top and src != dst and not dst.startswith(src + "."):
            graph.setdefault(src, set()).add(dst)
    _assert_acyclic(graph)


def _assert_acyclic(graph):
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in graph.get(n, ()):
            if state.get(m) == 1:
                raise AssertionError("import circle: " + " -> ".join(stack[stack.index(m):] + [m]))
            if m not in state:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in list(graph):
        if n not in state:
            visit(n)


def test_top_level_has_only_the_tiers():
    """The package root holds the tiers as folders, the builder, and a few small modules."""
    loose = sorted(p.name for p in PKG.glob("*.py"))
    assert loose == ["__init__.py", "__main__.py", "_docgen.py", "_errors.py", "_private.py",
                     "_progress.py", "_signature.py", "_symbols.py", "_version.py", "cli.py", "model.py",
                     "models.py"]
    folders = sorted(p.name for p in PKG.iterdir() if p.is_dir() and (p / "__init__.py").exists())
    assert folders == ["analyses", "compile", "constraints", "draw", "geometry", "io", "loads",
                       "results", "solvers", "testing"]


def _solvers_arrows():
    """``(importer, imported)`` for every import between two modules of ``solvers/``, at module
    level or inside a function (``from . import a, b`` names two modules)."""
    folder = PKG / "solvers"
    names = {f.stem for f in folder.glob("*.py")}
    arrows = set()
    for f in sorted(folder.glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                targets = [node.module.split(".")[0]] if node.module else [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mechsys.solvers."):
                targets = [node.module.split(".")[2]]
            elif isinstance(node, ast.Import):
                targets = [a.name.split(".")[2] for a in node.names if a.name.startswith("mechsys.solvers.")]
            else:
                continue
            arrows |= {(f.stem, t) for t in targets if t in names and t != f.stem}
    return names, arrows


def test_every_solvers_module_has_a_tier():
    names, _ = _solvers_arrows()
    assert names == set(SOLVERS_TIER), (
        f"solvers/ modules without a tier: {sorted(names - set(SOLVERS_TIER))}; "
        f"tiers of missing modules: {sorted(set(SOLVERS_TIER) - names)}")


def test_solvers_imports_run_down_its_tiers():
    """No module of ``solvers/`` imports one of a higher tier, even inside a function."""
    _, arrows = _solvers_arrows()
    bad = sorted(f"{a} (tier {SOLVERS_TIER[a]}) -> {b} (tier {SOLVERS_TIER[b]})"
                 for a, b in arrows if a in SOLVERS_TIER and b in SOLVERS_TIER
                 and SOLVERS_TIER[b] > SOLVERS_TIER[a])
    assert not bad, "imports up the tiers of solvers/:\n" + "\n".join(bad)


def test_no_import_circles_in_solvers():
    """The imports of ``solvers/``, call-time ones included, form no circle."""
    _, arrows = _solvers_arrows()
    graph: dict[str, set[str]] = {}
    for a, b in arrows:
        graph.setdefault(a, set()).add(b)
    _assert_acyclic(graph)


def test_solvers_imports_nothing_above_it():
    """``solvers/`` is the bottom tier of the package: what it imports from mechsys, at
    module level or in a function, is a layer-0 module (``_errors``, ``_private``, ...)."""
    bad = [f"{src} -> {dst}" for src, dst, _top in _graph()
           if _part(src) == "solvers" and _part(dst) != "solvers" and LAYER[_part(dst)] > 0]
    assert not bad, "solvers/ imports from higher tiers:\n" + "\n".join(bad)


def test_the_solvers_checks_see_a_circle():
    """The circle check finds one made by a call-time import (as ``_jit_loop`` importing
    ``_kinematics`` made before decision 0058)."""
    import pytest

    with pytest.raises(AssertionError, match="import circle"):
        _assert_acyclic({"_kinematics": {"_jit_sweep"}, "_jit_sweep": {"_jit_sweep_loop"},
                         "_jit_sweep_loop": {"_kinematics"}})
