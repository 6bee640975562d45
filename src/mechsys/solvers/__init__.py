"""Pure numeric algorithms (no SymPy): position, velocity, acceleration, sweeps."""

from ._kinematics import ORDERS, SweepResult, solve_acceleration, solve_velocity, sweep
from ._linalg import dependent_rows
from ._position import PositionOptions, PositionResult, solve_position
from ._statics import MODES, MultiplierOptions, solve_multipliers

__all__ = [
    "MODES",
    "MultiplierOptions",
    "solve_multipliers",
    "ORDERS",
    "PositionOptions",
    "PositionResult",
    "SweepResult",
    "dependent_rows",
    "solve_acceleration",
    "solve_position",
    "solve_velocity",
    "sweep",
]
