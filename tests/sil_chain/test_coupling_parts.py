"""The coupling's parts on their own: the spindle plant loaded from outside (SpindleInputs.guide_load_n), the
robot's base trajectory, the bridge, and the session's plant arguments (the plant contract)."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.plant import pitch_quat_wxyz
from robowrangler_sim.plants.spindle import SpindleInputs, SpindleOutputs, SpindleParams, SpindlePlant
from robowrangler_sim.scenarios import ScenarioError, run_scenario
from robowrangler_sim.scenarios.base_trajectory import BaseTrajectory


def _retract(guide_load_n: float) -> SpindleOutputs:
    spindle = SpindlePlant(SpindleParams(load_noise_permille=0.0), seed=0)
    inputs = SpindleInputs(moving_speed_raw=1023, guide_load_n=guide_load_n)  # full speed ccw = retract
    for _ in range(500):
        out = spindle.update(inputs, 0.001)
    return out


def test_a_chain_load_on_the_guide_slows_the_retract_and_shows_in_the_load_register() -> None:
    free, loaded = _retract(0.0), _retract(100.0)
    assert loaded.speed_rpm < free.speed_rpm - 5.0
    # torque = friction + F x lead / (2 pi) / efficiency, in per mille of the 1.5 N m stall torque
    expected = (0.05 + 100.0 * 0.008 / (2 * np.pi) / 0.35) / 1.5 * 1000
    assert (loaded.load_raw & 0x3FF) == pytest.approx(expected, abs=2)
    assert loaded.rope_tension_n == pytest.approx(50.0)  # two strands share the guide load


def test_the_load_cannot_be_negative_or_nan_and_inputs_are_checked() -> None:
    spindle = SpindlePlant()
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="guide_load_n: expected a finite force >= 0 N"):
            spindle.update(SpindleInputs(moving_speed_raw=0, guide_load_n=bad), 0.001)
    with pytest.raises(ValueError, match="moving_speed_raw: expected a register value 0..2047, got 4096"):
        spindle.update(SpindleInputs(moving_speed_raw=4096), 0.001)
    with pytest.raises(TypeError, match="inputs: expected SpindleInputs, got int"):
        spindle.update(1023, 0.001)


def test_an_outside_load_replaces_the_stand_in_object_and_none_gives_it_back() -> None:
    spindle = SpindlePlant(SpindleParams(load_noise_permille=0.0), seed=0)
    spindle.object_circumference_m = 10.0  # a loop of 2 m is far inside it: the stand-in object pulls hard
    assert spindle.update(SpindleInputs(moving_speed_raw=0), 0.001).rope_tension_n > 1000.0
    assert spindle.update(SpindleInputs(moving_speed_raw=0, guide_load_n=4.0), 0.001).rope_tension_n == 2.0


def test_reset_goes_back_to_power_up_with_the_same_noise() -> None:
    spindle = SpindlePlant(seed=3)
    start = spindle.outputs()
    for _ in range(300):
        spindle.update(SpindleInputs(moving_speed_raw=1023), 0.001)
    assert spindle.outputs().guide_position_mm > start.guide_position_mm + 1.0
    spindle.reset()
    assert spindle.outputs() == start


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

    class ContractOnly(ChainPlant):
        """Counts the contract's updates; a step outside update() fails the test."""

        updates: list = []
        in_update = False

        def update(self, inputs, dt_s):
            self.in_update = True
            try:
                out = super().update(inputs, dt_s)
            finally:
                self.in_update = False
            self.updates.append((inputs, dt_s, out))
            return out

        def step(self, inputs=None):
            assert self.in_update, "the bridge stepped the chain outside the plant contract"
            super().step(inputs)

    params = ChainParams(n_links=10)
    quat = pitch_quat_wxyz(0.0, roll_rad=np.pi / 2)  # loop plane horizontal, exit 3 cm above the floor
    sil = SilSession(speedup=None, trace_every=0, seed=5)
    chain = ContractOnly(table=default_or_synthetic_table(), params=params, floor_height_m=0.0, airborne=False,
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
        # composed through the contract: one update(inputs, h) per chain step, the loads from its outputs
        assert len(chain.updates) == bridge.chain_steps
        assert {dt for _, dt, _ in chain.updates} == {params.timestep_s}
        last = chain.updates[-1][2]
        assert bridge.outputs is last and last.time_s == chain.time_s
        assert sil.loads.external_rope_load_n == 0.3 * (sum(last.chain_object_force_n.values())
                                                        + last.chain_floor_force_n)
        # the loop follows the spindle's guide (40 mm at power-up: 80 mm of rope inside)
        assert chain.loop_length_m() == pytest.approx(params.loop_length_m(sil.spindle_out.guide_position_mm),
                                                      abs=1e-9)
        # lying on the floor: the drive feels Coulomb friction of the rope's weight, mu x m g (a few mN)
        weight_n = params.rope_linear_density_kg_per_m * chain.loop_length_m() * 9.81
        assert sil.loads.external_rope_load_n == pytest.approx(0.3 * weight_n, rel=0.35)
        assert sil.drive_out.external_rope_load_n == pytest.approx(sil.loads.external_rope_load_n, rel=0.1)
        assert sil.loads.guide_load_n == 0.0  # nothing to pull on
        assert sil.spindle.guide_load_n == 0.0  # the spindle got it as its input


class _Recording(SpindlePlant):
    """A spindle plant meeting the contract that counts what it was given (a factory too: it is a class)."""

    def __init__(self, params=None, *, seed=0):
        self.inputs_seen: list[SpindleInputs] = []
        super().__init__(params, seed=seed)

    def update(self, inputs, dt_s):
        self.inputs_seen.append(inputs)
        return super().update(inputs, dt_s)


def test_session_plant_arguments_take_a_plant_or_a_factory_and_reject_anything_else() -> None:
    from robowrangler_sim.plants.drive import DriveParams, DrivePlant
    from robowrangler_sim.sil import SilSession

    params = SpindleParams(load_noise_permille=0.0)
    default = SilSession(speedup=None, seed=2, spindle_params=params)
    assert type(default.spindle) is SpindlePlant and default.spindle.params == params
    assert type(default.drive) is DrivePlant and default.plant is default.drive
    made = SilSession(speedup=None, seed=2, spindle_params=params, spindle=_Recording)
    assert isinstance(made.spindle, _Recording) and made.spindle.params == params
    # the factory gets the session's seed: the same register noise as a plant built with that seed
    twin = SpindlePlant(SpindleParams(), seed=9)
    seeded = SilSession(speedup=None, seed=9, spindle=_Recording)
    assert seeded.spindle.outputs() == twin.outputs()
    given = SpindlePlant(params, seed=1)
    assert SilSession(speedup=None, spindle=given).spindle is given
    drive = DrivePlant(DriveParams(motor_resistance_ohm=0.09), seed=4)
    assert SilSession(speedup=None, drive=drive).drive is drive
    with pytest.raises(TypeError, match="spindle: expected None, a plant meeting the plant contract"):
        SilSession(speedup=None, spindle=3)
    with pytest.raises(TypeError, match="drive: expected the factory to return a plant meeting the plant contract"):
        SilSession(speedup=None, drive=lambda p, *, seed: "motor")
    with pytest.raises(ValueError, match="spindle: expected a plant built with spindle_params"):
        SilSession(speedup=None, spindle_params=params, spindle=SpindlePlant(SpindleParams(), seed=0))


def test_the_session_steps_its_plants_only_through_the_contract(native_build_dir) -> None:
    from robowrangler_sim.sil import SilSession
    from robowrangler_sim.sil.scripted_host import ScriptedHost

    sil = SilSession(speedup=None, trace_every=0, seed=1, spindle=_Recording)
    with sil:
        sil.loads.guide_load_n = 3.0
        host = ScriptedHost(sil)
        host.run_for(0.2)
        host.close()
    seen = sil.spindle.inputs_seen
    assert len(seen) == sil.ticks  # one update per tick
    assert {i.guide_load_n for i in seen[-10:]} == {3.0}
    assert sil.spindle_out == sil.spindle.outputs()
