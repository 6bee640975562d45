"""The import graph of ``src/mechsys/solvers``: files, lines, arrows, and circles.

Every ``import`` statement of every module is read with :mod:`ast`, the ones inside
functions too (a call-time import put there to dodge a circle is still an arrow: the
module cannot work without the other). An *arrow* is one ordered pair of modules of the
folder, ``a -> b`` when ``a`` imports ``b`` anywhere (counted once however many names or
statements); the package ``__init__`` is a module like the others. A *circle* is a strongly
connected component of more than one module (Tarjan's algorithm), i.e. a set of modules
each of which reaches every other by arrows.

Imports that leave the folder are listed apart, with the tier of the part they reach
(``tests/test_layout.py`` keeps the tier map; ``solvers`` is the bottom tier, so anything
it imports from the package must be a tier-0 module such as ``_errors``).

Run: ``python benchmarks/solvers_graph.py`` (no mechsys import, it reads the sources);
``--arrows`` also prints every arrow, ``--json`` the numbers as one JSON object, ``--at
COMMIT`` measures the folder as it was at a git commit (decision 0058's "before": ``--at
88dfcfa``).
"""

from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "src" / "mechsys"
FOLDER = ROOT / "solvers"


def modules(folder: Path = FOLDER) -> dict[str, Path]:
    """Module name (``_linalg``, ``__init__``) -> file, for the folder's own ``.py`` files."""
    return {f.stem: f for f in sorted(folder.glob("*.py"))}


def imports(f: Path) -> list[tuple[str, bool]]:
    """``(target, inside a function?)`` for every import of ``f`` that names mechsys.

    A target is ``solvers.<module>`` for a sibling, else the dotted mechsys path.
    """
    tree = ast.parse(f.read_text())
    top = {id(n) for n in tree.body}
    # statements under a module-level ``if``/``try`` run at import time as well
    for n in tree.body:
        if isinstance(n, (ast.If, ast.Try)):
            top |= {id(c) for c in ast.walk(n) if isinstance(c, (ast.Import, ast.ImportFrom))}
    out = []
    for node in ast.walk(tree):
        lazy = id(node) not in top
        if isinstance(node, ast.ImportFrom):
            if node.level == 1:  # "from . import x" / "from ._x import y"
                if node.module:
                    out.append((f"solvers.{node.module.split('.')[0]}", lazy))
                else:
                    out.extend((f"solvers.{a.name}", lazy) for a in node.names)
            elif node.level == 2:  # "from .. import x" / "from .._errors import y"
                if node.module:
                    out.append((f"mechsys.{node.module}", lazy))
                else:
                    out.extend((f"mechsys.{a.name}", lazy) for a in node.names)
            elif node.module and node.module.split(".")[0] == "mechsys":
                bits = node.module.split(".")
                if len(bits) > 1 and bits[1] == "solvers":
                    out.append((f"solvers.{bits[2]}" if len(bits) > 2 else "solvers.__init__", lazy))
                else:
                    out.append((node.module, lazy))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "mechsys":
                    out.append((a.name, lazy))
    return out


def graph(folder: Path = FOLDER):
    """``(arrows, lazy, outside)``: the set of sibling arrows, the subset of them made only by
    imports inside functions, and the set of ``(module, mechsys target)`` leaving the folder."""
    mods = modules(folder)
    arrows: set[tuple[str, str]] = set()
    eager: set[tuple[str, str]] = set()
    outside: set[tuple[str, str]] = set()
    for name, f in mods.items():
        for target, lazy in imports(f):
            if target.startswith("solvers."):
                dst = target.split(".", 1)[1]
                if dst == name:
                    continue
                if dst not in mods:
                    raise SystemExit(f"{name} imports {dst}, which is not a module of {folder}")
                arrows.add((name, dst))
                if not lazy:
                    eager.add((name, dst))
            else:
                outside.add((name, target))
    return arrows, arrows - eager, outside


def circles(nodes, arrows) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan), each sorted."""
    succ: dict[str, list[str]] = {n: [] for n in nodes}
    for a, b in sorted(arrows):
        succ[a].append(b)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in succ[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for n in sorted(nodes):
        if n not in index:
            visit(n)
    return sorted(out, key=lambda c: (-len(c), c))


def measure(folder: Path = FOLDER) -> dict:
    mods = modules(folder)
    arrows, lazy, outside = graph(folder)
    return {
        "files": len(mods),
        "lines": sum(len(f.read_text().splitlines()) for f in mods.values()),
        "arrows": len(arrows),
        "lazy_arrows": len(lazy),
        "circles": circles(mods, arrows),
        "outside": sorted({t for _, t in outside}),
        "per_file": {n: len(f.read_text().splitlines()) for n, f in mods.items()},
        "_arrows": sorted(arrows),
        "_lazy": sorted(lazy),
    }


def _at(commit: str, out: Path) -> Path:
    """The folder as it was at ``commit``, unpacked into the directory ``out``."""
    import subprocess
    import tarfile

    tar = subprocess.run(["git", "-C", str(ROOT.parents[1]), "archive", commit, "src/mechsys/solvers"],
                         check=True, capture_output=True).stdout
    path = out / "solvers.tar"
    path.write_bytes(tar)
    with tarfile.open(path) as t:
        t.extractall(out, filter="data")
    return out / "src" / "mechsys" / "solvers"


def main(argv: list[str]) -> None:
    if "--at" in argv:
        import tempfile

        with tempfile.TemporaryDirectory(prefix="solvers_graph_") as tmp:
            m = measure(_at(argv[argv.index("--at") + 1], Path(tmp)))
    else:
        m = measure()
    if "--json" in argv:
        print(json.dumps({k: v for k, v in m.items() if not k.startswith("_")}, indent=1))
        return
    print(f"src/mechsys/solvers{' at ' + argv[argv.index('--at') + 1] if '--at' in argv else ''}: "
          f"{m['files']} files, {m['lines']} lines, {m['arrows']} arrows "
          f"({m['lazy_arrows']} only inside functions)")
    print(f"circles: {len(m['circles'])}")
    for c in m["circles"]:
        print("  {" + ", ".join(c) + "}")
    print("imports leaving the folder: " + (", ".join(m["outside"]) or "none"))
    print("files (lines):")
    for n, k in sorted(m["per_file"].items(), key=lambda x: -x[1]):
        print(f"  {n:22s} {k:5d}")
    if "--arrows" in argv:
        lazy = set(map(tuple, m["_lazy"]))
        print("arrows (* = only inside functions):")
        for a, b in m["_arrows"]:
            print(f"  {a} -> {b}{' *' if (a, b) in lazy else ''}")


if __name__ == "__main__":
    main(sys.argv[1:])
