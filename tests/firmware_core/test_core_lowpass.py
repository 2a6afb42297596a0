"""rw_lowpass: first-order low-pass filter of the firmware core (through ctypes).

Q16.16 in and out (the binding converts, rw_core_ctypes.to_q16; LSB = 1/65536), the state kept to 2^-32 and
alpha to 2^-20.
"""

from __future__ import annotations

import ctypes
import math

import pytest

from rw_core_ctypes import LowpassConfig, LowpassFilter

LSB = 1.0 / 65536


def test_step_response_follows_the_first_order_law(rw_core):
    tau_s, dt_s = 0.05, 0.001
    lp = LowpassFilter(rw_core, tau_s=tau_s)
    ys = [lp.step(1.0, dt_s) for _ in range(500)]
    # Backward-Euler law: y[n] = 1 - (tau / (tau + dt))^n exactly (up to the Q16 output and alpha to 2^-20).
    for n in (1, 10, 50, 200, 500):
        assert ys[n - 1] == pytest.approx(1.0 - (tau_s / (tau_s + dt_s)) ** n, abs=2 * LSB)
    # After one time constant the response is within 1 % of the continuous 1 - 1/e.
    assert ys[49] == pytest.approx(1.0 - math.exp(-1.0), rel=0.01)
    assert ys[-1] == pytest.approx(1.0, abs=1e-4)
    assert all(b >= a for a, b in zip(ys, ys[1:])), "the step response must be monotonic"


def test_larger_dt_gives_the_same_time_response(rw_core):
    slow = LowpassFilter(rw_core, tau_s=0.02)
    fast = LowpassFilter(rw_core, tau_s=0.02)
    for _ in range(20):
        y_fast = fast.step(2.0, 0.001)
    for _ in range(2):
        y_slow = slow.step(2.0, 0.01)
    # Both have covered one time constant; backward Euler is a little slower at the larger step.
    assert y_fast == pytest.approx(2.0 * (1.0 - math.exp(-1.0)), rel=0.02)
    assert y_slow == pytest.approx(2.0 * (1.0 - math.exp(-1.0)), rel=0.15)
    assert y_slow < y_fast


def test_zero_tau_passes_through(rw_core):
    lp = LowpassFilter(rw_core, tau_s=0.0)
    assert lp.step(3.5, 0.001) == 3.5
    assert lp.step(-7.25, 0.001) == -7.25


def test_tau_change_takes_effect_on_the_next_step_once_prepared(rw_core):
    lp = LowpassFilter(rw_core, tau_s=1.0)
    lp.prepare(0.001)
    assert lp.step(1.0, 0.001) < 0.01
    lp.obj.cfg.tau_s = 0.0
    lp.prepare(0.001)
    assert lp.step(1.0, 0.001) == 1.0


def test_a_prepared_step_and_an_unprepared_one_agree(rw_core):
    prepared = LowpassFilter(rw_core, tau_s=0.02)
    prepared.prepare(0.002)
    other = LowpassFilter(rw_core, tau_s=0.02)  # prepared for no step: each step computes its coefficient
    for k in range(50):
        x = 1.0 + 0.1 * k
        assert prepared.step(x, 0.002) == other.step(x, 0.002)
    assert prepared.step(3.0, 0.005) == other.step(3.0, 0.005)  # another dt: converted for itself


@pytest.mark.parametrize("x", [float("nan"), float("inf"), float("-inf")])
def test_non_finite_input_is_refused_by_the_binding(rw_core, x):
    lp = LowpassFilter(rw_core, tau_s=0.01)
    held = lp.step(0.5, 0.001)
    with pytest.raises(ValueError, match="x"):
        lp.step(x, 0.001)
    assert lp.output == held


def test_small_inputs_are_not_lost_to_the_resolution(rw_core):
    """The state is kept to 2^-32: a one-LSB input with tau 1 s at 1 ms steps (alpha 0.1 %) is reached, not
    stuck under the rounding of a Q16 state; tau 1 s is followed to 0.1 % (alpha to 2^-20)."""
    lp = LowpassFilter(rw_core, tau_s=1.0)
    ys = [lp.step(LSB, 0.001) for _ in range(10_000)]
    assert ys[-1] == LSB
    big = LowpassFilter(rw_core, tau_s=1.0)
    y = [big.step(100.0, 0.001) for _ in range(1000)][-1]
    assert y == pytest.approx(100.0 * (1.0 - (1.0 / 1.001) ** 1000), rel=1e-3)


@pytest.mark.parametrize("x, dt_s", [(1.0, 0.0), (1.0, -0.001), (1.0, float("nan")), (1.0, float("inf"))])
def test_bad_input_keeps_the_output(rw_core, x, dt_s):
    lp = LowpassFilter(rw_core, tau_s=0.01)
    held = lp.step(0.5, 0.001)
    assert lp.step(x, dt_s) == held
    assert math.isfinite(lp.output)
    assert lp.step(0.5, 0.001) > held, "the filter keeps working after bad input"


def test_huge_inputs_never_produce_inf(rw_core):
    lp = LowpassFilter(rw_core, tau_s=0.01)
    lp.step(3.0e38, 1.0)  # saturates at the Q16 range, +-32768
    y = lp.step(-3.0e38, 1.0)
    assert math.isfinite(y) and -32768.0 <= y <= 32768.0


def test_reset_and_reset_to(rw_core):
    lp = LowpassFilter(rw_core, tau_s=0.01)
    lp.step(4.0, 0.01)
    lp.reset()
    assert lp.output == 0.0
    lp.reset_to(2.5)
    assert lp.output == 2.5
    assert lp.step(2.5, 0.001) == 2.5
    with pytest.raises(ValueError, match="y"):
        lp.reset_to(float("nan"))


@pytest.mark.parametrize("tau_s, valid", [(0.0, True), (0.01, True), (-0.01, False), (float("nan"), False),
                                          (float("inf"), False)])
def test_config_validation(rw_core, tau_s, valid):
    assert rw_core.rw_lowpass_config_is_valid(ctypes.byref(LowpassConfig(tau_s))) is valid
