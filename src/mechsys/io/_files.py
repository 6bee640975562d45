r"""Save a model to a declarative JSON file and load it back (docs/model_files.md).

The file holds data only: bodies (points, mass properties, guesses), parameters, variables,
constraints and loads. A constraint or load is its class name (constraints: the Mech name
of :data:`mechsys.constraints.REGISTRY`; loads: a class of :mod:`mechsys.loads`) and the
arguments its constructor was called with. Loading never imports or calls anything else:
class names outside those two lists are errors, expressions are read by the restricted
grammar of :mod:`mechsys.io._expr` (never ``eval``), strings must be plain identifiers
(so that no constructor's ``sympify`` can run code), and the file's size and nesting are
limited. Values are written as JSON numbers, identifier strings, lists, or one-key objects::

    {"expr": "2*L*sin(T)"}   {"tuple": [...]}   {"body": "crank"}   {"matrix": [[...], ...]}
    {"point": {"body": "crank", "local": ["L", 0], "label": "A"}}
    {"vector": {"body": null, "local": [1, 0]}}     {"vector": {"from": point, "to": point}}
    {"axis": {"origin": point, "direction": vector, "reference": vector | "default" | ...}}
    {"line": [point, point]}   {"plane": [point, point, point]}
    {"constraint": {"type": "Revolute2", "args": [...], "kwargs": {...}}}   (nested stages)
    {"constraint_ref": "c1"}   (a constraint of the model, e.g. a friction load's joint)

Example::

    m.save("crank.json")
    m2 = ms.load("crank.json")
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import sympy as sp

from .. import loads as _loads_pkg
from .._errors import MechError, ModelError
from .._symbols import T, acceleration_symbol, velocity_symbol
from ..constraints import REGISTRY
from ..constraints._base import ConstraintBase
from ..constraints._generalized import (
    GenConstraint,
    GenCylindrical4,
    GenOrthoRevolute4,
    GenRevolute2,
    GenRevolute5,
    GenTranslate2,
    GenTranslate5,
)
from ..constraints._switches import StageSwitch, TimeSwitch
from ..geometry._bodies import Body
from ..geometry._points import Axis, GlobalVector, Line, Plane, Point, Vector
from ..loads._loads import LoadBase
from ..loads._switched import StageSwitchedLoad, TimeSwitchedLoad
from ..model import Model2D, Model3D
from ._expr import CONSTANTS, condition_text, parse, parse_condition, to_text

FORMAT = "mechsys-model"
VERSION = 1
MAX_FILE_BYTES = 5_000_000
MAX_NESTING = 64
MAX_ITEMS = 100_000
_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,99}")
# strings of graphics (colours, label texts): no quotes, brackets, dots or markup, so that they
# can reach neither an expression parser nor the HTML of the 3D viewer as code
#: a coordinate named as "body.coord" (e.g. ``Load("piston.x", ...)``): two plain names
_COORDINATE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,99}\.[A-Za-z][A-Za-z0-9_]{0,99}")
_GRAPHIC_TEXT = re.compile(r"[A-Za-z0-9_#: +-]{0,100}")

#: load class name -> class: the only load classes a file may name
LOAD_TYPES = {name: obj for name in _loads_pkg.__all__
              if isinstance(obj := getattr(_loads_pkg, name), type) and issubclass(obj, LoadBase)
              and obj is not LoadBase}      # (the abstract base builds nothing)
# switched loads (Mech 7.4.1) are built by StageSwitch/TimeSwitch of loads: saved by their class
LOAD_TYPES.update({cls.__name__: cls for cls in (StageSwitchedLoad, TimeSwitchedLoad)})
GEN_JOINTS = (GenRevolute2, GenTranslate2, GenRevolute5, GenTranslate5, GenCylindrical4,
              GenOrthoRevolute4, GenConstraint)
#: constraint types a file may name: the registry, the Gen joints (chapter 11), which write no
#: equations, and the stage and time switches (chapter 5), which hold other constraints
CONSTRAINT_TYPES = {**REGISTRY, **{cls.mech_name: cls for cls in (*GEN_JOINTS, StageSwitch, TimeSwitch)}}


# -- writing ------------------------------------------------------------------------------
class _Writer:
    def __init__(self, model):
        self.m = model
        self.in_model = {id(c): c.name for c in model.constraints}
        self.names = _all_names(model)
        self.texts = _IDENT  # the strings allowed where the writer is (graphics: _GRAPHIC_TEXT)

    def value(self, v, where: str):
        if v is None or isinstance(v, bool):
            return v
        if isinstance(v, (int, np.integer)):
            return int(v)
        if isinstance(v, (float, np.floating)):
            if not math.isfinite(float(v)):
                raise ModelError(f"{where}: cannot save the non-finite number {v!r}")
            return float(v)
        if isinstance(v, str):
            if not (self.texts.fullmatch(v) or _COORDINATE_NAME.fullmatch(v)):
                raise ModelError(f"{where}: cannot save the string {v!r}; model files take strings "
                                 "that are plain names (letters, digits, _; in graphics also "
                                 "spaces, #, :, + and -)")
            return v
        if isinstance(v, sp.MatrixBase):
            return {"matrix": [[self.expr(e, where) for e in v.row(i)] for i in range(v.rows)]}
        if isinstance(v, _CONDITIONS):                   # a switch test
            return {"condition": self.condition(v, where)}
        if isinstance(v, sp.Basic):
            return {"expr": self.expr(v, where)}
        if isinstance(v, np.ndarray):
            return {"array": [self.value(x, where) for x in v.tolist()]}
        if isinstance(v, tuple):
            return {"tuple": [self.value(x, where) for x in v]}
        if isinstance(v, dict):
            return {"dict": [[self.value(k, where), self.value(x, where)] for k, x in v.items()]}
        if isinstance(v, list):
            return [self.value(x, where) for x in v]
        if isinstance(v, Body):
            return {"body": v.name}
        if isinstance(v, Geometry_types):
            return self.geometry(v, where)
        if isinstance(v, ConstraintBase):
            if id(v) in self.in_model:
                return {"constraint_ref": self.in_model[id(v)]}
            return {"constraint": self.constraint(v, where)}
        if isinstance(v, LoadBase):                       # a load inside a switched load
            return {"load": self.load(v, where)}
        raise ModelError(f"{where}: cannot save {v!r} ({type(v).__name__}) to a model file; "
                         "model files hold numbers, expressions, bodies, geometry and the "
                         "registered constraint and load types (no Python callables or objects)")

    def expr(self, e, where: str) -> str:
        e = sp.sympify(e) if isinstance(e, (int, float)) else e
        if not isinstance(e, sp.Expr):
            raise ModelError(f"{where}: cannot save {e!r} ({type(e).__name__}): model files take "
                             "arithmetic expressions only (no conditions or relations)")
        for s in e.free_symbols:
            if not _IDENT.fullmatch(s.name):
                raise ModelError(f"{where}: the symbol name {s.name!r} cannot be written to a "
                                 "model file; use names of letters, digits and _")
            _constant_name(s, where)
        text = to_text(e)
        back = parse(text, self.names, where)  # everything written must read back
        if back != e and sp.simplify(back - e) != 0:
            raise ModelError(f"{where}: the expression {e} does not read back from its text "
                             f"{text!r}; it cannot be saved")
        return text

    def condition(self, c, where: str) -> str:
        for sym in c.free_symbols:
            if not _IDENT.fullmatch(sym.name):
                raise ModelError(f"{where}: the symbol name {sym.name!r} cannot be written to a "
                                 "model file; use names of letters, digits and _")
            _constant_name(sym, where)
        try:
            text = condition_text(c)
        except ModelError as exc:
            raise ModelError(f"{where}: {exc}") from None
        if parse_condition(text, self.names, where) != c:   # everything written must read back
            raise ModelError(f"{where}: the condition {c} does not read back from its text "
                             f"{text!r}; it cannot be saved")
        return text

    def point(self, p: Point, where: str) -> dict:
        return {"point": {"body": None if p.body is None else p.body.name,
                          "local": [self.expr(c, where) for c in p.local], "label": p.label}}

    def geometry(self, g, where: str):
        if isinstance(g, Point):
            return self.point(g, where)
        if isinstance(g, Plane):
            return {"plane": [self.point(p, where) for p in g.points]}
        if isinstance(g, Line):
            return {"line": [self.point(p, where) for p in g.points]}
        if isinstance(g, Axis):
            ref = g.reference_rule if g.reference is None else self.geometry(g.reference, where)
            return {"axis": {"origin": self.point(g.origin, where),
                             "direction": self.geometry(g.dir, where), "reference": ref}}
        if isinstance(g, GlobalVector):
            return {"global_vector": {"local": [self.expr(c, where) for c in g.local],
                                      "bodies": [b.name for b in g.bodies()]}}
        if isinstance(g, Vector):
            if g.endpoints is not None:
                return {"vector": {"from": self.point(g.endpoints[0], where),
                                   "to": self.point(g.endpoints[1], where)}}
            return {"vector": {"body": None if g.body is None else g.body.name,
                               "local": [self.expr(c, where) for c in g.local]}}
        raise ModelError(f"{where}: cannot save the geometry {g!r}")  # pragma: no cover

    def call(self, obj, kind: str, where: str) -> dict:
        args, kwargs = getattr(obj, "_init_args", ((), {}))
        return {"type": kind,
                "args": [self.value(a, f"{where}, argument {i + 1}") for i, a in enumerate(args)],
                "kwargs": {k: self.value(v, f"{where}, argument {k}") for k, v in kwargs.items()}}

    def constraint(self, c: ConstraintBase, where: str) -> dict:
        kind = type(c).mech_name
        if CONSTRAINT_TYPES.get(kind) is not type(c):
            raise ModelError(f"{where}: the constraint class {type(c).__name__} is not a registered "
                             "constraint type; only the types of mechsys.constraints.REGISTRY, "
                             "the Gen joints and the switches can be saved")
        out = self.call(c, kind, where)
        # the symbols the constraint introduces (cam parameters, variables): declared before
        # its arguments are read, with their one allowed assumption (real or none)
        syms = []
        for v in c.new_variables():
            real = v.symbol.assumptions0 == _REAL_ASSUMPTIONS
            if not real and v.symbol.assumptions0 != _PLAIN_ASSUMPTIONS:
                raise ModelError(f"{where}: the variable {v.symbol.name!r} has assumptions "
                                 f"{v.symbol.assumptions0}; model files keep real or plain symbols")
            syms.append([v.symbol.name, real])
        if syms:
            out["symbols"] = syms
        return out

    def load(self, ld: LoadBase, where: str) -> dict:
        kind = type(ld).__name__
        if LOAD_TYPES.get(kind) is not type(ld):
            raise ModelError(f"{where}: the load class {kind} is not one of mechsys.loads; "
                             "it cannot be saved")
        return self.call(ld, kind, where)


Geometry_types = (Point, Vector, Axis)
# (not sp.logic.boolalg.Boolean: a SymPy Symbol is one too)
_CONDITIONS = (sp.core.relational.Relational, sp.And, sp.Or, sp.Not, sp.logic.boolalg.BooleanTrue,
               sp.logic.boolalg.BooleanFalse)
_REAL_ASSUMPTIONS = sp.Symbol("x", real=True).assumptions0
_PLAIN_ASSUMPTIONS = sp.Symbol("x").assumptions0


def _primitive_types() -> dict:
    """Graphics class name -> class: the only graphics classes a file may name."""
    from .. import draw

    return {name: obj for name in draw.__all__
            if isinstance(obj := getattr(draw, name), type) and issubclass(obj, draw.Primitive)
            and obj is not draw.Primitive}


def _all_names(m) -> dict:
    """Every symbol name an expression of model ``m`` may use."""
    names = {"T": T}
    names.update({s.name: s for s in m._params})
    for v in m._variables:
        names[v.symbol.name] = v.symbol
    coords = [s for b in m.bodies for s in b.q] + [v.symbol for v in m._variables]
    for s in coords:  # body coordinates and variables, with their rates
        names[s.name] = s
        for f in (velocity_symbol, acceleration_symbol):
            d = f(s.name)
            names[d.name] = d
    return names


def model_to_dict(m) -> dict:
    """The model as JSON-ready data (see the module docstring); raises
    :class:`~mechsys.ModelError` naming anything that cannot be saved."""
    from ..draw._scene import attached

    w = _Writer(m)
    graphics = []
    prims = attached(m)
    if prims:
        types = _primitive_types()
        w.texts = _GRAPHIC_TEXT
        for i, g in enumerate(prims):
            where = f"graphics[{i}] ({type(g).__name__})"
            if types.get(type(g).__name__) is not type(g):
                raise ModelError(f"{where}: not a graphics class of mechsys.draw; it cannot be saved")
            graphics.append(w.call(g, type(g).__name__, where))
        w.texts = _IDENT
    con_vars = {id(v) for c in m.constraints for v in c.new_variables()}
    con_syms = {v.symbol for c in m.constraints for v in c.new_variables()}
    bodies = []
    for b in m.bodies:
        if b.is_ground:
            continue
        where = f"body {b.name!r}"
        inertia = None if b.inertia is None else w.value(b.inertia, f"{where}, inertia")
        bodies.append({
            "name": b.name,
            "points": [[k, [w.expr(c, f"{where}, point {k!r}") for c in b.points[k]]] for k in b._order],
            "mass": w.expr(b.mass, f"{where}, mass"),
            "centroid": [w.expr(c, f"{where}, centroid") for c in b.centroid],
            "inertia": inertia,
            "guess": [float(g) for g in b.guess],
        })
    return {
        "format": FORMAT,
        "version": VERSION,
        "space": m.space.name,
        "options": {**({"velocity": m.velocity_representation, "coordinates": m.coordinates}
                       if isinstance(m, Model3D) else {}),
                    **({"orientation": "euler"} if getattr(m, "orientation", "angle") == "euler" else {}),
                    **({"backend": m._backend} if m._backend else {})},
        "units": dict(m.units) if m.units else None,
        "parameters": [[s.name, float(v)] for s, v in m._params.items()],
        "variables": [[v.symbol.name, float(v.guess)] for v in m._variables
                      if id(v) not in con_vars and v.symbol not in con_syms],
        "bodies": bodies,
        "constraints": [dict(name=c.name, **w.constraint(c, f"constraint {c.name!r}"))
                        for c in m.constraints],
        "loads": [dict(name=ld.name, **w.load(ld, f"load {ld.name!r}")) for ld in m.load_list],
        "guesses": [[s.name, float(v)] for s, v in m._guess_override.items()],
        "graphics": graphics,
    }


def _constant_name(sym, where: str) -> None:
    """A :class:`ModelError` naming a symbol (a parameter or variable) whose name a model file
    reads as a constant (``pi``, ``E``): it would come back as the constant."""
    if sym.name in CONSTANTS:
        raise ModelError(
            f"{where}: the symbol {sym.name!r} (a parameter or variable of the model) has the "
            f"name of the constant {sym.name}, which a model file reads as that constant, so "
            f"the model cannot be saved: rename it (e.g. {sym.name + '_'!r}); m.parameter "
            "refuses such names")


def save(m, path) -> Path:
    """Write model ``m`` to the JSON file ``path``; returns the path."""
    data = model_to_dict(m)
    path = Path(path)
    path.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


# -- reading ------------------------------------------------------------------------------
class _Reader:
    def __init__(self, m, source: str):
        self.m, self.source = m, source
        self.names = _all_names(m)
        self._nvars = len(m._variables)
        self._bodies: dict = {}
        self.texts = _IDENT

    def err(self, where: str, why: str) -> ModelError:
        return ModelError(f"{self.source}: {where}: {why}")

    def refresh(self) -> None:
        self.names = _all_names(self.m)
        self._nvars = len(self.m._variables)

    def add_variables(self) -> None:
        """The names of the variables added to the model since the last call (a constraint's
        new variables, and their rates): only these, so that loading stays linear in the
        number of constraints (:meth:`refresh` after each made it quadratic)."""
        new = self.m._variables[self._nvars:]
        self._nvars = len(self.m._variables)
        for v in new:
            s = v.symbol
            self.names[s.name] = s
            for f in (velocity_symbol, acceleration_symbol):
                d = f(s.name)
                self.names[d.name] = d

    def expr(self, text, where: str):
        return parse(text, self.names, f"{self.source}: {where}")

    def number(self, v, where: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or abs(v) > 1e300:
            raise self.err(where, f"expected a finite number, got {v!r}")
        return float(v)

    def name(self, v, where: str) -> str:
        if not isinstance(v, str) or not _IDENT.fullmatch(v):
            raise self.err(where, f"expected a name (letters, digits, _), got {v!r}")
        return v

    def label(self, v, where: str) -> str:
        """A body, point, constraint or load name: a short printable text (it is only ever
        compared, and written to tables and pictures: no control characters, no lone
        surrogates that no file encoding can hold)."""
        if not isinstance(v, str) or not 0 < len(v) <= 200:
            raise self.err(where, f"a name must be a text of 1 to 200 characters, got "
                                  f"{_shown(v)}")
        if not _printable(v):
            raise self.err(where, f"the name {_shown(v)} has control characters or lone "
                                  "surrogates; names must be printable text")
        return v

    def body(self, name, where: str):
        if name is None:
            return None
        if not isinstance(name, str):
            raise self.err(where, f"expected a body name, got {name!r}")
        if len(self._bodies) != len(self.m.bodies):     # a dict: Model.body(name) scans the list
            self._bodies = {b.name: b for b in self.m.bodies}
        b = self._bodies.get(name)
        if b is None:
            raise self.err(where, f"unknown body {_shown(name)}")
        return b

    def one_key(self, v, where: str) -> tuple[str, object]:
        if len(v) != 1:
            raise self.err(where, f"expected an object with one key (expr, tuple, body, point, ...), "
                                  f"got keys {sorted(v)[:5]}")
        return next(iter(v.items()))

    def point(self, v, where: str) -> Point:
        if not isinstance(v, dict) or "point" not in v or not isinstance(v["point"], dict):
            raise self.err(where, f"expected a point, got {str(v)[:80]}")
        d = v["point"]
        label = d.get("label")
        if label is not None:
            if not isinstance(label, str):
                raise self.err(where, "a point label must be a string")
            label = self.label(label, where)
        local = d.get("local")
        if not isinstance(local, list) or len(local) != self.m.space.dim:
            raise self.err(where, f"a point needs {self.m.space.dim} local coordinates")
        return Point(self.body(d.get("body"), where), [self.expr(c, where) for c in local], label)

    def exprs(self, v, where: str) -> list:
        if not isinstance(v, list) or len(v) > MAX_ITEMS:
            raise self.err(where, "expected a list of expressions")
        return [self.expr(c, where) for c in v]

    def value(self, v, where: str):
        if v is None or isinstance(v, bool):
            return v
        if isinstance(v, (int, float)):
            self.number(v, where)
            return v
        if isinstance(v, str):
            if not (self.texts.fullmatch(v) or _COORDINATE_NAME.fullmatch(v)):
                raise self.err(where, f"the string {v[:80]!r} is not allowed here (plain names of "
                                      "letters, digits and _; in graphics also spaces, #, :, + and -)")
            return v
        if isinstance(v, list):
            return [self.value(x, where) for x in v]
        if not isinstance(v, dict):
            raise self.err(where, f"unexpected value {v!r}")  # pragma: no cover - JSON has no more
        key, d = self.one_key(v, where)
        if key == "expr":
            return self.expr(d, where)
        if key == "condition":
            return parse_condition(d, self.names, f"{self.source}: {where}")
        if key == "load" and isinstance(d, dict):
            return self.call(d, LOAD_TYPES, "load", where)
        if key == "dict" and isinstance(d, list) and all(isinstance(p, list) and len(p) == 2 for p in d):
            return {self.value(k, where): self.value(x, where) for k, x in d}
        if key == "tuple" and isinstance(d, list):
            return tuple(self.value(x, where) for x in d)
        if key == "array" and isinstance(d, list):
            return np.array([self.value(x, where) for x in d], dtype=float)
        if key == "matrix" and isinstance(d, list) and all(isinstance(r, list) for r in d):
            return sp.Matrix([[self.expr(e, where) for e in r] for r in d])
        if key == "body":
            return self.body(d, where)
        if key == "point":
            return self.point(v, where)
        if key == "vector" and isinstance(d, dict):
            if "from" in d:
                return Vector(self.point(d["from"], where), self.point(d.get("to"), where))
            return Vector(self.body(d.get("body"), where), self.exprs(d.get("local"), where))
        if key == "global_vector" and isinstance(d, dict):
            bodies = d.get("bodies")
            if not isinstance(bodies, list):
                raise self.err(where, "a global vector needs a list of bodies")
            return GlobalVector(sp.Matrix(self.exprs(d.get("local"), where)),
                                [self.body(b, where) for b in bodies])
        if key == "axis" and isinstance(d, dict):
            ref = d.get("reference")
            ref = self.name(ref, where) if isinstance(ref, str) else self.value(ref, where)
            return Axis(self.point(d.get("origin"), where), self.value(d.get("direction"), where), ref)
        if key == "line" and isinstance(d, list) and len(d) == 2:
            return Line(*(self.point(p, where) for p in d))
        if key == "plane" and isinstance(d, list) and len(d) == 3:
            return Plane(*(self.point(p, where) for p in d))
        if key == "constraint" and isinstance(d, dict):
            return self.constraint(d, where)
        if key == "constraint_ref":
            try:
                return self.m.constraint(self.name(d, where))
            except ModelError:
                raise self.err(where, f"unknown constraint {d!r}") from None
        raise self.err(where, f"unknown or malformed value of kind {key!r}")

    def call(self, d: dict, types: dict, what: str, where: str):
        kind = d.get("type")
        if not isinstance(kind, str) or kind not in types:
            raise self.err(where, f"unknown {what} type {kind!r}; model files may name only "
                                  f"{', '.join(sorted(types))}")
        args, kwargs = d.get("args", []), d.get("kwargs", {})
        if not isinstance(args, list) or not isinstance(kwargs, dict):
            raise self.err(where, "args must be a list and kwargs an object")
        a = [self.value(x, f"{where}, argument {i + 1}") for i, x in enumerate(args)]
        kw = {self.name(k, where): self.value(x, f"{where}, argument {k}") for k, x in kwargs.items()}
        try:
            return types[kind](*a, **kw)
        except ModelError as exc:
            raise self.err(where, str(exc)) from None
        except (TypeError, ValueError, AttributeError, IndexError, KeyError, NotImplementedError,
                ArithmeticError) as exc:
            raise self.err(where, f"bad arguments for {kind}: {exc}") from None

    def constraint(self, d, where: str):
        if not isinstance(d, dict):
            raise self.err(where, "expected a constraint object")
        syms = d.get("symbols", [])
        if not isinstance(syms, list):
            raise self.err(where, "symbols must be a list of [name, real] pairs")
        for item in syms:
            if not isinstance(item, list) or len(item) != 2 or not isinstance(item[1], bool):
                raise self.err(where, "symbols must be a list of [name, real] pairs")
            name = self.name(item[0], where)
            if name not in self.names:
                self.names[name] = sp.Symbol(name, real=True) if item[1] else sp.Symbol(name)
        return self.call(d, CONSTRAINT_TYPES, "constraint", where)


def _check_shape(obj, depth: int = 0, count: list | None = None) -> None:
    """Bound the nesting and size of the parsed JSON before anything reads it."""
    count = count if count is not None else [0]
    count[0] += 1
    if count[0] > MAX_ITEMS:
        raise ModelError(f"model file has more than {MAX_ITEMS} values")
    if depth > MAX_NESTING:
        raise ModelError(f"model file nests deeper than {MAX_NESTING} levels")
    if isinstance(obj, dict):
        for v in obj.values():
            _check_shape(v, depth + 1, count)
    elif isinstance(obj, list):
        for v in obj:
            _check_shape(v, depth + 1, count)


def _json_depth_ok(text: str) -> bool:
    """Bracket depth of the raw text (outside strings) below the limit, checked before
    ``json.loads`` (whose recursion a deeply nested file would exhaust)."""
    depth, in_str, esc = 0, False, False
    for ch in text:
        if in_str:
            if esc:
                esc = False
            elif ch == "\\":
                esc = True
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
            if depth > MAX_NESTING:
                return False
        elif ch in "]}":
            depth -= 1
    return True


def model_from_dict(data: dict, source: str = "model file"):
    """Build a model from the data of :func:`model_to_dict` (checked as from a stranger).
    Every problem is a :class:`~mechsys.ModelError` (or another :class:`~mechsys.MechError`)."""
    try:
        return _model_from_dict(data, source)
    except MechError:
        raise
    except (TypeError, ValueError, AttributeError, IndexError, KeyError, RecursionError,
            ZeroDivisionError, OverflowError, ArithmeticError, NotImplementedError) as exc:
        # malformed data that slipped past the checks into a constructor: still our error
        raise ModelError(f"{source}: malformed model file ({type(exc).__name__}: {exc})") from None


def _model_from_dict(data: dict, source: str):
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ModelError(f"{source}: not a mechsys model file (no \"format\": \"{FORMAT}\")")
    if data.get("version") != VERSION:
        raise ModelError(f"{source}: model file version {data.get('version')!r}; this mechsys reads "
                         f"version {VERSION}")
    _check_shape(data)
    space = data.get("space")
    opts = data.get("options") or {}
    if not isinstance(opts, dict) or not all(isinstance(v, str) and _IDENT.fullmatch(v)
                                             for v in opts.values()):
        raise ModelError(f"{source}: options must map names to plain names")
    unknown = sorted(set(opts) - {"velocity", "coordinates", "backend", "orientation"})
    if unknown:
        raise ModelError(f"{source}: unknown options {unknown}")
    if "backend" in opts:
        from ..compile._backends import available_backends

        if opts["backend"] not in available_backends():
            raise ModelError(f"{source}: options.backend {opts['backend']!r} is not a backend of "
                             f"this installation; choose from {available_backends()} (or leave "
                             "it out)")
    if space == "planar":
        if set(opts) - {"backend", "orientation"}:
            raise ModelError(f"{source}: velocity and coordinates options are for spatial models")
        m = Model2D(backend=opts.get("backend"), orientation=opts.get("orientation", "angle"))
    elif space == "spatial":
        if "orientation" in opts:
            raise ModelError(f"{source}: the orientation option is for planar models")
        m = Model3D(**opts)
    else:
        raise ModelError(f"{source}: space must be 'planar' or 'spatial', got {space!r}")
    r = _Reader(m, source)
    units = data.get("units")
    if units:
        if not isinstance(units, dict):
            raise r.err("units", "expected an object")
        m.set_units(**{r.name(k, "units"): r.name(v, "units") for k, v in units.items()})
    for i, item in enumerate(_list(data, "parameters", source)):
        where = f"parameters[{i}]"
        if not isinstance(item, list) or len(item) != 2:
            raise r.err(where, "expected [name, value]")
        m.parameter(r.name(item[0], where), r.number(item[1], where))
    for i, item in enumerate(_list(data, "variables", source)):
        where = f"variables[{i}]"
        if not isinstance(item, list) or len(item) != 2:
            raise r.err(where, "expected [name, guess]")
        m.variable(r.name(item[0], where), r.number(item[1], where))
    r.refresh()
    for i, b in enumerate(_list(data, "bodies", source)):
        where = f"bodies[{i}]"
        if not isinstance(b, dict):
            raise r.err(where, "expected an object")
        name = b.get("name")
        if not isinstance(name, str) or not name or len(name) > 200:
            raise r.err(where, f"a body needs a name, got {_shown(name)}")
        name = r.label(name, where)
        where = f"body {name!r}"
        pts = {}
        points = b.get("points", [])
        if not isinstance(points, list):
            raise r.err(where, "points must be a list of [name, [coordinates]] pairs")
        for k in points:
            if not isinstance(k, list) or len(k) != 2 or not isinstance(k[0], str):
                raise r.err(where, "points must be [name, [coordinates]] pairs")
            pts[r.label(k[0], f"{where}, points")] = r.exprs(k[1], f"{where}, point {k[0]!r}")
        inertia = b.get("inertia")
        inertia = None if inertia is None else r.value(inertia, f"{where}, inertia")
        centroid = b.get("centroid")
        body = m.add_body(name, points=pts or None, mass=r.expr(b.get("mass", 0), f"{where}, mass"),
                          centroid=None if centroid is None else r.exprs(centroid, f"{where}, centroid"),
                          inertia=inertia)
        guess = b.get("guess")
        if guess is not None:
            g = np.array([r.number(x, f"{where}, guess") for x in guess]) if isinstance(guess, list) \
                else None
            if g is None or g.shape != body.guess.shape:
                raise r.err(where, f"guess must be a list of {body.guess.size} numbers")
            body.guess = g
    r.refresh()
    for i, c in enumerate(_list(data, "constraints", source)):
        if not isinstance(c, dict):
            raise r.err(f"constraints[{i}]", "expected an object")
        name = c.get("name")
        where = f"constraint {name!r}" if isinstance(name, str) else f"constraints[{i}]"
        con = r.constraint(c, where)
        try:
            m.add(con, name=r.label(name, where) if name is not None else None)
        except ModelError as exc:
            raise r.err(where, str(exc)) from None
        r.add_variables()
    for i, ld in enumerate(_list(data, "loads", source)):
        if not isinstance(ld, dict):
            raise r.err(f"loads[{i}]", "expected an object")
        name = ld.get("name")
        where = f"load {name!r}" if isinstance(name, str) else f"loads[{i}]"
        obj = r.call(ld, LOAD_TYPES, "load", where)
        try:
            m.add_load(obj, name=r.label(name, where) if name is not None else None)
        except ModelError as exc:
            raise r.err(where, str(exc)) from None
    guesses = {}
    for i, item in enumerate(_list(data, "guesses", source)):
        where = f"guesses[{i}]"
        if not isinstance(item, list) or len(item) != 2:
            raise r.err(where, "expected [coordinate, value]")
        guesses[r.name(item[0], where)] = r.number(item[1], where)
    if guesses:
        try:
            m.set_guess(guesses)
        except ModelError as exc:
            raise r.err("guesses", str(exc)) from None
    graphics = _list(data, "graphics", source)
    if graphics:
        from .. import draw

        types = _primitive_types()
        r.texts = _GRAPHIC_TEXT
        prims = []
        for i, g in enumerate(graphics):
            if not isinstance(g, dict):
                raise r.err(f"graphics[{i}]", "expected an object")
            prims.append(r.call(g, types, "graphics", f"graphics[{i}]"))
        draw.attach(m, *prims)
    return m


def _printable(text: str) -> bool:
    """``text`` is printable and encodable (no control characters, no lone surrogates)."""
    if not text.isprintable():
        return False
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def _shown(v) -> str:
    """``v`` in a message: its ``repr`` (ASCII, so that a lone surrogate prints), shortened."""
    return ascii(v if not isinstance(v, str) else v[:80])


def _list(data: dict, key: str, source: str) -> list:
    v = data.get(key, [])
    if v is None:
        return []
    if not isinstance(v, list):
        raise ModelError(f"{source}: {key!r} must be a list")
    return v


def load(path):
    """Read a model file written by :meth:`Model.save` (safe for files from strangers: see
    the module docstring). Bad or malicious files raise :class:`~mechsys.ModelError`."""
    path = Path(path)
    text = read_text_bounded(path, MAX_FILE_BYTES, "model file")
    if not _json_depth_ok(text):
        raise ModelError(f"{path}: model file nests deeper than {MAX_NESTING} levels")
    try:
        data = json.loads(text, parse_constant=_no_constant, parse_int=_int)
    except ValueError as exc:  # (JSONDecodeError is one)
        if isinstance(exc, ModelError):
            raise ModelError(f"{path}: {exc}") from None
        raise ModelError(f"{path}: not valid JSON ({exc})") from None
    except RecursionError:                                   # pragma: no cover - depth checked
        raise ModelError(f"{path}: model file nests deeper than {MAX_NESTING} levels") from None
    return model_from_dict(data, str(path))


def read_text_bounded(path: Path, limit: int, what: str) -> str:
    """The UTF-8 text of the regular file ``path``, read with a byte cap: at most ``limit``
    bytes are ever read (the size ``stat`` reports is not trusted: ``/dev/zero`` reports 0),
    and only regular files are opened for reading (a FIFO would block, a device never end).
    Every failure is a :class:`~mechsys.ModelError` naming the path."""
    import os
    import stat

    try:
        # O_NONBLOCK: opening a FIFO must not wait for a writer before we can refuse it
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except OSError as exc:
        raise ModelError(f"{path}: cannot open the {what} ({exc.strerror or exc})") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
        raise ModelError(f"{path}: {kind}; a {what} is a regular file")
    with os.fdopen(fd, "rb") as fh:
        try:
            raw = fh.read(limit + 1)
        except OSError as exc:
            raise ModelError(f"{path}: cannot read the {what} ({exc.strerror or exc})") from None
    if len(raw) > limit:
        raise ModelError(f"{path}: {what} of more than {limit} bytes; at most {limit} are read "
                         "(the limit MAX_FILE_BYTES)")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: the {what} is not UTF-8 text (byte {raw[exc.start]:#04x} at "
                         f"offset {exc.start}); model files are written in UTF-8") from None


def _int(text: str) -> int:
    if len(text.lstrip("-")) > 40:
        raise ModelError(f"model file contains an integer of {len(text)} digits; at most 40 are read")
    return int(text)


def _no_constant(name: str):
    raise ModelError(f"model file contains {name}; numbers must be finite")
