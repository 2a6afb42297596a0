"""The spindle's split bus transaction end to end (firmware/hal/sil/sil_spindle_bus.h, the board's
arduino_spindle.cpp): the control tick never waits for the servo, it steps with the reading its bus side
completed since the previous step. Each bounded-wait path of the bus, judged from telemetry, the plant and the
SIL's spindle bus counters (printed by rw_sil on exit):

- replies lost to an interrupt burst while the rope flies at 15,000 rpm: the spindle rides through on dead
  reckoning (no NO_ANSWER fault, the guide still reaches its target), the rope stays airborne;
- a servo that stops answering (a timeout at every read): SPINDLE_NO_ANSWER after spindle_timeout_s, the guide
  stops, the rope is untouched;
- a bus slower than the tick (each transaction 1.5 ms, running on into the next tick): the reading still
  arrives by the next spindle step, the guide reaches its target;
- servo timeouts in flight leave the speed loop alone: the ESC pulse tick by tick is the one of the same run
  with the servo answering.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.plant_faults import SpindleReplyLoss
from robowrangler_sim.sil.scripted_host import ScriptedHost

P = gen.PARAMS_BY_NAME
WHEEL_RADIUS_M = 0.015
TOP_RPM = 15_000
TOP_MMPS = round(TOP_RPM / 60 * 2 * math.pi * WHEEL_RADIUS_M * 1000)  # 23,562 mm/s


def _bus_counters(sil: SilSession) -> dict[str, int]:
    match = re.search(r"rw_sil spindle_bus (.*)", sil.firmware_stderr)
    assert match, f"no spindle bus counters on the SIL firmware's stderr: {sil.firmware_stderr!r}"
    return {k: int(v) for k, v in (item.split("=") for item in match.group(1).split())}


def _homed_host(**session) -> tuple[SilSession, ScriptedHost]:
    sil = SilSession(speedup=None, **session).start()
    host = ScriptedHost(sil)
    host.run_for(0.6)
    assert isinstance(host.command(gen.Home()), gen.Ack)
    assert host.run_until(lambda h: h.last_telemetry.spindle_flags & gen.SpindleFlag.HOMED, timeout_s=40.0)
    return sil, host


def _target_reached(host: ScriptedHost, target_um: int) -> bool:
    return any(e.event == gen.EventKind.SPINDLE_TARGET_REACHED and abs(e.arg - target_um) < 600
               for e in host.received.events)


def test_replies_lost_to_an_interrupt_burst_at_15000_rpm_are_ridden_through(native_build_dir: Path) -> None:
    sil, host = _homed_host()
    try:
        assert isinstance(host.command(gen.ParamSet(P["max_rope_speed_mps"].id, 25.0)), gen.Ack)
        host.arm_and_spin(TOP_MMPS, settle_s=4.0)
        t = host.last_telemetry
        assert t.state == gen.State.AIRBORNE and abs(t.motor_rpm - TOP_RPM) < 300, f"not at 15,000 rpm: {t}"
        host.received.events.clear()
        target_um = 60_000
        assert isinstance(host.command(gen.SetLoop(target_um)), gen.Ack)
        host.run_for(0.5)  # the guide is on its way
        burst = SpindleReplyLoss(start_s=sil.plant.time_us / 1e6, duration_s=0.035).install(sil)  # 3-4 reads lost
        host.run_for(0.2)
        assert burst.ticks_lost == 35
        assert host.run_until(lambda h: _target_reached(h, target_um), timeout_s=30.0)
        host.run_for(0.3)
        t = host.last_telemetry
        assert not t.fault_bits & gen.Fault.SPINDLE_NO_ANSWER and t.spindle_flags & gen.SpindleFlag.ANSWERING
        assert abs(sil.spindle.guide_position_mm - target_um / 1000) <= 0.6
        assert t.state == gen.State.AIRBORNE and abs(t.motor_rpm - TOP_RPM) < 300  # the rope never noticed
        assert t.tick_overruns == 0
    finally:
        host.close()
        sil.stop()
    counters = _bus_counters(sil)
    assert 3 <= counters["reads_failed"] <= 4, counters  # the burst's reads, and no other
    assert counters["missing"] >= counters["reads_failed"]


def test_a_servo_that_stops_answering_times_out_without_touching_the_rope(native_build_dir: Path) -> None:
    sil, host = _homed_host()
    try:
        host.arm_and_spin(6000)
        assert isinstance(host.command(gen.SetLoop(80_000)), gen.Ack)
        host.run_for(0.5)
        sil.spindle.answering = False  # every read times out from now on
        timeout_s = P["spindle_timeout_s"].default
        host.run_for(timeout_s + 0.5)
        t = host.last_telemetry
        assert t.fault_bits & gen.Fault.SPINDLE_NO_ANSWER and not t.spindle_flags & gen.SpindleFlag.MOVING
        assert sil.spindle.moving_speed_raw == 0  # the stop was written (the servo executes writes it cannot answer)
        assert t.state == gen.State.AIRBORNE and abs(t.rope_speed_mmps - 6000) < 150 and t.tick_overruns == 0
    finally:
        host.close()
        sil.stop()
    counters = _bus_counters(sil)
    assert counters["reads_failed"] >= timeout_s / 0.01 - 2, counters


def _pulses_airborne(*, servo_silent: bool) -> tuple[list[float], gen.Telemetry, dict[str, int]]:
    """Airborne at 6 m/s with the guide at rest; for 0.6 s the ESC pulse the plant applied each tick, the servo
    answering or not (every read timing out)."""
    sil, host = _homed_host()
    pulses: list[float] = []
    try:
        host.arm_and_spin(6000, settle_s=2.0)
        sil.spindle.answering = not servo_silent
        sil.tick_hooks.append(lambda s: pulses.append(s.last_esc_pulse_fine_us))
        host.run_for(0.6)
        t = host.last_telemetry
    finally:
        host.close()
        sil.stop()
    return pulses, t, _bus_counters(sil)


def test_servo_timeouts_leave_the_esc_pulse_the_same_tick_by_tick(native_build_dir: Path) -> None:
    """The speed loop never waits on the servo: with every read timing out (counted, SPINDLE_NO_ANSWER after
    spindle_timeout_s), the ESC pulse is the one of the same run with the servo answering, tick by tick."""
    answered, t_ok, c_ok = _pulses_airborne(servo_silent=False)
    silent, t_silent, c_silent = _pulses_airborne(servo_silent=True)
    assert len(answered) == len(silent) >= 590
    assert len(set(answered)) > 1, "the pulse moved: the speed loop was working"
    assert silent == answered, "a servo timeout changed an ESC pulse"
    assert c_ok["reads_failed"] == 0 and c_silent["reads_failed"] >= 0.6 / 0.01 - 2, (c_ok, c_silent)
    assert t_silent.fault_bits & gen.Fault.SPINDLE_NO_ANSWER and not t_ok.fault_bits & gen.Fault.SPINDLE_NO_ANSWER
    assert t_silent.state == t_ok.state == gen.State.AIRBORNE and t_silent.tick_overruns == 0


def test_a_bus_slower_than_the_tick_is_late_but_the_guide_arrives(native_build_dir: Path) -> None:
    sil, host = _homed_host(spindle_bus_us=1500)
    try:
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        assert isinstance(host.command(gen.SetLoop(30_000)), gen.Ack)
        assert host.run_until(lambda h: _target_reached(h, 30_000), timeout_s=30.0)
        host.run_for(0.3)
        assert abs(sil.spindle.guide_position_mm - 30.0) <= 0.6
        assert not host.last_telemetry.fault_bits & gen.Fault.SPINDLE_NO_ANSWER
    finally:
        host.close()
        sil.stop()
    counters = _bus_counters(sil)
    assert counters["reads_ok"] > 100 and counters["reads_failed"] == 0 and counters["late"] == 0, counters
    assert counters["missing"] <= 2, counters  # the first step (nothing requested yet), never again
