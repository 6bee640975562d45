r"""Export of tree models to URDF and MJCF: ``m.to_urdf(path)``, ``m.to_mjcf(path)``
(decision 0040).

What the formats can express: a tree of ``GenRevolute5`` and ``GenTranslate5`` joints on
ground, bodies with mass, centroid and inertia, gravity (URDF: only 9.81 down ``z``, which
URDF consumers assume), and on a joint coordinate the loads ``-k (q - ref) - d q_dot - a
q_ddot`` the importers make (MJCF: ``stiffness``, ``springref``, ``damping``, ``armature``;
URDF: ``<dynamics damping>`` only; decision 0048). Anything else (absolute bodies,
constraint equations, other Gen joints, other loads, symbolic values) is refused with
``ModelError`` naming it.

With a Gen joint's frames ``(o_1, R_1)`` on the slave and ``(o_2, R_2)`` on the master
(``constraints/_generalized.py``) the slave's pose is :math:`A_s = A_m R_0 \operatorname{Rot}(u_1, q)`,
:math:`R_0 = R_2 R_1^T`, ``u_1`` the slave's axis direction, and :math:`r_s = r_m + A_m o_2 - A_s o_1`. Hence

* MJCF: ``<body pos="o_2 - R_0 o_1" quat="R_0">`` with ``<joint pos="o_1" axis="u_1">``
  (MuJoCo turns the body about the joint's point), the body frame being mechsys's;
* URDF: a joint turns its child about the child frame's origin, so each link frame is the
  body frame moved to its joint's point ``o_1`` (same axes): ``<origin xyz="o_2 - o_1^m"
  rpy="R_0">`` (``o_1^m`` the master's shift), ``<axis xyz="u_1">``; the centroid and the
  drawn points shift by ``-o_1``. ``rpy`` from :math:`R = R_z(y) R_y(p) R_x(r)`.

Numbers are written with ``repr`` (shortest round-trip), so a file read back gives the
same doubles.
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


def _tree(m, fmt: str):
    """``(joints by slave in tree order, {body: (mass, c, I)})`` or ModelError naming what
    the format cannot hold."""
    from ..constraints._generalized import GenJoint, GenRevolute5, GenTranslate5
    from ..loads._loads import Gravity

    if m.space.dim != 3:
        raise ModelError(f"to_{fmt}: only spatial models (Model3D) can be exported")
    joints = {}
    for c in m.constraints:
        if isinstance(c, GenJoint):
            if not isinstance(c, (GenRevolute5, GenTranslate5)):
                raise ModelError(f"to_{fmt}: joint {c.label()} ({type(c).__name__}) has no "
                                 f"{fmt.upper()} counterpart; only GenRevolute5 and GenTranslate5")
            joints[c.slave] = c
        else:
            raise ModelError(f"to_{fmt}: constraint {c.label()} makes equations, which "
                             f"{fmt.upper()} export does not hold (a tree of Gen joints only)")
    for b in m.bodies[1:]:
        if b not in joints:
            raise ModelError(f"to_{fmt}: body {b.name!r} has its own (absolute) coordinates; export "
                             "holds bodies moved by GenRevolute5/GenTranslate5 joints only")
    gravity = None
    coords = {j.coordinates[0].name for j in joints.values()}
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
    order, seen = [], set()

    def visit(b):
        if b in seen:
            return
        mst = joints[b].master
        if mst is not None and not mst.is_ground:
            visit(mst)
        seen.add(b)
        order.append(b)

    for b in m.bodies[1:]:
        visit(b)
    props = {}
    for b in order:
        mass = _float(b.mass, f"mass of body {b.name!r}")
        c = np.array([_float(x, f"centroid of body {b.name!r}") for x in np.ravel(b.centroid)]) \
            if b.centroid is not None else np.zeros(3)
        Iraw = np.asarray(m.space.inertia_matrix(b.inertia)) if b.inertia is not None else np.zeros((3, 3))
        I = np.array([[_float(x, f"inertia of body {b.name!r}") for x in row] for row in Iraw])
        props[b] = (mass, c, I)
    return [joints[b] for b in order], props, gravity, passive


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


def to_urdf(m, path, robot: str = "mechsys") -> Path:
    r"""Write the tree model ``m`` as a URDF file (module doc); returns the path."""
    from ..constraints._generalized import GenTranslate5

    joints, props, gravity, passive = _tree(m, "urdf")
    for name, ((c0, k, _d, a), labels) in passive.items():
        if c0 or k or a:
            raise ModelError(f"to_urdf: load {', '.join(labels)} on joint {name!r} is a spring, a "
                             "constant force or an armature, which URDF cannot hold (only "
                             "<dynamics damping>); use to_mjcf or remove it")
    if gravity is not None and not np.allclose(gravity, (0, 0, -9.81), rtol=0, atol=1e-12):
        raise ModelError(f"to_urdf: gravity {gravity.tolist()} cannot be written (URDF has no gravity; "
                         "its users assume 9.81 down z)")
    shift = {}
    root = m.ground.name
    lines = [f"<robot name={quoteattr(robot)}>", f"  <link name={quoteattr(root)}/>"]
    for j in joints:
        b = j.slave
        o1, R1, o2, R2 = _frames(j, m.space)
        shift[b] = o1
        mass, c, I = props[b]
        lines.append(f"  <link name={quoteattr(b.name)}>")
        lines.append(f'    <inertial><origin xyz="{_vec(c - o1)}" rpy="0.0 0.0 0.0"/>'
                     f'<mass value="{_num(mass)}"/><inertia {_inertia_attrs_urdf(I)}/></inertial>')
        lines.append("  </link>")
    for j in joints:
        b = j.slave
        o1, R1, o2, R2 = _frames(j, m.space)
        mst = j.master
        parent = root if mst is None or mst.is_ground else mst.name
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
    r"""Write the tree model ``m`` as an MJCF (MuJoCo) file (module doc); returns the path."""
    from ..constraints._generalized import GenTranslate5
    from ..geometry._rotations import _from_matrix

    joints, props, gravity, passive = _tree(m, "mjcf")
    g = gravity if gravity is not None else np.zeros(3)
    children: dict = {}
    for j in joints:
        mst = j.master
        children.setdefault(None if mst is None or mst.is_ground else mst, []).append(j)
    out = [f"<mujoco model={quoteattr(model)}>", '  <compiler angle="radian" autolimits="true"/>',
           f'  <option gravity="{_vec(g)}"/>', "  <worldbody>"]

    def placed(j):
        """``(pos, R0, o1, u1)``: the slave's frame in its master's, the joint's point and axis
        on the slave (module doc)."""
        o1, R1, o2, R2 = _frames(j, m.space)
        R0 = R2 @ R1.T
        return o2 - R0 @ o1, R0, o1, R1[:, 2]

    def massless(b):
        mass, _, I = props[b]
        return mass == 0 and not np.any(I)

    def body(j, depth, Pa, Ra):
        """The body of joint ``j`` (its frame placed in the written parent's frame moved by
        ``(Pa, Ra)``, the parent's content frame in the written frame)."""
        pad = "  " * depth
        pos, R0, _, _ = placed(j)
        # MuJoCo refuses moving bodies without mass (an importer's intermediate body of a
        # body with several joints, a planar joint's slides, a massless URDF link): a
        # massless body with one child joint is written as one body holding both joints.
        # MuJoCo applies a body's joints in order, each about its point and axis in the frame
        # the joints before it have moved: the chain's own frames. The child's frame is the
        # written one moved by (Pb, Rb); its joint and content are written in the written frame.
        chain = [j]
        while massless(chain[-1].slave) and len(children.get(chain[-1].slave, [])) == 1:
            chain.append(children[chain[-1].slave][0])
        last = chain[-1].slave
        mass, c, I = props[last]
        if massless(last):
            what = ("has no child" if not children.get(last) else
                    f"carries {len(children[last])} bodies")
            raise ModelError(f"to_mjcf: body {last.name!r} is moved by a joint and has no mass and "
                             f"no inertia, and it {what}: MuJoCo refuses moving bodies without "
                             "mass; give it a mass and inertia (or remove it)")
        if not mass > MJ_MINVAL or np.linalg.eigvalsh(I).min() <= MJ_MINVAL:
            raise ModelError(f"to_mjcf: body {last.name!r} has mass {mass!r} and principal moments "
                             f"of inertia {np.linalg.eigvalsh(I).tolist()}: MuJoCo refuses a moving "
                             "body unless both are positive (a point mass or a slender rod is "
                             "refused); give it a positive mass and positive principal moments")
        out.append(f"{pad}<body name={quoteattr(last.name)} pos=\"{_vec(Pa + Ra @ pos)}\" "
                   f"quat=\"{_vec(_from_matrix(Ra @ R0))}\">")
        Pb, Rb = np.zeros(3), np.eye(3)
        for k, jj in enumerate(chain):
            pk, Rk, o1, u1 = placed(jj)
            if k:
                Pb, Rb = Pb + Rb @ pk, Rb @ Rk
            kind = "slide" if isinstance(jj, GenTranslate5) else "hinge"
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
            out.append(f"{pad}  <joint name={quoteattr(jn)} type=\"{kind}\" "
                       f"pos=\"{_vec(Pb + Rb @ o1)}\" axis=\"{_vec(Rb @ u1)}\"{extra}/>")
        Iw = Rb @ I @ Rb.T
        full = (Iw[0, 0], Iw[1, 1], Iw[2, 2], Iw[0, 1], Iw[0, 2], Iw[1, 2])
        out.append(f"{pad}  <inertial pos=\"{_vec(Pb + Rb @ c)}\" mass=\"{_num(mass)}\" "
                   f"fullinertia=\"{_vec(full)}\"/>")
        for k in children.get(last, []):
            body(k, depth + 1, Pb, Rb)
        out.append(f"{pad}</body>")

    for j in children.get(None, []):
        body(j, 2, np.zeros(3), np.eye(3))
    out += ["  </worldbody>", "</mujoco>"]
    p = Path(path)
    p.write_text("\n".join(out) + "\n", encoding="utf-8")
    return p
