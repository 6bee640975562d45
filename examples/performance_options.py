"""Chapter 12 of Mech's manual, 12.2-12.4: simplification, compile options and coordinates.

* 12.2.1 -- the symbolic location of three points of a crank: the local origin is the
  cheapest, every nonzero local coordinate adds terms; a centroid off the local origin
  fills the mass matrix.
* 12.2 ($MechProcessFunction) -- ``m.set_compile_options(process="chop")`` drops the
  round-off of local coordinates such as ``cos(pi/2) = 6e-17`` from the equations.
* 12.3 (Compiled) -- ``opt_level`` trades LLVM compile time against evaluation time.
* 12.4.1 -- the 2D degenerate Euler coordinates ``Model2D(orientation="euler")``: the
  location and velocity of an arbitrary point have no sine or cosine; a four-bar sweep in
  both coordinate systems gives the same answers.

Timings are printed for information only; the checks at the end are on the numbers.

Run: ``python examples/performance_options.py``
"""

import os
import time

import numpy as np
import sympy as sp

import mechsys as ms
from mechsys import T


def four_bar(orientation="angle", pin_y=0.0):
    a, b, c, d = 1.0, 4.0, 3.0, 4.0
    m = ms.Model2D(orientation=orientation)
    crank = m.add_body("crank", points={"A": (a, 0)}, guess=((0, 0), 0), mass=1.0,
                       inertia=0.1)
    coupler = m.add_body("coupler", points={"B": (b, pin_y)}, guess=((a, 0), 0.9), mass=2.0,
                         inertia=1.0, centroid=(2.0, 0.0))
    rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((d, 0), 1.8), mass=1.5,
                        inertia=0.5)
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="O2")
    m.add(ms.Revolute2(crank.point("A"), coupler.point(0)), name="A")
    m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")), name="B")
    m.add(ms.Revolute2(m.ground.point((d, 0)), rocker.point(0)), name="O4")
    m.add(ms.RotationLock1(crank, T), name="drive")
    m.add_load(ms.Gravity((0, -1), 9.81))
    return m


def ops(exprs) -> int:
    return int(sum(sp.count_ops(e) for e in exprs))


# -- 12.2.1: local coordinate choices -----------------------------------------------------
m = four_bar()
crank = m.body("crank")
print("12.2.1  three points of the crank (global location, operation count)")
for local in ((0, 0), (1, 0), (1, 2)):
    loc = m.location(crank.point(local))
    print(f"  {str(local):7s} {ops(loc):3d}  {list(loc)}")
for centroid in ((0, 0), (0.5, 0.2)):
    mm = four_bar()
    mm.set_mass_properties("crank", centroid=centroid)
    M = mm.mass_matrix("crank")
    print(f"  centroid {centroid}: crank mass matrix has {sum(e != 0 for e in M)} nonzero "
          f"entries, {ops(M)} operations")

# -- 12.2: the process function (Mech's $MechProcessFunction = Chop) ----------------------
raw = four_bar(pin_y=4.0 * np.cos(np.pi / 2))        # 2.4e-16: round-off of a computed point
chopped = four_bar(pin_y=4.0 * np.cos(np.pi / 2))
chopped.set_compile_options(process="chop")
n_raw, n_chop = ops(raw.equations().phi), ops(chopped.equations().phi)
print(f"\n12.2  constraint equations: {n_raw} operations as built, {n_chop} with process='chop'")

# -- 12.3: compile options ------------------------------------------------------------------
t = np.linspace(0, 2 * np.pi, 201)
print("\n12.3  opt_level: compile + 201-point acceleration sweep (CPU s; MECHSYS_CACHE off)")
results = {}
os.environ["MECHSYS_CACHE"] = "0"         # measure compiling, not the on-disk kernel cache
for level in (0, 3):
    mm = four_bar()
    mm.set_compile_options(opt_level=level)
    c0 = time.process_time()
    mm.compile().f_position, mm.compile().f_velocity, mm.compile().f_gamma
    c1 = time.process_time()
    results[level] = mm.solve(t)
    c2 = time.process_time()
    print(f"  opt_level={level}: compile {c1 - c0:.3f}  sweep {c2 - c1:.3f}")

# -- 12.4.1: 2D coordinate systems ----------------------------------------------------------
print("\n12.4.1  location and velocity of an arbitrary point (px, py) of the crank")
px, py = sp.symbols("px py")
for orientation in ("angle", "euler"):
    mm = four_bar(orientation)
    p = mm.body("crank").point((px, py))
    print(f"  {orientation}: location {list(mm.location(p))}")
    print(f"  {' ' * len(orientation)}  velocity {list(mm.velocity(p))}")

sweeps = {}
for orientation in ("angle", "euler"):
    mm = four_bar(orientation)
    c0 = time.process_time()
    sweeps[orientation] = mm.solve(t, solution="dynamic")
    print(f"  {orientation}: build + 201-point dynamic sweep {time.process_time() - c0:.3f} CPU s, "
          f"{mm.compile().n} coordinates, {mm.compile().m} equations")
ang, eul = sweeps["angle"], sweeps["euler"]
d_th = np.abs(np.angle(np.exp(1j * (ang.angle("rocker") - eul.angle("rocker"))))).max()
d_w = np.abs(ang.omega("rocker") - eul.omega("rocker")).max()
d_a = np.abs(ang.alpha("rocker") - eul.alpha("rocker")).max()
d_m = np.abs(ang.reaction("drive", "crank")[1] - eul.reaction("drive", "crank")[1]).max()
print(f"  angle vs euler: rocker angle {d_th:.1e}, omega {d_w:.1e}, alpha {d_a:.1e}, "
      f"drive torque {d_m:.1e}")

# -- checks ---------------------------------------------------------------------------------
if not n_chop < n_raw:
    raise SystemExit("process='chop' did not shorten the equations")
if np.abs(results[0].qdd - results[3].qdd).max() > 1e-9:
    raise SystemExit("opt_level changed the answers")
if max(d_th, d_w, d_a) > 1e-9 or d_m > 1e-8:
    raise SystemExit("the Euler-parameter model disagrees with the angle model")
euler_phi = four_bar("euler").equations().phi
q = {s for b in four_bar("euler").bodies[1:] for s in b.q}
if any(f.free_symbols & q for e in euler_phi for f in e.atoms(sp.sin, sp.cos)):
    raise SystemExit("an Euler-parameter constraint contains a sine or cosine of a coordinate")
