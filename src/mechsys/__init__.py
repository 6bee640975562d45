"""mechsys: kinematic and dynamic analysis of planar and spatial rigid-body mechanisms.

Quick start::

    import numpy as np, sympy as sp
    import mechsys as ms
    from mechsys import T

    m = ms.Model2D()
    crank = m.add_body("crank", points={"pin": (2, 0)})
    ...
    sol = m.solve(t=np.linspace(0, 1, 101))
"""

from ._errors import (
    ConstraintCountError,
    ConvergenceError,
    GeometryError,
    MechError,
    ModelError,
    NearSingularWarning,
    SingularJacobianError,
    SingularMassError,
    UnknownBodyError,
    UnknownConstraintError,
    UnknownPointError,
)
from ._symbols import T
from .analyses._free import FreeSystem
from .analyses._path import PathSystem
from .constraints import (
    REGISTRY,
    ConstantVelocity4,
    Constraint,
    ConstraintBase,
    Cylindrical4,
    LineOnCylinder3,
    LineToCircle1,
    LineToLine1,
    LineToPlane2,
    OriginLock2,
    OriginLock3,
    Orthogonal1,
    OrthoRevolute4,
    Parallel1,
    Parallel2,
    ParaRevolute4,
    Planar3,
    PlaneToCircle1,
    PlaneToPlane3,
    PointAtIntersection3,
    PointOnCircle2,
    PointOnLine1,
    PointOnLine2,
    PointOnPlane1,
    RelativeAngle1,
    RelativeDistance1,
    RelativeX1,
    RelativeY1,
    RelativeZ1,
    Revolute2,
    Revolute5,
    RotationLock1,
    RotationLock3,
    Spherical3,
    Translate2,
    Translate5,
    Universal4,
    Variable,
)
from .geometry._bodies import Body
from .geometry._inertia import (
    CompositeInertia,
    ParallelAxis,
    PrincipalAxes,
    composite_inertia,
    parallel_axis,
    principal_axes,
)
from .geometry._points import Axis, Line, Plane, Point, Vector, reference_direction
from .geometry._rotations import (
    CylindricalToXYZ,
    Direction,
    Distance,
    EulerInverse,
    EulerMultiply,
    EulerParameters,
    IntersectionPoint,
    Magnitude,
    ProjectedAngle,
    Rotation,
    RotationMatrix,
    SphericalToXYZ,
    Unit,
    VirtualRotation,
    XYZToCylindrical,
    XYZToSpherical,
    cylindrical_to_xyz,
    direction,
    distance,
    euler_parameters,
    intersection_point,
    magnitude,
    projected_angle,
    quaternion_inverse,
    quaternion_product,
    rotation,
    rotation_matrix,
    spherical_to_xyz,
    unit,
    virtual_rotation,
    xyz_to_cylindrical,
    xyz_to_spherical,
)
from .loads._friction import JointFriction
from .loads._gyro import GyroFilter, GyroMoment, gyro_filter
from .loads._loads import Damper, Force, Gravity, Load, LoadBase, Moment, Spring
from .model import DOF, Model, Model2D, Model3D
from .results._outputs import All, Rest
from .results._solution import Solution, State
from .solvers import PositionOptions

__version__ = "0.1.0"

__all__ = [
    "All",
    "Rest",
    "NearSingularWarning",
    "PathSystem",
    "GyroFilter",
    "GyroMoment",
    "gyro_filter",
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
    "CylindricalToXYZ",
    "Direction",
    "Distance",
    "EulerInverse",
    "EulerMultiply",
    "EulerParameters",
    "IntersectionPoint",
    "Magnitude",
    "ProjectedAngle",
    "Rotation",
    "RotationMatrix",
    "SphericalToXYZ",
    "Unit",
    "VirtualRotation",
    "XYZToCylindrical",
    "XYZToSpherical",
    "cylindrical_to_xyz",
    "direction",
    "distance",
    "euler_parameters",
    "intersection_point",
    "magnitude",
    "projected_angle",
    "quaternion_inverse",
    "quaternion_product",
    "rotation",
    "rotation_matrix",
    "spherical_to_xyz",
    "unit",
    "virtual_rotation",
    "xyz_to_cylindrical",
    "xyz_to_spherical",
    "Plane",
    "reference_direction",
    "FreeSystem",
    "CompositeInertia",
    "Damper",
    "Force",
    "Gravity",
    "JointFriction",
    "Load",
    "LoadBase",
    "Moment",
    "ParallelAxis",
    "PrincipalAxes",
    "Spring",
    "composite_inertia",
    "parallel_axis",
    "principal_axes",
    "DOF",
    "REGISTRY",
    "Axis",
    "Body",
    "Constraint",
    "ConstraintBase",
    "ConstraintCountError",
    "ConvergenceError",
    "GeometryError",
    "Line",
    "MechError",
    "Model",
    "Model2D",
    "Model3D",
    "ModelError",
    "OriginLock2",
    "Orthogonal1",
    "Parallel1",
    "Point",
    "PointOnLine1",
    "PositionOptions",
    "RelativeAngle1",
    "RelativeDistance1",
    "RelativeX1",
    "RelativeY1",
    "Revolute2",
    "RotationLock1",
    "SingularJacobianError",
    "SingularMassError",
    "Solution",
    "State",
    "T",
    "Translate2",
    "UnknownBodyError",
    "UnknownConstraintError",
    "UnknownPointError",
    "Variable",
    "Vector",
    "__version__",
]


# cam constraints (Mech manual 6.1)
from .constraints import (  # noqa: E402
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

__all__ += ["CamToCam1", "CamToCircle1", "CamToLine1", "CamToPlane1", "CamToPoint1",
            "CamToSphere1", "CurveToCam1", "CurveToCylinder1", "CurveToPlane1", "CurveToPoint2",
            "pressure_angle", "profile_radius"]


def __getattr__(name):
    """Lazy subpackages: ``mechsys.draw`` (and matplotlib) load on first use only."""
    if name == "draw":
        import importlib

        return importlib.import_module(".draw", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
