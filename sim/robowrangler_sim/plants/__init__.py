"""Plants the SIL steps in lockstep behind one contract (contract.py): the rope drive (ESC -> BLDC motors -> wheels
-> rope, encoder, battery) and the spindle (AX-12A -> lead screw -> guide)."""

from robowrangler_sim.plants.contract import Plant
from robowrangler_sim.plants.drive import (
    DriveInputs,
    DriveOutputs,
    DrivePlant,
    kv_throttle_for_speed,
    rope_drag_force_n,
    speed_time_constant_s,
    steady_battery_v,
    steady_throttle_for_speed,
)
from robowrangler_sim.plants.drive_params import DriveParams, DriveParamsError

__all__ = [
    "DriveInputs",
    "DriveOutputs",
    "DriveParams",
    "DriveParamsError",
    "DrivePlant",
    "Plant",
    "kv_throttle_for_speed",
    "rope_drag_force_n",
    "speed_time_constant_s",
    "steady_battery_v",
    "steady_throttle_for_speed",
]
