"""Pins the public API: the names users and acceptance checks call must not disappear.

Only required *subsets* are checked, so names added later do not break these tests; removing
or renaming one of the names below is an API change and needs a decision record.
"""

import importlib
from pathlib import Path

import pytest

import mechsys

PACKAGE_DIR = Path(mechsys.__file__).resolve().parent

#: Top-level names of the foundation (issue 2) and the loads named in the design.
REQUIRED_TOP_LEVEL = {
    "__version__", "T",
    # model, bodies, geometry
    "Model", "Model2D", "Model3D", "DOF", "Body", "Point", "Vector", "Axis", "Line",
    # constraints
    "REGISTRY", "ConstraintBase", "Constraint", "Variable", "Revolute2", "Translate2",
    "OriginLock2", "RotationLock1", "RelativeX1", "RelativeY1", "RelativeDistance1",
    "RelativeAngle1", "Orthogonal1", "Parallel1", "PointOnLine1",
    # solving and results
    "PositionOptions", "Solution", "State",
    # errors
    "MechError", "ModelError", "UnknownBodyError", "UnknownPointError",
    "UnknownConstraintError", "GeometryError", "ConstraintCountError", "ConvergenceError",
    "SingularJacobianError",
    # loads (design: Force, Moment, Gravity, Load)
    "Force", "Moment", "Gravity", "Load",
    # Mech's All / Rest selections of output functions (issue 10, section 5)
    "All", "Rest",
    # curves for cam and gear profiles (issue 13, manual chapter 6)
    "SplineFit", "SplineFunction", "Involute",
}

#: Multistage mechanisms (issue 14, Mech chapter 5).
REQUIRED_TOP_LEVEL |= {"StageSwitch", "TimeSwitch", "FindSwitchTime", "FindTime", "find_switch_time",
                       "find_time"}

#: Sensitivity to parameters (issue 15, Mech 9.5): m.sensitivity(...) and its results.
REQUIRED_TOP_LEVEL |= {"Sensitivity", "SensitivitySystem", "ParameterSensitivity"}

#: Coupled models and parameter sweeps (issue 15, Mech chapter 9).
REQUIRED_TOP_LEVEL |= {"Configuration", "CoupleSystem", "CoupleSolution", "Free", "sweep"}

#: Vibration and the features users looked for at once (issue 17).
REQUIRED_TOP_LEVEL |= {"VibrationModes", "TorsionSpring", "TorsionDamper", "tabulated"}

#: Rolling without slip (issue 36 item 2, decision 0046): velocity constraints A(q) qd = 0.
REQUIRED_TOP_LEVEL |= {"RollingDisk2", "RollingSphere2", "RollingCircle1", "RollingContact",
                       "linear_velocity_form"}

#: Public subpackages and modules; every other module is private (``_name.py``).
PUBLIC_MODULES = {"constraints", "compile", "solvers", "testing", "draw", "models", "cli", "model",
                  "geometry", "loads", "analyses", "results", "io"}

REQUIRED_IN_MODULE = {
    "mechsys.constraints": {"REGISTRY", "ConstraintBase", "Constraint", "Variable", "register",
                            "constraint_types", "velocity_rows", "VelocityRows",
                            "linear_velocity_form"},
    "mechsys.compile": {"System", "Layout", "compile_exprs", "available_backends",
                        "default_backend"},
    "mechsys.solvers": {"PositionOptions", "PositionResult", "solve_position",
                        "solve_velocity", "solve_acceleration", "sweep", "SweepResult"},
    "mechsys.testing": {"check_constraint_case", "iter_cases", "case", "Case"},
    "mechsys.models": {"slider_crank", "four_bar", "four_bar_chain"},
    "mechsys.cli": {"main"},
}

#: Methods and attributes the design's API example uses.
REQUIRED_MEMBERS = {
    "Model": {"ground", "bodies", "constraints", "add_body", "body", "add", "constraint",
              "remove", "replace", "parameter", "set_parameters", "parameters", "variable",
              "set_guess", "guess", "compile", "dof", "solve", "location", "velocity",
              "acceleration", "omega", "alpha", "angle", "instant_center", "jacobian",
              "time_derivative", "generalized", "loads"},
    "Body": {"point", "vector", "axis", "line"},
    "Solution": {"location", "velocity", "acceleration", "omega", "alpha", "angle",
                 "instant_center", "eval", "interpolate", "to_dataframe", "state",
                 "coordinate", "names", "table"},
}


#: Issue 17: vibration, momentum and linkage outputs, copies, units.
_ISSUE17_OUTPUTS = {"linear_momentum", "angular_momentum", "centre_of_mass", "transmission_angle",
                    "mechanical_advantage"}
REQUIRED_MEMBERS["Model"] |= _ISSUE17_OUTPUTS | {"vibration", "copy", "remove_body", "set_units",
                                                 "to_units"}
REQUIRED_MEMBERS["Solution"] |= _ISSUE17_OUTPUTS
REQUIRED_MEMBERS["VibrationModes"] = {"shape", "motion", "animate", "table"}
#: Issue 17: model files (docs/model_files.md).
REQUIRED_TOP_LEVEL |= {"load"}
REQUIRED_MEMBERS["Model"] |= {"save"}
REQUIRED_IN_MODULE["mechsys.io"] = {"load", "save", "parse_expression", "expression_text"}
#: Issue 37: robot description files and robot-style dynamics (decision 0040).
REQUIRED_TOP_LEVEL |= {"from_urdf", "from_mjcf", "JointValues"}
REQUIRED_MEMBERS["Model"] |= {"inverse_dynamics", "forward_dynamics", "forward_kinematics", "to_urdf",
                              "to_mjcf"}
REQUIRED_IN_MODULE["mechsys.io"] |= {"from_urdf", "from_mjcf", "ImportReport"}
#: Issue 36: linearisation to state space (decision 0047).
REQUIRED_TOP_LEVEL |= {"LinearSystem", "NotSteadyError"}
REQUIRED_MEMBERS["FreeSystem"] = {"linearize", "solve", "simulate"}
REQUIRED_MEMBERS["LinearSystem"] = {"A", "B", "C", "D", "eigenvalues", "stability", "stable",
                                    "to_scipy", "to_control", "controllability", "controllable"}

def test_all_contains_the_required_names():
    missing = REQUIRED_TOP_LEVEL - set(mechsys.__all__)
    assert not missing, f"removed from mechsys.__all__: {sorted(missing)}"


def test_every_name_in_all_is_importable():
    assert len(mechsys.__all__) == len(set(mechsys.__all__)), "duplicates in __all__"
    for name in mechsys.__all__:
        assert hasattr(mechsys, name), f"mechsys.__all__ lists {name!r} but it is not defined"
    namespace: dict = {}
    exec("from mechsys import *", namespace)  # noqa: S102
    assert set(mechsys.__all__) - {"__version__"} <= set(namespace)


def test_public_names_are_not_modules():
    import types

    for name in mechsys.__all__:
        assert not isinstance(getattr(mechsys, name), types.ModuleType), name


@pytest.mark.parametrize("module", sorted(REQUIRED_IN_MODULE))
def test_public_modules_export_required_names(module):
    mod = importlib.import_module(module)
    exported = set(getattr(mod, "__all__", dir(mod)))
    missing = REQUIRED_IN_MODULE[module] - exported
    assert not missing, f"{module} no longer exports {sorted(missing)}"
    for name in getattr(mod, "__all__", []):
        assert hasattr(mod, name), f"{module}.__all__ lists {name!r} but it is not defined"


@pytest.mark.parametrize("cls", sorted(REQUIRED_MEMBERS))
def test_required_members(cls):
    obj = getattr(mechsys, cls)
    missing = {m for m in REQUIRED_MEMBERS[cls] if not hasattr(obj, m)}
    if cls in ("Solution", "LinearSystem"):  # dataclass fields are instance attributes
        missing -= {f for f in obj.__dataclass_fields__}
    assert not missing, f"mechsys.{cls} lost {sorted(missing)}"


def _modules():
    """Dotted names (relative to mechsys) of every module and subpackage on disk."""
    out = []
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        rel = path.relative_to(PACKAGE_DIR).with_suffix("")
        parts = rel.parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if parts and "__pycache__" not in parts:
            out.append(parts)
    return out


def test_implementation_modules_are_private():
    public = []
    for parts in _modules():
        if parts[-1] == "__main__" or (len(parts) == 1 and parts[0] in PUBLIC_MODULES):
            continue
        if not parts[-1].startswith("_"):
            public.append(".".join(("mechsys", *parts)))
    assert not public, (
        f"modules {public} are public; name implementation modules _name.py and export the "
        "public names from mechsys/__init__.py (public packages/modules: "
        f"{sorted(PUBLIC_MODULES)})")


def test_public_packages_exist():
    present = {parts[0] for parts in _modules()}
    # draw is added by the drawing work; the others are the foundation
    assert PUBLIC_MODULES - {"draw"} <= present


def test_version_matches_metadata():
    from importlib.metadata import PackageNotFoundError, version

    try:
        assert mechsys.__version__ == version("mechsys")
    except PackageNotFoundError:  # running from a source tree without installing
        pytest.skip("mechsys is not installed")


#: The cam constraints and outputs of issue 13 (Mech manual 6.1).
REQUIRED_CAMS = {"CamToPoint1", "CamToCircle1", "CamToLine1", "CamToCam1", "CamToSphere1", "CamToPlane1",
                 "CurveToPoint2", "CurveToPlane1", "CurveToCylinder1", "CurveToCam1", "pressure_angle",
                 "profile_radius"}


def test_cam_names_exported():
    import mechsys.constraints as C

    assert REQUIRED_CAMS <= set(mechsys.__all__)
    assert REQUIRED_CAMS <= set(C.__all__)
    assert {n for n in REQUIRED_CAMS if n[0].isupper()} <= set(C.REGISTRY)

#: Mech's names completed for issue 34 (docs/mech_to_mechsys.md): PolarToXY, PointToLocal,
#: VectorToLocal, VelocityTerms, AccelerationTerms, TimeInterpolate, ArcLength, ClearParameters.
REQUIRED_TOP_LEVEL |= {"PolarToXY", "polar_to_xy"}
REQUIRED_MEMBERS["Model"] |= {"point_to_local", "vector_to_local", "velocity_terms",
                              "acceleration_terms", "clear_parameters"}
REQUIRED_MEMBERS["Solution"] |= {"point_to_local", "vector_to_local", "velocity_terms",
                                 "acceleration_terms", "time_interpolate", "arc_length"}
