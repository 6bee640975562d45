"""mechsys.sweep: parameter grids and samples, serial, on a process pool and on Dask, checked
against the slider-crank's closed form and against each other (exact equality)."""

import numpy as np
import pandas as pd
import pytest
import sympy as sp

import mechsys as ms
from mechsys import T

T0 = 0.1                                   # crank angle 2 pi T0


def build_slider_crank():
    """Slider-crank with crank radius r and rod length L as parameters."""
    m = ms.Model2D()
    r = m.parameter("r", 2.0)
    L = m.parameter("L", 6.0)
    crank = m.add_body("crank", points={"pin": (r, 0)})
    rod = m.add_body("rod", points={"a": (0, 0), "b": (L, 0)}, guess=((4, 1), 0.3))
    piston = m.add_body("piston", guess=((8, 0), 0))
    m.add(ms.Revolute2((0, 0), crank.point(0)))
    m.add(ms.Revolute2(crank.point("pin"), rod.point("a")))
    m.add(ms.Revolute2(rod.point("b"), piston.point(0)))
    m.add(ms.Translate2(((0, 0), (1, 0)), piston.axis((0, 0), (1, 0))))
    m.add(ms.RotationLock1(crank, 2 * sp.pi * T), name="drive")
    return m


def piston_closed_form(r, L, t=T0):
    th, w = 2 * np.pi * t, 2 * np.pi
    root = np.sqrt(L**2 - (r * np.sin(th)) ** 2)
    x = r * np.cos(th) + root
    v = -r * w * np.sin(th) - r**2 * w * np.sin(th) * np.cos(th) / root
    return x, v


X4, X4_D = sp.Symbol("x4", real=True), sp.Symbol("x4_d", real=True)
OUTPUTS = {"x": X4, "v": X4_D}
GRID = {"r": [1.5, 2.0], "L": [5.0, 6.0, 7.0]}


@pytest.fixture(scope="module")
def serial():
    return ms.sweep(build_slider_crank, GRID, "velocity", OUTPUTS, t=T0)


def test_serial_grid_matches_closed_form(serial):
    df = serial
    assert list(df.columns) == ["r", "L", "x", "v"]
    assert list(zip(df["r"], df["L"])) == [(r, L) for r in GRID["r"] for L in GRID["L"]]
    x, v = piston_closed_form(df["r"].to_numpy(), df["L"].to_numpy())
    assert np.allclose(df["x"], x, rtol=1e-12, atol=0)
    assert np.allclose(df["v"], v, rtol=1e-10, atol=0)
    assert df.attrs["executor"] == "serial" and df.attrs["builds"] == 1


def test_samples_in_every_form_agree(serial):
    pts = [(r, L) for r in GRID["r"] for L in GRID["L"]]
    rs, Ls = [p[0] for p in pts], [p[1] for p in pts]
    zipped = ms.sweep(build_slider_crank, {"r": rs, "L": Ls}, "velocity", OUTPUTS, t=T0,
                      grid=False)
    listed = ms.sweep(build_slider_crank, [{"r": r, "L": L} for r, L in pts], "velocity",
                      OUTPUTS, t=T0)
    framed = ms.sweep(build_slider_crank, pd.DataFrame({"r": rs, "L": Ls}), "velocity",
                      OUTPUTS, t=T0)
    for df in (zipped, listed, framed):
        pd.testing.assert_frame_equal(df, serial, check_exact=True, check_dtype=False)
    # a Model instance works too, and the sweep leaves its parameters as they were
    m = build_slider_crank()
    m.set_parameters(r=2.2)
    piston = m.body("piston")
    df = ms.sweep(m, {"L": [5.0, 6.0]}, lambda mm: mm.solve(T0), {
        "x": lambda sol: sol.location(piston.point(0))[0]})
    assert np.allclose(df["x"], piston_closed_form(2.2, np.array([5.0, 6.0]))[0], rtol=1e-12)
    assert m.parameters == {"r": 2.2, "L": 6.0}


def test_dask_sweep_equals_serial_exactly(serial):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(processes=False, n_workers=1, threads_per_worker=2,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        df = ms.sweep(build_slider_crank, GRID, "velocity", OUTPUTS, t=T0, executor=client,
                      chunks=6)
        # a pickled Model with an analysis capturing one of its body handles
        m = build_slider_crank()
        piston = m.body("piston")
        dfm = ms.sweep(m, GRID, lambda mm: mm.solve(T0), {
            "x": lambda sol: sol.location(piston.point(0))[0],
            "v": lambda sol: sol.velocity(piston.point(0))[0]}, executor=client, chunks=3)
    pd.testing.assert_frame_equal(df, serial, check_exact=True)
    pd.testing.assert_frame_equal(dfm, serial, check_exact=True)
    assert df.attrs["executor"] == "dask"
    # six chunks on two worker threads: the model was built once per thread, not per chunk
    assert df.attrs["builds"] == df.attrs["workers"] <= 2


def test_process_pool_equals_serial_exactly(serial):
    # one worker process (spawning is the slow part); three chunks, one build
    df = ms.sweep(build_slider_crank, GRID, "velocity", OUTPUTS, t=T0, executor="processes",
                  workers=1, chunks=3)
    pd.testing.assert_frame_equal(df, serial, check_exact=True)
    assert df.attrs["executor"] == "processes"
    assert df.attrs["builds"] == df.attrs["workers"] == 1


def four_bar_with_target():
    """Four-bar (crank 1, coupler 4, ground 4) with rocker length ``c`` and a target rocker
    angle ``target`` as parameters: the couple's condition is the same expression at every
    point, so it is compiled once per worker."""
    m = ms.Model2D()
    c = m.parameter("c", 3.0)
    m.parameter("target", 1.7)
    crank = m.add_body("crank", points={"A": (1, 0)})
    coupler = m.add_body("coupler", points={"A": (0, 0), "B": (4, 0)}, guess=((1, 0), 0.9))
    rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((4, 0), 1.8))
    m.add(ms.Revolute2((0, 0), crank.point(0)))
    m.add(ms.Revolute2(crank.point("A"), coupler.point("A")))
    m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")))
    m.add(ms.Revolute2((4, 0), rocker.point(0)))
    m.add(ms.RotationLock1(crank, T))
    return m


def rocker_couple(m):
    return m.couple(unknowns=["c"], conditions=sp.Eq(m.angle("rocker"), sp.Symbol("target")),
                    t=0.8).solve()


def test_sweep_of_a_couple_matches_freudenstein():
    targets = [1.6, 1.7, 1.8]
    df = ms.sweep(four_bar_with_target, {"target": targets}, rocker_couple)
    assert list(df.columns) == ["target", "c"]
    th2, a, b, d = 0.8, 1.0, 4.0, 4.0
    for th4, c in zip(df["target"], df["c"]):
        K1, K2, K3 = d / a, d / c, (a**2 - b**2 + c**2 + d**2) / (2 * a * c)
        assert K1 * np.cos(th4) - K2 * np.cos(th2) + K3 == pytest.approx(np.cos(th2 - th4),
                                                                           abs=1e-12)


def test_failed_points_and_bad_input():
    # L = 1 < r sin(th): the rod cannot reach the slider line at T0
    grid = {"r": [2.0], "L": [6.0, 1.0]}
    with pytest.raises(ms.ConvergenceError, match=r"sweep point 1 \(r=2.0, L=1.0\)"):
        ms.sweep(build_slider_crank, grid, "location", {"x": X4}, t=T0)
    df = ms.sweep(build_slider_crank, grid, "location", {"x": X4}, t=T0, on_error="nan")
    assert list(df.columns) == ["r", "L", "x", "error"]
    assert df["x"][0] == pytest.approx(piston_closed_form(2.0, 6.0)[0], rel=1e-12)
    assert np.isnan(df["x"][1]) and df["error"][1].startswith("ConvergenceError")
    with pytest.raises(ms.ModelError, match="unknown parameter 'R'"):
        ms.sweep(build_slider_crank, {"R": [1.0]}, "location", {"x": X4})
    with pytest.raises(ms.ModelError, match="equally many values"):
        ms.sweep(build_slider_crank, {"r": [1.0, 2.0], "L": [6.0]}, grid=False)
    with pytest.raises(ms.ModelError, match="executor"):
        ms.sweep(build_slider_crank, GRID, "location", {"x": X4}, executor="threads")
    with pytest.raises(ms.ModelError, match="analysis"):
        ms.sweep(build_slider_crank, GRID, "positions", {"x": X4})
    with pytest.raises(ms.ModelError, match="give outputs"):
        ms.sweep(build_slider_crank, GRID, lambda m: m.solve([0.0, 0.1]))


def test_progress_bar_counts_points(capsys):
    ms.sweep(build_slider_crank, GRID, "location", {"x": X4}, progress=True)
    err = capsys.readouterr().err
    assert "sweep:" in err and "6/6" in err and "points/s" in err
