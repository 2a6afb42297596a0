"""rw_multiturn: multi-turn angle of the AX-12A from its single-turn position register.

A simulated servo drives it: the true output angle advances at a set speed; the position register is
angle x 1023 / 300 with reading noise while the angle is in 0..300 degrees and garbage (uniform random
0..1023) in the 60 degree dead zone; the present-speed register is the true speed quantised to 0.111 rpm.
The estimate must stay within a couple of degrees of the truth over many turns, never take a dead-zone
value, reject a one-off impossible reading (and count it), and re-synchronise after the dead zone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from spindle_ctypes import SPEED_Q10_PER_DEG_S, TICKS_PER_DEG, Multiturn, declare, multiturn_defaults

DT_S = 0.01  # the core's spindle period
TRACK_TOL_DEG = 2.0


class SimServo:
    """Truth and registers of an AX-12A output turning at speed_deg_s (+ = counter-clockwise).

    position_deg(): what the core reads (rw_ax12_position_deg of the register); speed_deg_s_measured():
    the present-speed register converted back (0.111 rpm units)."""

    def __init__(self, lib, *, start_deg: float, speed_deg_s: float, seed: int, noise_units: float = 0.6,
                 dead_zone_reads=None) -> None:
        self.lib = lib
        self.angle_deg = start_deg
        self.speed_deg_s = speed_deg_s
        self.rng = np.random.default_rng(seed)
        self.noise_units = noise_units
        self.dead_zone_reads = dead_zone_reads  # None: uniform garbage; else a fixed register value

    @property
    def in_dead_zone(self) -> bool:
        return self.angle_deg % 360.0 >= 300.0

    def registers_deg(self, angles_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position readings (degrees, as rw_ax12_position_deg converts them) and dead-zone flags for
        the true angles angles_deg, shape (n,)."""
        a = angles_deg % 360.0
        dead = a >= 300.0
        noisy = np.clip(np.round(a * 1023.0 / 300.0 + self.rng.normal(0.0, self.noise_units, a.shape)), 0, 1023)
        if self.dead_zone_reads is None:
            garbage = self.rng.integers(0, 1024, a.shape)
        else:
            garbage = np.full(a.shape, self.dead_zone_reads)
        raw = np.where(dead, garbage, noisy).astype(np.float32)
        return raw * (np.float32(300.0) / np.float32(1023.0)), dead

    def position_deg(self) -> float:
        return float(self.registers_deg(np.array([self.angle_deg]))[0][0])

    def speed_deg_s_measured(self) -> float:
        units = min(1023, round(abs(self.speed_deg_s) / 6.0 / 0.111))
        return self.lib.rw_ax12_speed_deg_s(units | (0x400 if self.speed_deg_s < 0 else 0))

    def advance(self, dt_s: float) -> None:
        self.angle_deg += self.speed_deg_s * dt_s


def track(mt: Multiturn, servo: SimServo, *, seconds: float, speed_scale_in_dead_zone: float = 1.0):
    """Steps servo then estimator for `seconds`; returns arrays (truth_deg, estimate_deg, in_dead_zone,
    garbage_taken) per step, garbage_taken = a dead-zone reading changed the estimate."""
    n = int(round(seconds / DT_S))
    truth = servo.angle_deg + servo.speed_deg_s * DT_S * np.arange(1, n + 1)
    servo.angle_deg = float(truth[-1])
    positions, dead = servo.registers_deg(truth)
    speed = servo.speed_deg_s_measured()
    speeds = np.where(dead, np.float32(speed * speed_scale_in_dead_zone), np.float32(speed)).astype(np.float32)
    est = np.empty(n)
    initialized_before = np.zeros(n, dtype=bool)
    step, ptr = mt.lib.rw_multiturn_step, mt.ptr  # direct calls in the hot loop; the canary is checked below
    state = mt.obj.state
    previous = mt.angle_deg
    initialized = bool(state.initialized)
    # the C units (spindle_ctypes converts the same way): ticks, ticks/ms Q10, milliseconds
    position_ticks = np.round(positions.astype(np.float64) * TICKS_PER_DEG).astype(np.int64)
    speed_q10 = np.round(speeds.astype(np.float64) * SPEED_Q10_PER_DEG_S).astype(np.int64)
    dt_ms = round(DT_S * 1000)
    for k in range(n):
        initialized_before[k] = initialized
        est[k] = step(ptr, True, int(position_ticks[k]), int(speed_q10[k]), dt_ms) / TICKS_PER_DEG
        if not initialized:
            initialized = bool(state.initialized)
    mt._check()
    before = np.concatenate(([previous], est[:-1])).astype(np.float32)
    predicted = before + speeds * np.float32(DT_S)
    garbage_taken = dead & initialized_before & (np.abs(est - predicted) > 1e-3)
    return truth, est, dead, garbage_taken


SPEEDS_RPM = [5.0, 20.0, 59.0]


@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["ccw", "cw"])
@pytest.mark.parametrize("rpm", SPEEDS_RPM)
def test_tracks_twenty_turns_within_two_degrees(rw_core, rpm, direction):
    servo = SimServo(rw_core, start_deg=150.0, speed_deg_s=direction * rpm * 6.0, seed=int(rpm) + 7)
    mt = Multiturn(rw_core)
    turns = 20.5
    truth, est, dead, garbage_taken = track(mt, servo, seconds=turns * 60.0 / rpm)
    assert abs(truth[-1] - truth[0]) >= 20 * 360.0
    err = np.abs(est - truth)
    assert err.max() < TRACK_TOL_DEG, f"worst error {err.max():.2f} deg at step {err.argmax()}"
    assert dead.sum() > 20 * (60.0 / 360.0) * len(dead) / turns * 0.9, "the run crossed the dead zone every turn"
    assert not garbage_taken.any(), f"a dead-zone reading moved the estimate at steps {np.flatnonzero(garbage_taken)[:5]}"
    assert mt.rejected == 0, "a real move at up to the no-load speed is never rejected"


@pytest.mark.parametrize("scale", [1.08, 0.9], ids=["speed+8%", "speed-10%"])
@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["ccw", "cw"])
@pytest.mark.parametrize("rpm", SPEEDS_RPM)
def test_wrong_speed_in_the_dead_zone_is_resynchronised_on_exit(rw_core, rpm, direction, scale):
    servo = SimServo(rw_core, start_deg=150.0, speed_deg_s=direction * rpm * 6.0, seed=3)
    mt = Multiturn(rw_core)
    truth, est, dead, garbage_taken = track(mt, servo, seconds=3.2 * 60.0 / rpm, speed_scale_in_dead_zone=scale)
    err = np.abs(est - truth)
    # inside the dead zone the error grows up to 10 % of 60 degrees; after the exit it is gone again
    assert err[dead].max() < 60.0 * 0.1 + 1.0
    assert err[dead].max() > 3.0, "the wrong speed did show in the dead zone (the test bites)"
    exits = np.flatnonzero(dead[:-1] & ~dead[1:]) + 1
    assert len(exits) >= 3
    steps_per_deg = 1.0 / (rpm * 6.0 * DT_S)
    margin = multiturn_defaults(rw_core).dead_zone_margin_deg
    # through the margin band behind the lagging prediction (6 degrees at -10 %), then one usable reading
    settle = int(math.ceil((margin + 6.0) * steps_per_deg)) + 2
    for e in exits:
        after = err[e + settle:e + settle + int(100 * steps_per_deg)]
        assert after.max() < TRACK_TOL_DEG, f"not re-synchronised {settle} steps after the exit at step {e}"
    assert not garbage_taken.any()
    assert mt.rejected == 0


def test_ten_percent_speed_overestimate_in_the_dead_zone_takes_no_garbage(rw_core):
    failures = []
    for rpm in SPEEDS_RPM:
        for direction in (1.0, -1.0):
            for seed in range(4):
                servo = SimServo(rw_core, start_deg=150.0, speed_deg_s=direction * rpm * 6.0, seed=seed)
                mt = Multiturn(rw_core)
                truth, est, _, garbage_taken = track(mt, servo, seconds=20.5 * 60.0 / rpm,
                                                     speed_scale_in_dead_zone=1.1)
                worst = np.abs(est - truth).max()
                if garbage_taken.any() or worst >= 60.0 * 0.1 + 1.0 or mt.rejected:
                    failures.append(f"{rpm} rpm x{direction:+.0f} seed {seed}: {garbage_taken.sum()} garbage "
                                    f"taken, worst {worst:.1f} deg, {mt.rejected} rejected")
    assert not failures, "; ".join(failures)


AGREE = 4  # RW_MULTITURN_AGREE: readings that must agree before the first reference is taken


def _referenced(mt: Multiturn, position_deg: float) -> None:
    """A still servo read AGREE times: the estimator takes its first reference there."""
    for _ in range(AGREE):
        mt.step(valid=True, position_deg=position_deg, speed_deg_s=0.0, dt_s=DT_S)
    assert mt.initialized


def test_single_impossible_jump_is_rejected_and_counted(rw_core):
    servo = SimServo(rw_core, start_deg=100.0, speed_deg_s=20.0 * 6.0, seed=11)
    mt = Multiturn(rw_core)
    track(mt, servo, seconds=0.5)
    assert mt.rejected == 0
    servo.advance(DT_S)
    before = mt.angle_deg
    speed = servo.speed_deg_s_measured()
    glitch_deg = (servo.angle_deg + 90.0) % 360.0  # a usable reading 90 degrees off
    out = mt.step(valid=True, position_deg=glitch_deg, speed_deg_s=speed, dt_s=DT_S)
    assert mt.rejected == 1
    assert out == pytest.approx(before + speed * DT_S, abs=1e-3), "the estimate dead-reckons over the glitch"
    truth, est, _, _ = track(mt, servo, seconds=1.0)
    assert np.abs(est - truth).max() < TRACK_TOL_DEG
    assert mt.rejected == 1, "only the glitch was counted"


def test_jump_just_under_the_limit_is_accepted_and_just_over_is_rejected(rw_core):
    mt = Multiturn(rw_core)
    limit = multiturn_defaults(rw_core).max_jump_deg
    _referenced(mt, 100.0)
    assert mt.step(valid=True, position_deg=100.0 + limit - 0.5, speed_deg_s=0.0, dt_s=DT_S) == pytest.approx(
        100.0 + limit - 0.5, abs=1e-4)
    assert mt.rejected == 0
    assert mt.step(valid=True, position_deg=100.0 + 2 * limit + 1.0, speed_deg_s=0.0, dt_s=DT_S) == pytest.approx(
        100.0 + limit - 0.5, abs=1e-4)
    assert mt.rejected == 1


def test_start_in_the_dead_zone_dead_reckons_until_the_first_usable_reading(rw_core):
    # the register reads its end values in the dead zone (as many AX-12A units do): never usable
    servo = SimServo(rw_core, start_deg=320.0, speed_deg_s=20.0 * 6.0, seed=5, dead_zone_reads=1023)
    mt = Multiturn(rw_core)
    angle = mt.step(valid=True, position_deg=servo.position_deg(), speed_deg_s=servo.speed_deg_s_measured(),
                    dt_s=DT_S)
    assert not mt.initialized and mt.dead_reckoning
    assert angle == pytest.approx(servo.speed_deg_s_measured() * DT_S, abs=1e-4), "dead-reckons from 0"
    truth, est, dead, _ = track(mt, servo, seconds=10 * 60.0 / 20.0)
    assert mt.initialized
    first = np.flatnonzero(~dead)[0]
    ref = first + int(2 * multiturn_defaults(rw_core).dead_zone_margin_deg / (120.0 * DT_S)) + 2
    offset = est[ref] - truth[ref]
    assert abs(offset - 360.0 * round(offset / 360.0)) < TRACK_TOL_DEG, "referenced to the register"
    assert np.abs(est[ref:] - truth[ref:] - offset).max() < TRACK_TOL_DEG, "then tracks ten turns"
    assert mt.rejected == 0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_start_in_the_dead_zone_with_garbage_readings_never_initialises_on_garbage(rw_core, seed):
    servo = SimServo(rw_core, start_deg=330.0, speed_deg_s=20.0 * 6.0, seed=seed)
    mt = Multiturn(rw_core)
    truth, est, dead, _ = track(mt, servo, seconds=5 * 60.0 / 20.0)
    first = np.flatnonzero(~dead)[0]
    ref = first + int(2 * multiturn_defaults(rw_core).dead_zone_margin_deg / (120.0 * DT_S)) + 2
    offset = est[ref] - truth[ref]
    assert abs(offset - 360.0 * round(offset / 360.0)) < TRACK_TOL_DEG
    assert np.abs(est[ref:] - truth[ref:] - offset).max() < TRACK_TOL_DEG


def test_a_displacement_confirmed_by_consistent_readings_is_taken_after_a_few_steps(rw_core):
    mt = Multiturn(rw_core)
    for _ in range(10):
        mt.step(valid=True, position_deg=100.0, speed_deg_s=0.0, dt_s=DT_S)
    # the bus was silent for 0.5 s while the servo turned 40 degrees (no speed information)
    for _ in range(50):
        mt.step(valid=False, position_deg=0.0, speed_deg_s=0.0, dt_s=DT_S)
    rng = np.random.default_rng(0)
    out = [mt.step(valid=True, position_deg=140.0 + rng.normal(0.0, 0.2), speed_deg_s=0.0, dt_s=DT_S)
           for _ in range(20)]
    assert out[-1] == pytest.approx(140.0, abs=TRACK_TOL_DEG)


def test_no_answer_dead_reckons_and_flags(rw_core):
    mt = Multiturn(rw_core)
    _referenced(mt, 100.0)
    assert mt.initialized and not mt.dead_reckoning
    out = mt.step(valid=False, position_deg=250.0, speed_deg_s=60.0, dt_s=0.1)
    assert out == pytest.approx(106.0, abs=1e-4), "no answer: the reading is ignored, the speed integrated"
    assert mt.rejected == 0


def test_dead_reckoning_flag_follows_the_predicted_angle_band(rw_core):
    margin = multiturn_defaults(rw_core).dead_zone_margin_deg
    mt = Multiturn(rw_core)
    _referenced(mt, 290.0)
    flags = []
    for k in range(85):  # 85 degrees: through the band and 5 degrees past the margin
        mt.step(valid=True, position_deg=1023 * 300.0 / 1023.0, speed_deg_s=100.0, dt_s=DT_S)
        flags.append((mt.angle_deg % 360.0, mt.dead_reckoning))
    for w, flag in flags:
        in_band = w >= 300.0 - margin or w < margin
        assert flag == in_band, f"at {w:.1f} deg"
    assert any(f for _, f in flags) and not all(f for _, f in flags)


def test_angle_resolution_is_one_tick(rw_core):
    """The fixed-point angle: one tick is 1/2560 of a register unit (0.000115 degrees); a register reading
    converts exactly and a still servo holds its angle to the tick."""
    mt = Multiturn(rw_core)
    assert 1.0 / TICKS_PER_DEG == pytest.approx(300.0 / 1023.0 / 2560.0)
    for raw in (100, 500, 980):  # clear of the dead-zone margin
        mt.reset()
        for _ in range(AGREE):
            mt.step_ticks(valid=True, position_ticks=mt.lib.rw_ax12_position_ticks(raw), speed_ticks_per_ms_q10=0,
                          dt_ms=10)
        assert mt.angle_ticks == raw * 2560
        assert mt.angle_deg == pytest.approx(mt.lib.rw_ax12_position_deg(raw), abs=1e-4)


@pytest.mark.parametrize("speed_deg_s, dt_s", [(math.nan, DT_S), (math.inf, DT_S), (10.0, -1.0), (10.0, math.nan),
                                               (10.0, 0.0105)])
def test_bad_speed_or_dt_is_refused_by_the_binding(rw_core, speed_deg_s, dt_s):
    mt = Multiturn(rw_core)
    mt.step(valid=True, position_deg=100.0, speed_deg_s=0.0, dt_s=DT_S)
    with pytest.raises(ValueError, match="speed_deg_s|dt_s"):
        mt.step(valid=False, position_deg=0.0, speed_deg_s=speed_deg_s, dt_s=dt_s)
    assert mt.angle_deg == pytest.approx(100.0, abs=1e-4)


def test_out_of_range_speed_is_clamped_and_position_is_no_reading(rw_core):
    mt = Multiturn(rw_core)
    mt.step(valid=True, position_deg=100.0, speed_deg_s=0.0, dt_s=DT_S)
    start = mt.angle_ticks
    for bad in (-5, 1023 * 2560 + 1):  # outside the register range: dead reckoning at speed 0
        mt.step_ticks(valid=True, position_ticks=bad, speed_ticks_per_ms_q10=0, dt_ms=10)
    assert mt.angle_ticks == start and mt.rejected == 0
    mt.step_ticks(valid=False, position_ticks=0, speed_ticks_per_ms_q10=2**31 - 1, dt_ms=10)
    assert mt.angle_ticks == start + 10 * (2**23 >> 10), "clamped to RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10"
    assert mt.step(valid=True, position_deg=math.fmod(100.0, 360.0) + 0.0, speed_deg_s=0.0, dt_s=DT_S) != 0.0


def test_long_gap_dead_reckons_as_the_same_time_in_short_steps(rw_core):
    """60 s without an answer at 59 rpm: one step (the int64 path) and 6000 steps of 10 ms agree to the tick."""
    one, many = Multiturn(rw_core), Multiturn(rw_core)
    speed_q10 = one.lib.rw_ax12_speed_ticks_per_ms_q10(532)
    for mt in (one, many):
        mt.step(valid=True, position_deg=100.0, speed_deg_s=0.0, dt_s=DT_S)
    one.step_ticks(valid=False, position_ticks=0, speed_ticks_per_ms_q10=speed_q10, dt_ms=60000)
    for _ in range(6000):
        many.step_ticks(valid=False, position_ticks=0, speed_ticks_per_ms_q10=speed_q10, dt_ms=10)
    assert one.angle_ticks == many.angle_ticks
    # 532 units = 354.3 deg/s; the Q10 speed unit is 0.0075 % slow: under 2 degrees over 59 turns
    assert one.angle_deg - 100.0 == pytest.approx(532 * 0.666 * 60.0, abs=2.0)


def test_reset_forgets_the_reference(rw_core):
    mt = Multiturn(rw_core)
    _referenced(mt, 100.0)
    mt.step(valid=True, position_deg=250.0, speed_deg_s=0.0, dt_s=DT_S)
    assert mt.rejected == 1
    mt.reset()
    assert not mt.initialized and mt.rejected == 0 and mt.angle_deg == 0.0
    assert mt.step(valid=True, position_deg=250.0, speed_deg_s=0.0, dt_s=DT_S) == pytest.approx(250.0)


def test_defaults(rw_core):
    cfg = multiturn_defaults(declare(rw_core))
    # the margin must cover dead-reckoning drift over the 60 degree zone (10 % speed error = 6 degrees),
    # and one 10 ms step at the no-load speed (3.5 degrees) must stay well under the jump limit
    assert cfg.dead_zone_margin_deg >= 6.0
    assert 59.0 * 6.0 * DT_S * 2 < cfg.max_jump_deg < 180.0
