"""ctypes bindings of the firmware core control blocks in build/native/librw_core.so.

The Structure classes mirror the C structs in firmware/core/rw_*.h field for field (same order,
same types); change both together. Every object is allocated with a canary block behind it, and
each wrapper call checks the canary, so a mirror that is smaller than the C struct fails loudly
instead of corrupting memory silently.

The wrappers take and return Python floats/ints in the units of the C API (seconds, m/s, us). Where a C
step runs in Q16.16 fixed point (rw_float_bits.h: the PI, ramp, low-pass, feed-forward and ESC pulse) the
wrapper converts with to_q16 / from_q16, the one place the tests do it; a non-finite input is refused there
with a ValueError naming the argument (a Q16.16 value cannot be NaN or infinite).
"""

from __future__ import annotations

import ctypes
import math
from ctypes import c_bool, c_float, c_int8, c_int32, c_int64, c_uint16, c_uint32
from pathlib import Path

CANARY = 0xA5A5A5A5A5A5A5A5
_CANARY_WORDS = 8


class LowpassConfig(ctypes.Structure):
    _fields_ = [("tau_s", c_float)]


class _LowpassState(ctypes.Structure):
    _fields_ = [("y_q32", c_int64), ("alpha_q20", c_int32), ("prepared_dt_s", c_float)]


class Lowpass(ctypes.Structure):
    _fields_ = [("cfg", LowpassConfig), ("state", _LowpassState)]


class RampConfig(ctypes.Structure):
    _fields_ = [("rate_up_per_s", c_float), ("rate_down_per_s", c_float)]


class _RampState(ctypes.Structure):
    _fields_ = [("y_q32", c_int64), ("step_up_q32", c_int64), ("step_down_q32", c_int64), ("prepared_dt_s", c_float)]


class Ramp(ctypes.Structure):
    _fields_ = [("cfg", RampConfig), ("state", _RampState)]


class PiConfig(ctypes.Structure):
    _fields_ = [("kp", c_float), ("ki_per_s", c_float), ("out_min", c_float), ("out_max", c_float)]


class _PiState(ctypes.Structure):
    _fields_ = [("integral_q32", c_int64), ("output_q16", c_int32), ("saturation", c_int8), ("valid", c_bool),
                ("kp_q24", c_int32), ("ki_dt_q32", c_int64), ("prepared_dt_s", c_float), ("out_min_q16", c_int32),
                ("out_max_q16", c_int32)]


class Pi(ctypes.Structure):
    _fields_ = [("cfg", PiConfig), ("state", _PiState)]


class MtConfig(ctypes.Structure):
    _fields_ = [("counts_per_rev", c_uint32), ("timeout_us", c_uint32), ("wheel_radius_m", c_float),
                ("filter_tau_s", c_float)]


class _MtState(ctypes.Structure):
    _fields_ = [("last_count", c_uint32), ("last_edge_us", c_uint32), ("raw_rev_per_s_q16", c_int32),
                ("filter", Lowpass), ("primed", c_bool), ("stale", c_bool), ("valid", c_bool),
                ("two_pi_r_q32", c_uint32), ("rope_mps_q16", c_int32), ("max_int_dt_us", c_uint32)]


class Mt(ctypes.Structure):
    _fields_ = [("cfg", MtConfig), ("state", _MtState)]


class ThrottleConfig(ctypes.Structure):
    _fields_ = [("kv_rpm_per_v", c_float), ("wheel_radius_m", c_float), ("pulse_min_us", c_uint16),
                ("pulse_max_us", c_uint16)]


class _ThrottleState(ctypes.Structure):
    _fields_ = [("two_pi_r_kv", c_float), ("pulse_lo_us", c_uint16), ("pulse_hi_us", c_uint16),
                ("battery_v", c_float), ("throttle_per_mps", c_float), ("throttle_per_mps_q24", c_int32)]


class Throttle(ctypes.Structure):
    _fields_ = [("cfg", ThrottleConfig), ("state", _ThrottleState)]


class TovConfig(ctypes.Structure):
    _fields_ = [("tov_mps", c_float), ("margin", c_float), ("collapse_time_s", c_float)]


class _TovState(ctypes.Structure):
    _fields_ = [("below_s", c_float), ("collapsed", c_bool), ("min_airborne_mps", c_float),
                ("min_airborne_mps_q16", c_int32), ("config_valid", c_bool)]


class Tov(ctypes.Structure):
    _fields_ = [("cfg", TovConfig), ("state", _TovState)]


# name -> (restype, argtypes); pointer types are filled in by _declare.
_SIGNATURES = {
    "rw_lowpass_init": (None, ["Lowpass*", "LowpassConfig*"]),
    "rw_lowpass_reset": (None, ["Lowpass*"]),
    "rw_lowpass_reset_to": (None, ["Lowpass*", c_int32]),
    "rw_lowpass_step": (c_int32, ["Lowpass*", c_int32, c_float]),
    "rw_lowpass_output_q16": (c_int32, ["Lowpass*"]),
    "rw_lowpass_config_is_valid": (c_bool, ["LowpassConfig*"]),
    "rw_lowpass_prepare": (None, ["Lowpass*", c_float]),
    "rw_ramp_init": (None, ["Ramp*", "RampConfig*"]),
    "rw_ramp_config_defaults": (None, ["RampConfig*"]),
    "rw_ramp_reset": (None, ["Ramp*"]),
    "rw_ramp_reset_to": (None, ["Ramp*", c_float]),
    "rw_ramp_step": (c_int32, ["Ramp*", c_int32, c_float]),
    "rw_ramp_output_q16": (c_int32, ["Ramp*"]),
    "rw_ramp_output": (c_float, ["Ramp*"]),
    "rw_ramp_at_target": (c_bool, ["Ramp*", c_float]),
    "rw_ramp_config_is_valid": (c_bool, ["RampConfig*"]),
    "rw_ramp_prepare": (None, ["Ramp*", c_float]),
    "rw_pi_controller_init": (None, ["Pi*", "PiConfig*"]),
    "rw_pi_controller_config_defaults": (None, ["PiConfig*"]),
    "rw_pi_controller_reset": (None, ["Pi*"]),
    "rw_pi_controller_step": (c_int32, ["Pi*", c_int32, c_int32, c_int32, c_float]),
    "rw_pi_controller_output_q16": (c_int32, ["Pi*"]),
    "rw_pi_controller_config_is_valid": (c_bool, ["PiConfig*"]),
    "rw_pi_controller_prepare": (None, ["Pi*", c_float]),
    "rw_pi_controller_set_out_min_q16": (None, ["Pi*", c_int32]),
    "rw_mt_speed_estimator_init": (None, ["Mt*", "MtConfig*"]),
    "rw_mt_speed_estimator_config_defaults": (None, ["MtConfig*"]),
    "rw_mt_speed_estimator_reset": (None, ["Mt*"]),
    "rw_mt_speed_estimator_step": (c_float, ["Mt*", c_uint32, c_uint32, c_uint32, c_float]),
    "rw_mt_speed_estimator_rev_per_s": (c_float, ["Mt*"]),
    "rw_mt_speed_estimator_rpm": (c_float, ["Mt*"]),
    "rw_mt_speed_estimator_rope_mps": (c_float, ["Mt*"]),
    "rw_mt_speed_estimator_rope_mps_q16": (c_int32, ["Mt*"]),
    "rw_mt_speed_estimator_raw_rev_per_s": (c_float, ["Mt*"]),
    "rw_mt_speed_estimator_is_stale": (c_bool, ["Mt*"]),
    "rw_mt_speed_estimator_config_is_valid": (c_bool, ["MtConfig*"]),
    "rw_mt_speed_estimator_prepare": (None, ["Mt*", c_float]),
    "rw_throttle_map_init": (None, ["Throttle*", "ThrottleConfig*"]),
    "rw_throttle_map_config_defaults": (None, ["ThrottleConfig*"]),
    "rw_throttle_map_feed_forward": (c_int32, ["Throttle*", c_int32, c_float]),
    "rw_throttle_map_no_load_rope_mps": (c_float, ["Throttle*", c_float, c_float]),
    "rw_throttle_map_pulse_us": (c_uint16, ["Throttle*", c_int32]),
    "rw_throttle_map_pulse_third_us": (c_uint16, ["Throttle*", c_int32]),
    "rw_throttle_map_throttle_from_pulse": (c_float, ["Throttle*", c_uint16]),
    "rw_throttle_map_config_is_valid": (c_bool, ["ThrottleConfig*"]),
    "rw_throttle_map_prepare": (None, ["Throttle*"]),
    "rw_tov_guard_init": (None, ["Tov*", "TovConfig*"]),
    "rw_tov_guard_config_defaults": (None, ["TovConfig*"]),
    "rw_tov_guard_reset": (None, ["Tov*"]),
    "rw_tov_guard_min_airborne_mps": (c_float, ["Tov*"]),
    "rw_tov_guard_setpoint_allowed": (c_bool, ["Tov*", c_float]),
    "rw_tov_guard_step": (c_bool, ["Tov*", c_float, c_float]),
    "rw_tov_guard_is_collapsed": (c_bool, ["Tov*"]),
    "rw_tov_guard_config_is_valid": (c_bool, ["TovConfig*"]),
    "rw_tov_guard_prepare": (None, ["Tov*"]),
}


def _declare(lib: ctypes.CDLL) -> None:
    for name, (restype, argtypes) in _SIGNATURES.items():
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = [ctypes.POINTER(globals()[a[:-1]]) if isinstance(a, str) else a for a in argtypes]


def load(build_dir: Path) -> ctypes.CDLL:
    """Loads librw_core.so from the native CMake build directory and declares the signatures."""
    path = Path(build_dir) / "librw_core.so"
    if not path.is_file():
        raise FileNotFoundError(f"core shared library: expected {path} to exist after the native build")
    lib = ctypes.CDLL(str(path))
    _declare(lib)
    return lib


def f32(x: float) -> float:
    """x rounded to single precision (what the C core sees)."""
    return ctypes.c_float(x).value


Q16_ONE = 65536


def to_q16(x: float, *, name: str = "value") -> int:
    """x in Q16.16 (x 65536, rounded, saturated at +-(2^31 - 1)) as the fixed-point steps take it; a
    non-finite x is refused (ValueError naming the argument)."""
    if not math.isfinite(x):
        raise ValueError(f"{name}: expected a finite number for a Q16.16 input, got {x!r}")
    q = min(abs(x) * Q16_ONE, 2.0**31 - 1)
    return int(math.copysign(math.floor(q + 0.5) if q < 2**31 - 1 else 2**31 - 1, x))


def from_q16(q: int) -> float:
    """A Q16.16 value as a float."""
    return q / Q16_ONE


class _Guarded:
    """Holds one C object followed by a canary block; every call checks the canary."""

    struct_type: type[ctypes.Structure]

    def __init__(self, lib: ctypes.CDLL) -> None:
        self.lib = lib
        holder_type = type("Holder", (ctypes.Structure,),
                           {"_fields_": [("obj", self.struct_type), ("canary", ctypes.c_uint64 * _CANARY_WORDS)]})
        self._holder = holder_type()
        for i in range(_CANARY_WORDS):
            self._holder.canary[i] = CANARY
        self.obj = self._holder.obj
        self.ptr = ctypes.pointer(self.obj)

    def _check(self) -> None:
        if any(word != CANARY for word in self._holder.canary):
            raise AssertionError(f"C code wrote past the ctypes mirror of {self.struct_type.__name__}: "
                                 "the struct layouts in rw_core_ctypes.py and firmware/core differ")

    def _call(self, name: str, *args):
        result = getattr(self.lib, name)(self.ptr, *args)
        self._check()
        return result


class LowpassFilter(_Guarded):
    struct_type = Lowpass

    def __init__(self, lib: ctypes.CDLL, *, tau_s: float) -> None:
        super().__init__(lib)
        self._call("rw_lowpass_init", ctypes.byref(LowpassConfig(tau_s)))

    def step(self, x: float, dt_s: float) -> float:
        """One sample; x in Q16.16 (to_q16: a non-finite one raises ValueError), the output as a float."""
        return from_q16(self._call("rw_lowpass_step", to_q16(x, name="x"), dt_s))

    def reset(self) -> None:
        self._call("rw_lowpass_reset")

    def reset_to(self, y: float) -> None:
        self._call("rw_lowpass_reset_to", to_q16(y, name="y"))

    def prepare(self, dt_s: float = 0.0) -> None:
        """Converts the (changed) config for steps of dt_s (0: for none in particular)."""
        self._call("rw_lowpass_prepare", dt_s)

    @property
    def output(self) -> float:
        return from_q16(self._call("rw_lowpass_output_q16"))


class RampLimiter(_Guarded):
    struct_type = Ramp

    def __init__(self, lib: ctypes.CDLL, *, rate_up_per_s: float, rate_down_per_s: float) -> None:
        super().__init__(lib)
        self._call("rw_ramp_init", ctypes.byref(RampConfig(rate_up_per_s, rate_down_per_s)))

    def step(self, target: float, dt_s: float) -> float:
        """One step; target in Q16.16 (to_q16: a non-finite one raises ValueError), the output as a float."""
        return from_q16(self._call("rw_ramp_step", to_q16(target, name="target"), dt_s))

    def reset(self) -> None:
        self._call("rw_ramp_reset")

    def reset_to(self, y: float) -> None:
        self._call("rw_ramp_reset_to", y)

    def at_target(self, target: float) -> bool:
        return self._call("rw_ramp_at_target", target)

    def prepare(self, dt_s: float = 0.0) -> None:
        """Converts the (changed) rates for steps of dt_s (0: for none in particular)."""
        self._call("rw_ramp_prepare", dt_s)

    @property
    def output(self) -> float:
        return self._call("rw_ramp_output")


class PiController(_Guarded):
    struct_type = Pi

    def __init__(self, lib: ctypes.CDLL, *, kp: float, ki_per_s: float, out_min: float, out_max: float) -> None:
        super().__init__(lib)
        self._call("rw_pi_controller_init", ctypes.byref(PiConfig(kp, ki_per_s, out_min, out_max)))

    def step(self, setpoint: float, measurement: float, feed_forward: float, dt_s: float) -> float:
        """One step; the inputs in Q16.16 (to_q16: non-finite ones raise ValueError), the output as a float."""
        return from_q16(self._call("rw_pi_controller_step", to_q16(setpoint, name="setpoint"),
                                   to_q16(measurement, name="measurement"),
                                   to_q16(feed_forward, name="feed_forward"), dt_s))

    def reset(self) -> None:
        self._call("rw_pi_controller_reset")

    def prepare(self, dt_s: float = 0.0) -> None:
        """Converts the (changed) config for steps of dt_s (0: for none in particular)."""
        self._call("rw_pi_controller_prepare", dt_s)

    @property
    def output(self) -> float:
        return from_q16(self._call("rw_pi_controller_output_q16"))

    @property
    def integral(self) -> float:
        """The integral term, output units (Q32 in the C state)."""
        self._check()
        return self.obj.state.integral_q32 / 2**32

    @property
    def saturation(self) -> int:
        self._check()
        return self.obj.state.saturation


class MtSpeedEstimator(_Guarded):
    struct_type = Mt

    def __init__(self, lib: ctypes.CDLL, *, counts_per_rev: int, timeout_us: int, wheel_radius_m: float,
                 filter_tau_s: float) -> None:
        super().__init__(lib)
        cfg = MtConfig(counts_per_rev, timeout_us, wheel_radius_m, filter_tau_s)
        self._call("rw_mt_speed_estimator_init", ctypes.byref(cfg))

    def step(self, count: int, edge_us: int, now_us: int, dt_s: float) -> float:
        """Returns the (filtered) rope speed, m/s. Integers are reduced modulo 2^32 as in C."""
        mask = 0xFFFFFFFF
        return self._call("rw_mt_speed_estimator_step", count & mask, edge_us & mask, now_us & mask, dt_s)

    def reset(self) -> None:
        self._call("rw_mt_speed_estimator_reset")

    def prepare(self, dt_s: float = 0.0) -> None:
        """Converts the (changed) config for steps of dt_s (0: for none in particular)."""
        self._call("rw_mt_speed_estimator_prepare", dt_s)

    @property
    def rev_per_s(self) -> float:
        return self._call("rw_mt_speed_estimator_rev_per_s")

    @property
    def rpm(self) -> float:
        return self._call("rw_mt_speed_estimator_rpm")

    @property
    def rope_mps(self) -> float:
        return self._call("rw_mt_speed_estimator_rope_mps")

    @property
    def raw_rev_per_s(self) -> float:
        return self._call("rw_mt_speed_estimator_raw_rev_per_s")

    @property
    def stale(self) -> bool:
        return self._call("rw_mt_speed_estimator_is_stale")


class ThrottleMap(_Guarded):
    struct_type = Throttle

    def __init__(self, lib: ctypes.CDLL, *, kv_rpm_per_v: float, wheel_radius_m: float, pulse_min_us: int,
                 pulse_max_us: int) -> None:
        super().__init__(lib)
        cfg = ThrottleConfig(kv_rpm_per_v, wheel_radius_m, pulse_min_us, pulse_max_us)
        self._call("rw_throttle_map_init", ctypes.byref(cfg))

    def feed_forward(self, rope_mps: float, battery_v: float) -> float:
        """Feed-forward throttle; rope_mps in Q16.16 (to_q16: a non-finite one raises ValueError)."""
        return from_q16(self._call("rw_throttle_map_feed_forward", to_q16(rope_mps, name="rope_mps"), battery_v))

    def no_load_rope_mps(self, throttle: float, battery_v: float) -> float:
        return self._call("rw_throttle_map_no_load_rope_mps", throttle, battery_v)

    def pulse_us(self, throttle: float) -> int:
        """ESC pulse for a throttle fraction, in Q16.16 (to_q16: a non-finite one raises ValueError)."""
        return self.pulse_us_q16(to_q16(throttle, name="throttle"))

    def pulse_us_q16(self, throttle_q16: int) -> int:
        return self._call("rw_throttle_map_pulse_us", throttle_q16)

    def pulse_third_us_q16(self, throttle_q16: int) -> int:
        """The pulse in thirds of a microsecond (the PWM timer's counts)."""
        return self._call("rw_throttle_map_pulse_third_us", throttle_q16)

    def throttle_from_pulse(self, pulse_us: int) -> float:
        return self._call("rw_throttle_map_throttle_from_pulse", pulse_us)

    def prepare(self) -> None:
        """Converts the (changed) config."""
        self._call("rw_throttle_map_prepare")


class TovGuard(_Guarded):
    struct_type = Tov

    def __init__(self, lib: ctypes.CDLL, *, tov_mps: float, margin: float, collapse_time_s: float) -> None:
        super().__init__(lib)
        self._call("rw_tov_guard_init", ctypes.byref(TovConfig(tov_mps, margin, collapse_time_s)))

    def step(self, measured_mps: float, dt_s: float) -> bool:
        return self._call("rw_tov_guard_step", measured_mps, dt_s)

    def reset(self) -> None:
        self._call("rw_tov_guard_reset")

    def prepare(self) -> None:
        """Converts the (changed) config."""
        self._call("rw_tov_guard_prepare")

    def setpoint_allowed(self, setpoint_mps: float) -> bool:
        return self._call("rw_tov_guard_setpoint_allowed", setpoint_mps)

    @property
    def min_airborne_mps(self) -> float:
        return self._call("rw_tov_guard_min_airborne_mps")

    @property
    def collapsed(self) -> bool:
        return self._call("rw_tov_guard_is_collapsed")
