"""Constraint types. Every class is registered under its Mech name in ``REGISTRY``."""

from ._base import ConstraintBase, Variable
from ._general import Constraint
from ._planar import (
    OriginLock2,
    Orthogonal1,
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
from ._spatial import (
    SPATIAL_TYPES,
    ConstantVelocity4,
    Cylindrical4,
    LineOnCylinder3,
    LineToCircle1,
    LineToLine1,
    LineToPlane2,
    OriginLock3,
    OrthoRevolute4,
    Parallel2,
    ParaRevolute4,
    Planar3,
    PlaneToCircle1,
    PlaneToPlane3,
    PointAtIntersection3,
    PointOnCircle2,
    PointOnLine2,
    PointOnPlane1,
    RelativeZ1,
    Revolute5,
    RotationLock3,
    Spherical3,
    Translate5,
    Universal4,
)

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
    *SPATIAL_TYPES,
):
    register(_cls)

__all__ = [
    "ConstantVelocity4",
    "Cylindrical4",
    "LineOnCylinder3",
    "LineToCircle1",
    "LineToLine1",
    "LineToPlane2",
    "OriginLock3",
    "OrthoRevolute4",
    "Parallel2",
    "ParaRevolute4",
    "Planar3",
    "PlaneToCircle1",
    "PlaneToPlane3",
    "PointAtIntersection3",
    "PointOnCircle2",
    "PointOnLine2",
    "PointOnPlane1",
    "RelativeZ1",
    "Revolute5",
    "RotationLock3",
    "Spherical3",
    "Translate5",
    "Universal4",
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

# cam constraints (Mech manual 6.1)
from ._cams import (  # noqa: E402
    CAM_TYPES,
    CamToCam1,
    CamToCircle1,
    CamToLine1,
    CamToPlane1,
    CamToPoint1,
    CamToSphere1,
    CurveToCam1,
    CurveToCylinder1,
    CurveToPlane1,
    CurveToPoint2,
    pressure_angle,
    profile_radius,
)

for _cls in CAM_TYPES:
    register(_cls)

__all__ += ["CamToCam1", "CamToCircle1", "CamToLine1", "CamToPlane1", "CamToPoint1",
            "CamToSphere1", "CurveToCam1", "CurveToCylinder1", "CurveToPlane1", "CurveToPoint2",
            "pressure_angle", "profile_radius"]
