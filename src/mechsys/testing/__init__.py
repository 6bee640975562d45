"""Public conformance checks for constraint classes (run by the test suite over every type).

``iter_cases()`` yields ``(mech_name, Case)`` for each registered case;
``check_constraint_case(case)`` runs the residual, Jacobian, gamma and DOF checks.
Register cases for a new constraint type with the ``@case("Name")`` decorator.
"""

from . import (
    _cases_cams,  # noqa: F401  (registers cases)
    _cases_gears,  # noqa: F401  (registers cases)
    _cases_planar,  # noqa: F401  (registers cases)
    _cases_rolling,  # noqa: F401  (registers cases)
    _cases_spatial,  # noqa: F401  (registers cases)
)
from ._checks import (
    CASES,
    Case,
    case,
    check_constraint_case,
    check_dof,
    check_gamma,
    check_jacobian,
    check_residual,
    check_velocity_case,
    iter_cases,
    pose_vector,
)

__all__ = [
    "CASES",
    "Case",
    "case",
    "check_constraint_case",
    "check_dof",
    "check_gamma",
    "check_jacobian",
    "check_residual",
    "check_velocity_case",
    "iter_cases",
    "pose_vector",
]
