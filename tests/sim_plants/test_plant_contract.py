"""The plant contract (plants/contract.py): update(inputs, dt_s) -> outputs, outputs(), reset() for the drive,
the spindle and the chain; update integrates exactly as the hand-driven step does."""

from __future__ import annotations

import dataclasses

import pytest

from robowrangler_sim.plants import DriveInputs, DriveOutputs, DriveParams, DrivePlant, Plant
from robowrangler_sim.plants.spindle import SpindleInputs, SpindlePlant


def _armed(plant: DrivePlant) -> None:
    for _ in range(300):  # the ESC's arming hold: a valid zero-throttle signal
        plant.update(DriveInputs(esc_pulse_us=1000.0), 0.001)


def test_every_plant_meets_the_contract():
    from robowrangler_sim.chain.default_table import default_or_synthetic_table
    from robowrangler_sim.chain.params import ChainParams
    from robowrangler_sim.chain.plant import ChainPlant

    chain = ChainPlant(table=default_or_synthetic_table(), params=ChainParams(n_links=10))
    for plant in (DrivePlant(), SpindlePlant(), chain):
        assert isinstance(plant, Plant)


def test_drive_update_is_the_same_integration_as_step():
    by_contract, by_hand = DrivePlant(seed=3), DrivePlant(seed=3)
    _armed(by_contract)
    for _ in range(300):
        by_hand.step(esc_pulse_us=1000.0, dt_s=0.001)
    by_hand.external_rope_load_n = 0.05
    by_hand.rope_exposed_length_m = 1.2
    for _ in range(500):
        out = by_contract.update(DriveInputs(esc_pulse_us=1500.0, external_rope_load_n=0.05,
                                             rope_exposed_length_m=1.2), 0.001)
        by_hand.step(esc_pulse_us=1500.0, dt_s=0.001)
    assert isinstance(out, DriveOutputs) and out.rope_speed_mps > 3.0
    assert out == by_hand.outputs()
    assert out.external_rope_load_n == 0.05 and out.rope_exposed_length_m == 1.2


def test_drive_inputs_left_out_take_the_params_values_not_the_last_ones():
    plant = DrivePlant(DriveParams(battery_aux_current_a=0.3))
    plant.update(DriveInputs(esc_pulse_us=1000.0, battery_aux_current_a=5.0, rope_exposed_length_m=0.5), 0.001)
    out = plant.update(DriveInputs(esc_pulse_us=1000.0), 0.001)
    assert out.battery_aux_current_a == 0.3 and out.rope_exposed_length_m == DriveParams().rope_exposed_length_m


def test_drive_reset_returns_to_power_up():
    plant = DrivePlant(seed=5)
    start = plant.outputs()
    _armed(plant)
    plant.update(DriveInputs(esc_pulse_us=1600.0), 0.005)
    assert plant.outputs() != start
    plant.reset()
    assert plant.outputs() == start


@pytest.mark.parametrize("inputs, dt_s, error, match", [
    (DriveInputs(esc_pulse_us=float("nan")), 0.001, ValueError, "esc_pulse_us"),
    (DriveInputs(esc_pulse_us=1000.0, external_rope_load_n=-1.0), 0.001, ValueError, "external_rope_load_n"),
    (DriveInputs(esc_pulse_us=1000.0, rope_exposed_length_m=9.0), 0.001, ValueError, "rope_exposed_length_m"),
    (DriveInputs(esc_pulse_us=1000.0), 0.0, ValueError, "dt_s"),
    ({"esc_pulse_us": 1000.0}, 0.001, TypeError, "inputs: expected DriveInputs"),
])
def test_drive_bad_inputs_are_refused_naming_the_field(inputs, dt_s, error, match):
    with pytest.raises(error, match=match):
        DrivePlant().update(inputs, dt_s)


def test_outputs_are_frozen_values():
    out = DrivePlant().outputs()
    with pytest.raises(dataclasses.FrozenInstanceError):
        out.rope_speed_mps = 1.0
    sp = SpindlePlant().update(SpindleInputs(moving_speed_raw=0), 0.001)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sp.guide_position_mm = 1.0
