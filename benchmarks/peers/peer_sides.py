"""The entrants: each package's models of the peer problems (``peer_problems.py``) with the
settings worth measuring, as :class:`Case` objects that ``run.py`` times side by side.

A case is built (model construction and compilation, not timed), then ``reset()`` puts it
back at the initial state (not timed) and ``run()`` integrates (timed: CPU time of that call
only); ``result()`` returns the final absolute link angles and the loop-closure gap (or
None where it does not apply).

mechsys: absolute coordinates (x, y, angle per body) with revolute constraints, the
default DOP853 integrator (``constraint_correction`` = projection onto the constraints after
each step) or Mech's Adams-Bashforth-Moulton (``method="adams"``). The gap is the largest
``|Phi|`` over the output points.

MuJoCo (optional): joint coordinates (relative hinge angles), fixed-step RK4; the four-bar is
closed by an ``equality/connect`` between two sites, stiffened (``solref = (2 dt, 1)``,
``solimp = (0.99, 0.999, 0.001)``, its best setting for accuracy); contacts off. The gap is
the site distance at the final state.

Exudyn (optional): ``ObjectKinematicTree`` (minimal joint coordinates, explicit RK67 or
DOPRI5) for the open chains, redundant coordinates (``NodeRigidBody2D`` +
``ObjectJointRevolute2D``) with the implicit GeneralizedAlpha integrator for the four-bar
(its explicit solvers refuse closed loops); one thread, the ``exudynCPPfast`` module.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import peer_problems as P


@dataclass
class Case:
    problem: str           # "A", "B4" ... "B256", "C"
    package: str
    setting: str
    reset: Callable[[], None]
    run: Callable[[], None]
    result: Callable[[], tuple[np.ndarray, float | None]]
    note: str = ""
    extra: dict = field(default_factory=dict)


def available(package: str) -> bool:
    return importlib.util.find_spec(package) is not None


# ---------------------------------------------------------------------------------------
# mechsys
# ---------------------------------------------------------------------------------------
def _mechsys_case(problem, free, t_end, names, method, opts, setting, gap):
    box = {}
    s = free.system

    case = None

    def run():
        box["sol"] = free.simulate((0.0, t_end), method=method, **opts)
        case.extra["evaluations"] = box["sol"].extra["evaluations"]

    def result():
        sol = box["sol"]
        angles = np.array([sol[k][-1] for k in names])
        if not gap:
            return angles, None
        return angles, max(float(np.abs(s.residual(tk, qk)).max()) for tk, qk in zip(sol.t, sol.q))

    case = Case(problem, "mechsys", setting, lambda: None, run, result)
    return case


def mechsys_cases(problems: set[str], sizes) -> list[Case]:
    import free_motion as F

    cases = []
    dop = lambda r, c=True: ("dop853", {"rtol": r, "atol": r / 100, "constraint_correction": c})  # noqa: E731
    if "A" in problems:
        free, comp = F.compiled(F.double_pendulum)
        # (half decades from 1e-10 on: a decade's step in rtol costs about 1.4 times, so a
        # target missed by a few percent at one decade's setting would read as a slowdown)
        grid = [dop(r, c) for r in (1e-7, 1e-9, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12, 3e-13, 1e-13)
                for c in (True, False)]
        # Mech's MaxError -> e means {e, e/10, e/100}; the three-number form also sets when
        # the step doubles (each of the last 2n errors below c): c = a/20 doubles sooner
        errors = [1e-11, 1e-12, 1e-13] + [(e, e / 10, e / 20) for e in (2e-12, 1e-12, 5e-13)]
        grid += [("adams", {"fit_degree": "quartic", "max_error": e, "constraint_correction": False})
                 for e in errors]
        for method, opts in grid:
            cases.append(_mechsys_case("A", free, P.T_PENDULUM, ["l0.th", "l1.th"], method, opts,
                                       _label(method, opts), gap=False))
    for n in sizes:
        if f"B{n}" not in problems:
            continue
        free, comp = F.compiled(F.chain, n)
        names = [f"l{k}.th" for k in range(n)]
        for method, opts in (dop(1e-5), dop(1e-6), dop(1e-7), dop(1e-8, False)):
            c = _mechsys_case(f"B{n}", free, P.T_CHAIN, names, method, opts, _label(method, opts),
                              gap=False)
            c.extra["compile"] = comp["compile"]
            cases.append(c)
    if "C" in problems:
        free, comp = F.compiled(F.four_bar)
        for r in (1e-8, 1e-9, 1e-10, 1e-11):
            method, opts = dop(r)
            cases.append(_mechsys_case("C", free, P.T_FOUR_BAR, ["crank.th", "coupler.th", "rocker.th"],
                                       method, opts, _label(method, opts), gap=True))
    return cases


def _label(method, opts):
    if method == "adams":
        e = opts["max_error"]
        e = f"{e:.0e}" if np.ndim(e) == 0 else "(" + ", ".join(f"{v:.1e}" for v in e) + ")"
        text = f"Adams {opts['fit_degree']}, max_error {e}"
    else:
        text = f"{method.upper()} rtol {opts['rtol']:.0e}"
    return text + ("" if opts.get("constraint_correction", True) else ", no projection")


# ---------------------------------------------------------------------------------------
# MuJoCo
# ---------------------------------------------------------------------------------------
def _rod(mass: float, length: float) -> str:
    i = mass * length**2 / 12
    # the rod lies along the body's x; its spin inertia is irrelevant in the plane
    return (f'<inertial pos="{length / 2} 0 0" mass="{mass}" '
            f'diaginertia="1e-9 {i} {i}"/>')


def _mjcf(world: str, dt: float, extra: str = "") -> str:
    # planar y is MuJoCo's z; hinges about -y so that positive angles are counter-clockwise
    return (f'<mujoco><option timestep="{dt}" integrator="RK4" gravity="0 0 {-P.G}">'
            f'<flag contact="disable"/></option><worldbody>{world}</worldbody>{extra}</mujoco>')


def mujoco_cases(problems: set[str], sizes) -> list[Case]:
    import mujoco

    cases = []

    def chain_case(problem, n, dt, t_end):
        world = "".join(f'<body pos="{0 if k == 0 else 1} 0 0"><joint type="hinge" axis="0 -1 0"/>'
                        + _rod(1.0, 1.0) for k in range(n)) + "</body>" * n
        model = mujoco.MjModel.from_xml_string(_mjcf(world, dt))
        data = mujoco.MjData(model)
        steps = round(t_end / dt)
        return Case(problem, "MuJoCo", f"RK4 dt {dt:g}", lambda: mujoco.mj_resetData(model, data),
                    lambda: mujoco.mj_step(model, data, nstep=steps),
                    lambda: (np.cumsum(data.qpos), None))

    if "A" in problems:
        cases += [chain_case("A", 2, dt, P.T_PENDULUM) for dt in (2e-3, 1e-3, 5e-4, 2e-4)]
    for n in sizes:
        if f"B{n}" in problems:
            cases += [chain_case(f"B{n}", n, dt, P.T_CHAIN) for dt in (2e-3, 1.6e-3, 1e-3)]
    if "C" in problems:
        for dt in (2e-3, 1.25e-3, 1e-3, 5e-4):
            cases.append(_mujoco_four_bar(mujoco, dt))
    return cases


def _mujoco_four_bar(mujoco, dt):
    a, b, c, d = P.FB_CRANK, P.FB_COUPLER, P.FB_ROCKER, P.FB_GROUND
    world = (f'<body><joint type="hinge" axis="0 -1 0"/>{_rod(a, a)}'
             f'<body pos="{a} 0 0"><joint type="hinge" axis="0 -1 0"/>{_rod(b, b)}'
             f'<site name="cc" pos="{b} 0 0"/></body></body>'
             f'<body pos="{d} 0 0"><joint type="hinge" axis="0 -1 0"/>{_rod(c, c)}'
             f'<site name="cr" pos="{c} 0 0"/></body>')
    stiff = f'solref="{2 * dt} 1" solimp="0.99 0.999 0.001"'
    extra = f'<equality><connect site1="cc" site2="cr" {stiff}/></equality>'
    model = mujoco.MjModel.from_xml_string(_mjcf(world, dt, extra))
    data = mujoco.MjData(model)
    coupler, rocker = P.four_bar_angles(P.FB_CRANK0)
    steps = round(P.T_FOUR_BAR / dt)

    def reset():
        mujoco.mj_resetData(model, data)
        data.qpos[:] = [P.FB_CRANK0, coupler - P.FB_CRANK0, rocker]   # relative hinge angles
        mujoco.mj_forward(model, data)

    def result():
        q = data.qpos
        mujoco.mj_kinematics(model, data)
        gap = float(np.linalg.norm(data.site("cc").xpos - data.site("cr").xpos))
        return np.array([q[0], q[0] + q[1], q[2]]), gap

    return Case("C", "MuJoCo", f"RK4 dt {dt:g}, solref 2dt", reset,
                lambda: mujoco.mj_step(model, data, nstep=steps), result)


# ---------------------------------------------------------------------------------------
# Exudyn
# ---------------------------------------------------------------------------------------
def _exudyn():
    sys.exudynFast = os.environ.get("PEERS_EXUDYN_SAFE", "") != "1"   # read by exudyn's import
    import exudyn

    return exudyn


def _exudyn_settings(exu, t_end, *, h=None, tol=None, implicit=False):
    s = exu.SimulationSettings()
    s.parallel.numberOfThreads = 1
    s.solution.file.write = False        # no solution file: time the integration only
    s.solution.sensors.active = False
    s.show.globalTimers = False
    s.show.statistics = False
    ti = s.timeIntegration
    ti.endTime = t_end
    ti.verboseMode = 0
    if implicit:
        ti.numberOfSteps = round(t_end / h)
        ti.generalizedAlpha.spectralRadius = 0.9     # undamped (1.0) diverges on the four-bar
        ti.newton.relativeTolerance = 1e-10
        ti.newton.absoluteTolerance = 1e-12
        ti.newton.useModifiedNewton = True
    elif tol is not None:
        ti.automaticStepSize = True
        ti.absoluteTolerance = ti.relativeTolerance = tol
        ti.numberOfSteps = round(t_end / 1e-2)
        ti.minimumStepSize = 1e-12
    else:
        ti.automaticStepSize = False
        ti.numberOfSteps = round(t_end / h)
    return s


def _exudyn_tree(exu, n):
    from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=[0.0] * n,
                                       initialCoordinates_t=[0.0] * n, numberOfODE2Coordinates=n))
    frames, offsets, coms, inertias = (exu.Matrix3DList(), exu.Vector3DList(), exu.Vector3DList(),
                                       exu.Matrix3DList())
    for k in range(n):
        frames.Append(np.eye(3))
        offsets.Append([0.0 if k == 0 else 1.0, 0.0, 0.0])
        coms.Append([0.5, 0.0, 0.0])
        inertias.Append(np.diag([0.0, 1 / 12, 1 / 12]))
    mbs.AddObject(ObjectKinematicTree(nodeNumber=node, jointTypes=[exu.JointType.RevoluteZ] * n,
                                      linkParents=[k - 1 for k in range(n)], jointTransformations=frames,
                                      jointOffsets=offsets, linkInertiasCOM=inertias, linkCOMs=coms,
                                      linkMasses=[1.0] * n, baseOffset=[0.0, 0.0, 0.0],
                                      gravity=[0.0, -P.G, 0.0]))
    mbs.Assemble()
    return sc, mbs, node


def exudyn_cases(problems: set[str], sizes, full: bool) -> list[Case]:
    exu = _exudyn()
    solver = exu.DynamicSolverType
    cases = []

    def tree_case(problem, n, t_end, kind, step):
        sc, mbs, node = _exudyn_tree(exu, n)
        if kind == "RK67":
            settings, setting = _exudyn_settings(exu, t_end, h=step), f"KinematicTree RK67 h {step:g}"
        else:
            settings, setting = _exudyn_settings(exu, t_end, tol=step), f"KinematicTree DOPRI5 tol {step:g}"

        def result():
            q = mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates)
            return np.cumsum(q), None

        # SolveDynamic starts from the initial coordinates at every call: no reset needed
        return Case(problem, "Exudyn", setting, lambda: None,
                    lambda: mbs.SolveDynamic(settings, solverType=getattr(solver, kind)), result)

    if "A" in problems:
        cases += [tree_case("A", 2, P.T_PENDULUM, "RK67", h) for h in (1e-2, 5e-3, 2.5e-3, 2e-3)]
        cases += [tree_case("A", 2, P.T_PENDULUM, "DOPRI5", tol) for tol in (1e-9, 1e-11)]
    for n in sizes:
        if f"B{n}" not in problems:
            continue
        # N = 256 takes about a minute per run with KinematicTree (cost ~ N^2..N^3): full runs only
        if n <= 64 or full:
            steps = (1e-2, 5e-3) if n <= 64 else (5e-3,)
            cases += [tree_case(f"B{n}", n, P.T_CHAIN, "RK67", h) for h in steps]
    if "C" in problems:
        cases += [_exudyn_four_bar(exu, h) for h in (5e-4, 3e-4, 2e-4)]
    return cases


def _exudyn_four_bar(exu, h):
    from exudyn.itemInterface import (
        LoadForceVector,
        MarkerBodyPosition,
        MarkerNodePosition,
        NodeRigidBody2D,
        ObjectGround,
        ObjectJointRevolute2D,
        ObjectRigidBody2D,
    )

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    coupler, rocker = P.four_bar_angles(P.FB_CRANK0)
    angles = [P.FB_CRANK0, coupler, rocker]
    lengths = [P.FB_CRANK, P.FB_COUPLER, P.FB_ROCKER]
    starts = [np.zeros(2), P.FB_CRANK * np.array([np.cos(angles[0]), np.sin(angles[0])]),
              np.array([P.FB_GROUND, 0.0])]
    ground = mbs.AddObject(ObjectGround())
    nodes, ends = [], []
    for ang, length, start in zip(angles, lengths, starts):
        centre = start + 0.5 * length * np.array([np.cos(ang), np.sin(ang)])
        mass = length          # 1 kg/m
        nd = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[centre[0], centre[1], ang]))
        body = mbs.AddObject(ObjectRigidBody2D(mass=mass, inertia=mass * length**2 / 12, nodeNumber=nd))
        mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=nd)),
                                    loadVector=[0.0, -mass * P.G, 0.0]))
        ends.append([mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[s * length / 2, 0, 0]))
                     for s in (-1, 1)])
        nodes.append(nd)
    pivot_a = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    pivot_d = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[P.FB_GROUND, 0, 0]))
    for pair in ([pivot_a, ends[0][0]], [ends[0][1], ends[1][0]], [pivot_d, ends[2][0]],
                 [ends[1][1], ends[2][1]]):
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=pair))
    mbs.Assemble()
    settings = _exudyn_settings(exu, P.T_FOUR_BAR, h=h, implicit=True)

    def result():
        th = np.array([angles[k] + mbs.GetNodeOutput(nd, exu.OutputVariableType.Coordinates)[2]
                       for k, nd in enumerate(nodes)])
        tips = []
        for k, nd in enumerate(nodes):
            centre = np.array(mbs.GetNodeOutput(nd, exu.OutputVariableType.Position))[:2]
            half = 0.5 * lengths[k] * np.array([np.cos(th[k]), np.sin(th[k])])
            tips.append((centre - half, centre + half))
        # the worst of the four joints, from the bodies' own positions
        gaps = [tips[0][0], tips[0][1] - tips[1][0], tips[2][0] - [P.FB_GROUND, 0.0],
                tips[1][1] - tips[2][1]]
        return th, max(float(np.linalg.norm(g)) for g in gaps)

    return Case("C", "Exudyn", f"redundant coords, GeneralizedAlpha h {h:g}", lambda: None,
                lambda: mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.GeneralizedAlpha),
                result)
