"""Factories of classic mechanisms, for docs, demos, tests and benchmarks."""

from __future__ import annotations

import numpy as np
import sympy as sp

from ._errors import ModelError
from ._symbols import T
from .constraints import RelativeDistance1, Revolute2, RotationLock1, Translate2
from .model import Model2D


def _count(factory: str, name: str, value, least: int) -> None:
    """A factory's integer argument of at least ``least`` (bool refused), else ModelError."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise ModelError(f"{factory}: {name} must be an integer >= {least}, got {value!r}")


def _finite(factory: str, **values) -> None:
    """A factory's real arguments: finite numbers (bool and strings refused), else
    ModelError naming the first that is not."""
    for name, v in values.items():
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                or not np.isfinite(v):
            raise ModelError(f"{factory}: {name} must be a finite number, got {v!r}")


def slider_crank(crank: float = 2.0, rod: float = 6.0, offset: float = 0.0,
                 speed: float = 2 * np.pi, drive=None) -> Model2D:
    r"""The planar slider-crank of Mech's section 1.2.

    Crank of length ``crank`` pinned to ground at the origin and driven at ``speed`` rad/s
    (:math:`\theta = \mathit{speed} T`, or any expression ``drive`` of ``T``); connecting rod of length
    ``rod``; the piston slides along the line ``y = offset`` of ground. Bodies: ``crank``
    (point ``pin``), ``rod`` (points ``a``, ``b``), ``piston``. The driver is named ``drive``.
    """
    m = Model2D()
    g = m.ground
    cr = m.add_body("crank", points={"pin": (crank, 0)}, guess=((0, 0), 0))
    xr = np.sqrt(rod**2 - offset**2)
    ang = np.arctan2(offset - 0.0, xr - crank)
    rd = m.add_body("rod", points={"a": (0, 0), "b": (rod, 0)}, guess=((crank, 0), ang))
    pi = m.add_body("piston", guess=((crank + xr, offset), 0))
    m.add(Revolute2(g.point((0, 0)), cr.point(0)), name="crank pin")
    m.add(Revolute2(cr.point("pin"), rd.point("a")), name="crank-rod")
    m.add(Revolute2(rd.point("b"), pi.point(0)), name="wrist pin")
    m.add(Translate2(g.axis((0, offset), (1, 0)), pi.axis((0, 0), (1, 0))), name="slider")
    m.add(RotationLock1(cr, drive if drive is not None else speed * T), name="drive")
    return m


def slider_crank_dynamic(crank: float = 2.0, rod: float = 6.0, speed: float = 2 * np.pi,
                         masses=(1.5, 2.0, 3.0), inertias=(0.4, 5.0, 0.0), g: float = 9.81,
                         piston_force=0.0) -> Model2D:
    """:func:`slider_crank` with mass properties (uniform links: centroids at mid-length;
    ``inertias`` about the centroids), gravity ``g`` along -Y and a force ``piston_force``
    (an expression of ``T`` allowed) along +X on the piston, for statics and inverse
    dynamics (``solve(..., solution="dynamic")``)."""
    from .loads._loads import Force, Gravity

    m = slider_crank(crank=crank, rod=rod, speed=speed)
    for name, mass, c, J in zip(("crank", "rod", "piston"), masses,
                                ((crank / 2, 0), (rod / 2, 0), (0, 0)), inertias):
        m.set_mass_properties(name, mass=mass, centroid=c, inertia=J)
    if g:
        m.add_load(Gravity((0, -1), g))
    if piston_force != 0:
        m.add_load(Force(m.body("piston").point(0), (1, 0), piston_force), name="gas force")
    return m


def four_bar(ground: float = 4.0, crank: float = 1.0, coupler: float = 4.0, rocker: float = 3.0,
             speed: float = 1.0, branch: int = 1, crank_angle=None) -> Model2D:
    """A planar four-bar linkage driven at its crank.

    Ground pivots at ``(0, 0)`` (crank) and ``(ground, 0)`` (rocker). The coupler is a
    ``RelativeDistance1`` link between crank tip and rocker tip, so the bodies are ``crank``
    and ``rocker`` only. ``branch`` = +1 (rocker tip above the ground line) or -1 (below)
    picks the initial guess, hence the assembly branch.
    """
    m = Model2D()
    g = m.ground
    th = crank_angle if crank_angle is not None else speed * T
    th0 = float(sp.sympify(th).subs(T, 0))
    ax, ay = crank * np.cos(th0), crank * np.sin(th0)
    # rocker angle of the requested branch, for the guess
    dx, dy = ax - ground, ay
    d = np.hypot(dx, dy)
    c = (rocker**2 + d**2 - coupler**2) / (2 * rocker * d)
    phi = np.arctan2(dy, dx) - branch * np.arccos(np.clip(c, -1, 1))
    cr = m.add_body("crank", points={"tip": (crank, 0)}, guess=((0, 0), th0))
    ro = m.add_body("rocker", points={"tip": (rocker, 0)}, guess=((ground, 0), phi))
    m.add(Revolute2(g.point((0, 0)), cr.point(0)), name="crank pivot")
    m.add(Revolute2(g.point((ground, 0)), ro.point(0)), name="rocker pivot")
    m.add(RelativeDistance1(cr.point("tip"), ro.point("tip"), coupler), name="coupler")
    m.add(RotationLock1(cr, th), name="drive")
    return m


def four_bar_chain(n_loops: int, speed: float = 1.0) -> Model2D:
    """A chain of ``n_loops`` parallelogram-like four-bar loops sharing links.

    Loop ``k`` has ground pivots at ``x = k`` and ``x = k + 1``; its rocker is the next loop's
    crank, and the coupler of each loop is a body (pinned to both). Every link is a body, so
    the model has ``3 (2 n + 1)`` coordinates. Only the first crank is driven.
    """
    m = Model2D()
    g = m.ground
    L, H = 1.0, 1.0
    th0 = np.pi / 2 + 0.2
    cranks = []
    for k in range(n_loops + 1):
        cranks.append(m.add_body(f"link{k}", points={"tip": (H, 0)}, guess=((k * L, 0), th0)))
        m.add(Revolute2(g.point((k * L, 0)), cranks[-1].point(0)), name=f"pivot{k}")
    for k in range(n_loops):
        a = cranks[k]
        tip = (k * L + H * np.cos(th0), H * np.sin(th0))
        cp = m.add_body(f"coupler{k}", points={"end": (L, 0)}, guess=(tip, 0.0))
        m.add(Revolute2(a.point("tip"), cp.point(0)), name=f"left{k}")
        m.add(Revolute2(cp.point("end"), cranks[k + 1].point("tip")), name=f"right{k}")
    m.add(RotationLock1(cranks[0], th0 + 0.3 * sp.sin(speed * T)), name="drive")
    return m


def radial_engine(cylinders: int = 9, crank: float = 1.0, rod: float = 4.0,
                  speed: float = 2 * np.pi, g: float = 0.0) -> Model2D:
    r"""A planar radial engine: one crank pinned to ground at the origin and driven at
    ``speed`` rad/s (:math:`\theta = \mathit{speed} T`), and ``cylinders`` cylinders whose axes are spaced
    evenly around it (cylinder ``k`` at ``2 pi k / cylinders`` from the crank's zero). Each
    rod (length ``rod``) is pinned to the crank pin, as if the master and articulated rods were
    one pin, and its piston slides along its cylinder's axis. Bodies: ``crank`` (point
    ``pin``), ``rod{k}`` (points ``a``, ``b``), ``piston{k}``; joints ``pin{k}``, ``wrist{k}``,
    ``cylinder{k}``; the driver ``drive``. ``3 (2 cylinders + 1)`` coordinates.

    Uniform links (crank 2, rods 1 with centroids at mid-length, pistons 0.5) for inverse
    dynamics, and gravity ``g`` along -Y when ``g`` is not zero. Every rod hangs on
    the crank pin: the Jacobian's pattern is a star, whose band is as wide as the engine
    (the sparse LU of ``FixedPattern`` solves it in time linear in the cylinders)::

        m = models.radial_engine(9)
        sol = m.solve(np.linspace(0, 1, 50))
    """
    from .loads import Gravity

    _count("radial_engine", "cylinders", cylinders, 1)
    if not (0 < crank < rod):     # (also NaN)
        raise ModelError(f"radial_engine: need 0 < crank < rod (got crank={crank!r}, "
                         f"rod={rod!r}): a rod no longer than the crank locks the engine")
    m = Model2D()
    gnd = m.ground
    cr = m.add_body("crank", points={"pin": (crank, 0)}, guess=((0, 0), 0.0))
    m.add(Revolute2(gnd.point((0, 0)), cr.point(0)), name="crank pin")
    m.add(RotationLock1(cr, speed * T), name="drive")
    masses = {"crank": (2.0, (crank / 2, 0), 2.0 * crank**2 / 12)}
    for k in range(cylinders):
        a = 2 * np.pi * k / cylinders
        u = np.array([np.cos(a), np.sin(a)])
        # the piston's distance s along the axis: |s u - (crank, 0)| = rod
        s = crank * u[0] + np.sqrt(rod**2 - (crank * u[1]) ** 2)
        tip = s * u
        rd = m.add_body(f"rod{k}", points={"a": (0, 0), "b": (rod, 0)},
                        guess=((crank, 0.0), float(np.arctan2(tip[1], tip[0] - crank))))
        pi = m.add_body(f"piston{k}", guess=(tuple(tip), a))
        m.add(Revolute2(cr.point("pin"), rd.point("a")), name=f"pin{k}")
        m.add(Revolute2(rd.point("b"), pi.point(0)), name=f"wrist{k}")
        m.add(Translate2(gnd.axis((0, 0), tuple(u)), pi.axis((0, 0), (1, 0))),
              name=f"cylinder{k}")
        masses[f"rod{k}"] = (1.0, (rod / 2, 0), rod**2 / 12)
        masses[f"piston{k}"] = (0.5, (0, 0), 0.01)
    for name, (mass, c, J) in masses.items():
        m.set_mass_properties(name, mass=mass, centroid=c, inertia=J)
    if g:
        m.add_load(Gravity((0, -1), g))
    return m


def trailer_train(trailers: int = 10, speed: float = 2.0, rate: float = 0.4,
                  reach: float = 1.0):
    """A nonholonomic path (Mech's ``SetPath``, manual 10.5): a tractor steered at ``rate``
    rad/s (its heading ``rate T``), whose blade at the origin of its frame moves forward at
    ``speed`` without slipping sideways, towing ``trailers`` trailers. Each trailer's front
    (at ``reach`` ahead of its blade) is pinned to the hitch of the body ahead (at ``reach /
    2`` behind that body's blade), and its blade cannot slip sideways either. Returns the
    :class:`~mechsys.analyses.PathSystem` (its model is ``path.model``): ``3 (trailers + 1)``
    coordinates, one velocity constraint per trailer and two for the tractor; bodies
    ``tractor``, ``trailer{k}`` (points ``blade``, ``hitch``, and ``front`` on trailers).

    The tractor's blade runs on the circle of radius ``speed / rate`` (closed form). With
    the hitch behind the blade, a trailer's swing is halved down the train; a hitch further
    back than the trailer's reach would double it from trailer to trailer (an ill-posed
    motion for long trains)::

        path = models.trailer_train(50)
        sol = path.simulate(np.linspace(0, 3, 31))
    """
    from .constraints import Constraint, Orthogonal1, RelativeX1, RelativeY1

    _count("trailer_train", "trailers", trailers, 0)
    _finite("trailer_train", speed=speed, rate=rate, reach=reach)
    if not reach > 0:
        raise ModelError(f"trailer_train: reach must be positive, got {reach!r}")
    m = Model2D()
    hitch = (-reach / 2, 0.0)
    tractor = m.add_body("tractor", points={"blade": (0.0, 0.0), "hitch": hitch})
    m.add(RelativeX1(tractor.point("blade"), 0.0), name="dummy x")
    m.add(RelativeY1(tractor.point("blade"), 0.0), name="dummy y")
    m.add(RotationLock1(tractor, rate * T), name="steering")
    prev, bodies = tractor, []
    for k in range(trailers):
        b = m.add_body(f"trailer{k}", points={"front": (reach, 0.0), "blade": (0.0, 0.0),
                                              "hitch": hitch},
                       guess=((-1.5 * reach * (k + 1), 0.0), 0.0))
        m.add(Revolute2(prev.point("hitch"), b.point("front")), name=f"pin{k}")
        m.add(RotationLock1(b, 0.0), name=f"dummy{k}")
        bodies.append(b)
        prev = b
    m.solve(0.0)
    v = m.velocity(tractor.point("blade"))
    ahead = tractor.A * sp.Matrix([1, 0])
    replace = {"dummy x": Orthogonal1(v, tractor.vector((0, 1))),
               "dummy y": Constraint([(v.T * ahead)[0, 0] - speed])}
    for k, b in enumerate(bodies):
        replace[f"dummy{k}"] = Orthogonal1(m.velocity(b.point("blade")), b.vector((0, 1)))
    return m.path(replace=replace)


def pendulum_chain(n_links: int, g: float = 9.81) -> Model2D:
    """``n_links`` uniform rods (length 1, mass 1, centroidal inertia 1/12) pinned end to end,
    the first to the ground at the origin, all horizontal along +x, under gravity ``g``
    along -y. Bodies ``l0 ... l{N-1}``, joints ``j{k}``; the constraints ``lock{k}`` hold the
    link angles at zero for assembly and are the ones to drop for free motion::

        m = models.pendulum_chain(4)
        free = m.free(drop=[f"lock{k}" for k in range(4)])
    """
    from .loads import Gravity

    m = Model2D()
    prev = None
    for k in range(n_links):
        b = m.add_body(f"l{k}", points={"tip": (1, 0)}, mass=1.0, centroid=(0.5, 0),
                       inertia=1 / 12, guess=((float(k), 0.0), 0.0))
        joint = m.ground.point((0, 0)) if prev is None else prev.point("tip")
        m.add(Revolute2(joint, b.point(0)), name=f"j{k}")
        m.add(RotationLock1(b, 0.0), name=f"lock{k}")
        prev = b
    m.add_load(Gravity((0, -1), g))
    return m


def spatial_chain(n_links: int, g: float = 9.81, zigzag: float = 0.0, length: float = 1.0):
    """``n_links`` rods in space (``length``, mass 1, centroidal inertia ``diag(1e-3, 1/12,
    1/12) length^2`` in its frame, x along the rod), joined end to end by ball joints
    (``Spherical3``), the first to the ground at the origin, under gravity ``g`` along -Z.
    Every rod lies in the horizontal XY plane, turned about Z by ``+zigzag`` (even links) or
    ``-zigzag`` (odd links) from +X: with ``zigzag = 0`` the chain is straight along X and
    swings in the XZ plane exactly as :func:`pendulum_chain` (X, Z for its x, y); otherwise
    it falls out of any plane. Euler-parameter coordinates: ``7 n_links`` of them. Bodies
    ``l0 ... l{N-1}`` (point ``tip``), joints ``j{k}``; the constraints ``lock{k}``
    (``RotationLock3``) hold the rods' orientations for assembly and are the ones to drop::

        m = models.spatial_chain(24, zigzag=0.3)
        free = m.free(drop=[f"lock{k}" for k in range(24)])
    """
    from .constraints import RotationLock3, Spherical3
    from .loads import Gravity
    from .model import Model3D

    _count("spatial_chain", "n_links", n_links, 1)
    _finite("spatial_chain", g=g, zigzag=zigzag, length=length)
    if not length > 0:
        raise ModelError(f"spatial_chain: length must be positive, got {length!r}")
    L = float(length)
    m = Model3D()
    prev, at = None, np.zeros(3)
    for k in range(n_links):
        angle = zigzag if k % 2 == 0 else -zigzag
        turn = (float(angle), (0, 0, 1))
        b = m.add_body(f"l{k}", points={"tip": (L, 0, 0)}, mass=1.0, centroid=(L / 2, 0, 0),
                       inertia=(1e-3 * L**2, L**2 / 12, L**2 / 12, 0, 0, 0),
                       guess=(tuple(at), turn))
        joint = m.ground.point((0, 0, 0)) if prev is None else prev.point("tip")
        m.add(Spherical3(joint, b.point(0)), name=f"j{k}")
        m.add(RotationLock3(b, turn), name=f"lock{k}")
        at = at + L * np.array([np.cos(angle), np.sin(angle), 0.0])
        prev = b
    m.add_load(Gravity((0, 0, -1), g))
    return m


def driven_gen_arm(links: int, g: float = 9.81) -> Model2D:
    r"""A planar arm of ``links`` rods (1 m, 1 kg, centroidal inertia 1/12) in generalized
    coordinates: rod ``k`` (body ``link{k}``, points ``o`` and ``e``) is a ``GenRevolute2``
    slave of the previous rod's end (the first of the ground at the origin) through the
    joint angle ``q{k}`` (constraint ``joint{k}``), and every joint is driven,
    :math:`q_k = 0.3 \sin((k + 1) t)` (constraints ``drive{k}``), under gravity ``g`` along -y. The
    coordinates are the ``links`` joint angles; short arms get the symbolic dynamics, longer
    ones the recursive one (decision 0016). For kinematic sweeps and inverse dynamics::

        m = models.driven_gen_arm(12)
        sol = m.solve(np.linspace(0, 2, 400), solution="dynamic")   # joint torques: sol.lam
    """
    from .constraints import Constraint, GenRevolute2
    from .loads import Gravity

    _count("driven_gen_arm", "links", links, 1)
    _finite("driven_gen_arm", g=g)
    m = Model2D()
    master = m.ground.axis((0, 0))
    for k in range(links):
        link = m.add_body(f"link{k}", points={"o": (0, 0), "e": (1.0, 0)}, mass=1.0,
                          centroid=(0.5, 0), inertia=1 / 12)
        m.add(GenRevolute2(link.axis("o"), master, (f"q{k}", 0.0)), name=f"joint{k}")
        master = link.axis("e")
    q = sp.symbols(f"q0:{links}")
    for k in range(links):
        m.add(Constraint([q[k] - 0.3 * sp.sin((k + 1) * T)]), name=f"drive{k}")
    if g:
        m.add_load(Gravity((0, -1), g))
    return m


def n_four_bar(n_loops: int, g: float = 9.81, length: float = 1.0) -> Model2D:
    r"""The IFToMM multibody benchmark's N-four-bar mechanism (problem A02): ``n_loops``
    parallelogram loops of ``2 N + 1`` uniform links (length 1, mass 1, centroidal inertia
    1/12; ``length`` changes the unit of length: every length and ``g`` are multiplied by
    it). Cranks ``crank0 ... crankN`` are pinned to the ground at :math:`x = 0 \dots N`
    (joints ``A{k}``); couplers ``coupler0 ... coupler{N-1}`` join the crank tips (joints
    ``B{k}``, ``C{k}``). At the start the cranks are vertical; gravity ``g`` along -y. The
    constraint ``"hold"`` fixes ``crank0`` for assembly: drop it for the free motion, whose
    benchmark initial condition is a velocity of 1 along +x of point ``B0`` (the tip of
    ``crank0``, the origin of ``coupler0``)::

        m = models.n_four_bar(2)
        m.solve(0.0)
        free = m.free(drop=["hold"])
        sol = free.simulate(np.linspace(0, 10, 401), initial_condition={"crank0.th_d": -1.0})

    When the links are horizontal (twice per turn) all of them are collinear and the
    Jacobian loses ``N`` ranks: the mobility jumps from 1 to ``N + 1`` for an instant.
    """
    from .loads import Gravity

    m = Model2D()
    L = float(length)
    link = {"mass": 1.0, "centroid": (L / 2, 0), "inertia": L * L / 12}
    cranks = []
    for k in range(n_loops + 1):
        c = m.add_body(f"crank{k}", points={"tip": (L, 0)}, guess=((k * L, 0.0), np.pi / 2),
                       **link)
        m.add(Revolute2(m.ground.point((k * L, 0.0)), c.point(0)), name=f"A{k}")
        cranks.append(c)
    for k in range(n_loops):
        b = m.add_body(f"coupler{k}", points={"end": (L, 0)}, guess=((k * L, L), 0.0), **link)
        m.add(Revolute2(cranks[k].point("tip"), b.point(0)), name=f"B{k}")
        m.add(Revolute2(b.point("end"), cranks[k + 1].point("tip")), name=f"C{k}")
    m.add(RotationLock1(cranks[0], np.pi / 2), name="hold")
    m.add_load(Gravity((0, -1), g * L))
    return m


# -- spatial ---------------------------------------------------------------------------------


def slider_crank_3d(crank: float = 2.0, rod: float = 6.0, offset: float = 0.0,
                    height: float = 0.0, speed: float = 2 * np.pi, drive=None):
    """The spatial slider-crank of Mech's section 1.3, built from 3D joints.

    The crank turns about the global Z axis at the origin (``Revolute5``), driven at
    ``speed`` rad/s (``RotationLock1`` about that axis from global X; or any expression
    ``drive`` of ``T``); the connecting rod hangs on the crank pin by a ball joint
    (``Spherical3``) and on the piston by a universal joint (``Universal4``: rod pin along
    its local Y, piston pin along its local Z), which stops the rod spinning about its own
    axis; the piston slides without turning along the line through ``(0, offset, height)``
    parallel to X (``Translate5``). With ``height = 0`` every point moves in the XY plane
    exactly as in the planar :func:`slider_crank` with the same arguments.

    Bodies: ``crank`` (point ``pin``), ``rod`` (points ``a``, ``b``), ``piston``; constraints
    named as in the planar model: ``crank pin``, ``crank-rod``, ``wrist pin``, ``slider``,
    ``drive``.
    """
    from .constraints import Revolute5, Spherical3, Translate5, Universal4
    from .model import Model3D

    m = Model3D()
    g = m.ground
    z = (0, 0, 1)
    cr = m.add_body("crank", points={"pin": (crank, 0, 0)}, guess=((0, 0, 0), (1, 0, 0, 0)))
    reach = np.sqrt(rod**2 - offset**2 - height**2)
    d = np.array([reach - crank, offset, height])
    d /= np.linalg.norm(d)
    y = np.cross([0.0, 0.0, 1.0], d)
    y /= np.linalg.norm(y)
    R = np.column_stack([d, y, np.cross(d, y)])       # rod x along the rod, y horizontal
    rd = m.add_body("rod", points={"a": (0, 0, 0), "b": (rod, 0, 0)}, guess=((crank, 0, 0), R))
    pi = m.add_body("piston", guess=((crank + reach, offset, height), (1, 0, 0, 0)))
    m.add(Revolute5(cr.axis(0, z), g.axis((0, 0, 0), z)), name="crank pin")
    m.add(Spherical3(cr.point("pin"), rd.point("a")), name="crank-rod")
    m.add(Universal4(rd.axis("b", (0, 1, 0)), pi.axis(0, z)), name="wrist pin")
    m.add(Translate5(pi.axis(0, (1, 0, 0)), g.axis((0, offset, height), (1, 0, 0))),
          name="slider")
    m.add(RotationLock1(cr.axis(0, z), g.axis((0, 0, 0), z), drive if drive is not None
                        else speed * T), name="drive")
    return m


def cardan_joint(bend: float = 0.5, speed: float = 2 * np.pi, joint: str = "universal",
                 drive=None):
    r"""Two shafts joined by a Cardan (Hooke) joint, or a constant-velocity joint.

    The input shaft turns about the global X axis (``Revolute5``), driven at ``speed``
    (``RotationLock1``: its yoke pin, local Y, makes the angle ``speed T`` -- or ``drive`` --
    with the global Y axis, so the angle is measured from the plane of the two shafts). The
    output shaft's axis (local X) stays along ``(cos bend, sin bend, 0)`` (``Parallel2``)
    and the joint centre is at the origin. ``joint="universal"``: ``Universal4`` between the
    input yoke pin (local Y of ``input``) and the output yoke pin (local Z of ``output``);
    ``joint="cv"``: ``ConstantVelocity4`` between the shaft axes (reference directions the
    local Y axes), so the output turns at exactly the input speed.

    Bodies ``input``, ``output``; constraints ``bearing``, ``output axis``, ``joint``,
    ``drive``. For the universal joint the output speed is
    :math:`\omega_2 / \omega_1 = \cos(\mathit{bend}) / (1 - \sin^2(\mathit{bend}) \cos^2\theta_1)` with
    ``th1`` the drive angle.
    """
    from ._errors import choice
    from .constraints import ConstantVelocity4, Parallel2, Revolute5, Universal4
    from .model import Model3D

    choice(joint, ("universal", "cv"), "cardan_joint: joint")
    m = Model3D()
    g = m.ground
    x, y = (1, 0, 0), (0, 1, 0)
    a2 = (float(np.cos(bend)), float(np.sin(bend)), 0.0)
    s1 = m.add_body("input", guess=((0, 0, 0), (1, 0, 0, 0)))
    s2 = m.add_body("output", guess=((0, 0, 0), (bend, (0, 0, 1))))
    m.add(Revolute5(s1.axis(0, x), g.axis((0, 0, 0), x)), name="bearing")
    m.add(Parallel2(s2.vector(x), g.vector(a2)), name="output axis")
    if joint == "universal":
        m.add(Universal4(s1.axis(0, y), s2.axis(0, (0, 0, 1))), name="joint")
    else:
        m.add(ConstantVelocity4(s1.axis(0, x, y), s2.axis(0, x, y)), name="joint")
    m.add(RotationLock1(s1.axis(0, x, y), g.axis((0, 0, 0), x, y),
                        drive if drive is not None else speed * T), name="drive")
    return m


def geneva_drive(slots: int = 4, center_distance: float = 2.0, turns: int = 2) -> Model2D:
    r"""A Geneva drive as a ``StageSwitch`` (Mech chapter 5), the intermittent motion of a
    wheel with ``slots`` radial slots driven by a crank pin.

    The crank turns about the origin at 1 rad/s, ``theta = T - pi`` (so ``T`` from 0 to
    ``2 pi turns`` covers ``turns`` engagements, the first around ``T = pi``); its pin, at
    radius :math:`a = c \sin(\pi / \mathit{slots})` (tangential entry), engages the wheel centred at
    ``(c, 0)``. While engaged (:math:`\lvert \theta - 2 \pi k \rvert \le \alpha = \pi/2 -
    \pi/\mathit{slots}`) the wheel
    turns by ``-2 pi / slots``, following

    .. math:: \tan\phi = \frac{\sin\theta}{c/a - \cos\theta},\qquad \text{wheel} = \text{mid} - \phi;

    between engagements it is locked. The switch, named ``"geneva"``, has ``2 turns + 1``
    stages: a ``RotationLock1`` of the wheel at ``pi/slots - 2 pi k / slots`` before
    engagement ``k``, the pin on the line of slot ``k`` (``PointOnLine1``; the slot's local
    direction at angle ``2 pi k / slots``) during it. Bodies ``crank`` (point ``pin``) and
    ``wheel``; the crank's driver is named ``drive``.

    >>> m = geneva_drive()
    >>> sol = m.solve(np.linspace(0, 4 * np.pi, 101))
    >>> sorted(set(sol.stage("geneva")))
    [1, 2, 3, 4, 5]
    """
    from ._errors import ModelError
    from .constraints import PointOnLine1, StageSwitch

    _count("geneva_drive", "slots", slots, 3)
    _count("geneva_drive", "turns", turns, 1)
    try:
        c = float(center_distance)
    except (TypeError, ValueError):
        c = float("nan")
    if not (np.isfinite(c) and c > 0):
        raise ModelError("geneva_drive: center_distance must be a positive length, got "
                         f"{center_distance!r}")
    step = 2 * sp.pi / slots                 # the wheel's turn per engagement
    half = sp.pi / 2 - sp.pi / slots         # the crank's half angle of engagement
    m = Model2D()
    g = m.ground
    crank = m.add_body("crank", points={"pin": (c * np.sin(np.pi / slots), 0)},
                       guess=((0, 0), -np.pi))
    wheel = m.add_body("wheel", guess=((c, 0), np.pi / slots))
    m.add(Revolute2(g.point((0, 0)), crank.point(0)), name="crank pivot")
    m.add(Revolute2(g.point((c, 0)), wheel.point(0)), name="wheel pivot")
    m.add(RotationLock1(crank, T - sp.pi), name="drive")
    th = crank.q[2]
    stages = []
    for k in range(turns):
        slot = (float(sp.cos(k * step)), float(sp.sin(k * step)))
        stages.append((th < 2 * sp.pi * k - half, RotationLock1(wheel, sp.pi / slots - k * step)))
        stages.append((th <= 2 * sp.pi * k + half,
                       PointOnLine1(crank.point("pin"), wheel.axis((0, 0), slot))))
    stages.append((True, RotationLock1(wheel, sp.pi / slots - turns * step)))
    m.add(StageSwitch(*stages), name="geneva")
    return m
