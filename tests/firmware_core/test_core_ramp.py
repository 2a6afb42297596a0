"""rw_ramp: setpoint rate limiter with separate rise and fall rates (through ctypes).

The step runs in Q16.16 (the binding converts, rw_core_ctypes.to_q16): outputs and targets resolve 1/65536
(LSB), rate x dt is rounded to an LSB (at least one).
"""

from __future__ import annotations

import ctypes
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rw_core_ctypes import RampConfig, RampLimiter, from_q16, to_q16

LSB = 1.0 / 65536


def q(x: float) -> float:
    """x as the Q16.16 ramp holds it."""
    return from_q16(to_q16(x))


def test_rise_moves_exactly_rate_times_dt_per_step_and_lands_on_target(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=10.0, rate_down_per_s=15.0)
    dt_s = 0.001
    out = [ramp.step(5.0, dt_s) for _ in range(600)]
    steps = [b - a for a, b in zip([0.0] + out, out)]
    moving = [s for s in steps if s > 0.0]
    # 5 m/s at 10 (m/s)/s takes 0.5 s = 500 steps (+1 for the rounding of the last partial step).
    assert 500 <= len(moving) <= 501
    for s in moving[:-1]:
        assert s == pytest.approx(10.0 * dt_s, abs=LSB)  # 655.36 LSB: 655 or 656 in the Q16 output
    assert out[-1] == 5.0, "the ramp ends exactly on the target"
    assert max(out) == 5.0, "no overshoot"
    assert ramp.at_target(5.0)


def test_fall_uses_the_down_rate(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=10.0, rate_down_per_s=2.0)
    ramp.reset_to(4.0)
    out = [ramp.step(0.0, 0.01) for _ in range(250)]
    assert out[0] == pytest.approx(4.0 - 0.02, abs=LSB)
    assert out[99] == pytest.approx(2.0, abs=LSB), "after 1 s it has fallen by 2"
    assert out[-1] == 0.0
    assert not ramp.at_target(1.0)


def test_reversal_mid_ramp_switches_rate_at_once(rw_core):
    ramp = RampLimiter(rw_core, rate_up_per_s=10.0, rate_down_per_s=5.0)
    for _ in range(100):
        y = ramp.step(10.0, 0.001)
    assert y == pytest.approx(1.0, abs=1e-5)
    y2 = ramp.step(0.0, 0.001)
    assert y2 == pytest.approx(1.0 - 0.005, abs=LSB)


@pytest.mark.parametrize("rate", [0.0, -1.0, float("inf"), float("nan")])
def test_non_positive_or_non_finite_rate_means_unlimited(rw_core, rate):
    ramp = RampLimiter(rw_core, rate_up_per_s=rate, rate_down_per_s=rate)
    assert ramp.step(7.0, 0.001) == 7.0
    assert ramp.step(-3.0, 0.001) == -3.0


@pytest.mark.parametrize("target, dt_s", [(5.0, 0.0), (5.0, -1.0), (5.0, float("nan"))])
def test_bad_dt_keeps_the_output(rw_core, target, dt_s):
    ramp = RampLimiter(rw_core, rate_up_per_s=1.0, rate_down_per_s=1.0)
    ramp.reset_to(2.0)
    assert ramp.step(target, dt_s) == 2.0


@pytest.mark.parametrize("target", [float("nan"), float("inf")])
def test_non_finite_target_is_refused_by_the_binding(rw_core, target):
    ramp = RampLimiter(rw_core, rate_up_per_s=1.0, rate_down_per_s=1.0)
    ramp.reset_to(2.0)
    with pytest.raises(ValueError, match="target"):
        ramp.step(target, 0.001)
    assert ramp.output == 2.0


def test_fixed_point_resolution_of_the_step(rw_core):
    """rate x dt and the output are kept to 2^-32 (the output reads them rounded to Q16): the speed ramp's
    20 (m/s)/s at 2 ms (2621.44 LSB a step) covers 500 steps to within one LSB, and a rate of a thousandth
    of an LSB a step still moves the output one LSB in a thousand steps."""
    ramp = RampLimiter(rw_core, rate_up_per_s=20.0, rate_down_per_s=10.0)
    out = [ramp.step(30.0, 0.002) for _ in range(500)]
    assert out[-1] == pytest.approx(20.0 * 0.002 * 500, abs=LSB)
    slow = RampLimiter(rw_core, rate_up_per_s=LSB / 1000 / 0.001, rate_down_per_s=1.0)
    outs = [slow.step(1.0, 0.001) for _ in range(1200)]  # 1.2 LSB: reads 1
    assert outs[0] == 0.0 and outs[-1] == LSB


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
            assert delta <= up * dt_s + LSB
            assert -delta <= down * dt_s + LSB
            # never past the target
            assert (y_prev <= q(target) and y <= q(target)) or (y_prev >= q(target) and y >= q(target))
            y_prev = y
    arrive_dt_s = 1.0  # long steps so that even 100 units at 0.1/s arrive in ~1000 steps
    for _ in range(int(abs(targets[-1] - y_prev) / min(up, down) / arrive_dt_s) + 2):
        y = ramp.step(targets[-1], arrive_dt_s)
    assert y == q(targets[-1])
