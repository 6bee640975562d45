r"""The "from Mech to mechsys" table: every Mech function and option named in the manual,
with its mechsys counterpart or "not yet".

Usage: ``python docs/_gen/gen_mech_map.py docs/mech_to_mechsys.md`` (what ``make docs`` runs);
without an argument the page is printed. Constraint rows are generated from
:data:`mechsys.constraints.REGISTRY` (a newly registered Mech constraint turns its row from
"not yet" to its class by itself); the other rows are the table :data:`ENTRIES` below.
Every counterpart is a dotted path that :func:`resolve` follows through the installed
package (``mechsys.Model.solve``, with ``(keyword=)`` naming a keyword argument that must be
in the signature), and a test resolves them all and compares the committed page with a
fresh one, so the page cannot name a function that does not exist.
"""

from __future__ import annotations

import importlib
import inspect
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from mechsys import MechError

NOT_YET = "not yet"


@dataclass(frozen=True)
class Entry:
    """One Mech name: its group, mechsys counterparts (dotted paths, ``(kw=)`` for a
    keyword argument; empty when there is none yet) and a note."""

    mech: str
    group: str
    targets: tuple[str, ...] = ()
    note: str = ""
    status: str = ""            # "" = by targets; "n/a" = no counterpart needed (note says why)


def _e(mech, group, targets=(), note="", status=""):
    if isinstance(targets, str):
        targets = (targets,)
    return Entry(mech, group, tuple(targets), note, status)


BUILD, OUT, LOADS, FREE, STAGES, CAMS, DRAW, GEOM, OPTS, SESSION, COUPLE = (
    "Building and solving", "Outputs", "Loads, statics and dynamics",
    "Underconstrained systems", "Multistage mechanisms", "Cams and gears",
    "Graphics", "Geometry, rotations and inertia", "Options and settings",
    "Session and model management", "Parametric design")

# Mech constraint names used in the manual that are not (yet) in REGISTRY get "not yet";
# the registered ones are added from REGISTRY by `entries()`.
MANUAL_CONSTRAINTS = (
    "OriginLock1", "OriginLock2", "OriginLock3", "RotationLock1", "RotationLock3",
    "Translate2", "Revolute2", "RelativeX1", "RelativeY1", "RelativeZ1", "RelativeDistance1",
    "RelativeAngle1", "PointOnLine1", "PointOnLine2", "PointOnCircle2", "Orthogonal1",
    "Parallel1", "Parallel2", "PointOnPlane1", "Planar3", "Spherical3", "Revolute5",
    "Translate5", "Cylindrical4", "Universal4", "ParaRevolute4", "OrthoRevolute4",
    "ConstantVelocity4", "LineToLine1", "LineToPlane2", "LineToCircle1", "LineOnCylinder3",
    "PlaneToCircle1", "PlaneToPlane3", "PointAtIntersection3", "TwoGears1", "TwoGears2",
    "RackAndPinion1", "RackAndPinion2", "RackAndPinion4", "RackAndPinion5", "TwoPulleys1",
    "TwoPulleys2", "TwoPulleys4", "TwoPulleys5", "ParallelGears4", "ParallelGears5",
    "OrthogonalGears5", "LeadScrew5", "CamToPoint1", "CamToLine1", "CamToCircle1",
    "CamToCam1", "CamToPlane1", "CamToSphere1", "CurveToPoint2", "CurveToCylinder1",
    "CurveToPlane1", "CurveToCam1", "Constraint", "GenConstraint", "GenRevolute2",
    "GenTranslate2", "GenRevolute5", "GenTranslate5", "GenCylindrical4", "GenOrthoRevolute4",
)

ENTRIES: tuple[Entry, ...] = (
    # -- building and solving ---------------------------------------------------------------
    _e("Modeler2D", BUILD, "mechsys.Model2D", "a planar model object; no global package state"),
    _e("Modeler3D", BUILD, "mechsys.Model3D", "a spatial model object"),
    _e("Body", BUILD, "mechsys.Model.add_body", "returns the body's handle"),
    _e("SetBodies", BUILD, ("mechsys.Model.add_body", "mechsys.Model.set_mass_properties")),
    _e("PointList", BUILD, "mechsys.Model.add_body(points=)", "named or numbered local points"),
    _e("InitialGuess", BUILD, ("mechsys.Model.add_body(guess=)", "mechsys.Model.free(initial_guess=)")),
    _e("Mass", BUILD, "mechsys.Model.add_body(mass=)"),
    _e("Centroid", BUILD, "mechsys.Model.add_body(centroid=)"),
    _e("Inertia", BUILD, "mechsys.Model.add_body(inertia=)"),
    _e("Point", BUILD, "mechsys.Point"),
    _e("Vector", BUILD, "mechsys.Vector"),
    _e("Axis", BUILD, "mechsys.Axis"),
    _e("Line", BUILD, "mechsys.Line"),
    _e("Plane", BUILD, "mechsys.Plane"),
    _e("SetConstraints", BUILD, ("mechsys.Model.add", "mechsys.Model.remove", "mechsys.Model.replace")),
    _e("Constraints", BUILD, "mechsys.Model.constraint_equations", "the symbolic equations"),
    _e("SysCon", BUILD, "mechsys.ConstraintBase", "the constraint object"),
    _e("SetParameters", BUILD, ("mechsys.Model.parameter", "mechsys.Model.set_parameters")),
    _e("Parameters", BUILD, "mechsys.Model.parameters"),
    _e("SetGuess", BUILD, "mechsys.Model.set_guess"),
    _e("SolveMech", BUILD, "mechsys.Model.solve"),
    _e("LastSolve", BUILD, "mechsys.Model.last_solution"),
    _e("MechVariables", BUILD, "mechsys.Solution.names", "and each body's `q`"),
    _e("Jacobian", BUILD, ("mechsys.Model.jacobian", "mechsys.Solution.jacobian")),
    _e("CheckSystem", BUILD, "mechsys.Model.dof", "degrees of freedom, redundant equations"),
    _e("BuildMech", BUILD, "mechsys.Model.compile", "derived lazily, part by part"),
    _e("LockMech", BUILD, "mechsys.Model.lock", "then `.solve(\"static\", parameters={...})`"),
    _e("FunctionOfTime", OPTS, "mechsys.Solution.interpolate", "results are arrays over `t`"),
    _e("MakeRules", OPTS, "mechsys.Solution.coordinate", "every coordinate is kept"),
    # -- outputs ----------------------------------------------------------------------------
    _e("Location", OUT, ("mechsys.Model.location", "mechsys.Solution.location")),
    _e("Velocity", OUT, ("mechsys.Model.velocity", "mechsys.Solution.velocity")),
    _e("Acceleration", OUT, ("mechsys.Model.acceleration", "mechsys.Solution.acceleration")),
    _e("Omega", OUT, ("mechsys.Model.omega", "mechsys.Solution.omega")),
    _e("Alpha", OUT, ("mechsys.Model.alpha", "mechsys.Solution.alpha")),
    _e("Origin", OUT, "mechsys.Model.location", "`location(body.point(0))`"),
    _e("Rotation", OUT, ("mechsys.Rotation", "mechsys.Model.angle", "mechsys.Solution.angle"),
       "3D: (angle, axis) of a body or any rotation format; 2D: the angle of a planar body, of "
       "(ei, ej) or of a 2 x 2 rotation matrix (`rotation(body)`, `m.angle(body)`)"),
    _e("PointToLocal", OUT, ("mechsys.Model.point_to_local", "mechsys.Solution.point_to_local"),
       "a point's coordinates in a body's frame, A^T (r_P - r_b)"),
    _e("VectorToLocal", OUT, ("mechsys.Model.vector_to_local", "mechsys.Solution.vector_to_local"),
       "online manual; a vector's components in a body's axes"),
    _e("ArcLength", OUT, "mechsys.Solution.arc_length",
       "the distance a point travels over a solution, cumulative from the first time"),
    _e("TimeInterpolate", OUT, ("mechsys.Solution.time_interpolate", "mechsys.Solution.interpolate"),
       "an expression at other times, cubic Hermite from the solved velocities"),
    _e("InterpolationOrder", OUT, "mechsys.Solution.interpolate",
       "online manual (TimeInterpolate's option); the order is fixed: cubic Hermite on positions "
       "with velocities, linear without"),
    _e("Interpolation", OUT, ("mechsys.Solution.interpolate", "mechsys.Solution.time_interpolate"),
       "results are arrays over the solved times; interpolate them at others"),
    _e("VelocityTerms", BUILD, ("mechsys.Model.velocity_terms", "mechsys.Solution.velocity_terms"),
       "online manual; Phi_t, so that `jacobian(c) @ qd + velocity_terms(c) == 0`"),
    _e("AccelerationTerms", BUILD, ("mechsys.Model.acceleration_terms",
                                    "mechsys.Solution.acceleration_terms"),
       "online manual; -gamma, so that `jacobian(c) @ qdd + acceleration_terms(c) == 0`"),
    _e("Direction", OUT, ("mechsys.Direction", "mechsys.Model.direction")),
    _e("Distance", OUT, ("mechsys.Distance", "mechsys.Model.distance")),
    _e("ProjectedAngle", OUT, "mechsys.ProjectedAngle"),
    _e("Magnitude", OUT, ("mechsys.Magnitude", "mechsys.Model.magnitude")),
    _e("Unit", OUT, ("mechsys.Unit", "mechsys.Model.unit")),
    _e("InstantCenter", OUT, ("mechsys.Model.instant_center", "mechsys.Solution.instant_center")),
    _e("RelativeVelocity", OUT, ("mechsys.Model.relative_velocity",
                                 "mechsys.Solution.relative_velocity")),
    _e("IntersectionPoint", OUT, "mechsys.IntersectionPoint"),
    _e("Centrifugal", OUT, ("mechsys.Model.centrifugal", "mechsys.Solution.centrifugal"),
       "the velocity-dependent inertial forces Q_v on the right of M qdd = Q + Q_v + reactions; "
       "sign: `centrifugal(All) - mass_matrix(All) @ qdd == loads(All, type=\"dynamic\")` (so "
       "that applied + reaction + dynamic = 0, Mech's Loads identity); the manual's MassMatrix "
       "page writes Centrifugal[All] + MassMatrix[All] . Acceleration[All], which agrees only "
       "with the opposite sign of Centrifugal"),
    # -- loads ------------------------------------------------------------------------------
    _e("SetLoads", LOADS, "mechsys.Model.add_load"),
    _e("Force", LOADS, "mechsys.Force"),
    _e("Moment", LOADS, "mechsys.Moment"),
    _e("Load", LOADS, "mechsys.Load"),
    _e("Gravity", LOADS, "mechsys.Gravity"),
    _e("SysLoad", LOADS, "mechsys.LoadBase", "the load object"),
    _e("Loads", LOADS, ("mechsys.Model.loads", "mechsys.Solution.loads")),
    _e("Reaction", LOADS, ("mechsys.Model.reaction", "mechsys.Solution.reaction"),
       "forms: `reaction(c, body, at=point)`; `reaction(c, body.point(p))` (Point); "
       "`reaction(All, body)` (total); `reaction([c1, c2], body)` (summed); "
       "`reaction(c or All, sym)` for a coordinate or a parameter symbol (a link's tension)"),
    _e("Applied", LOADS, "mechsys.Solution.loads(type=)", 'type="applied"'),
    _e("CutOff", LOADS, ("mechsys.Force(cutoff=)", "mechsys.Moment(cutoff=)")),
    _e("Absolute", LOADS, "mechsys.Force(mode=)", 'mode="absolute" (Magnitude -> Absolute)'),
    _e("Relative", LOADS, ("mechsys.Force(mode=)", "mechsys.Moment(mode=)"),
       'mode="relative" (Magnitude -> Relative)'),
    _e("CompositeInertia", LOADS, ("mechsys.CompositeInertia", "mechsys.composite_inertia"),
       "parts (mass, centroid, inertia) and in 3D an optional rotation of the part's axes"),
    _e("Generalized", LOADS, ("mechsys.Model.generalized", "mechsys.Solution.generalized")),
    _e("MassMatrix", LOADS, ("mechsys.Model.mass_matrix", "mechsys.Solution.mass_matrix")),
    _e("BodyEnergy", LOADS, ("mechsys.Model.body_energy", "mechsys.Solution.body_energy")),
    _e("GyroMoment", LOADS, "mechsys.GyroMoment"),
    _e("GyroFilter", LOADS, "mechsys.GyroFilter"),
    _e("LambdaGuess", LOADS, "mechsys.Model.solve(lambda_guess=)"),
    # -- underconstrained -------------------------------------------------------------------
    _e("SetFree", FREE, "mechsys.Model.free"),
    _e("SolveFree", FREE, ("mechsys.FreeSystem.solve", "mechsys.FreeSystem.simulate")),
    _e("FreeSystem", FREE, "mechsys.FreeSystem"),
    _e("SetPath", FREE, "mechsys.Model.path"),
    _e("SolvePath", FREE, "mechsys.PathSystem.simulate"),
    _e("PathSystem", FREE, "mechsys.PathSystem"),
    _e("InitialCondition", FREE, "mechsys.Model.free(initial_condition=)"),
    _e("FitDegree", FREE, "mechsys.FreeSystem.simulate(fit_degree=)"),
    _e("MaxError", FREE, "mechsys.FreeSystem.simulate(max_error=)"),
    _e("Linear", FREE, "mechsys.FreeSystem.simulate(fit_degree=)", 'fit_degree="linear"'),
    _e("ConstraintCorrection", FREE, "mechsys.FreeSystem.simulate(constraint_correction=)"),
    _e("StepSize", FREE, "mechsys.FreeSystem.simulate(step_size=)",
       "a constant Adams step; adaptive when not given (Mech's Automatic)"),
    _e("StartingStepSize", FREE, "mechsys.FreeSystem.simulate(starting_step_size=)",
       "the first step of an adaptive run, every method"),
    _e("Cubic", FREE, "mechsys.FreeSystem.simulate(fit_degree=)", 'fit_degree="cubic"'),
    _e("Quadratic", FREE, "mechsys.FreeSystem.simulate(fit_degree=)", 'fit_degree="quadratic"'),
    _e("Quartic", FREE, "mechsys.FreeSystem.simulate(fit_degree=)", 'fit_degree="quartic"'),
    _e("Predictor", FREE, "mechsys.FreeSystem.simulate(method=)", 'method="predictor"'),
    _e("Corrector", FREE, "mechsys.FreeSystem.simulate(method=)", 'method="corrector"'),
    _e("MaxIterations", OPTS, ("mechsys.PositionOptions(max_iterations=)",
                               "mechsys.FreeSystem.solve(max_iterations=)"),
       "SolveMech's and SolveFree's Newton; FindSwitchTime's has none (see FindSwitchTime)"),
    _e("ZeroTest", OPTS, ("mechsys.PositionOptions(ftol=)", "mechsys.FreeSystem.solve(tolerance=)"),
       "SolveMech's convergence test; FindSwitchTime's has none (see FindSwitchTime)"),
    _e("DampingFactor", OPTS, "mechsys.PositionOptions(damping=)",
       "SolveMech's Newton damping (a line search, on or off); FindSwitchTime's has none"),
    _e("CheckRules", OPTS, note="SolveMech(..., Solution -> Velocity, CheckRules -> False) skips "
       "the position solve for given rules; `solve` always solves positions (one Newton step "
       "from a valid guess)"),
    _e("StepMech", OPTS, note="online manual; `solve(post_iterate=)` shows each Newton step"),
    _e("Diagnostics", FREE, "mechsys.FreeSystem.simulate(diagnostics=)",
       'per-step step_size (and Adams max_error) in sol.extra["diagnostics"]'),
    # -- multistage ---------------------------------------------------------------------------
    _e("StageSwitch", STAGES, "mechsys.StageSwitch"),
    _e("TimeSwitch", STAGES, "mechsys.TimeSwitch"),
    _e("FindSwitchTime", STAGES, ("mechsys.FindSwitchTime", "mechsys.find_switch_time"),
       "Mech iterates Newton (DampingFactor, MaxIterations, ZeroTest) from the last solution; "
       "mechsys brackets the first sign change over `t_range` (default: the last solution's "
       "span) and refines it by Brent's method to 1e-13, so it needs none of those options and "
       "finds the first switch in the range rather than the one nearest the last solution "
       "(narrow `t_range` to pick another); `guess=` gives the coordinates to start from"),
    _e("FindTime", STAGES, ("mechsys.FindTime", "mechsys.find_time"),
       "as FindSwitchTime: the first root in `t_range` (default: the last solution's span), "
       "bracketed and refined by Brent's method, where Mech starts Newton from the last "
       "solution's time; `guess=` gives the coordinates to start from"),
    _e("Sum", STAGES, "mechsys.find_switch_time(required_equations=)",
       'RequiredEquations -> {All, Sum}: required_equations=("all", "sum")'),
    _e("RequiredEquations", STAGES, "mechsys.find_switch_time"),
    _e("TangentConstraint", STAGES, "mechsys.find_switch_time"),
    # -- cams and gears -----------------------------------------------------------------------
    _e("SplineFit", CAMS, "mechsys.SplineFit"),
    _e("SplineFunction", CAMS, "mechsys.SplineFunction"),
    _e("Involute", CAMS, "mechsys.Involute"),
    _e("Interference", CAMS, "mechsys.Involute"),
    _e("EndConditions", CAMS, "mechsys.SplineFit(end_conditions=)"),
    _e("Natural", CAMS, "mechsys.SplineFit(end_conditions=)", 'end_conditions="natural"'),
    _e("CamPlot", CAMS, "mechsys.draw.CamPlot"),
    # -- graphics -------------------------------------------------------------------------------
    _e("Bar", DRAW, "mechsys.draw.Bar"),
    _e("Wheel", DRAW, "mechsys.draw.Wheel"),
    _e("Arrow", DRAW, "mechsys.draw.Arrow"),
    _e("HeadSize", DRAW, "mechsys.draw.Arrow(head_size=)"),
    _e("Box", DRAW, "mechsys.draw.Box"),
    _e("Sphere", DRAW, "mechsys.draw.Sphere"),
    _e("Cylinder", DRAW, "mechsys.draw.Cylinder"),
    _e("Torus", DRAW, "mechsys.draw.Torus"),
    _e("Revolve", DRAW, "mechsys.draw.Revolve"),
    _e("Extrude", DRAW, "mechsys.draw.Extrude"),
    _e("Facet", DRAW, "mechsys.draw.Facet"),
    _e("Faces", DRAW, "mechsys.draw.Box", "`faces=` of the solid primitives"),
    _e("Edge", DRAW, "mechsys.draw.Edge"),
    _e("Vertex", DRAW, "mechsys.draw.Vertex"),
    _e("LocalAxes", DRAW, "mechsys.draw.LocalAxes"),
    _e("LocusPlot", DRAW, "mechsys.draw.LocusPlot"),
    _e("PointLabel", DRAW, "mechsys.draw.PointLabel"),
    _e("Animate", DRAW, ("mechsys.draw.animate", "mechsys.draw.viewer")),
    # -- geometry ---------------------------------------------------------------------------
    _e("EulerParameters", GEOM, ("mechsys.EulerParameters", "mechsys.euler_parameters")),
    _e("EulerMultiply", GEOM, "mechsys.EulerMultiply"),
    _e("EulerInverse", GEOM, "mechsys.EulerInverse"),
    _e("VirtualRotation", GEOM, "mechsys.VirtualRotation"),
    _e("RotationMatrix", GEOM, "mechsys.RotationMatrix"),
    _e("ReferenceDirection", GEOM, "mechsys.reference_direction"),
    _e("ParallelAxis", GEOM, "mechsys.ParallelAxis"),
    _e("PrincipalAxes", GEOM, "mechsys.PrincipalAxes"),
    _e("XYZToCylindrical", GEOM, "mechsys.XYZToCylindrical"),
    _e("XYZToSpherical", GEOM, "mechsys.XYZToSpherical"),
    _e("CylindricalToXYZ", GEOM, "mechsys.CylindricalToXYZ"),
    _e("SphericalToXYZ", GEOM, "mechsys.SphericalToXYZ"),
    _e("Normalized", GEOM, "mechsys.Rotation"),
    _e("XYZ", GEOM, ("mechsys.XYZToCylindrical(coordinates=)", "mechsys.XYZToSpherical(coordinates=)"),
       'coordinates="XYZ" (default) of the coordinate conversions'),
    _e("YZX", GEOM, ("mechsys.XYZToCylindrical(coordinates=)", "mechsys.XYZToSpherical(coordinates=)"),
       'coordinates="YZX": altitude along X'),
    _e("ZXY", GEOM, ("mechsys.XYZToCylindrical(coordinates=)", "mechsys.XYZToSpherical(coordinates=)"),
       'coordinates="ZXY": altitude along Y'),
    _e("PolarToXY", GEOM, ("mechsys.PolarToXY", "mechsys.polar_to_xy"), "(radius, angle) to (x, y)"),
    _e("Assumptions", GEOM, "mechsys.euler_parameters(normalized=)",
       "Assumptions -> Normalized: normalized=True"),
    _e("Closed", CAMS, "mechsys.SplineFit(end_conditions=)", 'end_conditions="closed"'),
    # -- options and settings -----------------------------------------------------------------
    _e("Solution", OPTS, "mechsys.Model.solve(solution=)"),
    _e("Kinematic", OPTS, "mechsys.Model.solve(solution=)", 'solution="kinematic"'),
    _e("Static", OPTS, "mechsys.Model.solve(solution=)", 'solution="static"'),
    _e("Dynamic", OPTS, "mechsys.Model.solve(solution=)", 'solution="dynamic"'),
    _e("Coordinates", OPTS, "mechsys.Solution.instant_center(coordinates=)"),
    _e("Global", OPTS, "mechsys.Solution.loads(coordinates=)", 'coordinates="global"'),
    _e("Local", OPTS, "mechsys.Solution.loads(coordinates=)", 'coordinates="local"'),
    _e("Type", OPTS, "mechsys.Solution.loads(type=)", '"applied", "reaction", "dynamic"'),
    _e("Free", COUPLE, "mechsys.Free", "time as an unknown of a couple"),
    _e("Method", OPTS, ("mechsys.Model2D(orientation=)", "mechsys.Model3D(velocity=)",
                        "mechsys.FreeSystem.simulate(method=)"),
       "SetSymbols' Method: 2D orientation=\"euler\" builds in degenerate Euler parameters "
       "(decision 0015), 3D a view of one formulation (decision 0006); SolveFree's and "
       "SolvePath's Method: method=\"adams\" (Automatic), \"predictor\", \"corrector\""),
    _e("SetSymbols", OPTS, ("mechsys.Model2D(orientation=)", "mechsys.Model3D(velocity=)",
                            "mechsys.Model3D(coordinates=)", "mechsys.Solution.velocities(representation=)"),
       "Method and Coordinates per model; the time symbol is always `mechsys.T` (no renaming)"),
    _e("Rest", OPTS, "mechsys.Rest", "the model variables' part of a selection"),
    _e("Time", COUPLE, "mechsys.Model.couple(t=)", "Time -> Free: put `mechsys.Free` among the "
       "unknowns"),
    _e("Angle", DRAW, "mechsys.draw.Revolve(angle=)", "the swept angle of a solid of revolution"),
    _e("Euler", OPTS, "mechsys.Model2D(orientation=)",
       'orientation="euler": bodies (x, y, ei, ej), manual 12.4'),
    _e("Angular", OPTS, "mechsys.Model2D(orientation=)", 'orientation="angle" (default)'),
    _e("Compiled", OPTS, "mechsys.Model.set_compile_options(opt_level=)",
       "always compiled (LLVM); opt_level, cse and the backend choose how (manual 12.3)"),
    _e("All", OPTS, "mechsys.All"),
    # -- parametric design ----------------------------------------------------------------------
    _e("SetCouple", COUPLE, "mechsys.Model.couple", "chapter 9.1-9.4"),
    _e("SolveCouple", COUPLE, "mechsys.CoupleSystem.solve"),
    _e("SetSensitivity", COUPLE, "mechsys.Model.sensitivity", "chapter 9.5"),
    _e("Parameterize", COUPLE, "mechsys.Model.parameter", "parameters are SymPy symbols"),
    # -- session and model management -----------------------------------------------------------
    _e("MechVersion", SESSION, "mechsys.__version__"),
    _e("ClearMech", SESSION, status="n/a", note="make a new Model; there is no global model"),
    _e("ResetMech", SESSION, status="n/a", note="make a new Model; there is no global model"),
    _e("KillMech", SESSION, status="n/a", note="Python modules need no unloading"),
    _e("HelpModel2D", SESSION, note="the model of Mech's online help examples (a crank and a "
       "link); mechsys.models has the manual's chapter models instead (slider_crank, ...)"),
    _e("HelpModel3D", SESSION, note="online manual; as HelpModel2D"),
    _e("ClearParameters", BUILD, "mechsys.Model.clear_parameters",
       "refuses parameters still used, naming their users"),
    _e("LineToCylinder1", "Constraints", "mechsys.LineToLine1",
       "the manual's other name for LineToLine1 with a distance"),
    _e("ParaRevolute", "Constraints", "mechsys.ParaRevolute4",
       "the manual's shorthand on the ParaRevolute4 page"),
    _e("X2", SESSION, "mechsys.Solution.names",
       "Mech's coordinate symbols X2, Y3d, Ei2, ... are x2, y3_d, ei2, ... (`body.q`, "
       "`sol.names`); the completeness test maps every such name here"),
    _e("JoinRows", SESSION, "numpy.hstack", "NumPy does it"),
    _e("Mech", SESSION, "mechsys.MechError", "the messages are exceptions"),
    _e("MechBodyList", SESSION, "mechsys.Model.bodies"),
    _e("MechConstraintList", SESSION, "mechsys.Model.constraints"),
    _e("MechTimeSymbol", SESSION, "mechsys.T"),
    _e("MechPreSolve", SESSION, "mechsys.Model.solve(pre_solve=)", "a hook before each solve"),
    _e("MechPostIterate", SESSION, "mechsys.Model.solve(post_iterate=)",
       "a hook after each Newton iteration"),
    _e("MechProcessFunction", SESSION, "mechsys.Model.set_compile_options(process=)",
       'process="chop" or a function on every constraint equation (manual 12.2)'),
    _e("MechPrimeRules", SESSION, "mechsys.Model.velocity_symbols"),
    _e("MechTimeRules", SESSION, "mechsys.Model.time_derivative"),
    _e("MechUseEulerMassTerm", SESSION, status="n/a",
       note="one angular-velocity representation (decision 0006)"),
    _e("MechUseMinimalRotation", SESSION, status="n/a",
       note="one angular-velocity representation (decision 0006)"),
)


#: Symbols in the manual's text that are not Mech's: Mathematica's own, and page furniture.
NOT_MECH = {
    "Abs": "Mathematica", "Chop": "Mathematica", "Derivative": "Mathematica",
    "False": "Mathematica", "General": "Mathematica (message group)", "Get": "Mathematica",
    "Indeterminate": "Mathematica", "InterpolatingFunction": "Mathematica",
    "Join": "Mathematica", "MapThread": "Mathematica", "Needs": "Mathematica",
    "None": "Mathematica", "Polygon": "Mathematica", "Print": "Mathematica",
    "Step": "Mathematica", "Transpose": "Mathematica", "True": "Mathematica",
    "Automatic": "Mathematica (a default setting)",
    "MechanicalSystems": "the package's name (page headers)",
}

#: Names of Mech's online function index (reference.wolfram.com/applications/mechsystems)
#: met while completing the table that the seed's excerpt of the manual does not contain.
ONLINE_NAMES = ("AccelerationTerms", "ArcLength", "HelpModel3D", "InterpolationOrder",
                "StepMech", "VectorToLocal", "VelocityTerms")

#: Mech's coordinate symbols (X2, Y3d, Ei2 ...): all covered by the "X2" row.
COORDINATE_SYMBOL = re.compile(r"(?:X|Y|Z|Ei|Ej|Ek|Eo)\d+d{0,2}")
#: Words the manual's text breaks across lines ("Parame ters").
SPLIT_WORDS = {"Parame ters": "Parameters", "Reac tion": "Reaction"}
_ID = r"\$?[A-Z][A-Za-z0-9]*"
_LIST = rf"((?:{_ID})(?:,? (?:and |or )?(?:{_ID}))*)"
_ID_ARG = rf"({_ID})"


def _placeholder(name: str) -> bool:
    """Argument names of the manual's templates (``C``, ``G``, ``Ixx`` ...), not symbols."""
    return len(name) == 1 or re.fullmatch(r"I[xyz]{2}", name) is not None


def manual_names(text: str) -> dict:
    """Every Mech symbol the manual's function reference text uses, with how it was found:
    entry headings (``Name 2D/3D †``), calls ``Name[``, options and settings
    (``Name -> Setting``), "See also" lists, option tables, "option/setting for A, B and C",
    "the Name option", lists of alternatives and valid settings, symbol arguments
    (``Loads[Rest]``) and symbol lists (``{All, Sum}``). Template placeholders are dropped."""
    for a, b in SPLIT_WORDS.items():
        text = text.replace(a, b)
    found: dict = {}

    def add(name, how):
        if not _placeholder(name.lstrip("$")):
            found.setdefault(name, set()).add(how)

    for m in re.finditer(rf"({_ID}) (?:2D/3D|2D|3D) \u2020", text):
        add(m.group(1), "heading")
    for m in re.finditer(rf"(?<![\w$])({_ID})\[", text):
        add(m.group(1), "call")
    for m in re.finditer(rf"(?<![\w$])({_ID})\s*->\s*\{{?\s*({_ID})?", text):
        add(m.group(1), "option")
        if m.group(2):
            add(m.group(2), "setting")
    for m in re.finditer(r"See also: ([^\u2020]+?)\.(?:\s|$)", text):
        for n in re.split(r",\s*", m.group(1)):
            if re.fullmatch(_ID, n.strip()):
                add(n.strip(), "see also")
    for m in re.finditer(rf"can be givens?: ({_ID})", text):
        add(m.group(1), "option table")
    for m in re.finditer(rf"^({_ID})$", text, re.M):
        add(m.group(1), "option table")
    for m in re.finditer(rf"(?:option|setting|settings) for {_LIST}", text):
        for n in re.findall(_ID, m.group(1)):
            add(n, "option for")
    for m in re.finditer(rf"the ({_ID}) (?:option|setting)", text):
        add(m.group(1), "the X option")
    for m in re.finditer(rf"(?:alternatives? to (?:the )?{_ID}(?: setting)?|Valid settings for "
                         rf"{_ID}) (?:is|are) {_LIST}", text):
        for n in re.findall(_ID, m.group(1)):
            add(n, "alternatives")
    for m in re.finditer(rf"(?<![\w$])(?:{_ID})\[([^\[\]]*)\]", text):
        for n in re.findall(rf"(?:^|[\s,{{]){_ID_ARG}(?=\s*(?:,|\]|\}}|$))", m.group(1)):
            add(n, "argument")
    for m in re.finditer(r"\{([^{}]*)\}", text):
        items = [x.strip() for x in m.group(1).split(",") if x.strip()]
        if items and all(re.fullmatch(_ID, x) for x in items):
            for x in items:
                add(x, "list")
    return found



def uncovered(names) -> list:
    """The names that are neither a row of the table, nor a coordinate symbol (the ``X2``
    row), nor one of :data:`NOT_MECH`."""
    rows = {e.mech for e in entries()}
    return sorted(n for n in names if n not in rows and n.lstrip("$") not in rows
                  and n not in NOT_MECH and not COORDINATE_SYMBOL.fullmatch(n))


def _instance_attr(cls: type, name: str) -> bool:
    """Whether ``name`` is a dataclass field of ``cls`` or assigned as ``self.<name> = `` in
    the ``__init__`` of ``cls`` or a base."""
    if name in getattr(cls, "__dataclass_fields__", {}):
        return True
    for klass in cls.__mro__:
        init = klass.__dict__.get("__init__")
        if init is None:
            continue
        try:
            src = inspect.getsource(init)
        except (OSError, TypeError):
            continue
        if re.search(rf"\bself\.{re.escape(name)}\s*(?::[^=]*)?=", src):
            return True
    return False


def _attr_chain(path: str):
    """Import the longest importable prefix of ``path`` and follow the rest as attributes."""
    parts = path.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            if isinstance(obj, type) and not hasattr(obj, name) and _instance_attr(obj, name):
                return obj                   # set on every instance by __init__
            obj = getattr(obj, name)
        return obj
    raise ImportError(path)


def resolve(target: str):
    """The object a counterpart names (``mechsys.Model.solve`` or
    ``mechsys.Model.solve(solution=)``); raises :class:`MechError` when it does not exist."""
    m = re.fullmatch(r"([\w.]+)(?:\((\w+)=\))?", target)
    if not m:
        raise MechError(f"malformed counterpart {target!r}: write a dotted path, optionally "
                        "followed by (keyword=)")
    path, kw = m.groups()
    try:
        obj = _attr_chain(path)
    except (ImportError, AttributeError) as exc:
        raise MechError(f"counterpart {target!r} does not exist: {exc}") from exc
    if kw is not None:
        fn = obj.__init__ if isinstance(obj, type) else obj
        params = inspect.signature(fn).parameters
        if kw not in params:
            raise MechError(f"counterpart {target!r}: {path} has no keyword {kw!r} "
                            f"(it takes {', '.join(params)})")
    return obj


def entries() -> list[Entry]:
    """All rows: constraints from the registry and the manual's constraint names, then
    :data:`ENTRIES`."""
    import mechsys
    from mechsys.constraints import REGISTRY

    rows = []
    for name in sorted(set(MANUAL_CONSTRAINTS) | set(REGISTRY)):
        if name in REGISTRY and getattr(REGISTRY[name], "order", 0) == 1:
            # the rolling contacts (decision 0046) have no Mech name: Mech writes them with
            # Constraint and velocities (manual 10.5)
            rows.append(Entry(name, "Constraints", (f"mechsys.{name}",),
                              "mechsys's own, not a Mech name: rolling without slip, a "
                              "velocity constraint for m.path (Mech: Constraint of velocities)"))
        elif name in REGISTRY:
            rows.append(Entry(name, "Constraints", (f"mechsys.{name}",)))
        elif hasattr(mechsys, name):
            # joints that write no equations (the Gen joints of chapter 11) are not registered
            rows.append(Entry(name, "Constraints", (f"mechsys.{name}",), "generalized coordinates"))
        else:
            rows.append(Entry(name, "Constraints"))
    seen = {r.mech for r in rows}
    for e in ENTRIES:
        if e.mech in seen:
            raise MechError(f"{e.mech} is listed twice in the Mech table")
        seen.add(e.mech)
        rows.append(e)
    return rows


def _status(e: Entry) -> str:
    if e.status:
        return e.status
    return "yes" if e.targets else NOT_YET


def _target_md(t: str) -> str:
    return f"`{t.removeprefix('mechsys.')}`" if t.startswith("mechsys.") else f"`{t}`"


HEADER = """\
# From Mech to mechsys

<!-- Generated by `python docs/_gen/gen_mech_map.py docs/mech_to_mechsys.md` (`make docs`) from
docs/_gen/gen_mech_map.py and the constraint registry. Do not edit by hand. -->

Every function, object and option of Mech (Mathematica's MechanicalSystems) that its manual
names, with the mechsys counterpart: a name under `mechsys` (so `Model.solve` is
`mechsys.Model.solve`, used as `m.solve(...)` on a model; `Solution.location` as
`sol.location(...)` on a solution), `name(keyword=)` for an option that became a keyword
argument, **not yet** when mechsys has none so far, and **n/a** when mechsys needs none (the
note says why). The constraint rows come from the constraint registry, and a test checks
that every counterpart named here exists. See also the [user guide](guide.md) and the
[constraint reference](constraints.md).
"""


def render() -> str:
    rows = entries()
    counts = {s: sum(_status(r) == s for r in rows) for s in ("yes", NOT_YET, "n/a")}
    out = [HEADER, f"{len(rows)} names: {counts['yes']} with a counterpart, "
           f"{counts[NOT_YET]} not yet, {counts['n/a']} not needed.", "",
           "The manual's text also uses symbols that are not Mech's: "
           + ", ".join(f"`{k}`" for k in sorted(NOT_MECH)) + " (Mathematica's own, and the "
           "package name in page headers). A test reads every symbol of the manual's function "
           "reference (calls, options, settings, See-also lists, option tables) and checks that "
           "each is a row here or one of these.", ""]
    groups = []
    for r in rows:
        if r.group not in groups:
            groups.append(r.group)
    for g in groups:
        out += [f"## {g}", "", "| Mech | mechsys | status | note |", "| --- | --- | --- | --- |"]
        for r in sorted((r for r in rows if r.group == g), key=lambda r: r.mech):
            target = ", ".join(_target_md(t) for t in r.targets) or "—"
            st = _status(r)
            st = f"**{st}**" if st != "yes" else st
            out.append(f"| `{r.mech}` | {target} | {st} | {r.note} |")
        out.append("")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    for e in entries():
        for t in e.targets:
            resolve(t)
    text = render()
    if argv:
        Path(argv[0]).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
