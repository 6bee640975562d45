r"""MJCF import: ``ms.from_mjcf(path)`` builds a :class:`~mechsys.Model3D` of a MuJoCo model.

Frames (decision 0040). A ``<body pos quat>`` places the body's frame in its parent's; its
joints act in the body's frame, in the order written, about (hinge) or along (slide) their
``axis`` through their ``pos``:

.. math::

    T_{\mathrm{body}} &= T_{\mathrm{parent}}\, (\mathit{pos}, R)\, J_1(q_1)\, J_2(q_2) \cdots \\
    J(q) &= \operatorname{Trans}(p_j) \operatorname{Rot}(a, q) \operatorname{Trans}(-p_j)
        \quad \text{(hinge)}, \qquad J(q) = \operatorname{Trans}(q\, a) \quad \text{(slide)}

A hinge becomes ``GenRevolute5(body.axis(p_j, a, g), parent.axis(pos + R p_j, R a, R g))``,
a slide ``GenTranslate5`` with the same axes (``g`` normal to ``a``), each coordinate named
after its joint; a body with several joints gets a massless intermediate body per extra
joint. A ``ball`` or ``free`` joint makes the body an absolute body (``x, y, z, e0..e3``),
a ball joint adding ``Spherical3`` at its point. Orientations: ``quat`` (w x y z),
``axisangle``, ``euler`` (``compiler eulerseq``, lower case intrinsic, upper case extrinsic),
``xyaxes``, ``zaxis``; angles in degrees unless ``<compiler angle="radian">``.
``<inertial pos quat mass diaginertia | fullinertia>`` gives the centroid and the inertia
:math:`R \operatorname{diag}(I) R^T` (``fullinertia="Ixx Iyy Izz Ixy Ixz Iyz"``); without it the body's mass
comes from its geoms (sphere, box, cylinder, capsule, ellipsoid, mesh; ``mass`` or
``density``, default 1000) as MuJoCo's ``inertiafromgeom="auto"`` does. Equalities: ``connect`` ->
``Spherical3``, ``weld`` -> ``Spherical3`` + ``RotationLock3``, ``joint`` -> ``Constraint(q1
- poly(q2))`` (hard constraints here; MuJoCo's are soft, ``solref``/``solimp`` reported). A
weld between bodies locks their relative rotation at ``qpos0``; a weld between sites locks
the sites' frames together, as MuJoCo does: with ``F`` the MJCF body's frame in its mechsys
body's and ``S`` the site's, :math:`A_1 F_1 S_1 = A_2 F_2 S_2`, so ``RotationLock3`` of
body 1 to body 2 turned by :math:`F_2 S_2 S_1^T F_1^T` (decision 0067).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .._errors import ModelError
from .._symbols import acceleration_symbol, velocity_symbol
from ._mesh import INERTIA_MODES, hull_faces, load_mesh, mesh_mass_properties, signed_volume
from ._urdf import MAX_DRAWN_TRIANGLES, ImportReport, add_joint, normal_to
from ._xml import MAX_XML_BYTES, Element, floats, read_xml, where

#: ``<include>`` nesting deeper than this is refused (a cycle is refused before that)
MAX_INCLUDE_DEPTH = 16


def quat_matrix(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _axis_angle(a, angle) -> np.ndarray:
    a = np.asarray(a, float) / np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _at(source: str, el: Element) -> str:
    """``"line n"`` of an element of the main file, ``"file, line n"`` of an included one."""
    return f"line {el.line}" if el.source in (None, source) else f"{el.source}, line {el.line}"


class _Ctx:
    def __init__(self, source, root: Element):
        self.source = source
        self.degree = True
        self.eulerseq = "xyz"
        self.notes: list[str] = []
        self.totalmass: float | None = None      # <compiler settotalmass>
        for c in root.findall("compiler"):
            ang = c.get("angle")
            if ang is not None:
                if ang not in ("degree", "radian"):
                    raise ModelError(f"{where(source, c)}: angle={ang!r} is 'degree' or 'radian'")
                self.degree = ang == "degree"
            seq = c.get("eulerseq")
            if seq is not None:
                if len(seq) != 3 or any(ch not in "xyzXYZ" for ch in seq):
                    raise ModelError(f"{where(source, c)}: eulerseq={seq!r} is three of x y z X Y Z")
                self.eulerseq = seq
            if c.get("settotalmass") is not None:
                self.totalmass = floats(source, c, "settotalmass", 1)[0]
            ifg = c.get("inertiafromgeom")
            if ifg == "true":
                self.notes.append(f"{_at(source, c)}: inertiafromgeom='true' (inertials from geoms only "
                                  "where a body has none)")
        # default classes: name -> (parent name, {tag: attrs}), each class holding its
        # parent's values as they were when it was defined, over its own (as MuJoCo copies
        # the parent class into a new one): a later top-level <default> changes the main
        # class only, not the classes already derived from it
        self.defaults: dict = {}
        for d in root.findall("default"):
            self._read_default(d, None)

    def _read_default(self, d: Element, parent):
        name = d.get("class", "main" if parent is None else None)
        if name is None:
            raise ModelError(f"{where(self.source, d)}: a nested <default> needs class=...")
        if name in self.defaults and not (parent is None and name == "main"):
            raise ModelError(f"{where(self.source, d)}: default class {name!r} defined twice")
        if name not in self.defaults:
            inherited = self.defaults[parent][1] if parent is not None else {}
            self.defaults[name] = (parent, {tag: dict(a) for tag, a in inherited.items()})
        # a second top-level <default> (often from an <include>) is merged into the main
        # class, a later attribute replacing an earlier one, as MuJoCo does; the block's own
        # elements apply before its nested classes copy it (whatever their order in the file)
        own = self.defaults[name][1]
        for c in d.children:
            if c.tag != "default":
                own.setdefault(c.tag, {}).update(c.attrib)
        for c in d.findall("default"):
            self._read_default(c, name)

    def attrs(self, el: Element, cls: str | None) -> dict:
        """``el``'s attributes over those of its default class."""
        name = el.get("class", cls) or "main"
        if name not in self.defaults and name != "main":
            raise ModelError(f"{where(self.source, el)}: default class {name!r} is not defined")
        out: dict = dict(self.defaults.get(name, (None, {}))[1].get(el.tag, {}))
        out.update(el.attrib)
        return out

    def num(self, el, attrs, key, n, default=None):
        if key not in attrs:
            return default
        tmp = Element(el.tag, {key: attrs[key]}, el.line, source=el.source)
        tmp.attrib["name"] = el.get("name")
        if tmp.attrib["name"] is None:
            del tmp.attrib["name"]
        return floats(self.source, tmp, key, n)

    def angle(self, v: float) -> float:
        return math.radians(v) if self.degree else v

    def orientation(self, el, attrs) -> np.ndarray:
        given = [k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in attrs]
        if len(given) > 1:
            raise ModelError(f"{where(self.source, el)}: give one orientation, not {given}")
        if not given:
            return np.eye(3)
        k = given[0]
        if k == "quat":
            q = self.num(el, attrs, "quat", 4)
            if np.linalg.norm(q) < 1e-12:
                raise ModelError(f"{where(self.source, el)}: quat is zero")
            return quat_matrix(q)
        if k == "axisangle":
            v = self.num(el, attrs, "axisangle", 4)
            if np.linalg.norm(v[:3]) < 1e-12:
                raise ModelError(f"{where(self.source, el)}: axisangle has a zero axis")
            return _axis_angle(v[:3], self.angle(v[3]))
        if k == "euler":
            v = self.num(el, attrs, "euler", 3)
            R = np.eye(3)
            for ch, a in zip(self.eulerseq, v):
                E = _axis_angle(np.eye(3)["xyz".index(ch.lower())], self.angle(a))
                R = R @ E if ch.islower() else E @ R
            return R
        if k == "xyaxes":
            v = np.array(self.num(el, attrs, "xyaxes", 6))
            x = v[:3] / np.linalg.norm(v[:3])
            y = v[3:] - (v[3:] @ x) * x
            y /= np.linalg.norm(y)
            return np.column_stack([x, y, np.cross(x, y)])
        z = np.array(self.num(el, attrs, "zaxis", 3))
        z /= np.linalg.norm(z)
        c = z[2]
        axis = np.cross([0.0, 0.0, 1.0], z)
        s = np.linalg.norm(axis)
        if s < 1e-12:
            return np.eye(3) if c > 0 else _axis_angle((1, 0, 0), math.pi)
        return _axis_angle(axis / s, math.atan2(s, c))


# -- geom mass properties (MuJoCo's inertiafromgeom) ---------------------------------------------
def _geom_groups(groups) -> set:
    """``geom_groups`` of :func:`from_mjcf` as the set of group attributes drawn ("0" to "5")."""
    from .._errors import OptionError

    try:
        if isinstance(groups, (str, bytes)):
            raise TypeError
        got = {int(g) for g in groups}
        ok = all(float(g) == int(g) for g in groups)
    except (TypeError, ValueError):
        got, ok = set(), False
    if not ok or not got <= set(range(6)):
        raise OptionError(f"from_mjcf: geom_groups={groups!r} is a collection of MuJoCo geom groups, "
                          "whole numbers 0 to 5 (e.g. (0, 1, 2), what MuJoCo's viewer shows)")
    return {str(g) for g in got}


def _geom_frame(ctx, el, a):
    """``(pos, R, size list)`` of a geom; ``fromto`` for capsule/cylinder/box/ellipsoid."""
    size = ctx.num(el, a, "size", None, [])
    if "fromto" in a:
        ft = np.array(ctx.num(el, a, "fromto", 6))
        p0, p1 = ft[:3], ft[3:]
        d = p1 - p0
        L = np.linalg.norm(d)
        if L < 1e-12:
            raise ModelError(f"{where(ctx.source, el)}: fromto has coincident ends")
        z = d / L
        axis = np.cross([0.0, 0.0, 1.0], z)
        s = np.linalg.norm(axis)
        R = np.eye(3) if s < 1e-12 and z[2] > 0 else (_axis_angle((1, 0, 0), math.pi) if s < 1e-12
                                                      else _axis_angle(axis / s, math.atan2(s, z[2])))
        size = [size[0] if size else 0.0, L / 2] + (
            [size[0]] if a.get("type") in ("box", "ellipsoid") else [])
        return (p0 + p1) / 2, R, size
    return np.array(ctx.num(el, a, "pos", 3, [0.0, 0.0, 0.0])), ctx.orientation(el, a), size


def _geom_inertia(ctx, el, a, typ, size):
    """``(mass, diagonal inertia)`` about the geom's centre in its frame, or None."""
    need = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
    if typ not in need:
        return None
    if len(size) < need[typ]:
        raise ModelError(f"{where(ctx.source, el)}: a {typ} needs {need[typ]} size values")
    if typ == "sphere":
        r = size[0]
        vol = 4 / 3 * math.pi * r**3
        I = lambda m: [2 / 5 * m * r * r] * 3  # noqa: E731
    elif typ == "box":
        x, y, z = size[:3]
        vol = 8 * x * y * z
        I = lambda m: [m / 3 * (y * y + z * z), m / 3 * (x * x + z * z), m / 3 * (x * x + y * y)]  # noqa: E731
    elif typ == "ellipsoid":
        x, y, z = size[:3]
        vol = 4 / 3 * math.pi * x * y * z
        I = lambda m: [m / 5 * (y * y + z * z), m / 5 * (x * x + z * z), m / 5 * (x * x + y * y)]  # noqa: E731
    elif typ == "cylinder":
        r, h = size[:2]
        vol = math.pi * r * r * 2 * h
        I = lambda m: [m * (3 * r * r + 4 * h * h) / 12] * 2 + [m * r * r / 2]  # noqa: E731
    else:  # capsule: a cylinder of half-length h and two hemispheres
        r, h = size[:2]
        vc, vs = math.pi * r * r * 2 * h, 4 / 3 * math.pi * r**3
        vol = vc + vs

        def I(m):  # noqa: E743
            mc, ms_ = m * vc / vol, m * vs / vol
            # hemispheres: own inertia 83/320 m r^2 about their centroid (3r/8 from the base)
            # moved to the capsule's centre (h + 3r/8 away)
            d = h + 3 * r / 8
            perp = mc * (3 * r * r + 4 * h * h) / 12 + ms_ * (83 / 320 * r * r + d * d)
            return [perp, perp, mc * r * r / 2 + ms_ * 2 / 5 * r * r]
    if "mass" in a:
        mass = ctx.num(el, a, "mass", 1)[0]
    else:
        mass = ctx.num(el, a, "density", 1, [1000.0])[0] * vol
    return mass, np.array(I(mass))


def _flatten(ctx, el: Element, tag: str, cls):
    """The ``tag`` children of ``el``, through nested ``<frame pos quat childclass>``
    elements: ``(child, frame origin, frame rotation, default class)``."""
    out = []

    def walk(e, p, R, c):
        for ch in e.children:
            if ch.tag == tag:
                out.append((ch, p, R, c))
            elif ch.tag == "frame":
                fa = dict(ch.attrib)
                fp = np.array(ctx.num(ch, fa, "pos", 3, [0.0, 0.0, 0.0]))
                walk(ch, p + R @ fp, R @ ctx.orientation(ch, fa), ch.get("childclass", c))

    walk(el, np.zeros(3), np.eye(3), cls)
    return out


# -- the import ------------------------------------------------------------------------------------
def _expand_includes(root: Element, source: str) -> None:
    r"""Replace every ``<include file="f"/>`` under ``root`` by the children of ``f``'s
    ``<mujoco>`` root, as MuJoCo assembles its files before reading them (decision 0070).

    ``f`` is looked up in the main file's directory (MuJoCo's rule), then in the including
    file's directory (where MuJoCo 4 also looks). Each included file is read as the main
    one (:func:`~mechsys.io._xml.read_xml`: no declarations, size and element limits), the
    files together at most :data:`~mechsys.io._xml.MAX_XML_BYTES`; a file is included at most
    once (MuJoCo's rule), a cycle and nesting deeper than :data:`MAX_INCLUDE_DEPTH` are
    refused, and so is an included root other than ``<mujoco>`` and an empty one. Every
    element keeps its own file in ``Element.source``, so later errors name the file and line
    it was written on.
    """
    main = Path(source).resolve()
    base = main.parent
    seen: dict = {main: None}
    total = [main.stat().st_size]

    def expand(el: Element, chain: tuple) -> None:
        out = []
        for c in el.children:
            if c.tag != "include":
                expand(c, chain)
                out.append(c)
                continue
            fn = c.get("file")
            if not fn:
                raise ModelError(f"{where(source, c)}: an <include> needs file=...")
            here = Path(c.source or source).resolve().parent
            cands = [base / fn, here / fn]
            f = next((p.resolve() for p in cands if p.is_file()), None)
            if f is None:
                raise ModelError(f"{where(source, c)}: included file {fn!r} not found in "
                                 f"{base} (the main file's directory) or {here}")
            if f in chain:
                raise ModelError(f"{where(source, c)}: {fn!r} closes an include cycle ("
                                 "" + " -> ".join(p.name for p in chain) + f" -> {f.name})")
            if f in seen:
                raise ModelError(f"{where(source, c)}: {fn!r} is already included (a file is "
                                 "included at most once, as in MuJoCo)")
            if len(chain) > MAX_INCLUDE_DEPTH:
                raise ModelError(f"{where(source, c)}: includes nested deeper than "
                                 f"{MAX_INCLUDE_DEPTH} levels")
            total[0] += f.stat().st_size
            if total[0] > MAX_XML_BYTES:
                raise ModelError(f"{where(source, c)}: the included files together pass the "
                                 f"limit of {MAX_XML_BYTES} bytes for a robot description")
            sub, sub_source = read_xml(f)
            if sub.tag != "mujoco":
                raise ModelError(f"{where(sub_source, sub)}: an included file's root element is "
                                 f"<mujoco>, not <{sub.tag}> (included at {where(source, c)})")
            if not sub.children:
                raise ModelError(f"{where(sub_source, sub)}: the included file is empty (included "
                                 f"at {where(source, c)})")
            seen[f] = c
            expand(sub, chain + (f,))
            for k in sub.children:
                k.parent = el
                out.append(k)
        el.children = out

    expand(root, (main,))


def from_mjcf(path, *, gravity=None, joint_damping: bool = False, joint_springs: bool = False,
              geometry: bool = True, armature: bool = False, coordinates: str = "generalized",
              backend: str | None = None, geom_groups=(0, 1, 2)):
    r"""A :class:`~mechsys.Model3D` of the MJCF (MuJoCo) model ``path``.

    Hinge and slide joints become generalized-coordinate joints named after them
    (``sol["elbow"]``), ball and free joints absolute bodies (see the module doc); bodies take
    their ``<inertial>`` (or their geoms' mass as MuJoCo computes it); default classes,
    ``childclass``, ``<compiler angle eulerseq>``, ``<option gravity>`` and ``<include
    file>`` (nested; found beside the main file, else beside the including file; each file
    read as safely as the main one, decision 0070) are read; ``<compiler settotalmass>``
    scales the masses and inertias and ``<flag gravity="disable"/>`` drops gravity, as in
    MuJoCo;
    equality constraints ``connect``, ``weld`` and ``joint`` become mechsys constraints (so
    closed-loop models work). ``gravity``: a number overrides the file's magnitude (along
    the file's direction; default ``<option gravity>`` or 9.81 down ``z``).
    Geoms are kept for drawing: spheres, cylinders, capsules, boxes, ellipsoids, and meshes
    as the triangles of their STL, OBJ or MSH files (``<asset><mesh file scale refpos
    refquat>`` under the ``<compiler meshdir>``). A mesh geom's mass, centroid and inertia
    are those MuJoCo computes with the mesh's ``inertia`` mode (default ``legacy``; see
    :mod:`mechsys.io._mesh`, decision 0072); a mesh file that is missing, malformed, too
    large or encloses no volume is refused naming the file when a body's mass needs it.
    ``geom_groups``: the geom groups drawn (MuJoCo's ``group``, 0 to 5); the default
    ``(0, 1, 2)`` shows what MuJoCo's viewer shows by default (the Menagerie's files put
    their detailed visual meshes in group 2 and their coarse collision meshes in group 3:
    ``geom_groups=(3,)`` draws the latter); the number of geoms left out is in the import
    report. ``joint_damping`` adds ``damping`` as ``-d q_dot`` loads,
    ``joint_springs`` the hinge and slide springs ``-k (q - springref)`` (MuJoCo's passive
    forces), ``armature`` the joints' armature ``a`` as the load :math:`-a \ddot q` (MuJoCo
    adds ``a`` to the mass matrix's diagonal; so do mechsys's dynamics with it); ranges,
    friction loss, springs, armature (unless asked), actuators, sensors, contacts and
    everything else without a counterpart are listed in ``m.import_report``. Read safely, as
    ``from_urdf``.

    ``coordinates="absolute"``: every body with hinge or slide joints an absolute body
    (guessed at its pose at ``qpos0``) and each joint ``Revolute5`` / ``Translate5`` with its
    coordinate named after it (``from_urdf``'s :func:`~mechsys.io._urdf.add_joint`;
    decision 0048).
    """
    from .._errors import OptionError

    if coordinates not in ("generalized", "absolute"):
        raise OptionError(f"from_mjcf: coordinates={coordinates!r} is 'generalized' or 'absolute'")
    groups = _geom_groups(geom_groups)
    absolute = coordinates == "absolute"
    import sympy as sp

    from .. import constraints as C
    from .. import loads as L
    from ..model import Model3D

    root, source = read_xml(path)
    if root.tag != "mujoco":
        raise ModelError(f"{where(source, root)}: an MJCF's root element is <mujoco>, not <{root.tag}>")
    _expand_includes(root, source)
    ctx = _Ctx(source, root)
    notes = ctx.notes
    m = Model3D(backend=backend)
    g_vec = np.array([0.0, 0.0, -9.81])
    gravity_off = False
    for el in root.children:
        if el.tag == "option":
            g_vec = np.array(floats(source, el, "gravity", 3, list(g_vec)))
            for fl in el.findall("flag"):
                if fl.get("gravity") is not None:
                    # MuJoCo leaves gravity out of the dynamics: so does the import
                    gravity_off = fl.get("gravity") == "disable"
            for key in ("density", "viscosity", "wind", "magnetic"):
                v = floats(source, el, key, None, [])
                if v and any(v):
                    notes.append(f"{_at(ctx.source, el)}: <option {key}=...> (fluid or magnetic forces; "
                                 "no counterpart; ignored)")
        elif el.tag in ("actuator", "sensor", "contact", "tendon", "keyframe", "visual", "statistic",
                        "extension", "custom", "deformable", "size"):
            notes.append(f"{_at(ctx.source, el)}: {el.label()} (no counterpart; ignored)")
    wb = root.find("worldbody")
    if wb is None:
        raise ModelError(f"{where(source, root)}: the model has no <worldbody>")

    world_pose: dict = {"world": (np.zeros(3), np.eye(3))}   # at qpos0, for equalities
    sites: dict = {}
    joints_rep: dict = {}
    limits, damping, friction = {}, {}, {}
    prims: list = []
    hidden: dict = {}           # geom group -> geoms not drawn (not in geom_groups)
    count = [0]

    def add_geoms(el, body_name, cls):
        """Mass properties from the geoms (when needed) and drawing primitives."""
        parts = []
        for gel, fp, fR, gcls in _flatten(ctx, el, "geom", cls):
            a = ctx.attrs(gel, gcls)
            typ = a.get("type", "sphere")
            pos, R, size = _geom_frame(ctx, gel, a)
            parts.append((gel, a, typ, fp + fR @ pos, fR @ R, size))
        return parts

    def mesh_inertia(gel, a, body_name):
        """``(mass, centroid, inertia about it)`` of a mesh geom in its frame, by MuJoCo's
        ``<mesh inertia=...>`` mode (default ``legacy``), or None when massless."""
        if a.get("shellinertia") in ("true", "1"):
            raise ModelError(f"{where(source, gel)}: shellinertia on a mesh geom: give the mesh asset "
                             "inertia='shell' (MuJoCo refuses it on the geom too)")
        given = ctx.num(gel, a, "mass", 1)
        density = ctx.num(gel, a, "density", 1, [1000.0])[0]
        if (given is not None and given[0] == 0) or (given is None and density == 0):
            return None
        Vg, F, me, label = mesh_in_geom(gel, a)
        mode = mesh_assets[a["mesh"]][2].get("inertia", "legacy")
        if mode not in INERTIA_MODES:
            raise ModelError(f"{where(source, me)}: inertia={mode!r} is one of {', '.join(INERTIA_MODES)}")
        key = (a["mesh"], mode)
        if key not in mesh_cache:
            try:
                mesh_cache[key] = mesh_mass_properties(Vg, F, mode, label)
            except ModelError as exc:
                raise ModelError(f"{where(source, gel)}: {exc} (the mass of body {body_name!r})") from None
            vol_ = mesh_cache[key][0]
            if mode == "legacy":
                exact = signed_volume(Vg, F)
                if exact < 0:
                    notes.append(f"{_at(ctx.source, me)}: mesh {label!r} is wound inside out (signed volume "
                                 f"{exact:.4g}); MuJoCo's legacy inertia takes absolute volumes, so the "
                                 "solid's mass is used, as MuJoCo does")
                elif abs(vol_ - exact) > 1e-6 * vol_:
                    notes.append(f"{_at(ctx.source, me)}: mesh {label!r} is not convex: MuJoCo's legacy "
                                 f"inertia (the default, reproduced here) counts volume {vol_:.6g} against "
                                 f"the enclosed {exact:.6g}; inertia='exact' on the <mesh> gives the solid's")
        vol, cg, J = mesh_cache[key]
        gm = given[0] if given is not None else density * vol
        return gm, cg, J * (gm / vol)

    def mass_from_geoms(parts, body_name):
        mass, cs, Is = 0.0, [], []
        for gel, a, typ, pos, R, size in parts:
            if typ in ("plane", "hfield"):
                continue
            if typ == "mesh":
                got = mesh_inertia(gel, a, body_name)
                if got is None:
                    continue
                gm, cg, Jg = got
                mass += gm
                cs.append((gm, pos + R @ cg))
                Is.append((gm, pos + R @ cg, R @ Jg @ R.T))
                continue
            if a.get("mesh") is not None:
                raise ModelError(f"{where(source, gel)}: a {typ} geom fitted to mesh {a.get('mesh')!r} "
                                 "(MuJoCo's fitted primitives) is not read; give the body an <inertial>")
            got = _geom_inertia(ctx, gel, a, typ, size)
            if got is None:
                continue
            gm, Id = got
            if gm <= 0:
                continue
            mass += gm
            cs.append((gm, pos))
            Is.append((gm, pos, R @ np.diag(Id) @ R.T))
        if mass <= 0:
            return 0.0, np.zeros(3), np.zeros((3, 3))
        c = sum(gm * p for gm, p in cs) / mass
        I = np.zeros((3, 3))
        for gm, p, Ig in Is:
            d = p - c
            I += Ig + gm * (d @ d * np.eye(3) - np.outer(d, d))
        return mass, c, I

    def draw(parts, b):
        from .. import draw as D

        for gel, _a, typ, pos, R, size in parts:
            group = str(int(ctx.num(gel, _a, "group", 1, [0])[0]))
            if group not in groups:
                hidden[group] = hidden.get(group, 0) + 1
                continue
            if typ == "mesh":
                mesh_prims(D, gel, _a, pos, R, b)
                continue
            try:
                if typ == "sphere":
                    prims.append(D.Sphere(b, b.point(tuple(pos)), size[0]))
                elif typ in ("cylinder", "capsule"):
                    h = R[:, 2] * size[1]
                    prims.append(D.Cylinder(b, b.point(tuple(pos - h)), b.point(tuple(pos + h)), size[0]))
                elif typ in ("box", "ellipsoid"):
                    hs = np.array(size[:3])
                    corners = [pos + R @ (hs * np.array(s)) for s in
                               [(-1, -1, -1), (-1, -1, 1), (-1, 1, -1), (-1, 1, 1),
                                (1, -1, -1), (1, -1, 1), (1, 1, -1), (1, 1, 1)]]
                    for f in ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4),
                              (1, 3, 7, 5)):
                        prims.append(D.Facet([b.point(tuple(corners[i])) for i in f]))
            except (ModelError, IndexError):
                notes.append(f"{_at(ctx.source, gel)}: geom of type {typ!r} not drawn")

    # <asset><mesh>: name (default: the file's stem) -> (element, file, its attributes);
    # files are looked up in <compiler meshdir> (or assetdir) beside the model file, as
    # MuJoCo does
    meshdir = ""
    for c in root.findall("compiler"):
        meshdir = c.get("meshdir", c.get("assetdir", meshdir))
    mesh_assets: dict = {}
    for asset in root.findall("asset"):
        for me in asset.findall("mesh"):
            fn = me.get("file")
            name = me.get("name") or (Path(fn).stem if fn else None)
            if name:
                mesh_assets[name] = (me, fn, ctx.attrs(me, None))
    mesh_cache: dict = {}

    def mesh_in_geom(gel, a):
        """``(vertices in the geom's frame, faces, mesh element, label)`` of a mesh geom:
        the file's (or inline) vertices moved by ``-refpos``, turned by ``refquat``'s
        inverse and scaled, as MuJoCo places them before it moves the mesh to its
        principal frame and the geom by the opposite offset. Raises ModelError."""
        name = a.get("mesh", "")
        if name not in mesh_assets:
            raise ModelError(f"{where(source, gel)}: the mesh geom names no <asset><mesh> {name!r}")
        if name in mesh_cache:
            return mesh_cache[name]
        me, fn, ma = mesh_assets[name]
        if fn:
            label = fn
            try:
                V, F = load_mesh(Path(source).resolve().parent / meshdir / fn, label)
            except ModelError as exc:
                raise ModelError(f"{where(source, me)}: {exc}") from None
        else:
            label = name
            vv = ctx.num(me, ma, "vertex", None)
            if not vv or len(vv) % 3 or len(vv) < 12:
                raise ModelError(f"{where(source, me)}: mesh {name!r} has no file and no vertex list of "
                                 "at least four points (3 numbers each)")
            # MuJoCo keeps vertices in single precision
            V = np.array(vv, dtype=np.float32).astype(float).reshape(-1, 3)
            ff = ctx.num(me, ma, "face", None)
            if ff:
                if len(ff) % 3 or any(f_ != int(f_) or not 0 <= f_ < len(V) for f_ in ff):
                    raise ModelError(f"{where(source, me)}: mesh {name!r}: face is a list of vertex "
                                     f"numbers 0..{len(V) - 1}, three a triangle")
                F = np.array(ff, dtype=np.int64).reshape(-1, 3)
            else:
                F = hull_faces(V, name)       # MuJoCo: no faces -> the convex hull's
        refpos = np.array(ctx.num(me, ma, "refpos", 3, [0.0, 0.0, 0.0]))
        refq = ctx.num(me, ma, "refquat", 4, [1.0, 0.0, 0.0, 0.0])
        if np.linalg.norm(refq) < 1e-12:
            raise ModelError(f"{where(source, me)}: refquat is zero")
        scale = np.array(ctx.num(me, ma, "scale", 3, [1.0, 1.0, 1.0]))
        V = ((V - refpos) @ quat_matrix(refq)) * scale      # rows: R_ref^T (v - refpos), scaled
        if np.prod(scale) < 0:
            F = F[:, [0, 2, 1]]     # a mirroring scale turns the faces inside out: MuJoCo turns them back
        mesh_cache[name] = (V, F, me, label)
        return mesh_cache[name]

    def mesh_prims(D, gel, a, pos, R, b):
        """A mesh geom drawn as its triangles (its bounding box when it has more than
        ``MAX_DRAWN_TRIANGLES``) in the geom's frame (``mesh_in_geom``), where MuJoCo
        draws it too."""
        try:
            Vg, F, me, label = mesh_in_geom(gel, a)
        except ModelError as exc:
            notes.append(f"{_at(ctx.source, gel)}: mesh geom not drawn ({exc})")
            return
        V = pos + Vg @ R.T
        if len(F) <= MAX_DRAWN_TRIANGLES:
            prims.append(D.Mesh(b, V, F))
            return
        notes.append(f"{_at(ctx.source, gel)}: mesh {label!r} drawn as its bounding box ({len(F)} "
                     f"triangles > {MAX_DRAWN_TRIANGLES})")
        lo, hi = Vg.min(axis=0), Vg.max(axis=0)
        corners = [pos + R @ np.array([(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]])
                   for i in (0, 1) for j in (0, 1) for k in (0, 1)]
        for f in ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)):
            prims.append(D.Facet([b.point(tuple(corners[i])) for i in f]))

    # frame_of[MJCF body] = (mechsys body, origin, rotation): a body without joints is
    # merged into its parent's mechsys body (as URDF's fixed joints), ground included
    frame_of: dict = {"world": (m.ground, np.zeros(3), np.eye(3))}
    mass_parts: dict = {}
    body_line: dict = {}

    def visit(el: Element, parent: str, cls: str | None, fp, fR):
        name = el.get("name")
        if not name:
            count[0] += 1
            name = f"body{count[0]}"
        if name in world_pose:
            raise ModelError(f"{where(source, el)}: a second body named {name!r}")
        cls = el.get("childclass", cls)
        a = dict(el.attrib)
        pos = fp + fR @ np.array(ctx.num(el, a, "pos", 3, [0.0, 0.0, 0.0]))
        R = fR @ ctx.orientation(el, a)
        pr, pR = world_pose[parent]
        world_pose[name] = (pr + pR @ pos, pR @ R)
        if el.get("gravcomp") not in (None, "0", "0.0"):
            notes.append(f"{_at(ctx.source, el)}: body {name!r} gravcomp={el.get('gravcomp')} (gravity "
                         "compensation; no counterpart; ignored)")
        parts = add_geoms(el, name, cls)
        ine = el.find("inertial")
        if ine is not None:
            ia = dict(ine.attrib)
            mass = ctx.num(ine, ia, "mass", 1)
            if mass is None or mass[0] < 0:
                raise ModelError(f"{where(source, ine)}: an <inertial> needs mass >= 0")
            c = np.array(ctx.num(ine, ia, "pos", 3, [0.0, 0.0, 0.0]))
            Ri = ctx.orientation(ine, ia)
            if "fullinertia" in ia:
                xx, yy, zz, xy, xz, yz = ctx.num(ine, ia, "fullinertia", 6)
                I = Ri @ np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) @ Ri.T
            elif "diaginertia" in ia:
                I = Ri @ np.diag(ctx.num(ine, ia, "diaginertia", 3)) @ Ri.T
            else:
                raise ModelError(f"{where(source, ine)}: an <inertial> needs diaginertia or fullinertia")
            mass = mass[0]
        else:
            mass, c, I = mass_from_geoms(parts, name)
        pb, pp, pRm = frame_of[parent]
        P, RR = pp + pRm @ pos, pRm @ R                 # this body's frame in pb's
        kinds = []
        for j in el.children:
            if j.tag == "joint":
                ja = ctx.attrs(j, cls)
                kinds.append((j, ja, ja.get("type", "hinge")))
            elif j.tag == "freejoint":
                kinds.append((j, {}, "free"))
        free_body = any(k in ("ball", "free") for _, _, k in kinds)
        if free_body and len(kinds) > 1:
            raise ModelError(f"{where(source, el)}: a ball or free joint with other joints in one body "
                             "is not supported; give the body that joint alone")
        if not kinds:                                   # merged into the parent's body
            frame_of[name] = (pb, P, RR)
            if pb is not m.ground:
                mass_parts.setdefault(pb.name, []).append((mass, P + RR @ c, RR @ I @ RR.T))
            for st, sfp, sfR, scls in _flatten(ctx, el, "site", cls):
                if st.get("name"):
                    sa = ctx.attrs(st, scls)
                    sp_ = sfp + sfR @ np.array(ctx.num(st, sa, "pos", 3, [0.0, 0.0, 0.0]))
                    sites[st.get("name")] = (name, sp_, sfR @ ctx.orientation(st, sa))
            if geometry:
                draw([(g_, a_, t_, P + RR @ p_, RR @ R_, s_) for g_, a_, t_, p_, R_, s_ in parts], pb)
            for child, cfp, cfR, ccls in _flatten(ctx, el, "body", cls):
                visit(child, name, ccls, cfp, cfR)
            return
        wr, wR = world_pose[name]
        guess = None
        if free_body or absolute:
            from ..geometry._rotations import _from_matrix

            # at qpos0 every joint's transform is the identity (ref included): the holders'
            # frames are the body's
            guess = (tuple(float(v) for v in wr), tuple(float(v) for v in _from_matrix(wR)))
        # massless intermediate bodies for all but the last of several joints
        chain = [m.add_body(f"{name}/{kinds[k][0].get('name') or k}", mass=0,
                            guess=guess if absolute else None) for k in range(len(kinds) - 1)]
        pts = {}
        for st, sfp, sfR, scls in _flatten(ctx, el, "site", cls):
            if st.get("name"):
                sa = ctx.attrs(st, scls)
                sp_ = sfp + sfR @ np.array(ctx.num(st, sa, "pos", 3, [0.0, 0.0, 0.0]))
                sites[st.get("name")] = (name, sp_, sfR @ ctx.orientation(st, sa))
                pts[st.get("name")] = tuple(float(v) for v in sp_)
        try:
            b = m.add_body(name, points=pts or None, guess=guess)
        except ModelError as exc:
            raise ModelError(f"{where(source, el)}: {exc}") from None
        mass_parts[name] = [(mass, c, I)]
        body_line[name] = el
        frame_of[name] = (b, np.zeros(3), np.eye(3))
        holders = [*chain, b]
        master, m_origin, m_R = pb, P, RR               # the body frame in the master's
        for k, (j, ja, typ) in enumerate(kinds):
            jname = j.get("name")
            if typ == "free":
                if pb is not m.ground:
                    notes.append(f"{_at(ctx.source, j)}: free joint of body {name!r} on a moving body: "
                                 "the body is absolute (its coordinates are global)")
                joints_rep[jname or name] = ("free", tuple(s.name for s in b.q), name)
                continue
            if not jname:
                # MuJoCo allows unnamed joints; the coordinate needs a name: the body's and
                # the joint's place in it, said in the report
                jname = f"{name}_{typ}{k}"
                if jname in joints_rep:
                    raise ModelError(f"{where(source, j)}: an unnamed {typ} joint would be called "
                                     f"{jname!r}, which another joint is; name it")
                notes.append(f"{_at(ctx.source, j)}: unnamed {typ} joint of body {name!r}: its coordinate "
                             f"is named {jname!r}")
            jp = np.array(ctx.num(j, ja, "pos", 3, [0.0, 0.0, 0.0]))
            if typ == "ball":
                m.add(C.Spherical3(b.point(tuple(float(v) for v in jp)),
                                   master.point(tuple(float(v) for v in m_origin + m_R @ jp))), name=jname)
                joints_rep[jname] = ("ball", tuple(s.name for s in b.q), name)
                notes.append(f"{_at(ctx.source, j)}: ball joint {jname!r}: the body has absolute coordinates "
                             "and a Spherical3 (MuJoCo's quaternion qpos has no named counterpart)")
                continue
            if typ not in ("hinge", "slide"):
                raise ModelError(f"{where(source, j)}: joint type {typ!r} is not hinge, slide, ball or free")
            ax = np.array(ctx.num(j, ja, "axis", 3, [0.0, 0.0, 1.0]))
            if np.linalg.norm(ax) < 1e-12:
                raise ModelError(f"{where(source, j)}: the joint axis is zero")
            ax = ax / np.linalg.norm(ax)
            g = normal_to(ax)
            slave = holders[k]
            # ``ref``: the file's pose is at q = ref, so the joint moves by q - ref: the master's
            # reference direction turned by -ref (hinge) or its origin moved by -ref (slide)
            ref = ctx.num(j, ja, "ref", 1, [0.0])[0]
            g2, o2 = m_R @ g, m_origin + m_R @ jp
            if typ == "hinge" and ref:
                g2 = m_R @ _axis_angle(ax, -ctx.angle(ref)) @ g
            elif ref:
                o2 = o2 - ref * (m_R @ ax)
            ref0 = ctx.angle(ref) if typ == "hinge" else ref
            try:
                add_joint(m, "revolute" if typ == "hinge" else "prismatic", slave, master, jp, ax, g,
                          o2, m_R @ ax, g2, jname, ref0 if absolute else 0.0, absolute)
            except ModelError as exc:
                raise ModelError(f"{where(source, j)}: {exc}") from None
            joints_rep[jname] = (typ, (jname,), name)
            master, m_origin, m_R = slave, np.zeros(3), np.eye(3)
            rng = ctx.num(j, ja, "range", 2)
            if rng is not None:
                limits[jname] = tuple(ctx.angle(v) if typ == "hinge" else v for v in rng) + (None, None)
            k_ = ctx.num(j, ja, "stiffness", 1, [0.0])[0]
            sd = ctx.num(j, ja, "springdamper", 2, [0.0, 0.0])
            auto = sd[0] > 0 and sd[1] > 0
            if any(sd) and not auto:
                raise ModelError(f"{where(source, j)}: springdamper={sd} needs two positive numbers "
                                 "(time constant, damping ratio), as in MuJoCo")
            if auto:
                # MuJoCo replaces the joint's stiffness and damping by values it derives from
                # the joint's inertia in the whole model at qpos0 (its dof_invweight0), which
                # the importer does not compute: neither is added, and neither is the
                # stiffness or damping written (MuJoCo ignores them too)
                notes.append(f"{_at(ctx.source, j)}: joint {jname!r} springdamper={sd} (MuJoCo derives the "
                             "stiffness and damping from the joint's inertia at qpos0; not mapped: no "
                             "spring or damping on this joint)")
                k_ = 0.0
            if k_:
                sref = ctx.num(j, ja, "springref", 1, [0.0])[0]
                sref = ctx.angle(sref) if typ == "hinge" else sref
                if joint_springs:
                    m.add_load(L.Load(sp.Symbol(jname), -k_ * (sp.Symbol(jname) - sref)),
                               name=f"{jname}_spring")
                else:
                    notes.append(f"{_at(ctx.source, j)}: joint {jname!r} stiffness {k_} (reported; "
                                 "joint_springs=True adds it as a load)")
            arm = ctx.num(j, ja, "armature", 1)
            if arm is not None and arm[0] != 0:
                if armature:
                    # MuJoCo adds the armature to the mass matrix's diagonal: the generalized
                    # force -a qdd on the coordinate
                    m.add_load(L.Load(sp.Symbol(jname), -arm[0] * acceleration_symbol(jname)),
                               name=f"{jname}_armature")
                else:
                    notes.append(f"{_at(ctx.source, j)}: joint {jname!r} armature={arm[0]} (reported; "
                                 "armature=True adds it as the load -armature * qdd)")
            v = ctx.num(j, ja, "frictionloss", 1)
            if v is not None and v[0] != 0:
                friction[jname] = v[0]
                notes.append(f"{_at(ctx.source, j)}: joint {jname!r} frictionloss={v[0]} (no counterpart; "
                             "ignored)")
            d = ctx.num(j, ja, "damping", 1)
            if d is not None and d[0] and not auto:
                damping[jname] = d[0]
                if joint_damping:
                    m.add_load(L.Load(sp.Symbol(jname), -d[0] * velocity_symbol(jname)),
                               name=f"{jname}_damping")
                else:
                    notes.append(f"{_at(ctx.source, j)}: joint {jname!r} damping {d[0]} (reported; "
                                 "joint_damping=True adds it as a load)")
        if geometry:
            draw(parts, b)
        for child, cfp, cfR, ccls in _flatten(ctx, el, "body", cls):
            visit(child, name, ccls, cfp, cfR)

    for el, fp, fR, ccls in _flatten(ctx, wb, "body", wb.get("childclass")):
        visit(el, "world", ccls, fp, fR)
    total = sum(pm for parts_ in mass_parts.values() for pm, _, _ in parts_)
    if ctx.totalmass is not None and ctx.totalmass > 0 and total > 0:
        # <compiler settotalmass>: MuJoCo scales every body's mass and inertia by one factor
        # so that the masses add up to it (centroids unchanged)
        k_mass = ctx.totalmass / total
        mass_parts = {b: [(pm * k_mass, pc, pI * k_mass) for pm, pc, pI in parts_]
                      for b, parts_ in mass_parts.items()}
    for bname, parts_ in mass_parts.items():
        mass = sum(pm for pm, _, _ in parts_)
        c = sum(pm * pc for pm, pc, _ in parts_) / mass if mass > 0 else np.zeros(3)
        I = np.zeros((3, 3))
        for pm, pc, pI in parts_:
            d = pc - c
            I = I + pI + pm * (d @ d * np.eye(3) - np.outer(d, d))
        try:
            m.set_mass_properties(bname, mass=float(mass), centroid=tuple(float(v) for v in c),
                                  inertia=(0.5 * (I + I.T)).tolist())
        except ModelError as exc:
            raise ModelError(f"{where(source, body_line[bname])}: {exc}") from None
    # geoms and sites on the world body
    for st, sfp, sfR, scls in _flatten(ctx, wb, "site", None):
        if st.get("name"):
            sa = ctx.attrs(st, scls)
            sp_ = sfp + sfR @ np.array(ctx.num(st, sa, "pos", 3, [0.0, 0.0, 0.0]))
            sites[st.get("name")] = ("world", sp_, sfR @ ctx.orientation(st, sa))
    if geometry:
        draw([p for p in add_geoms(wb, "world", None) if p[2] != "plane"], m.ground)
    # equalities
    for eq in root.findall("equality"):
        for e in eq.children:
            _equality(ctx, m, e, frame_of, world_pose, sites, C, notes)
    if gravity_off:
        g_vec = np.zeros(3)
    gnorm = float(np.linalg.norm(g_vec))
    if gravity is not None:
        gnorm = float(gravity)
    if gnorm:
        m.add_load(L.Gravity(tuple(float(v) for v in g_vec) if np.linalg.norm(g_vec) else (0, 0, -1), gnorm),
                   name="gravity")
    if hidden:
        notes.append("geoms not drawn: " + ", ".join(f"{hidden[g]} of group {g}" for g in sorted(hidden))
                     + f" (geom_groups={tuple(int(g) for g in sorted(groups))}; MuJoCo's viewer also "
                     "hides groups 3 to 5 by default)")
    if prims:
        m.add_graphics(*prims)
    frames = {n: (b.name, p.copy(), R.copy()) for n, (b, p, R) in frame_of.items()}
    m.import_report = ImportReport(source, "MJCF", root.get("model", ""), joints_rep, frames, limits,
                                   damping, friction, tuple(notes))
    return m


def _rot_spec(R):
    from ..geometry._rotations import _from_matrix

    return tuple(float(v) for v in _from_matrix(R))


def _equality(ctx, m, e, frame_of, world_pose, sites, C, notes):
    import sympy as sp

    source = ctx.source
    name = e.get("name")
    if e.get("active", "true") == "false":
        notes.append(f"{_at(ctx.source, e)}: inactive equality {e.label()} (ignored)")
        return
    for key in ("solref", "solimp"):
        if e.get(key) is not None:
            notes.append(f"{_at(source, e)}: {e.label()} {key} (MuJoCo's softness; here a hard constraint)")

    def body(key):
        n = e.get(key)
        if n is None:
            return None
        if n not in frame_of:
            raise ModelError(f"{where(source, e)}: {key}={n!r} is not a body of the model")
        return n

    def on(bname, p_local):
        """The point ``p_local`` of MJCF body ``bname`` as a point of its mechsys body."""
        mb, p, R = frame_of[bname]
        return mb.point(tuple(float(v) for v in p + R @ p_local))

    def world(bname, p_local):
        r, R = world_pose[bname]
        return r + R @ p_local

    if e.tag in ("connect", "weld"):
        if e.get("site1") is not None or e.get("site2") is not None:
            s1, s2 = e.get("site1"), e.get("site2")
            for s in (s1, s2):
                if s not in sites:
                    raise ModelError(f"{where(source, e)}: site {s!r} is not a site of the model")
            (b1, p1, S1), (b2, p2, S2) = sites[s1], sites[s2]
        else:
            S1 = S2 = None
            b1, b2 = body("body1"), body("body2") or "world"
            if b1 is None:
                raise ModelError(f"{where(source, e)}: a {e.tag} needs body1 (or site1 and site2)")
            p1 = np.array(floats(source, e, "anchor", 3, [0.0, 0.0, 0.0]))
            r2, R2 = world_pose[b2]
            p2 = R2.T @ (world(b1, p1) - r2)            # where the anchor is at qpos0
        mb1, mb2 = frame_of[b1][0], frame_of[b2][0]
        if mb1 is mb2:
            raise ModelError(f"{where(source, e)}: both sides are on one rigid body ({mb1.name!r})")
        label = name or f"{e.tag}_{b1}_{b2}"
        m.add(C.Spherical3(on(b1, p1), on(b2, p2)), name=label)
        if e.tag == "weld":
            if e.get("relpose") is not None:
                notes.append(f"{_at(ctx.source, e)}: weld relpose (the relative pose at qpos0 is used)")

            def A(b):           # the mechsys body's rotation at qpos0
                return world_pose[b][1] @ frame_of[b][2].T

            if S1 is not None:
                # MuJoCo welds the two sites' frames: A_1 F_1 S_1 = A_2 F_2 S_2 (F: the MJCF
                # body's frame in its mechsys body's), whatever the pose at qpos0
                Rrel = frame_of[b2][2] @ S2 @ S1.T @ frame_of[b1][2].T
            else:
                Rrel = A(b2).T @ A(b1)
            m.add(C.RotationLock3(mb1, None if mb2 is m.ground else mb2, _rot_spec(Rrel)),
                  name=label + "_rotation")
        return
    if e.tag == "joint":
        j1, j2 = e.get("joint1"), e.get("joint2")
        coords = {v.symbol.name for c_ in m.constraints for v in c_.new_variables()}
        for j in (j1, j2):
            if j is not None and j not in coords:
                raise ModelError(f"{where(source, e)}: joint {j!r} is not a hinge or slide of the model")
        if j1 is None:
            raise ModelError(f"{where(source, e)}: a joint equality needs joint1")
        c = floats(source, e, "polycoef", 5, [0.0, 1.0, 0.0, 0.0, 0.0])
        x = sp.Symbol(j2) if j2 else sp.S.Zero
        rhs = sum(sp.Float(ck) * x**k for k, ck in enumerate(c)) if j2 else sp.Float(c[0])
        m.add(C.Constraint(sp.Symbol(j1) - rhs), name=name or f"joint_{j1}")
        return
    notes.append(f"{_at(ctx.source, e)}: equality {e.label()} (not mapped)")
