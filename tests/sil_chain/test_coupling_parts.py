"""The coupling's parts on their own: the chain-loaded spindle plant and the robot's base trajectory."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.plant import pitch_quat_wxyz
from robowrangler_sim.plants.spindle import SpindleParams
from robowrangler_sim.scenarios import ScenarioError, run_scenario
from robowrangler_sim.scenarios.base_trajectory import BaseTrajectory
from robowrangler_sim.scenarios.loaded_spindle import ChainLoadedSpindlePlant


def _retract(guide_load_n: float) -> ChainLoadedSpindlePlant:
    spindle = ChainLoadedSpindlePlant(SpindleParams(load_noise_permille=0.0), seed=0)
    spindle.guide_load_n = guide_load_n
    spindle.moving_speed_raw = 1023  # full speed, counter-clockwise = retract
    for _ in range(500):
        spindle.step(0.001)
    return spindle


def test_a_chain_load_on_the_guide_slows_the_retract_and_shows_in_the_load_register() -> None:
    free, loaded = _retract(0.0), _retract(100.0)
    assert loaded.speed_rpm < free.speed_rpm - 5.0
    # torque = friction + F x lead / (2 pi) / efficiency, in per mille of the 1.5 N m stall torque
    expected = (0.05 + 100.0 * 0.008 / (2 * np.pi) / 0.35) / 1.5 * 1000
    assert (loaded.load_raw & 0x3FF) == pytest.approx(expected, abs=2)
    assert loaded.rope_tension_n == pytest.approx(50.0)  # two strands share the guide load


def test_the_load_cannot_be_negative_or_nan() -> None:
    spindle = ChainLoadedSpindlePlant()
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="guide_load_n: expected a finite force >= 0 N"):
            spindle.guide_load_n = bad


def test_base_trajectory_moves_rest_to_rest() -> None:
    traj = BaseTrajectory(start_pos_m=(0.0, 0.0, 1.0), quat_wxyz=pitch_quat_wxyz(0.0))
    traj.move_to((1.0, 0.0, 1.0), start_s=2.0, duration_s=2.0)
    np.testing.assert_allclose(traj.pos_at(1.0), [0.0, 0.0, 1.0])
    np.testing.assert_allclose(traj.pos_at(3.0), [0.5, 0.0, 1.0])
    np.testing.assert_allclose(traj.pos_at(9.0), [1.0, 0.0, 1.0])
    # rest to rest: slow at both ends
    assert traj.pos_at(2.1)[0] < 0.01 and traj.pos_at(3.9)[0] > 0.99
    with pytest.raises(ChainModelError, match="start_s: expected >= the end of the last move"):
        traj.move_to((0.0, 0.0, 0.0), start_s=3.0, duration_s=1.0)
    with pytest.raises(ChainModelError, match="quat_wxyz: expected a unit quaternion"):
        BaseTrajectory(start_pos_m=(0, 0, 0), quat_wxyz=(1, 1, 0, 0))


def test_bad_scenario_options_name_the_argument() -> None:
    with pytest.raises(ScenarioError, match="chain_noise_rad: expected 0..0.5 rad, got 2"):
        run_scenario("mug", chain_noise_rad=2)
    with pytest.raises(ScenarioError, match="sample_s: expected 0.001..1.0 s"):
        run_scenario("mug", sample_s=0.0)
