r"""Export to URDF and MJCF: ``m.to_urdf(path)``, ``m.to_mjcf(path)`` (decisions 0040, 0067).

What the formats can express: a tree of ``GenRevolute5`` and ``GenTranslate5`` joints, bodies
with mass, centroid and inertia, gravity (URDF: only 9.81 down ``z``, which URDF consumers
assume), and on a joint coordinate the loads ``-k (q - ref) - d q_dot - a q_ddot`` the
importers make (MJCF: ``stiffness``, ``springref``, ``damping``, ``armature``; URDF:
``<dynamics damping>`` only; decision 0048). Absolute bodies (``x, y, z, e0..e3``) and
equations (decision 0067):

* an absolute body whose first point of a ``Spherical3`` it is, the other point on a body
  that does not hang from it, is a body with a ``ball`` joint at that point (MJCF); an
  absolute body with no such joint is a free body under the world: MJCF ``<freejoint>``,
  URDF a ``floating`` joint from the world link, at the pose of the model's guess
  (``m.guess()``), which is where the importers put MuJoCo's ``qpos0`` and URDF's origin;
* MJCF equalities, named after the constraint: a ``Spherical3`` and a ``RotationLock3``
  between the same bodies a ``weld``, another ``Spherical3`` a ``connect``, both between two
  sites on the bodies (MuJoCo makes the sites, and for a weld their frames, coincide, so the
  file does not depend on its pose at ``qpos0``), and a ``Constraint`` with one equation
  :math:`a\,(q_1 - c_0 - c_1 q_2 - \dots - c_4 q_2^4) = 0` in joint coordinates a ``joint``
  equality with ``polycoef`` :math:`c_0 \dots c_4` (written divided by ``a``).

Anything else (other constraint types, a rotation lock without a point constraint, other
equations, URDF ball joints and loops, other Gen joints, other loads, symbolic values) is
refused with ``ModelError`` naming it.

With a Gen joint's frames ``(o_1, R_1)`` on the slave and ``(o_2, R_2)`` on the master
(``constraints/_generalized.py``) the slave's pose is :math:`A_s = A_m R_0 \operatorname{Rot}(u_1, q)`,
:math:`R_0 = R_2 R_1^T`, ``u_1`` the slave's axis direction, and :math:`r_s = r_m + A_m o_2 - A_s o_1`. Hence

* MJCF: ``<body pos="o_2 - R_0 o_1" quat="R_0">`` with ``<joint pos="o_1" axis="u_1">``
  (MuJoCo turns the body about the joint's point), the body frame being mechsys's;
* URDF: a joint turns its child about the child frame's origin, so each link frame is the
  body frame moved to its joint's point ``o_1`` (same axes): ``<origin xyz="o_2 - o_1^m"
  rpy="R_0">`` (``o_1^m`` the master's shift), ``<axis xyz="u_1">``; the centroid and the
  drawn points shift by ``-o_1``. ``rpy`` from :math:`R = R_z(y) R_y(p) R_x(r)`.

A ball joint ``Spherical3(p_1 on b, p_2 on the parent P)``: the body frame is mechsys's,
placed in its parent's at the initial relative rotation :math:`R_r = A_P^T A_b` (at the
guess) and at :math:`p_2 - R_r\, p_1`, so the points coincide at ``qpos0``; ``<joint
type="ball" pos="p_1">``. A weld ``RotationLock3`` :math:`A_1 = A_2 Q` is the site frames
:math:`S_1 = I` on body 1 and :math:`S_2 = Q` on body 2 (:math:`A_1 S_1 = A_2 S_2`).

Numbers are written with ``repr`` (shortest round-trip), so a file read back gives the
same doubles.

Example::

    m = ms.from_mjcf("humanoid.xml")        # a free base, ball joints, equalities
    m.to_mjcf("again.xml")                  # MuJoCo and ms.from_mjcf read it back
"""

from __future__ import annotations

import math
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from .._errors import ModelError


def matrix_rpy(R) -> tuple[float, float, float]:
    """``(r, p, y)`` with :math:`R = R_z(y) R_y(p) R_x(r)` (``p`` in [-pi/2, pi/2]; at ``|p| = pi/2``
    the yaw is set to 0)."""
    R = np.asarray(R, float)
    cp = math.hypot(R[0, 0], R[1, 0])
    p = math.atan2(-R[2, 0], cp)
    if cp > 1e-12:
        return math.atan2(R[2, 1], R[2, 2]), p, math.atan2(R[1, 0], R[0, 0])
    return math.atan2(-R[1, 2], R[1, 1]), p, 0.0


#: MuJoCo's ``mjMINVAL``: a moving body's mass and principal moments must exceed it
MJ_MINVAL = 1e-15


def _num(v) -> str:
    return repr(float(v))


def _vec(v) -> str:
    return " ".join(_num(x) for x in np.ravel(v))


def _float(value, what: str) -> float:
    try:
        return float(value)
    except TypeError:
        raise ModelError(f"{what} is symbolic ({value}); give numbers before exporting") from None


def _owner(m, pt):
    """The body of point ``pt`` (ground for a global point)."""
    b = pt.body
    return m.ground if b is None or b.is_ground else b


def _point(pt, what: str) -> np.ndarray:
    return np.array([_float(x, what) for x in np.ravel(pt.local)])


class _Tree:
    """What the exporters write: ``entries`` ``(body, kind, item)`` in tree order (parents
    first; ``kind`` ``"gen"`` with the Gen joint, ``"ball"`` with the Spherical3, ``"free"``
    with None), each body's ``parent`` (ground included), the loop closures ``loops``
    (``("connect", S)``, ``("weld", S, R, q)``, ``("joint", C, q1, q2, polycoef)``), the mass
    properties ``props``, ``gravity`` and the joint loads ``passive``."""

    def __init__(self, entries, parent, loops, props, gravity, passive):
        self.entries, self.parent, self.loops = entries, parent, loops
        self.props, self.gravity, self.passive = props, gravity, passive

    @property
    def joints(self):
        return [item for _, kind, item in self.entries if kind == "gen"]


_HOLDS = {"mjcf": "MJCF export holds GenRevolute5 and GenTranslate5 joints, Spherical3 (a ball "
                  "joint or a connect equality), Spherical3 with RotationLock3 between the same "
                  "bodies (a weld) and Constraint(q1 - poly(q2)) on joint coordinates (a joint "
                  "equality)",
          "urdf": "URDF holds a tree of GenRevolute5 and GenTranslate5 joints and free bodies "
                  "(floating joints); no ball joints or closed loops"}


def _tree(m, fmt: str) -> _Tree:
    """The model as the format's tree and loop closures, or ModelError naming what the
    format cannot hold."""
    from ..constraints._general import Constraint
    from ..constraints._generalized import GenJoint, GenRevolute5, GenTranslate5
    from ..constraints._spatial import RotationLock3, Spherical3
    from ..loads._loads import Gravity

    if m.space.dim != 3:
        raise ModelError(f"to_{fmt}: only spatial models (Model3D) can be exported; a planar "
                         "model's bodies and joints have no counterpart in the file")
    ground = m.ground
    gen: dict = {}
    sph, rot, eqs = [], [], []
    for c in m.constraints:
        if isinstance(c, GenJoint):
            if not isinstance(c, (GenRevolute5, GenTranslate5)):
                raise ModelError(f"to_{fmt}: joint {c.label()} has no "
                                 f"{fmt.upper()} counterpart; only GenRevolute5 and GenTranslate5")
            gen[c.slave] = c
        elif fmt == "urdf":
            raise ModelError(f"to_urdf: {c.label()} makes equations, which URDF export "
                             f"does not hold ({_HOLDS['urdf']}); use to_mjcf or remove it")
        elif type(c) is Spherical3:
            sph.append(c)
        elif type(c) is RotationLock3:
            rot.append(c)
        elif type(c) is Constraint:
            eqs.append(c)
        else:
            raise ModelError(f"to_mjcf: {c.label()} has no MJCF counterpart "
                             f"({_HOLDS['mjcf']}); remove it or write it with those")
    parent: dict = {b: (j.master if j.master is not None else ground) for b, j in gen.items()}
    loops: list = []
    # welds: a RotationLock3 and a Spherical3 between the same two bodies (the one named
    # after it first: the importer names them "w" and "w_rotation")
    for r in rot:
        pair = {r.b1 if not r.b1.is_ground else ground,
                r.b2 if r.b2 is not None and not r.b2.is_ground else ground}
        q = np.array([_float(x, f"rotation of {r.label()}") for x in r.q_rel])
        cands = [s for s in sph if {_owner(m, s.p1), _owner(m, s.p2)} == pair]
        named = [s for s in cands if r.name == f"{s.name}_rotation"]
        if not cands:
            raise ModelError(f"to_mjcf: {r.label()} locks a relative rotation only, "
                             "which MJCF cannot hold (its weld locks the relative position and "
                             "rotation); add a Spherical3 between the same bodies to make it a "
                             "weld, or remove it")
        s = (named or cands)[0]
        sph.remove(s)
        loops.append(("weld", s, r, q / np.linalg.norm(q)))

    def descends(b, anc):
        while b is not None and not b.is_ground:
            if b is anc:
                return True
            b = parent.get(b)
        return False

    # ball joints: a Spherical3 whose first point is on an absolute body not yet in the
    # tree and whose second is on a body that does not hang from it (as the importer makes
    # them); every other Spherical3 closes a loop (a connect)
    balls: dict = {}
    for s in sph:
        ch, pa = _owner(m, s.p1), _owner(m, s.p2)
        if not ch.is_ground and ch not in parent and not descends(pa, ch):
            parent[ch] = pa
            balls[ch] = s
        else:
            loops.append(("connect", s))
    coords = {j.coordinates[0].name for j in gen.values()}
    for c in eqs:
        loops.append(("joint", c, *_joint_equality(m, c, coords)))
    loops.sort(key=lambda it: it[1].number)     # the model's order: read back in it
    gravity = None
    passive: dict = {}                 # coordinate -> [constant, stiffness, damping, armature]
    for ld in m.load_list:
        if isinstance(ld, Gravity) and ld.only is None:
            v = np.array([_float(x, "gravity direction") for x in np.ravel(ld.vector.local)])
            gmag = _float(ld.g, "gravity magnitude")
            gravity = v / np.linalg.norm(v) * gmag if ld.mode == "absolute" else v * gmag
            continue
        got = _joint_load(ld, coords)
        if got is not None:
            name, c = got
            prev = passive.get(name, (np.zeros(4), ()))
            passive[name] = (prev[0] + c, (*prev[1], getattr(ld, "name", None) or "Load"))
            continue
        raise ModelError(f"to_{fmt}: load {getattr(ld, 'name', None) or type(ld).__name__} has no "
                         f"{fmt.upper()} counterpart (gravity on every body; on a joint coordinate "
                         "a spring, damper or armature); remove it first")
    entries, seen = [], set()

    def visit(b):
        if b in seen:
            return
        mst = parent.get(b)
        if mst is not None and not mst.is_ground:
            visit(mst)
        seen.add(b)
        if b in gen:
            entries.append((b, "gen", gen[b]))
        elif b in balls:
            entries.append((b, "ball", balls[b]))
        else:
            # a body with its own coordinates and no joint to a parent: free (MJCF free
            # joint, URDF floating joint) under the world
            parent[b] = ground
            entries.append((b, "free", None))

    for b in m.bodies[1:]:
        visit(b)
    props = {}
    for b, _, _ in entries:
        mass = _float(b.mass, f"mass of body {b.name!r}")
        c = np.array([_float(x, f"centroid of body {b.name!r}") for x in np.ravel(b.centroid)]) \
            if b.centroid is not None else np.zeros(3)
        Iraw = np.asarray(m.space.inertia_matrix(b.inertia)) if b.inertia is not None else np.zeros((3, 3))
        I = np.array([[_float(x, f"inertia of body {b.name!r}") for x in row] for row in Iraw])
        props[b] = (mass, c, I)
    return _Tree(entries, parent, loops, props, gravity, passive)


def _joint_equality(m, c, coords):
    r"""``(q1, q2 or None, [c0..c4])`` with ``c``'s equation
    :math:`a\,(q_1 - c_0 - c_1 q_2 - \dots - c_4 q_2^4) = 0` (``a`` a nonzero number), as MJCF's
    joint equality holds it, or ModelError saying why not."""
    import sympy as sp

    def refuse(why):
        return ModelError(f"to_mjcf: {c.label()} {why}; MJCF holds one equation "
                          "q1 = c0 + c1 q2 + ... + c4 q2^4 in two joint coordinates with numbers "
                          "(its joint equality); remove it or write it so")

    if c.new_variables():
        raise refuse(f"adds variables {[v.symbol.name for v in c.new_variables()]}")
    eqs = c.equations(m.space)
    if len(eqs) != 1:
        raise refuse(f"has {len(eqs)} equations")
    e = sp.expand(eqs[0])
    syms = sorted(e.free_symbols, key=lambda s: s.name)
    other = [s.name for s in syms if s.name not in coords]
    if other:
        raise refuse(f"depends on {other}, which are not coordinates of GenRevolute5 or "
                     "GenTranslate5 joints")
    if not 1 <= len(syms) <= 2 or not e.is_polynomial(*syms):
        raise refuse("is not a polynomial in one or two joint coordinates")
    best = None
    for k, y in enumerate(syms):
        P = sp.Poly(e, *syms)
        a = P.coeff_monomial(y)
        if a == 0 or any(mon[k] and mon != tuple(int(i == k) for i in range(len(syms)))
                         for mon in P.monoms()):
            continue                      # y is not alone and linear
        rest = sp.expand(e - a * y)
        x = syms[1 - k] if len(syms) == 2 else None
        if x is not None and sp.degree(rest, x) > 4:
            continue
        poly = [-float(rest.coeff(x, i) if x is not None else (rest if i == 0 else 0)) / float(a)
                for i in range(5)]
        if best is None or (a == 1 and best[0] != 1):
            best = (a, y.name, x.name if x is not None else None, poly)
    if best is None:
        raise refuse("is not linear in one coordinate and of degree at most 4 in the other")
    return best[1:]


def _joint_load(ld, coords):
    r"""``(coordinate, [c0, k, d, a])`` when ``ld`` is a ``Load`` on a joint coordinate ``q``
    with the magnitude ``c0 - k q - d q_dot - a q_ddot`` (numbers): a spring ``-k (q - ref)``
    (``c0 = k ref``), a damper and an armature, as the importers write them; else None."""
    import sympy as sp

    from .._symbols import acceleration_symbol, velocity_symbol
    from ..loads._loads import Load

    if not isinstance(ld, Load):
        return None
    name = ld.symbol.name if isinstance(ld.symbol, sp.Symbol) else str(ld.symbol)
    if name not in coords:
        return None
    e = sp.expand(sp.sympify(ld.magnitude))
    xs = [sp.Symbol(name), velocity_symbol(name), acceleration_symbol(name)]
    # the importers' symbols may carry assumptions: match by name
    sub = {f: x for f in e.free_symbols for x in xs if f.name == x.name}
    e = e.xreplace(sub)
    if e.free_symbols - set(xs):
        return None
    cs = [-sp.diff(e, x) for x in xs]
    if not all(c.is_number for c in cs):
        return None
    c0 = e.subs({x: 0 for x in xs})
    if not c0.is_number:
        return None
    return name, np.array([float(c0)] + [float(c) for c in cs])


def _frames(j, space):
    from ..geometry._rotations import rotation_matrix

    o1, R1, o2, R2 = j._frames(space)
    o1 = np.array([float(v) for v in o1])
    o2 = np.array([float(v) for v in o2])
    R1 = np.asarray(rotation_matrix([float(v) for v in R1]), float)
    R2 = np.asarray(rotation_matrix([float(v) for v in R2]), float)
    return o1, R1, o2, R2


def _inertia_attrs_urdf(I) -> str:
    return (f'ixx="{_num(I[0, 0])}" ixy="{_num(I[0, 1])}" ixz="{_num(I[0, 2])}" '
            f'iyy="{_num(I[1, 1])}" iyz="{_num(I[1, 2])}" izz="{_num(I[2, 2])}"')


def _initial_poses(m, tree: _Tree, fmt: str):
    """World rotations of the bodies at the model's initial guess (``m.guess()``: absolute
    bodies at their guessed pose, a Gen slave :math:`A_s = A_m R_2 R_z(q) R_1^T` at its
    coordinate's guess) and the absolute bodies' ``(r, e)`` there (``e`` normalised)."""
    from ..constraints._generalized import GenRevolute5
    from ._mjcf import quat_matrix

    vals = dict(zip((s.name for s in m._coordinate_symbols()), m.guess()))
    rots = {m.ground: np.eye(3)}
    poses = {}
    for b, kind, item in tree.entries:
        if kind == "gen":
            o1, R1, o2, R2 = _frames(item, m.space)
            Rz = np.eye(3)
            if isinstance(item, GenRevolute5):
                t = vals[item.coordinates[0].name]
                Rz = np.array([[math.cos(t), -math.sin(t), 0], [math.sin(t), math.cos(t), 0], [0, 0, 1]])
            rots[b] = rots[tree.parent[b]] @ R2 @ Rz @ R1.T
        else:
            g = np.array([vals[s.name] for s in b.q])
            if not np.linalg.norm(g[3:]) > 1e-12:
                raise ModelError(f"to_{fmt}: the guess of body {b.name!r} has Euler parameters "
                                 f"{g[3:].tolist()}, which are no rotation; give it a guess "
                                 "(m.set_guess) before exporting: the file places it there")
            e = g[3:] / np.linalg.norm(g[3:])
            rots[b] = quat_matrix(e)
            poses[b] = (g[:3], e)
    return rots, poses


def to_urdf(m, path, robot: str = "mechsys") -> Path:
    r"""Write the tree model ``m`` as a URDF file (module doc); returns the path."""
    from ..constraints._generalized import GenTranslate5

    tree = _tree(m, "urdf")
    props, gravity, passive = tree.props, tree.gravity, tree.passive
    for name, ((c0, k, _d, a), labels) in passive.items():
        if c0 or k or a:
            raise ModelError(f"to_urdf: load {', '.join(labels)} on joint {name!r} is a spring, a "
                             "constant force or an armature, which URDF cannot hold (only "
                             "<dynamics damping>); use to_mjcf or remove it")
    if gravity is not None and not np.allclose(gravity, (0, 0, -9.81), rtol=0, atol=1e-12):
        raise ModelError(f"to_urdf: gravity {gravity.tolist()} cannot be written (URDF has no gravity; "
                         "its users assume 9.81 down z)")
    _, poses = _initial_poses(m, tree, "urdf")
    taken = {j.coordinates[0].name for j in tree.joints}
    shift = {}
    root = m.ground.name
    lines = [f"<robot name={quoteattr(robot)}>", f"  <link name={quoteattr(root)}/>"]
    for b, kind, j in tree.entries:
        o1 = _frames(j, m.space)[0] if kind == "gen" else np.zeros(3)
        shift[b] = o1
        mass, c, I = props[b]
        lines.append(f"  <link name={quoteattr(b.name)}>")
        lines.append(f'    <inertial><origin xyz="{_vec(c - o1)}" rpy="0.0 0.0 0.0"/>'
                     f'<mass value="{_num(mass)}"/><inertia {_inertia_attrs_urdf(I)}/></inertial>')
        lines.append("  </link>")
    for b, kind, j in tree.entries:
        if kind == "free":
            # a floating joint on the root link: the importer makes its child a free body
            # guessed at the joint's origin, the body frame being the link frame
            name = f"{b.name}_floating"
            if name in taken:
                raise ModelError(f"to_urdf: the floating joint of body {b.name!r} would be named "
                                 f"{name!r}, which a joint coordinate is; rename one of them")
            taken.add(name)
            r, e = poses[b]
            from ._mjcf import quat_matrix

            lines.append(f"  <joint name={quoteattr(name)} type=\"floating\">")
            lines.append(f"    <parent link={quoteattr(root)}/><child link={quoteattr(b.name)}/>")
            lines.append(f'    <origin xyz="{_vec(r)}" rpy="{_vec(matrix_rpy(quat_matrix(e)))}"/>')
            lines.append("  </joint>")
            continue
        o1, R1, o2, R2 = _frames(j, m.space)
        mst = tree.parent[b]
        parent = root if mst.is_ground else mst.name
        ps = shift.get(mst, np.zeros(3))
        R0 = R2 @ R1.T
        kind = "prismatic" if isinstance(j, GenTranslate5) else "continuous"
        name = j.coordinates[0].name
        lines.append(f"  <joint name={quoteattr(name)} type=\"{kind}\">")
        lines.append(f"    <parent link={quoteattr(parent)}/><child link={quoteattr(b.name)}/>")
        lines.append(f'    <origin xyz="{_vec(o2 - ps)}" rpy="{_vec(matrix_rpy(R0))}"/>')
        lines.append(f'    <axis xyz="{_vec(R1[:, 2])}"/>')
        if kind == "prismatic":
            lines.append('    <limit lower="-1e9" upper="1e9" effort="1e9" velocity="1e9"/>')
        if name in passive and passive[name][0][2]:
            lines.append(f'    <dynamics damping="{_num(passive[name][0][2])}"/>')
        lines.append("  </joint>")
    lines.append("</robot>")
    p = Path(path)
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return p


def to_mjcf(m, path, model: str = "mechsys") -> Path:
    r"""Write the model ``m`` as an MJCF (MuJoCo) file (module doc); returns the path."""
    from ..constraints._generalized import GenTranslate5
    from ..geometry._rotations import _from_matrix
    from ._mjcf import quat_matrix

    tree = _tree(m, "mjcf")
    props, passive = tree.props, tree.passive
    rots, poses = _initial_poses(m, tree, "mjcf")
    g = tree.gravity if tree.gravity is not None else np.zeros(3)
    children: dict = {}
    for b, kind, item in tree.entries:
        pa = tree.parent[b]
        children.setdefault(None if pa.is_ground else pa, []).append((b, kind, item))
    names: dict = {}                              # joint name -> what it is
    for b, kind, item in tree.entries:
        if kind == "free":
            continue
        n = item.coordinates[0].name if kind == "gen" else item.name
        what = f"the joint of body {b.name!r}"
        if n in names:
            raise ModelError(f"to_mjcf: {what} and {names[n]} would both be MJCF joints named "
                             f"{n!r}; rename one of them")
        names[n] = what
    # loop closures: connect and weld between two sites (MuJoCo makes the sites coincide,
    # and for a weld their frames: A_1 S_1 = A_2 S_2, so S_1 = I, S_2 = the locked rotation),
    # joint equalities between the joints named after the coordinates
    sites: dict = {}                              # body -> [(name, local point, rotation, what)]
    equalities = []
    for it in tree.loops:
        kind, c = it[0], it[1]
        if kind == "joint":
            _, _, q1, q2, poly = it
            j2 = f" joint2={quoteattr(q2)}" if q2 is not None else ""
            equalities.append(f"    <joint name={quoteattr(c.name)} joint1={quoteattr(q1)}{j2} "
                              f"polycoef=\"{_vec(poly)}\"/>")
            continue
        b1, b2 = _owner(m, c.p1), _owner(m, c.p2)
        S2 = np.eye(3)
        if kind == "weld":
            r, q = it[2], it[3]
            Q = quat_matrix(q)
            # RotationLock3: A_{r.b1} = A_{r.b2} Q
            S2 = Q if (r.b1 is b1 or (r.b1.is_ground and b1.is_ground)) else Q.T
        n1, n2 = f"{c.name}_site1", f"{c.name}_site2"
        sites.setdefault(b1, []).append((n1, _point(c.p1, f"point 1 of {c.label()}"), np.eye(3), c))
        sites.setdefault(b2, []).append((n2, _point(c.p2, f"point 2 of {c.label()}"), S2, c))
        equalities.append(f"    <{kind} name={quoteattr(c.name)} site1={quoteattr(n1)} "
                          f"site2={quoteattr(n2)}/>")
    out = [f"<mujoco model={quoteattr(model)}>", '  <compiler angle="radian" autolimits="true"/>',
           f'  <option gravity="{_vec(g)}"/>', "  <worldbody>"]

    def write_sites(b, pad, P, R):
        for n, p, Rs, _ in sites.get(b, []):
            out.append(f"{pad}<site name={quoteattr(n)} pos=\"{_vec(P + R @ p)}\" "
                       f"quat=\"{_vec(_from_matrix(R @ Rs))}\"/>")

    write_sites(m.ground, "    ", np.zeros(3), np.eye(3))

    def placed(j):
        """``(pos, R0, o1, u1)``: the slave's frame in its master's, the joint's point and axis
        on the slave (module doc)."""
        o1, R1, o2, R2 = _frames(j, m.space)
        R0 = R2 @ R1.T
        return o2 - R0 @ o1, R0, o1, R1[:, 2]

    def massless(b):
        mass, _, I = props[b]
        return mass == 0 and not np.any(I)

    def body(entry, depth, Pa, Ra):
        """The body of tree entry ``(b, kind, item)`` (its frame placed in the written
        parent's frame moved by ``(Pa, Ra)``, the parent's content frame in the written
        frame)."""
        pad = "  " * depth
        b, kind, item = entry
        # MuJoCo refuses moving bodies without mass (an importer's intermediate body of a
        # body with several joints, a planar joint's slides, a massless URDF link): a
        # massless body with one child joint is written as one body holding both joints.
        # MuJoCo applies a body's joints in order, each about its point and axis in the frame
        # the joints before it have moved: the chain's own frames. The child's frame is the
        # written one moved by (Pb, Rb); its joint and content are written in the written frame.
        chain = []
        if kind == "gen":
            chain = [item]
            while massless(chain[-1].slave):
                kids = children.get(chain[-1].slave, [])
                if len(kids) != 1 or kids[0][1] != "gen":
                    break
                chain.append(kids[0][2])
            last = chain[-1].slave
        else:
            last = b
        for jj in chain[:-1]:
            for _, _, _, c in sites.get(jj.slave, []):
                raise ModelError(f"to_mjcf: {c.label()} has a point on body {jj.slave.name!r}, "
                                 "which has no mass and is written merged with the body its "
                                 "joint carries (MuJoCo refuses moving bodies without mass); give "
                                 f"{jj.slave.name!r} a mass and inertia, or put the point on "
                                 "another body")
        mass, c, I = props[last]
        if massless(last):
            what = ("has no child" if not children.get(last) else
                    f"carries {len(children[last])} bodies")
            how = "is moved by a joint" if kind == "gen" else f"has a {kind} joint"
            raise ModelError(f"to_mjcf: body {last.name!r} {how} and has no mass and "
                             f"no inertia, and it {what}: MuJoCo refuses moving bodies without "
                             "mass; give it a mass and inertia (or remove it)")
        if not mass > MJ_MINVAL or np.linalg.eigvalsh(I).min() <= MJ_MINVAL:
            raise ModelError(f"to_mjcf: body {last.name!r} has mass {mass!r} and principal moments "
                             f"of inertia {np.linalg.eigvalsh(I).tolist()}: MuJoCo refuses a moving "
                             "body unless both are positive (a point mass or a slender rod is "
                             "refused); give it a positive mass and positive principal moments")
        Pb, Rb = np.zeros(3), np.eye(3)
        if kind == "gen":
            pos, R0, _, _ = placed(item)
            out.append(f"{pad}<body name={quoteattr(last.name)} pos=\"{_vec(Pa + Ra @ pos)}\" "
                       f"quat=\"{_vec(_from_matrix(Ra @ R0))}\">")
        elif kind == "ball":
            # the body frame is mechsys's, turned in its parent's by its initial relative
            # rotation RR (the importer guesses the body at the file's pose); the ball's points
            # p1 (here) and p2 (on the parent) coincide there: pos = p2 - RR p1
            p1 = _point(item.p1, f"point 1 of {item.label()}")
            p2 = _point(item.p2, f"point 2 of {item.label()}")
            RR = rots[tree.parent[b]].T @ rots[b]
            out.append(f"{pad}<body name={quoteattr(b.name)} pos=\"{_vec(Pa + Ra @ (p2 - RR @ p1))}\" "
                       f"quat=\"{_vec(_from_matrix(Ra @ RR))}\">")
            out.append(f"{pad}  <joint name={quoteattr(item.name)} type=\"ball\" pos=\"{_vec(p1)}\"/>")
        else:
            # MuJoCo's free joint: qpos is the body frame's position and quaternion, mechsys's
            # coordinates; at qpos0 the body is where the model's guess puts it
            r, e = poses[b]
            out.append(f"{pad}<body name={quoteattr(b.name)} pos=\"{_vec(r)}\" quat=\"{_vec(e)}\">")
            out.append(f"{pad}  <freejoint/>")
        for k, jj in enumerate(chain):
            pk, Rk, o1, u1 = placed(jj)
            if k:
                Pb, Rb = Pb + Rb @ pk, Rb @ Rk
            jkind = "slide" if isinstance(jj, GenTranslate5) else "hinge"
            jn = jj.coordinates[0].name
            extra = ""
            if jn in passive:
                (c0, ks, d, a), labels = passive[jn]
                if c0 and not ks:
                    raise ModelError(f"to_mjcf: load {', '.join(labels)} on joint {jn!r} has a "
                                     f"constant part {c0!r} without a spring, which MJCF cannot "
                                     "hold on a joint; remove it")
                # -k (q - springref) - d qd - a qdd: MuJoCo's passive forces and armature
                for key, v in (("stiffness", ks), ("springref", c0 / ks if ks else 0.0),
                               ("damping", d), ("armature", a)):
                    if v:
                        extra += f" {key}=\"{_num(v)}\""
            out.append(f"{pad}  <joint name={quoteattr(jn)} type=\"{jkind}\" "
                       f"pos=\"{_vec(Pb + Rb @ o1)}\" axis=\"{_vec(Rb @ u1)}\"{extra}/>")
        Iw = Rb @ I @ Rb.T
        full = (Iw[0, 0], Iw[1, 1], Iw[2, 2], Iw[0, 1], Iw[0, 2], Iw[1, 2])
        out.append(f"{pad}  <inertial pos=\"{_vec(Pb + Rb @ c)}\" mass=\"{_num(mass)}\" "
                   f"fullinertia=\"{_vec(full)}\"/>")
        write_sites(last, pad + "  ", Pb, Rb)
        for k in children.get(last, []):
            body(k, depth + 1, Pb, Rb)
        out.append(f"{pad}</body>")

    for entry in children.get(None, []):
        body(entry, 2, np.zeros(3), np.eye(3))
    out.append("  </worldbody>")
    if equalities:
        out += ["  <equality>", *equalities, "  </equality>"]
    out.append("</mujoco>")
    p = Path(path)
    p.write_text("\n".join(out) + "\n", encoding="utf-8")
    return p
