"""Issue 34: names that are numbers are refused; copy.copy / copy.deepcopy are Model.copy."""

import copy

import numpy as np
import pytest

import mechsys as ms
from mechsys import ModelError


def _slider():
    m = ms.Model2D()
    b = m.add_body("b", guess=((1, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))), name="guide")
    m.add(ms.RelativeX1(b.point(0), 1.5), name="drive")
    return m, b


@pytest.mark.parametrize("name", [1, np.int64(2), True, 2.0, ""])
def test_constraint_name_that_is_a_number_is_refused(name):
    m, b = _slider()
    c = ms.RelativeY1(b.point(0), 0.0)
    with pytest.raises(ModelError, match="name must be a non-empty string"):
        m.add(c, name=name)
    # nothing was added, and number 1 is still the guide
    assert len(m.constraints) == 2 and m.constraint(1).name == "guide"


@pytest.mark.parametrize("name", [1, np.int32(1), False])
def test_load_name_that_is_a_number_is_refused(name):
    m, b = _slider()
    with pytest.raises(ModelError, match="load name must be a non-empty string"):
        m.add_load(ms.Force(b.point(0), (1, 0)), name=name)
    assert m.load_list == []


def test_string_names_that_look_like_numbers_address_by_name():
    # lookups never parse a string as a number: "1" is a name, 1 the Mech number
    m, b = _slider()
    m.remove("drive")
    c = m.add(ms.RelativeX1(b.point(0), 1.5), name="1")
    assert m.constraint("1") is c and m.constraint(1).name == "guide"


def test_copy_copy_is_independent():
    m, b = _slider()
    for cp in (copy.copy(m), copy.deepcopy(m)):
        assert cp is not m
        cp.add_body("extra")
        cp.remove("drive")
        cp.add_load(ms.Force(cp.body("b").point(0), (1, 0)))
        assert [x.name for x in m.bodies] == ["ground", "b"]
        assert [c.name for c in m.constraints] == ["guide", "drive"]
        assert m.load_list == []
        # the copy's handles belong to the copy
        assert cp.body("b") is not b and cp.body("b").model is cp
    # the original still solves as before, and so does an unedited copy
    for mm in (m, copy.copy(m), copy.deepcopy(m)):
        assert mm.solve(solution="location").location(mm.body("b").point(0))[0] == pytest.approx(1.5)


def test_a_default_name_taken_by_a_given_one_is_not_a_clash():
    m = ms.Model2D()
    b = m.add_body("b", guess=((1, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))), name="c2")
    second = m.add(ms.RelativeX1(b.point(0), 1.5))      # its default name would be "c2"
    assert second.number == 2 and second.name != "c2"
    assert m.constraint(second.name) is second and m.constraint("c2").number == 1
    assert m.solve(solution="location").location(b.point(0))[0] == pytest.approx(1.5)


def test_copy_of_a_model_with_redundant_constraints_after_a_solve():
    # the model caches the reduced systems of redundant constraints: not copied, rebuilt
    m = ms.Model2D()
    b = m.add_body("b", guess=((1, 0), 0))
    m.add(ms.Translate2(m.ground.axis((0, 0), (1, 0)), b.axis((0, 0), (1, 0))))
    m.add(ms.RelativeY1(b.point(0), 0.0))                 # redundant with the guide
    m.add(ms.RelativeX1(b.point(0), 1.5))
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m.solve(solution="location")
        cp = copy.copy(m)
        assert "_reduced" not in cp.__dict__
        assert cp.solve(solution="location").location(cp.body("b").point(0))[0] == pytest.approx(1.5)
