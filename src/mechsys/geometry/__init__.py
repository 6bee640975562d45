"""Geometry: points, vectors, axes, planes, bodies, rotations, coordinate spaces and inertia.

Imports run down inside this package: ``_points`` (no body module) <- ``_rotations`` <-
``_space`` <- ``_bodies``; ``_inertia`` stands alone. Nothing here imports constraints,
loads, compile, results or analyses.
"""

from ._bodies import Body
from ._curves import Involute, SplineFit, SplineFunction
from ._inertia import composite_inertia, parallel_axis, principal_axes
from ._planar_euler import PLANAR_EULER, PlanarEuler
from ._points import (
    Axis,
    BodyRef,
    Geometry,
    GlobalVector,
    Line,
    Plane,
    Point,
    Vector,
    as_axis,
    as_point,
    as_vector,
    reference_direction,
)
from ._space import PLANAR, SPATIAL, Planar, Space, Spatial

__all__ = [
    "Axis", "Body", "BodyRef", "Geometry", "GlobalVector", "Line", "PLANAR", "PLANAR_EULER", "Plane",
    "Planar", "PlanarEuler", "Point", "SPATIAL", "Space", "Spatial", "Vector", "as_axis",
    "as_point", "as_vector",
    "composite_inertia", "parallel_axis", "principal_axes", "reference_direction",
    "Involute", "SplineFit", "SplineFunction",
]
