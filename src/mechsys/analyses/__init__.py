"""Analyses: systems derived from a model for one kind of question.

``FreeSystem`` (Mech's SetFree/SolveFree, chapter 10) and ``PathSystem`` (SetPath/SolvePath,
10.5). Each reads the model's parameters when it solves or simulates, not when it is built.
"""

from ._free import FreeSystem
from ._multistage import FindSwitchTime, FindTime, find_switch_time, find_time
from ._path import PathSystem
from ._vibration import VibrationModes

__all__ = ["FindSwitchTime", "FindTime", "FreeSystem", "PathSystem", "VibrationModes", "find_switch_time",
           "find_time"]
