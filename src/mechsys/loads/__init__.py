"""Loads: forces, moments, gravity, springs and dampers, joint friction, gyroscopic loads.

Each load turns itself into point forces and body moments (``PointForce``, ``BodyMoment``) or
direct generalized forces (``DirectLoad``); ``compile`` sums their virtual work.
"""

from ._friction import JointFriction
from ._gyro import GyroMoment, gyro_filter
from ._loads import (
    BodyMoment,
    Damper,
    DirectLoad,
    Force,
    Gravity,
    Load,
    LoadBase,
    Moment,
    PointForce,
    Spring,
)
from ._torsion import TorsionDamper, TorsionSpring

__all__ = [
    "BodyMoment", "Damper", "DirectLoad", "Force", "Gravity", "GyroMoment", "JointFriction",
    "Load", "LoadBase", "Moment", "PointForce", "Spring", "TorsionDamper", "TorsionSpring",
    "gyro_filter",
]
