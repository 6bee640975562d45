r"""Units: any consistent system, and optional ``pint`` quantities as input.

mechsys computes with plain numbers and never assumes a unit: a model is correct in any
**consistent** system (m, kg, s, N; or mm, t, s, N; or in, lbf s^2/in, s, lbf ...), where the
force unit is mass x length / time^2. Angles are radians.

``m.set_units(length="mm", mass="kg", time="s")`` declares the model's system; from then on
a ``pint`` quantity given for any input is turned into a number in that system, once, where
it enters the model (decision 0043): a quantity of dimension ``[length]^a [mass]^b
[time]^c`` becomes a number in ``length^a mass^b time^c`` (angles, dimensionless in pint,
to radians). A quantity of another dimension (current, temperature ...), or of a dimension
other than the input's own (a mass given as a point coordinate), is a :class:`ModelError`.

Where the model is known when the value is given (``add_body``'s points, guess, mass,
centroid and inertia; ``body.point``, ``body.vector``, axes and planes of a body;
``m.parameter``; ``m.solve(t)``) the quantity is converted at once. A constraint's or load's
scalar arguments (a driver angle, a distance, a force magnitude, a spring stiffness) are
given before the model is: the quantity waits in a placeholder symbol and is converted when
the constraint or load is added (``m.add``, ``m.add_load``); the model's equations never
hold a unit. pint is optional (``pip install mechsys[units]``).
"""

from __future__ import annotations

from .._errors import ModelError, choice

BASE = ("length", "mass", "time")


def is_quantity(value) -> bool:
    """True for a pint ``Quantity`` (checked without importing pint)."""
    return all(hasattr(value, a) for a in ("dimensionality", "magnitude", "to", "units"))


def _registry():
    try:
        import pint
    except ImportError:
        raise ModelError("units need the optional package pint: pip install mechsys[units] "
                         "(or pip install pint)") from None
    return pint.get_application_registry()


def check_units(units: dict) -> dict:
    """Validate ``{"length": unit, "mass": unit, "time": unit}`` with pint (each unit of the
    right dimension); returns the unit names."""
    ureg = _registry()
    out = {}
    for key, name in units.items():
        choice(key, BASE, "set_units: base quantity")
        try:
            u = ureg.Unit(name)
        except Exception as exc:  # pint raises its own UndefinedUnitError, ValueError, ...
            raise ModelError(f"set_units: {key}={name!r} is not a unit pint knows ({exc})") from None
        if dict(u.dimensionality) != {f"[{key}]": 1}:
            raise ModelError(f"set_units: {key}={name!r} is not a {key} unit (its dimension is "
                             f"{u.dimensionality})")
        out[key] = str(name)
    return out


def to_units(value, units: dict | None, what: str) -> float:
    """``value`` (a pint quantity) as a float in the system ``units``; other values pass
    through unchanged."""
    if not is_quantity(value):
        return value
    if not units:
        raise ModelError(f"{what} is a pint quantity ({value}), but the model has no units: "
                         "declare them first with m.set_units(length=..., mass=..., time=...)")
    dims = dict(value.dimensionality)
    target = 1
    reg = value._REGISTRY
    for key, power in dims.items():
        base = key.strip("[]")
        if base not in BASE:
            raise ModelError(f"{what}: the quantity {value} has dimension {value.dimensionality}; "
                             "mechsys models take lengths, masses, times and their products")
        if base not in units:
            raise ModelError(f"{what}: the quantity {value} needs a {base} unit; declare it with "
                             f"m.set_units({base}=...)")
        target = target * reg.Unit(units[base]) ** power
    try:  # a dimensionless quantity (an angle in degrees, a ratio) goes to radians / 1
        return float(value.to(target if dims else "radian").magnitude)
    except Exception as exc:  # pint's DimensionalityError and friends
        raise ModelError(f"{what}: cannot convert {value} to the model's units ({exc})") from None


# -- quantities at the model's boundary (decision 0043) ---------------------------------------
LENGTH, MASS, TIME, ONE = (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, 0)
FORCE, MOMENT, INERTIA = (1, 1, -2), (2, 1, -2), (2, 1, 0)

#: the dimension each named scalar input must have (``what`` of ``as_expr``/``_magnitude``);
#: inputs not listed take their quantity's own dimension
EXPECTED = {
    "Force magnitude": FORCE, "Moment magnitude": MOMENT, "Gravity g": (1, 0, -2),
    "Spring stiffness": (0, 1, -2), "Spring free_length": LENGTH, "Damper damping": (0, 1, -1),
    "TorsionSpring stiffness": MOMENT, "TorsionSpring free_angle": ONE,
    "TorsionDamper damping": (2, 1, -1), "RotationLock1 angle": ONE, "RelativeAngle1 angle": ONE,
}

_DIM_NAMES = ("length", "mass", "time")


def dims_of(q, what: str) -> tuple:
    """Exponents ``(length, mass, time)`` of a quantity's dimension; other bases refused."""
    out = [0, 0, 0]
    for key, power in dict(q.dimensionality).items():
        base = key.strip("[]")
        if base not in _DIM_NAMES:
            raise ModelError(f"{what}: the quantity {q} has dimension {q.dimensionality}; "
                             "mechsys models take lengths, masses, times and their products")
        out[_DIM_NAMES.index(base)] = power
    return tuple(out)


def _dims_text(d) -> str:
    parts = [f"[{n}]" + (f"^{p}" if p != 1 else "") for n, p in zip(_DIM_NAMES, d) if p]
    return " ".join(parts) or "dimensionless"


def number(q, units: dict | None, what: str, dims: tuple | None = None) -> float:
    """One quantity as a float in ``units``; its dimension must be ``dims`` when given."""
    if dims is not None:
        got = dims_of(q, what)
        if tuple(got) != tuple(dims):
            raise ModelError(f"{what}: the quantity {q} is {_dims_text(got)}, but this input "
                             f"is {_dims_text(dims)}")
    return to_units(q, units, what)


def has_quantity(value) -> bool:
    """A quantity anywhere inside ``value`` (nested sequences, object arrays, dicts)."""
    if is_quantity(value):
        return True
    if isinstance(value, dict):
        return any(has_quantity(v) for v in value.values())
    if isinstance(value, (list, tuple)) or (hasattr(value, "dtype") and value.dtype == object):
        return any(has_quantity(v) for v in value)
    return False


def convert(value, units: dict | None, what: str, dims: tuple | None = None):
    """``value`` with every quantity inside replaced by its number in ``units`` (the structure
    kept: tuples stay tuples, an array quantity becomes an array). ``dims``: the dimension
    every quantity inside must have (None: its own)."""
    if is_quantity(value):
        mag = value.magnitude
        if hasattr(mag, "__len__"):  # an array quantity: one conversion factor for all
            import numpy as np

            return np.asarray(mag, dtype=float) * number(1.0 * value.units, units, what, dims)
        return number(value, units, what, dims)
    if not has_quantity(value):
        return value
    if isinstance(value, dict):
        return {k: convert(v, units, f"{what}[{k!r}]", dims) for k, v in value.items()}
    items = [convert(v, units, what, dims) for v in value]
    return tuple(items) if isinstance(value, tuple) else items


def time_numbers(model):
    """``(value, what) -> value`` with every pint quantity inside in ``model``'s time unit
    (the times and step lengths of a ``simulate``: :func:`~mechsys.solvers._integrators.plan_run`)."""
    return lambda value, what: convert(value, getattr(model, "units", None), what, (0, 0, 1))


_PENDING: dict = {}


def placeholder(q, what: str):
    """A SymPy symbol standing for the quantity ``q`` until the constraint or load holding it
    is added to a model (:func:`resolve`)."""
    import sympy as sp

    name = f"{what}={q} (pint quantity #{len(_PENDING) + 1})"
    sym = sp.Symbol(name, real=True)
    _PENDING[name] = (q, what)
    return sym


def resolve(obj, units: dict | None, label: str) -> None:
    """Replace, in the attributes of a constraint or load, every placeholder by its number in
    the model's ``units`` (the dimension named in :data:`EXPECTED` checked)."""
    import sympy as sp

    def subs_of(expr):
        found = {}
        for s in expr.free_symbols:
            hit = _PENDING.get(s.name)
            if hit is not None and isinstance(s, sp.Symbol):
                q, what = hit
                found[s] = sp.Float(number(q, units, f"{label}: {what}", EXPECTED.get(what)))
        return found

    def fix(value):
        if isinstance(value, (sp.Basic, sp.MatrixBase)):
            found = subs_of(value)
            return value.xreplace(found) if found else value
        if isinstance(value, list):
            return [fix(v) for v in value]
        if isinstance(value, tuple) and not hasattr(value, "_fields"):
            return tuple(fix(v) for v in value)
        return value

    if not _PENDING:
        return
    for key, value in list(vars(obj).items()):
        new = fix(value)
        if new is not value:
            setattr(obj, key, new)


__all__ = ["check_units", "convert", "has_quantity", "is_quantity", "placeholder", "resolve",
           "to_units"]
