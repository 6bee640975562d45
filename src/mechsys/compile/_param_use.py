"""Which parts of a model use given parameter symbols (for ``Model.clear_parameters``)."""

from __future__ import annotations

import sympy as sp


def _symbols(obj, seen: set, depth: int = 0) -> set:
    """Free symbols of SymPy objects found in ``obj`` (containers and plain objects' fields,
    a few levels deep; references back to a model are not followed)."""
    if id(obj) in seen or depth > 4:
        return set()
    seen.add(id(obj))
    if isinstance(obj, (sp.Basic, sp.MatrixBase)):
        return set(obj.free_symbols)
    if isinstance(obj, (str, bytes, int, float, complex, type(None))):
        return set()
    if isinstance(obj, dict):
        items = list(obj.keys()) + list(obj.values())
    elif isinstance(obj, (list, tuple, set, frozenset)):
        items = list(obj)
    elif hasattr(obj, "__dict__"):
        items = [v for k, v in vars(obj).items() if k not in ("model", "_model")]
    else:
        return set()
    out: set = set()
    for x in items:
        if type(x).__name__ in ("Model", "Model2D", "Model3D"):
            continue
        out |= _symbols(x, seen, depth + 1)
    return out


def parameter_users(model, params) -> dict:
    """``{parameter name: [labels of the constraints, loads and bodies using it]}`` for the
    parameters of ``params`` that are in use."""
    params = set(params)
    used: dict = {}

    def note(syms, label):
        for p in syms & params:
            used.setdefault(p.name, []).append(label)

    eqs, owners, _ = model._all_equations()
    by_owner: dict = {}
    for e, o in zip(eqs, owners):
        lab = o.label() if hasattr(o, "label") else str(o)
        by_owner.setdefault(lab, set()).update(e.free_symbols)
    for lab, syms in by_owner.items():
        note(syms, lab)
    for ld in model._loads:
        note(_symbols(ld, set()), ld.label() if hasattr(ld, "label") else repr(ld))
    for b in model._bodies[1:]:
        note(_symbols(b, set()), f"body {b.name!r}")
    return used
