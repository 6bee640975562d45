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
