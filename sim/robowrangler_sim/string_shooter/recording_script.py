"""What happens during a string-shooter recording: host commands at simulated times and the module's
inclination over time (the robot arm tilting the module: no firmware command, an input of the rope).

    script = RecordingScript.default()            # 12 s: arm, spin up through takeoff, speed steps, tilt, spin down
    script = RecordingScript.short()              # 4 s, the same story compressed (tests)
    script = RecordingScript(duration_s=5.0, commands=(ScriptCommand(0.6, gen.Arm()), ...),
                             phi_rad_points=((0.0, 0.0), (2.0, 0.0), (2.5, 0.35)))
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robowrangler.protocol import generated as gen

from .params import StringShooterParamError


@dataclass(frozen=True)
class ScriptCommand:
    """One host command sent at simulated time at_s [s]: at the first tick at or after it, and not before the
    parameter read a recording starts with (about 0.12 s) has finished."""

    at_s: float
    message: gen.Message


def _speed(rope_speed_mps: float) -> gen.SetRopeSpeed:
    return gen.SetRopeSpeed(round(rope_speed_mps * 1000))


@dataclass(frozen=True)
class RecordingScript:
    """Commands and module inclination of one recording.

    Attributes:
        duration_s: simulated length of the recording [s], > 0.
        commands: ScriptCommand in non-decreasing at_s, each within [0, duration_s); messages must be commands
            (ARM, SET_ROPE_SPEED, SPINDOWN, SET_LOOP, HOME, PARAM_SET, ...), not heartbeats or replies.
        phi_rad_points: (time_s, phi_rad) knots of the inclination, linear in between and constant outside;
            times strictly increasing, |phi| <= pi/2.
    """

    duration_s: float
    commands: tuple[ScriptCommand, ...] = ()
    phi_rad_points: tuple[tuple[float, float], ...] = ((0.0, 0.0),)

    def __post_init__(self) -> None:
        if not (isinstance(self.duration_s, (int, float)) and math.isfinite(self.duration_s) and self.duration_s > 0):
            raise StringShooterParamError(f"duration_s: expected a finite number > 0, got {self.duration_s!r}")
        last = -math.inf
        for i, cmd in enumerate(self.commands):
            if not isinstance(cmd, ScriptCommand):
                raise StringShooterParamError(f"commands[{i}]: expected a ScriptCommand, got {cmd!r}")
            if not (math.isfinite(cmd.at_s) and 0.0 <= cmd.at_s < self.duration_s):
                raise StringShooterParamError(
                    f"commands[{i}].at_s: expected a time in [0, {self.duration_s}) s, got {cmd.at_s!r}")
            if cmd.at_s < last:
                raise StringShooterParamError(
                    f"commands[{i}].at_s: expected non-decreasing times (>= {last} s), got {cmd.at_s!r}")
            last = cmd.at_s
            if not isinstance(cmd.message, gen.Message) or cmd.message.KIND != gen.MsgKind.COMMAND:
                raise StringShooterParamError(f"commands[{i}].message: expected a protocol command, got {cmd.message!r}")
        pts = np.asarray(self.phi_rad_points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 1 or not np.all(np.isfinite(pts)):
            raise StringShooterParamError(
                f"phi_rad_points: expected (time_s, phi_rad) pairs of finite numbers, got {self.phi_rad_points!r}")
        if np.any(np.diff(pts[:, 0]) <= 0):
            raise StringShooterParamError(f"phi_rad_points: expected strictly increasing times, got {pts[:, 0].tolist()}")
        if np.any(np.abs(pts[:, 1]) > math.pi / 2):
            raise StringShooterParamError(f"phi_rad_points: expected |phi| <= pi/2 rad, got {pts[:, 1].tolist()}")

    def phi_rad(self, t_s: np.ndarray) -> np.ndarray:
        """Inclination at times t_s, shape (K,) -> (K,) [rad]."""
        pts = np.asarray(self.phi_rad_points, dtype=float)
        return np.interp(np.asarray(t_s, dtype=float), pts[:, 0], pts[:, 1])

    @classmethod
    def default(cls) -> RecordingScript:
        """12 s: ARM at 0.6 s (after the ESC arming hold), 4 m/s at 0.8 s (through ToV 2.6 m/s: the loop lifts),
        5 m/s at 4 s, 3.5 m/s at 6 s, the module tilts from 0 to +20 deg over 7.5-8.5 s, back to -10 deg over
        9-9.5 s, SPINDOWN at 10.5 s (the loop lands)."""
        return cls(duration_s=12.0,
                   commands=(ScriptCommand(0.6, gen.Arm()), ScriptCommand(0.8, _speed(4.0)),
                             ScriptCommand(4.0, _speed(5.0)), ScriptCommand(6.0, _speed(3.5)),
                             ScriptCommand(10.5, gen.Spindown())),
                   phi_rad_points=((0.0, 0.0), (7.5, 0.0), (8.5, math.radians(20.0)), (9.0, math.radians(20.0)),
                                   (9.5, math.radians(-10.0))))

    @classmethod
    def short(cls) -> RecordingScript:
        """4 s: ARM at 0.6 s, 4.5 m/s at 0.7 s, the module tilts to +20 deg over 2.2-2.7 s, SPINDOWN at 3.1 s."""
        return cls(duration_s=4.0,
                   commands=(ScriptCommand(0.6, gen.Arm()), ScriptCommand(0.7, _speed(4.5)),
                             ScriptCommand(3.1, gen.Spindown())),
                   phi_rad_points=((0.0, 0.0), (2.2, 0.0), (2.7, math.radians(20.0))))
