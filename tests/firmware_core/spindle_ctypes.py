"""ctypes bindings of the spindle blocks of the firmware core: rw_ax12, rw_multiturn, rw_spindle.

The Structure classes mirror firmware/core/rw_multiturn.h, rw_spindle.h and hal/rw_hal_spindle.h field
for field (same order, same types); change both together. Objects are held with the canary block of
rw_core_ctypes, so a mirror smaller than the C struct fails loudly.

Units: the wrappers (Multiturn.step, Spindle.step) take degrees, deg/s and seconds and convert them here, the
one place, to the integer units of the C API (multi-turn ticks of 1/2560 register unit, ticks/ms Q10,
milliseconds; rw_ax12.h); the spindle's config and position_mm stay millimetres, its speeds are um/s.
"""

from __future__ import annotations

import ctypes
import math
from ctypes import c_bool, c_float, c_int, c_int16, c_int32, c_uint8, c_uint16, c_uint32
from enum import IntEnum

from rw_core_ctypes import _Guarded

DIRECTION_BIT = 0x0400
MAGNITUDE_MASK = 0x03FF
TICKS_PER_DEG = 8729.6  # RW_AX12_TICKS_PER_DEG: 2560 ticks per register unit, 1023 units per 300 degrees
SPEED_Q10_PER_DEG_S = TICKS_PER_DEG * 1024.0 / 1000.0  # deg/s -> ticks per millisecond, Q10


def ticks_of_deg(position_deg: float) -> int:
    """Degrees -> multi-turn ticks, rounded (0.000115 degree resolution)."""
    if not math.isfinite(position_deg):
        raise ValueError(f"position_deg: expected a finite angle in degrees, got {position_deg!r}")
    return int(round(position_deg * TICKS_PER_DEG))


def speed_q10_of_deg_s(speed_deg_s: float) -> int:
    """deg/s -> ticks per millisecond, Q10, rounded."""
    if not math.isfinite(speed_deg_s):
        raise ValueError(f"speed_deg_s: expected a finite speed in deg/s, got {speed_deg_s!r}")
    return int(round(speed_deg_s * SPEED_Q10_PER_DEG_S))


def ms_of_s(dt_s: float) -> int:
    """Seconds -> whole milliseconds (the C steps take dt_ms); rejects what is not a whole, non-negative ms."""
    if not math.isfinite(dt_s) or dt_s < 0.0 or abs(dt_s * 1000.0 - round(dt_s * 1000.0)) > 1e-6:
        raise ValueError(f"dt_s: expected a non-negative whole number of milliseconds in seconds, got {dt_s!r}")
    return int(round(dt_s * 1000.0))


class Mode(IntEnum):
    """rw_spindle_mode."""

    IDLE = 0
    HOMING = 1
    POSITION = 2
    RETRACT = 3


class Outcome(IntEnum):
    """rw_spindle_outcome."""

    NOTHING = 0
    HOMED_BY_STALL = 1
    HOMED_BY_SWITCH = 2
    TARGET_REACHED = 3
    SECURED = 4
    STROKE_END = 5
    STALLED = 6
    NO_ANSWER = 7


class MultiturnConfig(ctypes.Structure):
    _fields_ = [("dead_zone_margin_deg", c_float), ("max_jump_deg", c_float)]


class _MultiturnState(ctypes.Structure):
    _fields_ = [("angle_ticks", c_int32), ("angle_rem_q10", c_uint16), ("initialized", c_bool),
                ("dead_reckoning", c_bool), ("rejected", c_uint16), ("agree", c_uint8),
                ("candidate_ticks", c_int32), ("turn_base_ticks", c_int32), ("margin_ticks", c_int32),
                ("max_jump_ticks", c_int32), ("memo_margin_deg", c_float), ("memo_max_jump_deg", c_float)]


class MultiturnStruct(ctypes.Structure):
    _fields_ = [("cfg", MultiturnConfig), ("state", _MultiturnState)]


class SpindleConfig(ctypes.Structure):
    _fields_ = [(name, c_float) for name in (
        "lead_mm_per_rev", "guide_min_mm", "guide_max_mm", "kp_per_s", "max_speed_mmps", "tolerance_mm",
        "homing_speed_mmps", "homing_load_pct", "stall_load_pct", "stall_time_s", "secure_load_pct",
        "retract_speed_mmps", "timeout_s")]


class SpindleReading(ctypes.Structure):
    _fields_ = [("position_raw", c_uint16), ("speed_raw", c_uint16), ("load_raw", c_uint16),
                ("limit_switch", c_bool)]


class SpindleDerived(ctypes.Structure):
    _fields_ = [("um_per_tick_q32", c_uint32), ("ticks_per_ms_q10_per_umps_q8", c_int32),
                ("moving_raw_per_umps_q16", c_uint32)] + [(name, c_int32) for name in (
                    "full_scale_umps", "kp_per_s_q16", "guide_min_um", "guide_max_um", "tolerance_um",
                    "max_speed_umps", "homing_speed_umps", "retract_speed_umps", "homing_load_permille",
                    "stall_load_permille", "secure_load_permille", "still_speed_raw")]


class _SpindleState(ctypes.Structure):
    _fields_ = [("turns", MultiturnStruct), ("mode", c_uint8), ("homed", c_bool), ("answering", c_bool),
                ("target_reported", c_bool), ("home_ticks", c_int32), ("position_um", c_int32),
                ("position_mm", c_float), ("target_mm", c_float), ("target_um", c_int32),
                ("present_speed_raw", c_uint16), ("command_umps", c_int32), ("load_permille", c_int16),
                ("stall_ms", c_uint32), ("silent_ms", c_uint32), ("moving_speed_raw", c_uint16),
                ("memo_cfg", SpindleConfig), ("derived", SpindleDerived)]


class SpindleStruct(ctypes.Structure):
    _fields_ = [("cfg", SpindleConfig), ("state", _SpindleState)]


_SIGNATURES = {
    "rw_ax12_position_deg": (c_float, [c_uint16]),
    "rw_ax12_speed_deg_s": (c_float, [c_uint16]),
    "rw_ax12_load_permille": (c_int16, [c_uint16]),
    "rw_ax12_moving_speed_raw": (c_uint16, [c_float]),
    "rw_multiturn_init": (None, [ctypes.POINTER(MultiturnStruct), ctypes.POINTER(MultiturnConfig)]),
    "rw_multiturn_config_defaults": (None, [ctypes.POINTER(MultiturnConfig)]),
    "rw_multiturn_reset": (None, [ctypes.POINTER(MultiturnStruct)]),
    "rw_ax12_position_ticks": (c_int32, [c_uint16]),
    "rw_ax12_speed_ticks_per_ms_q10": (c_int32, [c_uint16]),
    "rw_multiturn_step": (c_int32, [ctypes.POINTER(MultiturnStruct), c_bool, c_int32, c_int32, c_uint32]),
    "rw_multiturn_angle_deg": (c_float, [ctypes.POINTER(MultiturnStruct)]),
    "rw_spindle_init": (None, [ctypes.POINTER(SpindleStruct), ctypes.POINTER(SpindleConfig)]),
    "rw_spindle_stop": (None, [ctypes.POINTER(SpindleStruct)]),
    "rw_spindle_home": (None, [ctypes.POINTER(SpindleStruct)]),
    "rw_spindle_move_to": (None, [ctypes.POINTER(SpindleStruct), c_float]),
    "rw_spindle_retract": (None, [ctypes.POINTER(SpindleStruct)]),
    "rw_spindle_step": (c_int, [ctypes.POINTER(SpindleStruct), ctypes.POINTER(SpindleReading), c_uint32]),
}


def declare(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Declares the spindle signatures on the loaded core library (idempotent); returns lib."""
    for name, (restype, argtypes) in _SIGNATURES.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = argtypes
    return lib


def multiturn_defaults(lib: ctypes.CDLL) -> MultiturnConfig:
    cfg = MultiturnConfig()
    declare(lib).rw_multiturn_config_defaults(ctypes.byref(cfg))
    return cfg


class Multiturn(_Guarded):
    """rw_multiturn: continuous servo angle (degrees) from the single-turn register."""

    struct_type = MultiturnStruct

    def __init__(self, lib: ctypes.CDLL, *, dead_zone_margin_deg: float | None = None,
                 max_jump_deg: float | None = None) -> None:
        super().__init__(declare(lib))
        cfg = multiturn_defaults(lib)
        if dead_zone_margin_deg is not None:
            cfg.dead_zone_margin_deg = dead_zone_margin_deg
        if max_jump_deg is not None:
            cfg.max_jump_deg = max_jump_deg
        self._call("rw_multiturn_init", ctypes.byref(cfg))

    def step(self, *, valid: bool, position_deg: float, speed_deg_s: float, dt_s: float) -> float:
        """One step (degrees, deg/s and seconds converted to the C units, see the module docstring); returns the
        continuous angle, degrees."""
        self.step_ticks(valid=valid, position_ticks=ticks_of_deg(position_deg),
                        speed_ticks_per_ms_q10=speed_q10_of_deg_s(speed_deg_s), dt_ms=ms_of_s(dt_s))
        return self.angle_deg

    def step_ticks(self, *, valid: bool, position_ticks: int, speed_ticks_per_ms_q10: int, dt_ms: int) -> int:
        """One step in the C units; returns the continuous angle, ticks."""
        return self._call("rw_multiturn_step", valid, position_ticks, speed_ticks_per_ms_q10, dt_ms)

    def reset(self) -> None:
        self._call("rw_multiturn_reset")

    @property
    def angle_deg(self) -> float:
        return self._call("rw_multiturn_angle_deg")

    @property
    def angle_ticks(self) -> int:
        self._check()
        return int(self.obj.state.angle_ticks)

    @property
    def initialized(self) -> bool:
        self._check()
        return bool(self.obj.state.initialized)

    @property
    def dead_reckoning(self) -> bool:
        self._check()
        return bool(self.obj.state.dead_reckoning)

    @property
    def rejected(self) -> int:
        self._check()
        return int(self.obj.state.rejected)


# The core's spindle defaults (protocol spec parameter defaults, RW_PARAM_DEFAULT_* in rw_protocol.h).
DEFAULT_CONFIG = dict(
    lead_mm_per_rev=8.0, guide_min_mm=0.0, guide_max_mm=180.0, kp_per_s=4.0, max_speed_mmps=6.0,
    tolerance_mm=0.5, homing_speed_mmps=3.0, homing_load_pct=25.0, stall_load_pct=50.0, stall_time_s=0.3,
    secure_load_pct=12.0, retract_speed_mmps=5.0, timeout_s=0.2,
)


class Spindle(_Guarded):
    """rw_spindle: homing, position loop, retract, stall and silence detection (mm, mm/s, s)."""

    struct_type = SpindleStruct

    def __init__(self, lib: ctypes.CDLL, **overrides: float) -> None:
        super().__init__(declare(lib))
        unknown = set(overrides) - set(DEFAULT_CONFIG)
        if unknown:
            raise TypeError(f"Spindle: unknown config field(s) {sorted(unknown)}; expected {sorted(DEFAULT_CONFIG)}")
        cfg = SpindleConfig(**{**DEFAULT_CONFIG, **overrides})
        self._call("rw_spindle_init", ctypes.byref(cfg))

    def step(self, reading: SpindleReading | None, dt_s: float) -> Outcome:
        """One spindle step with the servo's reading (None: no answer), dt_s a whole number of milliseconds."""
        ptr = ctypes.byref(reading) if reading is not None else None
        return Outcome(self._call("rw_spindle_step", ptr, ms_of_s(dt_s)))

    def stop(self) -> None:
        self._call("rw_spindle_stop")

    def home(self) -> None:
        self._call("rw_spindle_home")

    def move_to(self, target_mm: float) -> None:
        self._call("rw_spindle_move_to", target_mm)

    def retract(self) -> None:
        self._call("rw_spindle_retract")

    def __getattr__(self, name: str):
        # state fields by name (mode, homed, position_mm, moving_speed_raw, ...), canary checked
        if name in {f[0] for f in _SpindleState._fields_}:
            self._check()
            return getattr(self.obj.state, name)
        raise AttributeError(name)

    @property
    def rejected(self) -> int:
        self._check()
        return int(self.obj.state.turns.state.rejected)

    @property
    def command_mmps(self) -> float:
        """The commanded guide speed, mm/s (the C state keeps um/s)."""
        self._check()
        return self.obj.state.command_umps * 1e-3


def signed_raw(value: int) -> int:
    """A signed magnitude (+ = counter-clockwise) as an AX-12A 11-bit register (bit 10 = clockwise)."""
    magnitude = min(abs(int(value)), MAGNITUDE_MASK)
    return magnitude | (DIRECTION_BIT if value < 0 else 0)


def raw_signed(raw: int) -> int:
    """An AX-12A 11-bit register as a signed magnitude (+ = counter-clockwise)."""
    magnitude = raw & MAGNITUDE_MASK
    return -magnitude if raw & DIRECTION_BIT else magnitude
