"""The error catalogue of docs/errors.md: every bad input listed there raises its documented
exception class, with a message naming the culprit.

The table ``CATALOGUE`` below is the single source: docs/errors.md's catalogue section is
generated from it (``python tests/test_error_catalogue.py --write``), and
``test_doc_matches_the_table`` fails when the two disagree. Each entry is
``(area, code, exception class name, culprit)``: ``code`` runs in a namespace holding ``ms``,
``np``, ``sp``, ``T`` and the small models built by the helpers below; ``culprit`` must
appear in the message.
"""

from __future__ import annotations

import pathlib
import re
import sys

import numpy as np
import pytest
import sympy as sp

import mechsys as ms
from mechsys import _errors

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "errors.md"
BEGIN, END = "<!-- catalogue:begin -->", "<!-- catalogue:end -->"


# -- the small models the entries start from --------------------------------------------------
def crank():
    """A crank pinned to ground and driven: fully constrained (0 DOF)."""
    m = ms.Model2D()
    c = m.add_body("crank", points={"tip": (1, 0)}, guess=((0, 0), 0.1))
    m.add(ms.Revolute2(m.ground.point((0, 0)), c.point(0)), name="pivot")
    m.add(ms.RotationLock1(c, ms.T), name="drive")
    return m


def pend():
    """A pendulum held by a rotation lock ``hold``, under gravity, solved."""
    m = ms.Model2D()
    b = m.add_body("bar", points={"tip": (1, 0)}, mass=1.0, centroid=(1, 0), inertia=0.1,
                   guess=((0, 0), -1.0))
    m.add(ms.Revolute2(m.ground.point((0, 0)), b.point(0)), name="pivot")
    m.add(ms.RotationLock1(b, -1.0), name="hold")
    m.add_load(ms.Gravity((0, -1), 9.81))
    m.solve(0.0)
    return m


def free():
    """The free motion of ``pend()`` (``hold`` dropped)."""
    return pend().free(drop=["hold"])


def caster():
    """A caster dragged along x (nonholonomic path model of docs/nonholonomic.md)."""
    m = ms.Model2D()
    c = m.add_body("caster", points={"wheel": (0.3, 0.0)}, guess=((0, 0), 3.09))
    m.add(ms.Revolute2(c.point(0), m.ground.point((-ms.T, 0))), name="pivot")
    m.add(ms.RotationLock1(c, 3.09), name="dummy")
    m.solve(0.0)
    return m


def rolling(m):
    c = m.body("caster")
    return ms.Orthogonal1(m.velocity(c.point("wheel")), c.vector((0, 1)))


def sol():
    """A three-point sweep of ``crank()``."""
    return crank().solve([0.0, 0.5, 1.0])


def m3():
    """A spatial model with one body ``box`` held by a spherical joint and a driver."""
    m = ms.Model3D()
    b = m.add_body("box", points={"p": (1, 0, 0)})
    m.add(ms.Spherical3(m.ground.point((0, 0, 0)), b.point(0)), name="ball")
    return m


# -- the catalogue ---------------------------------------------------------------------------
#: (area, code, exception, culprit named in the message)
CATALOGUE = [
    # model building
    ("model", 'ms.Model2D().add_body("")', "ModelError", "body name"),
    ("model", 'm = ms.Model2D(); m.add_body("a"); m.add_body("a")', "ModelError", "'a'"),
    ("model", 'crank().body("wheel")', "UnknownBodyError", "'wheel'"),
    ("model", "crank().body(9)", "UnknownBodyError", "9"),
    ("model", "crank().body(2.5)", "UnknownBodyError", "2.5"),
    ("model", 'crank().body("crank").point("hub")', "UnknownPointError", "hub"),
    ("model", 'crank().constraint("slider")', "UnknownConstraintError", "'slider'"),
    ("model", "crank().remove(7)", "UnknownConstraintError", "7"),
    ("model", 'crank().parameter("L", "long")', "ModelError", "'L'"),
    ("model", 'crank().parameter("L", float("nan"))', "ModelError", "'L'"),
    ("model", 'crank().parameter("T", 1.0)', "ModelError", "'T'"),
    ("model", 'crank().parameter("pi", 1.0)', "ModelError", "'pi'"),
    ("model", 'crank().set_guess({"crank.th": float("nan")})', "ModelError", "body 'crank'"),
    ("model", 'crank().parameter("th2", 1.0)', "ModelError", "'th2'"),
    ("model", 'm = crank(); m.parameter("L", 1.0); m.parameter("L", 2.0)', "ModelError", "'L'"),
    ("model", "crank().set_parameters(Q=3.0)", "ModelError", "'Q'"),
    ("model", 'crank().variable("lam1_1")', "ModelError", "'lam1_1'"),
    ("model", 'crank().add("Revolute2")', "ModelError", "'Revolute2'"),
    ("model", 'm = crank(); m.add(m.constraint("pivot"))', "ModelError", "'pivot'"),
    ("model", 'm = crank(); m.add(ms.RotationLock1(m.body("crank"), 0.0), name="pivot")',
     "ModelError", "'pivot'"),
    ("model", 'o = ms.Model2D(); z = o.add_body("z"); crank().add(ms.RotationLock1(z, 0.0))',
     "ModelError", "'z'"),
    ("model", 'm = crank(); m.replace("drive", ms.RotationLock1(m.body("crank"), sp.Symbol("w") * T));'
     ' m.solve(0.0)', "ModelError", "'w'"),
    ("model", 'm = crank(); m.add(ms.Spherical3(m.ground.point((0, 0)), m.body("crank").point(0)))',
     "ModelError", "Spherical3"),
    ("model", 'm = crank(); c = m.body("crank"); m.add(ms.Translate2(c.axis((0, 0), (0, 0)),'
     ' m.ground.axis((0, 0), (1, 0))))', "GeometryError", "axis"),
    ("model", 'ms.Model2D().add_body("a", points={"p": (1, 2, 3)})', "GeometryError", "'p'"),
    ("model", 'ms.Model2D().add_body("a", guess="here")', "ModelError", "'a'"),
    ("model", 'ms.Model2D().add_body("a", mass=-1.0)', "ModelError", "'a'"),
    ("model", 'crank().set_mass_properties("ground", mass=1.0)', "ModelError", "ground"),
    ("model", 'crank().set_mass_properties("crank", centroid=(1, 2, 3))', "ModelError", "'crank'"),
    ("model", "crank().add_load(3.0)", "ModelError", "3.0"),
    ("model", "crank().add_load(ms.Gravity((0, 0), 9.81))", "GeometryError", "Gravity"),
    ("model", "m = crank(); m.remove_load(ms.Gravity((0, -1), 9.81))", "ModelError", "Gravity"),
    ("model", 'ms.Model3D(velocity="fast")', "OptionError", "'fast'"),
    ("model", "crank().set_guess(zz=1.0)", "ModelError", "'zz'"),
    ("model", 'crank().set_guess({"crank.th": "up"})', "ModelError", "'th2'"),
    ("model", "crank().set_guess(np.zeros(5))", "ModelError", "shape"),
    ("model", 'crank().equations("slider")', "UnknownConstraintError", "'slider'"),
    ("model", 'crank().equations().pretty("lagrangian")', "OptionError", "'lagrangian'"),
    # options
    ("options", "ms.PositionOptions(ftol=-1.0)", "ModelError", "ftol"),
    ("options", "ms.PositionOptions(max_iterations=0)", "ModelError", "max_iterations"),
    ("options", 'ms.PositionOptions(damping="yes")', "ModelError", "damping"),
    ("options", 'crank().solve(0.0, options={"tol": 1e-9})', "OptionError", "'tol'"),
    ("options", "crank().solve(0.0, options=5)", "ModelError", "options"),
    ("options", 'crank().solve(0.0, solution="position")', "OptionError", "'position'"),
    ("options", "crank().solve(0.0, pre_solve=1)", "ModelError", "pre_solve"),
    ("options", 'crank().solve(0.0, post_iterate="print")', "ModelError", "post_iterate"),
    ("options", "crank().singularity(threshold=2.0)", "ModelError", "threshold"),
    ("options", "crank().set_compile_options(optlevel=1)", "OptionError", "'optlevel'"),
    ("options", "crank().set_compile_options(opt_level=7)", "ModelError", "opt_level"),
    ("options", 'crank().set_compile_options(process="Chop")', "OptionError", "'Chop'"),
    ("options", 'ms.Model2D(orientation="Euler")', "OptionError", "'Euler'"),
    # solving
    ("solve", 'crank().solve(float("nan"))', "ModelError", "nan"),
    ("solve", "crank().solve([])", "ModelError", "empty"),
    ("solve", "crank().solve([[0.0, 1.0]])", "ModelError", "shape"),
    ("solve", "crank().solve(None)", "ModelError", "None"),
    ("solve", "crank().solve(0.0, guess=[1.0, 2.0])", "ModelError", "guess"),
    ("solve", "ms.Model2D().solve(0.0)", "ModelError", "no moving bodies"),
    ("solve", "g = crank().guess(); g[0] = np.nan; crank().solve(0.0, guess=g)", "ModelError",
     "'crank.x'"),
    ("solve", 'm = crank(); m.add_body("loose"); m.solve(0.0)', "ConstraintCountError",
     "body 'loose'"),
    ("solve", 'm = crank(); m.remove("drive"); m.add(ms.RotationLock1(m.body("crank"), "2*pi*T"));'
     " m.solve(0.1)", "ModelError", "mechsys.T"),
    ("solve", 'm = crank(); w = m.parameter("w", 1.0); m.remove("drive"); m.add(ms.RotationLock1('
     'm.body("crank"), sp.Symbol("w", positive=True) * T)); m.solve(0.1)', "ModelError",
     "m.parameter('w'"),
    ("path", 'm = caster(); m.add(rolling(m), name="rolling"); m.solve(0.0)', "ModelError",
     "m.path(replace="),
    ("solve", 'm = crank(); m.remove("drive"); m.solve(0.0)', "ConstraintCountError",
     "1 degree(s) of freedom"),
    ("solve", 'm = crank(); m.add(ms.RotationLock1(m.body("crank"), 0.5), name="lock"); m.solve(0.0)',
     "ConstraintCountError", "'lock'"),
    ("solve", 'm = crank(); m.add(ms.PointOnLine1(m.body("crank").point("tip"), m.ground.axis((0, 2),'
     ' (1, 0))), name="reach"); m.remove("drive"); m.solve(0.0)', "ConvergenceError", "'reach'"),
    ("solve", 'm = crank(); m.replace("drive", ms.RotationLock1(m.body("crank"), 1 / T)); m.solve(0.0)',
     "ConvergenceError", "'drive'"),
    ("solve", 'm = crank(); m.solve([0.0, 0.5], post_iterate=lambda it: False)', "MechError",
     "post_iterate"),
    ("solve", 'pend().solve(0.0, "static", lambda_guess=[1.0] * 5)', "ModelError", "lambda_guess"),
    ("solve", 'm = pend(); m.add_load(ms.Force(m.body("bar").point("tip"), (0, 1), 1 / (T - 1))); '
     'm.solve([0.0, 1.0], "static")', "ModelError", "bar.y"),
    ("solve", 'ms.Model2D().add_body("a", inertia=-1.0)', "ModelError", "'a'"),
    # free motion
    ("free", 'pend().free(drop=["brake"])', "UnknownConstraintError", "'brake'"),
    ("free", 'pend().free(drop=["hold"], solution="fast")', "OptionError", "'fast'"),
    ("free", "free().simulate(1.0)", "ModelError", "t=1.0"),
    ("free", "free().linearize()", "NotSteadyError", "acceleration of bar.th"),
    ("free", 'free().linearize(inputs=["nope"])', "ModelError", "'nope'"),
    ("free", 'free().linearize(coordinates=["bar.x"])', "ModelError", "['bar.x']"),
    ("free", 'm = ms.Model2D(); b = m.add_body("s", mass=1.0, inertia=1.0); '
     'm.add(ms.Orthogonal1(m.velocity(b.point(0)), b.vector((0, 1)))); '
     'm.free().linearize(speeds=["s.x", "s.y"])', "ModelError", "['s.x', 's.y']"),
    ("free", "free().simulate((0.0, 0.0))", "ModelError", "equal"),
    ("free", "free().simulate([0.0, 2.0, 1.0])", "ModelError", "t[1]"),
    ("free", 'free().simulate((0.0, 1.0), method="euler")', "OptionError", "'euler'"),
    ("free", "free().simulate((0.0, 1.0), rtol=-1.0)", "ModelError", "rtol"),
    ("free", 'free().simulate((0.0, 1.0), fit_degree="cubic")', "ModelError", "fit_degree"),
    ("free", "free().simulate((0.0, 1.0), bogus=1)", "OptionError", "bogus"),
    ("free", 'free().simulate((0.0, 1.0), progress="yes")', "ModelError", "progress"),
    ("free", "free().simulate((0.0, 1.0), starting_step_size=2.0)", "ModelError",
     "starting_step_size=2"),
    ("free", 'free().simulate((0.0, 1.0), method="adams", step_size=0.1, starting_step_size=0.1)',
     "ModelError", "starting_step_size"),
    ("free", 'free().simulate((1e6, 1e6 + 1), method="adams", step_size=1e-12)', "ModelError",
     "does not advance the time"),
    ("free", 'free().simulate((1e11, 1e11 + 1), method="adams", max_error=1e-9)', "MechError",
     "time's resolution"),
    ("free", 'free().solve(float("inf"))', "ModelError", "inf"),
    ("free", "free().solve(0.0, tolerance=1e-9)", "ModelError", "tolerance"),
    ("free", 'free().simulate((0.0, 1.0), initial_condition={"zz": 1.0})', "ModelError", "'zz'"),
    ("free", 'pend().free(drop=["hold"], solution="static").simulate((0.0, 1.0))', "MechError",
     "solution='dynamic'"),
    ("free", 'pend().free(drop=["hold"], solution="kinematic").solve(0.0)', "ModelError",
     "velocit"),
    ("free", 'm = ms.Model2D(); b = m.add_body("b", guess=((0, 0), 0), mass=1, inertia=1); '
     'm.add(ms.Constraint([m.velocity(b.point(0))[0] - 1]), name="belt"); '
     'm.add_load(ms.Gravity((0, -1), 9.81)); m.free(solution="static").solve(0.0)',
     "ModelError", "belt"),
    ("free", 'm = ms.Model2D(); b = m.add_body("b", points={"p": (1, 0)}); m.add(ms.Revolute2('
     'm.ground.point((0, 0)), b.point(0))); m.free().solve(0.0)', "SingularMassError", "'b'"),
    # paths
    ("path", "caster().path({})", "ModelError", "replace"),
    ("path", 'm = caster(); m.path({"brake": rolling(m)})', "UnknownConstraintError", "'brake'"),
    ("path", 'caster().path({"dummy": "rolling"})', "ModelError", "'dummy'"),
    ("path", 'm = caster(); m.path({"dummy": rolling(m)}).simulate(2.0)', "ModelError", "t=2.0"),
    ("path", 'm = caster(); m.path({"dummy": rolling(m)}).simulate((0.0, 1.0), method="euler")',
     "OptionError", "'euler'"),
    ("path", 'm = caster(); m.path({"dummy": rolling(m)}, initial_condition={"zz": 0.0})'
     '.simulate((0.0, 1.0))', "ModelError", "'zz'"),
    # outputs and drawing
    ("outputs", 'sol().coordinate("crank.phi")', "ModelError", "crank.phi"),
    ("outputs", 'sol()["wheel.x"]', "ModelError", "wheel.x"),
    ("outputs", 'sol().location(crank().body("crank").point("tip"))', "UnknownBodyError", "'crank'"),
    ("drawing", "ms.draw.snapshot(sol(), index=9)", "ModelError", "0..2"),
    ("drawing", 'ms.draw.snapshot(sol(), default="maybe")', "ModelError", "default"),
    ("drawing", "ms.draw.attach(crank(), 3.0)", "ModelError", "3.0"),
    ("drawing", 'ms.draw.Bar("crank", 0, 1, colour="red")', "ModelError", "colour"),
    ("drawing", "ms.draw.plot(sol(), [])", "ModelError", "no outputs"),
    ("drawing", 'ms.draw.animate(sol(), rate=-1.0)', "ModelError", "rate"),
    ("drawing", "ms.draw.snapshot(3.0)", "ModelError", "3.0"),
    # issue 34: non-physical loads, misspelt options, foreign objects, complex numbers
    ("model", 'm = pend(); b = m.body("bar"); m.add_load(ms.Spring(b.point("tip"), '
     'm.ground.point((2, 0)), 10.0, free_length=-1.0))', "ModelError", "free_length"),
    ("model", 'pend().add_load(ms.JointFriction("pivot", mu=-0.1, radius=0.05))', "ModelError",
     "mu"),
    ("options", 'ms.Model2D(backend="symengin")', "OptionError", "did you mean 'symengine'"),
    ("options", "ms.PositionOptions(tol=1e-9)", "OptionError", "'ftol'"),
    ("path", 'm = caster(); o = caster(); m.path({"dummy": ms.Orthogonal1(m.velocity('
     'm.body("caster").point("wheel")), o.body("caster").vector((0, 1)))})', "ModelError",
     "another model"),
    ("solve", "m = crank(); m.replace(\"drive\", ms.RotationLock1(m.body(\"crank\"), sp.sqrt(-1) * T));"
     " m.solve(0.0)", "ModelError", "complex constant"),
    ("model", 'm = crank(); m.add(ms.RotationLock1(m.body("crank"), 0.0), name=1)', "ModelError",
     "name must be a non-empty string"),
    ("model", 'ms.Model3D().add_body("b", guess=((0, 0, 0), np.diag([1.0, 1.0, -1.0])))',
     "GeometryError", "'b'"),
    ("model", "ms.euler_parameters(2 * np.eye(3))", "GeometryError", "not a rotation"),
    ("model", "ms.rotation_matrix([[1, 0, 0], [0, 1, 0], [0, 0, 1]])", "ModelError", "ambiguous"),
    # model files (issue 39: every failure of ms.load a MechError naming the field)
    ("file", 'ms.load("/nonexistent/crank.json")', "ModelError", "No such file"),
    ("file", 'ms.load("/dev/null")', "ModelError", "not a regular file"),
    ("file", 'ms.io._expr.parse("log(0)*T", {"T": T}, "drive")', "ModelError", "not finite"),
    ("file", 'ms.io._expr.parse("T/0.0", {"T": T}, "drive")', "ModelError", "division by zero"),
    # robot description files and robot-style dynamics (docs/import.md)
    ("import", 'ms.from_urdf("no_such_robot.urdf")', "ModelError", "no_such_robot.urdf"),
    ("import", 'ms.from_mjcf(".")', "ModelError", "not a regular file"),
    ("import", 'crank().inverse_dynamics([0.0], [0.0], [0.0])', "ModelError", "inverse_dynamics"),
    # rolling constraints (decision 0046)
    ("path", 'm = ms.Model3D(); b = m.add_body("disk"); '
     'ms.RollingDisk2(m.ground.axis((0, 0, 0), (0, 0, 1)), b.axis(0, (0, 1, 0)), 0)',
     "GeometryError", "RollingDisk2 rad"),
    ("path", 'm = ms.Model2D(); b = m.add_body("wheel"); '
     'ms.RollingCircle1(b.point(0), float("nan"), m.ground.axis((0, 0), (1, 0)))',
     "GeometryError", "RollingCircle1 rad"),
    ("path", 'm = ms.Model3D(); ms.RollingSphere2(m.ground.axis((0, 0, 0), (0, 0, 1)), '
     '(0, 0, 1), 0.2)', "GeometryError", "centre"),
    ("path", 'm = ms.Model2D(); b = m.add_body("w"); '
     'ms.linear_velocity_form(ms.Constraint([m.velocity_symbols()[b.q[0]] ** 2]), m)',
     "ModelError", "not linear"),
    # a velocity constraint has no multiplier symbols for loads (decision 0068)
    ("path", 'm = caster(); m.add(rolling(m), name="rolling"); m.multipliers("rolling")',
     "ModelError", "'rolling'"),
    # export of absolute bodies and equations (decision 0067)
    ("import", 'm = ms.Model3D(); b = m.add_body("b", mass=1, inertia=(1, 1, 1)); '
     'm.add(ms.RotationLock3(b), name="turn"); m.to_mjcf("never_written.xml")', "ModelError", "'turn'"),
]


def _namespace() -> dict:
    return {"ms": ms, "np": np, "sp": sp, "T": ms.T, "crank": crank, "pend": pend,
            "free": free, "caster": caster, "rolling": rolling, "sol": sol, "m3": m3}


def run_entry(code: str) -> BaseException | None:
    """Run one entry's code; the exception it raised (None if none)."""
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exec(compile(code, "<catalogue>", "exec"), _namespace())
    except Exception as exc:  # noqa: BLE001 - what we examine
        return exc
    return None


@pytest.mark.parametrize("area,code,exc,culprit", CATALOGUE,
                         ids=[f"{i + 1:02d}-{a}" for i, (a, *_) in enumerate(CATALOGUE)])
def test_catalogue_entry_raises_its_documented_error(area, code, exc, culprit):
    err = run_entry(code)
    assert err is not None, f"{code!r} raised nothing"
    assert type(err).__name__ == exc, f"{code!r} raised {type(err).__name__}: {err}"
    assert isinstance(err, ms.MechError)
    assert culprit in str(err), f"{code!r}: message does not name {culprit!r}: {err}"


def test_catalogue_is_large_and_covers_every_area():
    assert len(CATALOGUE) >= 60
    areas = {a for a, *_ in CATALOGUE}
    assert {"model", "options", "solve", "free", "path", "drawing"} <= areas
    assert len({c for _, c, *_ in CATALOGUE}) == len(CATALOGUE)  # no entry twice


# -- the page --------------------------------------------------------------------------------
def exception_classes() -> list:
    """Every exception class mechsys exports (MechError and its subclasses, and warnings)."""
    out = []
    for name in dir(_errors):
        obj = getattr(_errors, name)
        if isinstance(obj, type) and issubclass(obj, (ms.MechError, Warning)) \
                and obj.__module__ == _errors.__name__:
            out.append(obj)
    return sorted(out, key=lambda c: (len(c.__mro__), c.__name__))


def render() -> str:
    """The catalogue section of docs/errors.md."""
    lines = ["| # | area | bad input | raises | message names |", "|---|---|---|---|---|"]
    for i, (area, code, exc, culprit) in enumerate(CATALOGUE, 1):
        lines.append(f"| {i} | {area} | `{code}` | `{exc}` | `{culprit}` |")
    return "\n".join(lines)


def test_doc_matches_the_table():
    page = DOC.read_text(encoding="utf-8")
    i, j = page.index(BEGIN) + len(BEGIN), page.index(END)
    assert page[i:j].strip() == render().strip(), (
        "docs/errors.md's catalogue differs from tests/test_error_catalogue.py: run "
        "python tests/test_error_catalogue.py --write")


def test_doc_lists_every_exception_class_with_cause_and_cure():
    page = DOC.read_text(encoding="utf-8")
    for cls in exception_classes():
        m = re.search(rf"^### `{cls.__name__}`.*?(?=^### |\Z)", page, re.S | re.M)
        assert m, f"docs/errors.md has no section for {cls.__name__}"
        body = m.group(0)
        assert "**Cause**" in body and "**Cure**" in body, cls.__name__
    # and every class the catalogue raises is a documented one
    names = {c.__name__ for c in exception_classes()}
    assert {exc for _, _, exc, _ in CATALOGUE} <= names


if __name__ == "__main__":
    if "--write" in sys.argv:
        page = DOC.read_text(encoding="utf-8")
        i, j = page.index(BEGIN) + len(BEGIN), page.index(END)
        DOC.write_text(page[:i] + "\n" + render() + "\n" + page[j:], encoding="utf-8")
    else:
        for area, code, exc, culprit in CATALOGUE:
            err = run_entry(code)
            ok = err is not None and type(err).__name__ == exc and culprit in str(err)
            if not ok:
                print(f"{'OK ' if ok else 'BAD'} [{area}] {code}\n    -> "
                      f"{type(err).__name__ if err else None}: {str(err)[:300]}")
