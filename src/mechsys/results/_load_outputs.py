r"""Load and energy outputs, written once: symbolic on a Model, numeric on a Solution.

Sign conventions (also in ``docs/loads.md``)::

    M qdd + Phi_q^T lambda = Q + Qv
    applied  = Q_b                       (the loads, generalized on body b's coordinates)
    reaction = -(Phi_q^T lambda)_b        (what the constraints apply to body b)
    dynamic  = (Qv - M qdd)_b             (the inertial load, d'Alembert)
    applied + reaction + dynamic = 0

A generalized load on a body converts to a force at the body origin ``O`` and a moment
(2D scalar, 3D global vector); moved to a point ``P``: ``M_P = M_O + (r_O - r_P) x F``.
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError


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
        m = self._model()
        s = self._sys()
        b = m.body(body)
        if b.is_ground:
            return s, b, slice(0, 0)
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
        elif coordinates != "global":
            raise ModelError(f"coordinates must be 'global' or 'local', got {coordinates!r}")
        return F, M

    def _finish_pair(self, F, M):
        return self._finish(F), self._finish(M)

    # -- multipliers and reactions ----------------------------------------------------------
    def generalized(self, constraint):
        """The Lagrange multipliers of a constraint (Mech's ``Generalized``): symbols on a
        model, values ``(N, k)`` on a solution."""
        m = self._model()
        return self._finish(sp.Matrix(self._lams(m.constraint(constraint))))

    def reaction(self, constraint, body, at=None, coordinates: str = "global"):
        """``(force, moment)`` that ``constraint`` applies *to* ``body``, the moment about
        ``at`` (default the body origin), in global or body-local axes.

        On ground, the reaction is the opposite of that on the constraint's other body
        (the constraint must join ground to exactly one body)."""
        m = self._model()
        c = m.constraint(constraint)
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

    def _reaction_expr(self, c, b, at, coordinates):
        m = self._model()
        lam = sp.Matrix(self._lams(c))
        eqs = sp.Matrix(c.equations(m.space))
        G = -(eqs.jacobian(list(b.q)).T * lam)
        return self._wrench(b, G, at, coordinates)

    # -- load vectors -------------------------------------------------------------------------
    def loads(self, body, type: str = "applied", coordinates: str | None = None):
        """Total load on a body (Mech's ``Loads``): ``type`` ``"applied"``, ``"reaction"``
        or ``"dynamic"``. Generalized on the body's coordinates by default; with
        ``coordinates="global"|"local"`` a ``(force, moment)`` pair at the body origin."""
        s, b, rows = self._body_rows(body)
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
            raise ModelError(f"type must be 'applied', 'reaction' or 'dynamic', got {type!r}")
        if coordinates is None:
            return self._finish(G)
        F, M = self._wrench(b, G, None, coordinates)
        return self._finish_pair(F, M)

    def mass_matrix(self, body=None):
        """The mass matrix (of one body's coordinates, or all)."""
        s = self._sys()
        dyn = s.dynamics
        M = sp.zeros(s.n, s.n)
        for r, c, e in zip(dyn.M_rows, dyn.M_cols, dyn.M_exprs):
            M[r, c] += e
        if body is not None:
            _, _, rows = self._body_rows(body)
            M = M[rows, rows]
        return self._finish(M)

    def centrifugal(self, body=None):
        """Velocity-dependent inertial forces ``Qv`` (centrifugal, gyroscopic, Coriolis)."""
        s = self._sys()
        Qv = sp.Matrix(s.dynamics.Qv)
        if body is not None:
            _, _, rows = self._body_rows(body)
            Qv = Qv[rows, :]
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
        """Power a constraint delivers to the mechanism (a driver's power):
        ``-lambda_c^T (Phi_c)_q qd``."""
        m = self._model()
        c = m.constraint(constraint)
        s = self._sys()
        lam = sp.Matrix(self._lams(c))
        eqs = sp.Matrix(c.equations(m.space))
        q, qd = list(s.layout.q_symbols), sp.Matrix(s.layout.qd_symbols)
        return self._finish(-(lam.T * eqs.jacobian(q) * qd)[0, 0])
