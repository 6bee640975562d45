"""Factories of classic mechanisms, for docs, demos, tests and benchmarks."""

from __future__ import annotations

import numpy as np
import sympy as sp

from ._model import Model2D
from ._symbols import T
from .constraints import RelativeDistance1, Revolute2, RotationLock1, Translate2


def slider_crank(crank: float = 2.0, rod: float = 6.0, offset: float = 0.0,
                 speed: float = 2 * np.pi, drive=None) -> Model2D:
    """The planar slider-crank of Mech's section 1.2.

    Crank of length ``crank`` pinned to ground at the origin and driven at ``speed`` rad/s
    (``theta = speed T``, or any expression ``drive`` of ``T``); connecting rod of length
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
