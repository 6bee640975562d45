r"""Generalized-coordinate joints (Mech ch. 11): ``GenRevolute2``, ``GenTranslate2`` (2D),
``GenRevolute5``, ``GenTranslate5``, ``GenCylindrical4``, ``GenOrthoRevolute4`` (3D) and
``GenConstraint`` (both).

A Gen joint is not a constraint: it writes no equation. It makes its *slave* body's pose an
explicit function of its *master*'s pose and of new generalized coordinates (added to the
model as variables with their guesses), so it *adds* as many degrees of freedom as it has
coordinates. With the joint frames :math:`(o_1, R_1)` of the slave's axis and
:math:`(o_2, R_2)` of the master's (origin and rotation, local) and the joint's relative
motion :math:`(t_j(g), R_j(g))` (in the master's joint frame):

.. math::

    A_s &= A_m R_2 R_j R_1^T
    \qquad \text{(3D: } e_s = e_m * q_2 * q_j * q_1^{-1} \text{)} \\
    r_s &= r_m + A_m (o_2 + R_2 t_j) - A_s o_1
    \qquad \text{(2D: } \theta_s = \theta_m + a_2 + \phi_j - a_1 \text{)}

(:math:`*` the quaternion product, :math:`a_1, a_2` the joint frames' angles in 2D)

so the joint's axes meet as the standard joint would hold them. The model substitutes these
expressions for the slave's coordinate symbols (chains: masters first) in every equation,
output and load, and projects the slave's inertia on the coordinates it depends on
(``compile/_dynamics.py``): see ``docs/decisions/0010-generalized-coordinates.md``.
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from .._errors import GeometryError, ModelError
from .._symbols import T, acceleration_symbol, velocity_symbol
from ..geometry._points import Axis, GlobalVector, as_axis, as_point
from ..geometry._rotations import _from_matrix, quaternion_inverse, quaternion_product
from ..geometry._rotations import _parse as _rotation_spec
from ._base import ConstraintBase, Variable

_ONE_Q = (sp.S.One, sp.S.Zero, sp.S.Zero, sp.S.Zero)


def _variable(spec, who: str) -> Variable:
    """A ``(sym, guess)`` pair (or a bare symbol/name, guess 0) as a :class:`Variable`."""
    if isinstance(spec, Variable):
        return spec
    if isinstance(spec, (tuple, list)) and len(spec) == 2:
        return Variable(spec[0], spec[1])
    if isinstance(spec, (str, sp.Symbol)):
        return Variable(spec, 0.0)
    raise ModelError(f"{who}: a generalized coordinate is (symbol, guess), got {spec!r}")


class GenJoint(ConstraintBase):
    """Base of the generalized-coordinate joints: a slave body, its master, new coordinates.

    Subclasses give ``_frames(space)`` -> ``(o_1, R_1, o_2, R_2)`` (local origins on the
    slave and the master and the joint frames' rotations: an angle in 2D, Euler parameters
    in 3D) and ``_relative(space)`` -> ``(t_j, R_j)``.
    """

    dof_removed = None  # negative: -len(coordinates), see count_removed
    _axes = True  # the arguments are axes (GenConstraint: points)

    def __init__(self, slave_geometry, master_geometry, coordinates):
        super().__init__()
        if self._axes:
            slave_geometry, master_geometry = as_axis(slave_geometry), as_axis(master_geometry)
        self._g1, self._g2 = slave_geometry, master_geometry
        who = type(self).__name__
        self._vars = [_variable(c, who) for c in coordinates]
        names = [v.symbol.name for v in self._vars]
        if len(set(names)) != len(names):
            raise ModelError(f"{who}: the generalized coordinates {names} repeat a name; give "
                             "each its own symbol")
        self.slave = self._one_body(self._g1, "slave (first)")
        self.master = self._one_body(self._g2, "master (second)")
        if self.slave is None or getattr(self.slave, "is_ground", False):
            raise ModelError(f"{who}: the slave (first argument) must be on a moving body, not "
                             "ground: ground cannot be represented by generalized coordinates")
        if self.master is self.slave:
            raise ModelError(f"{who}: body {self.slave.name!r} cannot be a slave of itself; the "
                             "master (second argument) must be another body")

    def _one_body(self, g, what: str):
        """The single body a joint argument is defined on (Mech: each axis entirely on one
        body); ``None`` for ground."""
        bodies = {b for b in g.bodies() if not getattr(b, "is_ground", False)}
        if isinstance(g, Axis):
            if g.dir.points is not None or isinstance(g.dir, GlobalVector) or (
                    g.reference is not None and (g.reference.points is not None
                                                 or g.reference.body is not g.dir.body)):
                raise GeometryError(f"{type(self).__name__}: the {what} axis must be defined "
                                    "entirely on one body (origin, direction and reference)")
        if len(bodies) > 1:
            raise GeometryError(f"{type(self).__name__}: the {what} argument spans bodies "
                                f"{sorted(b.name for b in bodies)}; a Gen joint needs each "
                                "argument on a single body")
        return next(iter(bodies)) if bodies else None

    # -- constraint contract ---------------------------------------------------------------
    def geometry(self):
        return [self._g1, self._g2]

    def sides(self):
        return None

    def new_variables(self) -> list[Variable]:
        return list(self._vars)

    @property
    def coordinates(self) -> list[sp.Symbol]:
        """The generalized coordinate symbols this joint adds."""
        return [v.symbol for v in self._vars]

    def equations(self, space) -> list:
        """None: a Gen joint writes no equation (its frames are checked here, once)."""
        key = space.name
        if key not in self._cache:
            if space.name not in self.spaces:
                raise ModelError(f"{self.label()} is for {' and '.join(self.spaces)} models, "
                                 f"not {space.name} ones")
            for g in self.geometry():
                g.check_dim(space.dim)
            self._frames(space)
            self._cache[key] = []
        return self._cache[key]

    def count_removed(self, space) -> int:
        return -len(self._vars)

    # -- the slave's pose ----------------------------------------------------------------
    def pose(self, space, conv=None) -> tuple[sp.Matrix, list]:
        """``(r_s, rot_s)``: the slave's position and rotation coordinates (angle, or Euler
        parameters) as expressions of the master's coordinate symbols and the joint's.
        ``conv`` (3D; ``symengine.sympify``): the same products in that algebra, returned as
        two lists of its expressions (SymPy's evaluation of the quaternion and matrix
        products is most of a robot arm's first dynamics; decision 0057)."""
        o1, R1, o2, R2 = self._frames(space)
        tj, Rj = self._relative(space)
        m = self.master
        ground = m is None or m.is_ground
        if conv is not None and space.dim == 3:
            return self._pose_in(conv, o1, R1, o2, R2, tj, Rj, None if ground else m)
        if space.dim == 2 and hasattr(space, "continuous_angle"):
            # planar Euler parameters (orientation="euler"): the master's (ei, ej) turned by
            # the joint's angle; the Gen coordinate itself counts the turns
            ei, ej = (sp.S.One, sp.S.Zero) if ground else (m.q[2], m.q[3])
            psi = R2 + Rj - R1
            c, s_ = sp.cos(psi), sp.sin(psi)
            rot_s = [ei * c - ej * s_, ei * s_ + ej * c]
        elif space.dim == 2:
            rot_m = sp.S.Zero if ground else m.q[2]
            rot_s = [rot_m + R2 + Rj - R1]
        else:
            e_m = list(_ONE_Q) if ground else list(m.q[3:])
            rot_s = quaternion_product(quaternion_product(quaternion_product(e_m, list(R2)),
                                                          list(Rj)), quaternion_inverse(list(R1)))
        A_m = sp.eye(space.dim) if ground else m.A
        r_m = sp.zeros(space.dim, 1) if ground else m.r
        A_s = space.rotation_matrix(rot_s)
        if space.dim == 2:
            R2m = sp.Matrix([[sp.cos(R2), -sp.sin(R2)], [sp.sin(R2), sp.cos(R2)]])
        else:
            R2m = space.rotation_matrix(R2)
        r_s = r_m + A_m * (o2 + R2m * tj) - A_s * o1
        return r_s, [sp.sympify(e) for e in rot_s]

    @staticmethod
    def _pose_in(conv, o1, R1, o2, R2, tj, Rj, m):
        """:meth:`pose` in 3D in the algebra of ``conv``: the same formulas term for term."""
        from ..geometry._rotations import matrix_elements

        def vec(v):
            return [conv(c) for c in v]

        e_m = vec(_ONE_Q if m is None else m.q[3:])
        rot_s = quaternion_product(quaternion_product(quaternion_product(e_m, vec(R2)), vec(Rj)),
                                   quaternion_inverse(vec(R1)))
        A_s = matrix_elements(rot_s)
        R2m = matrix_elements(vec(R2))
        o1, o2, tj = vec(o1), vec(o2), vec(tj)
        w = [o2[i] + sum((R2m[i][k] * tj[k] for k in range(3)), conv(0)) for i in range(3)]
        if m is None:
            r_s = [w[i] - sum((A_s[i][k] * o1[k] for k in range(3)), conv(0)) for i in range(3)]
        else:
            A_m = [[conv(m.A[i, k]) for k in range(3)] for i in range(3)]
            r_m = vec(m.r)
            r_s = [r_m[i] + sum((A_m[i][k] * w[k] for k in range(3)), conv(0))
                   - sum((A_s[i][k] * o1[k] for k in range(3)), conv(0)) for i in range(3)]
        return r_s, rot_s

    def _relative(self, space):  # pragma: no cover - interface
        raise NotImplementedError

    def _frames(self, space):
        """Joint frames of the two axes: 2D the local direction angle, 3D the Euler
        parameters of ``[g, u x g, u]`` (reference, normal, unit direction), local; made once
        per space (the check at ``add``, each pose and the exporters ask for them)."""
        key = ("frames", space.name)
        got = self._cache.get(key)
        if got is None:
            got = self._cache[key] = self._make_frames(space)
        return got

    def _make_frames(self, space):
        out = []
        for ax in (self._g1, self._g2):
            o = ax.origin.local
            if space.dim == 2:
                d = ax.dir.local
                out += [o, sp.atan2(d[1], d[0])]
                continue
            u = ax.dir.local
            g = ax.reference_vector().local
            try:
                un = np.array([float(c) for c in u])
                gn = np.array([float(c) for c in g])
            except TypeError:
                raise GeometryError(f"{type(self).__name__}: 3D Gen joints need numeric local axis "
                                    f"directions and references, got {tuple(u)}") from None
            un = un / np.linalg.norm(un)
            gn = gn / np.linalg.norm(gn)
            R = np.column_stack([gn, np.cross(un, gn), un])
            out += [o, tuple(_exact(c) for c in _from_matrix(R))]
        return tuple(out)


_EXACT: list = []          # (float, exact value) of 0, +-1/2, +-1, +-sqrt(2)/2, made once


def _exact(c: float) -> sp.Expr:
    """A numeric frame parameter, exact when it is 0, +-1/2, +-1 or +-sqrt(2)/2 (the common
    frames), so expressions stay free of stray floats."""
    if not _EXACT:
        _EXACT.extend((sgn * float(v), sgn * v) for v in (sp.S.Zero, sp.S.Half, sp.S.One,
                                                          sp.sqrt(2) / 2) for sgn in (1, -1))
    for f, v in _EXACT:
        if abs(c - f) < 1e-14:
            return v
    return sp.Float(c)


def _rot_z(space, angle):
    """The joint rotation about the frame's z axis (2D: the angle itself)."""
    if space.dim == 2:
        return angle
    return (sp.cos(angle / 2), sp.S.Zero, sp.S.Zero, sp.sin(angle / 2))


def _no_rot(space):
    return sp.S.Zero if space.dim == 2 else _ONE_Q


def _along(space, s):
    """Translation ``s`` along the joint frame's axis (2D: x = the axis direction, 3D: z)."""
    return sp.Matrix([s, 0]) if space.dim == 2 else sp.Matrix([0, 0, s])


class GenRevolute2(GenJoint):
    r"""``GenRevolute2(axis1, axis2, (sym, guess))`` (2D): the body of ``axis1`` is a slave
    of that of ``axis2``, hinged at their origins; ``sym`` is the counterclockwise angle from
    ``axis2`` to ``axis1``. Adds one DOF (Revolute2 removes two):

    .. math::

        \theta_s = \theta_m + a_2 + \mathit{sym} - a_1, \qquad r_s = r_m + A_m o_2 - A_s o_1

    Example::

        arm = m.add_body("arm", points={"pin": (0, 0), "tip": (1, 0)})
        m.add(GenRevolute2(arm.axis("pin"), m.ground.axis((0, 0)), ("phi", 0.3)))
    """

    mech_name = "GenRevolute2"
    spaces = ("planar",)

    def __init__(self, axis1, axis2, coordinate):
        super().__init__(axis1, axis2, [coordinate])

    def _relative(self, space):
        return sp.zeros(2, 1), self.coordinates[0]


class GenTranslate2(GenJoint):
    r"""``GenTranslate2(axis1, axis2, (sym, guess))`` (2D): the slave (body of ``axis1``)
    slides along ``axis2``: the axes are colinear and parallel, ``sym`` is the distance from
    the origin of ``axis2`` to that of ``axis1`` along ``axis2``'s unit direction. Adds one
    DOF:

    .. math::

        \theta_s = \theta_m + a_2 - a_1, \qquad
        r_s = r_m + A_m (o_2 + \mathit{sym}\, u_2') - A_s o_1
    """

    mech_name = "GenTranslate2"
    spaces = ("planar",)

    def __init__(self, axis1, axis2, coordinate):
        super().__init__(axis1, axis2, [coordinate])

    def _relative(self, space):
        return _along(space, self.coordinates[0]), _no_rot(space)


class GenRevolute5(GenJoint):
    r"""``GenRevolute5(axis1, axis2, (sym, guess))`` (3D): hinge; the axes are parallel,
    their origins coincide, and ``sym`` is the right-handed angle about ``axis2`` from its
    reference direction to that of ``axis1``. Adds one DOF (Revolute5 removes five):

    .. math::

        e_s = e_m * q_2 * \left(\cos\tfrac{\mathit{sym}}{2}, 0, 0,
        \sin\tfrac{\mathit{sym}}{2}\right) * q_1^{-1}
    """

    mech_name = "GenRevolute5"
    spaces = ("spatial",)

    def __init__(self, axis1, axis2, coordinate):
        super().__init__(axis1, axis2, [coordinate])

    def _relative(self, space):
        return sp.zeros(3, 1), _rot_z(space, self.coordinates[0])


class GenTranslate5(GenJoint):
    r"""``GenTranslate5(axis1, axis2, (sym, guess))`` (3D): prismatic; the axes are colinear,
    their reference directions parallel, and ``sym`` is the distance from the origin of
    ``axis2`` to that of ``axis1`` along ``axis2``. Adds one DOF."""

    mech_name = "GenTranslate5"
    spaces = ("spatial",)

    def __init__(self, axis1, axis2, coordinate):
        super().__init__(axis1, axis2, [coordinate])

    def _relative(self, space):
        return _along(space, self.coordinates[0]), _no_rot(space)


class GenCylindrical4(GenJoint):
    r"""``GenCylindrical4(axis1, axis2, (alpha, guess), (beta, guess))`` (3D): the axes are
    colinear; ``alpha`` is the distance from the origin of ``axis2`` to that of ``axis1``
    along ``axis2``, ``beta`` the right-handed angle between their reference directions.
    Adds two DOF."""

    mech_name = "GenCylindrical4"
    spaces = ("spatial",)

    def __init__(self, axis1, axis2, alpha, beta):
        super().__init__(axis1, axis2, [alpha, beta])

    def _relative(self, space):
        a, b = self.coordinates
        return _along(space, a), _rot_z(space, b)


class GenOrthoRevolute4(GenJoint):
    r"""``GenOrthoRevolute4(axis1, axis2, (alpha, guess), (beta, guess))`` (3D): a universal
    joint; the origins coincide and the axes are orthogonal. ``alpha`` is the angle, about
    ``axis2``, from its reference direction to ``axis1``; ``beta`` the angle, about
    ``axis1``, from its reference direction to ``axis2``. In ``axis2``'s frame:

    .. math::

        R_j = R_z(\alpha)\, R_y(\pi/2)\, R_z(\pi - \beta)

    (then :math:`u_1 = \cos\alpha\, g_2 + \sin\alpha\, (u_2 \times g_2)` and
    :math:`u_2 = \cos\beta\, g_1 + \sin\beta\, (u_1 \times g_1)`). Adds two DOF."""

    mech_name = "GenOrthoRevolute4"
    spaces = ("spatial",)

    def __init__(self, axis1, axis2, alpha, beta):
        super().__init__(axis1, axis2, [alpha, beta])

    def _relative(self, space):
        a, b = self.coordinates
        h = sp.sqrt(2) / 2
        q = quaternion_product(list(_rot_z(space, a)), [h, sp.S.Zero, h, sp.S.Zero])
        return sp.zeros(3, 1), tuple(quaternion_product(q, list(_rot_z(space, sp.pi - b))))


class GenConstraint(GenJoint):
    r"""``GenConstraint(point1, point2, rot, (sym1, guess1), ...)`` (2D/3D): a user-defined
    generalized-coordinate relation. ``point1`` (on the slave) coincides with ``point2`` (on
    the master; its local coordinates may use the new symbols) and the slave's orientation
    relative to the master is ``rot``: an angle or degenerate Euler parameters ``(ei, ej)``
    in 2D, any rotation form of ``RotationLock3`` in 3D (``(angle, axis)``, a sequence of
    them, ...), also in the new symbols. Adds one DOF per symbol:

    .. math::

        A_s = A_m R(\mathit{rot}), \qquad r_s = r_m + A_m p_2' - A_s p_1'

    Example (a slider-pendulum on one body: slide ``s`` along master x, turn ``phi``)::

        m.add(GenConstraint(bob.point(0), cart.point(("s", 0)), "phi", ("s", 0), ("phi", 0.1)))
    """

    mech_name = "GenConstraint"
    _axes = False

    def __init__(self, point1, point2, rot, *coordinates):
        if not coordinates:
            raise ModelError("GenConstraint: give at least one generalized coordinate "
                             "(sym, guess); it adds one DOF per coordinate")
        self._rot = rot
        super().__init__(as_point(point1), as_point(point2), coordinates)
        self._rot = _symbolize(rot, self.coordinates)

    def _frames(self, space):
        o1, o2 = self._g1.local, _symbolize(self._g2.local, self.coordinates)
        if space.dim == 2:
            rot = self._rot
            if isinstance(rot, (tuple, list)):
                if len(rot) != 2:
                    raise ModelError(f"GenConstraint: a 2D rotation is an angle or (ei, ej), got {rot!r}")
                rot = sp.atan2(sp.sympify(rot[1]), sp.sympify(rot[0]))
            return o1, sp.S.Zero, o2, sp.sympify(rot)
        try:
            q = tuple(sp.sympify(c) for c in _rotation_spec(self._rot))
        except ModelError as exc:
            raise ModelError(f"GenConstraint: {exc}") from None
        return o1, _ONE_Q, o2, q

    def _relative(self, space):
        return sp.zeros(space.dim, 1), _no_rot(space)


def _symbolize(obj, coordinates):
    """Names of the new coordinates written as strings become their symbols."""
    by_name = {s.name: s for s in coordinates}
    if isinstance(obj, str):
        return by_name.get(obj, sp.Symbol(obj))
    if isinstance(obj, sp.MatrixBase):
        return obj.xreplace({sp.Symbol(k): v for k, v in by_name.items()})
    if isinstance(obj, (tuple, list)):
        return type(obj)(_symbolize(o, coordinates) for o in obj)
    if isinstance(obj, sp.Basic):
        return obj.xreplace({sp.Symbol(k): v for k, v in by_name.items()})
    return obj


GEN_TYPES = (GenRevolute2, GenTranslate2, GenRevolute5, GenTranslate5, GenCylindrical4,
             GenOrthoRevolute4, GenConstraint)


# -- the model's side: slaves, their order and the substitution ------------------------------


def gen_joints(model) -> list[GenJoint]:
    return [c for c in model._constraints if isinstance(c, GenJoint)]


def check_new_joint(model, joint: GenJoint) -> None:
    """Mech's rules (11.1): a slave has one master, the chain of masters starts at ground or
    a standard body (no loops), and every argument belongs to this model."""
    who = joint.label()
    for b in (joint.slave, joint.master):
        if b is not None and getattr(b, "model", None) is not model:
            raise ModelError(f"{who}: body {b.name!r} is not a body of this model (add it with "
                             "m.add_body first)")
    for c in gen_joints(model):
        if c.slave is joint.slave:
            raise ModelError(f"{who}: body {joint.slave.name!r} is already the slave of "
                             f"{c.label()}; a body can be the slave of only one master")
    masters = {c.slave: c.master for c in gen_joints(model)}
    b = joint.master
    chain = [joint.slave.name]
    while b is not None and not b.is_ground:
        chain.append(b.name)
        if b is joint.slave:
            raise ModelError(f"{who}: the masters form a loop ({' -> '.join(chain)}); a chain "
                             "of slaves must start at ground or at a body with its own coordinates")
        b = masters.get(b)
    taken = {v.symbol.name for v in model._variables}
    for v in joint.new_variables():
        if v.symbol.name in taken:
            raise ModelError(f"{who}: its generalized coordinate {v.symbol.name!r} is already a "
                             "variable of the model (another joint's coordinate?); give it a new name")


class GenKinematics:
    r"""Poses, velocities, accelerations and pose Jacobians of every slave body in the
    layout's (independent) coordinates, derived *recursively* (masters first): with the
    joint's local relation :math:`p_s = F(x, t)` (:math:`x` the master's pose symbols and the
    joint's coordinates, :math:`\dot x` their rates):

    .. math::

        \dot p_s &= \sum_x F_x\, \dot x, \qquad J_s = \sum_x F_x J_x \\
        \ddot p_s &= \sum_x \left(V_x\, \dot x + V_{\dot x}\, \ddot x\right)
        \qquad (V = \dot p_s)

    then the master's own expressions replace :math:`x, \dot x, \ddot x`. Each derivative is of
    one joint's small expression, never of the nested chain (SymEngine when installed).

    ``pos``/``vel``/``acc`` map slave symbols to expressions, ``jac`` maps a slave's pose
    symbol to ``{layout index: dp/dq_i}``; ``sympy`` is the SymPy substitution dict.
    """

    def __init__(self, model, layout):
        try:
            import symengine as se
        except ImportError:  # pragma: no cover
            se = None
        conv = se.sympify if se is not None else sp.sympify
        self.conv = conv
        joints = {c.slave: c for c in gen_joints(model)}
        space = model.space
        qs = list(layout.q_symbols)
        index = {s: i for i, s in enumerate(qs)}
        self.pos, self.vel, self.acc, self.jac = {}, {}, {}, {}
        self.index = index
        tsym = conv(T)

        def resolve(body):
            if body.q[0] in self.pos:
                return
            j = joints[body]
            if j.master is not None and j.master in joints:
                resolve(j.master)
            r, rot = j.pose(space)
            F = [conv(e) for e in [*r, *rot]]
            slaves = set(self.pos)
            free = set().union(*(sp.sympify(e).free_symbols for e in [*r, *rot]))
            X = [x for x in free if x in index or x in slaves]
            xd = {x: conv(velocity_symbol(x.name)) for x in X}
            xdd = {x: conv(acceleration_symbol(x.name)) for x in X}
            cx = {x: conv(x) for x in X}
            has_t = T in free
            sub = {}
            for x in X:
                if x in slaves:
                    sub[cx[x]] = self.pos[x]
                    sub[xd[x]] = self.velocity(x)
                    sub[xdd[x]] = self.acceleration(x)
            for s, f in zip(body.q, F):
                parts = {x: f.diff(cx[x]) for x in X}
                v = sum((parts[x] * xd[x] for x in X if parts[x] != 0), conv(0))
                if has_t:
                    v = v + f.diff(tsym)
                a = sum((v.diff(cx[x]) * xd[x] + v.diff(xd[x]) * xdd[x] for x in X), conv(0))
                if has_t:
                    a = a + v.diff(tsym)
                row: dict = {}
                for x in X:
                    if parts[x] == 0:
                        continue
                    px = parts[x].xreplace(sub) if sub else parts[x]
                    for i, d in (self.jac[x].items() if x in slaves else [(index[x], conv(1))]):
                        row[i] = row[i] + px * d if i in row else px * d
                self.jac[s] = row
                self.pos[s] = f.xreplace(sub) if sub else f
                self.vel[velocity_symbol(s.name)] = v.xreplace(sub) if sub else v
                self.acc[acceleration_symbol(s.name)] = a.xreplace(sub) if sub else a

        for b in joints:
            resolve(b)
        self._sympy = None

    def velocity(self, s):
        return self.vel[velocity_symbol(s.name)]

    @property
    def native_subs(self) -> dict:
        """``{slave symbol: expression}`` with native (SymEngine) keys, for ``xreplace``."""
        if getattr(self, "_native_subs", None) is None:
            self._native_subs = {self.conv(k): v for d in (self.pos, self.vel, self.acc)
                                 for k, v in d.items()}
        return self._native_subs

    def acceleration(self, s):
        return self.acc[acceleration_symbol(s.name)]

    @property
    def sympy(self) -> dict:
        """SymPy ``{slave symbol: expression}`` for coordinates, velocities, accelerations;
        each value converted from SymEngine on first use (large chains need few of them)."""
        if self._sympy is None:
            self._sympy = _LazySympy({k: v for d in (self.pos, self.vel, self.acc)
                                      for k, v in d.items()})
        return self._sympy


def slave_refused(body, what: str) -> ModelError:
    """Mech 11.2: a slave body has no Cartesian coordinates of its own, so the loads and
    reactions *on it* are not defined; those on the generalized coordinates are."""
    j = body.gen_joint
    syms = ", ".join(repr(s.name) for s in j.coordinates)
    return ModelError(
        f"{what} on body {body.name!r}: it is the slave of {j.label()} and has no coordinates "
        f"of its own (Mech 11.2); ask for the {what} on its generalized coordinate(s) {syms} "
        f"(e.g. sol.loads(sym), sol.reaction(constraint, sym)), or for the force the joint "
        "transmits with sol.joint_reaction(joint)")


def generalized_reaction(model, c, coordinate, lams):
    r"""Mech 11.2's ``Reaction[cnum, sym]``: the generalized load constraint ``c`` applies to
    the coordinate ``sym``, :math:`-(\partial \Phi_c / \partial \mathit{sym})^T \lambda_c` (a moment for an
    angle, a force for
    a distance). A Gen joint is not a constraint and applies none (``ModelError``)."""
    if isinstance(c, GenJoint):
        raise ModelError(f"reaction of {c.label()}: a generalized-coordinate joint is not a "
                         "constraint and has no multipliers (Mech 11.2); use "
                         "sol.joint_reaction(joint) for the force and moment it transmits, or "
                         "sol.loads(sym) for the loads on its coordinates")
    if not isinstance(coordinate, sp.Symbol) or coordinate not in model._coordinate_symbols():
        raise ModelError(f"reaction of {c.label()} on {coordinate!r}: give a body or a coordinate "
                         "symbol of this model")
    sub = model._gen_substitution()
    eqs = [e.xreplace(sub) if sub else e for e in c.equations(model.space)]
    lam = lams(c)
    return -sp.Add(*(e.diff(coordinate) * la for e, la in zip(eqs, lam)))


class _LazySympy(dict):
    """A substitution dict (for ``xreplace``) whose SymEngine values become SymPy on first
    lookup."""

    def __init__(self, native: dict):
        super().__init__({k: None for k in native})
        self._native = native

    def __getitem__(self, key):
        v = dict.__getitem__(self, key)
        if v is None:
            from .._symbols import restore_assumptions

            v = restore_assumptions(sp.sympify(self._native[key]))
            dict.__setitem__(self, key, v)
        return v

    def get(self, key, default=None):
        return self[key] if key in self else default

    def items(self):
        return [(k, self[k]) for k in self]

    def values(self):
        return [self[k] for k in self]


__all__ = [t.__name__ for t in GEN_TYPES] + ["GEN_TYPES", "GenJoint"]
