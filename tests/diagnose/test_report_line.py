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


def _drive_result(after_mps: float, noise_mps: float = 0.002):
    from types import SimpleNamespace

    from robowrangler_sim.diagnose.findings import EffectFinding
    e = EffectFinding("external_rope_load", {"external_load_n": {"value": 0.4, "unit": "N", "ci95": [0.3, 0.5]}},
                      ["rope_speed_mps"], [[3.0, 5.0]], {}, {"rope_speed_mps": 0.030}, {"rope_speed_mps": after_mps},
                      {}, "F")
    return SimpleNamespace(verdict="missing_physics", effects=[e], noise_rms={"rope_speed_mps": noise_mps})


def test_a_named_law_that_leaves_much_more_than_the_noise_says_so():
    from robowrangler_sim.diagnose.report import first_line
    left = first_line(_drive_result(after_mps=0.015))
    assert left.startswith("left out: external rope load") and "30 -> 15 mm/s" in left
    assert left.endswith("still 15 mm/s against a noise of 2 mm/s: the closest law of the library, not all of the physics")
    explained = first_line(_drive_result(after_mps=0.0045))
    assert explained.endswith("30 -> 4 mm/s") and "still" not in explained


def test_the_loop_line_says_what_a_named_law_leaves_beyond_the_camera_noise():
    from types import SimpleNamespace

    from robowrangler_sim.diagnose.loop.api import LoopFinding
    from robowrangler_sim.diagnose.loop.report import loop_first_line

    def line(after_mm: float) -> str:
        e = LoopFinding("uniform_wind", {"wind_mps": {"value": 0.5, "unit": "m/s", "ci95": [0.4, 0.6]}}, "w",
                        "upper_branch", [], 5.8, after_mm, {})
        return loop_first_line(SimpleNamespace(verdict="missing_physics", effects=[e], noise_mm=2.0,
                                               candidates=[{"heldout_rms_mm": 5.8}]))
    assert line(5.4).endswith("still 5.4 mm against 2.0 mm camera noise: the closest law of the library, "
                              "not all of the physics")
    assert line(2.1).endswith("5.8 -> 2.1 mm")


def test_none_with_a_miss_far_beyond_the_noise_is_never_called_explained():
    """A refit that misses by 33 mm/s against 2 mm/s of noise, with no span standing out of its residual (the miss is
    spread over the run), used to read "the refitted nominal model explains the recording"."""
    from types import SimpleNamespace

    from robowrangler_sim.diagnose.report import first_line

    def line(held_mps: float, located: list) -> str:
        return first_line(SimpleNamespace(verdict="none", candidates=[{"heldout_rms": {"rope_speed_mps": held_mps}}],
                                          noise_rms={"rope_speed_mps": 0.002}, located=located))
    spread = line(0.033, [])
    assert spread.startswith("none of the library:") and "misses by 33 mm/s against a noise of 2 mm/s" in spread
    assert "(spread over the run)" in spread and "explains" not in spread
    at = line(0.033, [{"span_s": [4.0, 6.5], "significance": 3.0}, {"span_s": [8.0, 9.0], "significance": 7.0}])
    assert "(most at 8.0-9.0 s)" in at
    assert line(0.004, []).startswith("none beyond noise: the refitted nominal model explains the recording")
