"""rw_spindle: homing, guide position loop, retract until secured, stall, silence, soft limits.

Two kinds of drive:
- the real spindle plant (robowrangler_sim.plants.spindle: AX-12A wheel mode -> T8 lead screw -> guide,
  end stops, rope wrapped around an object, register noise and dead-zone garbage), closed in the order the
  core does it every 10 ms: read the registers, rw_spindle_step, write the moving speed, the plant steps;
- hand-made register readings where a law or a timing must be checked exactly.
Defaults are the core's parameter defaults (lead 8 mm, stroke 0..180 mm, kp 4/s, 6 mm/s, tolerance 0.5 mm,
homing 3 mm/s over 25 %, stall 50 % for 0.3 s, secure 12 %, retract 5 mm/s, timeout 0.2 s).
"""

from __future__ import annotations

import math

import pytest

from robowrangler_sim.plants.spindle import SpindleParams, SpindlePlant
from spindle_ctypes import DEFAULT_CONFIG, DIRECTION_BIT, Mode, Outcome, Spindle, SpindleReading, signed_raw

DT_S = 0.01
MM_PER_DEG = DEFAULT_CONFIG["lead_mm_per_rev"] / 360.0
STALL_STEPS = round(DEFAULT_CONFIG["stall_time_s"] / DT_S)


def moving_raw_for(lib, mmps: float) -> int:
    return lib.rw_ax12_moving_speed_raw(mmps / MM_PER_DEG)


def reading(*, position_raw: int = 500, speed_units: int = 0, load_permille: int = 0,
            switch: bool = False) -> SpindleReading:
    """A register reading; speed and load signed (+ = counter-clockwise = retract direction)."""
    return SpindleReading(position_raw, signed_raw(speed_units), signed_raw(load_permille), switch)


class Rig:
    """rw_spindle closed around the real spindle plant, stepped at the core's 10 ms spindle period."""

    def __init__(self, lib, *, plant: SpindleParams | None = None, seed: int = 0, **cfg: float) -> None:
        self.lib = lib
        self.sp = Spindle(lib, **cfg)
        self.plant = SpindlePlant(plant, seed=seed)
        self.t_s = 0.0
        self.outcomes: list[tuple[float, Outcome]] = []
        self.trace: list[dict] = []

    def step(self) -> Outcome:
        p = self.plant
        read_mm = p.guide_position_mm  # where the guide was when the registers were read
        r = SpindleReading(p.position_raw, p.speed_raw, p.load_raw, p.limit_switch) if p.answering else None
        out = self.sp.step(r, DT_S)
        raw = self.sp.moving_speed_raw
        assert raw & ~0x7FF == 0 and (raw & 0x3FF) <= 1023, f"moving speed register {raw:#x} out of range"
        p.moving_speed_raw = raw
        p.step(DT_S)
        self.t_s += DT_S
        self.trace.append(dict(t_s=self.t_s, out=out, raw=raw, pos_mm=self.sp.position_mm,
                               plant_mm=read_mm, load=self.sp.load_permille,
                               cmd_mmps=self.sp.command_mmps))
        if out != Outcome.NOTHING:
            self.outcomes.append((self.t_s, out))
        return out

    def run(self, seconds: float, *, until: Outcome | None = None) -> Outcome | None:
        """Steps for `seconds`, or until `until` happens (then returns it)."""
        for _ in range(int(round(seconds / DT_S))):
            if self.step() == until and until is not None:
                return until
        return None

    def home(self) -> None:
        self.sp.home()
        assert self.run(30.0, until=Outcome.HOMED_BY_STALL if not self.plant.params.switch_fitted
                        else Outcome.HOMED_BY_SWITCH) is not None, "homing did not end"
        self.outcomes.clear()
        self.trace.clear()


# ------------------------------------------------------------------------------------------------ homing

def test_homing_by_stall_finds_the_end_stop_after_the_stall_time(rw_core):
    rig = Rig(rw_core)
    assert not rig.sp.homed
    start_mm = rig.plant.guide_position_mm
    rig.sp.home()
    assert rig.run(30.0, until=Outcome.HOMED_BY_STALL) == Outcome.HOMED_BY_STALL
    assert rig.outcomes == [(pytest.approx(rig.t_s), Outcome.HOMED_BY_STALL)], "one homing event"
    assert abs(rig.plant.guide_position_mm) < 0.05, "the end stop is home"
    moving = [s for s in rig.trace[:-1] if s["raw"]]
    assert all(s["raw"] & DIRECTION_BIT for s in moving), "homing turns clockwise (towards home, -mm)"
    assert (moving[len(moving) // 2]["raw"] & 0x3FF) == moving_raw_for(rw_core, 3.0)
    at_stop = next(s["t_s"] for s in rig.trace if s["plant_mm"] <= 1e-6)
    assert start_mm / 3.0 * 0.8 < at_stop, "drove the whole way at the homing speed"
    waited = rig.t_s - at_stop
    # (the step's time is counted in whole ms: the stall_time_s-th ms of the hold ends it; 1e-9: t_s is a float sum)
    assert DEFAULT_CONFIG["stall_time_s"] - DT_S - 1e-9 <= waited <= DEFAULT_CONFIG["stall_time_s"] + 0.1
    assert rig.sp.homed and rig.sp.mode == Mode.IDLE and rig.sp.moving_speed_raw == 0
    assert rig.sp.position_mm == 0.0
    rig.run(1.0)
    assert len(rig.outcomes) == 1 and rig.sp.moving_speed_raw == 0
    assert abs(rig.sp.position_mm - rig.plant.guide_position_mm) < 0.05


def test_homing_by_limit_switch_stops_before_the_end_stop(rw_core):
    rig = Rig(rw_core, plant=SpindleParams(switch_fitted=True, switch_travel_mm=1.0))
    rig.sp.home()
    assert rig.run(30.0, until=Outcome.HOMED_BY_SWITCH) == Outcome.HOMED_BY_SWITCH
    assert [o for _, o in rig.outcomes] == [Outcome.HOMED_BY_SWITCH]
    assert 0.7 < rig.plant.guide_position_mm <= 1.0, "homed where the switch closed"
    assert rig.sp.position_mm == 0.0 and rig.sp.homed and rig.sp.moving_speed_raw == 0
    rig.run(0.5)
    assert rig.plant.guide_position_mm > 0.7, "never ran into the end stop"


def test_homing_stall_needs_load_and_stillness_held_for_the_stall_time(rw_core):
    sp = Spindle(rw_core)
    sp.home()
    for _ in range(200):  # loaded but moving: not a stop
        assert sp.step(reading(speed_units=-200, load_permille=-400), DT_S) == Outcome.NOTHING
    for _ in range(200):  # still but lightly loaded (10 % < 25 %): not a stop
        assert sp.step(reading(load_permille=-100), DT_S) == Outcome.NOTHING
    for _ in range(3):  # interrupted stalls do not add up
        for _ in range(STALL_STEPS - 2):
            assert sp.step(reading(load_permille=-400), DT_S) == Outcome.NOTHING
        assert sp.step(reading(speed_units=-200, load_permille=-400), DT_S) == Outcome.NOTHING
    steps = 0
    while sp.step(reading(load_permille=-400), DT_S) == Outcome.NOTHING:
        steps += 1
        assert steps < 100, "a held stall never ended homing"
    assert STALL_STEPS - 1 <= steps + 1 <= STALL_STEPS + 1
    assert sp.homed and sp.mode == Mode.IDLE and sp.moving_speed_raw == 0


def test_homing_again_when_already_homed_finds_the_end_stop(rw_core):
    rig = Rig(rw_core)
    rig.home()
    rig.sp.move_to(10.0)
    assert rig.run(10.0, until=Outcome.TARGET_REACHED) == Outcome.TARGET_REACHED
    rig.sp.home()
    assert rig.run(10.0, until=Outcome.HOMED_BY_STALL) == Outcome.HOMED_BY_STALL
    assert abs(rig.plant.guide_position_mm) < 0.05


# ------------------------------------------------------------------------------------------------ position

def _homed_at_zero(lib, **cfg) -> Spindle:
    sp = Spindle(lib, **cfg)
    sp.home()
    assert sp.step(reading(switch=True), DT_S) == Outcome.HOMED_BY_SWITCH
    assert sp.position_mm == 0.0
    return sp


@pytest.mark.parametrize("target_mm, expected_mmps", [
    (0.4, 0.0), (-0.4, 0.0), (0.5, 0.0),          # inside the tolerance: no drive
    (0.6, 2.4), (1.0, 4.0), (-1.2, -4.8),         # kp 4 /s times the error
    (1.6, 6.0), (10.0, 6.0), (-40.0, -6.0),       # saturated at the 6 mm/s limit
])
def test_position_loop_command_is_p_law_saturated_and_zero_in_tolerance(rw_core, target_mm, expected_mmps):
    sp = _homed_at_zero(rw_core, guide_min_mm=-50.0)
    sp.move_to(target_mm)
    sp.step(reading(), DT_S)
    assert sp.command_mmps == pytest.approx(expected_mmps, abs=1e-4)
    assert sp.moving_speed_raw == moving_raw_for(rw_core, expected_mmps)
    if expected_mmps > 0:
        assert not sp.moving_speed_raw & DIRECTION_BIT, "+mm (retract) = counter-clockwise = bit 10 clear"
    elif expected_mmps < 0:
        assert sp.moving_speed_raw & DIRECTION_BIT


def test_fixed_point_resolution_of_position_and_command(rw_core):
    """The step is integer: the angle in ticks (1/2560 register unit), the guide in um, the command in um/s.
    Every register value near home maps to the float law (register x 300/1023 deg x lead/360) within 1 um,
    and the P law's command is kp x the error within kp x 1 um/s (+ 1 um/s of rounding)."""
    sp = _homed_at_zero(rw_core, guide_min_mm=-50.0)  # home at register 500
    lead = DEFAULT_CONFIG["lead_mm_per_rev"]
    kp = DEFAULT_CONFIG["kp_per_s"]
    for raw in list(range(500, 571, 3)) + list(range(570, 429, -3)):  # small steps: never a rejected jump
        sp.step(reading(position_raw=raw), DT_S)
        expected_mm = (raw - 500) * 300.0 / 1023.0 * lead / 360.0
        assert sp.position_mm == pytest.approx(expected_mm, abs=1e-3), f"register {raw}"
        target_mm = expected_mm + 0.7777  # inside the speed limit: kp x 0.7777 = 3.11 mm/s
        sp.move_to(target_mm)
        sp.step(reading(position_raw=raw), DT_S)
        assert sp.command_mmps == pytest.approx(kp * 0.7777, abs=(kp + 1.0) * 1e-3)
    assert sp.rejected == 0


def test_target_reached_once_per_target(rw_core):
    sp = _homed_at_zero(rw_core)
    sp.move_to(0.3)
    outs = [sp.step(reading(), DT_S) for _ in range(100)]
    assert outs.count(Outcome.TARGET_REACHED) == 1 and outs[0] == Outcome.TARGET_REACHED
    sp.move_to(0.2)  # a new target, even one already reached, is reported again
    outs = [sp.step(reading(), DT_S) for _ in range(100)]
    assert outs.count(Outcome.TARGET_REACHED) == 1
    assert sp.mode == Mode.POSITION, "holds the target"


def test_moves_the_real_guide_across_many_dead_zones_and_reports_the_target_once(rw_core):
    rig = Rig(rw_core, seed=4)
    rig.home()
    rig.sp.move_to(100.0)  # 12.5 turns of the servo: 12 dead-zone crossings
    rig.run(25.0)
    assert [o for _, o in rig.outcomes] == [Outcome.TARGET_REACHED]
    assert abs(rig.plant.guide_position_mm - 100.0) <= DEFAULT_CONFIG["tolerance_mm"] + 0.05
    worst = max(abs(s["pos_mm"] - s["plant_mm"]) for s in rig.trace)
    assert worst < 2.0 * MM_PER_DEG, f"guide position estimate off by {worst:.3f} mm (over 2 degrees)"
    assert max(abs(s["cmd_mmps"]) for s in rig.trace) == pytest.approx(6.0)
    assert max(s["raw"] & 0x3FF for s in rig.trace) == moving_raw_for(rw_core, 6.0)
    assert rig.sp.rejected == 0
    assert rig.sp.moving_speed_raw == 0
    rig.sp.move_to(60.0)
    rig.run(10.0)
    assert [o for _, o in rig.outcomes] == [Outcome.TARGET_REACHED] * 2
    assert abs(rig.plant.guide_position_mm - 60.0) <= DEFAULT_CONFIG["tolerance_mm"] + 0.05
    assert all(s["raw"] & DIRECTION_BIT for s in rig.trace[-1000:] if s["raw"]), "towards home = clockwise"


def test_soft_limits_stop_outward_motion_only(rw_core):
    sp = _homed_at_zero(rw_core, guide_min_mm=0.0, guide_max_mm=10.0)  # at the min limit
    sp.move_to(-5.0)
    sp.step(reading(), DT_S)
    assert sp.command_mmps == 0.0 and sp.moving_speed_raw == 0, "no further out of the stroke"
    sp.move_to(5.0)
    sp.step(reading(), DT_S)
    assert sp.command_mmps == pytest.approx(6.0), "back into the stroke is allowed"
    sp = _homed_at_zero(rw_core, guide_min_mm=-10.0, guide_max_mm=0.0)  # at the max limit
    sp.move_to(5.0)
    sp.step(reading(), DT_S)
    assert sp.command_mmps == 0.0 and sp.moving_speed_raw == 0
    sp.retract()
    sp.step(reading(), DT_S)
    assert sp.moving_speed_raw == 0, "retracting stops at the max limit too"
    sp.move_to(-5.0)
    sp.step(reading(), DT_S)
    assert sp.command_mmps == pytest.approx(-6.0)


def test_soft_limits_do_not_apply_before_homing(rw_core):
    sp = Spindle(rw_core)
    sp.step(reading(), DT_S)
    sp.move_to(-5.0)
    sp.step(reading(), DT_S)
    assert sp.command_mmps == pytest.approx(-6.0), "positions mean nothing before homing"


def test_blocked_guide_is_a_stall_after_the_stall_time(rw_core):
    rig = Rig(rw_core)
    rig.home()
    rig.sp.move_to(60.0)
    while rig.plant.guide_position_mm < 20.0:
        rig.step()
    rig.plant.stalled = True
    blocked_at = rig.t_s
    assert rig.run(3.0, until=Outcome.STALLED) == Outcome.STALLED
    assert [o for _, o in rig.outcomes] == [Outcome.STALLED]
    assert DEFAULT_CONFIG["stall_time_s"] <= rig.t_s - blocked_at <= DEFAULT_CONFIG["stall_time_s"] + 0.1
    assert rig.sp.mode == Mode.IDLE and rig.sp.moving_speed_raw == 0
    rig.run(1.0)
    assert len(rig.outcomes) == 1


def test_guide_blocked_just_short_of_its_target_is_a_stall(rw_core):
    rig = Rig(rw_core)
    rig.home()
    rig.sp.move_to(20.0)
    while rig.plant.guide_position_mm < 19.2:
        rig.step()
    rig.plant.stalled = True
    assert rig.run(3.0, until=Outcome.STALLED) == Outcome.STALLED


def test_position_stall_needs_load_over_the_threshold_and_no_motion(rw_core):
    sp = _homed_at_zero(rw_core)
    sp.move_to(50.0)
    for _ in range(200):
        assert sp.step(reading(load_permille=450), DT_S) == Outcome.NOTHING  # 45 % < 50 %
    for _ in range(200):
        assert sp.step(reading(speed_units=300, load_permille=800), DT_S) == Outcome.NOTHING  # moving
    outs = [sp.step(reading(load_permille=800), DT_S) for _ in range(STALL_STEPS + 1)]
    assert Outcome.STALLED in outs and outs.index(Outcome.STALLED) + 1 in (STALL_STEPS, STALL_STEPS + 1)


# ------------------------------------------------------------------------------------------------ retract

def test_retract_secures_a_real_object_after_the_load_has_held(rw_core):
    rig = Rig(rw_core)
    rig.home()
    rig.plant.object_circumference_m = 1.8  # the loop closes on it at 100 mm of guide travel
    rig.sp.retract()
    assert rig.run(40.0, until=Outcome.SECURED) == Outcome.SECURED
    assert [o for _, o in rig.outcomes] == [Outcome.SECURED]
    secure_permille = DEFAULT_CONFIG["secure_load_pct"] * 10
    spike = [s["load"] for s in rig.trace[:5]]
    assert max(spike) > 2 * secure_permille, "starting from rest loads the servo (the spike is real)"
    assert all(s["raw"] and not s["raw"] & DIRECTION_BIT for s in rig.trace[:-1]), "retract = counter-clockwise"
    held = rig.trace[-STALL_STEPS:]
    assert all(s["load"] >= secure_permille for s in held), "the load held for stall_time_s before SECURED"
    assert 99.0 < rig.plant.guide_position_mm < 110.0 and rig.plant.rope_tension_n > 0.0
    assert rig.sp.mode == Mode.IDLE and rig.sp.moving_speed_raw == 0
    rig.run(1.0)
    assert len(rig.outcomes) == 1


def test_lost_replies_while_the_load_holds_neither_restart_nor_fake_the_hold(rw_core):
    """The split bus on the board makes a lost reply a step without a reading: the time the secure load has held
    is kept through it (not restarted, so the retract does not pull on for another stall_time_s; not advanced,
    so a load never seen does not count)."""
    rig = Rig(rw_core)
    rig.home()
    rig.plant.object_circumference_m = 1.8
    rig.sp.retract()
    secure_permille = DEFAULT_CONFIG["secure_load_pct"] * 10
    for _ in range(4000):  # until the load has held for half the stall time
        rig.step()
        held = 0
        for s in reversed(rig.trace):
            if s["load"] < secure_permille:
                break
            held += 1
        if held >= STALL_STEPS // 2 and rig.t_s > 1.0:
            break
    assert held >= STALL_STEPS // 2, "the retract never loaded the rope"
    lost = 3
    for _ in range(lost):  # an interrupt burst: three replies lost, the servo keeps pulling
        p = rig.plant
        assert rig.sp.step(None, DT_S) == Outcome.NOTHING
        p.moving_speed_raw = rig.sp.moving_speed_raw
        p.step(DT_S)
    steps = 0
    while rig.step() != Outcome.SECURED:
        steps += 1
        assert steps < STALL_STEPS, "the hold restarted after the lost replies"
    assert steps + 1 == STALL_STEPS - held, "the hold resumed where it was: the lost steps did not count"


def test_retract_start_up_spike_shorter_than_the_stall_time_does_not_secure(rw_core):
    sp = _homed_at_zero(rw_core)
    sp.retract()
    for _ in range(STALL_STEPS - 1):  # 0.29 s at 60 %
        assert sp.step(reading(load_permille=600), DT_S) == Outcome.NOTHING
    for _ in range(100):
        assert sp.step(reading(speed_units=200, load_permille=30), DT_S) == Outcome.NOTHING
    for _ in range(100):  # a load pushing the other way is not the rope holding
        assert sp.step(reading(speed_units=200, load_permille=-400), DT_S) == Outcome.NOTHING
    assert sp.mode == Mode.RETRACT and sp.moving_speed_raw == moving_raw_for(rw_core, 5.0)
    outs = [sp.step(reading(speed_units=5, load_permille=130), DT_S) for _ in range(STALL_STEPS + 1)]
    assert outs.index(Outcome.SECURED) + 1 in (STALL_STEPS, STALL_STEPS + 1)
    assert sp.mode == Mode.IDLE and sp.moving_speed_raw == 0


def test_retract_with_nothing_to_hold_against_the_hard_stop_is_not_secured(rw_core):
    """guide_max = the stroke (180 mm, where the hard stop is): the servo stalls on the stop with a full load
    just short of guide_max (the position estimate is not exact); that is the end of the stroke, not an
    object: an empty loop must never read as secured."""
    rig = Rig(rw_core, guide_max_mm=180.0)
    rig.home()
    rig.sp.retract()
    assert rig.run(60.0, until=Outcome.STROKE_END) == Outcome.STROKE_END
    assert [o for _, o in rig.outcomes] == [Outcome.STROKE_END]
    assert rig.sp.mode == Mode.IDLE and rig.sp.moving_speed_raw == 0


def test_retract_with_nothing_to_hold_ends_at_the_stroke(rw_core):
    rig = Rig(rw_core, guide_max_mm=30.0)
    rig.home()
    rig.sp.retract()
    assert rig.run(20.0, until=Outcome.STROKE_END) == Outcome.STROKE_END
    assert [o for _, o in rig.outcomes] == [Outcome.STROKE_END]
    assert rig.sp.position_mm >= 30.0
    assert rig.sp.mode == Mode.IDLE and rig.sp.moving_speed_raw == 0
    rig.run(1.0)
    assert 30.0 <= rig.plant.guide_position_mm < 30.3, "stopped at the end of the stroke"
    assert len(rig.outcomes) == 1


# ------------------------------------------------------------------------------------------------ silence

def test_silent_servo_is_reported_once_after_the_timeout_and_stops_the_spindle(rw_core):
    rig = Rig(rw_core)
    rig.home()
    rig.sp.move_to(60.0)
    rig.run(2.0)
    rig.plant.answering = False
    silent_from = rig.t_s
    assert rig.run(1.0, until=Outcome.NO_ANSWER) == Outcome.NO_ANSWER
    assert DEFAULT_CONFIG["timeout_s"] - 1e-6 <= rig.t_s - silent_from <= DEFAULT_CONFIG["timeout_s"] + DT_S + 1e-6
    assert rig.sp.mode == Mode.IDLE and rig.sp.moving_speed_raw == 0 and not rig.sp.answering
    rig.run(2.0)
    assert [o for _, o in rig.outcomes] == [Outcome.NO_ANSWER], "reported once"
    assert all(s["raw"] == 0 for s in rig.trace[-200:])
    rig.plant.answering = True
    rig.run(0.5)
    assert rig.sp.answering
    rig.plant.answering = False
    rig.run(1.0)
    assert [o for _, o in rig.outcomes] == [Outcome.NO_ANSWER] * 2, "a new silence is a new report"


def test_short_silence_is_bridged(rw_core):
    rig = Rig(rw_core)
    rig.home()
    rig.sp.move_to(30.0)
    rig.run(2.0)
    rig.plant.answering = False
    rig.run(DEFAULT_CONFIG["timeout_s"] - 2 * DT_S)
    rig.plant.answering = True
    rig.run(8.0)
    assert [o for _, o in rig.outcomes] == [Outcome.TARGET_REACHED]
    assert abs(rig.plant.guide_position_mm - 30.0) <= DEFAULT_CONFIG["tolerance_mm"] + 0.05


# ------------------------------------------------------------------------------------------------ registers

@pytest.mark.parametrize("mode", ["home", "move_out", "move_in", "retract"])
def test_command_register_never_exceeds_1023_whatever_the_speed_limits(rw_core, mode):
    fast = dict(max_speed_mmps=1000.0, homing_speed_mmps=1000.0, retract_speed_mmps=1000.0, kp_per_s=1000.0,
                guide_min_mm=-1000.0, guide_max_mm=1000.0)
    sp = _homed_at_zero(rw_core, **fast)
    {"home": sp.home, "move_out": lambda: sp.move_to(500.0), "move_in": lambda: sp.move_to(-500.0),
     "retract": sp.retract}[mode]()
    sp.step(reading(speed_units=300), DT_S)
    expected = 2047 if mode in ("home", "move_in") else 1023
    assert sp.moving_speed_raw == expected, "saturated at full scale, direction kept"


def test_unhomed_spindle_reports_no_position_events_and_idle_writes_zero(rw_core):
    sp = Spindle(rw_core)
    for _ in range(50):
        assert sp.step(reading(load_permille=900), DT_S) == Outcome.NOTHING
    assert sp.moving_speed_raw == 0 and sp.mode == Mode.IDLE and not sp.homed
    assert math.isfinite(sp.position_mm)
