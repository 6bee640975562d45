r"""Load and energy outputs, written once: symbolic on a Model, numeric on a Solution.

Sign conventions (also in ``docs/loads.md``):

.. math::

    M \ddot q + \Phi_q^T \lambda &= Q + Q_v \\
    \mathit{applied} &= Q_b
        \qquad \text{(the loads, generalized on the coordinates of body } b \text{)} \\
    \mathit{reaction} &= -(\Phi_q^T \lambda)_b
        \qquad \text{(what the constraints apply to body } b \text{)} \\
    \mathit{dynamic} &= (Q_v - M \ddot q)_b
        \qquad \text{(the inertial load, d'Alembert)} \\
    \mathit{applied} + \mathit{reaction} + \mathit{dynamic} &= 0

A generalized load on a body converts to a force at the body origin ``O`` and a moment
(2D scalar, 3D global vector); moved to a point ``P``: :math:`M_P = M_O + (r_O - r_P) \times F`.

Mech's selection forms (``All``, ``Rest``, lists; see :mod:`._outputs`) make the static
balance one line, :math:`\Phi_q^T \lambda = Q`::

    sol.jacobian(All, All).T @ sol.generalized(All) == sol.loads(All)

(with inverse dynamics ``== sol.loads(All) + sol.loads(All, "dynamic")``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import sympy as sp

from .._errors import ModelError, choice
from ._outputs import All, Rest, is_selection, selected_coordinates
from ._stagewise import is_staged as _staged


class LoadOutputs:
    """Mixin: subclasses provide ``_model()`` and ``_finish(expr)``."""

    # -- helpers --------------------------------------------------------------------------
    def _sys(self):
        """The compiled system these outputs refer to (a free system drops constraints)."""
        sys_ = getattr(self, "system", None)
        return sys_ if sys_ is not None else self._model().compile()

    def _lams(self, c):
        s = self._sys()
        out = [lam for lam, o in zip(s.lam_symbols, s.layout.eq_owner) if o is c]
        if not out:
            raise ModelError(f"{c.label()} is not among the constraints of this system "
                             "(was it dropped by free()?)")
        return out

    def _body_rows(self, body):
        """``(system, body or None, slice)``: the rows of a body, or of ``All``, ``Rest`` or
        one coordinate symbol (then no body)."""
        m = self._model()
        s = self._sys()
        if body is All:
            return s, None, slice(0, s.n)
        if body is Rest:
            return s, None, slice(s.n - len(m._variables), s.n)
        if isinstance(body, sp.Symbol):
            j = self._indices(body)[0]
            return s, None, slice(j, j + 1)
        b = m.body(body)
        if b.is_ground:
            return s, b, slice(0, 0)
        if b.gen_joint is not None:
            from ..constraints._generalized import slave_refused

            raise slave_refused(b, "loads")
        return s, b, s.layout.body_slices[b.name]

    def _wrench(self, b, G, at=None, coordinates="global"):
        m = self._model()
        sp_ = m.space
        F, MO = sp_.wrench_from_generalized(list(G), b.q[sp_.dim :])
        M = MO
        if at is not None:
            P = m._point(at).location()
            M = MO + sp_.moment_about(b.r - P, F)
        if coordinates == "local":
            F = b.A.T * F
            if sp_.dim == 3:
                M = b.A.T * M
        else:
            choice(coordinates, ("global", "local"), "coordinates")
        return F, M

    def _finish_pair(self, F, M):
        return self._finish(F), self._finish(M)

    def _indices(self, spec) -> list:
        """Layout indices of the coordinates of a selection (or a body)."""
        m = self._model()
        q = list(self._sys().layout.q_symbols)
        syms = selected_coordinates(m, spec) if is_selection(spec) else list(m.body(spec).q)
        try:
            return [q.index(x) for x in syms]
        except ValueError:  # pragma: no cover - the layout holds every coordinate
            raise ModelError(f"{spec!r} has coordinates outside this system") from None

    @staticmethod
    def _concat(parts):
        """Stack finished column results: SymPy columns, or arrays along the last axis."""
        if isinstance(parts[0], sp.MatrixBase):
            return sp.Matrix.vstack(*parts)
        return np.concatenate(parts, axis=-1)

    # -- multipliers and reactions ----------------------------------------------------------
    def generalized(self, constraint):
        """The Lagrange multipliers of a constraint (Mech's ``Generalized``): symbols on a
        model, values ``(N, k)`` on a solution. ``All`` gives every multiplier of the system
        (Euler normalisations included, in equation order: the rows of
        ``jacobian(All, ...)``); a list of constraints their multipliers concatenated."""
        m = self._model()
        if constraint is All:
            return self._finish(sp.Matrix(self._sys().lam_symbols))
        if isinstance(constraint, list):
            return self._finish(sp.Matrix([lam for c in constraint
                                           for lam in self._lams(m.constraint(c))]))
        return self._finish(sp.Matrix(self._lams(m.constraint(constraint))))

    def reaction(self, constraint, body, at=None, coordinates: str = "global"):
        r"""``(force, moment)`` that ``constraint`` applies *to* ``body``, the moment about
        ``at`` (default the body origin), in global or body-local axes.

        Mech's forms (``Reaction[cnum, bnum]``, ``Reaction[cnum, bnum, point]``,
        ``Reaction[cnum, Point[bnum, lpnt]]``, ``Reaction[cnum, sym]``):

        * ``body`` may be a point of a body, ``body.point("pin")``: the reaction on that
          body with the moment about that point;
        * ``constraint`` may be ``All`` (every constraint of the system: the total reaction
          on the body, ``loads(body, "reaction")`` as a force and moment) or a list of
          constraints (their reactions summed);
        * ``body`` may be a coordinate symbol (a generalized coordinate, Mech 11.2) or a
          **parameter** symbol: the generalized load the constraints apply to it,
          :math:`-\sum_c (\partial \Phi_c / \partial p)^T \lambda_c` (for a parameter that is a link's
          length, the
          link's tension, positive when the link pulls; Mech: ``Reaction[All, len]``), a scalar.

        On ground, the reaction is the opposite of that on the constraint's other body
        (the constraint must join ground to exactly one body)."""
        if _staged(self):  # a multistage solution: each point with its stage's rows
            from ._stagewise import stagewise

            return stagewise(self, lambda s: s.reaction(constraint, body, at, coordinates))
        m = self._model()
        from ..geometry._points import Point

        if isinstance(body, Point):
            if at is not None:
                raise ModelError(f"reaction({constraint!r}, {body!r}, at={at!r}): a point already "
                                 "names where the moment is taken; give the body and at=, or "
                                 "the point alone")
            if body.body is None:
                raise ModelError(f"reaction: {body!r} is not a point of a moving body; give a "
                                 "point of the body the reaction acts on")
            body, at = body.body, body
        if isinstance(body, sp.Symbol) and body in m._params:
            return self._finish(self._parameter_reaction(constraint, body))
        if constraint is All or isinstance(constraint, (list, tuple)):
            return self._reaction_sum(constraint, body, at, coordinates)
        c = m.constraint(constraint)
        viewed = getattr(c, "_view", None)
        if viewed is not None and c.velocity_members(viewed):
            # a switch whose stage (evaluated by stagewise) holds velocity constraints
            # (decision 0063): their -A^T mu (zero where the stage is dropped) plus the
            # reaction of the stage's position rows
            F, M = self._velocity_reaction(c, body, at, coordinates)
            if any(o is c for o in self._sys().layout.eq_owner):
                F2, M2 = self._position_reaction(c, body, at, coordinates)
                F, M = F + np.asarray(F2), M + np.asarray(M2)
            return F, M
        if self._velocity_columns(c) is not None:
            return self._velocity_reaction(c, body, at, coordinates)
        return self._position_reaction(c, body, at, coordinates)

    def _position_reaction(self, c, body, at, coordinates):
        """The reaction of constraint ``c``'s position rows (its multipliers ``lambda``) on
        ``body`` (:meth:`reaction`)."""
        m = self._model()
        if getattr(c, "slave", None) is not None or isinstance(body, sp.Symbol):
            from ..constraints._generalized import generalized_reaction

            return self._finish(generalized_reaction(m, c, body, self._lams))
        b = m.body(body)
        if b.is_ground:
            others = [x for x in c.bodies() if not x.is_ground]
            if len(others) != 1:
                raise ModelError(f"reaction on ground from {c.label()}: it joins "
                                 f"{len(others)} moving bodies; ask for each body's reaction")
            ref = at if at is not None else (0,) * m.space.dim
            F, M = self._reaction_expr(c, others[0], ref, "global")
            return self._finish_pair(-F, -M)
        F, M = self._reaction_expr(c, b, at, coordinates)
        return self._finish_pair(F, M)

    def _velocity_columns(self, c):
        """The columns of ``extra["mu"]`` that hold the multipliers of the velocity constraint
        ``c`` on a free-motion solution with velocity constraints (decision 0053), else None;
        of a switch evaluated stage by stage, those of the velocity constraints of the
        stage in view (``"edge.stage2[0]"``, decision 0063)."""
        extra = getattr(self, "extra", None)
        names = extra.get("velocity_multipliers") if isinstance(extra, dict) else None
        if not names:
            return None
        name = c.name
        if getattr(c, "_view", None) is not None:
            name = f"{c.name}.stage{c._view + 1}"
        cols = [i for i, x in enumerate(names) if x.rsplit("[", 1)[0] == name]
        return cols or None

    def _velocity_reaction(self, c, body, at, coordinates):
        r"""``(force, moment)`` a velocity constraint applies to ``body`` over a free-motion
        solution: its generalized force :math:`-A_b^T \mu` (``A_b`` the rows' columns of the
        body's rates, :math:`\mu` its multipliers) as a force and moment (about ``at``, default
        the body origin). On ground: the opposite of that on the constraint's one moving
        body, the moment about ``at`` (default the origin)."""
        m = self._model()
        if not isinstance(body, (str, int)) and isinstance(body, sp.Symbol):
            raise ModelError(f"reaction({c.name!r}, {body!r}): the reaction of a velocity "
                             "constraint on a coordinate is -A^T mu; give a body")
        b = m.body(body)
        sign = 1.0
        if b.is_ground:
            others = [x for x in c.bodies() if not x.is_ground]
            if len(others) != 1:
                raise ModelError(f"reaction on ground from {c.label()}: it joins "
                                 f"{len(others)} moving bodies; ask for each body's reaction")
            b, sign = m.body(others[0]), -1.0
            at = at if at is not None else (0,) * m.space.dim
        if b.gen_joint is not None:
            from ..constraints._generalized import slave_refused

            raise slave_refused(b, "reaction")
        rates = m.velocity_symbols()
        viewed = getattr(c, "_view", None)
        members = [c] if viewed is None else c.velocity_members(viewed)
        psi = sp.Matrix([e for x in members for e in x.equations(m.space)])
        Ab = psi.jacobian([rates[x] for x in b.q])
        mu = np.asarray(self.extra["mu"], dtype=float)
        mu = mu.reshape(-1, mu.shape[-1])
        cols = self._velocity_columns(c)
        # (a dropped stage's velocity constraints have no columns: no force)
        mu = mu[:, cols] if cols is not None else np.zeros((len(mu), psi.shape[0]))
        F = M = 0.0
        for i in range(Ab.shape[0]):
            # the wrench is linear in the generalized force: one per row, weighted by -mu_i
            Fi, Mi = self._wrench(b, Ab[i, :].T, at, coordinates)
            Fi, Mi = self._finish_pair(Fi, Mi)
            shape_F, shape_M = np.shape(Fi), np.shape(Mi)
            w = -sign * mu[:, i:i + 1]
            F = F + w * np.asarray(Fi, dtype=float).reshape(len(mu), -1)
            M = M + w * np.asarray(Mi, dtype=float).reshape(len(mu), -1)
        return F.reshape(shape_F), M.reshape(shape_M)

    def _reaction_constraints(self, constraint) -> list:
        """The constraints of ``All`` (those with multipliers in this system) or a list."""
        m = self._model()
        if constraint is All:
            owners = self._sys().layout.eq_owner
            out = []
            for o in owners:
                if not isinstance(o, str) and all(o is not x for x in out):
                    out.append(o)
            return out
        if not constraint:
            raise ModelError("reaction([] , ...): the list of constraints is empty")
        return [m.constraint(c) for c in constraint]

    def _reaction_sum(self, constraint, body, at, coordinates):
        """Reaction of several constraints (``All`` or a list) on one body or coordinate."""
        m = self._model()
        cs = self._reaction_constraints(constraint)
        if isinstance(body, sp.Symbol):
            from ..constraints._generalized import generalized_reaction

            return self._finish(sp.Add(*(generalized_reaction(m, c, body, self._lams)
                                         for c in cs)))
        b = m.body(body)
        if b.is_ground:
            raise ModelError(f"reaction({constraint!r}, ground): ask for the reaction of each "
                             "constraint on ground, or on the moving bodies")
        if b.gen_joint is not None:
            from ..constraints._generalized import slave_refused

            raise slave_refused(b, "reaction")
        G = sp.zeros(len(b.q), 1)
        for c in cs:
            lam = sp.Matrix(self._lams(c))
            eqs = sp.Matrix(c.equations(m.space))
            G -= eqs.jacobian(list(b.q)).T * lam
        F, M = self._wrench(b, G, at, coordinates)
        return self._finish_pair(F, M)

    def _parameter_reaction(self, constraint, p):
        r""":math:`-\sum_c (\partial \Phi_c / \partial p)^T \lambda_c` over ``All`` or the given
        constraints."""
        m = self._model()
        cs = (self._reaction_constraints(constraint) if constraint is All
              or isinstance(constraint, (list, tuple)) else [m.constraint(constraint)])
        out = sp.S.Zero
        for c in cs:
            eqs = c.equations(m.space)
            out -= sp.Add(*(e.diff(p) * la for e, la in zip(eqs, self._lams(c))))
        return out

    def joint_reaction(self, joint, at=None, coordinates: str = "global"):
        """``(force, moment)`` the master applies to the slave through a generalized-coordinate
        joint (``GenRevolute2`` ...), the moment about ``at`` (default the slave's origin),
        found by Newton-Euler on the bodies the joint carries (Mech 11.2 offers none: a Gen
        joint is not a constraint). Includes any load on the joint's own coordinates (an
        actuator torque); needs accelerations (a dynamic or free-motion solution) when the
        carried bodies have mass."""
        from ..constraints._generalized import GenJoint
        from ._generalized import joint_generalized_load

        m = self._model()
        c = m.constraint(joint)
        if not isinstance(c, GenJoint):
            raise ModelError(f"joint_reaction: {c.label()} is not a generalized-coordinate joint; "
                             "use reaction(constraint, body)")
        G = joint_generalized_load(m, c, self._lams)
        F, M = self._wrench(c.slave, G, at, coordinates)
        return self._finish_pair(F, M)

    def _reaction_expr(self, c, b, at, coordinates):
        m = self._model()
        if b.gen_joint is not None:
            from ..constraints._generalized import slave_refused

            raise slave_refused(b, "reaction")
        lam = sp.Matrix(self._lams(c))
        eqs = sp.Matrix(c.equations(m.space))
        G = -(eqs.jacobian(list(b.q)).T * lam)
        return self._wrench(b, G, at, coordinates)

    # -- load vectors -------------------------------------------------------------------------
    def loads(self, body, type: str = "applied", coordinates: str | None = None):
        """Total load on a body (Mech's ``Loads``): ``type`` ``"applied"``, ``"reaction"``
        or ``"dynamic"``. Generalized on the body's coordinates by default; with
        ``coordinates="global"|"local"`` a ``(force, moment)`` pair at the body origin.

        Mech's other forms (generalized only): ``All`` the whole load vector, ``Rest`` the
        model variables' part, a coordinate symbol its element, a list of bodies and
        symbols the parts concatenated."""
        if type == "reaction" and _staged(self):  # each point with its stage's rows
            from ._stagewise import stagewise

            return stagewise(self, lambda s: s.loads(body, type, coordinates))
        if is_selection(body) and coordinates is not None:
            raise ModelError(f"loads({body!r}, coordinates={coordinates!r}): a force and moment "
                             "belong to one body; give a single body, or coordinates=None")
        if isinstance(body, list):
            if not body:
                raise ModelError("loads([]): the list of bodies and coordinates is empty")
            return self._concat([self.loads(x, type) for x in body])
        s, b, rows = self._body_rows(body)
        if rows.start == rows.stop and b is None:  # Rest without model variables
            return self._finish(sp.zeros(0, 1))
        dyn = s.dynamics
        lay = s.layout
        if type == "applied":
            G = sp.Matrix(dyn.Q[rows])
        elif type == "reaction":
            # -(Phi_q^T lambda) on the body's columns, from the system's Jacobian entries
            G = sp.zeros(rows.stop - rows.start, 1)
            lam = s.lam_symbols
            for i, j, e in zip(s.jac_rows, s.jac_cols, s.jac_exprs):
                if rows.start <= j < rows.stop:
                    G[j - rows.start] -= e * lam[i]
        elif type == "dynamic":
            G = sp.Matrix(dyn.Qv[rows])
            qdd = lay.qdd_symbols
            for r, cidx, e in zip(dyn.M_rows, dyn.M_cols, dyn.M_exprs):
                if rows.start <= r < rows.stop:
                    G[r - rows.start] -= e * qdd[cidx]
        else:
            choice(type, ("applied", "reaction", "dynamic"), "loads: type")
        if coordinates is None:
            return self._finish(G)
        F, M = self._wrench(b, G, None, coordinates)
        return self._finish_pair(F, M)

    def mass_matrix(self, body=None):
        """The mass matrix (of one body's coordinates, or all; or of a selection: ``All``,
        ``Rest``, a list of bodies and coordinate symbols)."""
        s = self._sys()
        dyn = s.dynamics
        M = sp.zeros(s.n, s.n)
        for r, c, e in zip(dyn.M_rows, dyn.M_cols, dyn.M_exprs):
            M[r, c] += e
        if body is not None:
            idx = self._indices(body)
            M = M.extract(idx, idx)
        return self._finish(M)

    def centrifugal(self, body=None):
        """Velocity-dependent inertial forces ``Qv`` (centrifugal, gyroscopic, Coriolis), of
        all coordinates, one body or a selection."""
        s = self._sys()
        Qv = sp.Matrix(s.dynamics.Qv)
        if body is not None:
            Qv = Qv.extract(self._indices(body), [0])
        return self._finish(Qv)

    # -- energies and power ---------------------------------------------------------------------
    def body_energy(self, body=None):
        """Kinetic energy of a body (all bodies when omitted)."""
        m = self._model()
        kin = self._sys().dynamics.kinetic
        if body is None:
            return self._finish(sum(kin.values(), sp.S.Zero))
        return self._finish(kin.get(m.body(body).name, sp.S.Zero))

    def potential_energy(self):
        """Potential energy of the conservative loads (gravity, linear springs)."""
        pot = self._sys().dynamics.potential
        return self._finish(pot if pot is not None else sp.S.Zero)

    def power(self, constraint):
        r"""Power a constraint delivers to the mechanism (a driver's power):
        :math:`-\lambda_c^T (\Phi_c)_q \dot q`; of a velocity constraint
        :math:`A \dot q + b = 0` in free motion, :math:`-\mu^T A \dot q` (zero for ideal
        rolling or a knife edge, where ``b = 0``)."""
        if _staged(self):  # a multistage solution: each point with its stage's rows
            from ._stagewise import stagewise

            return stagewise(self, lambda s: s.power(constraint))
        m = self._model()
        c = m.constraint(constraint)
        viewed = getattr(c, "_view", None)
        if (viewed is not None and c.velocity_members(viewed)) or \
                self._velocity_columns(c) is not None:
            # velocity constraints (decisions 0053, 0063): -mu^T A qd, plus a switch's
            # position rows in the stage in view
            P = self._velocity_power(c)
            if viewed is not None and any(o is c for o in self._sys().layout.eq_owner):
                P = P + np.asarray(self._position_power(c), dtype=float)
            return P
        return self._position_power(c)

    def _position_power(self, c):
        r""":math:`-\lambda_c^T (\Phi_c)_q \dot q` of constraint ``c``'s position rows."""
        m = self._model()
        s = self._sys()
        lam = sp.Matrix(self._lams(c))
        eqs = sp.Matrix(c.equations(m.space))
        q, qd = list(s.layout.q_symbols), sp.Matrix(s.layout.qd_symbols)
        return self._finish(-(lam.T * eqs.jacobian(q) * qd)[0, 0])

    def _velocity_power(self, c):
        r"""Power of a velocity constraint's force :math:`-A^T \mu` over a free-motion
        solution: :math:`-\mu^T A \dot q` (the rows' part linear in the rates,
        :math:`A \dot q = \psi - \psi|_{\dot q = 0}`); along the motion
        :math:`A \dot q = -b`, so an ideal rolling or knife edge (``b = 0``) delivers none."""
        m = self._model()
        rates = list(m.velocity_symbols().values())
        viewed = getattr(c, "_view", None)
        members = [c] if viewed is None else c.velocity_members(viewed)
        psi = [e for x in members for e in x.equations(m.space)]
        zero = dict.fromkeys(rates, 0)
        mu = np.asarray(self.extra["mu"], dtype=float)
        mu = mu.reshape(-1, mu.shape[-1])
        cols = self._velocity_columns(c)
        if cols is None:                     # a stage that drops them: no force, no power
            return np.zeros(len(mu)) if mu.shape[0] > 1 else 0.0
        P = np.zeros(len(mu))
        for i, e in enumerate(psi):
            rate_part = sp.expand(e - e.subs(zero))
            v = np.asarray(self._finish(rate_part), dtype=float).reshape(-1)
            P -= mu[:, cols[i]] * v
        return P if P.size > 1 else float(P[0])


def lambda_guess_vector(system, model, spec) -> np.ndarray:
    """Starting multipliers ``(m,)`` from any of Mech's ``LambdaGuess`` forms.

    ``None`` -> all ones (Mech's default); a number -> that value for all; a sequence of
    ``m`` numbers -> all values (order of ``generalized(All)``); a mapping -> the given
    entries, the others one: keys are multiplier symbols (``{lam2_1: 5.0}``) or constraints
    (handle, name or number) with a number (for all their multipliers) or one value each
    (``{"drive": -40.0}``). A partial dictionary is Mech's ``LambdaGuess -> {rules}``.
    """
    m = system.m
    if spec is None:
        return np.ones(m)
    if isinstance(spec, Mapping):
        lam = np.ones(m)
        syms = list(system.lam_symbols)
        for key, val in spec.items():
            if isinstance(key, sp.Symbol):
                if key not in syms:
                    raise ModelError(f"lambda_guess: {key} is not a multiplier of this system; "
                                     f"they are {[str(x) for x in syms]}")
                rows = [syms.index(key)]
            else:
                c = model.constraint(key)
                rows = [i for i, o in enumerate(system.layout.eq_owner) if o is c]
                if not rows:
                    raise ModelError(f"lambda_guess: {c.label()} is not among the constraints "
                                     "of this system (was it dropped by free()?)")
            vals = np.asarray(val, dtype=float).ravel()
            if vals.size not in (1, len(rows)) or not np.all(np.isfinite(vals)):
                raise ModelError(f"lambda_guess[{key!r}]: give one finite number or "
                                 f"{len(rows)} (one per multiplier), got {val!r}")
            lam[rows] = vals
        return lam
    try:
        vals = np.asarray(spec, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"lambda_guess must be a number, {m} numbers or a mapping "
                         f"{{multiplier or constraint: value}}, got {spec!r}") from None
    if vals.ndim == 0:
        vals = np.full(m, float(vals))
    if vals.shape != (m,) or not np.all(np.isfinite(vals)):
        raise ModelError(f"lambda_guess must be a number or {m} finite numbers (one per "
                         f"multiplier, as generalized(All)), got shape {vals.shape}")
    return vals.copy()
