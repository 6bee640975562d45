"""Bad solver input is rejected with a ModelError naming the field or argument (issue 10,
section 2): PositionOptions fields, the times of solve, the options argument."""

import numpy as np
import pytest

import mechsys as ms
from mechsys import models


@pytest.mark.parametrize("kw, field", [
    ({"ftol": -1}, "ftol"), ({"ftol": 0.0}, "ftol"), ({"ftol": float("nan")}, "ftol"),
    ({"ftol": float("inf")}, "ftol"), ({"ftol": "1e-8"}, "ftol"),
    ({"max_iterations": 0}, "max_iterations"), ({"max_iterations": 2.5}, "max_iterations"),
    ({"max_iterations": True}, "max_iterations"), ({"damping": "yes"}, "damping"),
])
def test_position_options_are_validated(kw, field):
    """Before: ftol=-1 gave 'did not converge (max residual 0.0)'."""
    with pytest.raises(ms.ModelError, match=rf"PositionOptions: {field} must be"):
        ms.PositionOptions(**kw)


def test_valid_position_options_and_mapping():
    m = models.slider_crank()
    a = m.solve(0.1, options=ms.PositionOptions(ftol=1e-8, max_iterations=20, damping=False))
    b = m.solve(0.1, options={"ftol": 1e-8})
    assert abs(a["piston.x"] - b["piston.x"]) < 1e-8
    with pytest.raises(ms.ModelError, match=r"unknown option\(s\) \['maxiter'\]"):
        m.solve(0.1, options={"maxiter": 3})
    with pytest.raises(ms.ModelError, match=r"options must be a PositionOptions"):
        m.solve(0.1, options=1e-8)


@pytest.mark.parametrize("t, what", [
    (None, "got None"), ([[0.0, 0.1]], r"shape \(1, 2\)"), ([], "empty sequence"),
    (np.nan, "got nan at index 0"), ([0.0, np.inf], "got inf at index 1"), ("soon", "got 'soon'"),
])
def test_solve_rejects_bad_times(t, what):
    """Before: solve(None) reported 'a coordinate left the domain of an expression'."""
    with pytest.raises(ms.ModelError, match=rf"solve: t must be a finite time .*{what}"):
        models.slider_crank().solve(t)


def test_solving_an_empty_model_says_there_is_nothing_to_solve():
    """Before: an empty Solution of 0 coordinates came back (and LAPACK printed errors)."""
    with pytest.raises(ms.ModelError, match="no moving bodies"):
        ms.Model2D().solve(0.0)
    with pytest.raises(ms.ModelError, match="no moving bodies"):
        ms.Model3D().solve([0.0, 1.0])
