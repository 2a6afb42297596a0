"""rw_throttle_map: feed-forward throttle and throttle <-> ESC pulse (through ctypes).

The feed-forward and the pulse run in Q16.16 (the binding converts, rw_core_ctypes.to_q16): the throttle
resolves 1/65536 of full throttle (LSB), i.e. 0.5 mm/s of rope at full throttle here.
"""

from __future__ import annotations

import ctypes
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rw_core_ctypes import ThrottleConfig, ThrottleMap

LSB = 1.0 / 65536

KV = 1400.0
RADIUS_M = 0.015
BATTERY_V = 14.8
FULL_MPS = 2.0 * math.pi * RADIUS_M * KV * BATTERY_V / 60.0  # 32.55 m/s


def make(lib, *, pulse_min_us: int = 1000, pulse_max_us: int = 2000) -> ThrottleMap:
    return ThrottleMap(lib, kv_rpm_per_v=KV, wheel_radius_m=RADIUS_M, pulse_min_us=pulse_min_us,
                       pulse_max_us=pulse_max_us)


def test_feed_forward_from_kv_battery_and_radius(rw_core):
    m = make(rw_core)
    # ToV 2.6 m/s = 1655 rpm at a 15 mm wheel; 1400 rpm/V x 14.8 V = 20,720 rpm at full throttle.
    assert m.feed_forward(2.6, BATTERY_V) == pytest.approx(2.6 / FULL_MPS, abs=LSB)
    assert m.feed_forward(2.6, BATTERY_V) == pytest.approx(1655.3 / 20720.0, rel=1e-3)
    # 15,000 rpm = 23.56 m/s
    assert m.feed_forward(23.56, BATTERY_V) == pytest.approx(15000.0 / 20720.0, rel=1e-3)


def test_sagging_battery_raises_the_feed_forward(rw_core):
    m = make(rw_core)
    fresh = m.feed_forward(10.0, 16.8)
    sagged = m.feed_forward(10.0, 13.2)
    assert sagged == pytest.approx(fresh * 16.8 / 13.2, abs=2 * LSB)


def test_feed_forward_clamps_to_full_throttle(rw_core):
    m = make(rw_core)
    assert m.feed_forward(FULL_MPS * 1.5, BATTERY_V) == 1.0


@pytest.mark.parametrize("rope_mps, battery_v", [
    (-3.0, BATTERY_V), (0.0, BATTERY_V), (-1e30, BATTERY_V),
    (5.0, 0.0), (5.0, -12.0), (5.0, float("nan")), (5.0, float("inf")),
])
def test_feed_forward_is_zero_for_bad_input(rw_core, rope_mps, battery_v):
    assert make(rw_core).feed_forward(rope_mps, battery_v) == 0.0


@pytest.mark.parametrize("rope_mps", [float("nan"), float("inf")])
def test_non_finite_rope_speed_is_refused_by_the_binding(rw_core, rope_mps):
    with pytest.raises(ValueError, match="rope_mps"):
        make(rw_core).feed_forward(rope_mps, BATTERY_V)


def test_fixed_point_resolution_of_the_feed_forward(rw_core):
    """Q16.16 in, Q16.16 out, the factor in Q24: every speed from 0.5 to 30 m/s maps within one LSB of the
    exact throttle, and one LSB of rope speed (15 um/s) never moves it by more than one LSB."""
    m = make(rw_core)
    for k in range(60):
        v = 0.5 + 0.5 * k
        exact = min(v / FULL_MPS, 1.0)
        assert m.feed_forward(v, BATTERY_V) == pytest.approx(exact, abs=LSB)
        assert abs(m.feed_forward(v + LSB, BATTERY_V) - m.feed_forward(v, BATTERY_V)) <= LSB


def test_feed_forward_inverse(rw_core):
    m = make(rw_core)
    for v in (1.0, 2.6, 10.0, 23.6):
        assert m.no_load_rope_mps(m.feed_forward(v, BATTERY_V), BATTERY_V) == pytest.approx(v, abs=FULL_MPS * LSB)
    assert m.no_load_rope_mps(2.0, BATTERY_V) == pytest.approx(FULL_MPS, rel=1e-5)
    assert m.no_load_rope_mps(float("nan"), BATTERY_V) == 0.0


def test_pulse_mapping_end_points_and_midpoint(rw_core):
    m = make(rw_core, pulse_min_us=1050, pulse_max_us=2000)
    assert m.pulse_us(0.0) == 1050
    assert m.pulse_us(1.0) == 2000
    assert m.pulse_us(0.5) == 1525
    assert m.pulse_us(0.25) == 1288  # 1287.5 rounds to nearest


@pytest.mark.parametrize("throttle", [-0.1, -1e30, 0.0])
def test_pulse_never_below_the_esc_minimum_for_bad_throttle(rw_core, throttle):
    m = make(rw_core, pulse_min_us=1080)
    assert m.pulse_us(throttle) == 1080
    assert m.pulse_us_q16(-2**31) == 1080


@pytest.mark.parametrize("throttle", [float("-inf"), float("nan"), float("inf")])
def test_non_finite_throttle_is_refused_by_the_binding(rw_core, throttle):
    with pytest.raises(ValueError, match="throttle"):
        make(rw_core, pulse_min_us=1080).pulse_us(throttle)


def test_pulse_saturates_at_the_maximum(rw_core):
    m = make(rw_core, pulse_min_us=1080, pulse_max_us=1900)
    assert m.pulse_us(1.5) == 1900
    assert m.pulse_us(1e30) == 1900
    assert m.pulse_us_q16(2**31 - 1) == 1900


@pytest.mark.parametrize("lo, hi, expect_lo, expect_hi", [
    (900, 2000, 1000, 2000),   # minimum below the hard 1000 us floor
    (1000, 2500, 1000, 2000),  # maximum above 2000 us
    (1500, 1200, 1500, 1500),  # inverted: everything at the ESC minimum
    (2100, 2200, 2000, 2000),
])
def test_invalid_ranges_are_narrowed_into_1000_2000(rw_core, lo, hi, expect_lo, expect_hi):
    m = make(rw_core, pulse_min_us=lo, pulse_max_us=hi)
    assert not rw_core.rw_throttle_map_config_is_valid(ctypes.byref(m.obj.cfg))
    assert m.pulse_us(0.0) == expect_lo
    assert m.pulse_us(1.0) == expect_hi
    for t in (0.1, 0.5, 0.9):
        assert expect_lo <= m.pulse_us(t) <= expect_hi


def test_pulse_round_trip(rw_core):
    m = make(rw_core, pulse_min_us=1040, pulse_max_us=1960)
    for pulse in range(1040, 1961, 7):
        assert m.pulse_us(m.throttle_from_pulse(pulse)) == pulse
    assert m.throttle_from_pulse(900) == 0.0
    assert m.throttle_from_pulse(2200) == 1.0


@settings(max_examples=200, deadline=None)
@given(lo=st.integers(1000, 1999), span=st.integers(1, 1000),
       throttle=st.floats(allow_nan=False, allow_infinity=False, width=32))
def test_pulse_always_within_esc_range_and_monotonic(rw_core, lo, span, throttle):
    hi = min(lo + span, 2000)
    m = make(rw_core, pulse_min_us=lo, pulse_max_us=hi)
    pulse = m.pulse_us(throttle)
    assert lo <= pulse <= hi
    if 0.0 <= throttle <= 0.99:
        assert m.pulse_us(throttle + 0.01) >= pulse


def test_defaults(rw_core):
    cfg = ThrottleConfig()
    rw_core.rw_throttle_map_config_defaults(ctypes.byref(cfg))
    assert rw_core.rw_throttle_map_config_is_valid(ctypes.byref(cfg))
    assert (cfg.pulse_min_us, cfg.pulse_max_us) == (1000, 2000)
    assert cfg.wheel_radius_m == pytest.approx(0.015)
    for bad in (ThrottleConfig(0.0, 0.015, 1000, 2000), ThrottleConfig(KV, float("nan"), 1000, 2000),
                ThrottleConfig(KV, 0.015, 2000, 2000)):
        assert not rw_core.rw_throttle_map_config_is_valid(ctypes.byref(bad))


@settings(max_examples=300, deadline=None)
@given(st.integers(min_value=-2**31, max_value=2**31 - 1), st.sampled_from([(1000, 2000), (1080, 1900), (1000, 1001)]))
def test_the_third_microsecond_pulse_rounds_to_the_whole_microsecond_pulse(rw_core, throttle_q16, span):
    """The pulse at the timer's resolution is the exact throttle law to 1/3 us, and its rounding to the
    microsecond is what the whole-microsecond pulse gives (so a board without the fine output loses nothing else)."""
    lo, hi = span
    m = make(rw_core, pulse_min_us=lo, pulse_max_us=hi)
    third = m.pulse_third_us_q16(throttle_q16)
    assert 3 * lo <= third <= 3 * hi
    assert (third + 1) // 3 == m.pulse_us_q16(throttle_q16)
    t = min(max(throttle_q16, 0), 65536)
    exact_third = 3 * lo + t * 3 * (hi - lo) / 65536
    assert abs(third - exact_third) <= 0.5
