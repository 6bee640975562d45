"""The peer problems: data, independent references and the accuracy measures.

Conventions shared by every package: planar, x horizontal, y up, g = 9.81 along -y; every
link a uniform rod (mass m = rho L, centroidal inertia m L^2 / 12). Accuracy is the largest
absolute difference of the final *absolute* link angles (from +x, counter-clockwise,
unwrapped) from the reference, in rad.

* A  double pendulum, 10 s: two rods of 1 m, 1 kg released at rest, both horizontal.
* B  N-link chain, 2 s, N = 4, 16, 64, 256: the same rods, the same start.
* C  four-bar, 5 s: ground 4 m, crank 1, coupler 4, rocker 3, rods of 1 kg/m, crank at
     90 degrees (up), upper assembly, released at rest. The loop-closure gap (the distance
     between the coupler's and the rocker's copy of their common pin) is reported beside
     the error.
* D  slider-crank sweep: crank 2, rod 6, piston on the x axis, crank angle 2 pi t;
     positions, velocities and accelerations at 1000 times over t in [0, 1].

References are computed here, independently of every package measured:

* A and C: the minimal-coordinate Lagrange equations, integrated in mpmath by
  Gragg-Bulirsch-Stoer extrapolation (``benchmarks/free_motion.py``'s references).
* B: the minimal-coordinate equations of the chain in absolute angles,
  ``sum_j c_ij [cos(phi_i - phi_j) phi_j'' + sin(phi_i - phi_j) phi_j'^2] + I phi_i''
  = -m g L s_i cos(phi_i)``, with ``c_ij = m L^2 sum_k a_ki a_kj`` (``a_kj`` = 1 below the
  diagonal, 1/2 on it) and ``s_i = sum_k a_ki``, integrated by SciPy's DOP853 at
  rtol = atol = 1e-12 (checked against a run at 1e-11: the difference is printed).

The references are cached in ``reference_cache.json`` beside this file (delete it, or pass
``--fresh-reference`` to ``run.py``, to recompute them).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # benchmarks/: free_motion.py, _machine.py

G = 9.81
CHAIN_SIZES = (4, 16, 64, 256)
T_PENDULUM, T_CHAIN, T_FOUR_BAR = 10.0, 2.0, 5.0
# four-bar: ground, crank, coupler, rocker lengths; rods of 1 kg/m
FB_GROUND, FB_CRANK, FB_COUPLER, FB_ROCKER = 4.0, 1.0, 4.0, 3.0
FB_CRANK0 = np.pi / 2
CACHE = HERE / "reference_cache.json"


def four_bar_angles(crank: float) -> tuple[float, float]:
    """Absolute coupler and rocker angles at crank angle ``crank`` (upper assembly)."""
    bx, by = FB_CRANK * np.cos(crank), FB_CRANK * np.sin(crank)
    dx, dy = FB_GROUND - bx, -by
    d = np.hypot(dx, dy)
    along = (FB_COUPLER**2 - FB_ROCKER**2 + d * d) / (2 * d)
    up = np.sqrt(max(FB_COUPLER**2 - along**2, 0.0))
    cx = bx + (along * dx - up * dy) / d
    cy = by + (along * dy + up * dx) / d
    return float(np.arctan2(cy - by, cx - bx)), float(np.arctan2(cy, cx - FB_GROUND))


def four_bar_gap(angles) -> float:
    """Loop-closure gap of absolute link angles (crank, coupler, rocker)."""
    a, b, c = angles
    gx = FB_CRANK * np.cos(a) + FB_COUPLER * np.cos(b) - FB_GROUND - FB_ROCKER * np.cos(c)
    gy = FB_CRANK * np.sin(a) + FB_COUPLER * np.sin(b) - FB_ROCKER * np.sin(c)
    return float(np.hypot(gx, gy))


def chain_rhs(n: int):
    """Right-hand side of the chain's minimal-coordinate equations (see the module text)."""
    below = np.tril(np.ones((n, n)), -1) + 0.5 * np.eye(n)      # a[k, j]
    c = below.T @ below
    s = below.sum(axis=0)
    inertia = np.eye(n) / 12.0

    def rhs(_t, y):
        phi, w = y[:n], y[n:]
        d = phi[:, None] - phi[None, :]
        mass = c * np.cos(d) + inertia
        force = -(c * np.sin(d)) @ (w * w) - G * s * np.cos(phi)
        return np.concatenate([w, np.linalg.solve(mass, force)])

    return rhs


def _chain_reference(n: int) -> dict:
    from scipy.integrate import solve_ivp

    out = {}
    for tol in (1e-12, 1e-11):
        c0 = time.process_time()
        r = solve_ivp(chain_rhs(n), (0.0, T_CHAIN), np.zeros(2 * n), method="DOP853",
                      rtol=tol, atol=tol)
        out[tol] = (r.y[:n, -1], time.process_time() - c0)
    best, other = out[1e-12][0], out[1e-11][0]
    return {"phi": best.tolist(), "check": float(np.abs(best - other).max()),
            "cpu": out[1e-12][1]}


def references(fresh: bool = False, sizes=CHAIN_SIZES) -> dict:
    """Final absolute angles of every problem: ``{"A": [...], "C": [...], "B": {N: [...]}}``
    with a ``"check"`` (difference from a looser second run) for each."""
    cache = {} if fresh or not CACHE.exists() else json.loads(CACHE.read_text())
    changed = False
    if "A" not in cache or "C" not in cache:
        import free_motion

        for key, problem in (("A", "double pendulum"), ("C", "four-bar")):
            print(f"reference {key} ({problem}) in mpmath ...", flush=True)
            ref = free_motion.reference(problem, quick=False)
            phi = [float(v) for v in ref["q"]]
            if key == "C":     # the crank's reference; the other angles by closure
                phi = [phi[0], *four_bar_angles(phi[0])]
            cache[key] = {"phi": phi, "check": ref.get("accuracy")}
        changed = True
    cache.setdefault("B", {})
    for n in sizes:
        if str(n) not in cache["B"]:
            print(f"reference B (chain N = {n}) by DOP853 at 1e-12 ...", flush=True)
            cache["B"][str(n)] = _chain_reference(n)
            changed = True
    if changed:
        CACHE.write_text(json.dumps(cache, indent=1))
    return cache


def angle_error(angles, reference) -> float:
    return float(np.abs(np.asarray(angles, float) - np.asarray(reference, float)).max())


def slider_crank_closed_form(t: np.ndarray, r: float = 2.0, rod: float = 6.0) -> np.ndarray:
    """Problem D in vectorised NumPy: crank angle 2 pi t, rod angle from
    ``rod sin(phi) = -r sin(theta)``, piston x; each with its first two derivatives.
    Returns shape ``(9, len(t))``: theta, phi, x and their rates and accelerations."""
    w = 2 * np.pi
    th = w * t
    k = r / rod
    phi = np.arcsin(-k * np.sin(th))
    cphi = np.cos(phi)
    phid = -k * w * np.cos(th) / cphi
    phidd = (k * w * w * np.sin(th) + phid * phid * np.sin(phi)) / cphi
    x = r * np.cos(th) + rod * cphi
    xd = -r * w * np.sin(th) - rod * np.sin(phi) * phid
    xdd = -r * w * w * np.cos(th) - rod * (np.cos(phi) * phid * phid + np.sin(phi) * phidd)
    return np.stack([th, phi, x, np.full_like(t, w), phid, xd, np.zeros_like(t), phidd, xdd])
