"""m.set_compile_options (Mech's manual 12.2 $MechProcessFunction and 12.3 Compiled): each
option is validated, changes the compiled code (and so the kernel cache key) and leaves the
answers unchanged."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import ModelError, T, models
from mechsys.compile import _backends, _cache
from mechsys.compile._options import chop

TIMES = np.linspace(0.0, 1.0, 11)


def four_bar(scale=1.0):
    """A four-bar whose coupler point B is at (b, b cos(pi/2)) computed in floating point:
    its y coordinate is 2.4e-16, round-off that only costs work."""
    a, b, c, d = (v * scale for v in (1.0, 4.0, 3.0, 4.0))
    m = ms.Model2D()
    crank = m.add_body("crank", points={"A": (a, 0)}, guess=((0, 0), 0))
    coupler = m.add_body("coupler", points={"B": (b, b * np.cos(np.pi / 2))},
                         guess=((a, 0), 0.9))
    rocker = m.add_body("rocker", points={"B": (c, 0)}, guess=((d, 0), 1.8))
    m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="O2")
    m.add(ms.Revolute2(crank.point("A"), coupler.point(0)), name="A")
    m.add(ms.Revolute2(coupler.point("B"), rocker.point("B")), name="B")
    m.add(ms.Revolute2(m.ground.point((d, 0)), rocker.point(0)), name="O4")
    m.add(ms.RotationLock1(crank, T), name="drive")
    return m


def floats(m):
    return [abs(float(a)) for e in m.equations().phi for a in e.atoms(sp.Float)]


def test_options_are_validated_by_name():
    m = four_bar()
    with pytest.raises(ModelError, match="compile_options: unknown option.*'optlevel'.*process, opt_level"):
        m.set_compile_options(optlevel=1)
    with pytest.raises(ModelError, match="process must be None, 'chop' or a function"):
        m.set_compile_options(process="chopp")
    for bad in (4, -1, 1.5, True, "3"):
        with pytest.raises(ModelError, match="opt_level must be an integer 0, 1, 2 or 3"):
            m.set_compile_options(opt_level=bad)
    for bad in ("yes", 1, 0):
        with pytest.raises(ModelError, match="cse must be None .automatic., True or False"):
            m.set_compile_options(cse=bad)
    assert m.compile_options == {"process": None, "opt_level": None, "cse": None}
    # a level read from an array is a NumPy integer: taken, stored as a plain int
    assert m.set_compile_options(opt_level=np.int64(2))["opt_level"] == 2
    assert type(m.compile_options["opt_level"]) is int
    with pytest.raises(ModelError, match="opt_level must be"):
        m.set_compile_options(opt_level=np.bool_(True))


@pytest.mark.parametrize("scale", [1.0, 1e-3])
def test_chop_drops_round_off_whatever_the_unit(scale):
    plain, chopped = four_bar(scale), four_bar(scale)
    chopped.set_compile_options(process="chop")
    big = max(floats(plain))
    assert min(floats(plain)) < 1e-15 * big              # the round-off is in the equations
    assert min(floats(chopped)) > 1e-12 * big            # and only there
    ops = [sum(sp.count_ops(e) for e in mm.equations().phi) for mm in (plain, chopped)]
    assert ops[1] < ops[0]
    a, b = plain.solve(TIMES), chopped.solve(TIMES)
    assert np.abs(a.q - b.q).max() < 1e-12 * scale
    assert np.abs(a.qd - b.qd).max() < 1e-12 * scale


def test_chop_is_relative_to_the_equation():
    x = sp.Symbol("x")
    assert chop(2.0 * x + 1e-17 * sp.cos(x) - 0.5) == 2.0 * x - 0.5
    assert chop(1e-9 * x + 1e-17) == 1e-9 * x + 1e-17        # same order of magnitude: kept
    assert chop(x + 1) == x + 1


def test_process_function_is_applied_to_every_equation():
    m = four_bar()
    before = list(m.equations().phi)
    m.set_compile_options(process=sp.expand)
    after = list(m.equations().phi)
    assert after == [sp.expand(e) for e in before]
    assert np.abs(m.solve(TIMES).q - four_bar().solve(TIMES).q).max() < 1e-12
    m.set_compile_options(process=lambda e: 1 / 0)
    with pytest.raises(ModelError, match="process failed on an equation of.*ZeroDivisionError"):
        m.compile()
    m.set_compile_options(process=lambda e: [e])
    with pytest.raises(ModelError, match="process returned"):
        m.compile()


@pytest.mark.skipif(_backends.default_backend() != "symengine", reason="LLVM kernels only")
def test_opt_level_and_cse_reach_the_compiler_and_the_cache_key(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHSYS_CACHE", str(tmp_path))
    seen = []
    real = _backends._se.Lambdify

    def spy(*args, **kw):
        seen.append((kw.get("opt_level"), kw.get("cse")))
        return real(*args, **kw)

    monkeypatch.setattr(_backends._se, "Lambdify", spy)
    m = models.slider_crank()
    ref = m.solve(TIMES)
    n_default = len(list(tmp_path.glob("*" + _cache.SUFFIX)))
    assert set(seen) == {(3, False)}
    n_before = n_default
    for opts, expect in (({"opt_level": 0}, (0, False)), ({"opt_level": 3, "cse": True}, (3, True))):
        seen.clear()
        m.set_compile_options(**opts)
        assert m.compile().backend == "symengine" and m.compile().backend.opt_level == expect[0]
        sol = m.solve(TIMES)
        # every kernel compiled with them; a CSE kernel with repeated outputs is compiled
        # once more without CSE for the sweep's loop, which writes every output
        # (``_SymengineCompiled.c_function``), at the same level
        assert expect in seen and set(seen) <= {expect, (expect[0], False)}
        assert np.abs(sol.q - ref.q).max() < 1e-12 and np.abs(sol.qdd - ref.qdd).max() < 1e-10
        n = len(list(tmp_path.glob("*" + _cache.SUFFIX)))
        # new kernels, new keys: the three kernels, and with CSE their plain variants too
        assert n == n_before + 3 * (1 + (expect[1] is True))
        n_before = n
    # unchanged options keep the compiled system
    s = m.compile()
    m.set_compile_options(cse=True)
    assert m.compile() is s


def test_process_reaches_the_rows_of_every_stage():
    from mechsys.compile._stages import stage_system

    m = ms.Model2D()
    rod = m.add_body("rod", points={"pivot": (-0.5, 0.0)}, mass=1.0, inertia=0.1,
                     guess=((0.5, 0.0), 0.0))
    m.add(ms.Revolute2(rod.point("pivot"), m.ground.point((0.0, 0.0))), name="pivot")
    m.add(ms.StageSwitch((rod.q[2] > -1.0, ms.RotationLock1(rod, -T)),
                         (True, ms.RotationLock1(rod, -1.0))), name="latch")
    seen = []
    m.set_compile_options(process=lambda e: seen.append(e) or e)
    second = stage_system(m, (1,))
    th = rod.q[2]
    assert th + 1.0 in seen and th + 1.0 in second.phi       # the second stage's lock
    assert th + T in seen


@pytest.mark.parametrize("scale", [1.0, 1e-3])
def test_dead_centre_guess_with_exact_or_chopped_geometry(scale):
    """A slider-crank assembled at its dead centre (crank pin in line with the rod): the
    rod's rotational Jacobian entry there is 0 exactly (pin at (0, r)) or round-off (pin at
    (r cos(pi/2), r)). Neither may become the model's characteristic length: both sweeps
    follow the drive, with and without process="chop" (solvers/_linalg.py Scaling.of)."""
    t = np.linspace(0.0, 1.0, 11)
    for px in (0.0, scale * np.cos(np.pi / 2)):
        for process in (None, "chop"):
            m = ms.Model2D()
            m.set_compile_options(process=process)
            crank = m.add_body("crank", points={"pin": (px, scale)}, guess=((0, 0), -np.pi / 2))
            slider = m.add_body("slider", guess=((3.3 * scale, 0), 0))
            m.add(ms.Revolute2(m.ground.point((0, 0)), crank.point(0)), name="O")
            m.add(ms.Translate2(slider.axis(0, (1, 0)), m.ground.axis((0, 0), (1, 0))),
                  name="slide")
            m.add(ms.RelativeDistance1(crank.point("pin"), slider.point(0), 3 * scale), name="rod")
            m.add(ms.RotationLock1(crank, T - np.pi / 2), name="drive")
            sol = m.solve(t)
            th = t - np.pi / 2
            assert np.abs(sol.angle(crank) - th).max() < 1e-12
            x = scale * (-np.sin(th) + np.sqrt(9 - np.cos(th) ** 2))   # closed form
            assert np.abs(sol["x3"] - x).max() < 1e-12 * scale
