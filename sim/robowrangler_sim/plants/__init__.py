"""Plants the SIL steps in lockstep: the rope drive (ESC -> BLDC motors -> wheels -> rope, encoder, battery)."""

from robowrangler_sim.plants.drive import (
    DrivePlant,
    kv_throttle_for_speed,
    rope_drag_force_n,
    speed_time_constant_s,
    steady_battery_v,
    steady_throttle_for_speed,
)
from robowrangler_sim.plants.drive_params import DriveParams, DriveParamsError

__all__ = [
    "DriveParams",
    "DriveParamsError",
    "DrivePlant",
    "kv_throttle_for_speed",
    "rope_drag_force_n",
    "speed_time_constant_s",
    "steady_battery_v",
    "steady_throttle_for_speed",
]
