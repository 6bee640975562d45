"""The Whipple bicycle's nonlinear motion in mechsys and in SymPy mechanics' ``KanesMethod``
with SciPy, side by side (issue 36, item 6): build time, run time of 10 s, steps, agreement.

The model is the benchmark of Meijaard, Papadopoulos, Ruina & Schwab (2007) with its Table 1
parameters, upright at 4.6 m/s (just above the weave speed, 4.29 m/s) after a lean-rate kick
of 0.5 rad/s: it weaves (lean and steer peak at 0.12 and 0.13 rad) and recovers. Both sides
integrate 10 s with DOP853 at ``rtol = 1e-8, atol = 1e-10``.

* **mechsys**: the model of examples/whipple_bicycle.py (imported: four bodies in absolute
  coordinates with Euler parameters, three ``Revolute5`` hinges, two ``RollingDisk2``
  contacts), ``m.free().simulate`` (28 coordinates, 21 position rows, 4 rolling rows; the
  compiled stepper holding the rolling rows, decision 0062).
* **SymPy**: a minimal-coordinate Kane formulation written here: yaw ``q1``, lean ``q2``,
  pitch ``q3``, steer ``q4`` of the rear frame and fork (the wheel angles and the contact's
  ``x, y`` are ignorable and left out), speeds ``u1..u4`` their rates and ``u5, u6`` the
  wheels' spins relative to their frames. The rear wheel's rolling is built into the
  velocities (its contact point has zero velocity); the front contact's velocity along the
  yaw frame's ``x, y`` and the vertical are the three velocity constraints, with the
  dependent speeds ``u1`` (yaw), ``u3`` (pitch), ``u6`` (front spin)::

      KanesMethod(N, q_ind=[q1, q2, q3, q4], u_ind=[u2, u4, u5], u_dependent=[u1, u3, u6],
                  velocity_constraints=..., kd_eqs=[q_i' - u_i])

  ``kanes_equations`` gives ``M(q) u' = f(q, u)`` (6 rows: 3 dynamic, 3 differentiated
  constraints); both are turned into NumPy functions by ``lambdify(..., cse=True)`` and
  ``u'`` is ``numpy.linalg.solve`` at each evaluation inside ``scipy.integrate.solve_ivp``.
  The parameters are numbers from the start (as in mechsys's model; symbols passed to
  ``lambdify`` as arguments would give larger expressions, not measured). The pitch follows
  from the third constraint (the front contact's vertical velocity), so the front contact's
  height is kept only to the integration's accuracy: nothing projects it back, where mechsys
  projects positions and velocities onto all rows after each step.

The lean and steer angles of the two are the same angles (the lean is the roll of the rear
frame's axle, the steer the fork's rotation about the steer axis): they are compared at 201
times over the 10 s.

**First run** is what a new installation meets: the CPU time of a fresh process with empty
caches (``MECHSYS_CACHE`` and ``NUMBA_CACHE_DIR`` pointed at new directories) and
``MECHSYS_COMPILE`` at its default (``background``), from after the imports to the end of
the 10 s run (model, ``free()``, kernels, the run on the Python path while one low-priority
process compiles the stepper's loop into the cache, decision 0064); that process's CPU time
is reported beside it (it runs on the other core and is waited for before the next
measurement). **Build** is the CPU time in a fresh process from after the imports to the
first result of a 1 ms run (mechsys: the model built, ``free()`` and its kernels compiled;
SymPy: the derivation, ``lambdify`` and a first right-hand side). mechsys's build is
measured with empty caches and ``MECHSYS_COMPILE=wait`` (the stepper's loop compiled in the
process first: cold) and again with the caches that run filled (warm). **Run** is the median
CPU time of the 10 s integration over interleaved rounds in one process (after a warm-up
run of each).

Run from the repository root::

    PYTHONPATH=src python benchmarks/bicycle_kane.py                       # print
    PYTHONPATH=src python benchmarks/bicycle_kane.py --write docs/performance.md
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import importlib.util  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE))

from _machine import machine, write_block  # noqa: E402

V, KICK, T_END = 4.6, 0.5, 10.0
RTOL, ATOL = 1e-8, 1e-10
TIMES = np.linspace(0.0, T_END, 201)
#: the SymPy derivation is given this much CPU time before the comparison gives up on it
SYMPY_CAP_S = 1200.0
BEGIN = "<!-- bicycle_kane: begin (written by benchmarks/bicycle_kane.py --write; rerun it) -->"
END = "<!-- bicycle_kane: end -->"
#: CPU seconds of the SymPy build's two parts (filled by :func:`sympy_build`)
PHASES: dict = {}


def _example():
    """examples/whipple_bicycle.py as a module (its builder and the benchmark's numbers)."""
    spec = importlib.util.spec_from_file_location(
        "whipple_bicycle", _HERE.parent / "examples" / "whipple_bicycle.py")
    wb = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(wb)
    return wb


# -- mechsys ---------------------------------------------------------------------------------

def mechsys_build():
    """``(simulate(t) -> (lean, steer, solution))``: the example's model, freed."""
    wb = _example()
    m, _ = wb.build()
    free = m.free()
    i = free.system.layout.index("rear_frame.e0")
    j = free.system.layout.index("front_frame.e0")
    down = np.array([np.sin(wb.LAM), 0.0, -np.cos(wb.LAM)])
    start = {("omega", "rear_frame"): (KICK, 0.0, 0.0),
             ("omega", "rear_wheel"): (KICK, V / wb.R_R, 0.0)}

    def simulate(t):
        sol = free.simulate(t, initial_condition=start, rtol=RTOL, atol=ATOL, progress=False)
        e = sol.q[:, i:i + 4]
        f = sol.q[:, j:j + 4]
        # lean: the rear frame's axle (its y axis) rises by sin(lean)
        lean = np.arcsin(2 * (e[:, 2] * e[:, 3] + e[:, 0] * e[:, 1]))
        # steer: the fork's rotation relative to the frame about the steer axis, from the
        # relative Euler parameters conj(e) * f
        r0 = np.einsum("ij,ij->i", e, f)
        rv = (e[:, :1] * f[:, 1:] - f[:, :1] * e[:, 1:] - np.cross(e[:, 1:], f[:, 1:]))
        steer = 2 * np.arctan2(rv @ down, r0)
        return lean, steer, sol

    return simulate


# -- SymPy mechanics -------------------------------------------------------------------------

def sympy_build():
    """``(simulate(t) -> (lean, steer, OdeResult))``: the bicycle derived with ``KanesMethod``
    (numbers in place of the parameters from the start), lambdified, integrated by
    ``solve_ivp``."""
    import sympy as sp
    from scipy.integrate import solve_ivp
    from sympy.physics import mechanics as me

    t0 = time.process_time()
    wb = _example()
    lam = sp.pi / 10
    q1, q2, q3, q4 = q = me.dynamicsymbols("q1:5")
    u1, u2, u3, u4, u5, u6 = u = me.dynamicsymbols("u1:7")
    N = me.ReferenceFrame("N")                     # x forward, y left, z up
    Y = N.orientnew("Y", "Axis", (q1, N.z))        # yaw
    L = Y.orientnew("L", "Axis", (q2, Y.x))        # lean (to the right: z turns to -y)
    B = L.orientnew("B", "Axis", (q3, L.y))        # the rear frame, pitch zero when upright
    down = sp.sin(lam) * B.x - sp.cos(lam) * B.z   # the steer axis, pointing down
    H = me.ReferenceFrame("H")                     # the front frame (fork and handlebar)
    H.orient_axis(B, down, q4)
    Rw, Fw = me.ReferenceFrame("Rw"), me.ReferenceFrame("Fw")   # the wheels: only their spin
    Y.set_ang_vel(N, u1 * N.z)
    L.set_ang_vel(Y, u2 * Y.x)
    B.set_ang_vel(L, u3 * L.y)
    H.set_ang_vel(B, u4 * down)
    Rw.set_ang_vel(B, u5 * B.y)
    Fw.set_ang_vel(H, u6 * H.y)

    # points (upright, every body's axes along the global ones; the paper's z down turned up)
    contact_r = me.Point("contact_r")
    contact_r.set_vel(N, 0)                        # rolling without slip: zero velocity
    hub_r = contact_r.locatenew("hub_r", wb.R_R * L.z)
    hub_r.v2pt_theory(contact_r, N, Rw)
    cg_b = hub_r.locatenew("cg_b", wb.XB * B.x + (-wb.ZB - wb.R_R) * B.z)
    cg_b.v2pt_theory(hub_r, N, B)
    pivot = hub_r.locatenew("pivot", (wb.W + wb.C) * B.x - wb.R_R * B.z)   # on the steer axis
    pivot.v2pt_theory(hub_r, N, B)
    cg_h = pivot.locatenew("cg_h", (wb.XH - wb.W - wb.C) * H.x + (-wb.ZH) * H.z)
    cg_h.v2pt_theory(pivot, N, H)
    hub_f = pivot.locatenew("hub_f", -wb.C * H.x + wb.R_F * H.z)
    hub_f.v2pt_theory(pivot, N, H)
    # the front contact: from the hub, in the wheel's plane, straight towards the ground
    toward = (N.z & H.y) * H.y - N.z
    contact_f = hub_f.locatenew("contact_f", wb.R_F * toward / sp.sqrt(1 - (N.z & H.y) ** 2))
    contact_f.v2pt_theory(hub_f, N, Fw)

    def body_inertia(frame, ixx, iyy, izz, ixz=0.0):
        # the paper's z-down product of inertia changes sign in z-up axes
        return me.inertia(frame, ixx, iyy, izz, 0, 0, -ixz)

    bodies = [
        me.RigidBody("rear_wheel", hub_r, Rw, wb.M_R, (body_inertia(B, *wb.IR), hub_r)),
        me.RigidBody("rear_frame", cg_b, B, wb.M_B, (body_inertia(B, *wb.IB), cg_b)),
        me.RigidBody("front_frame", cg_h, H, wb.M_H, (body_inertia(H, *wb.IH), cg_h)),
        me.RigidBody("front_wheel", hub_f, Fw, wb.M_F, (body_inertia(H, *wb.IF), hub_f)),
    ]
    loads = [(b.masscenter, -b.mass * wb.G * N.z) for b in bodies]
    v_f = contact_f.vel(N)
    km = me.KanesMethod(N, q_ind=list(q), u_ind=[u2, u4, u5], u_dependent=[u1, u3, u6],
                     velocity_constraints=[v_f & Y.x, v_f & Y.y, v_f & N.z],
                     kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u[:4])],
                     constraint_solver="CRAMER")
    km.kanes_equations(bodies, loads)
    PHASES["derivation"] = time.process_time() - t0
    # km.u is ordered [independent, dependent]: u2, u4, u5, u1, u3, u6
    ku = list(km.u)
    args = list(q) + ku
    mass = sp.lambdify(args, km.mass_matrix, cse=True)
    forcing = sp.lambdify(args, km.forcing, cse=True)
    order = [ku.index(ui) for ui in u]           # km.u's places of u1..u6

    def rhs(_t, x):
        qu = x[:4], x[4:][order]
        ud = np.linalg.solve(mass(*x), np.asarray(forcing(*x), dtype=float).ravel())
        return np.concatenate((qu[1][:4], ud))

    # the start: upright, lean rate KICK, the wheels' spins v / r; yaw, pitch, steer rates
    # and the front spin are the dependent speeds at this state: yaw 0, pitch 0 by symmetry
    x0 = np.zeros(10)
    x0[4:] = [KICK, 0.0, V / wb.R_R, 0.0, 0.0, V / wb.R_F]       # u2, u4, u5, u1, u3, u6
    rhs(0.0, x0)
    PHASES["lambdify"] = time.process_time() - t0 - PHASES["derivation"]

    def simulate(t):
        # two times: every accepted step is returned (counts them), else those times
        sol = solve_ivp(rhs, (t[0], t[-1]), x0, method="DOP853",
                        t_eval=t if len(t) > 2 else None, rtol=RTOL, atol=ATOL)
        if not sol.success:
            raise RuntimeError(sol.message)
        return sol.y[1], sol.y[3], sol

    def steps_with_wheels():
        """Accepted steps of the same run with the wheels' spin angles added as Euler
        parameter pairs ``(cos, sin)`` of half the angle (as mechsys carries each wheel's
        rotation): what resolving the spinning wheels costs the step size control."""
        def rhs4(t, y):
            w_r, w_f = y[6], y[9]                  # u5, u6 (km.u order)
            return np.concatenate((rhs(t, y[:10]), [-y[11] * w_r / 2, y[10] * w_r / 2,
                                                     -y[13] * w_f / 2, y[12] * w_f / 2]))

        sol = solve_ivp(rhs4, (0.0, T_END), np.concatenate((x0, [1.0, 0.0, 1.0, 0.0])),
                        method="DOP853", rtol=RTOL, atol=ATOL)
        return len(sol.t) - 1

    simulate.steps_with_wheels = steps_with_wheels
    return simulate


# -- one side in a fresh process -------------------------------------------------------------

def side(name: str, whole: bool = False) -> dict:
    """Build one side (CPU time from here, after the imports), run it once over 1 ms, or
    over the whole 10 s (``whole``)."""
    import scipy.integrate  # noqa: F401
    import sympy.physics.mechanics  # noqa: F401

    import mechsys  # noqa: F401  (imports are not part of the build)

    t0 = time.process_time()
    simulate = (mechsys_build if name == "mechsys" else sympy_build)()
    *_, sol = simulate(TIMES if whole else np.array([0.0, 1e-3]))
    out = {"build": time.process_time() - t0, **PHASES}
    if name == "mechsys":
        out["compiled_steps"] = int(sol.extra["compiled_steps"])
    return out


def _background_cpu(numba_dir: Path, timeout: float = 900.0) -> float:
    """The CPU seconds of the background compiles a first run started (decision 0064), read
    from their result files in ``numba_dir`` once no compile holds its lock any more: the
    largest process total of each compiling process, summed."""
    end = time.time() + timeout
    while any(numba_dir.rglob("mechsys-bg-*.lock")) and time.time() < end:
        time.sleep(1.0)
    per_process: dict = {}
    for f in numba_dir.rglob("mechsys-bg-*.json"):
        got = json.loads(f.read_text())
        per_process[got["pid"]] = max(per_process.get(got["pid"], 0.0), got["process_cpu"])
    return float(sum(per_process.values()))


def fresh(name: str, env: dict | None = None, whole: bool = False) -> dict:
    """:func:`side` in a new Python process (capped at :data:`SYMPY_CAP_S`)."""
    code = (f"import sys, json; sys.path.insert(0, {str(_HERE)!r}); import bicycle_kane as b; "
            f"print(json.dumps(b.side({name!r}, {whole!r})))")
    try:
        out = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, **(env or {})),
                             capture_output=True, text=True, check=True, timeout=SYMPY_CAP_S)
    except subprocess.TimeoutExpired:
        return {"build": float("inf")}
    return json.loads(out.stdout.strip().splitlines()[-1])


def _interpreted(simulate):
    """``simulate`` with ``MECHSYS_JIT=0`` (the stepper's own code run by the interpreter,
    decision 0082), for the comparison."""
    def run(t):
        old = os.environ.get("MECHSYS_JIT")
        os.environ["MECHSYS_JIT"] = "0"
        try:
            return simulate(t)
        finally:
            if old is None:
                del os.environ["MECHSYS_JIT"]
            else:
                os.environ["MECHSYS_JIT"] = old

    return run


def measure(rounds: int = 5) -> dict:
    cold, warm, first, first_compiled, background, kernels = [], [], [], [], [], 0
    for _ in range(rounds):
        # a new installation's first run (the default policy), then a cold and a warm
        # build (compile waited), each pair with new caches
        with tempfile.TemporaryDirectory() as tmp:
            got = fresh("mechsys", {"MECHSYS_CACHE": str(Path(tmp) / "kernels"),
                                    "NUMBA_CACHE_DIR": str(Path(tmp) / "numba"),
                                    "MECHSYS_COMPILE": "background"}, whole=True)
            first.append(got["build"])
            first_compiled.append(got["compiled_steps"])
            background.append(_background_cpu(Path(tmp) / "numba"))
        with tempfile.TemporaryDirectory() as tmp:
            caches = {"MECHSYS_CACHE": str(Path(tmp) / "kernels"),
                      "NUMBA_CACHE_DIR": str(Path(tmp) / "numba"), "MECHSYS_COMPILE": "wait"}
            cold.append(fresh("mechsys", caches)["build"])
            kernels = len(list((Path(tmp) / "kernels").glob("*.kernel")))
            warm.append(fresh("mechsys", caches)["build"])
    sym = fresh("sympy")
    if sym["build"] == float("inf"):
        raise SystemExit(f"SymPy's build took more than {SYMPY_CAP_S:.0f} s of CPU: no comparison")
    sims = {"mechsys": mechsys_build(), "sympy": sympy_build()}
    sims["python"] = _interpreted(sims["mechsys"])
    out = {k: f(TIMES) for k, f in sims.items()}          # warm-up, and the compared runs
    times = {k: [] for k in sims}
    for _ in range(rounds):
        for k, f in sims.items():
            t0 = time.process_time()
            f(TIMES)
            times[k].append(time.process_time() - t0)
    (lm, sm, solm), (ls, ss, sols) = out["mechsys"], out["sympy"]
    return {"cold": statistics.median(cold), "warm": statistics.median(warm),
            "cold_all": cold, "warm_all": warm, "kernels": kernels,
            "first": statistics.median(first), "first_all": first,
            "first_compiled_steps": first_compiled,
            "background": statistics.median(background), "background_all": background,
            "sympy_build": sym["build"],
            "sympy_phases": {k: sym.get(k) for k in ("derivation", "lambdify")},
            "run": {k: statistics.median(v) for k, v in times.items()},
            "steps": {"mechsys": solm.extra["steps"], "python": out["python"][2].extra["steps"],
                      "compiled": solm.extra["compiled_steps"],
                      "sympy": len(sims["sympy"](np.array([0.0, T_END]))[2].t) - 1},
            "rejected": {"mechsys": solm.extra.get("rejected")},
            "sympy_steps_with_wheels": sims["sympy"].steps_with_wheels(),
            "evaluations": {"mechsys": solm.extra["evaluations"], "sympy": sols.nfev},
            "lean": float(np.abs(lm - ls).max()), "steer": float(np.abs(sm - ss).max()),
            "lean_peak": float(np.abs(ls).max()), "steer_peak": float(np.abs(ss).max()),
            "lean_end": float(abs(ls[-1])), "rounds": rounds}


def table(r: dict) -> str:
    def sec(x):
        return f"{x:.1f} s" if x >= 1 else f"{1e3 * x:.0f} ms"

    ev, st, run = r["evaluations"], r["steps"], r["run"]
    lines = [
        "| | states | first build + 10 s run, new installation (CPU) | build, cold caches, "
        "compile waited (CPU) | build, warm caches (CPU) | "
        "10 s run (CPU, median) | steps | RHS evaluations | per evaluation |",
        "|---|---|---|---|---|---|---|---|---|",
        f"| mechsys | 56 | {sec(r['first'])} (+ {sec(r['background'])} on the other core, "
        f"once) | {sec(r['cold'])} | {sec(r['warm'])} | {sec(run['mechsys'])} | "
        f"{st['mechsys']} | {ev['mechsys']} | {1e6 * run['mechsys'] / ev['mechsys']:.0f} µs |",
        f"| SymPy `KanesMethod` + SciPy | 10 | {sec(r['sympy_build'] + run['sympy'])} | "
        f"{sec(r['sympy_build'])} | (no cache) | "
        f"{sec(run['sympy'])} | {st['sympy']} | {ev['sympy']} | "
        f"{1e6 * run['sympy'] / ev['sympy']:.0f} µs |",
        "",
        f"Agreement over the 10 s (201 times): lean within {r['lean']:.1e} rad (peak "
        f"{r['lean_peak']:.3f} rad, {r['lean_end']:.1e} rad at 10 s), steer within "
        f"{r['steer']:.1e} rad (peak {r['steer_peak']:.3f} rad). The step counts differ by "
        f"the states: mechsys carries every body's rotation, the wheels' spin (about 15 rad/s) "
        f"included, which SymPy's minimal coordinates leave out; with the two wheels' spins "
        f"added to the SymPy run as Euler parameter pairs it takes "
        f"{r['sympy_steps_with_wheels']} steps instead of {st['sympy']}. SymPy's build: "
        f"{sec(r['sympy_phases']['derivation'])} for the derivation (`kanes_equations`), "
        f"{sec(r['sympy_phases']['lambdify'])} for `lambdify` (common subexpressions) and "
        f"the first evaluation. mechsys's builds: the median of {len(r['cold_all'])} fresh "
        f"processes each (cold {min(r['cold_all']):.2f}-{max(r['cold_all']):.2f} s, warm "
        f"{min(r['warm_all']):.2f}-{max(r['warm_all']):.2f} s); the run compiles "
        f"{r['kernels']} small kernels into the cache and the compiled stepper's loop for the "
        "rolling rows (decision 0062): the cold build compiles it with Numba in its own "
        "process, the warm one loads it from the cache. A new installation's first run "
        "(the default `MECHSYS_COMPILE=background`: "
        f"{min(r['first_all']):.2f}-{max(r['first_all']):.2f} s) does not wait for that "
        f"compile ({max(r['first_compiled_steps'])} compiled steps): it runs on the Python "
        "path (SciPy's DOP853 with the Python derivative, "
        "its 28 coordinates being above the interpreted tier's 12 unknowns, decision 0083) while one "
        "low-priority process compiles the loop on the other core "
        f"({min(r['background_all']):.0f}-{max(r['background_all']):.0f} s of CPU, imports "
        "included); the next session runs compiled. "
        "The same run interpreted (`MECHSYS_JIT=0`, the stepper's "
        "own code, the same numbers): "
        f"{sec(run['python'])} ({r['steps']['python']} steps).",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", metavar="PATH", help="also put the table into this page")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args(argv)
    r = measure(args.rounds)
    text = table(r)
    print(machine())
    print(json.dumps(r, indent=1, default=str))
    print(text)
    if args.write:
        intro = (f"The Whipple bicycle (examples/whipple_bicycle.py) at {V} m/s after a lean-rate "
                 f"kick of {KICK} rad/s, 10 s with DOP853 at rtol {RTOL:g}, atol {ATOL:g}, in "
                 "mechsys and in SymPy mechanics' `KanesMethod` (minimal coordinates, the front "
                 "contact's three velocity constraints, `lambdify(cse=True)`, the mass matrix "
                 "solved at each evaluation) with SciPy's `solve_ivp`. First build + run: CPU "
                 "time of a fresh process from after the imports to the end of the 10 s run, "
                 "with empty kernel and Numba caches and `MECHSYS_COMPILE` unset (what a new "
                 "installation meets). Build: CPU time in a fresh process to the first result "
                 "of a 1 ms run (imports excluded); mechsys with empty kernel and Numba caches "
                 "and `MECHSYS_COMPILE=wait` (cold) and with the ones that run filled (warm). "
                 f"Run: median CPU time over {r['rounds']} interleaved rounds. Method in the "
                 "script's docstring; command: `python benchmarks/bicycle_kane.py --write "
                 f"{args.write}`.")
        block = "\n".join([BEGIN, "", "## The Whipple bicycle against SymPy's `KanesMethod`",
                           "", f"Measured on: {machine()}.", "", intro, "", text, "", END])
        write_block(Path(args.write), BEGIN, END, block)
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
