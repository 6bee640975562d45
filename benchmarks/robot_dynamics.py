"""Imported robots: the first inverse dynamics in a fresh process, and the cost per point of
inverse and forward dynamics beside Pinocchio (C++) and MuJoCo on the same file.

Robots: the UR5 (6 joints) and the Panda (7 arm joints, 2 finger slides) of
``example-robot-data``. ``first`` is the CPU time of a fresh interpreter that imports
mechsys, reads the URDF (``ms.from_urdf``) and evaluates one inverse dynamics (everything
compiled on the way; mechsys's kernel cache empty, Numba's as installed). The
per-point columns are CPU time per state, median of interleaved repetitions over 200 random
states: mechsys ``m.inverse_dynamics`` / ``m.forward_dynamics`` over all 200 at once,
Pinocchio ``rnea`` / ``aba`` and MuJoCo ``mj_inverse`` / ``mj_forward`` (constraints off) in a
Python loop (each call crosses into C/C++ once per state).

Run: ``.venv/bin/python benchmarks/robot_dynamics.py`` (about a minute) prints the table.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import importlib.metadata  # noqa: E402
import re  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from _machine import machine  # noqa: E402  (sibling module)

SHARE = Path(importlib.metadata.distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots"))
ROBOTS = {"UR5": SHARE / "ur_description/urdf/ur5_robot.urdf",
          "Panda": SHARE / "panda_description/urdf/panda.urdf"}
N = 200
REPEAT = 5

FIRST = """
import time
t0 = time.process_time()
import numpy as np
import mechsys as ms
m = ms.from_urdf({path!r})
n = m.compile().n
m.inverse_dynamics(np.zeros(n), np.zeros(n), np.zeros(n))
print(time.process_time() - t0)
"""


def first(path: Path) -> float:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, MECHSYS_CACHE=cache)
        out = subprocess.run([sys.executable, "-c", FIRST.format(path=str(path))], env=env,
                             capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def median_per_point(fn) -> float:
    times = []
    for _ in range(REPEAT):
        t0 = time.process_time()
        fn()
        times.append((time.process_time() - t0) / N)
    return float(np.median(times))


def row(name: str, path: Path) -> str:
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

    def pin_id():
        for k in range(N):
            pin.rnea(pm, pd, Q[k], QD[k], QDD[k])

    def pin_fd():
        for k in range(N):
            pin.aba(pm, pd, Q[k], QD[k], tau[k])

    def mj_id():
        for k in range(N):
            md.qpos[:], md.qvel[:], md.qacc[:] = Q[k], QD[k], QDD[k]
            mujoco.mj_inverse(mm, md)

    def mj_fd():
        for k in range(N):
            md.qpos[:], md.qvel[:], md.qfrc_applied[:] = Q[k], QD[k], tau[k]
            mujoco.mj_forward(mm, md)

    us = {k: 1e6 * median_per_point(f) for k, f in [
        ("ms_id", lambda: m.inverse_dynamics(Q, QD, QDD)), ("pin_id", pin_id), ("mj_id", mj_id),
        ("ms_fd", lambda: m.forward_dynamics(Q, QD, tau)), ("pin_fd", pin_fd), ("mj_fd", mj_fd)]}
    return (f"| {name} | {n} | {first(path):.2f} | {us['ms_id']:.1f} | {us['pin_id']:.1f} | "
            f"{us['mj_id']:.1f} | {us['ms_fd']:.1f} | {us['pin_fd']:.1f} | {us['mj_fd']:.1f} |")


def main() -> None:
    print(machine())
    print()
    print("| robot | joints | first [s CPU] | ID mechsys [us] | ID Pinocchio | ID MuJoCo "
          "| FD mechsys [us] | FD Pinocchio | FD MuJoCo |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, path in ROBOTS.items():
        print(row(name, path), flush=True)


if __name__ == "__main__":
    main()
