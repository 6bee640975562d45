"""Exception classes. Every error raised on bad input or failed solves is one of these."""

from __future__ import annotations


class MechError(Exception):
    """Base class of every mechsys error."""


class ModelError(MechError, ValueError):
    """The model description is invalid (unknown body or point, bad dimension, duplicate name)."""


class UnknownBodyError(ModelError, KeyError):
    """A body was addressed by a name, number or handle that the model does not have."""

    def __str__(self) -> str:  # KeyError quotes its message; we want it plain
        return str(self.args[0]) if self.args else ""


class UnknownPointError(ModelError, KeyError):
    """A point was addressed by a name or number the body does not define."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class UnknownConstraintError(ModelError, KeyError):
    """A constraint was addressed by a name, number or handle the model does not have."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class GeometryError(ModelError):
    """A geometric argument is degenerate or has the wrong dimension (zero-length axis, ...)."""


class NotSteadyError(ModelError):
    """A linearisation's reference state is not an equilibrium or a steady motion in the
    chosen coordinates (an acceleration is not zero, or the motion changes them)."""


class ConstraintCountError(MechError):
    """The model has the wrong number of degrees of freedom for the requested analysis."""


class ConvergenceError(MechError):
    """Newton's method did not converge. ``residuals`` and ``history`` say by how much."""

    def __init__(self, message: str, *, time=None, residuals=None, history=None,
                 diagnosis=None):
        super().__init__(message)
        self.time = time
        self.residuals = residuals
        self.history = history
        #: a ``ConvergenceDiagnosis`` (Mech 13.2) when the solver made one, else None
        self.diagnosis = diagnosis

    @property
    def constraints(self) -> tuple:
        """``((constraint label, scaled residual), ...)``, worst first (empty if unknown)."""
        return self.diagnosis.constraints if self.diagnosis is not None else ()

    @property
    def coordinates(self) -> tuple:
        """``((coordinate name, move, scaled move), ...)``: the coordinates Newton moved most."""
        return self.diagnosis.coordinates if self.diagnosis is not None else ()

    @property
    def suggestion(self) -> str:
        """What to try (empty if unknown)."""
        return self.diagnosis.suggestion if self.diagnosis is not None else ""


class SingularJacobianError(MechError):
    """The constraint Jacobian is rank deficient: redundant constraints or a lock-up position."""

    def __init__(self, message: str, *, time=None, dependent=None, rank=None):
        super().__init__(message)
        self.time = time
        self.dependent = dependent or []
        self.rank = rank


class SingularMassError(SingularJacobianError):
    """Free motion: the mass matrix is singular on the motions the constraints leave free (a
    body without mass or inertia whose motion no constraint determines). ``bodies`` names
    them. A :class:`SingularJacobianError`, since the augmented matrix is what is singular."""

    def __init__(self, message: str, *, time=None, rank=None, bodies=None):
        super().__init__(message, time=time, rank=rank)
        self.bodies = bodies or []


class CacheError(MechError):
    """An on-disk cache mechsys would read (compiled kernels, ``MECHSYS_CACHE``) is not private
    to the user running it: the directory, its key file or an entry is owned by someone else
    or writable by others. Nothing in it is read; the message names the path and what to do."""


class NearSingularWarning(UserWarning):
    """The constraint Jacobian is nearly singular (close to a lock-up or toggle position):
    velocities and accelerations there are large and sensitive."""


class SlowPathWarning(UserWarning):
    """Numba or SymEngine, core dependencies of mechsys, cannot be imported (an install with
    ``--no-deps``, or a platform without their wheels): every result is the same, but the
    hot loops run in Python, 10 to 100 times slower. Said once per process."""


class RedundantConstraintWarning(UserWarning):
    """Redundant but consistent constraints (as in Adams): the dependent equations, found by
    a rank-revealing factorisation at the start, are left out of the solution; their
    reactions are not determined by rigid-body statics and are reported as the minimum-norm
    solution (``Solution.extra["indeterminate"]``). ``redundant``: the constraints whose
    equations were left out; ``mobility``: the degrees of freedom of the mechanism."""

    def __init__(self, message: str, *, redundant=None, mobility=None):
        super().__init__(message)
        self.redundant = redundant or []
        self.mobility = mobility


_warned: set[str] = set()


def slow_path_warning(package: str, exc: BaseException) -> None:
    """Say once per package and process that a core dependency cannot be imported (decision
    0041): the answers are the same, the hot loops run in Python."""
    if package in _warned:
        return
    _warned.add(package)
    import warnings

    warnings.warn(f"{package} cannot be imported ({exc}); it is a core dependency of mechsys: "
                  f"results are unchanged but the hot loops run in Python, 10 to 100 times "
                  f"slower. Install it with `pip install {package}`.", SlowPathWarning,
                  stacklevel=3)


def parameter_value(name: str, value) -> float:
    """A parameter value as a finite float, or a :class:`ModelError` naming the parameter
    (shared by ``Model.parameter``/``set_parameters`` and the analyses that take parameter
    values)."""
    import math

    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ModelError(f"parameter {name!r} needs a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ModelError(f"parameter {name!r} must be finite, got {v}")
    return v


class OptionError(ModelError):
    """An option or an enumerated keyword has a value outside its accepted set (a misspelt
    backend, method or solution kind), or an option class got a field it does not have. The
    message names the option, lists the accepted values and suggests the closest one."""


class DegradedAccuracyWarning(UserWarning):
    """A run's own measure says its answer is less accurate than asked: the constraint drift
    of a free motion without correction, or coordinates so far from the origin (against the
    model's length scale) that double precision cannot meet the residual tolerance.
    ``measure`` holds the figure that triggered it, ``threshold`` the bound it passed."""

    def __init__(self, message: str, *, measure=None, threshold=None):
        super().__init__(message)
        self.measure = measure
        self.threshold = threshold


def closest(value, allowed):
    """The accepted value closest to ``value`` (case-insensitive ``difflib`` ratio of at least
    0.6), or None."""
    import difflib

    if not isinstance(value, str):
        return None
    lower = {a.lower(): a for a in allowed if isinstance(a, str)}
    hit = difflib.get_close_matches(value.lower(), list(lower), n=1, cutoff=0.6)
    return lower[hit[0]] if hit else None


def close_match(value, allowed) -> str:
    """`` (did you mean 'x'?)`` for the accepted value closest to ``value``, or ``""``."""
    hit = closest(value, allowed)
    return f" (did you mean {hit!r}?)" if hit is not None else ""


def choice(value, allowed, what: str, hint: str = ""):
    """``value`` if it is one of ``allowed``; else an :class:`OptionError` naming ``what``
    (the option or keyword), the accepted values and the closest of them. ``hint``: a
    sentence appended to the message (what the values mean)."""
    allowed = tuple(allowed)
    try:
        ok = bool(value in allowed)
    except (TypeError, ValueError):  # an array (ambiguous truth) or an uncomparable value
        ok = False
    if ok:
        return value
    listed = ", ".join(repr(a) for a in allowed)
    raise OptionError(f"{what} must be one of {listed}, got {value!r}{close_match(value, allowed)}"
                      + (f"; {hint}" if hint else ""))


def option_fields(cls):
    """Class decorator for an options dataclass: an unknown keyword or too many positional
    arguments raise an :class:`OptionError` naming the option class and its fields, instead
    of the bare ``TypeError`` of the generated ``__init__``."""
    import functools

    init = cls.__init__
    fields = tuple(cls.__dataclass_fields__)

    @functools.wraps(init)
    def __init__(self, *args, **kwargs):
        unknown = [k for k in kwargs if k not in fields]
        if unknown:
            hints = "".join(close_match(k, fields) for k in unknown[:1])
            raise OptionError(f"{cls.__name__}: unknown option(s) {unknown}{hints}; its options are "
                              f"{list(fields)}")
        if len(args) > len(fields):
            raise OptionError(f"{cls.__name__} takes at most {len(fields)} options "
                              f"({list(fields)}), got {len(args)} positional arguments")
        twice = [f for f in fields[:len(args)] if f in kwargs]
        if twice:
            raise OptionError(f"{cls.__name__}: option(s) {twice} given twice (by position and "
                              "by name)")
        init(self, *args, **kwargs)

    cls.__init__ = __init__
    return cls


def unknown_options(what: str, unknown, known) -> None:
    """Raise an :class:`OptionError` for the ``unknown`` option names given to ``what``,
    listing the ``known`` ones and the closest to each misspelt name; nothing if none."""
    unknown = sorted(map(str, unknown))
    if not unknown:
        return
    known = list(known)
    hints = [f"{u!r}: did you mean {closest(u, known)!r}?" for u in unknown
             if closest(u, known) is not None]
    raise OptionError(f"{what}: unknown option(s) {unknown}"
                      + (f" ({'; '.join(hints)})" if hints else "")
                      + f"; the options are {', '.join(known)}")
