"""Fuzzing with hypothesis (short profile; the long one is benchmarks/fuzz_long.py).

* random planar and spatial mechanisms (``mechsys.testing._fuzz``: a conformance case of any
  constraint type, extra pinned bodies, masses, gravity, drivers): only MechError escapes;
  Jacobian and gamma match finite differences; solved points satisfy the constraints;
  ``m.dof()`` matches an independent rank; the free acceleration satisfies
  ``Phi_q qdd = gamma``;
* odd arguments (None, NaN, strings, arrays of the wrong shape, objects ...) to the public
  entry points: every one is answered with a MechError subclass or accepted.

Derandomized (``derandomize=True``, no example database), so CI runs the same examples
every time.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import mechsys as ms  # noqa: E402
from mechsys.testing._fuzz import WEIRD, case_names, check_mechanism  # noqa: E402

SETTINGS = dict(derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck))


@settings(max_examples=6, **SETTINGS)
@given(seed=st.integers(0, 2**31 - 1), name=st.sampled_from(case_names()),
       extra=st.integers(0, 2))
def test_random_mechanisms_keep_their_invariants(seed, name, extra):
    res = check_mechanism(seed, extra=extra, name=name)
    assert res["outcome"], res
    # (check_mechanism asserted them against their scaled tolerances; these are absolute)
    assert res["jacobian_fd"] < 1e-5 and res["gamma_fd"] < 1e-3


# -- odd arguments -----------------------------------------------------------------------------
@functools.lru_cache(maxsize=1)
def _fixtures():
    m = ms.Model2D()
    L = m.parameter("L", 1.0)
    c = m.add_body("crank", points={"tip": (L, 0)}, mass=1.0, centroid=(0.5, 0), inertia=0.1,
                   guess=((0, 0), 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)), name="pivot")
    m.add(ms.RotationLock1(c, ms.T), name="drive")
    m.add_load(ms.Gravity((0, -1), 9.81))
    sol = m.solve([0.0, 0.5])
    free = m.free(drop=["drive"])
    return m, sol, free


def _ops():
    def guess(m, v):
        try:
            m.set_guess(v)
        finally:
            m._guess_override.clear()

    return {
        "solve(t)": lambda m, s, f, v: m.solve(v),
        "solve(solution=)": lambda m, s, f, v: m.solve(0.0, solution=v),
        "solve(guess=)": lambda m, s, f, v: m.solve(0.0, guess=v),
        "solve(options=)": lambda m, s, f, v: m.solve(0.0, options=v),
        "solve(lambda_guess=)": lambda m, s, f, v: m.solve(0.0, "static", lambda_guess=v),
        "solve(pre_solve=)": lambda m, s, f, v: m.solve(0.0, pre_solve=v),
        "body": lambda m, s, f, v: m.body(v),
        "constraint": lambda m, s, f, v: m.constraint(v),
        "set_guess": lambda m, s, f, v: guess(m, v),
        "set_parameters": lambda m, s, f, v: m.set_parameters({"L": v}) or m.set_parameters(L=1.0),
        "singularity": lambda m, s, f, v: m.singularity(v),
        "equations": lambda m, s, f, v: m.equations(v),
        "multipliers": lambda m, s, f, v: m.multipliers(v),
        "PositionOptions(ftol)": lambda m, s, f, v: ms.PositionOptions(ftol=v),
        "PositionOptions(max_iterations)": lambda m, s, f, v: ms.PositionOptions(max_iterations=v),
        "add_body(name)": lambda m, s, f, v: ms.Model2D().add_body(v),
        "add_body(guess)": lambda m, s, f, v: ms.Model2D().add_body("a", guess=v),
        "add_body(points)": lambda m, s, f, v: ms.Model2D().add_body("a", points=v),
        "add_body(mass)": lambda m, s, f, v: ms.Model2D().add_body("a", mass=v),
        "parameter": lambda m, s, f, v: ms.Model2D().parameter("p", v),
        "RotationLock1(angle)": lambda m, s, f, v: ms.RotationLock1(m.body("crank"), v),
        "Gravity(vector)": lambda m, s, f, v: ms.Gravity(v, 9.81),
        "Gravity(g)": lambda m, s, f, v: ms.Gravity((0, -1), v),
        "sol[]": lambda m, s, f, v: s[v],
        "sol.coordinate": lambda m, s, f, v: s.coordinate(v),
        "free.simulate(t)": lambda m, s, f, v: f.simulate(v),
        "free.simulate(method=)": lambda m, s, f, v: f.simulate((0.0, 0.1), method=v),
        "free.solve(t)": lambda m, s, f, v: f.solve(v),
        "free.solve(initial_condition=)": lambda m, s, f, v: f.solve(0.0, initial_condition=v),
        "free(drop=)": lambda m, s, f, v: m.free(drop=v),
    }


OPS = _ops()


@settings(max_examples=150, **SETTINGS)
@given(op=st.sampled_from(sorted(OPS)), value=st.sampled_from(range(len(WEIRD))))
def test_odd_arguments_raise_only_mech_errors(op, value):
    m, sol, free = _fixtures()
    v = WEIRD[value]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            OPS[op](m, sol, free, v)
    except ms.MechError:
        pass
    except Exception as exc:  # noqa: BLE001
        pytest.fail(f"{op} with {v!r} raised {type(exc).__name__}: {exc}")


def test_fuzz_generator_covers_planar_spatial_and_every_case_type():
    names = case_names()
    from mechsys.testing import CASES

    assert names == sorted(CASES) and len(names) >= 50
    dims = set()
    for seed in range(3):
        from mechsys.testing._fuzz import random_mechanism

        m, q, t, drivers, info = random_mechanism(seed, extra=1, name=["Revolute2", "Spherical3",
                                                                        "TwoGears1"][seed])
        dims.add(info["dim"])
        assert np.abs(m.compile().residual(t, q, m._p())).max() < 1e-10
        # drivers leave no degree of freedom (unless asked to leave one)
        assert m.compile().m == m.compile().n or info["dof_before_drivers"] > len(drivers)
    assert dims == {2, 3}


# -- bugs the fuzzer found (each raised a non-mechsys exception before) ---------------------------
REGRESSIONS = [
    # a dict of strings was sympified as code: AttributeError 'Symbol' object has no attribute 'th'
    ("RotationLock1(angle)", {"crank.th": "a"}),
    ("Gravity(g)", {"crank.th": "a"}),
    ("add_body(mass)", {"crank.th": "a"}),
    # solve(guess="x"): ValueError from float(); singularity("x") the same
    ("solve(guess=)", "x"),
    ("singularity", "crank"),
    # solve(solution=[...]): TypeError unhashable type
    ("solve(solution=)", []),
    # sol[2-D array]: ValueError truth value of an array is ambiguous
    ("sol[]", np.zeros((2, 2))),
]


@pytest.mark.parametrize("op,value", REGRESSIONS, ids=[f"{o}-{i}" for i, (o, _) in enumerate(REGRESSIONS)])
def test_regressions_found_by_the_fuzzer(op, value):
    m, sol, free = _fixtures()
    with pytest.raises(ms.MechError):
        OPS[op](m, sol, free, value)


def test_long_profile_merges_parallel_runs():
    """benchmarks/fuzz_long.py --merge: adjacent seed ranges add up; gaps are refused."""
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "fuzz_long.py"
    spec = importlib.util.spec_from_file_location("_fuzz_long", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)

    def part(start, models, worst, fails=()):
        return {"models": models, "start": start, "types": 59, "all_types": 59,
                "dims": {"2": models // 2, "3": models - models // 2},
                "outcomes": {"dof": models, "solved": models - 1}, "failures": list(fails),
                "worst": {"jacobian_fd": worst, "gamma_fd": worst / 2, "free_acceleration": 0.0},
                "wall_s": 60.0 * models, "cpu_s": 1.0 * models}

    r = mod.merged([part(100, 50, 1e-9), part(0, 100, 3e-9, [{"seed": 7, "type": "x",
                                                              "what": "y"}])])
    assert r["start"] == 0 and r["models"] == 150 and r["dims"] == {2: 75, 3: 75}
    assert r["outcomes"] == {"dof": 150, "solved": 148} and len(r["failures"]) == 1
    assert r["worst"]["jacobian_fd"] == 3e-9 and r["cpu_s"] == 150.0 and r["wall_s"] == 6000.0
    assert "seeds 0 to 149" in mod.summary(r)
    with pytest.raises(SystemExit, match="not adjacent"):
        mod.merged([part(0, 100, 1e-9), part(101, 10, 1e-9)])
