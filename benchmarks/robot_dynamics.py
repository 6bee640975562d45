"""Imported robots: the first inverse dynamics in a fresh process, and the cost per point of
inverse and forward dynamics beside Pinocchio (C++) and MuJoCo on the same file (issue 37,
items 2 and 5; decisions 0057, 0073).

Robots: the UR5 (6 joints) and the Panda (7 arm joints and 2 finger slides) of
``example-robot-data``.

* ``first``: CPU time (user + system, ``resource.getrusage``, imports included) of a fresh
  interpreter that imports mechsys, reads the URDF (``ms.from_urdf``) and evaluates one
  inverse dynamics, with new empty Numba and kernel caches (``NUMBA_CACHE_DIR``,
  ``MECHSYS_CACHE``); then of a second fresh process with the caches the first filled. The
  median of ``FIRST`` such pairs, run one after the other, and the phases of the cold one
  (import, reading the file, the first inverse dynamics). mechsys's bytecode is compiled
  first (``compileall``, as ``pip install`` does): with ``PYTHONDONTWRITEBYTECODE`` set and
  a source checkout, every process would otherwise compile its ~100 modules from source
  (about 0.4 s, decision 0065).
* ``FD first``: the same for one forward dynamics instead (``FIRST_FD`` cold processes).
* per point: CPU time per state over ``N`` random states, median of ``REPEAT`` interleaved
  rounds (every tool once per round) after a warm-up: mechsys ``m.inverse_dynamics`` /
  ``m.forward_dynamics`` over all ``N`` at once (``MECHSYS_JIT`` unset: the compiled loops
  from 100 points on), Pinocchio ``rnea`` / ``aba`` and MuJoCo ``mj_inverse`` /
  ``mj_forward`` (constraints off) in a Python loop, one call per state, and Pinocchio's
  batched ``abaInParallel`` on one thread (its C++ loop over the states).

Run from the repository root (a few minutes)::

    PYTHONPATH=$PWD/src python benchmarks/robot_dynamics.py
    PYTHONPATH=$PWD/src python benchmarks/robot_dynamics.py --write docs/performance.md
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before NumPy loads: CPU time of one thread

import importlib.metadata  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machine import table_main  # noqa: E402  (sibling module)

SHARE = Path(importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots"))
ROBOTS = {"UR5": SHARE / "ur_description/urdf/ur5_robot.urdf",
          "Panda": SHARE / "panda_description/urdf/panda.urdf"}
N = 10_000
REPEAT = 5
FIRST = 5
FIRST_FD = 3

_FIRST = """
import resource, json
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
t = [cpu()]
import numpy as np
import mechsys as ms
t.append(cpu())
m = ms.from_urdf({path!r})
t.append(cpu())
n = m.compile().n
tau = m.{call}(np.zeros(n), np.zeros(n), np.zeros(n))
t.append(cpu())
print(json.dumps({{"cpu": t[-1], "phases": [t[1], t[2] - t[1], t[3] - t[2]]}}))
"""


def _bytecode() -> None:
    """Compile mechsys's modules to bytecode (what ``pip install`` does), so that a fresh
    process reads them instead of compiling their source."""
    import compileall
    import importlib.util

    spec = importlib.util.find_spec("mechsys")
    compileall.compile_dir(str(Path(spec.origin).parent), quiet=1)


def _fresh(path: Path, numba_cache: str, mechsys_cache: str,
           call: str = "inverse_dynamics") -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=numba_cache, MECHSYS_CACHE=mechsys_cache)
    env.pop("MECHSYS_JIT", None)
    out = subprocess.run([sys.executable, "-c", _FIRST.format(path=str(path), call=call)], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def first(path: Path) -> tuple[float, float, list[float]]:
    """``(cold, second session, phases of the cold one)`` CPU seconds, medians of
    :data:`FIRST` pairs; the phases: interpreter start and ``import mechsys``, reading the
    file, the first inverse dynamics."""
    _bytecode()
    cold, warm = [], []
    for _ in range(FIRST):
        with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
            cold.append(_fresh(path, nb, mc))
            warm.append(_fresh(path, nb, mc))
    phases = [statistics.median(c["phases"][k] for c in cold) for k in range(3)]
    return (statistics.median(c["cpu"] for c in cold), statistics.median(w["cpu"] for w in warm),
            phases)


def first_fd(path: Path) -> float:
    """CPU seconds of a fresh process with empty caches to its first forward dynamics (one
    state: the Python path), median of :data:`FIRST_FD`."""
    cold = []
    for _ in range(FIRST_FD):
        with tempfile.TemporaryDirectory() as nb, tempfile.TemporaryDirectory() as mc:
            cold.append(_fresh(path, nb, mc, "forward_dynamics")["cpu"])
    return statistics.median(cold)


def per_point(name: str, path: Path) -> dict:
    """Microseconds of CPU per state of each tool (median of interleaved rounds)."""
    import mujoco
    import pinocchio as pin

    import mechsys as ms

    m = ms.from_urdf(path)
    n = m.compile().n
    rng = np.random.default_rng(0)
    Q, QD, QDD = rng.uniform(-1, 1, size=(3, N, n)) * [[[1.0] * min(n, 7) + [0.02] * (n - 7)]]
    tau = m.inverse_dynamics(Q, QD, QDD).values          # warm-up (compiles)
    m.forward_dynamics(Q, QD, tau)
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    text = re.sub(r"<(visual|collision)>.*?</\1>", "", path.read_text(), flags=re.S)
    mm = mujoco.MjModel.from_xml_string(text)
    mm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    md = mujoco.MjData(mm)
    ref = np.array([pin.rnea(pm, pd, Q[k], QD[k], QDD[k]) for k in range(N)])
    err = float(np.abs(tau - ref).max() / np.abs(ref).max())
    acc = m.forward_dynamics(Q, QD, tau).values
    ref = np.array([pin.aba(pm, pd, Q[k], QD[k], tau[k]) for k in range(N)])
    err_fd = float(np.abs(acc - ref).max() / np.abs(ref).max())
    pool = pin.ModelPool(pm, 1)
    Qt, QDt, Tt = (np.asfortranarray(a.T) for a in (Q, QD, tau))
    batch = np.zeros((n, N), order="F")

    def pin_id():
        for k in range(N):
            pin.rnea(pm, pd, Q[k], QD[k], QDD[k])

    def pin_fd():
        for k in range(N):
            pin.aba(pm, pd, Q[k], QD[k], tau[k])

    def pin_fd_batch():
        pin.abaInParallel(1, pool, Qt, QDt, Tt, batch)

    def mj_id():
        for k in range(N):
            md.qpos[:], md.qvel[:], md.qacc[:] = Q[k], QD[k], QDD[k]
            mujoco.mj_inverse(mm, md)

    def mj_fd():
        for k in range(N):
            md.qpos[:], md.qvel[:], md.qfrc_applied[:] = Q[k], QD[k], tau[k]
            mujoco.mj_forward(mm, md)

    tools = {"ms_id": lambda: m.inverse_dynamics(Q, QD, QDD), "pin_id": pin_id, "mj_id": mj_id,
             "ms_fd": lambda: m.forward_dynamics(Q, QD, tau), "pin_fd": pin_fd,
             "pin_fd_batch": pin_fd_batch, "mj_fd": mj_fd}
    times: dict = {k: [] for k in tools}
    for _ in range(REPEAT):
        for key, fn in tools.items():
            t0 = time.process_time()
            fn()
            times[key].append((time.process_time() - t0) / N)
    out = {k: 1e6 * statistics.median(v) for k, v in times.items()}
    out["n"], out["err"], out["err_fd"] = n, err, err_fd
    print(f"{name}: {out}", file=sys.stderr)
    return out


def table() -> str:
    import mujoco
    import pinocchio as pin

    lines = [f"Pinocchio {pin.__version__}, MuJoCo {mujoco.__version__}.", "",
             "| robot | joints | first, cold [s CPU] | first, second session [s CPU] | "
             "FD first, cold [s CPU] | ID mechsys [µs] | ID Pinocchio | ID MuJoCo | "
             "FD mechsys [µs] | FD Pinocchio | FD Pinocchio batched | FD MuJoCo | "
             "ID vs Pinocchio | FD vs Pinocchio |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
             "| ---: | ---: |"]
    split = ["", "Phases of the cold first call (CPU s, medians): interpreter start and "
             "`import mechsys`; `ms.from_urdf`; `compile()` and the first "
             "`inverse_dynamics` (symbolic derivation and kernels).", "",
             "| robot | start + import | read URDF | first inverse dynamics |",
             "| --- | ---: | ---: | ---: |"]
    for name, path in ROBOTS.items():
        cold, warm, phases = first(path)
        print(f"{name}: first {cold:.2f} s cold, {warm:.2f} s cached, phases {phases}",
              file=sys.stderr)
        fd_cold = first_fd(path)
        print(f"{name}: first forward dynamics {fd_cold:.2f} s cold", file=sys.stderr)
        us = per_point(name, path)
        lines.append(f"| {name} | {us['n']} | {cold:.2f} | {warm:.2f} | {fd_cold:.2f} | "
                     f"{us['ms_id']:.1f} | {us['pin_id']:.1f} | {us['mj_id']:.1f} | "
                     f"{us['ms_fd']:.1f} | {us['pin_fd']:.1f} | {us['pin_fd_batch']:.1f} | "
                     f"{us['mj_fd']:.1f} | {us['err']:.0e} | {us['err_fd']:.0e} |")
        split.append(f"| {name} | {phases[0]:.2f} | {phases[1]:.2f} | {phases[2]:.2f} |")
    return "\n".join(lines + split)


INTRO = ("`first`: CPU time (imports included) of a fresh process that imports mechsys, reads "
         "the URDF and evaluates one inverse dynamics, with empty Numba and kernel caches "
         "(`NUMBA_CACHE_DIR`, `MECHSYS_CACHE` in new directories), then of a second fresh "
         f"process with the caches the first filled (median of {FIRST} pairs; mechsys's "
         "bytecode compiled first, as `pip install` does); `FD first`: the same cold process "
         f"with one forward dynamics instead (median of {FIRST_FD}). Then CPU time "
         f"per state, median of {REPEAT} interleaved rounds over {N} random states: mechsys's "
         "`m.inverse_dynamics` (ID) and `m.forward_dynamics` (FD) over all of them in one call "
         "(the compiled loop over points from 100 points on, decision 0073); Pinocchio's "
         "`rnea`/`aba` and MuJoCo's `mj_inverse`/`mj_forward` called once per state from "
         "Python (MuJoCo's forward step also computes what its simulation needs beyond the "
         "accelerations), and Pinocchio's `abaInParallel` on one thread over all states "
         "(batched). Last columns: mechsys's joint forces against Pinocchio's RNEA and its "
         "accelerations against Pinocchio's ABA, relative. Decision 0057 has the numbers "
         "before its changes, 0065 those of the first call, 0073 those of forward dynamics "
         "before its compiled loop.")


def main(argv=None) -> int:
    return table_main(__doc__, "robot_dynamics", "Imported robots", INTRO, table, argv)


if __name__ == "__main__":
    raise SystemExit(main())
