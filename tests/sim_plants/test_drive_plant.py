"""Drive plant: ESC arming, speed, time constant, encoder, rope drag, battery, load, determinism, bad input."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from robowrangler_sim.plants.encoder import Encoder
from robowrangler_sim.plants import (
    DriveParams,
    DriveParamsError,
    DrivePlant,
    kv_throttle_for_speed,
    rope_drag_force_n,
    speed_time_constant_s,
    steady_battery_v,
    steady_throttle_for_speed,
)

PARAMS = DriveParams()
DT_S = 0.001
MIN_US = PARAMS.esc_min_pulse_us


def run(plant: DrivePlant, pulse_us: float, duration_s: float, dt_s: float = DT_S) -> list[dict]:
    """Step the plant at a fixed pulse; returns the snapshot after every step."""
    out = []
    for _ in range(round(duration_s / dt_s)):
        plant.step(esc_pulse_us=pulse_us, dt_s=dt_s)
        out.append(plant.snapshot())
    return out


def armed_plant(seed: int = 0, params: DriveParams = PARAMS) -> DrivePlant:
    plant = DrivePlant(params, seed=seed)
    run(plant, MIN_US, 0.25)
    assert plant.esc_armed
    return plant


def pulse_for_speed(rope_speed_mps: float, **kwargs) -> float:
    span = PARAMS.esc_max_pulse_us - PARAMS.esc_min_pulse_us
    return MIN_US + span * steady_throttle_for_speed(PARAMS, rope_speed_mps, **kwargs)


# --- speed -----------------------------------------------------------------------------------------------

def test_full_throttle_at_12_v_reaches_about_15000_rpm():
    plant = armed_plant()
    run(plant, 2000.0, 1.0)
    assert plant.motor_rpm == pytest.approx(15000.0, rel=0.10)
    # losses (friction, drag, I R, sag) keep it a little under the no-load Kv x V figure
    assert plant.motor_rpm < PARAMS.motor_kv_rpm_per_v * PARAMS.battery_open_circuit_v
    assert plant.rope_speed_mps == pytest.approx(plant.wheel_speed_rad_s * 0.015)
    assert plant.loop_airborne


@pytest.mark.parametrize("rope_speed_mps", [1.0, 3.0, 10.0, 20.0])
def test_steady_throttle_map_holds_the_speed_in_the_plant(rope_speed_mps):
    plant = armed_plant()
    run(plant, pulse_for_speed(rope_speed_mps), 1.0)
    assert plant.rope_speed_mps == pytest.approx(rope_speed_mps, rel=2e-3)
    assert plant.battery_v == pytest.approx(steady_battery_v(PARAMS, rope_speed_mps), abs=2e-3)


def test_kv_feed_forward_map_is_close_above_tov():
    """The firmware's loss-free Kv map under-commands by the deadband plus losses: documented <= 0.015."""
    for v in np.linspace(PARAMS.takeoff_speed_mps, 22.0, 12):
        exact = steady_throttle_for_speed(PARAMS, v)
        kv = kv_throttle_for_speed(PARAMS, v, battery_v=steady_battery_v(PARAMS, v))
        assert 0.0 < exact - kv < 0.015


def test_out_of_reach_speed_raises_naming_the_argument():
    with pytest.raises(ValueError, match="rope_speed_mps"):
        steady_throttle_for_speed(PARAMS, 30.0)
    with pytest.raises(ValueError, match="rope_speed_mps"):
        steady_throttle_for_speed(PARAMS, -1.0)
    with pytest.raises(ValueError, match="rope_speed_mps"):
        steady_throttle_for_speed(PARAMS, 5.0, external_rope_load_n=45.0)  # beyond the current limit
    with pytest.raises(ValueError, match="external_rope_load_n"):
        steady_throttle_for_speed(PARAMS, 5.0, external_rope_load_n=-1.0)


def test_throttle_step_response_has_the_documented_time_constant():
    """63 % rise of a small throttle step: mechanical tau (~6.4 ms at 5 m/s) + ESC lag 3 ms + latch delay."""
    plant = armed_plant()
    run(plant, pulse_for_speed(5.0), 1.0)
    v0 = plant.rope_speed_mps
    plant.step(esc_pulse_us=pulse_for_speed(5.5), dt_s=DT_S)  # command changes at an arbitrary frame phase
    speeds = [plant.rope_speed_mps] + [s["rope_speed_mps"] for s in run(plant, pulse_for_speed(5.5), 0.3)]
    v1 = speeds[-1]
    assert v1 == pytest.approx(5.5, rel=2e-3)
    t63_s = (next(i for i, v in enumerate(speeds) if v - v0 >= 0.632 * (v1 - v0)) + 1) * DT_S
    tau_mech_s = speed_time_constant_s(PARAMS, 5.25)
    assert 0.005 < tau_mech_s < 0.010
    assert tau_mech_s < t63_s <= tau_mech_s + PARAMS.esc_lag_s + PARAMS.esc_frame_us * 1e-6 + 2 * DT_S
    assert 0.008 <= t63_s <= 0.016  # docs/drive_plant.md: about 10-13 ms depending on the frame phase


def test_full_throttle_spin_up_is_current_limited_and_brakes_actively_on_throttle_drop():
    plant = armed_plant()
    spin = run(plant, 2000.0, 0.005)
    assert max(s["motor_current_a"] for s in spin) == pytest.approx(PARAMS.esc_current_limit_a)
    run(plant, 2000.0, 1.0)
    braking = run(plant, 1300.0, 0.03)
    assert min(s["motor_current_a"] for s in braking) < -10.0  # damped light: current reverses
    assert max(s["battery_v"] for s in braking) > PARAMS.battery_open_circuit_v  # regeneration lifts the pack

    coast_params = replace(PARAMS, esc_damped_light=False)
    coast = armed_plant(params=coast_params)
    run(coast, 2000.0, 1.0)
    coasting = run(coast, 1300.0, 0.03)
    assert min(s["motor_current_a"] for s in coasting) >= 0.0
    assert braking[-1]["rope_speed_mps"] < coasting[-1]["rope_speed_mps"] - 3.0


def test_throttle_reapplied_to_a_coasting_motor_picks_it_up_without_braking():
    plant = armed_plant()
    run(plant, 1500.0, 1.0)
    run(plant, MIN_US, 0.1)  # zero throttle: bridge off, the rope coasts
    assert plant.esc_armed and plant.motor_current_a == 0.0
    v_coast = plant.rope_speed_mps
    states = run(plant, 1500.0, 0.05)
    assert min(s["motor_current_a"] for s in states) >= 0.0
    assert min(s["rope_speed_mps"] for s in states) >= v_coast - 0.05


# --- ESC arming ------------------------------------------------------------------------------------------

def test_no_movement_until_armed():
    plant = DrivePlant()
    states = run(plant, 2000.0, 1.0)  # full throttle from power-up never arms
    assert not any(s["esc_armed"] for s in states)
    assert plant.rope_speed_mps == 0.0 and plant.encoder_counts == 0 and plant.motor_current_a == 0.0

    run(plant, MIN_US, 0.150)  # too short a hold
    assert not plant.esc_armed
    run(plant, 1500.0, 0.2)
    assert plant.rope_speed_mps == 0.0 and plant.shaft_angle_rad == 0.0

    states = run(plant, MIN_US, 0.199)
    assert not any(s["esc_armed"] for s in states)
    run(plant, MIN_US, 0.002)  # the frame 200 ms after the first zero-throttle frame arms it
    assert plant.esc_armed
    assert plant.rope_speed_mps == 0.0  # armed at zero throttle: still at rest
    run(plant, 1500.0, 0.2)
    assert plant.rope_speed_mps > 5.0


@pytest.mark.parametrize("bad_pulse_us", [900.0, 0.0])
def test_pulse_below_minimum_or_no_signal_disarms(bad_pulse_us):
    plant = armed_plant()
    run(plant, 1500.0, 0.5)
    v_running = plant.rope_speed_mps
    run(plant, bad_pulse_us, PARAMS.esc_frame_us * 1e-6)
    assert not plant.esc_armed
    assert plant.motor_current_a == 0.0 and plant.esc_duty == 0.0
    states = run(plant, 1500.0, 0.3)  # a valid throttle again does not restart it: it coasts down
    assert not any(s["esc_armed"] for s in states)
    assert all(s["motor_current_a"] == 0.0 for s in states)
    speeds = [s["rope_speed_mps"] for s in states]
    assert all(b < a for a, b in zip(speeds, speeds[1:]))
    assert plant.rope_speed_mps < 0.7 * v_running  # friction and drag only
    run(plant, MIN_US, 0.21)
    assert plant.esc_armed
    run(plant, 1500.0, 0.5)
    assert plant.rope_speed_mps == pytest.approx(v_running, rel=1e-3)


def test_pulse_just_inside_the_jitter_margin_stays_valid():
    plant = armed_plant()
    run(plant, PARAMS.esc_invalid_below_us + 1.0, 0.1)
    assert plant.esc_armed


# --- encoder ---------------------------------------------------------------------------------------------

def test_encoder_counts_equal_revolutions_times_cpr_and_are_monotonic():
    plant = armed_plant(seed=3)
    states = run(plant, 1700.0, 0.5) + run(plant, 1200.0, 0.3)
    counts = [s["encoder_counts"] for s in states]
    assert all(b >= a for a, b in zip(counts, counts[1:]))
    for s in states[::37]:
        revs = s["shaft_angle_rad"] / (2.0 * math.pi)
        assert abs(s["encoder_counts"] - revs * PARAMS.encoder_counts_per_rev) < 1.0
    assert counts[-1] > 5_000


@pytest.mark.parametrize("rope_speed_mps", [0.5, 3.0, 12.0])
def test_last_edge_times_match_the_speed_at_constant_speed(rope_speed_mps):
    plant = armed_plant(seed=7)
    run(plant, pulse_for_speed(rope_speed_mps), 1.0)
    states = run(plant, pulse_for_speed(rope_speed_mps), 0.2)
    rev_per_s = plant.wheel_speed_rad_s / (2.0 * math.pi)
    period_us = 1e6 / (rev_per_s * PARAMS.encoder_counts_per_rev)
    edges = [(s["encoder_counts"], s["encoder_last_edge_us"]) for s in states]
    for (c_a, t_a), (c_b, t_b) in zip(edges, edges[1:]):
        if c_b == c_a:
            assert t_b == t_a  # no new edge: the capture keeps the old time
            continue
        assert abs((t_b - t_a) - (c_b - c_a) * period_us) <= 1.0
    for s in states:  # the last edge lies inside the step that produced it, or earlier
        assert s["encoder_last_edge_us"] <= s["time_us"]
    if rope_speed_mps == 0.5:  # slower than one edge per step: consecutive captures are one period apart
        distinct = sorted({t for _, t in edges})
        assert all(abs((b - a) - period_us) <= 1.0 for a, b in zip(distinct, distinct[1:]))


def test_encoder_counts_down_when_turning_backwards():
    enc = Encoder(counts_per_rev=64, phase_counts=0.25)
    enc.advance(2.0 * math.pi * (10.5 / 64), 0.0, 1000.0)  # forward 10.5 counts to x = 10.75
    assert enc.counts == 10
    # the 10th edge (x = 10) at (10 - 0.25) / 10.5 of the way
    assert enc.last_edge_us == math.floor(1000.0 * 9.75 / 10.5)
    enc.advance(-2.0 * math.pi, 1000.0, 1000.0)  # one revolution backwards to x = -53.25
    assert enc.counts == 10 - 64
    # last edge crossed going down is x = -53, at (10.75 + 53) / 64 of the way
    assert enc.last_edge_us == math.floor(1000.0 + 1000.0 * 63.75 / 64.0)


# --- rope drag, load, battery ------------------------------------------------------------------------------

def test_rope_drag_at_5_mps_matches_the_formula():
    # 0.5 rho C_f pi d v^2 per metre, 2 m of rope; C_f pi d = 2 lambda g / (rho ToV^2) = 5.33e-4 m (rope.py)
    cf_pi_d_m = 2 * 0.221e-3 * 9.81 / (1.204 * 2.6 ** 2)
    expected_n = 0.5 * 1.204 * cf_pi_d_m * 5.0 ** 2 * 2.0
    assert rope_drag_force_n(PARAMS, 5.0) == pytest.approx(expected_n, rel=1e-12)
    assert rope_drag_force_n(PARAMS, -5.0) == pytest.approx(-expected_n, rel=1e-12)
    # at ToV, drag per metre equals weight per metre (the takeoff condition the numbers come from)
    per_metre = rope_drag_force_n(PARAMS, PARAMS.takeoff_speed_mps) / PARAMS.rope_exposed_length_m
    assert per_metre == pytest.approx(PARAMS.rope_linear_density_kg_per_m * 9.81, rel=1e-9)
    plant = armed_plant()
    run(plant, pulse_for_speed(5.0), 1.0)
    assert plant.rope_drag_n == pytest.approx(rope_drag_force_n(PARAMS, plant.rope_speed_mps), rel=1e-12)
    assert plant.rope_drag_n == pytest.approx(expected_n, rel=5e-3)


def test_rope_drag_is_carried_by_the_motors():
    """At the same full throttle, the drag shows up as extra motor current r F_drag / (n Kt)."""
    no_drag = armed_plant(params=replace(PARAMS, rope=PARAMS.rope.with_(skin_friction_coeff=0.0)))
    with_drag = armed_plant()
    run(no_drag, 2000.0, 1.0)
    run(with_drag, 2000.0, 1.0)
    assert no_drag.rope_speed_mps > with_drag.rope_speed_mps
    extra_a = with_drag.motor_current_a - no_drag.motor_current_a
    drag_share_a = (PARAMS.wheel_radius_m * with_drag.rope_drag_n
                    / (PARAMS.motor_count * PARAMS.torque_constant_nm_per_a))
    assert drag_share_a > 0.3
    assert extra_a == pytest.approx(drag_share_a, rel=0.05)  # minus the little speed it also costs


def test_exposed_rope_length_scales_the_drag_and_reset_restores_it():
    plant = armed_plant()
    run(plant, 2000.0, 1.0)
    full_drag_n = plant.rope_drag_n
    plant.rope_exposed_length_m = 1.0  # a spindle shortened the loop in the air
    run(plant, 2000.0, 1.0)
    assert plant.rope_drag_n == pytest.approx(rope_drag_force_n(PARAMS, plant.rope_speed_mps) / 2.0, rel=1e-12)
    assert plant.rope_drag_n < 0.51 * full_drag_n
    with pytest.raises(ValueError, match="rope_exposed_length_m"):
        plant.rope_exposed_length_m = 2.5
    plant.reset()
    assert plant.rope_exposed_length_m == PARAMS.rope_exposed_length_m


def test_aux_load_on_the_pack_lowers_the_terminal_voltage():
    plant = armed_plant()
    rest_v = plant.battery_v
    plant.battery_aux_current_a = 1.1  # e.g. the spindle servo moving
    run(plant, MIN_US, 0.01)
    assert rest_v - plant.battery_v == pytest.approx(PARAMS.battery_internal_resistance_ohm * 1.0, rel=1e-3)
    with pytest.raises(ValueError, match="battery_aux_current_a"):
        plant.battery_aux_current_a = -1.0


def test_battery_sags_under_load():
    plant = armed_plant()
    rest_v = plant.battery_v
    assert rest_v == pytest.approx(12.0 - 0.030 * 0.1)
    spin = run(plant, 2000.0, 0.05)
    assert min(s["battery_v"] for s in spin) < rest_v - 2.0  # 2 x 40 A through 30 mOhm during spin-up
    run(plant, 2000.0, 1.0)
    steady_sag_v = rest_v - plant.battery_v
    assert plant.battery_open_circuit_v - plant.battery_v == pytest.approx(
        PARAMS.battery_internal_resistance_ohm * plant.battery_current_a, rel=1e-9)
    assert steady_sag_v > 0.05
    plant.external_rope_load_n = 2.0  # more load, more current, more sag
    run(plant, 2000.0, 0.5)
    assert rest_v - plant.battery_v > steady_sag_v + 0.05


def test_battery_adc_is_noisy_quantised_and_centred():
    plant = armed_plant()
    states = run(plant, MIN_US, 1.0)
    err = np.array([s["battery_adc_v"] - s["battery_v"] for s in states])
    assert abs(err.mean()) < 0.002
    assert err.std() == pytest.approx(PARAMS.battery_adc_noise_v, rel=0.15)
    lsb = PARAMS.battery_adc_lsb_v
    codes = np.array([s["battery_adc_v"] for s in states]) / lsb
    assert np.allclose(codes, np.round(codes), atol=1e-6)


def test_external_load_slows_the_rope_to_the_predicted_speed():
    plant = armed_plant()
    pulse = pulse_for_speed(10.0)
    run(plant, pulse, 1.0)
    plant.external_rope_load_n = 3.0
    run(plant, pulse, 1.0)
    assert plant.rope_speed_mps < 9.5
    throttle = (pulse - MIN_US) / (PARAMS.esc_max_pulse_us - MIN_US)
    # the slowed speed is where the load-aware steady map gives back the same throttle
    assert steady_throttle_for_speed(PARAMS, plant.rope_speed_mps, external_rope_load_n=3.0) == pytest.approx(
        throttle, abs=5e-4)
    plant.external_rope_load_n = 0.0
    run(plant, pulse, 1.0)
    assert plant.rope_speed_mps == pytest.approx(10.0, rel=2e-3)


def test_external_load_above_stall_holds_the_rope_at_rest():
    plant = armed_plant()
    plant.external_rope_load_n = 50.0  # 0.75 N m > 2 motors x 40 A x 7.64e-3 N m/A
    run(plant, 2000.0, 0.3)
    assert plant.rope_speed_mps == 0.0
    assert plant.motor_current_a == pytest.approx(PARAMS.esc_current_limit_a)


def test_loop_airborne_has_hysteresis_around_tov():
    plant = armed_plant()
    run(plant, pulse_for_speed(2.62), 1.0)
    assert not plant.loop_airborne  # above ToV but inside the band
    run(plant, pulse_for_speed(2.7), 1.0)
    assert plant.loop_airborne
    run(plant, pulse_for_speed(2.58), 1.0)
    assert plant.loop_airborne
    run(plant, pulse_for_speed(2.5), 1.0)
    assert not plant.loop_airborne


# --- clock, determinism ------------------------------------------------------------------------------------

def scenario(plant: DrivePlant, dt_s: float) -> list[dict]:
    rng = np.random.default_rng(42)
    out = run(plant, MIN_US, 0.25, dt_s)
    for k in range(20):
        plant.external_rope_load_n = float(rng.uniform(0.0, 1.0))
        out += run(plant, float(rng.uniform(1100.0, 1900.0)), 0.05, dt_s)
    return out


def test_same_seed_and_inputs_give_identical_telemetry():
    a = scenario(DrivePlant(seed=5), DT_S)
    b = scenario(DrivePlant(seed=5), DT_S)
    assert a == b
    plant = DrivePlant(seed=5)
    scenario(plant, DT_S)
    plant.reset()
    assert scenario(plant, DT_S) == a
    c = scenario(DrivePlant(seed=6), DT_S)
    assert [s["battery_adc_v"] for s in c] != [s["battery_adc_v"] for s in a]
    assert c[-1]["rope_speed_mps"] == a[-1]["rope_speed_mps"]  # the seed moves noise and encoder phase only


def test_clock_is_exact_and_step_size_barely_matters():
    fine = DrivePlant()
    coarse = DrivePlant()
    s_fine = scenario(fine, 0.001)
    s_coarse = scenario(coarse, 0.005)
    assert fine.time_us == coarse.time_us == 1_250_000
    assert s_fine[-1]["time_us"] == 1_250_000
    assert coarse.rope_speed_mps == pytest.approx(fine.rope_speed_mps, rel=1e-3)
    assert abs(coarse.encoder_counts - fine.encoder_counts) <= 0.001 * fine.encoder_counts


# --- bad input -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("dt_s", [0.0, -0.001, 0.0051, 1.0, math.nan, math.inf, 1.5e-6, "0.001", True])
def test_bad_dt_raises_naming_dt_s(dt_s):
    plant = DrivePlant()
    with pytest.raises(ValueError, match="dt_s"):
        plant.step(esc_pulse_us=MIN_US, dt_s=dt_s)
    assert plant.time_us == 0


@pytest.mark.parametrize("pulse", [math.nan, math.inf, -1.0, 2600.0, None, "1500"])
def test_bad_pulse_raises_naming_esc_pulse_us(pulse):
    plant = DrivePlant()
    with pytest.raises(ValueError, match="esc_pulse_us"):
        plant.step(esc_pulse_us=pulse, dt_s=DT_S)
    assert plant.time_us == 0


@pytest.mark.parametrize("load", [-0.1, math.nan, math.inf])
def test_bad_external_load_raises(load):
    plant = DrivePlant()
    with pytest.raises(ValueError, match="external_rope_load_n"):
        plant.external_rope_load_n = load


@pytest.mark.parametrize("field,value", [("wheel_radius_m", 0.0), ("battery_open_circuit_v", math.nan),
                                         ("encoder_counts_per_rev", 64.5), ("esc_max_duty", 1.2),
                                         ("guide_friction_n", -0.1)])
def test_bad_params_raise_naming_the_field(field, value):
    with pytest.raises(DriveParamsError, match=field):
        replace(PARAMS, **{field: value})


def test_numpy_scalars_are_accepted_and_give_the_same_result():
    a, b = armed_plant(), armed_plant()
    run(a, 1500.0, 0.1)
    for _ in range(100):
        b.step(esc_pulse_us=np.float32(1500.0), dt_s=np.float64(0.001))
    assert a.snapshot() == b.snapshot()


def test_bad_seed_and_params_type():
    with pytest.raises(ValueError, match="seed"):
        DrivePlant(seed=-1)
    with pytest.raises(TypeError, match="params"):
        DrivePlant({"wheel_radius_m": 0.015})
