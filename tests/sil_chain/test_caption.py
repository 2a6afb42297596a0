"""Captions of a scenario's rendered frames (scenarios/caption.py): the text each frame carries and the band it is
drawn in, as the README's wrangle figure has them."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.scenarios.caption import captioned, frame_caption, verdict_caption
from robowrangler_sim.scenarios.runner import ScenarioOutcome


def test_a_frame_caption_names_time_state_rope_speed_guide_and_phase() -> None:
    text = frame_caption(time_s=12.345, state="RETRACT", rope_speed_mps=0.004, guide_mm=142.26, phase="grasp")
    assert text == "t 12.35 s | RETRACT | rope 0.00 m/s | guide 142.3 mm | grasp"
    assert frame_caption(time_s=0.05, state=None, rope_speed_mps=0.0, guide_mm=3.0, phase="boot").startswith(
        "t 0.05 s | - |")  # before the first telemetry
    with pytest.raises(ValueError, match="guide_mm"):
        frame_caption(time_s=1.0, state="ARMED", rope_speed_mps=0.0, guide_mm=float("nan"), phase="home")


def test_the_verdict_caption_says_the_figures_or_what_ended_the_run() -> None:
    o = ScenarioOutcome(name="mug", object_name="mug", kind="grasp", seed=0, n_links=20, verdict="secured",
                        follow_ratio=0.934, touching_fraction=0.92)
    assert verdict_caption(o) == "secured: follow 0.93, rope touching 92 %"
    door = ScenarioOutcome(name="door_handle", object_name="door_handle", kind="door", seed=0, n_links=20,
                           verdict="held", touching_fraction=1.0, door_opening_deg=14.26)
    assert verdict_caption(door) == "held: rope touching 100 %, door opened 14.3 deg"
    o.verdict = "interrupted"
    assert verdict_caption(o) == "interrupted: no verdict"
    o.verdict = "diverged"
    assert verdict_caption(o) == "no verdict: diverged"


def test_the_caption_is_drawn_in_a_band_over_the_top_and_leaves_the_rest() -> None:
    rng = np.random.default_rng(0)
    frame = rng.integers(0, 200, size=(360, 640, 3), dtype=np.uint8)
    original = frame.copy()
    one = captioned(frame, "t 1.00 s | ARMED | rope 0.00 m/s | guide 3.0 mm | boot")
    assert one.shape == frame.shape and one.dtype == np.uint8
    band = one[:26]
    assert (band == 255).mean() > 0.8 and (band < 100).any()  # white band with dark text in it
    np.testing.assert_array_equal(one[26:], frame[26:])  # the picture below is untouched
    np.testing.assert_array_equal(frame, original)  # and the frame given is not changed
    two = captioned(frame, "first line\nsecond line")
    assert (two[26:52] < 100).any() and (two[:52] == 255).mean() > 0.8
    np.testing.assert_array_equal(two[52:], frame[52:])
    long = captioned(frame, "x" * 400)  # shrinks to the frame's width instead of running off it
    assert (long[:26, -5:] == 255).all()
    with pytest.raises(ValueError, match="frame_rgb"):
        captioned(frame[:, :, 0], "no colour")
