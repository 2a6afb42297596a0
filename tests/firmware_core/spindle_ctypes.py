"""ctypes bindings of the spindle blocks of the firmware core: rw_ax12, rw_multiturn, rw_spindle.

The Structure classes mirror firmware/core/rw_multiturn.h, rw_spindle.h and hal/rw_hal_spindle.h field
for field (same order, same types); change both together. Objects are held with the canary block of
rw_core_ctypes, so a mirror smaller than the C struct fails loudly.

Units are those of the C API: degrees, degrees per second, millimetres, mm/s, seconds, raw registers.
"""

from __future__ import annotations

import ctypes
from ctypes import c_bool, c_float, c_int, c_int16, c_uint8, c_uint16
from enum import IntEnum

from rw_core_ctypes import _Guarded

DIRECTION_BIT = 0x0400
MAGNITUDE_MASK = 0x03FF


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
    _fields_ = [("angle_deg", c_float), ("initialized", c_bool), ("dead_reckoning", c_bool),
                ("rejected", c_uint16), ("agree", c_uint8), ("candidate_deg", c_float)]


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


class _SpindleState(ctypes.Structure):
    _fields_ = [("turns", MultiturnStruct), ("mode", c_uint8), ("homed", c_bool), ("answering", c_bool),
                ("target_reported", c_bool), ("home_angle_deg", c_float), ("position_mm", c_float),
                ("target_mm", c_float), ("speed_mmps", c_float), ("command_mmps", c_float),
                ("load_permille", c_int16), ("stall_s", c_float), ("silent_s", c_float),
                ("moving_speed_raw", c_uint16)]


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
    "rw_multiturn_step": (c_float, [ctypes.POINTER(MultiturnStruct), c_bool, c_float, c_float, c_float]),
    "rw_spindle_init": (None, [ctypes.POINTER(SpindleStruct), ctypes.POINTER(SpindleConfig)]),
    "rw_spindle_stop": (None, [ctypes.POINTER(SpindleStruct)]),
    "rw_spindle_home": (None, [ctypes.POINTER(SpindleStruct)]),
    "rw_spindle_move_to": (None, [ctypes.POINTER(SpindleStruct), c_float]),
    "rw_spindle_retract": (None, [ctypes.POINTER(SpindleStruct)]),
    "rw_spindle_step": (c_int, [ctypes.POINTER(SpindleStruct), ctypes.POINTER(SpindleReading), c_float]),
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
        """One step; returns the continuous angle, degrees."""
        return self._call("rw_multiturn_step", valid, position_deg, speed_deg_s, dt_s)

    def reset(self) -> None:
        self._call("rw_multiturn_reset")

    @property
    def angle_deg(self) -> float:
        self._check()
        return self.obj.state.angle_deg

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
        """One spindle step with the servo's reading (None: no answer)."""
        ptr = ctypes.byref(reading) if reading is not None else None
        return Outcome(self._call("rw_spindle_step", ptr, dt_s))

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


def signed_raw(value: int) -> int:
    """A signed magnitude (+ = counter-clockwise) as an AX-12A 11-bit register (bit 10 = clockwise)."""
    magnitude = min(abs(int(value)), MAGNITUDE_MASK)
    return magnitude | (DIRECTION_BIT if value < 0 else 0)


def raw_signed(raw: int) -> int:
    """An AX-12A 11-bit register as a signed magnitude (+ = counter-clockwise)."""
    magnitude = raw & MAGNITUDE_MASK
    return -magnitude if raw & DIRECTION_BIT else magnitude
