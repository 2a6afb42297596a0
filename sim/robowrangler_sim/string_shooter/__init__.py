"""First-principles string shooter: an axially moving rope loop with gravity, air drag and bending
stiffness, driven by a wheel nip through a guide eyelet (issue 6). See docs/string_shooter.md."""

from .contact import Box, Capsule, Cylinder, HalfSpace, Sphere
from .model import Frame, Recording, StringShooter, StringShooterDivergedError
from .motion import ModuleMotion
from .params import (AirParams, ModuleGeometry, NipParams, NumericsParams, RopeParams, ShooterParams,
                     StringShooterParamError, takeoff_speed_estimate_mps)

__all__ = [
    "AirParams", "Box", "Capsule", "Cylinder", "Frame", "HalfSpace", "ModuleGeometry", "ModuleMotion", "NipParams",
    "NumericsParams", "Recording", "RopeParams", "ShooterParams", "Sphere", "StringShooter",
    "StringShooterDivergedError", "StringShooterParamError", "takeoff_speed_estimate_mps",
]
