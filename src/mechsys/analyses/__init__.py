"""Analyses: systems derived from a model for one kind of question.

``FreeSystem`` (Mech's SetFree/SolveFree, chapter 10), ``PathSystem`` (SetPath/SolvePath,
10.5), ``CoupleSystem`` (SetCouple/SolveCouple, 9.1-9.4), parameter ``sweep``s and
``LockedModel`` (LockMech, 12.5). Each reads the model's parameters when it solves or
simulates, not when it is built.
"""

from ._couple import Configuration, CoupleSolution, CoupleSystem, Free, FreeTime
from ._free import FreeSystem
from ._linearize import LinearSystem
from ._lock import LockedModel
from ._multistage import FindSwitchTime, FindTime, find_switch_time, find_time
from ._path import PathSystem
from ._sweep import sweep
from ._vibration import VibrationModes

__all__ = ["Configuration", "CoupleSolution", "CoupleSystem", "FindSwitchTime", "FindTime", "Free",
           "FreeSystem", "FreeTime", "LinearSystem", "LockedModel", "PathSystem", "VibrationModes",
           "find_switch_time", "find_time", "sweep"]
