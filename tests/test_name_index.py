"""The model's name index (decision 0050): bodies and constraints found by name in O(1) give
the same answers as a scan of the model's lists after every kind of edit (add, remove,
replace, remove_body with cascade, copy)."""

import pytest

import mechsys as ms
from mechsys import ModelError, UnknownBodyError, UnknownConstraintError


def _scan(m):
    return ({b.name: b for b in m.bodies}, {c.name: c for c in m.constraints})


def _agrees(m):
    bodies, constraints = _scan(m)
    for name, b in bodies.items():
        assert m.body(name) is b
    for name, c in constraints.items():
        assert m.constraint(name) is c


def _model():
    m = ms.Model2D()
    a = m.add_body("a", points={"tip": (1, 0)})
    b = m.add_body("b", points={"tip": (1, 0)})
    m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="pin")
    m.add(ms.Revolute2(a.point("tip"), b.point(0)))            # default name c2
    m.add(ms.RotationLock1(a, 0.0), name="c3")
    return m, a, b


def test_lookups_follow_every_edit():
    m, a, b = _model()
    _agrees(m)
    # a default name skips the names taken, also one given explicitly ("c3")
    c = m.add(ms.RotationLock1(b, 0.0))
    assert c.name == "c4"
    _agrees(m)
    m.remove("pin")
    with pytest.raises(UnknownConstraintError):
        m.constraint("pin")
    again = m.add(ms.Revolute2(m.ground.point((0, 0)), a.point(0)), name="pin")
    assert m.constraint("pin") is again
    new = m.replace("c3", ms.RotationLock1(a, 0.5))
    assert m.constraint("c3") is new
    _agrees(m)
    m.remove_body("b", cascade=True)
    with pytest.raises(UnknownBodyError):
        m.body("b")
    with pytest.raises(UnknownConstraintError):
        m.constraint("c4")
    _agrees(m)
    nb = m.add_body("b")
    assert m.body("b") is nb and nb.number == 4        # numbers are never reused
    _agrees(m)


def test_clashes_are_refused_and_copies_answer_with_their_own_objects():
    m, a, _ = _model()
    with pytest.raises(ModelError, match="already exists"):
        m.add_body("a")
    with pytest.raises(ModelError, match="already exists"):
        m.add(ms.RotationLock1(a, 1.0), name="pin")
    twin = m.copy()
    assert twin.body("a") is not m.body("a")
    assert twin.constraint("pin") is not m.constraint("pin")
    _agrees(twin)
    twin.add_body("c")
    with pytest.raises(UnknownBodyError):
        m.body("c")
    _agrees(m)
    _agrees(twin)
