"""Pure numeric algorithms (no SymPy): position, velocity, acceleration, sweeps."""

from ._kinematics import ORDERS, SweepResult, solve_acceleration, solve_velocity, sweep
from ._linalg import dependent_rows
from ._position import PositionOptions, PositionResult, solve_position

__all__ = [
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
