"""The report's first line states each parameter and its interval in one unit, so a reader can compare them."""

from __future__ import annotations

from robowrangler_sim.diagnose.report import _fmt_param


def test_a_short_duration_and_its_interval_are_all_in_ms():
    line = _fmt_param("delay_s", {"value": 0.0092, "unit": "s", "ci95": [0.0082, 0.0102]})
    assert line == "delay_s 9.2 ms (8.2-10.2)"


def test_an_interval_reaching_past_1_s_keeps_seconds_for_the_value_too():
    # a 1.43 s time constant with a lower bound of 20 ms used to read "1.43 s (20.0-3.24)"
    line = _fmt_param("polarisation_time_constant_s", {"value": 1.43, "unit": "s", "ci95": [0.02, 3.24]})
    assert line == "polarisation_time_constant_s 1.43 s (0.02-3.24)"
    line = _fmt_param("tau_s", {"value": 0.8504, "unit": "s", "ci95": [0.6272, 1.07]})
    assert line == "tau_s 0.85 s (0.627-1.07)"


def test_a_time_of_the_recording_starting_at_zero_stays_in_seconds():
    line = _fmt_param("load_end_s", {"value": 7.27, "unit": "s", "ci95": [0.0, 12.0]})
    assert line == "load_end_s 7.27 s (0-12)"


def test_other_units_are_kept():
    line = _fmt_param("deadband_us", {"value": 44.8, "unit": "us", "ci95": [43.1, 46.5]})
    assert line == "deadband_us 44.8 us (43.1-46.5)"
