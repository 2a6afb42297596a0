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


def test_bridge_steps_the_chain_with_the_plants_and_loads_the_drive_with_rope_friction(native_build_dir) -> None:
    from robowrangler_sim.chain.default_table import default_or_synthetic_table
    from robowrangler_sim.chain.params import ChainParams
    from robowrangler_sim.chain.plant import ChainPlant, PlantInputs
    from robowrangler_sim.scenarios.chain_bridge import ChainBridge
    from robowrangler_sim.sil import SilSession
    from robowrangler_sim.sil.scripted_host import ScriptedHost

    params = ChainParams(n_links=10)
    quat = pitch_quat_wxyz(0.0, roll_rad=np.pi / 2)  # loop plane horizontal, exit 3 cm above the floor
    sil = SilSession(speedup=None, trace_every=0, seed=5, spindle=ChainLoadedSpindlePlant)
    spindle = sil.spindle
    assert isinstance(spindle, ChainLoadedSpindlePlant)
    chain = ChainPlant(table=default_or_synthetic_table(), params=params, floor_height_m=0.0, airborne=False,
                       initial=PlantInputs(rope_speed_mps=0.0, guide_position_mm=40.0, base_pos_m=(0, 0, 0.03),
                                           base_quat_wxyz=quat))
    bridge = ChainBridge(sil, chain, BaseTrajectory(start_pos_m=(0, 0, 0.03), quat_wxyz=quat)).install()
    with sil:
        host = ScriptedHost(sil)
        host.run_for(1.0)
        host.close()
        # lockstep: one 5 ms chain step per five 1 ms ticks, on the same clock
        assert chain.time_s == pytest.approx(sil.time_s, abs=params.timestep_s)
        assert bridge.chain_steps == round(sil.time_s / params.timestep_s)
        # the loop follows the spindle's guide (40 mm at power-up: 80 mm of rope inside)
        assert chain.loop_length_m() == pytest.approx(params.loop_length_m(spindle.guide_position_mm), abs=1e-9)
        # lying on the floor: the drive feels Coulomb friction of the rope's weight, mu x m g (a few mN)
        weight_n = params.rope_linear_density_kg_per_m * chain.loop_length_m() * 9.81
        assert sil.plant.external_rope_load_n == pytest.approx(0.3 * weight_n, rel=0.35)
        assert spindle.guide_load_n == 0.0  # nothing to pull on


def test_session_spindle_argument_takes_a_plant_or_a_factory_and_rejects_anything_else() -> None:
    from robowrangler_sim.plants.spindle import SpindlePlant
    from robowrangler_sim.sil import SilSession

    params = SpindleParams(load_noise_permille=0.0)
    default = SilSession(speedup=None, seed=2, spindle_params=params)
    assert type(default.spindle) is SpindlePlant and default.spindle.params == params
    made = SilSession(speedup=None, seed=2, spindle_params=params, spindle=ChainLoadedSpindlePlant)
    assert isinstance(made.spindle, ChainLoadedSpindlePlant) and made.spindle.params == params
    # the factory gets the session's seed: the same register noise as a plant built with that seed
    twin = ChainLoadedSpindlePlant(SpindleParams(), seed=9)
    seeded = SilSession(speedup=None, seed=9, spindle=ChainLoadedSpindlePlant)
    assert seeded.spindle.position_raw == twin.position_raw and seeded.spindle.load_raw == twin.load_raw
    given = ChainLoadedSpindlePlant(params, seed=1)
    assert SilSession(speedup=None, spindle=given).spindle is given
    with pytest.raises(TypeError, match="spindle: expected None, a SpindlePlant or a factory"):
        SilSession(speedup=None, spindle=3)
    with pytest.raises(TypeError, match="spindle: expected the factory to return a SpindlePlant, got str"):
        SilSession(speedup=None, spindle=lambda p, *, seed: "servo")
    with pytest.raises(ValueError, match="spindle: expected a SpindlePlant built with spindle_params"):
        SilSession(speedup=None, spindle_params=params, spindle=ChainLoadedSpindlePlant(SpindleParams(), seed=0))
