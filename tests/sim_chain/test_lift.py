"""Lift factor: rate-limited transition between airborne (1) and fallen (0) around ToV."""

from __future__ import annotations

import pytest

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.lift import LiftState


def test_lift_ramps_at_the_set_rate_both_ways():
    lift = LiftState(takeoff_speed_mps=2.6, lift_ramp_s=0.2, lift=1.0)
    values = [lift.step(2.5, 0.05) for _ in range(5)]
    assert values == pytest.approx([0.75, 0.5, 0.25, 0.0, 0.0])
    assert lift.step(2.6, 0.1) == pytest.approx(0.5)  # at ToV counts as airborne
    assert lift.step(-3.0, 0.1) == pytest.approx(1.0)  # speed magnitude: reversed rope still lifts


def test_zero_ramp_switches_and_bad_values_raise():
    lift = LiftState(takeoff_speed_mps=2.6, lift_ramp_s=0.0)
    assert lift.step(3.0, 0.001) == 1.0
    with pytest.raises(ChainModelError, match="lift"):
        LiftState(takeoff_speed_mps=2.6, lift_ramp_s=0.2, lift=1.5)
