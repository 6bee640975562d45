r"""A solution's outputs as pint quantities: ``sol.in_units`` (decision 0056).

Every named output whose physical dimension mechsys knows is offered with its unit in the
model's declared system (``m.set_units``): a point's location, velocity and acceleration
(:math:`L`, :math:`L T^{-1}`, :math:`L T^{-2}`), a body's angle, angular velocity and
acceleration (:math:`\mathrm{rad}`, :math:`\mathrm{rad}\, T^{-1}`,
:math:`\mathrm{rad}\, T^{-2}`), reactions and loads as force and moment
(:math:`M L T^{-2}`, :math:`M L^2 T^{-2}`), energies (:math:`M L^2 T^{-2}`) and momenta
(:math:`M L T^{-1}`, :math:`M L^2 T^{-1}`). The numbers are those of the plain output: the
unit is attached, never a conversion factor applied.

An arbitrary expression (``eval``) has no dimension mechsys could infer -- a number in it
may be a length or a ratio -- so the caller names it: ``sol.in_units.eval(expr, "[force]")``
or by any unit of that dimension (``"N"``). Every other output is refused with a
:class:`~mechsys.ModelError` that names it and says where its numbers are.

Example::

    m.set_units(length="mm", mass="kg", time="s")
    sol = m.solve(t, solution="dynamic")
    sol.in_units.location(piston.point(0)).to("m")
    F, M = sol.in_units.reaction("pin", crank)       # kg*mm/s^2 and kg*mm^2/s^2
    sol.in_units.eval(r * sp.cos(th), "mm")
"""

from __future__ import annotations

import numpy as np

from .._errors import ModelError
from ._tables import ENERGY, FORCE, LENGTH, MOMENT, ONE, unit_text

#: output name -> (dimension exponents (length, mass, time), angle) of its value, or a tuple
#: of such pairs for an output that returns ``(force, moment)``
_KNOWN: dict = {
    "location": (LENGTH, False),
    "velocity": ((1, 0, -1), False),
    "acceleration": ((1, 0, -2), False),
    "relative_velocity": ((1, 0, -1), False),
    "angle": (ONE, True),
    "omega": ((0, 0, -1), True),
    "alpha": ((0, 0, -2), True),
    "body_energy": (ENERGY, False),
    "potential_energy": (ENERGY, False),
    "linear_momentum": ((1, 1, -1), False),
    "angular_momentum": ((2, 1, -1), False),
    "reaction": ((FORCE, False), (MOMENT, False)),
    "joint_reaction": ((FORCE, False), (MOMENT, False)),
    "loads": ((FORCE, False), (MOMENT, False)),
}


class InUnits:
    """The outputs of one solution as pint ``Quantity`` arrays in the model's declared units
    (``sol.in_units``; see the module docstring). Needs pint."""

    def __init__(self, sol):
        units = getattr(sol.model, "units", None)
        if not units:
            raise ModelError("results in units need the model's units: declare them with "
                             "m.set_units(length=..., mass=..., time=...) before solving")
        from ..geometry._units import _registry

        self._sol, self._units, self._ureg = sol, units, _registry()

    def _quantity(self, values, dims, angle, what):
        text = unit_text(dims, self._units, angle)
        if text is None:
            base = [b for b, p in zip(("length", "mass", "time"), dims) if p
                    and b not in self._units]
            raise ModelError(f"in_units.{what}: its unit needs a {base[0]} unit the model did "
                             f"not declare: add it with m.set_units({base[0]}=...)")
        return self._ureg.Quantity(np.asarray(values, dtype=float), text.replace("^", "**"))

    @property
    def t(self):
        """The solution's times, in the model's time unit."""
        return self._quantity(self._sol.t, (0, 0, 1), False, "t")

    def eval(self, expr, dimension: str | None = None):
        """``sol.eval(expr)`` with the unit of ``dimension`` in the model's system.

        ``dimension`` is a pint dimension (``"[length]"``, ``"[force]"``,
        ``"[length]/[time]"``), any unit of it (``"N"``, ``"mm/s"``: only its dimension is
        used, the numbers stay in the model's units), or ``"rad"``/``"1"`` for an angle or a
        ratio. Example: ``sol.in_units.eval(r * sp.cos(th), "[length]").to("m")``."""
        from ..geometry._units import dims_of

        if not isinstance(dimension, str) or not dimension.strip():  # None: not given
            raise ModelError("in_units.eval(expr, dimension): name the expression's dimension, "
                             "e.g. '[length]', '[force]' or a unit of it such as 'N' or 'mm/s' "
                             "(mechsys cannot infer it: a number in an expression may be a "
                             "length or a ratio)")
        text = dimension.strip()
        angle = text in ("rad", "radian", "deg", "degree")
        try:
            if text.startswith("["):
                dim = self._ureg.get_dimensionality(text)
                dims = tuple(int(dim.get(f"[{b}]", 0)) for b in ("length", "mass", "time"))
                extra = [k for k in dim if k not in ("[length]", "[mass]", "[time]")]
                if extra:
                    raise ModelError(f"in_units.eval: dimension {text!r} holds {extra}; "
                                     "mechsys results are lengths, masses, times and their "
                                     "products")
            else:
                dims = dims_of(self._ureg.Quantity(1, text), f"in_units.eval dimension {text!r}")
        except ModelError:
            raise
        except Exception as exc:  # pint's UndefinedUnitError, DimensionalityError, ...
            raise ModelError(f"in_units.eval: {text!r} is neither a pint dimension like "
                             f"'[length]' nor a unit pint knows ({exc})") from None
        return self._quantity(self._sol.eval(expr), dims, angle, "eval")

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        if name not in _KNOWN:
            raise ModelError(
                f"in_units.{name}: mechsys does not know the dimension of {name!r}; outputs in "
                f"units are {sorted(_KNOWN) + ['eval', 't']}. Give an expression's dimension "
                "yourself with sol.in_units.eval(expr, '[length]'), or take a table column "
                "with sol.quantity(name)")
        method = getattr(self._sol, name)
        spec = _KNOWN[name]

        def call(*args, **kwargs):
            value = method(*args, **kwargs)
            if isinstance(spec[0], tuple) and isinstance(spec[0][0], tuple):
                if not (isinstance(value, tuple) and len(value) == len(spec)):
                    # loads(...) on generalized coordinates mixes forces and moments
                    raise ModelError(
                        f"in_units.{name}: this call returns loads on generalized coordinates, "
                        "whose components mix forces and moments; ask for "
                        "coordinates='global' or 'local' to get (force, moment) in units")
                return tuple(self._quantity(v, d, a, name) for v, (d, a) in zip(value, spec))
            return self._quantity(value, spec[0], spec[1], name)

        call.__name__ = name
        call.__doc__ = f"``sol.{name}(...)`` as a pint Quantity in the model's units."
        return call

    def __dir__(self):
        return sorted(set(_KNOWN) | {"eval", "t"})

    def __repr__(self) -> str:
        return f"<outputs in units {self._units} of {self._sol!r}>"
