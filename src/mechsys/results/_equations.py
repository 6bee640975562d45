r"""The equations of a model as SymPy objects (Mech 13.4, "Equations of motion").

:meth:`Model.equations <mechsys.Model.equations>` collects, for the whole model or a
selection of constraints,

* ``phi``: the constraint equations :math:`\Phi(q, t) = 0` (a column),
* ``jacobian``: :math:`\Phi_q`,
* ``phi_t``: :math:`\Phi_t`, so that velocities satisfy :math:`\Phi_q \dot q = -\Phi_t`,
* ``gamma``: the right side of the acceleration equations
  :math:`\Phi_q \ddot q = \gamma = -(\Phi_q \dot q)_q \dot q - 2 \Phi_{qt} \dot q - \Phi_{tt}`,
* ``mass_matrix``: :math:`M(q)`,
* ``loads``: the applied generalized forces :math:`Q`, and ``centrifugal`` the
  velocity-dependent inertial ones :math:`Q_v`,

so that the equations of motion read
:math:`M \ddot q + \Phi_q^T \lambda = Q + Q_v`, :math:`\Phi_q \ddot q = \gamma`
(``lam`` holds the multiplier symbols :math:`\lambda`). ``str()`` and ``pretty()`` print
them with SymPy's pretty printer, ``latex()`` and the notebook display (``_repr_latex_``)
give LaTeX. Example::

    eq = m.equations()
    print(eq.pretty("jacobian"))
    eq.mass_matrix * eq.qdd + eq.jacobian.T * eq.lam - eq.loads - eq.centrifugal
"""

from __future__ import annotations

import sympy as sp

from .._errors import ModelError, choice

#: the parts of an Equations object, in display order, with their symbols
PARTS = (
    ("phi", r"\Phi"),
    ("jacobian", r"\Phi_q"),
    ("phi_t", r"\Phi_t"),
    ("gamma", r"\gamma"),
    ("mass_matrix", "M"),
    ("loads", "Q"),
    ("centrifugal", "Q_v"),
)


class Equations:
    """SymPy matrices of one model's equations (see the module docstring): ``phi``,
    ``jacobian``, ``phi_t``, ``gamma``, ``mass_matrix``, ``loads``, ``centrifugal`` and the
    columns ``q``, ``qd``, ``qdd``, ``lam``; ``rows`` labels each equation."""

    def __init__(self, model, constraints=None):
        system = model.compile()
        lay = system.layout
        if constraints is None:
            keep = list(range(system.m))
        else:
            sel = constraints if isinstance(constraints, (list, tuple)) else [constraints]
            if not sel:
                raise ModelError("equations(constraints=[]): the selection is empty; give "
                                 "constraints by handle, name or number, or None for all")
            cs = [model.constraint(c) for c in sel]
            keep = [i for i, o in enumerate(lay.eq_owner) if any(o is c for c in cs)]
        q = list(lay.q_symbols)
        self.q = sp.Matrix(q)
        self.qd = sp.Matrix(lay.qd_symbols)
        self.qdd = sp.Matrix(lay.qdd_symbols)
        self.lam = sp.Matrix([system.lam_symbols[i] for i in keep])
        self.rows = tuple(lay.row_label(i) for i in keep)
        self.phi = sp.Matrix([system.phi[i] for i in keep]) if keep else sp.zeros(0, 1)
        J = sp.zeros(system.m, system.n)
        for i, j, e in zip(system.jac_rows, system.jac_cols, system.jac_exprs):
            J[i, j] += e
        self.jacobian = J.extract(keep, list(range(system.n))) if keep else sp.zeros(0, system.n)
        self.phi_t = sp.Matrix([system.phi_t[i] for i in keep]) if keep else sp.zeros(0, 1)
        self.gamma = sp.Matrix([system.gamma[i] for i in keep]) if keep else sp.zeros(0, 1)
        # the model's own symbolic outputs (Mech's MassMatrix, Loads[All], Centrifugal)
        from ._outputs import All

        self.mass_matrix = model.mass_matrix()
        self.loads = model.loads(All) if system.n else sp.zeros(0, 1)
        self.centrifugal = model.centrifugal() if system.n else sp.zeros(0, 1)

    def _part(self, name: str):
        choice(name, [p for p, _ in PARTS], "equations: part")
        return getattr(self, name)

    def pretty(self, part: str | None = None) -> str:
        """SymPy's pretty (Unicode) print of one part, or of all with their names."""
        if part is not None:
            return sp.pretty(self._part(part))
        return "\n\n".join(f"{name} =\n{sp.pretty(getattr(self, name))}" for name, _ in PARTS)

    def latex(self, part: str | None = None) -> str:
        """LaTeX of one part (``\\Phi_q = ...``), or of all, one equation a line."""
        names = [part] if part is not None else [p for p, _ in PARTS]
        sym = dict(PARTS)
        return "\\\\\n".join(f"{sym[nm]} = {sp.latex(self._part(nm))}" for nm in names)

    def _repr_latex_(self) -> str:
        return "$\\displaystyle\\begin{aligned}" + self.latex().replace(" = ", " &= ") \
            + "\\end{aligned}$"

    def __str__(self) -> str:
        return self.pretty()

    def __repr__(self) -> str:
        return (f"<Equations: {len(self.rows)} constraint equations, {self.q.rows} coordinates; "
                f"parts {', '.join(p for p, _ in PARTS)}>")
