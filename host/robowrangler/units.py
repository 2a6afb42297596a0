"""The one place where SI values (host side) and integer wire units (protocol) are converted.

Wire units are those of protocol/spec/robowrangler.toml: mm/s, um, ms, mV, us, rpm, per mille;
parameters travel as float32 in their own unit (SI, or mm / % where the parameter name says so). Host code uses SI only (m/s, s, V) and calls these functions at the
boundary; nothing else in the package multiplies by 1000.
"""

from __future__ import annotations

import math
import struct

from robowrangler.errors import InvalidArgument

INT32_MIN = -(2**31)
INT32_MAX = 2**31 - 1
FLOAT32_MAX = 3.4028234663852886e38
UINT32_WRAP = 2**32


def check_real(argument: str, value: object, *, allow_inf: bool = True) -> float:
    """value as a float; InvalidArgument for bool, non-numbers, NaN (and inf unless allow_inf)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidArgument(argument, "a real number", value)
    x = float(value)
    if math.isnan(x):
        raise InvalidArgument(argument, "a real number, not NaN", value)
    if not allow_inf and math.isinf(x):
        raise InvalidArgument(argument, "a finite number", value)
    return x


def _to_int32(argument: str, value: object, *, scale: float, what: str, symbol: str, wire_unit: str,
              si_unit: str) -> int:
    """value x scale rounded to the nearest int32; InvalidArgument for NaN, inf and what int32 cannot hold."""
    x = check_real(argument, value, allow_inf=False)
    scaled = x * scale  # inf for a finite x near the float limit (1e308): refused like any value beyond int32
    if not (math.isfinite(scaled) and INT32_MIN <= round(scaled) <= INT32_MAX):
        raise InvalidArgument(argument, f"a {what} encodable as int32 {wire_unit} "
                              f"(|{symbol}| <= {INT32_MAX / scale:g} {si_unit})", x)
    return round(scaled)


def mps_to_mmps(rope_speed_mps: object, *, argument: str = "rope_speed_mps") -> int:
    """Rope speed m/s -> int32 mm/s on the wire (rounded to the nearest mm/s).

    Only what cannot be encoded is refused here (NaN, inf, beyond int32); range is the device's job.
    """
    return _to_int32(argument, rope_speed_mps, scale=1000.0, what="speed", symbol="v", wire_unit="mm/s",
                     si_unit="m/s")


def mmps_to_mps(mmps: int) -> float:
    """mm/s (wire) -> m/s."""
    return mmps / 1000.0


def m_to_um(guide_position_m: object, *, argument: str = "guide_position_m") -> int:
    """Guide position m -> int32 um on the wire (rounded); only what cannot be encoded is refused."""
    return _to_int32(argument, guide_position_m, scale=1e6, what="position", symbol="x", wire_unit="um",
                     si_unit="m")


def um_to_m(um: int) -> float:
    """um (wire) -> m."""
    return um / 1e6


def mm_to_m(mm: float) -> float:
    """mm (CLI arguments, the device's mm parameters) -> m."""
    return mm / 1000.0


def m_to_mm(m: float) -> float:
    """m -> mm (human output next to the device's mm parameters)."""
    return m * 1000.0


def permille_to_pct(permille: int) -> float:
    """Per mille (wire) -> percent (the unit of the device's load parameters)."""
    return permille / 10.0


def ms_to_s(ms: int) -> float:
    """ms (wire) -> s."""
    return ms / 1000.0


def mv_to_v(mv: int) -> float:
    """mV (wire) -> V."""
    return mv / 1000.0


def s_to_ms_u32(time_s: float) -> int:
    """Host seconds -> uint32 milliseconds, wrapping like the device's millis()."""
    return int(time_s * 1000.0) % UINT32_WRAP


def param_to_float32(name: str, value: object) -> float:
    """A parameter value (SI) for PARAM_SET: NaN and non-numbers refused, beyond float32 refused.

    inf is sent (the device NACKs it as OUT_OF_RANGE).
    """
    x = check_real(name, value)
    if math.isfinite(x) and abs(x) > FLOAT32_MAX:
        raise InvalidArgument(name, f"a value encodable as float32 (|x| <= {FLOAT32_MAX:.6g})", value)
    return x


def float32_to_si(value: float) -> float:
    """A float32 from the wire as the shortest decimal that maps back to the same float32.

    2.6 travels as 2.5999999046325684; this returns 2.6, which packs to the identical float32.
    """
    if not math.isfinite(value):
        return value
    packed = struct.pack("<f", value)
    for digits in range(6, 10):
        candidate = float(f"{value:.{digits}g}")
        if struct.pack("<f", candidate) == packed:
            return candidate
    return value
