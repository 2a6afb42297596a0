"""SI <-> wire conversions: exact where the wire is exact, refusals name the argument."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robowrangler import units
from robowrangler.errors import InvalidArgument


@pytest.mark.parametrize("mps, mmps", [(2.99, 2990), (0.0005, 0), (0.0015, 2), (-1.0, -1000), (20.0, 20000)])
def test_rope_speed_rounds_to_nearest_mmps(mps: float, mmps: int) -> None:
    assert units.mps_to_mmps(mps) == mmps


@given(st.integers(min_value=-(2**31), max_value=2**31 - 1))
def test_every_int32_mmps_survives_the_round_trip_through_si(mmps: int) -> None:
    assert units.mps_to_mmps(units.mmps_to_mps(mmps)) == mmps


@pytest.mark.parametrize("bad, expected", [(math.nan, "not NaN"), (math.inf, "finite"), (True, "real number"),
                                           ("5", "real number"), (None, "real number"), (3e6, "int32")])
def test_unencodable_speed_is_refused_naming_argument_expected_actual(bad: object, expected: str) -> None:
    with pytest.raises(InvalidArgument) as info:
        units.mps_to_mmps(bad)
    assert info.value.argument == "rope_speed_mps"
    assert expected in str(info.value) and repr(bad) in str(info.value)
    assert isinstance(info.value, ValueError)


@given(st.floats(width=32, allow_nan=False, allow_infinity=False))
def test_float32_shown_as_shortest_decimal_packs_to_the_same_bits(x: float) -> None:
    shown = units.float32_to_si(x)
    assert struct.pack("<f", shown) == struct.pack("<f", x)
    assert len(repr(shown)) <= len(repr(x))


def test_float32_of_default_tov_reads_back_as_typed() -> None:
    wire = struct.unpack("<f", struct.pack("<f", 2.6))[0]
    assert wire != 2.6 and units.float32_to_si(wire) == 2.6


def test_param_value_nan_and_float32_overflow_refused_but_inf_is_sent() -> None:
    with pytest.raises(InvalidArgument, match="tov_mps: expected a real number, not NaN"):
        units.param_to_float32("tov_mps", math.nan)
    with pytest.raises(InvalidArgument, match="float32"):
        units.param_to_float32("tov_mps", 1e39)
    assert units.param_to_float32("tov_mps", math.inf) == math.inf  # the device NACKs it OUT_OF_RANGE


def test_wire_counters_convert_to_si() -> None:
    assert units.ms_to_s(1500) == 1.5 and units.mv_to_v(12600) == 12.6
    assert units.s_to_ms_u32(2**32 / 1000 + 1.0) == 1000  # wraps like millis()
