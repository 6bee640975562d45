"""Results: frozen ``State`` and ``Solution`` objects and the output functions they share
with the model (written once: symbolic on a model, numeric on a solution)."""

from ._load_outputs import LoadOutputs
from ._outputs import OutputFunctions, VelocityViews
from ._solution import Solution, State

__all__ = ["LoadOutputs", "OutputFunctions", "Solution", "State", "VelocityViews"]
