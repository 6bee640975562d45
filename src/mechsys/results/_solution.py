r"""Immutable results: :class:`State` (one time) and :class:`Solution` (arrays over time).

Array shapes (``N`` times, ``n`` coordinates): ``t (N,)``, ``q, qd, qdd (N, n)``. Output
functions evaluate the model's symbolic expressions over all ``N`` points in one compiled
call: points give ``(N, dim)``, scalars ``(N,)``; a solution of a scalar time drops the
leading axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from .._errors import MechError, ModelError
from ._extra import Extra
from ._linkage import LinkageOutputs
from ._load_outputs import LoadOutputs
from ._momentum import MomentumOutputs
from ._outputs import OutputFunctions, VelocityViews


@dataclass(frozen=True, eq=False)
class Solution(OutputFunctions, LoadOutputs, VelocityViews, MomentumOutputs, LinkageOutputs):
    """Kinematic (or later dynamic) solution over ``N`` time points.

    Attributes:

    * ``t`` (N,) times; ``q``, ``qd``, ``qdd`` (N, n) coordinates, velocities, accelerations
      (``None`` when that order was not solved); ``p`` (np,) parameter values used;
    * ``system`` the compiled System; ``model`` the Model (for symbolic outputs);
    * ``iterations`` (N,) Newton iterations per point; ``evaluations`` compiled-function calls;
    * ``success``, ``status``, ``message`` the outcome (a failed solve raises instead);
    * ``extra`` more per-point data (a ``dict``), e.g. ``"rcond"`` (N,) the reciprocal
      condition estimate of the scaled ``Phi_q`` (computed when first read), and with
      switches ``"stages"`` (``{switch name: (N,) stage numbers}``, read with :meth:`stage`).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None
    qdd: np.ndarray | None
    p: np.ndarray
    system: object
    model: object
    iterations: np.ndarray
    evaluations: int = 0
    scalar: bool = False
    success: bool = True
    status: int = 0
    message: str = "solved"
    lam: np.ndarray | None = None
    mode: str = "acceleration"
    extra: dict = field(default_factory=dict)

    @classmethod
    def from_sweep(cls, model, system, res, p, scalar=False, lam=None,
                   mode="acceleration") -> Solution:
        for a in (res.q, res.qd, res.qdd, lam):
            if a is not None:
                a.setflags(write=False)
        if getattr(res, "rcond_pending", False):
            # computed when first read (a compiled sweep's regular points: decision 0023)
            extra = Extra(deferred={"rcond": lambda: res.rcond})
        else:
            rc = getattr(res, "rcond", None)
            extra = Extra() if rc is None else Extra({"rcond": rc})
        return cls(t=res.t, q=res.q, qd=res.qd, qdd=res.qdd, p=np.asarray(p), system=system,
                   model=model, iterations=res.iterations, evaluations=res.evaluations,
                   scalar=scalar, lam=lam, mode=mode, extra=extra)

    def __len__(self) -> int:
        return len(self.t)

    @property
    def names(self) -> tuple:
        """Coordinate names ``"body.coord"`` in layout order."""
        return self.system.layout.q_names

    def stage(self, switch=None) -> np.ndarray:
        """The stage (numbered from 1, as the switch lists them) of a ``StageSwitch`` or
        ``TimeSwitch`` in effect at every point: ``(N,)`` ints (an int for a scalar time).
        ``switch``: handle or name; may be omitted when the model has exactly one switch."""
        stages = self.extra.get("stages")
        if not stages:
            raise ModelError("this solution has no stages: the model has no StageSwitch or "
                             "TimeSwitch")
        if switch is None:
            if len(stages) > 1:
                raise ModelError(f"the model has {len(stages)} switches {sorted(stages)}; name one")
            name = next(iter(stages))
        else:
            name = getattr(switch, "name", switch)
            if name not in stages:
                raise ModelError(f"no switch {switch!r} in this solution; switches are "
                                 f"{sorted(stages)}")
        out = stages[name]
        return int(out[0]) if self.scalar else out

    # -- named access ---------------------------------------------------------------------
    def __getitem__(self, key):
        """Coordinate history by name (``"crank.th"``, ``"th2"``) or symbol."""
        return self.coordinate(key)

    def coordinate(self, key, order: int = 0) -> np.ndarray:
        """History of one coordinate (``order`` 0), its velocity (1) or acceleration (2)."""
        if order not in (0, 1, 2):
            raise ModelError(f"order must be 0 (coordinate), 1 (velocity) or 2 (acceleration), "
                             f"got {order!r}")
        j = self.system.layout.index(key)
        out = self._order(order)[:, j]
        return out[0] if self.scalar else out

    @property
    def _at_rest(self) -> bool:
        """A static solution (equilibrium): velocities and accelerations are zero by
        definition, not missing."""
        return self.mode in ("static", "free-static")

    def _order(self, order: int) -> np.ndarray:
        """Coordinates (0), velocities (1) or accelerations (2), ``(N, n)``."""
        arr = (self.q, self.qd, self.qdd)[order]
        if arr is None:
            if not self._at_rest:
                raise MechError(self._missing(order))
            arr = np.zeros_like(self.q)
        return arr

    def _missing(self, order: int) -> str:
        what = ("location", "velocity", "acceleration")[order]
        if self.mode.startswith("free-"):
            return (f"this {self.mode} solution has no {what} data; free motion "
                    "(free(solution='dynamic')) has all orders")
        if self.mode == "path":
            return f"this path solution has no {what} data"
        if order == 2:  # with multipliers (loads) inverse dynamics, else plain kinematics
            how = "solution='dynamic'" if self.mode == "kinematic" else "solution='acceleration'"
        else:
            how = "solution='velocity' or 'acceleration'"
        return f"this {self.mode} solution has no {what} data; solve with {how}"

    # -- evaluation -----------------------------------------------------------------------
    def _finish(self, expr):
        return self.eval(expr)

    def _model(self):
        return self.model

    def eval(self, expr):
        """Evaluate any SymPy expression or matrix of ``T``, coordinates, velocities,
        accelerations and parameters at every time point. Shape ``(N,) + expr.shape``
        (``(N,)`` for a scalar, ``(N, k)`` for a column vector)."""
        is_matrix = isinstance(expr, sp.MatrixBase)
        m = sp.Matrix(expr) if is_matrix else sp.Matrix([sp.sympify(expr)])
        lay = self.system.layout
        free = set().union(*(e.free_symbols for e in m)) if len(m) else set()
        if self.system.gen_subs:  # slave symbols stand for expressions of q, qd, qdd
            from ..compile._generalized import slave_dependencies

            free |= slave_dependencies(self.system, free)
        for order, syms in ((2, lay.qdd_symbols), (1, lay.qd_symbols)):  # the highest first
            if free & set(syms):
                self._order(order)  # raises when this order is missing
        lam_syms = self.system.lam_symbols
        if free & set(lam_syms) and self.lam is None:
            raise MechError("this solution has no Lagrange multipliers (reactions); solve with "
                            "solution='static', 'kinematic' or 'dynamic'")
        f = self.system.compile_expression(list(m))
        N, n, mm = len(self.t), lay.n, len(lam_syms)
        X = np.empty((N, 1 + 3 * n + mm + len(self.p)))
        X[:, 0] = self.t
        X[:, 1 : 1 + n] = self.q
        X[:, 1 + n : 1 + 2 * n] = 0.0 if self.qd is None else self.qd
        X[:, 1 + 2 * n : 1 + 3 * n] = 0.0 if self.qdd is None else self.qdd
        # (free motion with velocity constraints: lam holds mu after the mm multipliers)
        X[:, 1 + 3 * n : 1 + 3 * n + mm] = 0.0 if self.lam is None else self.lam[:, :mm]
        X[:, 1 + 3 * n + mm :] = self.p
        with np.errstate(divide="ignore", invalid="ignore"):
            vals = f.batch(X)
        if not is_matrix:
            out = vals[:, 0]
        elif m.shape[1] == 1:
            out = vals
        else:
            out = vals.reshape((N,) + m.shape)
        return out[0] if self.scalar else out

    def sensitivity(self, parameters):
        """Exact derivatives of this solution with respect to ``parameters`` (names or
        symbols): ``self.model.sensitivity(parameters).of(self)``, a
        :class:`~mechsys.Sensitivity` (see docs/sensitivity.md)."""
        return self.model.sensitivity(parameters).of(self)

    # -- states and interpolation ---------------------------------------------------------
    def state(self, k: int = -1) -> State:
        """The :class:`State` at index ``k`` (negative counts from the end)."""
        N = len(self.t)
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
            raise ModelError(f"state index must be an integer, got {k!r}")
        if not -N <= k < N:
            rng = f"0..{N - 1} (or -{N}..-1 from the end)" if N else "none: the solution is empty"
            raise ModelError(f"state index {k} is out of range; this solution has {N} time "
                             f"point(s), valid indices {rng}")
        return State(
            t=float(self.t[k]), q=self.q[k].copy(),
            qd=None if self.qd is None else self.qd[k].copy(),
            qdd=None if self.qdd is None else self.qdd[k].copy(),
            system=self.system)

    def interpolate(self, t) -> Solution:
        """Values at other times inside the solved range: cubic Hermite on positions with
        the solved velocities (and on velocities with accelerations), linear otherwise."""
        from scipy.interpolate import CubicHermiteSpline, interp1d

        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if len(self.t) < 2:
            raise MechError("interpolation needs a solution at two or more times")
        if tt.min() < self.t.min() - 1e-12 or tt.max() > self.t.max() + 1e-12:
            raise MechError(f"interpolation times must lie in [{self.t.min()}, {self.t.max()}]")

        def interp(y, dy):
            if dy is not None:
                return CubicHermiteSpline(self.t, y, dy, axis=0)(tt)
            return interp1d(self.t, y, axis=0)(tt)

        q = interp(self.q, self.qd)
        qd = None if self.qd is None else interp(self.qd, self.qdd)
        qdd = None if self.qdd is None else interp1d(self.t, self.qdd, axis=0)(tt)
        return Solution(t=tt, q=q, qd=qd, qdd=qdd, p=self.p, system=self.system,
                        model=self.model, iterations=np.zeros(len(tt), dtype=int),
                        scalar=np.ndim(t) == 0, message="interpolated")

    def time_interpolate(self, expr, t):
        """Mech's ``TimeInterpolate``: the values of a SymPy expression (of ``T``,
        coordinates, velocities, parameters) at times ``t`` inside the solved range, from
        the solution interpolated there (:meth:`interpolate`: cubic Hermite on the positions
        when velocities were solved, so an expression of positions is third-order accurate
        between the solved times). Equivalent to ``self.interpolate(t).eval(expr)``."""
        return self.interpolate(t).eval(expr)

    def arc_length(self, point) -> np.ndarray:
        r"""Length of the path a point travels over the solution (Mech's ``ArcLength``), from
        the first time to each solved time: an array ``(N,)`` starting at 0.

        .. math:: s(t_k) = \int_{t_0}^{t_k} \lVert \dot r_P(t) \rVert \, dt

        With solved velocities, each interval's path is the cubic Hermite curve through the
        two locations with their velocities, and its speed is integrated by five-point
        Gauss-Legendre quadrature (error ``O(h^4)`` per unit time); without them, the chords
        between the solved locations are summed (a lower bound). A point that moves back
        along its path adds the way back: this is distance travelled, not displacement."""
        P = np.asarray(self.location(point), dtype=float).reshape(len(self.t), -1)
        if len(self.t) < 2:
            return np.zeros(len(self.t))
        if self.qd is None:
            seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
        else:
            V = np.asarray(self.velocity(point), dtype=float).reshape(len(self.t), -1)
            h = np.diff(self.t)[:, None]
            x, w = np.polynomial.legendre.leggauss(5)
            s = (x + 1) / 2
            seg = np.zeros(len(h))
            dP = P[1:] - P[:-1]
            for sk, wk in zip(s, w):
                # derivative of the cubic Hermite basis on [0, 1], times 1/h for d/dt
                d00, d10 = 6 * sk**2 - 6 * sk, 3 * sk**2 - 4 * sk + 1
                d11 = 3 * sk**2 - 2 * sk
                vel = -d00 * dP / h + d10 * V[:-1] + d11 * V[1:]
                seg += wk / 2 * np.linalg.norm(vel, axis=1) * np.abs(h[:, 0])
        return np.concatenate(([0.0], np.cumsum(seg)))

    def plot(self, outputs, **kw):
        """Time histories of outputs (see :func:`mechsys.draw.plot`)."""
        from .. import draw

        return draw.plot(self, outputs, **kw)

    def to_dataframe(self, reactions: bool = False, loads: bool = False, energies: bool = False):
        """A pandas DataFrame: ``t``, each coordinate with ``<name>_d`` and ``<name>_dd``; with
        ``reactions=True`` every constraint's force and moment on each of its bodies
        (``<constraint>.<body>.Fx`` ...; needs multipliers), ``loads=True`` the applied loads
        on each body, ``energies=True`` kinetic energies per body, total kinetic and potential
        energy. ``df.attrs["units"]`` gives each column's unit in the model's declared units
        (``m.set_units``; None where not declared or not known), ``df.attrs["dimensions"]``
        its dimension (``"M*L/T^2"``). Needs pandas. See :mod:`mechsys.results._tables`.

        Example: ``sol.to_dataframe(reactions=True)["pivot.crank.Fx"]``."""
        from ._tables import to_dataframe

        return to_dataframe(self, reactions=reactions, loads=loads, energies=energies)

    def to_xarray(self, reactions: bool = False, loads: bool = False, energies: bool = False):
        """The table of :meth:`to_dataframe` as an xarray ``Dataset`` over ``t``, each
        variable with ``units`` (when known), ``dimension`` and ``long_name`` attributes.
        Needs xarray."""
        from ._tables import to_xarray

        return to_xarray(self, reactions=reactions, loads=loads, energies=energies)

    def quantity(self, name: str, reactions: bool = False, loads: bool = False,
                 energies: bool = False):
        """The column ``name`` of :meth:`to_dataframe` (``"t"``, a coordinate, ``"crank.th_d"``,
        a reaction ``"<constraint>.<body>.Fx"`` with ``reactions=True`` ...) as a pint
        ``Quantity`` array in the model's declared units (``m.set_units``), ready for
        ``.to("mm")``. A column whose unit mechsys does not know (a model variable) is refused
        with a :class:`~mechsys.ModelError`, a misspelt name with an
        :class:`~mechsys.OptionError` naming the closest. Needs pint.

        Example: ``sol.quantity("piston.x_d").to("m/s")``."""
        from ._tables import quantities

        return quantities(self, [name], reactions=reactions, loads=loads,
                          energies=energies)[name]

    @property
    def in_units(self):
        """The outputs whose dimension mechsys knows, as pint quantities in the model's
        declared units (``m.set_units``): ``location``, ``velocity``, ``acceleration``,
        ``relative_velocity``, ``angle``, ``omega``, ``alpha``, ``reaction``,
        ``joint_reaction``, ``loads`` (force and moment), ``body_energy``,
        ``potential_energy``, ``linear_momentum``, ``angular_momentum``, ``t``; and
        ``eval(expr, dimension)`` for an expression, whose dimension the caller names. Any
        other output is refused with a :class:`~mechsys.ModelError` (decision 0056). Needs
        pint.

        Example: ``sol.in_units.location(piston.point(0)).to("m")``,
        ``sol.in_units.eval(r * sp.cos(th), "[length]")``."""
        from ._in_units import InUnits

        return InUnits(self)

    def quantities(self, reactions: bool = False, loads: bool = False,
                   energies: bool = False) -> dict:
        """Every column of :meth:`to_dataframe` whose unit is known, as ``{name: pint
        Quantity}`` in the model's declared units (the columns of model variables are left
        out; :meth:`quantity` says why when one is asked for). Needs pint."""
        from ._tables import quantities

        return quantities(self, None, reactions=reactions, loads=loads, energies=energies)

    def save(self, path, reactions: bool = False, loads: bool = False, energies: bool = False):
        """Write the table of :meth:`to_dataframe` to ``path``: ``.csv`` (header
        ``name [unit]``, repr-exact floats), ``.parquet`` (pyarrow), ``.h5``/``.hdf5``
        (h5py) or ``.nc`` (netCDF via xarray), units in each format's metadata. Returns the
        path; the optional writer is named when it is missing."""
        from ._tables import save

        return save(self, path, reactions=reactions, loads=loads, energies=energies)

    def table(self) -> str:
        """A plain-text table of all coordinates over time."""
        cols = ["t", *self.names]
        rows = [" ".join(f"{c:>14s}" for c in cols)]
        for k in range(len(self.t)):
            rows.append(" ".join(f"{v:14.6g}" for v in [self.t[k], *self.q[k]]))
        return "\n".join(rows)

    def __repr__(self) -> str:
        orders = "location" + (", velocity" if self.qd is not None else "") + (
            ", acceleration" if self.qdd is not None else "")
        span = f" in [{np.min(self.t):g}, {np.max(self.t):g}]" if len(self.t) else ""
        its = int(np.sum(self.iterations)) if self.iterations is not None else 0
        n = getattr(self.system, "n", "?")
        return (f"<Solution: {len(self.t)} time point(s){span}, {n} coordinates, {orders}; "
                f"Newton iterations {its}>")

    def _repr_html_(self) -> str:
        """A summary table in Jupyter (see :mod:`mechsys.results._repr`)."""
        from ._repr import solution_html

        return solution_html(self)

    def _repr_markdown_(self) -> str:
        from ._repr import solution_markdown

        return solution_markdown(self)


@dataclass(frozen=True, eq=False)
class State:
    """Coordinates (n,), velocities and accelerations at one time."""

    t: float
    q: np.ndarray
    qd: np.ndarray | None
    qdd: np.ndarray | None
    system: object
