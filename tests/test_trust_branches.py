"""Issue 34: sweeps keep the assembly branch of the model, and coarse time steps are not
refused (decision 0035). References: the four-bar's closed form (the two intersections of
the circles about the crank tip and the rocker pivot) and the slider-crank's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T
from mechsys.models import four_bar, slider_crank_dynamic

pytestmark = pytest.mark.filterwarnings("ignore::mechsys.NearSingularWarning")

GROUND, ROCKER = 4.0, 3.0


def rocker_angle(a, b, th, branch=1):
    """Closed form: the rocker angle of the four-bar (ground 4, rocker 3, crank ``a``, coupler
    ``b``, crank angle ``th``) on ``branch`` (+1: rocker tip above the line from the rocker
    pivot to the crank tip, the branch of ``models.four_bar``'s guess)."""
    ax, ay = a * np.cos(th), a * np.sin(th)
    dx, dy = ax - GROUND, ay
    d = np.hypot(dx, dy)
    c = (ROCKER**2 + d**2 - b**2) / (2 * ROCKER * d)
    return np.arctan2(dy, dx) - branch * np.arccos(c)


def wrapped(x):
    return np.abs(np.angle(np.exp(1j * np.asarray(x))))


def build_four_bar():
    """``models.four_bar`` with the crank ``a`` and coupler ``b`` as parameters, crank angle T."""
    m = ms.Model2D()
    a, b = m.parameter("a", 1.0), m.parameter("b", 4.0)
    cr = m.add_body("crank", points={"tip": (a, 0)}, guess=((0, 0), 0))
    ro = m.add_body("rocker", points={"tip": (ROCKER, 0)},
                    guess=((GROUND, 0), rocker_angle(1.0, 4.0, 0.0)))
    m.add(ms.Revolute2(m.ground.point((0, 0)), cr.point(0)))
    m.add(ms.Revolute2(m.ground.point((GROUND, 0)), ro.point(0)))
    m.add(ms.RelativeDistance1(cr.point("tip"), ro.point("tip"), b))
    m.add(ms.RotationLock1(cr, T))
    return m


def test_parameter_sweep_rows_stay_on_the_assembly_branch():
    """78 rows of link lengths at t = 3 (crank angle 3 rad): 16 were on the mirrored branch."""
    A, B = np.linspace(0.8, 1.2, 6), np.linspace(3.5, 4.5, 13)
    with warnings.catch_warnings():
        warnings.simplefilter("error")           # no row flagged, nothing left unchecked
        df = ms.sweep(build_four_bar(), {"a": A, "b": B}, "location", t=3.0,
                      outputs={"phi": lambda s: np.ravel(s.q)[-1]})
    assert len(df) == 78
    err = wrapped(df["phi"] - rocker_angle(df["a"].to_numpy(), df["b"].to_numpy(), 3.0))
    assert err.max() < 1e-9


def test_parameter_sweep_velocity_rows_on_the_branch():
    """The velocity rows too: the rocker's rate from the closed form's derivative (central
    difference in the crank angle, which is T)."""
    df = ms.sweep(build_four_bar(), {"a": [0.8, 1.2], "b": [3.5, 4.5]}, "velocity", t=3.0,
                  outputs={"phi": lambda s: np.ravel(s.q)[-1], "w": lambda s: np.ravel(s.qd)[-1]})
    a, b = df["a"].to_numpy(), df["b"].to_numpy()
    h = 1e-6
    w = (rocker_angle(a, b, 3.0 + h) - rocker_angle(a, b, 3.0 - h)) / (2 * h)
    assert wrapped(df["phi"] - rocker_angle(a, b, 3.0)).max() < 1e-9
    np.testing.assert_allclose(df["w"], w, rtol=1e-6, atol=1e-8)


def test_rows_that_cannot_keep_the_branch_are_flagged():
    """A coupler (7) that closes the loop at t = 3 but not at t = 0, where the model's
    assembly is: which branch the row belongs to cannot be told, so it is flagged (NaN, the
    reason, a warning naming it), while its neighbours stay on the branch."""
    with pytest.warns(UserWarning, match=r"rows \[1\]"):
        df = ms.sweep(build_four_bar(), {"b": [4.0, 7.0, 4.2]}, "location", t=3.0,
                      outputs={"phi": lambda s: np.ravel(s.q)[-1]}, on_error="nan")
    assert np.isnan(df["phi"][1]) and "assembly branch" in df["error"][1]
    ok = df.index != 1
    assert wrapped(df["phi"][ok] - rocker_angle(1.0, df["b"][ok].to_numpy(), 3.0)).max() < 1e-9


@pytest.mark.parametrize("jit", ["0", "1"])
@pytest.mark.parametrize("kind", ["location", "acceleration"])
@pytest.mark.parametrize("deg", [100, 110, 120, 130, 140, 150, 180])
def test_coarse_time_steps_keep_the_branch(monkeypatch, jit, kind, deg):
    """Crank steps of 110-150 degrees put rows on the mirrored branch (acceleration), or were
    refused (location); both loops now follow the closed form at every row."""
    monkeypatch.setenv("MECHSYS_JIT", jit)
    t = np.arange(0, 4 * np.pi, np.radians(deg))
    sol = four_bar().solve(t, kind)
    assert wrapped(sol.q[:, -1] - rocker_angle(1.0, 4.0, t)).max() < 1e-9
    np.testing.assert_allclose(sol.q[:, 2], t, atol=1e-12)      # the crank, continuous
    if kind == "acceleration":
        fine = four_bar().solve(np.linspace(0, t[-1], 40 * (len(t) - 1) + 1), kind)
        # the fine sweep's rows at the coarse times (every 40th) give the same rates
        np.testing.assert_allclose(sol.qd, fine.qd[::40], atol=1e-8)
        np.testing.assert_allclose(sol.qdd, fine.qdd[::40], atol=1e-8)


@pytest.mark.parametrize("kind", ["location", "velocity", "acceleration", "static",
                                  "kinematic", "dynamic"])
def test_driven_crank_at_coarse_times_every_kind(kind):
    """t = 0, 1/2, 1 revolution: location and static raised "jumped by 3.14 rad"; every kind
    now gives the driven angles and the closed-form piston position."""
    m = slider_crank_dynamic()
    sol = m.solve([0.0, 0.5, 1.0], kind)
    np.testing.assert_allclose(sol.q[:, 2], [0, np.pi, 2 * np.pi], atol=1e-12)
    th = np.array([0, np.pi, 2 * np.pi])
    x = 2 * np.cos(th) + np.sqrt(36 - (2 * np.sin(th)) ** 2)
    np.testing.assert_allclose(sol.location(m.body("piston").point(0))[:, 0], x, atol=1e-12)
    ref = m.solve([0.0, 0.5, 1.0], "acceleration")
    np.testing.assert_allclose(sol.q, ref.q, atol=1e-12)


def test_fine_sweeps_are_the_loops_own():
    """Steps below the check (pi/6 of rotation) are not re-solved: identical to one sweep."""
    from mechsys.solvers import _kinematics as K

    m = four_bar()
    system = m.compile()
    t = np.linspace(0, 2 * np.pi, 61)
    a = K.sweep(system, t, m.guess(), 2, None, m._p())
    b = K._sweep_loop(system, t, m.guess(), 2, None, m._p())
    np.testing.assert_array_equal(a.q, b.q)
    assert a.evaluations == b.evaluations


def test_a_crank_turning_back_at_coarse_times():
    """A driver sin(T) sampled every 2.5 rad of time: the crank's angle follows the driver and
    the rocker stays on its branch."""
    m = four_bar(crank_angle=2.5 * sp.sin(T))
    t = np.arange(0, 12, 1.3)
    sol = m.solve(t, "location")
    th = 2.5 * np.sin(t)
    np.testing.assert_allclose(sol.q[:, 2], th, atol=1e-12)
    assert wrapped(sol.q[:, -1] - rocker_angle(1.0, 4.0, th)).max() < 1e-9


def bricard(rough: float, seed: int = 1):
    """A line-symmetric Bricard linkage: six revolute axes, the last three the half turn about
    the z axis of the first three, six links in a loop (ground the one between axes 6 and 1;
    Gruebler count 6 * 5 - 6 * 5 = 0, mobility 1). The bodies' frames are the ground's at the
    assembled configuration; ``rough`` perturbs their guesses (positions and Euler
    parameters) away from it."""
    rng = np.random.default_rng(seed)
    R = np.diag([-1.0, -1.0, 1.0])
    P = [np.array([1.0, 0.3, 0.2]), np.array([0.8, 1.1, -0.4]), np.array([-0.5, 1.2, 0.5])]
    D = [np.array([0.2, 1.0, 0.4]), np.array([1.0, -0.3, 0.6]), np.array([0.3, 0.5, 1.0])]
    P += [R @ p for p in P]
    D = [d / np.linalg.norm(d) for d in D + [R @ d for d in D]]
    m = ms.Model3D()
    links = [m.ground]
    for i in range(1, 6):
        e = np.r_[1.0, rng.normal(size=3) * rough]
        links.append(m.add_body(f"link{i}", guess=(tuple(rng.normal(size=3) * rough),
                                                   tuple(e / np.linalg.norm(e)))))
    links.append(m.ground)
    for i in range(6):
        ax = (tuple(P[i]), tuple(D[i]))
        m.add(ms.Revolute5(links[i].axis(*ax), links[i + 1].axis(*ax)), name=f"R{i + 1}")
    return m


def _dense(J):
    return J.toarray() if hasattr(J, "toarray") else np.asarray(J)


def test_bricard_mobility_is_taken_where_it_assembles():
    """From rough guesses the rank was taken at the guess (full: m.dof() = 0); the mobility is
    1 at the assembled configuration, which dof finds and reports."""
    m = bricard(rough=0.05)
    s = m.compile()
    p = m._p()
    g = m.guess()
    assert np.abs(s.residual(0.0, g, p)).max() > 1e-2             # rough: not assembled
    assert np.linalg.matrix_rank(_dense(s.jacobian(0.0, g, p))) == s.n   # full rank there
    d = m.dof()
    assert d.gruebler == 0 and int(d) == 1 and d.at == "assembled"
    assert "assembled configuration" in repr(d)
    q = d.configuration
    assert np.abs(s.residual(0.0, q, p)).max() < 1e-10
    # independently: the SVD of Phi_q there has one zero singular value ...
    sv = np.linalg.svd(_dense(s.jacobian(0.0, q, p)), compute_uv=False)
    assert sv[-1] < 1e-12 * sv[0] and sv[-2] > 1e-3 * sv[0]
    # ... and it is a finite motion, not an instantaneous one: a step along the null direction
    # projected back onto Phi = 0 stays away from q (an isolated assembly would pull it back)
    from mechsys.solvers._linalg import Scaling
    from mechsys.solvers._rank import continue_position

    v = np.linalg.svd(_dense(s.jacobian(0.0, q, p)))[2][-1]
    q1 = q + 0.05 * v / np.abs(v).max()
    got = continue_position(s, 0.0, q1, p, Scaling.of(s, q1, _dense(s.jacobian(0.0, q1, p))))
    assert got is not None and np.abs(got[0] - q).max() > 0.04
    assert int(bricard(rough=0.0).dof()) == 1                    # exact guesses: as before


def test_dof_says_when_the_figure_holds_at_the_guess_only():
    """A loop that cannot close (a four-bar whose coupler is longer than the other three
    together), Gruebler count 0: no assembly, and the report says the figure is the guess's."""
    m = four_bar(coupler=9.0)
    d = m.dof()
    assert d.at == "unassembled guess" and "holds at the guess only" in repr(d)


def test_a_hook_stopping_a_coarse_sweep_keeps_the_points_before():
    """The points re-solved after a coarse step and those before them are all in the partial
    solution a pre_solve hook leaves."""
    t = np.arange(0, 4 * np.pi, np.radians(130))
    # (at 130 degrees the loop put rows 4 and 5 on the mirrored branch)
    sol = four_bar().solve(t, "acceleration", pre_solve=lambda tt: tt < 11.0)
    n = int(np.sum(t < 11.0))
    assert len(sol.t) == n and "pre_solve" in sol.extra["stopped"]
    assert wrapped(sol.q[:, -1] - rocker_angle(1.0, 4.0, t[:n])).max() < 1e-9
