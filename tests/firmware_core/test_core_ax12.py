"""rw_ax12: AX-12A register conversions (position, present speed and load, wheel-mode moving speed).

Registers: position 0-1023 over 300 degrees; speed and load 10-bit magnitude + bit 10 = clockwise.
Sign convention of the core: counter-clockwise (bit 10 clear) = positive = the guide retracts.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rw_core_ctypes import f32
from spindle_ctypes import DIRECTION_BIT, declare

# AX-12A datasheet: 0.111 rpm per present-speed unit; wheel mode 1023 = the 59 rpm no-load speed at 12 V.
DEG_S_PER_SPEED_UNIT = 0.111 * 6.0
NO_LOAD_DEG_S = 59.0 * 6.0


@pytest.fixture(scope="module")
def ax(rw_core):
    return declare(rw_core)


def test_position_edges_and_every_register_value_round_trips(ax):
    assert ax.rw_ax12_position_deg(0) == 0.0
    assert ax.rw_ax12_position_deg(1023) == pytest.approx(300.0, abs=1e-4)
    assert ax.rw_ax12_position_deg(512) == pytest.approx(512 * 300.0 / 1023.0, abs=1e-4)
    previous = -1.0
    for raw in range(1024):
        deg = ax.rw_ax12_position_deg(raw)
        assert round(deg * 1023.0 / 300.0) == raw, f"position register {raw} does not round-trip"
        assert deg > previous, "degrees grow with the register"
        previous = deg


@pytest.mark.parametrize("raw", [1024, 2047, 0xFFFF])
def test_position_beyond_the_register_range_saturates_at_300_deg(ax, raw):
    assert ax.rw_ax12_position_deg(raw) == pytest.approx(300.0, abs=1e-4)


@pytest.mark.parametrize("raw, expected_deg_s", [
    (0, 0.0),
    (1, DEG_S_PER_SPEED_UNIT),
    (1023, 1023 * DEG_S_PER_SPEED_UNIT),       # about 681 deg/s counter-clockwise
    (1024, 0.0),                               # clockwise zero is still zero
    (1025, -DEG_S_PER_SPEED_UNIT),
    (2047, -1023 * DEG_S_PER_SPEED_UNIT),      # bit 10 = clockwise = negative
])
def test_present_speed_edges_and_direction_bit(ax, raw, expected_deg_s):
    assert ax.rw_ax12_speed_deg_s(raw) == pytest.approx(expected_deg_s, rel=1e-5, abs=1e-6)


@pytest.mark.parametrize("raw, expected_permille", [
    (0, 0), (1, 1), (1023, 1023), (1024, 0), (1124, -100), (2047, -1023),
])
def test_present_load_edges_and_direction_bit(ax, raw, expected_permille):
    assert ax.rw_ax12_load_permille(raw) == expected_permille


def test_speed_and_load_are_antisymmetric_in_the_direction_bit(ax):
    for magnitude in range(1024):
        assert ax.rw_ax12_speed_deg_s(magnitude | DIRECTION_BIT) == -ax.rw_ax12_speed_deg_s(magnitude)
        assert ax.rw_ax12_load_permille(magnitude | DIRECTION_BIT) == -ax.rw_ax12_load_permille(magnitude)


def test_moving_speed_full_scale_is_the_no_load_speed_in_both_directions(ax):
    assert ax.rw_ax12_moving_speed_raw(NO_LOAD_DEG_S) == 1023
    assert ax.rw_ax12_moving_speed_raw(-NO_LOAD_DEG_S) == 1023 | DIRECTION_BIT == 2047
    assert ax.rw_ax12_moving_speed_raw(NO_LOAD_DEG_S / 2.0) == 512  # 511.5 rounds up
    assert ax.rw_ax12_moving_speed_raw(0.0) == 0
    assert ax.rw_ax12_moving_speed_raw(-0.0) == 0


def test_moving_speed_every_magnitude_round_trips_with_its_sign(ax):
    for magnitude in range(1024):
        deg_s = magnitude * NO_LOAD_DEG_S / 1023.0
        assert ax.rw_ax12_moving_speed_raw(deg_s) == magnitude
        expected_negative = magnitude | DIRECTION_BIT if magnitude else 0
        assert ax.rw_ax12_moving_speed_raw(-deg_s) == expected_negative, (
            "clockwise = bit 10; a zero magnitude never carries the direction bit")


@pytest.mark.parametrize("deg_s, expected_raw", [
    (NO_LOAD_DEG_S * 1.0001, 1023), (1.0e4, 1023), (3.0e38, 1023),
    (-NO_LOAD_DEG_S * 1.0001, 2047), (-1.0e4, 2047), (-3.0e38, 2047),
])
def test_moving_speed_saturates_at_1023_and_keeps_the_direction(ax, deg_s, expected_raw):
    assert ax.rw_ax12_moving_speed_raw(deg_s) == expected_raw


@pytest.mark.parametrize("deg_s", [math.nan, -math.nan, math.inf, -math.inf])
def test_non_finite_speed_writes_stop(ax, deg_s):
    assert ax.rw_ax12_moving_speed_raw(deg_s) == 0


def test_a_speed_under_half_a_unit_is_a_stop_without_direction_bit(ax):
    half_unit_deg_s = 0.5 * NO_LOAD_DEG_S / 1023.0
    assert ax.rw_ax12_moving_speed_raw(0.9 * half_unit_deg_s) == 0
    assert ax.rw_ax12_moving_speed_raw(-0.9 * half_unit_deg_s) == 0
    assert ax.rw_ax12_moving_speed_raw(1.1 * half_unit_deg_s) == 1
    assert ax.rw_ax12_moving_speed_raw(-1.1 * half_unit_deg_s) == 1 | DIRECTION_BIT


@settings(max_examples=150, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False, width=32))
def test_moving_speed_is_an_11_bit_register_with_the_sign_of_the_speed(ax, deg_s):
    raw = ax.rw_ax12_moving_speed_raw(deg_s)
    magnitude = raw & 0x3FF
    assert raw & ~0x7FF == 0, "only the 10-bit magnitude and the direction bit may be set"
    exact_units = abs(f32(deg_s)) * 1023.0 / NO_LOAD_DEG_S
    if exact_units >= 1023.0:
        assert magnitude == 1023, "saturates at full scale"
    else:
        assert abs(magnitude - exact_units) <= 0.5 + 1e-3, "rounded to the nearest unit"
    assert bool(raw & DIRECTION_BIT) == (deg_s < 0.0 and magnitude > 0), "+ = counter-clockwise (bit 10 clear)"


def test_present_speed_written_back_as_moving_speed_keeps_its_direction(ax):
    # A measured 30 rpm counter-clockwise is about half the no-load speed: commanding it again gives
    # about half scale, same direction; clockwise likewise.
    units = round(30.0 / 0.111)
    assert ax.rw_ax12_moving_speed_raw(ax.rw_ax12_speed_deg_s(units)) == pytest.approx(1023 * 30 / 59, abs=2)
    cw = ax.rw_ax12_moving_speed_raw(ax.rw_ax12_speed_deg_s(units | DIRECTION_BIT))
    assert cw & DIRECTION_BIT and (cw & 0x3FF) == pytest.approx(1023 * 30 / 59, abs=2)
