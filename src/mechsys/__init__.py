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

from ._bodies import Body
from ._errors import (
    ConstraintCountError,
    ConvergenceError,
    GeometryError,
    MechError,
    ModelError,
    SingularJacobianError,
    UnknownBodyError,
    UnknownConstraintError,
    UnknownPointError,
)
from ._free import FreeSystem
from ._friction import JointFriction
from ._geometry import Axis, Line, Point, Vector
from ._inertia import (
    CompositeInertia,
    ParallelAxis,
    PrincipalAxes,
    composite_inertia,
    parallel_axis,
    principal_axes,
)
from ._loads import Damper, Force, Gravity, Load, LoadBase, Moment, Spring
from ._model import DOF, Model, Model2D, Model3D
from ._results import Solution, State
from ._symbols import T
from .constraints import (
    REGISTRY,
    Constraint,
    ConstraintBase,
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
    Variable,
)
from .solvers import PositionOptions

__version__ = "0.1.0"

__all__ = [
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
