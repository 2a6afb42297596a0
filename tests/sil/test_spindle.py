"""The spindle loop end to end: SIL firmware + AX-12A / lead-screw plant, judged from telemetry and the plant."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from robowrangler.protocol import generated as gen
from robowrangler_sim.plants.spindle import SpindleParams
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost

P = gen.PARAMS_BY_NAME


def _host(spindle_params: SpindleParams | None = None) -> tuple[SilSession, ScriptedHost]:
    sil = SilSession(speedup=None, spindle_params=spindle_params).start()
    host = ScriptedHost(sil)
    host.run_for(0.6)
    return sil, host


def _events(host: ScriptedHost, kind: gen.EventKind) -> list[gen.Event]:
    return [e for e in host.received.events if e.event == kind]


def _home(host: ScriptedHost) -> None:
    assert isinstance(host.command(gen.Home()), gen.Ack)
    assert host.run_until(lambda h: h.last_telemetry.spindle_flags & gen.SpindleFlag.HOMED, timeout_s=40.0)


@pytest.fixture
def homed(native_build_dir: Path) -> Iterator[ScriptedHost]:
    sil, host = _host()
    _home(host)
    assert isinstance(host.command(gen.Arm()), gen.Ack)
    yield host
    host.close()
    sil.stop()


def test_homing_by_stall_finds_the_end_stop(native_build_dir: Path) -> None:
    sil, host = _host()
    try:
        assert not host.last_telemetry.spindle_flags & gen.SpindleFlag.HOMED
        _home(host)
        (homed,) = _events(host, gen.EventKind.SPINDLE_HOMED)
        assert homed.arg == 1  # by stall: no switch fitted
        assert abs(sil.spindle.guide_position_mm) < 0.3  # the plant's end stop is the home
        host.run_for(0.5)
        assert host.last_telemetry.spindle_flags & gen.SpindleFlag.MOVING == 0
    finally:
        host.close()
        sil.stop()


def test_homing_by_limit_switch(native_build_dir: Path) -> None:
    sil, host = _host(SpindleParams(switch_fitted=True, switch_travel_mm=1.0))
    try:
        _home(host)
        (homed,) = _events(host, gen.EventKind.SPINDLE_HOMED)
        assert homed.arg == 2
        assert 0.0 < sil.spindle.guide_position_mm <= 1.1  # stopped at the switch, before the stop
    finally:
        host.close()
        sil.stop()


def test_loop_size_follows_set_loop(homed: ScriptedHost) -> None:
    sil = homed.sil
    for target_mm in (60.0, 25.0):
        assert isinstance(homed.command(gen.SetLoop(round(target_mm * 1000))), gen.Ack)
        assert homed.run_until(lambda h: any(e.event == gen.EventKind.SPINDLE_TARGET_REACHED
                                             and abs(e.arg - target_mm * 1000) < 600 for e in h.received.events),
                               timeout_s=40.0)
        homed.run_for(0.3)
        assert abs(sil.spindle.guide_position_mm - target_mm) <= 0.6  # tolerance 0.5 mm + reading noise
        assert abs(homed.last_telemetry.guide_position_um / 1000 - sil.spindle.guide_position_mm) < 0.3
        assert sil.spindle.loop_length_m == pytest.approx(2.0 - 2 * target_mm / 1000, abs=0.002)
        homed.received.events.clear()


@pytest.mark.parametrize("speed_mmps", [1.0, 3.0, 6.0])
def test_dead_zone_crossings_keep_the_turn_count_at_every_speed(homed: ScriptedHost, speed_mmps: float) -> None:
    sil = homed.sil
    assert isinstance(homed.command(gen.ParamSet(P["spindle_max_speed_mmps"].id, speed_mmps)), gen.Ack)
    target_mm = 40.0  # 5 turns of the 8 mm lead screw: 5 dead-zone crossings
    assert isinstance(homed.command(gen.SetLoop(round(target_mm * 1000))), gen.Ack)
    dead_zone_seen = False
    for _ in range(int((target_mm / speed_mmps * 2.2 + 5) * 10)):
        homed.run_for(0.1)
        dead_zone_seen |= bool(homed.last_telemetry.spindle_flags & gen.SpindleFlag.DEAD_ZONE)
        if any(e.event == gen.EventKind.SPINDLE_TARGET_REACHED for e in homed.received.events):
            break
    assert dead_zone_seen
    homed.run_for(0.2)
    assert abs(sil.spindle.guide_position_mm - target_mm) <= 0.6
    assert homed.last_telemetry.spindle_rejected == 0  # the garbage in the dead zone was never used


def test_grasp_relaxes_retracts_and_holds_the_object(homed: ScriptedHost) -> None:
    sil = homed.sil
    sil.spindle.object_circumference_m = 1.85  # the loop closes on it at about 75 mm of guide travel
    assert isinstance(homed.command(gen.SetRopeSpeed(5000)), gen.Ack)
    homed.run_for(1.0)
    assert isinstance(homed.command(gen.Grasp()), gen.Ack)
    assert homed.run_until(lambda h: h.last_telemetry.state == gen.State.HOLD, timeout_s=40.0)
    path = [(e.state_from, e.state_to, e.arg) for e in homed.received.events if e.event == gen.EventKind.STATE_CHANGED]
    assert path[-3:] == [(gen.State.AIRBORNE, gen.State.RELAX, gen.Cause.COMMAND),
                         (gen.State.RELAX, gen.State.RETRACT, gen.Cause.SPEED_REACHED),
                         (gen.State.RETRACT, gen.State.HOLD, gen.Cause.LOAD_SECURED)]
    assert sil.plant.rope_speed_mps < 0.2  # the rope stopped before the spindle reeled in
    assert 5.0 < sil.spindle.rope_tension_n < 60.0  # held, not crushed
    homed.run_for(2.0)
    assert sil.spindle.rope_tension_n > 5.0  # still held (the lead screw is self-locking)
    assert isinstance(homed.command(gen.Release()), gen.Ack)
    homed.run_for(8.0)
    assert sil.spindle.rope_tension_n == 0.0 and homed.last_telemetry.state == gen.State.ARMED


def test_retract_with_nothing_to_hold_ends_at_the_stroke(homed: ScriptedHost) -> None:
    assert isinstance(homed.command(gen.ParamSet(P["guide_max_mm"].id, 30.0)), gen.Ack)
    assert isinstance(homed.command(gen.Retract()), gen.Ack)
    assert homed.run_until(lambda h: h.last_telemetry.state == gen.State.ARMED
                           and h.last_telemetry.guide_position_um > 25000, timeout_s=30.0)
    last = [e for e in homed.received.events if e.event == gen.EventKind.STATE_CHANGED][-1]
    assert (last.state_from, last.state_to, last.arg) == (gen.State.RETRACT, gen.State.ARMED, gen.Cause.STROKE_END)
    assert homed.sil.spindle.guide_position_mm <= 30.6


def test_blocked_spindle_is_a_stall_fault_and_stops(homed: ScriptedHost) -> None:
    homed.sil.spindle.stalled = True  # something jams the lead screw
    assert isinstance(homed.command(gen.SetLoop(50000)), gen.Ack)
    homed.run_for(2.0)
    t = homed.last_telemetry
    assert t.fault_bits & gen.Fault.SPINDLE_STALL and not t.spindle_flags & gen.SpindleFlag.MOVING
    refused = homed.command(gen.SetLoop(20000))
    assert isinstance(refused, gen.Nack) and refused.reason == gen.NackReason.SPINDLE_UNAVAILABLE
    assert t.state == gen.State.ARMED  # a spindle fault does not drop the rope


def test_silent_servo_is_a_fault_and_nothing_moves(homed: ScriptedHost) -> None:
    assert isinstance(homed.command(gen.SetLoop(80000)), gen.Ack)
    homed.run_for(1.0)
    homed.sil.spindle.answering = False
    homed.run_for(1.0)
    t = homed.last_telemetry
    assert t.fault_bits & gen.Fault.SPINDLE_NO_ANSWER
    assert not t.spindle_flags & gen.SpindleFlag.ANSWERING and not t.spindle_flags & gen.SpindleFlag.MOVING
    assert homed.sil.spindle.moving_speed_raw == 0


def test_spindle_commands_are_refused_with_reasons(native_build_dir: Path) -> None:
    sil, host = _host()
    try:
        assert host.command(gen.Retract()).reason == gen.NackReason.BAD_STATE  # DISARMED
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        assert host.command(gen.SetLoop(50000)).reason == gen.NackReason.NOT_HOMED
        assert host.command(gen.Grasp()).reason == gen.NackReason.NOT_HOMED
        assert host.command(gen.Release()).reason == gen.NackReason.BAD_STATE
        _home(host)
        too_far = host.command(gen.SetLoop(181000))
        assert too_far.reason == gen.NackReason.OUT_OF_RANGE and too_far.detail == 180000
        assert host.command(gen.SetLoop(-1)).reason == gen.NackReason.OUT_OF_RANGE
        assert host.command(gen.Grasp()).reason == gen.NackReason.BAD_STATE  # not airborne
        host.run_for(0.5)
        assert host.last_telemetry.spindle_flags & gen.SpindleFlag.MOVING == 0  # nothing moved
    finally:
        host.close()
        sil.stop()


def test_battery_under_cutoff_lands_the_rope(native_build_dir: Path) -> None:
    sil, host = _host()
    try:
        host.arm_and_spin(6000)
        sil.loads.battery_aux_current_a = 90.0  # a short elsewhere drags the pack under 9.9 V
        host.run_for(2.5)
        kinds = [(e.event, e.arg) for e in host.received.events]
        assert (gen.EventKind.FAULT_RAISED, gen.Fault.BATTERY_LOW) in kinds
        down = [e for e in host.received.events if e.event == gen.EventKind.STATE_CHANGED
                and e.state_to == gen.State.SPINDOWN]
        assert down and down[0].arg == gen.Cause.BATTERY_LOW
        refused = host.command(gen.SetRopeSpeed(4000))
        assert isinstance(refused, gen.Nack) and refused.reason == gen.NackReason.BAD_STATE
    finally:
        host.close()
        sil.stop()


def test_heartbeat_loss_stops_a_guide_move(homed: ScriptedHost) -> None:
    assert isinstance(homed.command(gen.SetLoop(150000)), gen.Ack)
    homed.run_for(1.0)
    homed.heartbeats_enabled = False
    homed.run_for(1.0)
    position_mm = homed.sil.spindle.guide_position_mm
    homed.run_for(1.0)
    assert homed.sil.spindle.guide_position_mm == pytest.approx(position_mm, abs=0.3)  # stopped, not at 150
    assert position_mm < 40.0 and homed.sil.spindle.moving_speed_raw == 0
