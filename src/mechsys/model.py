r"""The editable model: bodies, constraints, parameters, variables. No numerics here except
through the compiled :class:`~mechsys.compile.System` it caches.

``Model2D`` and ``Model3D`` differ only in their space object (see ``_space``).
"""

from __future__ import annotations

import dataclasses
import re
import warnings
from collections.abc import Mapping

import numpy as np
import sympy as sp

from ._errors import (
    ConstraintCountError,
    MechError,
    ModelError,
    RedundantConstraintWarning,
    SingularJacobianError,
    UnknownBodyError,
    UnknownConstraintError,
    choice,
    parameter_value,
    unknown_options,
)
from ._symbols import T, acceleration_symbol, free_symbols, same_name_advice, velocity_symbol
from .compile import System, make_layout, time_derivative
from .compile._backends import gc_paused
from .compile._options import _UNSET, CompileOptions, process_equation
from .compile._options import updated as _updated_options
from .constraints import Constraint, ConstraintBase, Variable
from .constraints._generalized import GenJoint, GenKinematics, check_new_joint
from .constraints._switches import StageSwitch, is_velocity_constraint
from .geometry._bodies import Body
from .geometry._planar_euler import PLANAR_EULER
from .geometry._points import Axis, Point, Vector, as_point, as_vector
from .geometry._space import PLANAR, SPATIAL, Space
from .geometry._units import (
    INERTIA,
    LENGTH,
    MASS,
    TIME,
    check_units,
    convert,
    has_quantity,
    is_quantity,
    number,
    resolve,
    to_units,
)
from .results._linkage import LinkageOutputs
from .results._load_outputs import LoadOutputs, lambda_guess_vector
from .results._momentum import MomentumOutputs
from .results._outputs import OutputFunctions, VelocityViews
from .solvers import ORDERS, PositionOptions, sweep
from .solvers._linalg import Scaling
from .solvers._position import dependency
from .solvers._rank import constraint_names as _constraint_names
from .solvers._tolerances import SPARSE_THRESHOLD

_parameter_value = parameter_value   # the validation lives with the errors it raises


#: names SymPy and model files read as constants: not parameter or variable names
_CONSTANT_NAMES = {"pi": "the constant pi", "E": "Euler's number e", "I": "the imaginary unit",
                   "oo": "infinity", "zoo": "complex infinity", "nan": "not-a-number"}


class DOF(int):
    r"""Degrees of freedom of a model: an ``int`` (from the Jacobian rank at the current
    guess) carrying a report.

    Attributes: ``coordinates`` (n), ``equations`` (m), ``gruebler`` (n - m, the count),
    ``rank`` (of :math:`\Phi_q` at ``configuration``), ``redundant`` (constraints with dependent
    equations), ``at``: where the rank is taken — ``"guess"`` (the guess, assembled or with a
    positive Gruebler count), ``"assembled"`` (the assembled configuration nearest a guess
    that does not assemble) or ``"unassembled guess"`` (no assembly found: the figure holds
    at the guess only).
    """

    def __new__(cls, value, **info):
        obj = super().__new__(cls, value)
        obj.__dict__.update(info)
        return obj

    def __repr__(self) -> str:
        lines = [
            f"{int(self)} degree(s) of freedom",
            f"  coordinates: {self.coordinates}, equations: {self.equations}",
            f"  Gruebler count (coordinates - equations): {self.gruebler}",
            f"  Jacobian rank {self._where()}: {self.rank} -> {int(self)} DOF",
        ]
        if self.redundant:
            lines.append("  redundant (dependent) constraints: "
                         + ", ".join(c.label() for c in self.redundant))
        if getattr(self, "singular_guess", ""):
            lines.append("  " + self.singular_guess)
        if getattr(self, "at", "guess") == "unassembled guess":
            lines.append("  the guesses do not assemble the mechanism and no assembled "
                         "configuration was found from them, so this figure holds at the guess "
                         "only: a paradoxical linkage (mobile although the Gruebler count says "
                         "otherwise) shows its mobility only where it is assembled; give guesses "
                         "near an assembled position")
        return "\n".join(lines)

    def _where(self) -> str:
        at = getattr(self, "at", "guess")
        if at == "assembled":
            return "at the assembled configuration nearest the guess (t = 0)"
        if getattr(self, "singular_guess", ""):
            return "near the current guess"
        return "at the current guess" + (" (not assembled)" if at == "unassembled guess" else "")

    __str__ = __repr__


class Model(OutputFunctions, LoadOutputs, VelocityViews, MomentumOutputs, LinkageOutputs):
    """An editable mechanism model. Use :class:`Model2D` or :class:`Model3D`."""

    space: Space

    def __init__(self, backend: str | None = None):
        self._bodies: list[Body] = []
        self._constraints: list[ConstraintBase] = []
        self._params: dict[sp.Symbol, float] = {}
        self._variables: list[Variable] = []
        self._loads: list = []
        self._version = 0
        self._system: System | None = None
        self._guess_override: dict[sp.Symbol, float] = {}
        if backend is not None:
            from .compile._backends import available_backends

            # a misspelt name used to pass here and fail (or not) at the first compile
            choice(backend, available_backends(), "backend",
                   "None (the default) picks the fastest installed one")
        self._backend = backend
        self._compile_opts = CompileOptions()
        self.last_solution = None
        ground = Body(self.space, "ground", 1, is_ground=True)
        ground.model = self
        self._bodies.append(ground)

    # -- bodies -------------------------------------------------------------------------
    @property
    def ground(self) -> Body:
        """Ground, body number 1: fixed, coordinates none."""
        return self._bodies[0]

    @property
    def bodies(self) -> list[Body]:
        """All bodies, ground first."""
        return list(self._bodies)

    def add_body(self, name: str, points=None, guess=None, mass=0, centroid=None,
                 inertia=None) -> Body:
        """Add a body and return its handle.

        ``points``: ``{name: local coords}`` (numbered 1.. in order) or a list of coords;
        ``guess``: ``((x, y), angle)`` in 2D, ``((x, y, z), rotation)`` in 3D.
        """
        if not isinstance(name, str) or not name:
            raise ModelError(f"body name must be a non-empty string, got {name!r}")
        if name in self._names()[0]:
            raise ModelError(f"a body named {name!r} already exists; body names must be unique")
        # numbers are never reused: a removed body's successors keep theirs (and their symbols)
        # (bodies are appended in the order of their numbers: the last has the largest)
        number = max(self._bodies[-1].number, getattr(self, "_last_number", 1)) + 1
        taken = {s.name for s in self._params} | {v.symbol.name for v in self._variables}
        for c in self.space.coordinate_names:
            for sym in (f"{c}{number}", f"{c}{number}_d", f"{c}{number}_dd"):
                if sym in taken:  # a symbol declared before the naming rules saw it
                    raise ModelError(f"body {name!r} (number {number}) would get the symbol "
                                     f"{sym!r}, which is already a parameter or variable")
        if has_quantity((points, guess, mass, centroid, inertia)):
            points, guess, mass, centroid, inertia = self._body_numbers(
                name, points, guess, mass, centroid, inertia)
        b = Body(self.space, name, number, points=points, guess=guess, mass=mass,
                 centroid=centroid, inertia=inertia)
        b.model = self
        self._bodies.append(b)
        self._last_number = number
        self._touch_added(0, b)
        return b

    def remove_body(self, body, cascade: bool = False) -> Body:
        """Remove a moving body (by handle, name or number); returns it.

        A body still used by constraints or loads is refused with a :class:`ModelError`
        naming them, unless ``cascade=True``, which removes those constraints and loads
        too. The other bodies keep their numbers and coordinate symbols (a later
        ``add_body`` takes a new number), as constraints keep theirs after :meth:`remove`.
        Guesses set for the body's coordinates are dropped."""
        b = self.body(body)
        if b.is_ground:
            raise ModelError("ground (body 1) cannot be removed")
        users = [c for c in self._constraints if any(self.body(x) is b for x in c.bodies())]
        loads = [ld for ld in self._loads if any(self.body(x) is b for x in ld.bodies())]
        if (users or loads) and not cascade:
            names = [c.label() for c in users] + [ld.label() for ld in loads]
            raise ModelError(
                f"body {b.name!r} is used by {', '.join(names)}; remove them first "
                "(m.remove(...), m.remove_load(...)) or call remove_body(..., cascade=True) to "
                "remove them with the body")
        for c in users:
            self.remove(c)
        for ld in loads:
            self.remove_load(ld)
        self._bodies.remove(b)
        for s in b.q:
            self._guess_override.pop(s, None)
        b.model = None
        self._touch()
        return b

    def copy(self) -> Model:
        """An independent copy of the model: bodies, points, constraints, loads,
        parameters, variables, guesses and attached graphics, all rebound to the copy
        (editing one does not change the other). The compiled system and the last solution
        are not copied (the copy compiles on first use). ``copy.copy(m)`` and
        ``copy.deepcopy(m)`` do the same."""
        return self.__deepcopy__({})

    def __copy__(self) -> Model:
        """``copy.copy(m)`` is :meth:`copy`: a shallow copy would share the lists of bodies,
        constraints and loads, so editing one model would change the other."""
        return self.copy()

    def __deepcopy__(self, memo) -> Model:
        """``copy.deepcopy(m)`` is :meth:`copy` (the shared singletons stay shared; the
        compiled system and the last solution are not copied)."""
        import copy as _copy
        import sys

        # shared singletons stay shared: the spaces (compared by identity) and the time symbol
        for single in (PLANAR, SPATIAL, PLANAR_EULER, T):
            memo.setdefault(id(single), single)
        new = type(self).__new__(type(self))
        memo[id(self)] = new
        for key, value in self.__dict__.items():
            if key in ("_reduced", "_name_index"):  # made again on use (compiled systems of
                continue                                # redundant models, the name index)
            skip = key in ("_system", "last_solution")
            new.__dict__[key] = None if skip else _copy.deepcopy(value, memo)
        scene = sys.modules.get("mechsys.draw._scene")  # graphics, if any were attached
        if scene is not None and scene.attached(self):
            scene.attach(new, *_copy.deepcopy(scene.attached(self), memo))
        return new

    def _body_numbers(self, name, points, guess, mass, centroid, inertia):
        """``add_body``'s inputs with pint quantities in the model's units, each checked for
        its dimension (decision 0043)."""
        what = f"body {name!r}"
        u = self.units
        if isinstance(guess, (list, tuple)) and len(guess) == 2:
            guess = (convert(guess[0], u, f"{what} guess position", LENGTH),
                     convert(guess[1], u, f"{what} guess rotation"))
        return (convert(points, u, f"{what} points", LENGTH), guess,
                convert(mass, u, f"{what} mass", MASS), convert(centroid, u, f"{what} centroid", LENGTH),
                convert(inertia, u, f"{what} inertia", INERTIA))

    def set_mass_properties(self, body, mass=None, centroid=None, inertia=None) -> None:
        """Change a body's mass, centroid (local) or inertia (about the centroid, body axes)
        after it was added (Mech's ``SetBodies[Body[b, Mass -> ...]]``)."""
        from .geometry._points import _as_matrix

        b = self.body(body)
        if has_quantity((mass, centroid, inertia)):
            _, _, mass, centroid, inertia = self._body_numbers(b.name, None, None, mass, centroid,
                                                               inertia)
        if b.is_ground:
            raise ModelError("ground has no mass properties")
        old = (b.mass, b.centroid, b.inertia)
        try:  # the Body setters check each value; one bad value changes nothing
            if mass is not None:
                b.mass = mass
            if centroid is not None:
                c = _as_matrix(centroid, f"centroid of body {b.name!r}")
                if len(c) != self.space.dim:
                    raise ModelError(f"centroid of body {b.name!r} needs {self.space.dim} coordinates")
                b.centroid = c
            if inertia is not None:
                b.inertia = inertia
        except ModelError:
            b.mass, b.centroid, b.inertia = old
            raise
        self._touch()

    def body(self, spec) -> Body:
        """A body by handle, name or Mech number (ground is 1)."""
        if isinstance(spec, Body):
            if getattr(spec, "model", None) is not self:
                raise UnknownBodyError(f"body {spec.name!r} belongs to another model")
            return spec
        if isinstance(spec, str):
            b = self._names()[0].get(spec)
            if b is not None:
                return b
            raise UnknownBodyError(
                f"no body named {spec!r}; bodies are {[b.name for b in self._bodies]}")
        if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
            for b in self._bodies:
                if b.number == spec:
                    return b
            nums = [b.number for b in self._bodies]
            which = (f"1..{len(nums)}" if nums == list(range(1, len(nums) + 1))
                     else f"{nums} (numbers of removed bodies are not reused)")
            raise UnknownBodyError(f"no body number {spec}; bodies are numbered {which} (1 = ground)")
        raise UnknownBodyError(f"cannot address a body by {spec!r}; use a handle, name or number")

    # -- parameters and variables --------------------------------------------------------
    def parameter(self, name: str, value: float) -> sp.Symbol:
        """Declare a parameter with a value; returns its symbol for use in expressions.
        Changing values later (:meth:`set_parameters`) needs no recompilation.

        The name must not be one the model uses for something else, nor a name SymPy and model
        files read as a constant (``pi``, ``E``, ``I``, ``oo``, ``zoo``, ``nan``): the time
        ``T``, a body
        coordinate present or future (``x2``, ``th3``, ``e04`` ...), a velocity or
        acceleration symbol (``<coordinate or variable>_d``, ``_dd``), a multiplier
        (``lam<c>_<k>``, ``lamN_<body>``), a variable or another parameter."""
        if not isinstance(name, str) or not name:
            raise ModelError(f"parameter name must be a non-empty string, got {name!r}")
        s = sp.Symbol(name)
        if s in self._params:
            raise ModelError(f"parameter {name!r} already exists; use set_parameters to change it")
        why = self._name_conflict(name)
        if why:
            raise ModelError(f"parameter name {name!r} is reserved: {why}; choose another name")
        self._params[s] = _parameter_value(name, to_units(value, self.units, f"parameter {name!r}"))
        self._touch()
        return s

    def set_parameters(self, values: Mapping | None = None, **kw) -> None:
        """Change parameter values: ``set_parameters(L=6)`` or ``set_parameters({L: 6})``."""
        items = dict(values or {})
        items.update(kw)
        new = {}
        for k, v in items.items():
            s = k if isinstance(k, sp.Symbol) else sp.Symbol(str(k))
            if s not in self._params:
                raise ModelError(f"unknown parameter {k!r}; parameters are "
                                 f"{[p.name for p in self._params]}")
            new[s] = _parameter_value(s.name, to_units(v, self.units, f"parameter {s.name!r}"))
        self._params.update(new)  # all or nothing: one bad value changes none

    #: the declared unit system (``{"length": ..., "mass": ..., "time": ...}``) or None
    units: dict | None = None

    def set_units(self, length: str | None = None, mass: str | None = None,
                  time: str | None = None) -> None:
        """Declare the model's consistent unit system (pint unit names, e.g. ``"mm"``,
        ``"kg"``, ``"s"``); pint quantities given as parameter values, or converted with
        :meth:`to_units`, are then turned into numbers in it. Computation never needs units
        (any consistent system works); see ``docs/guide.md``, Units. Needs pint."""
        given = {k: v for k, v in (("length", length), ("mass", mass), ("time", time)) if v}
        if not given:
            raise ModelError("set_units: give at least one of length=, mass=, time=")
        self.units = {**(self.units or {}), **check_units(given)}

    def _coordinate_dims(self, sym) -> tuple | None:
        """The dimension ``(length, mass, time)`` of a body coordinate: its first ``dim``
        coordinates are a position (a length), the rest an angle or Euler parameters (none);
        None for a model variable (a quantity keeps its own dimension)."""
        for b in self.bodies:
            if sym in list(b.q):
                return LENGTH if list(b.q).index(sym) < self.space.dim else (0, 0, 0)
        return None

    def to_units(self, value) -> float:
        """A pint quantity as a number in the model's declared units (``m.set_units``):
        ``[length]^a [mass]^b [time]^c`` becomes ``length^a mass^b time^c``, a dimensionless
        one (an angle) radians. Any other value is returned unchanged.
        ``ms.Force(p, (1, 0), m.to_units(20 * ureg.N))``."""
        return to_units(value, self.units, "to_units")

    @property
    def parameters(self) -> dict[str, float]:
        return {s.name: v for s, v in self._params.items()}

    def clear_parameters(self, *names) -> None:
        """Remove parameters (Mech's ``ClearParameters``): the named ones (names or
        symbols), or every parameter when none is named. A parameter that a constraint,
        load or body of the model still uses is refused (``ModelError`` naming its users),
        since the model could no longer be evaluated; all or nothing."""
        from .compile._param_use import parameter_users

        if names:
            syms = [n if isinstance(n, sp.Symbol) else sp.Symbol(str(n)) for n in names]
            unknown = [str(x) for x in syms if x not in self._params]
            if unknown:
                raise ModelError(f"clear_parameters: unknown parameter(s) {unknown}; parameters "
                                 f"are {[p.name for p in self._params]}")
        else:
            syms = list(self._params)
        used = parameter_users(self, syms)
        if used:
            which = "; ".join(f"{p} by {', '.join(u)}" for p, u in used.items())
            raise ModelError(f"clear_parameters: parameter(s) still used ({which}); remove or "
                             "replace those first, or change the value with set_parameters")
        for x in syms:
            del self._params[x]
        self._touch()

    def variable(self, name: str, guess: float = 0.0) -> sp.Symbol:
        """Declare a new model variable (Mech's ``{s, guess}``) for use in constraints."""
        if not isinstance(name, str) or not name:
            raise ModelError(f"variable name must be a non-empty string, got {name!r}")
        for v in self._variables:
            if v.symbol.name == name:
                raise ModelError(f"variable {name!r} already exists")
        self._check_new_variable(name)
        v = Variable(name, guess)
        self._variables.append(v)
        self._touch()
        return v.symbol

    def _name_conflict(self, name: str) -> str | None:
        """Why ``name`` cannot be a parameter or a new variable (``None`` if it can): the
        symbols the model makes itself (time, coordinates of bodies present or future, their
        velocities and accelerations, multipliers) and the names already taken."""
        if name == T.name:
            return "it is the time symbol T"
        if name in _CONSTANT_NAMES:
            return (f"it is SymPy's name of {_CONSTANT_NAMES[name]}, which expressions given as "
                    "text and model files read as that constant (a model with it cannot be "
                    "saved)")
        for suffix, what in (("_dd", "acceleration"), ("_d", "velocity")):
            if name.endswith(suffix):
                base = name[: -len(suffix)]
                if self._coordinate_owner(base) or any(v.symbol.name == base for v in self._variables):
                    return f"it is the {what} symbol of {base!r}"
                break
        owner = self._coordinate_owner(name)
        if owner:
            return owner
        if re.fullmatch(r"lam\d+_\d+|lamN_.*", name):
            return "it is the name pattern of the Lagrange multipliers (lam<constraint>_<k>, lamN_<body>)"
        if any(v.symbol.name == name for v in self._variables):
            return "it is a variable of the model"
        if any(p.name == name for p in self._params):
            return "it is a parameter of the model"
        return None

    def _coordinate_text(self, name: str) -> str:
        """``"'x3' (coordinate x of body 'rod')"``: a coordinate or variable named for a user."""
        owner = self._coordinate_owner(name)
        if owner:
            return f"{name!r} ({owner.replace('it is the symbol of ', '')})"
        if any(v.symbol.name == name for v in self._variables):
            return f"{name!r} (a variable of the model)"
        return repr(name)

    def _coordinate_owner(self, name: str) -> str | None:
        """``"it is coordinate th of body 2 ..."`` when ``name`` has the form of a body
        coordinate symbol (``<coordinate name><body number>``, numbers from 2), else None."""
        for c in self.space.coordinate_names:
            rest = name[len(c):]
            if name.startswith(c) and rest.isdigit() and rest[0] != "0" and int(rest) >= 2:
                n = int(rest)
                owner = [b for b in self._bodies if b.number == n]
                last = max(max(b.number for b in self._bodies), getattr(self, "_last_number", 1))
                who = (f"body {owner[0].name!r}" if owner
                       else "the body that will be added as number " + rest if n > last
                       else f"a removed body (number {rest}, not reused)")
                return f"it is the symbol of coordinate {c} of {who}"
        return None

    def _check_new_variable(self, name: str) -> None:
        """A new variable's symbol must be free, and its velocity and acceleration symbols
        (``name_d``, ``name_dd``) must not be parameters."""
        why = self._name_conflict(name)
        if why:
            raise ModelError(f"variable name {name!r} is reserved: {why}; choose another name")
        for derived in (name + "_d", name + "_dd"):
            if sp.Symbol(derived) in self._params:
                raise ModelError(f"variable {name!r} collides with parameter {derived!r}, which "
                                 "would be its velocity/acceleration symbol; rename one of them")

    # -- constraints --------------------------------------------------------------------
    def add(self, constraint: ConstraintBase, name: str | None = None) -> ConstraintBase:
        """Add a constraint; returns it as the handle. Its Mech number is its position."""
        if not isinstance(constraint, ConstraintBase):
            raise ModelError(f"add() takes a constraint object, got {constraint!r}")
        if constraint.model is not None:
            raise ModelError(f"{constraint.label()} is already in a model; create a new one")
        default = len(self._constraints) + 1
        taken = self._names()[1]
        while f"c{default}" in taken:
            default += 1     # a name given earlier took the default one: not a clash of the user's
        name = _checked_name(name, "constraint", f"c{default}")
        resolve(constraint, self.units, f"constraint {name!r}")
        if name in taken:
            raise ModelError(f"a constraint named {name!r} already exists")
        for v in constraint.new_variables():
            # a default-named variable (gears) must not silently merge with another's
            if getattr(v, "auto_named", False) and any(v.symbol == w.symbol for w in self._variables):
                raise ModelError(f"constraint {name!r} ({type(constraint).__name__}): its default "
                                 f"variable {v.symbol.name!r} is "
                                 "already in the model (two such constraints join the same bodies); "
                                 "give its variable explicitly as (sym, guess)")
        if isinstance(constraint, StageSwitch):
            constraint.check_stages(self.space, name)
        if isinstance(constraint, GenJoint):
            constraint.name, constraint.number = name, len(self._constraints) + 1
            try:
                check_new_joint(self, constraint)
            finally:
                constraint.name = constraint.number = None
        self._validate(constraint)
        constraint.name = name
        constraint.number = len(self._constraints) + 1
        constraint.model = self
        self._constraints.append(constraint)
        if isinstance(constraint, GenJoint):
            constraint.slave.gen_joint = constraint
        for v in constraint.new_variables():
            if all(v.symbol != w.symbol for w in self._variables):
                self._variables.append(v)
        self._touch_added(1, constraint)
        return constraint

    def _validate(self, c: ConstraintBase) -> None:
        for b in c.bodies():
            if getattr(b, "model", None) is not self:
                raise ModelError(f"{c.label()} uses body {b.name!r} of another model")
        for v in c.new_variables():
            if all(v.symbol != w.symbol for w in self._variables):
                try:
                    self._check_new_variable(v.symbol.name)
                except ModelError as exc:
                    raise ModelError(f"{c.label()}: {exc}") from None
        c.equations(self.space)  # dimension and kind checks, with the culprit named

    @property
    def constraints(self) -> list[ConstraintBase]:
        return list(self._constraints)

    def constraint(self, spec) -> ConstraintBase:
        """A constraint by handle, name or Mech number."""
        if isinstance(spec, ConstraintBase):
            if spec.model is not self:
                raise UnknownConstraintError(f"{spec.label()} is not in this model")
            return spec
        if isinstance(spec, str):
            c = self._names()[1].get(spec)
            if c is not None:
                return c
            raise UnknownConstraintError(
                f"no constraint named {spec!r}; constraints are {[c.name for c in self._constraints]}")
        if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
            for c in self._constraints:
                if c.number == spec:
                    return c
            raise UnknownConstraintError(
                f"no constraint number {spec}; numbers are {[c.number for c in self._constraints]}")
        raise UnknownConstraintError(f"cannot address a constraint by {spec!r}")

    def remove(self, spec) -> ConstraintBase:
        """Remove a constraint (by handle, name or number); later ones keep their numbers."""
        c = self.constraint(spec)
        self._constraints.remove(c)
        if isinstance(c, GenJoint):
            c.slave.gen_joint = None
        c.model = None
        self._touch()
        return c

    def replace(self, spec, new: ConstraintBase) -> ConstraintBase:
        """Replace a constraint in place: the new one takes its name and number."""
        old = self.constraint(spec)
        if new.model is not None:
            raise ModelError(f"{new.label()} is already in a model")
        if isinstance(old, GenJoint) or isinstance(new, GenJoint):
            raise ModelError(f"replace: {old.label()} -> {type(new).__name__}: generalized-"
                             "coordinate joints change the model's coordinates; remove and add "
                             "them instead")
        if isinstance(new, StageSwitch):
            new.check_stages(self.space, old.name)
        self._validate(new)
        i = self._constraints.index(old)
        new.name, new.number, new.model = old.name, old.number, self
        old.model = None
        self._constraints[i] = new
        for v in new.new_variables():
            if all(v.symbol != w.symbol for w in self._variables):
                self._variables.append(v)
        self._touch()
        return new

    def add_graphics(self, *primitives) -> None:
        """Attach graphics primitives (``mechsys.draw.Bar``, ``Arrow``, ...) used by every
        picture of this model (same as ``mechsys.draw.attach``)."""
        from . import draw

        draw.attach(self, *primitives)

    # -- loads --------------------------------------------------------------------------
    def add_load(self, load, name: str | None = None):
        """Add a load (``Force``, ``Moment``, ``Gravity``, ``Load``, ``Spring``, ``Damper``,
        friction); returns it as the handle (Mech's ``SetLoads``)."""
        from .loads._loads import LoadBase

        loads = load if isinstance(load, (list, tuple)) else [load]
        name = _checked_name(name, "load", None)
        for ld in loads:
            if not isinstance(ld, LoadBase):
                raise ModelError(f"add_load() takes load objects, got {ld!r}")
            if ld.model is not None:
                raise ModelError(f"{ld.label()} is already in a model")
            for b in ld.bodies():
                if not isinstance(b, Body):  # a name or number (Moment("rod", ...))
                    self.body(b)
                elif b.model is not self:
                    raise ModelError(f"{ld.label()} uses body {b.name!r} of another model")
            resolve(ld, self.units, ld.label())
            ld.check_values({})  # the quantities just converted (decision 0043)
            ld.check(self)
            ld.name = name if (name and len(loads) == 1) else f"load{len(self._loads) + 1}"
            ld.model = self
            self._loads.append(ld)
        self._touch()
        return load

    @property
    def load_list(self) -> list:
        """The loads of the model, in order."""
        return list(self._loads)

    def remove_load(self, load) -> None:
        if load not in self._loads:
            raise ModelError(f"{getattr(load, 'label', lambda: load)()} is not in this model")
        self._loads.remove(load)
        load.model = None
        self._touch()

    def clear_loads(self) -> None:
        for ld in self._loads:
            ld.model = None
        self._loads.clear()
        self._touch()

    def multipliers(self, constraint) -> list:
        r"""Lagrange multiplier symbols of a position constraint (Mech's ``Generalized``):
        ``lam<number>_<row>``, the symbols loads such as ``JointFriction`` are written in.

        A velocity constraint (rolling) has none: its multipliers :math:`\mu` are unknowns of
        free motion only (``sol.extra["mu"]``), not symbols a load can use, so asking raises
        :class:`ModelError`. In a model that holds velocity constraints the symbols are those
        of its position constraints (the model's own kinematic system refuses the velocity
        rows; the free system keeps the same names, decision 0068)."""
        c = self.constraint(constraint)
        rates = set(self.velocity_symbols().values())
        if is_velocity_constraint(c, self.space, rates):
            raise ModelError(
                f"multipliers({c.label()}): a velocity constraint has no multiplier symbols "
                "for loads to use (its multipliers mu are unknowns of free motion: "
                "sol.extra['mu'], sol.reaction); write the load with the multipliers of a "
                "position constraint, e.g. the holonomic part roll.holonomic() of a rolling "
                "contact for its normal force")
        moving = [] if self._switches() else [
            d for d in self._constraints if is_velocity_constraint(d, self.space, rates)]
        s = self._system_without(moving) if moving else self.compile()
        return [lam for lam, o in zip(s.lam_symbols, s.layout.eq_owner) if o is c]

    # -- guesses ------------------------------------------------------------------------
    def set_guess(self, state=None, **values) -> None:
        """Set initial guesses: from a solved ``State``/``Solution`` (its last point), a
        ``{coordinate: value}`` mapping, a full coordinate vector (1-D, length ``n``, in the
        order of ``m.guess()``), or keywords (``x2=1.0``, ``s=0.3``)."""
        upd: dict = {}
        layout_syms = self._coordinate_symbols()
        if state is not None:
            if isinstance(state, Mapping):
                upd.update(state)
            elif hasattr(state, "q") and hasattr(state, "system"):
                q = np.atleast_2d(state.q)[-1]
                names = state.system.layout.q_symbols
                upd.update(dict(zip(names, q)))
            else:
                upd.update(zip(layout_syms, self._guess_vector(state, layout_syms)))
        upd.update(values)
        new = {}
        for k, v in upd.items():
            s = k if isinstance(k, sp.Symbol) else self._coordinate_by_name(str(k))
            if s not in layout_syms:
                raise ModelError(f"set_guess: {k!r} is not a coordinate or variable of this model")
            if is_quantity(v):   # a position a length, an angle or Euler parameter none
                v = number(v, self.units, f"set_guess {s.name!r}", self._coordinate_dims(s))
            try:
                new[s] = float(v)
            except (TypeError, ValueError):
                raise ModelError(f"set_guess: the guess of {s.name!r} must be a number, "
                                 f"got {v!r}") from None
            if not np.isfinite(new[s]):
                raise ModelError(f"set_guess: the guess of {self._coordinate_text(s.name)} must "
                                 f"be finite, got {v!r}")
        self._guess_override.update(new)

    def _guess_vector(self, state, syms) -> np.ndarray:
        """A full coordinate vector for ``set_guess``: 1-D, one value per coordinate."""
        try:
            g = np.asarray(state, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"set_guess takes a State/Solution, a mapping or a 1-D array of "
                             f"{len(syms)} numbers; got {state!r}") from None
        if g.shape != (len(syms),):
            raise ModelError(
                f"set_guess: an array guess must have shape ({len(syms)},), one value per "
                f"coordinate in the order {[s.name for s in syms]}; got shape {g.shape}")
        return g

    def _coordinate_by_name(self, name: str) -> sp.Symbol:
        for b in self._bodies:
            for c, s in zip(self.space.coordinate_names, b.q):
                if name in (s.name, f"{b.name}.{c}"):
                    return s
        for v in self._variables:
            if v.symbol.name == name:
                return v.symbol
        raise ModelError(f"no coordinate or variable named {name!r}")

    def guess(self) -> np.ndarray:
        """The current initial guess vector ``(n,)`` in layout order."""
        vals = []
        for b in self._bodies[1:]:
            if b.gen_joint is None:  # a slave's pose follows from its master's and its joint's
                vals.extend(b.guess)
        vals.extend(v.guess for v in self._variables)
        syms = self._coordinate_symbols()
        g = np.array(vals, dtype=float)
        for i, s in enumerate(syms):
            if s in self._guess_override:
                g[i] = self._guess_override[s]
        return g

    # -- symbolic machinery -------------------------------------------------------------
    def _touch(self) -> None:
        self._version += 1
        self._system = None

    def _names(self) -> tuple[dict, dict]:
        """``({name: body}, {name: constraint})``, rebuilt after any edit but an addition
        (:meth:`_touch_added` extends it): adding N bodies and constraints checks their
        names in O(N), not O(N^2) (a 1024-link chain spent 1.3 s in those scans)."""
        index = self.__dict__.get("_name_index")
        if index is None or index[0] != self._version:
            index = (self._version, {b.name: b for b in self._bodies},
                     {c.name: c for c in self._constraints})
            self._name_index = index
        return index[1], index[2]

    def _touch_added(self, kind: int, item) -> None:
        """:meth:`_touch` after appending ``item`` (``kind`` 0: a body, 1: a constraint),
        keeping the name index current instead of dropping it."""
        index = self.__dict__.get("_name_index")
        fresh = index is not None and index[0] == self._version
        self._touch()
        if fresh:
            index[1 + kind][item.name] = item
            self._name_index = (self._version, index[1], index[2])

    def _coordinate_symbols(self) -> list:
        return ([s for b in self._bodies if b.gen_joint is None for s in b.q]
                + [v.symbol for v in self._variables])

    def _gen_substitution(self) -> dict:
        """Slave-body symbol -> expression of the independent coordinates (Gen joints,
        ``constraints/_generalized.py``); empty without Gen joints. Cached per version."""
        kin = self._gen_kinematics()
        return kin.sympy if kin is not None else {}

    def _gen_kinematics(self):
        """The slaves' :class:`~mechsys.constraints._generalized.GenKinematics` (None
        without Gen joints), cached per version."""
        cache = getattr(self, "_gen_cache", None)
        if cache is None or cache[0] != self._version:
            kin = None
            if any(isinstance(c, GenJoint) for c in self._constraints):
                lay = make_layout(self._bodies[1:], self._variables, [], [], [])
                kin = GenKinematics(self, lay)
            self._gen_cache = cache = (self._version, kin)
        return cache[1]

    def _all_equations(self):
        eqs, owners, index = [], [], []
        sub = None
        for c in self._constraints:
            for k, e in enumerate(c.equations(self.space)):
                e = process_equation(self._compile_opts, e, c.label())  # Mech's $MechProcessFunction
                if sub is None:
                    # the slaves' nested poses only where an equation may use them: a tree
                    # of Gen joints (an imported robot) has none to substitute (decision 0057)
                    sub = self._gen_substitution()
                eqs.append(e.xreplace(sub) if sub else e)
                owners.append(c)
                index.append(k)
        for b in self._bodies[1:]:
            if b.gen_joint is not None:  # a slave's Euler parameters are its master's, turned
                continue
            for k, e in enumerate(self.space.body_normalization(b.q[self.space.dim :])):
                eqs.append(e)
                owners.append(f"Euler-parameter normalization of body {b.name!r}")
                index.append(k)
        return eqs, owners, index

    def _check_symbols(self, eqs, owners) -> None:
        coords = set(self._coordinate_symbols())
        known = coords | set(self._params) | {T}
        rates = {velocity_symbol(q.name) for q in coords} | {acceleration_symbol(q.name)
                                                              for q in coords}
        for e, o in zip(eqs, owners):
            extra = free_symbols(e) - known
            if extra:
                lab = o.label() if hasattr(o, "label") else str(o)
                names = sorted(map(str, extra))
                if extra & rates:
                    raise ModelError(
                        f"{lab} is a velocity constraint (it uses the rates "
                        f"{sorted(map(str, extra & rates))}), which the position equations of "
                        "solve, couple and the static and kinematic free systems cannot hold. "
                        "For the first-order motion "
                        "of a nonholonomic system keep a dummy constraint in the model in its "
                        "place and give the velocity constraint to m.path(replace={dummy: "
                        "velocity_constraint}) (docs/nonholonomic.md); free motion (m.free) holds "
                        "velocity constraints linear in the rates beside the position ones")
                same = same_name_advice(extra, known)
                if same:
                    raise ModelError(f"{lab} uses symbol(s) {names} that are not the model's: "
                                     f"{same}")
                raise ModelError(
                    f"{lab} uses unknown symbol(s) {names}: declare them with "
                    "m.parameter(name, value) or m.variable(name, guess), or pass "
                    "variables={sym: guess} to Constraint")

    @gc_paused()
    def _system_without(self, removed, loads=None) -> System:
        """A System of this model's equations minus those of ``removed`` constraints (free
        and path systems); same coordinates, parameters and (by default) loads."""
        if self._switches():
            if loads is None:  # free motion: the first stages (analyses/_free_switch.py)
                from .analyses._multistage import stage_system

                return stage_system(self, None, tuple(removed))
            raise ModelError(
                f"path motion of a model with stage or time switches "
                f"({', '.join(repr(c.name) for c in self._switches())}) is not supported; "
                "replace each switch by the constraint of the stage you need "
                "(m.replace(name, constraint)), or use free motion (m.free), which passes "
                "through stage changes")
        eqs, owners, index = self._all_equations()
        # by identity (constraints compare so): a set, not a scan of the list per equation
        # (3072 x 1024 comparisons for a 1024-link chain's free system)
        gone = {id(c) for c in removed}
        keep = [i for i, o in enumerate(owners) if id(o) not in gone]
        eqs = [eqs[i] for i in keep]
        owners = [owners[i] for i in keep]
        index = [index[i] for i in keep]
        self._check_symbols(eqs, owners)
        layout = make_layout(self._bodies[1:], self._variables, list(self._params), owners, index)
        return System(self.space, layout, eqs, list(self._params.values()), self.guess(),
                      backend=self._backend, version=self._version, model=self,
                      loads=list(self._loads) if loads is None else loads)

    def _independent(self, system: System, t, q, what: str = "solve"):
        """``(system, redundancy, q)``: when the equations of ``system`` are dependent at ``q``
        (consistent redundant constraints, as Adams accepts them), the System of an
        independent subset (pivoted QR of the scaled ``Phi_q^T``: the equations chosen last
        are dropped) and the :class:`~mechsys.solvers._position.Dependency`; else
        ``(system, None)``; ``q`` the configuration decided at (the guess, or where least
        squares on all equations assembles the mechanism). Only when the rest still fixes as much as the whole
        (``rank == n`` for a kinematic solve, any rank for free motion). Warns once per
        model version and set of dropped equations (RedundantConstraintWarning)."""
        if system.m == 0 or (what == "solve" and system.m <= system.n):
            return system, None, q
        # (sparse above SPARSE_THRESHOLD coordinates, as the solvers take it: the rank is
        # certified by a sparse LU of J J^T, and only a dependency found makes it dense)
        J = system.jacobian(t, q, self._p(), system.n > SPARSE_THRESHOLD)
        d = dependency(system, J, Scaling.of(system, q, J), q)
        if what == "solve" and d.rank < system.n:
            # the guess may not assemble the mechanism (a driver's row can vanish there):
            # decide at the configuration least squares on all equations reaches
            from .solvers._rank import continue_position

            got = continue_position(system, t, q, self._p(), Scaling.of(system, q, J))
            if got is not None:
                q = got[0]
                J = system.jacobian(t, q, self._p())
                d = dependency(system, J, Scaling.of(system, q, J), q)
        if not d.deficiency or (what == "solve" and d.rank < system.n):
            return system, None, q
        keep = tuple(i for i in range(system.m) if i not in set(d.rows))
        cache = self.__dict__.setdefault("_reduced", {})
        key = (id(system), system.version, keep)
        if key not in cache or cache[key][0] is not system:   # (the entry keeps the id taken)
            lay = dataclasses.replace(system.layout,
                                      eq_owner=tuple(system.layout.eq_owner[i] for i in keep),
                                      eq_index=tuple(system.layout.eq_index[i] for i in keep))
            cache[key] = (system, System(self.space, lay, [system.phi[i] for i in keep],
                                         system.p_values, system.guess, backend=system.backend,
                                         version=system.version, model=self,
                                         loads=system._loads))
            full = self.compile()
            Jm = full.jacobian(t, q, self._p()) if full.n == system.n else J
            mobility = full.n - Scaling.of(full, q, Jm).dependent_rows(Jm)[0] if (
                full.n == system.n) else None
            meant = "" if mobility is None else (
                f" The mechanism has {mobility} degree(s) of freedom (mobility), the "
                f"Gruebler count says {full.n - full.m}: that mobility is probably what you "
                "meant.")
            warnings.warn(RedundantConstraintWarning(
                f"{what}: redundant but consistent constraints {d.text} These equations are "
                "left out of the solution (they hold wherever the others do); the reactions of "
                "the constraints involved (" + ", ".join(_constraint_names(d.involved))
                + ") are statically indeterminate and reported as the minimum-norm solution, "
                "flagged in Solution.extra['indeterminate']." + meant,
                redundant=d.owners, mobility=mobility), stacklevel=3 if what == "solve" else 4)
        return cache[key][1], d, q

    def set_compile_options(self, process=_UNSET, opt_level=_UNSET, cse=_UNSET,
                            **unknown) -> dict:
        """Simplification and compile options (Mech's ``$MechProcessFunction`` and
        ``Compiled`` option, manual 12.2-12.3): ``process=None | "chop" | f`` applied to every
        constraint equation, ``opt_level=0..3`` (LLVM), ``cse=None | True | False``. Only the
        options given change; returns them all. See :mod:`mechsys.compile._options` and
        ``docs/performance-options.md``.

        Example: ``m.set_compile_options(process="chop", opt_level=1)``
        """
        unknown_options("set_compile_options", unknown, ("process", "opt_level", "cse"))
        new = _updated_options(self._compile_opts, process, opt_level, cse)
        if new != self._compile_opts:
            self._compile_opts = new
            self._touch()
        return new.as_dict()

    @property
    def compile_options(self) -> dict:
        """The current simplification and compile options (:meth:`set_compile_options`)."""
        return self._compile_opts.as_dict()

    @gc_paused()
    def compile(self) -> System:
        """The compiled :class:`System` (cached until the model changes). With switches
        (StageSwitch, TimeSwitch) it is the system of every switch's first stage."""
        if self._system is None and self._switches():
            from .analyses._multistage import stage_system

            self._system = stage_system(self, None)
        if self._system is None:
            eqs, owners, index = self._all_equations()
            self._check_symbols(eqs, owners)
            layout = make_layout(self._bodies[1:], self._variables, list(self._params), owners, index)
            self._system = System(self.space, layout, eqs, list(self._params.values()),
                                  self.guess(), backend=self._backend, version=self._version,
                                  model=self, loads=list(self._loads))
        return self._system

    def _p(self) -> np.ndarray:
        # after the parameters: the values variables of switches are held at (their guesses)
        held = [self._guess_override.get(v.symbol, v.guess)
                for sw in self._switches() for v in sw.new_variables()]
        return np.array(list(self._params.values()) + held, dtype=float)

    def _switches(self) -> list:
        """The StageSwitch/TimeSwitch constraints of the model (multistage, Mech ch. 5)."""
        return [c for c in self._constraints if isinstance(c, StageSwitch)]

    def time_derivative(self, expr):
        r"""Total time derivative of a SymPy expression (or matrix) of coordinates, velocities
        and ``T``: :math:`\dot f = f_q \dot q + f_{\dot q} \ddot q + f_T`."""
        lay = make_layout(self._bodies[1:], self._variables, [], [], [])
        sub = self._gen_substitution()
        if sub:
            expr = expr.xreplace(sub) if isinstance(expr, sp.Basic) else sp.sympify(expr).xreplace(sub)
        if isinstance(expr, sp.MatrixBase):
            return expr.applyfunc(lambda e: time_derivative(e, lay.q_symbols, lay.qd_symbols,
                                                            lay.qdd_symbols))
        return time_derivative(expr, lay.q_symbols, lay.qd_symbols, lay.qdd_symbols)

    def velocity_symbols(self) -> dict:
        """``{coordinate symbol: velocity symbol}``."""
        lay = make_layout(self._bodies[1:], self._variables, [], [], [])
        out = dict(zip(lay.q_symbols, lay.qd_symbols))
        for b in self._bodies[1:]:  # slaves: their rate symbols, substituted on output
            if b.gen_joint is not None:
                out.update({s: velocity_symbol(s.name) for s in b.q})
        return out

    def _omega(self, b: Body, local: bool):
        if b.is_ground:
            return sp.S.Zero if self.space.dim == 2 else sp.zeros(3, 1)
        vs = self.velocity_symbols()
        rot = b.q[self.space.dim :]
        return self.space.omega(rot, [vs[s] for s in rot], local)

    # -- outputs (symbolic) -------------------------------------------------------------
    def _model(self):
        return self

    def _finish(self, expr):
        sub = self._gen_substitution()
        if sub and isinstance(expr, (sp.Basic, sp.MatrixBase)):
            return expr.xreplace(sub)
        return expr

    def _point(self, obj) -> Point:
        if isinstance(obj, Axis):
            obj = obj.origin
        p = as_point(obj)
        p.check_dim(self.space.dim)
        for b in p.bodies():
            self.body(b)
        return p

    def _vector(self, obj) -> Vector:
        v = as_vector(obj)
        v.check_dim(self.space.dim)
        return v

    # -- analysis -----------------------------------------------------------------------
    def dof(self) -> DOF:
        """Degrees of freedom: the Gruebler count and the Jacobian rank at the current guess
        (on the unit-free scaled Jacobian, so the report does not depend on the unit of
        length). With a Gruebler count of 0 or less and guesses that do not assemble the
        mechanism, the rank is taken at the nearest assembled configuration (minimum-norm
        Gauss-Newton from the guesses at t = 0), where a paradoxical linkage (Bricard's,
        Bennett's) shows its mobility; ``DOF.at`` says where it was taken.
        When the guess is a singular configuration only because bodies were left at
        the default guess, the rank is taken at a nearby configuration and ``singular_guess``
        says which bodies need guesses."""
        system = self.compile()
        g, p = self.guess(), self._p()
        q, where = g, "guess"
        if system.m >= system.n:
            # a Gruebler count <= 0 says nothing of a paradoxical linkage (Bricard's, Bennett's):
            # its mobility shows only where it is assembled, which rough guesses are not
            q, where = self._assembled_for_dof(system, g, p)
        J = system.jacobian_once(0.0, q, p)
        d = dependency(system, J, Scaling.of(system, q, J))
        rank, redundant, note = d.rank, d.owners, ""
        if d.deficiency and where != "assembled":
            better = self._singular_guess(system, 0.0, g, d.rank)
            if better is not None:
                rank, note = better
                redundant = []
        elif where == "assembled":
            # the rank is the assembly's; still say when the guesses were singular only
            # because bodies were left at the default guess (a solve from them fails)
            Jg = system.jacobian_once(0.0, g, p)
            dg = dependency(system, Jg, Scaling.of(system, g, Jg))
            if dg.deficiency:
                better = self._singular_guess(system, 0.0, g, dg.rank)
                note = "" if better is None else better[1]
        owners = [o for o in redundant if isinstance(o, ConstraintBase)]
        return DOF(system.n - rank, coordinates=system.n, equations=system.m,
                   gruebler=system.n - system.m, rank=rank, redundant=owners,
                   singular_guess=note, at=where, configuration=q)

    def _assembled_for_dof(self, system, g, p):
        r"""``(q, where)``: the configuration ``dof`` takes the rank at. The guess when it
        assembles the mechanism (``"guess"``); else the nearest assembled configuration,
        Gauss-Newton with minimum-norm steps from the guess (``dq = -D pinv(J^) R^-1 Phi``, at
        t = 0, drivers included: :func:`~mechsys.solvers._rank.continue_position`),
        ``"assembled"``; the guess again when that fails, ``"unassembled guess"`` (the figure
        then holds at the guess only, and the report says so)."""
        from .solvers._rank import continue_position

        class Once:       # (the quickly compiled kernel: dof stays cheap to compile)
            def residual_and_jacobian(self, t, q, p=None, sparse=False):
                return system.position_once(t, q, p)

        F, J = system.position_once(0.0, g, p)
        sc = Scaling.of(system, g, J)
        if np.abs(F / sc.rows(J)).max(initial=0.0) <= 1e-9:
            return g, "guess"
        got = continue_position(Once(), 0.0, g, p, sc, 1e-12, 100)
        if got is None:
            return g, "unassembled guess"
        return got[0], "assembled"

    def equations(self, constraints=None):
        """The model's equations as SymPy matrices (Mech 13.4): constraints ``phi``, Jacobian
        ``jacobian``, ``phi_t``, acceleration right side ``gamma``, ``mass_matrix``, applied
        ``loads`` and velocity-dependent ``centrifugal`` forces, with pretty and LaTeX
        display; ``constraints`` restricts the constraint rows (a handle, name, number or a
        list of them). See :class:`~mechsys.results._equations.Equations`."""
        from .results._equations import Equations

        return Equations(self, constraints)

    def singularity(self, at=None, t: float | None = None, threshold: float = 1e-6):
        """Singular and near-singular directions of the constraint Jacobian (Mech 13.3) with
        the constraints involved and the motion left uncontrolled. ``at``: coordinates
        (array (n,)), a mapping of guesses, or a ``Solution`` (its point of smallest
        ``rcond``, or its last point); default the current guess. Returns a
        :class:`~mechsys.solvers._diagnostics.SingularityReport` (``print`` it)."""
        from .solvers._diagnostics import diagnose_singularity

        system = self.compile()
        tt = 0.0 if t is None else float(t)
        if at is not None and hasattr(at, "q") and hasattr(at, "system"):
            Q = np.atleast_2d(at.q)
            rc = at.extra.get("rcond") if isinstance(getattr(at, "extra", None), dict) else None
            k = int(np.nanargmin(rc)) if rc is not None and np.any(np.isfinite(rc)) else len(Q) - 1
            q = Q[k].copy()
            if t is None:
                tt = float(np.atleast_1d(at.t)[k])
            if at.system is not system and at.system.n != system.n:
                raise ModelError("singularity: the solution belongs to another system")
        else:
            q = self._resolve_guess(system, at)
        if t is not None and (not np.isfinite(tt)):
            raise ModelError(f"singularity: t must be finite, got {t!r}")
        J = system.jacobian_once(tt, q, self._p())
        return diagnose_singularity(system, J, Scaling.of(system, q, J), tt, threshold)

    def _singular_guess(self, system, t, g, rank):
        """``(rank, message)`` when the Jacobian, rank deficient (``rank``) at the guess
        ``g`` which does not assemble the mechanism, has a higher rank once the bodies left
        at the default guess (origin, no rotation) are moved a little: the guess, not the
        constraints, is singular. ``None`` otherwise: no such bodies, an assembled guess (a
        genuine lock-up there) or no better rank (a redundancy)."""
        dim = self.space.dim
        F, J = system.residual_and_jacobian(t, g, self._p())
        sc = Scaling.of(system, g, J)
        if np.abs(F / sc.rows(J)).max(initial=0.0) < 1e-6:
            return None
        default = np.array([0.0] * dim + list(self.space.zero_rotation()), dtype=float)
        lay = system.layout
        idle = [b for b in self._bodies[1:] if b.name in lay.body_slices  # slaves have none
                and np.array_equal(g[lay.body_slices[b.name]], default)]
        if not idle:
            return None
        rng = np.random.default_rng(12345)  # deterministic: the same report every call
        qp = np.array(g, dtype=float)
        for b in idle:
            sl = lay.body_slices[b.name]
            step = np.where(np.arange(sl.stop - sl.start) < dim, 0.3 * sc.length, 0.7)
            qp[sl] += step * rng.standard_normal(sl.stop - sl.start)
        Jp = system.jacobian(t, qp, self._p())
        rp = dependency(system, Jp, Scaling.of(system, qp, Jp)).rank
        if rp <= rank:
            return None
        names = ", ".join(repr(b.name) for b in idle)
        return rp, (
            f"the initial guesses put the mechanism in a singular configuration (Jacobian rank "
            f"{rank} there, {rp} at a nearby configuration), so the constraints are not "
            f"necessarily redundant: give guesses for bodies {names} (still at the default guess, "
            "the origin without rotation) near an assembled position, with add_body(..., "
            "guess=...), m.set_guess(...) or solve(..., guess=...).")

    def _require_square(self, system: System) -> None:
        n, m = system.n, system.m
        if m < n:
            loose = self._unconstrained_bodies(system)
            raise ConstraintCountError(
                f"the model has {n - m} degree(s) of freedom ({n} coordinates, {m} equations); "
                f"a kinematic solution needs 0. "
                + (f"No constraint uses the coordinates of bod{'ies' if len(loose) > 1 else 'y'} "
                   f"{', '.join(map(repr, loose))}: connect {'them' if len(loose) > 1 else 'it'}"
                   " to the mechanism with a joint (or remove it). " if loose else "")
                + f"Add {n - m} driving constraint(s), e.g. "
                "RotationLock1(crank, 2*pi*T), or drop constraints with m.free(...) for dynamics.")
        if m > n:
            g = self.guess()
            J = system.jacobian(0.0, g, self._p())
            d = dependency(system, J, Scaling.of(system, g, J))
            # rank <= n < m: at least m - n equations depend on the others
            msg = (f"the model is overconstrained by {m - n} equation(s) ({n} coordinates, {m} "
                   f"equations). Jacobian at the current guess {d.text} The cure is to remove or "
                   f"relax {d.deficiency} equation(s) in total, not whole joints: replace one or "
                   "more of the constraints involved by constraints that impose fewer equations "
                   "(for example a joint that leaves one more rotation or translation free), or "
                   "drop equations with a general Constraint.")
            if d.rank < n:
                msg += (f" Even then {n - d.rank} degree(s) of freedom would remain at this guess: "
                        "add drivers, or check the guess.")
            raise ConstraintCountError(msg)

    def _unconstrained_bodies(self, system) -> list[str]:
        """Names of the moving bodies none of whose coordinates any equation uses, apart from
        their own Euler-parameter normalisation."""
        used = set()
        for e, o in zip(*self._all_equations()[:2]):
            if not (isinstance(o, str) and o.startswith("Euler-parameter")):
                used |= e.free_symbols
        lay = system.layout
        return [b.name for b in self._bodies[1:] if b.name in lay.body_slices
                and not used & {lay.q_symbols[i] for i in range(*lay.body_slices[b.name].indices(
                    system.n))}]

    @staticmethod
    def _check_times(t) -> np.ndarray:
        """``t`` as a 1-D float array, or a :class:`ModelError` saying what is wrong with it."""
        what = "solve: t must be a finite time or a 1-D sequence of finite times"
        if t is None:
            raise ModelError(f"{what}, got None")
        try:
            arr = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"{what}, got {t!r}") from None
        if arr.ndim > 1:
            raise ModelError(f"{what}, got an array of shape {arr.shape}; flatten it or pass "
                             "one sequence of times")
        arr = np.atleast_1d(arr)
        if arr.size == 0:
            raise ModelError(f"{what}, got an empty sequence; give at least one time")
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise ModelError(f"{what}, got {arr[bad[0]]} at index {bad[0]}")
        return arr

    def solve(self, t=0.0, solution: str = "acceleration", guess=None,
              options: PositionOptions | None = None, lambda_guess=None, pre_solve=None,
              post_iterate=None, progress=None):
        r"""Kinematic solution at time(s) ``t`` (Mech's ``SolveMech``).

        ``solution``: ``"location"``, ``"velocity"`` or ``"acceleration"`` (default), or with
        loads ``"static"`` (positions, then :math:`\Phi_q^{\mathsf T} \lambda = Q` with zero
        velocities), ``"kinematic"`` (positions, velocities, velocity-dependent loads) or
        ``"dynamic"`` (inverse dynamics
        :math:`M \ddot q + \Phi_q^{\mathsf T} \lambda = Q + Q_v`). The kinematic levels solve

        .. math::

            \Phi(q, T) = 0, \qquad \Phi_q \dot q = -\Phi_t, \qquad \Phi_q \ddot q = \gamma .

        ``lambda_guess`` starts the multiplier Newton when loads depend on reactions
        (friction): a number, ``m`` numbers or a mapping
        ``{constraint or multiplier symbol: value(s)}`` (Mech's ``LambdaGuess``; see
        :func:`~mechsys.results._load_outputs.lambda_guess_vector`).
        ``guess``: starting coordinates (array (n,), a ``State``/``Solution`` or a mapping);
        default the model's guesses. A sweep continues each point from the previous one.
        Returns a :class:`~mechsys.Solution` and stores it as ``last_solution``.

        Hooks (Mech's ``$MechPreSolve`` and ``$MechPostIterate``, see docs/debugging.md):
        ``pre_solve(t)`` is called with each time before its position solve;
        ``post_iterate(it)`` after each Newton iteration with an
        :class:`~mechsys.solvers.Iteration` (``t, iteration, q, residual, step, names``).
        A hook returning ``False`` stops the solve: the points solved before are returned
        with ``sol.extra["stopped"]`` saying which hook stopped it where (a
        :class:`MechError` when no point was solved yet).

        ``progress``: a progress bar over the points (tqdm: stderr or a Jupyter widget;
        ``None``, the default: only on a terminal, once the solve has taken 2 s) or a callable
        ``progress(done, total)``. Unlike the hooks it keeps the compiled loop: that runs in
        chunks with the bar advanced between them (decision 0039). Ctrl-C (KeyboardInterrupt,
        also one raised by the callable) returns the points solved before it, with
        ``sol.extra["interrupted"] = True``, ``sol.extra["stopped"]`` and a warning (a
        :class:`MechError` when no point was solved yet). ``sol.extra["compiled_points"]``:
        how many points the compiled loop solved.
        """
        from ._progress import check_progress, reporter
        from .results._solution import Solution

        modes = {"static": 0, "kinematic": 1, "dynamic": 2}
        choice(solution, [*ORDERS, *modes], "solve: solution")
        times = self._check_times(convert(t, self.units, "solve: t", TIME))
        check_progress(progress, "solve")
        if self._loads:  # TimeSwitch loads with parameter times: increasing (issue 14)
            from .loads._loads import check_load_values
            from .loads._switched import check_switched_loads

            check_switched_loads(self)
            # stiffnesses, free lengths, damping and friction coefficients given as
            # parameters: not negative with the values of this run (issue 34)
            check_load_values(self._loads, dict(zip(self._params, self._p())))
        if isinstance(options, Mapping):
            fields = PositionOptions.__dataclass_fields__
            unknown_options("options (PositionOptions)", set(options) - set(fields), fields)
            options = PositionOptions(**options)
        if options is not None and not isinstance(options, PositionOptions):
            raise ModelError(f"options must be a PositionOptions(ftol=..., max_iterations=..., "
                             f"damping=...) or a mapping of its fields, got {options!r}")
        from .solvers._diagnostics import Hooks, Stopped

        hooks = Hooks.make(pre_solve, post_iterate)
        system = self.compile()
        if system.n == 0:
            raise ModelError("solve: the model has no moving bodies (or variables), so there is "
                             "nothing to solve; add bodies with m.add_body(...) first")
        g = self._resolve_guess(system, guess)
        full, (system, red, g_red) = system, self._independent(system, times[0], g)
        g = g_red if red is not None else g
        self._require_square(system)
        scalar = np.ndim(t) == 0
        order = ORDERS.get(solution, modes.get(solution))
        if self._switches():  # stages chosen point by point (analyses/_multistage.py)
            from .analyses._multistage import solve_stages

            if hooks is not None:
                raise ModelError("solve: pre_solve/post_iterate hooks are not supported for "
                                 "models with stage or time switches yet; leave them out")

            # (the stages' runs are not chunked: a bar or callable is advanced once, at the end)
            report, close = reporter(progress, len(times), "solve", "points", "solve",
                                     delay=2.0 if progress is None else 0.0)
            try:
                self.last_solution = solve_stages(self, times, g, solution, options, scalar,
                                                  lambda_guess=lambda_guess)
                if report is not None:
                    report(len(times))
            finally:
                close()
            return self.last_solution
        stopped = None
        report, close = reporter(progress, len(times), "solve", "points", "solve",
                                 delay=2.0 if progress is None else 0.0)
        try:
            res = sweep(system, times, g, order, options, self._p(), hooks=hooks,
                        progress=report)
        except Stopped as stop:
            if stop.k == 0:
                raise MechError(f"solve stopped before any point was solved: {stop.describe()}"
                                ) from None
            res, stopped = stop.partial, stop
        except SingularJacobianError as err:
            # a singular first point may be the guess's fault, not the constraints'
            J = system.jacobian(times[0], g, self._p())
            d = dependency(system, J, Scaling.of(system, g, J))
            better = self._singular_guess(system, times[0], g, d.rank) if (
                err.time == times[0] and d.deficiency) else None
            if better is None:
                raise
            raise SingularJacobianError(f"position solve at t = {times[0]:.6g}: {better[1]}",
                                        time=err.time, dependent=[], rank=err.rank) from None
        finally:
            close()
        lam = None
        if solution in modes:
            lam = self._multipliers_over(system, res, solution, lambda_guess)
        if red is not None:
            lam = _redundant_solution(full, system, res, lam, red, self._p())
        sol = Solution.from_sweep(self, full, res, self._p(), scalar=scalar, lam=lam,
                                  mode=solution)
        if red is not None:
            sol.extra["redundant"] = _constraint_names(red.owners)
            sol.extra["indeterminate"] = _constraint_names(red.involved)
        sol.extra["compiled_points"] = res.compiled
        if stopped is not None:
            sol.extra["stopped"] = stopped.describe()
            if stopped.hook == "interrupted":
                import warnings

                sol.extra["interrupted"] = True
                warnings.warn(f"solve: interrupted after {len(res.t)} of {len(times)} points "
                              f"({stopped.describe()}); returning the points solved "
                              "(sol.extra['interrupted'])", RuntimeWarning, stacklevel=2)
        self.last_solution = sol
        return sol

    def _multipliers_over(self, system, res, mode, lambda_guess):
        from .solvers._statics import multipliers_over

        return multipliers_over(system, res.t, res.q, res.qd, res.qdd, self._p(), mode,
                                lambda_guess_vector(system, self, lambda_guess),
                                scaling=res.scaling)

    def free(self, drop=(), solution: str = "dynamic", initial_guess=None,
             initial_condition=None):
        """Drop constraints and build the free system (Mech's ``SetFree``): equilibrium
        configuration (``solution="static"``), equilibrium velocity (``"kinematic"``) or free
        acceleration and motion (``"dynamic"``). Returns a :class:`FreeSystem`."""
        from .analyses._free import FreeSystem

        if self._switches() or (solution == "dynamic" and
                                any(getattr(ld, "tests", None) for ld in self._loads)):
            from .analyses._free_switch import SwitchedFreeSystem  # events (issue 14)

            return SwitchedFreeSystem(self, drop, solution, initial_guess, initial_condition)
        return FreeSystem(self, drop, solution, initial_guess, initial_condition)

    def couple(self, unknowns, conditions=None, t=None, guess=None, configurations=None,
               solution: str | None = None):
        """Make parameters unknowns fixed by conditions (Mech's ``SetCouple``): one
        configuration (``conditions=``, ``t=``, ``guess=``) or several
        (``configurations=[ms.Configuration(conditions, t=..., guess=...), ...]``) solved
        together; ``t=ms.Free`` makes a configuration's time an unknown. Returns a
        :class:`~mechsys.CoupleSystem` whose ``solve()`` is Mech's ``SolveCouple``
        (``docs/couples.md``)."""
        from .analyses._couple import CoupleSystem

        return CoupleSystem(self, unknowns, conditions, t, guess, configurations, solution)

    def vibration(self, at=None, drop=(), t=None, tolerance: float = 1e-6, rotating=None):
        """Linearised vibration about an equilibrium or a steady motion: natural frequencies
        [rad/s and Hz], damping ratios and mode shapes (a :class:`VibrationModes`). ``at``: the
        reference state (a Solution/State, a mapping or a coordinate array); ``drop``:
        constraints removed first, as in :meth:`free`; ``rotating=(omega, center[, axis])``:
        linearise in a rotating frame (relative equilibria). See ``docs/vibration.md``."""
        from .analyses._vibration import vibration

        return vibration(self, at=at, drop=drop, t=t, tolerance=tolerance, rotating=rotating)

    def path(self, replace, initial_condition=None):
        """Replace dummy constraints by velocity constraints (Mech's ``SetPath``):
        ``replace={dummy: velocity_constraint}``; a velocity constraint of ``k`` equations
        (a rolling contact, ``RollingDisk2``) takes the places of a tuple of ``k`` dummies,
        ``replace={("dummy x", "dummy y"): roll}``. Returns a :class:`PathSystem` whose
        ``simulate`` integrates the nonholonomic motion (``SolvePath``)."""
        from .analyses._path import PathSystem

        return PathSystem(self, replace, initial_condition)

    def save(self, path):
        """Write the model to a JSON model file (docs/model_files.md): bodies, points, mass
        properties, guesses, parameters, variables, constraints and loads, expressions as text
        of a restricted grammar. Read it back with ``mechsys.load(path)`` (safe for files from
        strangers). Anything a file cannot hold (a Python callable, attached graphics) raises
        :class:`ModelError` naming it. ``m.save("crank.json")``; returns the path."""
        from .io._files import save

        return save(self, path)

    def inverse_dynamics(self, q, qd, qdd, t: float = 0.0, actuated=None):
        r"""Joint forces :math:`\tau = M(q) \ddot q - Q - Q_v` (a robot from ``ms.from_urdf``), at one
        point or ``(N, n)`` points: a :class:`~mechsys.JointValues` named by coordinate
        (``m.inverse_dynamics(q, qd, qdd)["elbow_joint"]``). On a model with constraint
        equations (absolute coordinates, a floating base, closed loops) the forces on the
        ``actuated`` coordinates (default: those not of an absolute body) that with the
        constraints' reactions give ``qdd``,
        :math:`M \ddot q + \Phi_q^T \lambda = Q + Q_v + S^T \tau`; mappings may then name
        the independent coordinates only. Decisions 0040 and 0048."""
        from .analyses._robot import inverse_dynamics

        return inverse_dynamics(self, q, qd, qdd, t, actuated)

    def forward_dynamics(self, q, qd, tau, t: float = 0.0, actuated=None):
        r"""Joint accelerations :math:`\ddot q = M(q)^{-1} (Q + Q_v + \tau)` (the inverse of
        :meth:`inverse_dynamics`) at one point or ``(N, n)`` points; on a model with
        constraint equations every coordinate's acceleration from the augmented system, with
        ``tau`` on the ``actuated`` coordinates."""
        from .analyses._robot import forward_dynamics

        return forward_dynamics(self, q, qd, tau, t, actuated)

    def forward_kinematics(self, q, point, t: float = 0.0, frame: bool = False):
        """Global location of ``point`` (a body point, or a link name of an imported robot; or
        a list) at coordinates ``q`` (one point or ``(N, n)``); ``frame=True``: 4x4 poses."""
        from .analyses._robot import forward_kinematics

        return forward_kinematics(self, q, point, t, frame)

    def to_urdf(self, path, robot: str = "mechsys"):
        """Write a tree of ``GenRevolute5``/``GenTranslate5`` joints, free bodies included
        (``floating`` joints at their guessed pose), as a URDF file (docs/import.md); what
        URDF cannot hold (ball joints, closed loops, springs, ...) raises ``ModelError``
        naming it. Example: ``ms.from_urdf("arm.urdf").to_urdf("again.urdf")``."""
        from .io._export import to_urdf

        return to_urdf(self, path, robot)

    def to_mjcf(self, path, model: str = "mechsys"):
        r"""Write the model as an MJCF (MuJoCo) file (docs/import.md): a tree of
        ``GenRevolute5``/``GenTranslate5`` joints, ``ball`` joints (an absolute body and a
        ``Spherical3``), free bodies (``<freejoint>``, at their guessed pose) and, closing
        loops, ``connect``/``weld`` equalities between sites (``Spherical3``, with
        ``RotationLock3`` for a weld) and ``joint`` equalities (a ``Constraint``
        :math:`q_1 - c_0 - c_1 q_2 - \dots - c_4 q_2^4`); what MJCF cannot hold raises
        ``ModelError`` naming it. Example: ``ms.from_mjcf("loop.xml").to_mjcf("again.xml")``."""
        from .io._export import to_mjcf

        return to_mjcf(self, path, model)

    def lock(self, at=0.0, solution: str = "location", guess=None):
        """Freeze the mechanism at one configuration (Mech's ``LockMech``): ``at`` is a time
        (solved now), a one-point :class:`~mechsys.Solution` or a ``State``; ``solution``
        the highest order kept (``"location"``, ``"velocity"``, ``"acceleration"``).
        Returns a :class:`~mechsys.analyses.LockedModel` whose ``solve("static" | "kinematic"
        | "dynamic", parameters={...})`` gives reactions for new load or inertia parameters
        without solving the positions again (and refuses parameters that move the
        mechanism)."""
        from .analyses._lock import LockedModel

        return LockedModel(self, at, solution, guess)

    def sensitivity(self, parameters, free=None):
        """Sensitivity to parameters (Mech's ``SetSensitivity``): ``m.sensitivity(["L", "r"])``
        returns a :class:`SensitivitySystem` whose ``solve(t, solution=...)`` (Mech's
        ``SolveSensitivity``) or ``of(solution)`` gives exact derivatives of coordinates,
        velocities, accelerations, multipliers and any output; with ``free=m.free(...)``,
        ``simulate(t, ...)`` integrates free motion with its sensitivities. See
        docs/sensitivity.md."""
        from .analyses._sensitivity import SensitivitySystem

        return SensitivitySystem(self, parameters, free)

    def _resolve_guess(self, system, guess) -> np.ndarray:
        if guess is None:
            return self.guess()
        if isinstance(guess, Mapping):
            saved = dict(self._guess_override)
            try:
                self.set_guess(guess)
                return self.guess()
            finally:
                self._guess_override = saved
        if hasattr(guess, "q") and hasattr(guess, "system"):
            return np.atleast_2d(guess.q)[-1].copy()
        try:
            g = np.asarray(guess, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"guess must be an array of {system.n} numbers (coordinates "
                             f"{list(system.layout.q_names)}), a mapping, or a Solution/State; "
                             f"got {guess!r}") from None
        if g.shape != (system.n,):
            raise ModelError(f"guess must have shape ({system.n},) (coordinates "
                             f"{list(system.layout.q_names)}); got {g.shape}")
        bad = np.flatnonzero(~np.isfinite(g))
        if bad.size:
            raise ModelError(
                f"guess: the value {g[bad[0]]} given for "
                f"{self._coordinate_text(system.layout.q_names[bad[0]])} is not finite"
                + (f" (and {bad.size - 1} more)" if bad.size > 1 else "")
                + "; give finite numbers")
        return g

    def __repr__(self) -> str:
        return (f"<{type(self).__name__}: {len(self._bodies) - 1} moving bodies, "
                f"{len(self._constraints)} constraints>")

    # -- Jupyter displays (mechsys.results._repr) --------------------------------------------
    def _repr_html_(self) -> str:
        from .results._repr import model_html

        return model_html(self)

    def _repr_markdown_(self) -> str:
        from .results._repr import model_markdown

        return model_markdown(self)

    def _repr_latex_(self) -> str:
        from .results._repr import model_latex

        return model_latex(self)


def _checked_name(name, what: str, default):
    """The name given to a new constraint or load, or ``default`` when none is given.

    Constraints and loads are addressed by name (a string) or by number (an int), so a name
    must be a non-empty string: a name ``1`` would make ``m.remove(1)`` ambiguous, and a bool
    or a NumPy integer is a number too."""
    if name is None:
        return default
    if not isinstance(name, str) or not name.strip():
        raise ModelError(f"{what} name must be a non-empty string, got {name!r} "
                         f"({type(name).__name__}); {what}s are addressed by name (a string) or "
                         "by Mech number (an int), so a name cannot be a number: write it as "
                         "text, e.g. name='drive'")
    return name


def _owner_name(owner) -> str:
    return getattr(owner, "name", None) or str(owner)


def _redundant_solution(full, reduced, res, lam, red, p):
    """Check that the left-out equations hold at every solved point (consistent
    redundancy; else :class:`ConstraintCountError` naming them) and expand the multipliers
    to every equation (minimum norm for the indeterminate ones)."""
    from .solvers._rank import expand_multipliers

    for tk, qk in zip(res.t, res.q):
        F, J = full.residual_and_jacobian(tk, qk, p)
        sc = Scaling.of(full, qk, J)
        left = np.abs(F / sc.rows(J)).max(initial=0.0)
        if not left <= 1e-8 * (1.0 + sc.offset):
            raise ConstraintCountError(
                f"the model is overconstrained and the redundant equations are inconsistent at "
                f"t = {tk:.6g}: with the independent equations solved, the dependent ones keep a "
                f"scaled residual {left:.2e} {red.text} Make the constraints agree (same axes "
                "and points), or remove or relax the dependent equations.")
    if lam is None:
        return None
    out = np.empty((len(res.t), full.m))
    for k, (tk, qk) in enumerate(zip(res.t, res.q)):
        J = full.jacobian(tk, qk, p)
        out[k] = expand_multipliers(J, reduced.jacobian(tk, qk, p), lam[k],
                                    Scaling.of(full, qk, J))
    return out


class Model2D(Model):
    r"""Planar model. Bodies have coordinates ``x, y, theta``.

    ``orientation="angle"`` (default, Mech's ``Method -> Angular``) or ``"euler"`` (Mech's
    ``SetSymbols[Method -> Euler]``): each body's rotation as Mech's two degenerate Euler
    parameters :math:`(e_i, e_j) = (\cos \theta, \sin \theta)` with :math:`e_i^2 + e_j^2 = 1` added per
    body, so
    its coordinates are ``x, y, ei, ej`` and no constraint contains a sine or cosine of a
    coordinate (manual 12.4.1; ``docs/performance-options.md``, decision 0015). Outputs
    (``angle``, ``omega``, ``alpha``, reactions, drawing) stay in the user's terms; the
    angle is then reported in ``(-pi, pi]``.
    """

    space = PLANAR

    def __init__(self, backend: str | None = None, orientation: str = "angle"):
        choice(orientation, ("angle", "euler"), "Model2D: orientation",
               "Mech's Method -> Angular or Euler")
        self.orientation = orientation
        if orientation == "euler":
            self.space = PLANAR_EULER
        super().__init__(backend)


class Model3D(Model):
    """Spatial model. Bodies have coordinates ``x, y, z, e0, e1, e2, e3`` (Euler parameters,
    normalised by one equation per body).

    ``velocity="euler" | "angular"`` and ``coordinates="global" | "local"`` (Mech's
    ``SetSymbols[Method -> ..., Coordinates -> ...]``) set the default representation of
    ``velocities``/``accelerations`` views and the default axes of ``omega``/``alpha``; the
    equations are always solved with Euler-parameter rates (decision 0006).
    """

    space = SPATIAL

    def __init__(self, backend: str | None = None, velocity: str = "euler",
                 coordinates: str = "global"):
        choice(velocity, ("euler", "angular"), "Model3D: velocity")
        choice(coordinates, ("global", "local"), "Model3D: coordinates")
        # not ``self.velocity``: that name is the output method ``m.velocity(point)``
        self.velocity_representation, self.coordinates = velocity, coordinates
        super().__init__(backend)


__all__ = ["DOF", "Model", "Model2D", "Model3D", "Constraint"]
