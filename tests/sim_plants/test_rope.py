"""One rope for every model: the drive plant, the rope chain and the first-principles string shooter read the
same RopeParams, and the takeoff speed they use is the calibration of C_f to the measured 2.6 m/s."""

from __future__ import annotations

import math

import pytest

from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.plants.drive_params import DriveParams
from robowrangler_sim.rope import (GRAVITY_MPS2, STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams, RopeParamsError,
                                   skin_friction_coeff_for_takeoff)
from robowrangler_sim.string_shooter import ShooterParams, takeoff_speed_estimate_mps


def test_default_rope_takes_off_at_the_measured_speed_in_every_model():
    rope = RopeParams()
    assert rope.takeoff_speed_mps() == pytest.approx(2.6, rel=1e-12)
    # drag per metre equals weight per metre there: the definition of takeoff
    assert rope.axial_drag_n_per_m(2.6) == pytest.approx(rope.linear_density_kg_per_m * GRAVITY_MPS2, rel=1e-12)
    assert DriveParams().takeoff_speed_mps == pytest.approx(2.6, rel=1e-12)
    assert ChainParams().takeoff_speed_mps == pytest.approx(2.6, rel=1e-12)
    shooter = ShooterParams()
    assert takeoff_speed_estimate_mps(shooter.rope, shooter.air) == pytest.approx(2.6, rel=1e-12)


def test_one_rope_change_reaches_every_model():
    heavy = RopeParams(linear_density_kg_per_m=0.442e-3)  # twice the mass per metre: ToV up by sqrt(2)
    drive, chain, shooter = DriveParams(rope=heavy), ChainParams(rope=heavy), ShooterParams(rope=heavy)
    expected = 2.6 * math.sqrt(2.0)
    assert drive.takeoff_speed_mps == pytest.approx(expected, rel=1e-9)
    assert chain.takeoff_speed_mps == pytest.approx(expected, rel=1e-9)
    assert takeoff_speed_estimate_mps(shooter.rope, shooter.air) == pytest.approx(expected, rel=1e-9)
    assert drive.rope_mass_kg == pytest.approx(2 * DriveParams().rope_mass_kg)
    assert chain.link_mass_kg == pytest.approx(2 * ChainParams().link_mass_kg)
    thick = RopeParams(diameter_m=4e-3)
    assert ChainParams(rope=thick).rope_radius_m == pytest.approx(2e-3)
    assert DriveParams(rope=thick).rope_drag_coeff_n_s2_per_m2 == pytest.approx(
        2 * DriveParams().rope_drag_coeff_n_s2_per_m2)


def test_calibration_inverts_takeoff():
    cf = skin_friction_coeff_for_takeoff(3.0, air_density_kg_per_m3=STANDARD_AIR_DENSITY_KG_PER_M3)
    assert RopeParams(skin_friction_coeff=cf).takeoff_speed_mps() == pytest.approx(3.0, rel=1e-12)
    assert RopeParams(skin_friction_coeff=0.0).takeoff_speed_mps() == math.inf  # no axial drag: never lifts


@pytest.mark.parametrize("changes, name", [
    ({"diameter_m": -1.0}, "diameter_m"),
    ({"skin_friction_coeff": float("nan")}, "skin_friction_coeff"),
    ({"linear_density_kg_per_m": 0.0}, "linear_density_kg_per_m"),
    ({"compression_stiffness_ratio": 1.5}, "compression_stiffness_ratio"),
    ({"normal_drag_coeff": True}, "normal_drag_coeff"),
])
def test_bad_rope_is_refused_naming_the_field(changes, name):
    with pytest.raises(RopeParamsError, match=name):
        RopeParams(**changes)
    with pytest.raises(RopeParamsError, match="takeoff_speed_mps"):
        skin_friction_coeff_for_takeoff(0.0)


def test_models_refuse_a_rope_that_is_not_a_rope():
    from robowrangler_sim.chain.errors import ChainModelError
    from robowrangler_sim.plants.drive_params import DriveParamsError

    with pytest.raises(DriveParamsError, match="rope"):
        DriveParams(rope=0.221e-3)
    with pytest.raises(ChainModelError, match="rope"):
        ChainParams(rope=0.221e-3)
