"""Constraint types. Every class is registered under its Mech name in ``REGISTRY``."""

from ._base import ConstraintBase, Variable
from ._general import Constraint
from ._planar import (
    Orthogonal1,
    OriginLock2,
    Parallel1,
    PointOnLine1,
    RelativeAngle1,
    RelativeDistance1,
    RelativeX1,
    RelativeY1,
    Revolute2,
    RotationLock1,
    Translate2,
)
from ._registry import REGISTRY, constraint_types, register

for _cls in (
    Revolute2,
    Translate2,
    OriginLock2,
    RotationLock1,
    RelativeX1,
    RelativeY1,
    RelativeDistance1,
    RelativeAngle1,
    Orthogonal1,
    Parallel1,
    PointOnLine1,
    Constraint,
):
    register(_cls)

__all__ = [
    "REGISTRY",
    "Constraint",
    "ConstraintBase",
    "Orthogonal1",
    "OriginLock2",
    "Parallel1",
    "PointOnLine1",
    "RelativeAngle1",
    "RelativeDistance1",
    "RelativeX1",
    "RelativeY1",
    "Revolute2",
    "RotationLock1",
    "Translate2",
    "Variable",
    "constraint_types",
    "register",
]
