"""rw_ramp: setpoint rate limiter with separate rise and fall rates (through ctypes)."""

from __future__ import annotations

import ctypes
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rw_core_ctypes import RampConfig, RampLimiter, f32


def test_rise_moves_exactly_rate_times_dt_per_step_and_lands_on_target(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=10.0, rate_down_per_s=15.0)
    dt_s = 0.001
    out = [ramp.step(5.0, dt_s) for _ in range(600)]
    steps = [b - a for a, b in zip([0.0] + out, out)]
    moving = [s for s in steps if s > 0.0]
    # 5 m/s at 10 (m/s)/s takes 0.5 s = 500 steps (+1 for float rounding of the last partial step).
    assert 500 <= len(moving) <= 501
    for s in moving[:-1]:
        assert s == pytest.approx(10.0 * dt_s, rel=1e-3)
    assert out[-1] == f32(5.0), "the ramp ends exactly on the target"
    assert max(out) == f32(5.0), "no overshoot"
    assert ramp.at_target(5.0)


def test_fall_uses_the_down_rate(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=10.0, rate_down_per_s=2.0)
    ramp.reset_to(4.0)
    out = [ramp.step(0.0, 0.01) for _ in range(250)]
    assert out[0] == pytest.approx(4.0 - 0.02, abs=1e-6)
    assert out[99] == pytest.approx(2.0, abs=1e-4), "after 1 s it has fallen by 2"
    assert out[-1] == 0.0
    assert not ramp.at_target(1.0)


def test_reversal_mid_ramp_switches_rate_at_once(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=10.0, rate_down_per_s=5.0)
    for _ in range(100):
        y = ramp.step(10.0, 0.001)
    assert y == pytest.approx(1.0, abs=1e-5)
    y2 = ramp.step(0.0, 0.001)
    assert y2 == pytest.approx(1.0 - 0.005, abs=1e-6)


@pytest.mark.parametrize("rate", [0.0, -1.0, float("inf"), float("nan")])
def test_non_positive_or_non_finite_rate_means_unlimited(rw_core, rate):
    ramp = RampLimiter(rw_core, rate_up_per_s=rate, rate_down_per_s=rate)
    assert ramp.step(7.0, 0.001) == 7.0
    assert ramp.step(-3.0, 0.001) == -3.0


@pytest.mark.parametrize("target, dt_s", [
    (float("nan"), 0.001), (float("inf"), 0.001), (5.0, 0.0), (5.0, -1.0), (5.0, float("nan")),
])
def test_bad_input_keeps_the_output(rw_core, target, dt_s):
    ramp = RampLimiter(rw_core, rate_up_per_s=1.0, rate_down_per_s=1.0)
    ramp.reset_to(2.0)
    assert ramp.step(target, dt_s) == 2.0


def test_reset(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=1.0, rate_down_per_s=1.0)
    ramp.step(1.0, 0.5)
    ramp.reset()
    assert ramp.output == 0.0
    ramp.reset_to(float("inf"))
    assert ramp.output == 0.0


def test_defaults_are_the_speed_ramp_of_rw_defaults(rw_core):
    cfg = RampConfig()
    rw_core.rw_ramp_config_defaults(ctypes.byref(cfg))
    assert cfg.rate_up_per_s > 0.0 and cfg.rate_down_per_s > 0.0
    assert rw_core.rw_ramp_config_is_valid(ctypes.byref(cfg))
    assert not rw_core.rw_ramp_config_is_valid(ctypes.byref(RampConfig(float("nan"), 1.0)))


@settings(max_examples=60, deadline=None)
@given(up=st.floats(0.1, 100.0), down=st.floats(0.1, 100.0),
       targets=st.lists(st.floats(-50.0, 50.0), min_size=1, max_size=20),
       dt_s=st.floats(1e-4, 0.05))
def test_never_faster_than_the_rates_and_always_arrives(rw_core, up, down, targets, dt_s):
    ramp = RampLimiter(rw_core, rate_up_per_s=up, rate_down_per_s=down)
    y_prev = 0.0
    for target in targets:
        for _ in range(5):
            y = ramp.step(target, dt_s)
            assert math.isfinite(y)
            delta = y - y_prev
            assert delta <= f32(up) * f32(dt_s) * (1 + 1e-5) + 1e-5
            assert -delta <= f32(down) * f32(dt_s) * (1 + 1e-5) + 1e-5
            # never past the target
            assert (y_prev <= f32(target) and y <= f32(target)) or (y_prev >= f32(target) and y >= f32(target))
            y_prev = y
    arrive_dt_s = 1.0  # long steps so that even 100 units at 0.1/s arrive in ~1000 steps
    for _ in range(int(abs(targets[-1] - y_prev) / min(up, down) / arrive_dt_s) + 2):
        y = ramp.step(targets[-1], arrive_dt_s)
    assert y == f32(targets[-1])
