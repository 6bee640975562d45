"""Where the 2 s run of the N-link chain spends its time as N grows (issue 35, item 6).

For each N (64, 128, 256, 512, 1024) one fresh process builds ``models.pendulum_chain(N)``,
frees it and runs ``free.simulate((0, 2), rtol=1e-6, atol=1e-8)`` (DOP853, the compiled
stepper on its block path: block-diagonal mass matrix, banded ``S = J M^-1 J^T``), once to
load the stepper, then three times: the median CPU time is the run, and the part of it
inside the compiled loop (``FreeStepper._call("loop", ...)``) is the loop. Steps and
right-hand-side evaluations are those the loop reports (``sol.extra``).

The evaluation is then taken apart with the loop's own arrays, captured from its call, in
a compiled driver of this script that repeats, at the run's last state, the steps of
``_jit_free_loop._accel_blocks`` up to a point (each prefix timed on its own; the
differences are the pieces), in the order the loop runs them:

* **kernel**: the free-motion kernel (mass matrix, loads, Jacobian, ``gamma``; LLVM code);
* **assembly**: the finite check, the packed mass blocks, the Jacobian's segments;
* **blocks**: Cholesky and inverse of every mass block, ``u = M^-1 Q``, ``W = M^-1 J^T``;
* **band**: ``S = J W`` (banded), its Cholesky and solve, ``qdd = u - W lambda``;
* **checks**: the bound and zone tests of the whole ``_accel_blocks`` less the above.

``projection`` is one ``_project_blocks`` (after every accepted step), ``stepper`` what the
loop's time leaves over after ``evaluations x (evaluation)`` and ``steps x (projection)``:
the Runge-Kutta arithmetic, the error norm, the output rows, and the cache misses that the
isolated repetitions (whose data stays in the core's cache) do not pay. ``outside``: the
run less the loop (start, scaling, checks, the solution object).

Run: ``python benchmarks/run_cost.py [N ...]``. CPU seconds; the machine is shared, so
single figures spread 10-40 %.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402

import numpy as np  # noqa: E402

SIZES = (64, 128, 256, 512, 1024)

CHILD = r'''
import json, sys, time
import numba as nb
import numpy as np
from mechsys import models
from mechsys.solvers import _jit_free
from mechsys.solvers._jit_free_loop import (_evalx, _fill_rows, _chol_blocks, _invert_blocks,
    _block_mul, _gram, _band_chol, _band_solve, _accel_blocks, _project_blocks)
clock = time.process_time

@nb.njit
def prefix(stage, K, kp, x, nin, out, kk, kM, n, m, jr, jc, columns, blk_i, Mst, Jst, Wst, Sb,
           u, Minv, Li, qdd, lam, ex, ph):
    bstart, boff, rptr, rblk, roff, jpos, bsize, mpos, segs = blk_i
    nblk = bsize.size
    bw = Sb.shape[1] - 1
    acc = 0.0
    for _ in range(K):
        _evalx(kp, x, nin, out, ex, ph)
        if stage < 2:
            acc += out[0]
            continue
        for k in range(kk + n + m):
            if not np.isfinite(out[k]):
                return -1.0
        Mst[:] = 0.0
        for k in range(kM):
            Mst[mpos[k]] = out[k]
        _fill_rows(out, kM, jpos, Jst, False, lam, columns, jc, jr)
        if stage < 3:
            acc += Jst[0]
            continue
        _chol_blocks(Mst, bstart, boff, nblk)
        _invert_blocks(Mst, Minv, bstart, boff, nblk, Li)
        for b in range(nblk):
            _block_mul(Minv, boff[b], bsize[b], out, kk + bstart[b], u, bstart[b])
        for i in range(m):
            for p in range(rptr[i], rptr[i + 1]):
                b = rblk[p]
                _block_mul(Minv, boff[b], bsize[b], Jst, roff[p], Wst, roff[p])
        if stage < 4:
            acc += Wst[0]
            continue
        _gram(Jst, Wst, segs, bsize, Sb)
        for i in range(m):
            lam[i] = -out[kk + n + i]
        for k in range(jr.size):
            lam[jr[k]] += out[kM + k] * u[jc[k]]
        _band_chol(Sb, m, bw)
        _band_solve(Sb, m, bw, lam)
        for j in range(n):
            qdd[j] = u[j]
        for i in range(m):
            for p in range(rptr[i], rptr[i + 1]):
                b = rblk[p]
                for t in range(bsize[b]):
                    qdd[bstart[b] + t] -= Wst[roff[p] + t] * lam[i]
        acc += qdd[0]
    return acc

@nb.njit
def whole(K, kp, x, nin, out, kk, kM, n, m, jr, jc, rows0, columns, robust, blk_i, Mst, Jst,
          Wst, Sb, u, Minv, Li, qdd, lam, force, ex, ph):
    ok = 0
    for _ in range(K):
        ok += _accel_blocks(kp, x, nin, out, kk, kM, n, m, jr, jc, rows0, columns, robust,
                            blk_i, Mst, Jst, Wst, Sb, u, Minv, Li, qdd, lam, force, ex, ph)
    return ok

@nb.njit
def projection(K, pp, pv, xk, nin_k, out_pos, out_vel, jr, jc, columns, offset, n, m, t, y0,
               y, r, Fs, dq, blk_i, Pst, Sb, ex, ph):
    ok = 0
    for _ in range(K):
        y[:] = y0
        ok += _project_blocks(pp, pv, xk, nin_k, out_pos, out_vel, jr, jc, columns, offset,
                              1e-12, 8, True, n, m, t, y, r, Fs, dq, blk_i, Pst, Sb, ex, ph)
    return ok

def per_call(fn, *args):
    fn(1, *args)
    K = 1
    while True:
        t = clock(); fn(K, *args); dt = clock() - t
        if dt > 0.3:
            return dt / K
        K *= 4

n = int(sys.argv[1])
model = models.pendulum_chain(n); model.solve(0.0)
free = model.free(drop=[f"lock{k}" for k in range(n)]); free.solve(0.0)
cap = {}
orig = _jit_free.FreeStepper._call
def spy(self, name, *args):
    t = clock(); r = orig(self, name, *args)
    if name == "loop":
        cap["loop"] = cap.get("loop", 0.0) + clock() - t
        cap["args"] = args
    return r
_jit_free.FreeStepper._call = spy
free.simulate((0.0, 2.0), rtol=1e-6, atol=1e-8)
runs = []
for _ in range(3):
    cap.pop("loop", None)
    t = clock(); sol = free.simulate((0.0, 2.0), rtol=1e-6, atol=1e-8)
    runs.append((clock() - t, cap["loop"]))
run, loop = sorted(runs)[1]
a = cap["args"]
kp, p, kk, nn, mm, jr, jc, rows0, columns, offset, mode, blk_i, ws = (
    a[0], a[2], a[5], a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[14], a[15], a[16])
(x, xk, out, out_pos, out_vel, _, _, _, _, _, _, _, _, qdd, lam, force, blk_w, _, r, Fs, dq,
 *_) = ws
Mst, Jst, Wst, Sb, u, Pst, Minv, Li = blk_w[0]
ex, ph = blk_i[2], blk_w[2]
nin = 1 + 2 * nn + mm + p.size + nn
kM = kk - jr.size
common = (kp[0], x, nin, out, kk, kM, nn, mm, jr, jc, columns, blk_i[0], Mst, Jst, Wst, Sb, u,
          Minv, Li, qdd, lam, ex[0], ph[0])
st = {s: per_call(lambda K, *z, s=s: prefix(s, K, *z), *common) for s in (1, 2, 3, 4)}
ev = per_call(whole, kp[0], x, nin, out, kk, kM, nn, mm, jr, jc, rows0, columns, True,
              blk_i[0], Mst, Jst, Wst, Sb, u, Minv, Li, qdd, lam, force, ex[0], ph[0])
y0 = np.array(a[33])
pr = per_call(projection, kp[1], kp[2], xk, 1 + 2 * nn + p.size, out_pos, out_vel, jr, jc,
              columns, offset, nn, mm, float(a[32][0]), y0, y0.copy(), r, Fs, dq, blk_i[0], Pst,
              Sb, ex, ph)
e = sol.extra
row = dict(N=n, mode=int(mode), bandwidth=int(Sb.shape[1] - 1), run=run, loop=loop,
           steps=e["steps"], evaluations=e["evaluations"], rejected=e["rejected"],
           kernel=st[1], assembly=st[2] - st[1], blocks=st[3] - st[2], band=st[4] - st[3],
           checks=ev - st[4], evaluation=ev, projection=pr)
row["stepper"] = loop - row["evaluations"] * ev - row["steps"] * pr
row["outside"] = run - loop
print(json.dumps(row))
'''


def measure(n: int) -> dict:
    env = dict(os.environ, MECHSYS_COMPILE="wait")   # (the stepper compiled here if need be)
    out = subprocess.run([sys.executable, "-c", CHILD, str(n)], env=env, capture_output=True,
                         text=True)
    if out.returncode:
        raise RuntimeError(f"N = {n}: the measuring process failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def growth(rows, key) -> float:
    a, b = rows[0], rows[-1]
    return float(np.log(b[key] / a[key]) / np.log(b["N"] / a["N"]))


def main(argv) -> None:
    sizes = [int(x) for x in argv] or list(SIZES)
    rows = []
    for n in sizes:
        r = measure(n)
        r["per_step"] = r["run"] / r["steps"]
        r["per_eval_loop"] = r["loop"] / r["evaluations"]
        rows.append(r)
        print(json.dumps(r), file=sys.stderr, flush=True)
    us = 1e6
    print("| N | steps | evaluations | run [s] | loop [s] | outside [s] | per step [ms] | "
          "per evaluation in the loop [µs] | kernel | assembly | blocks | band | checks | "
          "evaluation alone [µs] | projection [µs] | stepper rest [s] |")
    print("| ---: " * 16 + "|")
    for r in rows:
        print(f"| {r['N']} | {r['steps']} | {r['evaluations']} | {r['run']:.3f} | "
              f"{r['loop']:.3f} | {r['outside']:.3f} | {1e3 * r['per_step']:.2f} | "
              f"{us * r['per_eval_loop']:.0f} | {us * r['kernel']:.0f} | "
              f"{us * r['assembly']:.0f} | {us * r['blocks']:.0f} | {us * r['band']:.0f} | "
              f"{us * r['checks']:.0f} | {us * r['evaluation']:.0f} | "
              f"{us * r['projection']:.0f} | {r['stepper']:.3f} |")
    if len(rows) >= 2:
        a, b = rows[0]["N"], rows[-1]["N"]
        print(f"\nGrowth from N = {a} to {b}: run N^{growth(rows, 'run'):.2f}, steps "
              f"N^{growth(rows, 'steps'):.2f}, evaluations N^{growth(rows, 'evaluations'):.2f}, "
              f"per step N^{growth(rows, 'per_step'):.2f}, per evaluation in the loop "
              f"N^{growth(rows, 'per_eval_loop'):.2f}, evaluation alone "
              f"N^{growth(rows, 'evaluation'):.2f}, kernel N^{growth(rows, 'kernel'):.2f}.")


if __name__ == "__main__":
    main(sys.argv[1:])
