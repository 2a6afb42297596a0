"""rw_pi_controller: PI with feed-forward, output limits and anti-windup (through ctypes).

The step runs in Q16.16 fixed point (the binding converts, rw_core_ctypes.to_q16): outputs, feed-forward
and limits resolve 1/65536 (LSB below), the integral 2^-32.

The closed-loop tests drive a first-order rope drive plant (throttle -> rope speed, gain
FULL_MPS m/s at full throttle, time constant PLANT_TAU_S) at the firmware tick of 1 ms.
"""

from __future__ import annotations

import ctypes
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rw_core_ctypes import PiConfig, PiController, f32, from_q16, to_q16

LSB = 1.0 / 65536  # Q16.16 resolution of the output, the feed-forward and the limits

DT_S = 0.001
FULL_MPS = 32.0  # rope speed at full throttle
PLANT_TAU_S = 0.08


def plant_step(v_mps: float, throttle: float, *, gain: float = 1.0) -> float:
    """Exact discretisation of tau dv/dt = gain * FULL_MPS * throttle - v over DT_S."""
    a = math.exp(-DT_S / PLANT_TAU_S)
    return a * v_mps + (1.0 - a) * gain * FULL_MPS * throttle


def make_speed_pi(lib) -> PiController:
    return PiController(lib, kp=0.03, ki_per_s=0.4, out_min=0.0, out_max=1.0)


def test_proportional_and_feed_forward_add(rw_core):
    pi = PiController(rw_core, kp=0.5, ki_per_s=0.0, out_min=-10.0, out_max=10.0)
    assert pi.step(3.0, 1.0, 0.25, DT_S) == pytest.approx(0.25 + 0.5 * 2.0)
    assert pi.step(1.0, 3.0, 0.0, DT_S) == pytest.approx(-1.0)


def test_integral_ramps_at_ki_times_error(rw_core):
    pi = PiController(rw_core, kp=0.0, ki_per_s=2.0, out_min=-10.0, out_max=10.0)
    for _ in range(100):
        u = pi.step(1.5, 1.0, 0.0, DT_S)
    assert u == pytest.approx(2.0 * 0.5 * 0.1, rel=1e-4)  # ki * e * t
    assert pi.integral == pytest.approx(u, abs=LSB)  # u is the integral rounded to Q16


def test_closed_loop_removes_feed_forward_error(rw_core):
    """The feed-forward model is 25 % optimistic (plant gain 0.75): the integral closes the gap."""
    pi = make_speed_pi(rw_core)
    setpoint_mps, v = 10.0, 0.0
    ff = setpoint_mps / FULL_MPS
    speeds = []
    for _ in range(3000):
        u = pi.step(setpoint_mps, v, ff, DT_S)
        v = plant_step(v, u, gain=0.75)
        speeds.append(v)
    assert speeds[-1] == pytest.approx(setpoint_mps, rel=2e-3), "no steady-state error"
    assert max(speeds) < setpoint_mps * 1.10, "overshoot under 10 %"
    assert pi.saturation == 0


def test_integral_frozen_while_clamped_and_output_leaves_saturation_at_once(rw_core):
    pi = make_speed_pi(rw_core)
    v = 0.0
    # Unreachable setpoint: 40 m/s needs more than full throttle (32 m/s).
    integrals = []
    for _ in range(2000):
        u = pi.step(40.0, v, 40.0 / FULL_MPS, DT_S)
        v = plant_step(v, u)
        integrals.append(pi.integral)
        assert u <= 1.0
    assert u == 1.0 and pi.saturation == 1
    assert v == pytest.approx(FULL_MPS, rel=1e-3)
    # While clamped the integral never grows; with ff beyond out_max it is bounded by 0.
    assert max(integrals) <= 1e-7
    assert all(b <= a + 1e-7 for a, b in zip(integrals, integrals[1:]))
    # Error reverses: the very first step is out of the upper limit (no wind-down of a huge integral).
    u = pi.step(10.0, v, 10.0 / FULL_MPS, DT_S)
    assert u < 1.0 and pi.saturation != 1
    # ... and the loop settles as fast as it would have without the saturation episode.
    fresh = make_speed_pi(rw_core)
    v_fresh = FULL_MPS
    t_settle = {}
    for name, ctl, v0 in (("after_saturation", pi, plant_step(v, u)), ("fresh", fresh, v_fresh)):
        vv = v0
        for k in range(3000):
            uu = ctl.step(10.0, vv, 10.0 / FULL_MPS, DT_S)
            vv = plant_step(vv, uu)
            if abs(vv - 10.0) > 0.2:
                t_settle[name] = (k + 1) * DT_S
        assert vv == pytest.approx(10.0, rel=2e-3)
    assert t_settle["after_saturation"] <= t_settle["fresh"] + 0.02


def test_integral_stops_when_a_load_saturates_the_output(rw_core):
    """Half the expected plant gain (load, sag): 20 m/s needs 1.25 x full throttle. The feed-forward
    (0.625) is within limits, so only conditional integration keeps the integral from winding."""
    pi = make_speed_pi(rw_core)
    v = 0.0
    ff = 20.0 / FULL_MPS
    saturated_integrals = []
    for _ in range(3000):
        p = f32(0.03) * f32(20.0 - v)
        integral_before = pi.integral
        u = pi.step(20.0, v, ff, DT_S)
        v = plant_step(v, u, gain=0.5)
        if pi.saturation == 1:
            saturated_integrals.append(pi.integral)
            # Grows at most to what holds the output exactly at the limit.
            assert pi.integral <= max(integral_before, 1.0 - ff - p) + 2 * LSB  # ff, p rounded to Q16
    assert v == pytest.approx(16.0, rel=1e-3)
    assert len(saturated_integrals) > 2900
    # Clamped at steady state: the integral no longer moves, and it is far from the 0.375 the clamp allows.
    assert max(saturated_integrals[-1000:]) - min(saturated_integrals[-1000:]) < 1e-5
    assert pi.integral == pytest.approx(1.0 - ff - 0.03 * (20.0 - v), abs=1e-4)
    # Error reverses: out of saturation on the first step.
    assert pi.step(5.0, v, 5.0 / FULL_MPS, DT_S) < 1.0


def test_lower_limit_is_symmetric(rw_core):
    pi = PiController(rw_core, kp=0.01, ki_per_s=1.0, out_min=-1.0, out_max=1.0)
    integrals = []
    for _ in range(3000):
        u = pi.step(0.0, 5.0, 0.0, DT_S)  # wants to go below out_min
        integrals.append(pi.integral)
    assert u == -1.0 and pi.saturation == -1
    # The integral wound down only until the output hit the limit (about 0.2 s), then froze.
    assert integrals[-1] == pytest.approx(-1.0 + 0.05, abs=1e-6), "output lands exactly on the limit"
    assert integrals[-1] == integrals[400]
    assert pi.step(5.0, 0.0, 0.0, DT_S) > -1.0, "leaves the lower limit on the first step"


def test_feed_forward_jump_does_not_leave_a_wound_integral(rw_core):
    pi = PiController(rw_core, kp=0.0, ki_per_s=1.0, out_min=0.0, out_max=1.0)
    for _ in range(500):
        pi.step(1.0, 0.0, 0.2, DT_S)
    assert pi.integral == pytest.approx(0.5, rel=1e-3)
    # ff jumps to 0.9: the integral is cut to out_max - ff = 0.1, not kept at 0.5.
    pi.step(1.0, 1.0, 0.9, DT_S)
    assert pi.integral == pytest.approx(0.1, abs=LSB)  # 1 - ff with ff = 0.9 rounded to Q16


@pytest.mark.parametrize("args", [(1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, -DT_S), (1.0, 0.0, 0.0, float("nan"))])
def test_bad_dt_holds_output_and_integral(rw_core, args):
    pi = PiController(rw_core, kp=0.1, ki_per_s=1.0, out_min=-1.0, out_max=1.0)
    held = pi.step(1.0, 0.5, 0.1, DT_S)
    integral = pi.integral
    assert pi.step(*args) == held
    assert pi.integral == integral


@pytest.mark.parametrize("args", [
    (float("nan"), 0.0, 0.0, DT_S), (1.0, float("nan"), 0.0, DT_S), (1.0, 0.0, float("inf"), DT_S),
])
def test_non_finite_inputs_are_refused_before_the_fixed_point_step(rw_core, args):
    pi = PiController(rw_core, kp=0.1, ki_per_s=1.0, out_min=-1.0, out_max=1.0)
    held = pi.step(1.0, 0.5, 0.1, DT_S)
    integral = pi.integral
    with pytest.raises(ValueError, match="setpoint|measurement|feed_forward"):
        pi.step(*args)
    assert pi.output == held and pi.integral == integral


def test_fixed_point_resolution_a_one_lsb_error_still_integrates(rw_core):
    """The integral is kept to 2^-32: an error of one Q16 LSB (15 um/s of rope) at the speed loop's ki and
    2 ms step moves it by ki dt LSB a step, so it cannot stall short of the setpoint; the output resolves
    one LSB (0.015 us of ESC pulse)."""
    pi = PiController(rw_core, kp=0.0, ki_per_s=0.4, out_min=0.0, out_max=1.0)
    for _ in range(10_000):
        pi.step(LSB, 0.0, 0.5, 0.002)
    # each step adds ki dt LSB to within 2^-32 (52.4 -> 52 units of 2^-32): 1 % here, nothing for larger errors
    assert pi.integral == pytest.approx(10_000 * 0.4 * 0.002 * LSB, rel=0.02)
    assert pi.output == pytest.approx(0.5 + pi.integral, abs=LSB / 2)


def test_invalid_limits_hold_the_output(rw_core):
    pi = PiController(rw_core, kp=0.1, ki_per_s=1.0, out_min=0.0, out_max=1.0)
    held = pi.step(1.0, 0.0, 0.0, DT_S)
    pi.obj.cfg.out_min = 2.0  # out_min > out_max
    pi.prepare(DT_S)
    assert pi.step(5.0, 0.0, 0.0, DT_S) == held
    assert not rw_core.rw_pi_controller_config_is_valid(ctypes.byref(pi.obj.cfg))


def test_reset_puts_the_output_inside_the_limits(rw_core):
    pi = PiController(rw_core, kp=0.1, ki_per_s=1.0, out_min=0.05, out_max=1.0)
    assert pi.output == from_q16(to_q16(0.05))  # the limit rounded to Q16
    pi.step(10.0, 0.0, 0.0, DT_S)
    pi.reset()
    assert pi.output == from_q16(to_q16(0.05)) and pi.integral == 0.0 and pi.saturation == 0


def test_defaults_are_valid_speed_loop_gains(rw_core):
    cfg = PiConfig()
    rw_core.rw_pi_controller_config_defaults(ctypes.byref(cfg))
    assert rw_core.rw_pi_controller_config_is_valid(ctypes.byref(cfg))
    assert (cfg.out_min, cfg.out_max) == (0.0, 1.0)
    assert cfg.kp > 0.0 and cfg.ki_per_s > 0.0
    for bad in (PiConfig(-1.0, 1.0, 0.0, 1.0), PiConfig(1.0, float("nan"), 0.0, 1.0),
                PiConfig(1.0, 1.0, 0.0, float("inf"))):
        assert not rw_core.rw_pi_controller_config_is_valid(ctypes.byref(bad))


def test_default_gains_settle_the_rope_speed_loop(rw_core):
    cfg = PiConfig()
    rw_core.rw_pi_controller_config_defaults(ctypes.byref(cfg))
    pi = PiController(rw_core, kp=cfg.kp, ki_per_s=cfg.ki_per_s, out_min=cfg.out_min, out_max=cfg.out_max)
    v = 0.0
    for _ in range(4000):
        v = plant_step(v, pi.step(5.0, v, 0.9 * 5.0 / FULL_MPS, DT_S), gain=1.0)
    assert v == pytest.approx(5.0, rel=5e-3)


finite = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=80, deadline=None)
@given(steps=st.lists(st.tuples(st.floats(allow_nan=False, allow_infinity=False), finite, finite,
                                st.floats(-0.01, 0.05)), min_size=1, max_size=30))
def test_output_always_finite_and_within_limits(rw_core, steps):
    pi = PiController(rw_core, kp=0.3, ki_per_s=5.0, out_min=-0.5, out_max=0.8)
    for setpoint, measurement, ff, dt_s in steps:
        u = pi.step(setpoint, measurement, ff, dt_s)
        assert math.isfinite(u) and from_q16(to_q16(-0.5)) <= u <= from_q16(to_q16(0.8))
        assert math.isfinite(pi.integral)
