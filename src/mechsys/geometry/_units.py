r"""Units: any consistent system, and optional ``pint`` quantities as input.

mechsys computes with plain numbers and never assumes a unit: a model is correct in any
**consistent** system (m, kg, s, N; or mm, t, s, N; or in, lbf s^2/in, s, lbf ...), where the
force unit is mass x length / time^2. Angles are radians.

``m.set_units(length="mm", mass="kg", time="s")`` declares the model's system; from then on
a ``pint`` quantity given as a parameter value (``m.parameter``, ``m.set_parameters``) or
converted with ``m.to_units(q)`` is turned into a number in that system: a quantity of
dimension ``[length]^a [mass]^b [time]^c`` is converted to ``length^a mass^b time^c``
(angles, dimensionless in pint, to radians). A quantity of another dimension (current,
temperature ...) is a :class:`ModelError`. pint is optional (``pip install mechsys[units]``).
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


__all__ = ["check_units", "is_quantity", "to_units"]
