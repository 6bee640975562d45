r"""URDF import: ``ms.from_urdf(path)`` builds a :class:`~mechsys.Model3D` of a robot description.

Frames (decision 0040). A URDF link has its own frame; a joint's ``<origin xyz rpy>`` places
the joint frame in the parent link's frame, and at zero joint coordinate the child link's
frame *is* the joint frame. ``rpy`` are fixed-axis X-Y-Z angles:

.. math::

    R(r, p, y) = R_z(y)\, R_y(p)\, R_x(r)

A revolute joint turns the child about the unit ``axis`` (joint-frame components) by ``q``,
a prismatic one slides it by ``q`` along ``axis``:

.. math::

    T_{\mathrm{child}} &= T_{\mathrm{parent}}\, (\mathit{xyz}, R(\mathit{rpy}))\,
        (0, \operatorname{Rot}(\mathit{axis}, q)) \qquad \text{(revolute, continuous)} \\
    T_{\mathrm{child}} &= T_{\mathrm{parent}}\, (\mathit{xyz}, R(\mathit{rpy}))\,
        (q\, \mathit{axis}, I) \qquad \text{(prismatic)}

Each moving link (with the links fixed to it, merged) is one mechsys body whose local frame
is the link's frame; a revolute joint becomes ``GenRevolute5(child.axis(0, a, g),
parent.axis(xyz, R a, R g))`` (``g`` a unit vector normal to ``a``), which gives exactly
the pose above, and a prismatic one ``GenTranslate5`` with the same axes. The coordinate is
named after the joint (``sol["shoulder_pan_joint"]``). A ``<inertial>`` with origin
``(c, R_i)`` and tensor ``I_i`` gives the centroid ``c`` and the centroidal inertia :math:`R_i I_i R_i^T` in
link axes; links fixed to a body add theirs by the parallel-axis theorem.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._errors import ModelError
from .._symbols import velocity_symbol
from ._xml import Element, floats, read_xml, where


def rpy_matrix(rpy) -> np.ndarray:
    """``R = Rz(y) Ry(p) Rx(r)``: URDF's fixed-axis roll, pitch, yaw."""
    r, p, y = rpy
    cr, sr, cp, sp_, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp_ * sr - sy * cr, cy * sp_ * cr + sy * sr],
                     [sy * cp, sy * sp_ * sr + cy * cr, sy * sp_ * cr - cy * sr],
                     [-sp_, cp * sr, cp * cr]])


def normal_to(a: np.ndarray) -> np.ndarray:
    """A unit vector normal to the unit vector ``a`` (the joint axes' reference direction):
    ``x`` made normal, or ``y`` when ``a`` is near ``x``."""
    e = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    g = e - (e @ a) * a
    return g / np.linalg.norm(g)


def add_joint(m, kind: str, slave, master, o1, a, g, o2, a2, g2, name: str, guess: float = 0.0,
              absolute: bool = False):
    r"""One joint of an imported file between the axes ``slave.axis(o1, a, g)`` and
    ``master.axis(o2, a2, g2)`` (``kind`` ``"revolute"`` or ``"prismatic"``), its coordinate
    named ``name``.

    Generalized coordinates: ``GenRevolute5`` / ``GenTranslate5``. Absolute coordinates
    (decision 0048): ``Revolute5`` / ``Translate5`` between the same axes and the joint
    coordinate ``q`` as a new variable of a ``Constraint`` (so ``sol[name]`` and joint
    forces keep their names); with ``g_1 = A_s g``, ``g_2 = A_m g2``, ``k_2 = A_m (a2 x g2)``
    (unit) and the axes' global origins ``o_1``, ``o_2``:

    .. math::

        \cos q\,(k_2 \cdot g_1) - \sin q\,(g_2 \cdot g_1) = 0 \quad\text{(revolute)},
        \qquad (A_m a_2) \cdot (o_1 - o_2) - q = 0 \quad\text{(prismatic)}

    the same pose ``A_s = A_m R_0 \mathrm{Rot}(a, q)`` (or the shift ``q a``) as the Gen
    joint."""
    import sympy as sp

    from .. import constraints as C

    tup = lambda v: tuple(float(x) for x in v)  # noqa: E731
    ax1 = slave.axis(tup(o1), tup(a), tup(g))
    ax2 = master.axis(tup(o2), tup(a2), tup(g2))
    if not absolute:
        cls = C.GenTranslate5 if kind == "prismatic" else C.GenRevolute5
        m.add(cls(ax1, ax2, (name, float(guess))), name=name)
        return
    cls = C.Translate5 if kind == "prismatic" else C.Revolute5
    m.add(cls(ax1, ax2), name=name)
    q = sp.Symbol(name)

    def glob(body, v):
        v = sp.Matrix([sp.Float(float(x)) for x in v])
        return v if body.is_ground else body.A * v

    def at(body, o):
        return glob(body, o) if body.is_ground else body.r + glob(body, o)

    a2n = np.asarray(a2, float) / np.linalg.norm(a2)
    if kind == "prismatic":
        eq = glob(master, a2n).dot(at(slave, o1) - at(master, o2)) - q
    else:
        g1w, g2w = glob(slave, g), glob(master, g2)
        k2 = glob(master, np.cross(a2n, g2))
        eq = sp.cos(q) * k2.dot(g1w) - sp.sin(q) * g2w.dot(g1w)
    m.add(C.Constraint([eq], {q: float(guess)}), name=f"{name}_coordinate")


@dataclass(frozen=True)
class ImportReport:
    """What an import read and what it could not map.

    ``joints``: joint name -> ``(type, coordinate names, child body)``; ``frames``: link
    name -> ``(body name, origin (3,), rotation (3, 3))``, the link's frame on the mechsys
    body that carries it (links joined by fixed joints are merged into one body);
    ``limits``: joint name -> ``(lower, upper, effort, velocity)`` (``None`` where absent);
    ``damping``/``friction``: joint name -> value; ``not_mapped``: one line per item of the
    file that has no counterpart in the model (with its line)."""

    source: str
    format: str
    robot: str
    joints: dict = field(default_factory=dict)
    frames: dict = field(default_factory=dict)
    limits: dict = field(default_factory=dict)
    damping: dict = field(default_factory=dict)
    friction: dict = field(default_factory=dict)
    not_mapped: tuple = ()

    def __str__(self) -> str:
        lines = [f"{self.format} import of {self.robot!r} from {self.source}: "
                 f"{len(self.joints)} joints, {len(self.frames)} link frames"]
        lines += [f"  not mapped: {s}" for s in self.not_mapped]
        return "\n".join(lines)


@dataclass
class _Link:
    name: str
    el: Element
    mass: float = 0.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    visuals: list = field(default_factory=list)
    collisions: list = field(default_factory=list)


@dataclass
class _Joint:
    name: str
    el: Element
    type: str
    parent: str
    child: str
    xyz: np.ndarray
    R: np.ndarray
    axis: np.ndarray


_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def _origin(source, el: Element | None):
    o = el.find("origin") if el is not None else None
    if o is None:
        return np.zeros(3), np.eye(3)
    return np.array(floats(source, o, "xyz", 3, [0.0, 0.0, 0.0])), rpy_matrix(
        floats(source, o, "rpy", 3, [0.0, 0.0, 0.0]))


def _read_link(source, el: Element) -> _Link:
    link = _Link(el.get("name"), el)
    ine = el.find("inertial")
    if ine is not None:
        mel = ine.find("mass")
        if mel is None:
            raise ModelError(f"{where(source, ine)}: an <inertial> without <mass value=...>")
        mass = floats(source, mel, "value", 1)
        if mass is None or mass[0] < 0:
            raise ModelError(f"{where(source, mel)}: the mass needs a value >= 0")
        link.mass = mass[0]
        c, R = _origin(source, ine)
        iel = ine.find("inertia")
        if iel is None:
            raise ModelError(f"{where(source, ine)}: an <inertial> without <inertia ixx=... izz=...>")
        v = {k: floats(source, iel, k, 1, [0.0])[0] for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        Ii = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]],
                       [v["ixz"], v["iyz"], v["izz"]]])
        link.com = c
        link.inertia = R @ Ii @ R.T
    for tag, out in (("visual", link.visuals), ("collision", link.collisions)):
        for vis in el.findall(tag):
            geo = vis.find("geometry")
            if geo is None or not geo.children:
                continue
            xyz, R = _origin(source, vis)
            out.append((geo.children[0], xyz, R))
    return link


def _read_joint(source, el: Element, links: dict) -> _Joint:
    name, typ = el.get("name"), el.get("type")
    if not name:
        raise ModelError(f"{where(source, el)}: a joint without a name")
    if typ not in _TYPES:
        raise ModelError(f"{where(source, el)}: joint type {typ!r} is not a URDF joint type "
                         f"({', '.join(_TYPES)})")
    ends = []
    for tag in ("parent", "child"):
        e = el.find(tag)
        if e is None or e.get("link") is None:
            raise ModelError(f"{where(source, el)}: the joint needs <{tag} link=...>")
        if e.get("link") not in links:
            raise ModelError(f"{where(source, e)}: link {e.get('link')!r} is not a <link> of the file")
        ends.append(e.get("link"))
    xyz, R = _origin(source, el)
    ax = el.find("axis")
    a = np.array(floats(source, ax, "xyz", 3, [1.0, 0.0, 0.0]) if ax is not None else [1.0, 0.0, 0.0])
    if typ in ("revolute", "continuous", "prismatic", "planar"):
        nrm = np.linalg.norm(a)
        if nrm < 1e-12:
            raise ModelError(f"{where(source, ax or el)}: the joint axis is zero; give a direction")
        a = a / nrm
    return _Joint(name, el, typ, ends[0], ends[1], xyz, R, a)


def _tree(source, robot: Element, links: dict, joints: list):
    """Root link and the children of each link (one parent per link, no loop)."""
    parent_of: dict = {}
    for j in joints:
        if j.child in parent_of:
            raise ModelError(f"{where(source, j.el)}: link {j.child!r} is already the child of joint "
                             f"{parent_of[j.child].name!r}; a URDF is a tree (one parent per link)")
        parent_of[j.child] = j
    roots = [n for n in links if n not in parent_of]
    if len(roots) != 1:
        raise ModelError(f"{source}: a URDF has one root link (a link no joint has as child); "
                         f"found {len(roots)}: {roots[:10]}" + (" (a loop of joints?)" if not roots else ""))
    children: dict = {n: [] for n in links}
    for j in joints:
        children[j.parent].append(j)
    seen, stack = set(), [roots[0]]
    while stack:
        n = stack.pop()
        seen.add(n)
        stack += [j.child for j in children[n]]
    if len(seen) != len(links):
        loose = sorted(set(links) - seen)[:10]
        raise ModelError(f"{source}: links {loose} are not reached from the root {roots[0]!r} "
                         "(their joints form a loop)")
    return roots[0], children


def from_urdf(path, *, floating_base: bool = False, gravity: float = 9.81,
              joint_damping: bool = False, mimic: bool = False, geometry: bool = True,
              coordinates: str = "generalized", backend: str | None = None):
    r"""A :class:`~mechsys.Model3D` of the URDF robot description ``path``.

    Every joint that moves becomes a generalized-coordinate joint named after it (revolute
    and continuous: ``GenRevolute5``; prismatic: ``GenTranslate5``), links joined by fixed
    joints one body (their frames kept in ``m.import_report.frames`` and as points of the
    body named after the link), gravity ``-gravity`` along ``z``. The root link is fixed to
    ground, or with ``floating_base=True`` a free body with its own (absolute) coordinates
    ``x, y, z, e0..e3``, as is the child of a ``floating`` joint (below the root its
    coordinates are global, noted in the report). A ``planar`` joint gives three
    coordinates ``name_x``, ``name_y`` (slides along ``g`` and ``a x g`` of the joint frame,
    ``g`` the axis' reference direction: ``x``, ``y`` for ``axis = z``) and ``name_theta``
    (the turn about the axis) on massless intermediate bodies. ``joint_damping``
    adds the joints' ``<dynamics damping>`` as loads :math:`-d\, \dot q`, ``mimic`` the
    ``<mimic>`` relations as constraints
    :math:`q = \mathit{multiplier}\; q_\text{other} + \mathit{offset}`; limits, friction and
    everything else without a counterpart are listed in ``m.import_report`` (an
    :class:`ImportReport`). ``geometry``: attach the visual shapes for drawing (boxes,
    cylinders, spheres; meshes as their triangles when the file is STL or OBJ and found --
    a visual mesh in another format by the link's collision mesh -- else noted).

    ``coordinates="absolute"``: every moving link an absolute body (``x, y, z, e0..e3``,
    guessed at its pose at zero joint coordinates) and each joint ``Revolute5`` /
    ``Translate5`` with its coordinate, named after it, defined by one more equation
    (:func:`add_joint`): the same robot, its joint forces from ``m.inverse_dynamics`` on the
    augmented system (decision 0048).

    Files are read safely (no entity expansion, a size limit, regular files only); a bad
    element raises ``ModelError`` naming the element and its line.

    Example::

        m = ms.from_urdf("ur5_robot.urdf")
        m.inverse_dynamics(q, qd, qdd)["shoulder_pan_joint"]
    """
    import sympy as sp

    from .. import constraints as C
    from .. import loads as L
    from .._errors import OptionError
    from ..model import Model3D

    if coordinates not in ("generalized", "absolute"):
        raise OptionError(f"from_urdf: coordinates={coordinates!r} is 'generalized' or 'absolute'")
    absolute = coordinates == "absolute"
    robot, source = read_xml(path)
    if robot.tag != "robot":
        raise ModelError(f"{where(source, robot)}: a URDF's root element is <robot>, not <{robot.tag}>")
    notes: list[str] = []
    links: dict = {}
    for el in robot.findall("link"):
        name = el.get("name")
        if not name:
            raise ModelError(f"{where(source, el)}: a link without a name")
        if name in links:
            raise ModelError(f"{where(source, el)}: a second link named {name!r}; link names are unique")
        links[name] = _read_link(source, el)
    if not links:
        raise ModelError(f"{where(source, robot)}: the robot has no <link>")
    joints = [_read_joint(source, el, links) for el in robot.findall("joint")]
    names = [j.name for j in joints]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        raise ModelError(f"{source}: joint names {sorted(dup)} repeat; joint names are unique")
    for el in robot.children:
        if el.tag not in ("link", "joint"):
            notes.append(f"line {el.line}: {el.label()} (no counterpart; ignored)")
    root, children = _tree(source, robot, links, joints)

    # segments: a moving link and the links fixed to it, merged on one body
    m = Model3D(backend=backend)
    frames: dict = {root: (None, np.zeros(3), np.eye(3))}     # link -> (segment link, p, R)
    seg_links: dict = {root: [root]}
    movable: list[_Joint] = []
    # depth first, children in file order: the coordinates come in the order Pinocchio and
    # MuJoCo give them (each joint's subtree before its next sibling)
    order: list = []
    stack: list = [(root, None)]
    while stack:
        n, j = stack.pop()
        order.append(n)
        if j is not None:
            seg, p, R = frames[j.parent]
            seg = j.parent if seg is None else seg
            if j.type == "fixed":
                frames[n] = (seg, p + R @ j.xyz, R @ j.R)
                seg_links[seg].append(n)
            else:
                frames[n] = (None, np.zeros(3), np.eye(3))
                seg_links[n] = [n]
                movable.append(j)
        stack += [(jj.child, jj) for jj in reversed(children[n])]
    frames[root] = (root, np.zeros(3), np.eye(3))
    for n in order:
        if frames[n][0] is None:
            frames[n] = (n, np.zeros(3), np.eye(3))

    bodies: dict = {}
    report_frames: dict = {}

    def make_body(seg: str, guess=None):
        mass, mc, Ic = 0.0, np.zeros(3), np.zeros((3, 3))
        parts = []
        for n in seg_links[seg]:
            lk = links[n]
            _, p, R = frames[n]
            if lk.mass > 0 or np.any(lk.inertia):
                parts.append((lk.mass, p + R @ lk.com, R @ lk.inertia @ R.T))
        mass = sum(pm for pm, _, _ in parts)
        if mass > 0:
            mc = sum(pm * c for pm, c, _ in parts) / mass
        for pm, c, Ii in parts:
            d = c - mc
            Ic = Ic + Ii + pm * (d @ d * np.eye(3) - np.outer(d, d))
        Ic = 0.5 * (Ic + Ic.T)
        pts = {n: tuple(float(v) for v in frames[n][1]) for n in seg_links[seg]}
        try:
            b = m.add_body(seg, points=pts, guess=guess, mass=mass,
                           centroid=tuple(float(v) for v in mc), inertia=Ic.tolist())
        except ModelError as exc:
            raise ModelError(f"{where(source, links[seg].el)}: {exc}") from None
        return b

    if floating_base:
        bodies[root] = make_body(root, guess=((0, 0, 0), (1, 0, 0, 0)))
    else:
        bodies[root] = m.ground
    from ..geometry._rotations import _from_matrix

    seg_world: dict = {root: (np.zeros(3), np.eye(3))}    # segment frames at q = 0
    report_joints: dict = {}
    limits: dict = {}
    damping: dict = {}
    friction: dict = {}
    mimics: list = []
    for j in movable:
        pseg, pp, pR = frames[j.parent]
        master = bodies[pseg]
        o2 = pp + pR @ j.xyz
        RR = pR @ j.R
        wp, wR = seg_world[pseg]
        seg_world[j.child] = (wp + wR @ o2, wR @ RR)
        pose0 = (tuple(float(v) for v in seg_world[j.child][0]),
                 tuple(float(v) for v in _from_matrix(seg_world[j.child][1])))
        if j.type in ("floating", "planar"):
            for tag in ("limit", "dynamics", "mimic", "safety_controller", "calibration"):
                e = j.el.find(tag)
                if e is not None:
                    notes.append(f"line {e.line}: joint {j.name!r} <{tag}> (not mapped on a "
                                 f"{j.type} joint; ignored)")
        if j.type == "floating":
            # a floating joint transmits no load: its child is a free body; below the root
            # its coordinates are global (x, y, z, e0..e3), not relative to the parent link
            bodies[j.child] = b = make_body(j.child, guess=pose0)
            report_joints[j.name] = (j.type, tuple(s.name for s in b.q), j.child)
            if master is not m.ground:
                notes.append(f"line {j.el.line}: floating joint {j.name!r} below the root: link "
                             f"{j.child!r} is a free body whose coordinates are global, not "
                             f"relative to link {j.parent!r}")
            continue
        if j.type == "planar":
            # motion in the plane normal to the axis: slides x, y along e1 = g (normal to the
            # axis) and e2 = a x g on massless intermediate bodies, then a turn about the
            # axis: T = T_origin Trans(x e1 + y e2) Rot(a, theta)
            a = j.axis
            e1 = normal_to(a)
            e2 = np.cross(a, e1)
            names_ = [f"{j.name}_x", f"{j.name}_y", f"{j.name}_theta"]
            slide1 = m.add_body(f"{j.child}/{names_[0]}", mass=0, guess=pose0 if absolute else None)
            slide2 = m.add_body(f"{j.child}/{names_[1]}", mass=0, guess=pose0 if absolute else None)
            child = make_body(j.child, guess=pose0 if absolute else None)
            bodies[j.child] = child
            try:
                add_joint(m, "prismatic", slide1, master, (0, 0, 0), e1, a, o2, RR @ e1, RR @ a,
                          names_[0], 0.0, absolute)
                add_joint(m, "prismatic", slide2, slide1, (0, 0, 0), e2, a, (0, 0, 0), e2, a,
                          names_[1], 0.0, absolute)
                add_joint(m, "revolute", child, slide2, (0, 0, 0), a, e1, (0, 0, 0), a, e1,
                          names_[2], 0.0, absolute)
            except ModelError as exc:
                raise ModelError(f"{where(source, j.el)}: {exc}") from None
            report_joints[j.name] = (j.type, tuple(names_), j.child)
            notes.append(f"line {j.el.line}: planar joint {j.name!r}: coordinates {names_} (slides "
                         f"along {tuple(float(v) for v in e1)} and {tuple(float(v) for v in e2)} "
                         "of the joint frame, then the turn about the axis)")
            continue
        a = j.axis
        g = normal_to(a)
        child = make_body(j.child, guess=pose0 if absolute else None)
        bodies[j.child] = child
        try:
            add_joint(m, "prismatic" if j.type == "prismatic" else "revolute", child, master,
                      (0, 0, 0), a, g, o2, RR @ a, RR @ g, j.name, 0.0, absolute)
        except ModelError as exc:
            raise ModelError(f"{where(source, j.el)}: {exc}") from None
        report_joints[j.name] = (j.type, (j.name,), j.child)
        lim = j.el.find("limit")
        if lim is not None:
            vals = tuple((floats(source, lim, kk, 1) or [None])[0]
                         for kk in ("lower", "upper", "effort", "velocity"))
            limits[j.name] = vals
        dyn = j.el.find("dynamics")
        if dyn is not None:
            d = floats(source, dyn, "damping", 1, [0.0])[0]
            f = floats(source, dyn, "friction", 1, [0.0])[0]
            if d:
                damping[j.name] = d
                if joint_damping:
                    m.add_load(L.Load(sp.Symbol(j.name), -d * velocity_symbol(j.name)),
                               name=f"{j.name}_damping")
                else:
                    notes.append(f"line {dyn.line}: joint {j.name!r} damping {d} (reported; "
                                 "joint_damping=True adds it as a load)")
            if f:
                friction[j.name] = f
                notes.append(f"line {dyn.line}: joint {j.name!r} friction {f} (no counterpart; ignored)")
        for tag in ("safety_controller", "calibration"):
            e = j.el.find(tag)
            if e is not None:
                notes.append(f"line {e.line}: joint {j.name!r} <{tag}> (no counterpart; ignored)")
        e = j.el.find("mimic")
        if e is not None:
            if mimic:
                mimics.append((j, e))
            else:
                notes.append(f"line {e.line}: joint {j.name!r} <mimic> (reported; mimic=True adds "
                             "it as a constraint)")
    for j, e in mimics:        # q = multiplier q_other + offset, once every joint exists
        other = e.get("joint")
        if other not in report_joints or report_joints[other][0] not in ("revolute", "continuous",
                                                                         "prismatic"):
            raise ModelError(f"{where(source, e)}: mimic joint {other!r} is not a moving joint of the file")
        k_ = floats(source, e, "multiplier", 1, [1.0])[0]
        off = floats(source, e, "offset", 1, [0.0])[0]
        m.add(C.Constraint(sp.Symbol(j.name) - k_ * sp.Symbol(other) - off), name=f"{j.name}_mimic")
    # link frames on their bodies
    for n in order:
        seg, p, R = frames[n]
        b = bodies[seg]
        report_frames[n] = (b.name, p.copy(), R.copy())
    if gravity:
        m.add_load(L.Gravity((0, 0, -1), float(gravity)), name="gravity")
    if geometry:
        notes += _attach_geometry(m, source, links, frames, bodies)
    m.import_report = ImportReport(source, "URDF", robot.get("name", ""), report_joints, report_frames,
                                   limits, damping, friction, tuple(notes))
    return m


# -- geometry for drawing ------------------------------------------------------------------------
#: meshes with more triangles are drawn as their bounding box (a picture of a robot stays quick)
MAX_DRAWN_TRIANGLES = 20000


def read_mesh(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """``(vertices (k, 3), faces (f, 3) int)`` of an STL (binary or ASCII), OBJ or MSH file
    for drawing, or None when it cannot be read (:func:`mechsys.io._mesh.load_mesh`, whose
    errors are for the mass properties)."""
    from ._mesh import load_mesh

    try:
        return load_mesh(path)
    except ModelError:
        return None


def _mesh_bounds(path: Path) -> np.ndarray | None:
    """``(2, 3)`` bounding box of an STL or OBJ file's vertices, or None."""
    got = read_mesh(path)
    if got is None or not np.all(np.isfinite(got[0])):
        return None
    return np.array([got[0].min(axis=0), got[0].max(axis=0)])


def _mesh_bounds_of(source: str, geo) -> np.ndarray | None:
    path = _resolve(source, geo.get("filename", ""))
    return _mesh_bounds(path) if path is not None else None


def _resolve(source: str, filename: str) -> Path | None:
    """A mesh file name (``package://pkg/rest``, ``file://...``, relative) as a path beside
    the URDF, searching the URDF's folder and its parents for ``pkg``."""
    base = Path(source).resolve().parent
    if filename.startswith("package://"):
        rest = filename[len("package://"):]
        for d in (base, *base.parents):
            cand = d / rest
            if cand.is_file():
                return cand
            # the package folder itself may be an ancestor (package://pkg/x with .../pkg/urdf)
            pkg, _, tail = rest.partition("/")
            if d.name == pkg and (d / tail).is_file():
                return d / tail
        return None
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    p = Path(filename)
    p = p if p.is_absolute() else base / p
    return p if p.is_file() else None


def _attach_geometry(m, source, links, frames, bodies) -> list[str]:
    from .. import draw

    notes, prims = [], []
    for name, lk in links.items():
        seg, p, R = frames[name]
        b = bodies[seg]
        shapes = list(lk.visuals)
        unread = [g for g, _, _ in shapes if g.tag == "mesh"
                  and _mesh_bounds_of(source, g) is None]
        if unread:
            # a visual mesh this reader cannot open (COLLADA, ...): the link's collision
            # meshes (usually STL) are drawn instead
            coll = [c for c in lk.collisions
                    if c[0].tag == "mesh" and _mesh_bounds_of(source, c[0]) is not None]
            if coll:
                shapes = [v for v in shapes if v[0] not in unread] + coll
                notes.append(f"line {unread[0].line}: visual mesh of link {name!r} drawn from its "
                             "collision mesh")
        for geo, xyz, Rv in shapes:
            c = p + R @ xyz
            Rt = R @ Rv
            if geo.tag == "sphere":
                r = floats(source, geo, "radius", 1)
                prims.append(draw.Sphere(b, b.point(tuple(c)), r[0]))
                continue
            if geo.tag == "cylinder":
                r, ln = floats(source, geo, "radius", 1), floats(source, geo, "length", 1)
                h = Rt[:, 2] * ln[0] / 2
                prims.append(draw.Cylinder(b, b.point(tuple(c - h)), b.point(tuple(c + h)), r[0]))
                continue
            if geo.tag == "box":
                lo, hi = -np.array(floats(source, geo, "size", 3)) / 2, None
                hi = -lo
            elif geo.tag == "mesh":
                fn = geo.get("filename", "")
                path = _resolve(source, fn)
                got = read_mesh(path) if path is not None else None
                if got is None or not np.all(np.isfinite(got[0])):
                    notes.append(f"line {geo.line}: mesh {fn!r} of link {name!r} not drawn "
                                 "(only STL and OBJ files found beside the URDF are read)")
                    continue
                scale = np.array(floats(source, geo, "scale", 3, [1.0, 1.0, 1.0]))
                V, F = got
                if len(F) <= MAX_DRAWN_TRIANGLES:
                    # the triangles themselves, in the body's coordinates
                    prims.append(draw.Mesh(b, c + (V * scale) @ Rt.T, F))
                    continue
                notes.append(f"line {geo.line}: mesh {fn!r} of link {name!r} drawn as its bounding "
                             f"box ({len(F)} triangles > {MAX_DRAWN_TRIANGLES})")
                bounds = np.array([V.min(axis=0), V.max(axis=0)])
                lo, hi = np.minimum(bounds[0] * scale, bounds[1] * scale), np.maximum(
                    bounds[0] * scale, bounds[1] * scale)
            else:
                notes.append(f"line {geo.line}: visual <{geo.tag}> of link {name!r} not drawn")
                continue
            if np.allclose(Rt, np.eye(3)):
                prims.append(draw.Box(b, tuple(c + lo), tuple(c + hi)))
                continue
            corners = [c + Rt @ np.array([(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]])
                       for i in (0, 1) for j in (0, 1) for k in (0, 1)]
            for face in ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)):
                prims.append(draw.Facet([b.point(tuple(corners[f])) for f in face]))
    if prims:
        m.add_graphics(*prims)
    return notes
