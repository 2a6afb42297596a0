"""rw_core tick schedule (rw_core.h): the speed loop runs on every other tick (dt 2 ms); the telemetry pack
and the spindle step run on the other ticks, never in the same tick as each other or as the speed loop, so
the worst-case tick on the M0+ is one job plus the per-tick work. Telemetry keeps its exact period with a
moving spindle; a state that stops the rope cuts the ESC in the tick that enters it, whatever the phase."""

from __future__ import annotations

import pytest

from core_harness import CoreHarness, FakeSpindle
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import Ack, EventKind, State

S = State


def _homed_airborne_moving(rw_core) -> CoreHarness:
    """Homed spindle, rope AIRBORNE at 4 m/s with a new target of 8 m/s (ramping), guide moving."""
    h = CoreHarness(rw_core, params={"homing_speed_mmps": 10.0, "heartbeat_timeout_s": 10.0, "ramp_up_mps2": 2.0},
                    spindle=FakeSpindle())
    h.tick()
    h.run_ms(600)
    assert isinstance(h.command(proto.Home()), Ack)
    h.run_until(lambda: h.events(EventKind.SPINDLE_HOMED) != [], max_ms=3000, what="SPINDLE_HOMED")
    assert isinstance(h.command(proto.Arm()), Ack)
    h.spin_to_airborne(target_mmps=4000, max_ms=4000)
    assert isinstance(h.command(proto.SetRopeSpeed(8000)), Ack)
    assert isinstance(h.command(proto.SetLoop(120_000)), Ack)
    return h


def _profile_ticks(h: CoreHarness, ticks: int) -> dict[str, list[int]]:
    """Runs ticks with a perfect plant; returns the uptimes (ms) of the ticks in which the ESC pulse changed,
    a TELEMETRY frame was packed (its time_ms: it may leave a tick later behind an event) and the spindle
    step ran (one servo write per step)."""
    pulse, spindle = [], []
    n_tel = len(h.telemetry())
    for _ in range(ticks):
        writes_before = len(h.spindle.writes)
        pulse_before = h.pulse_us
        tel = h.telemetry()
        if tel:
            h.encoder.speed_mps = tel[-1].rope_speed_setpoint_mmps / 1000.0
        h.tick()
        if h.pulse_us != pulse_before:
            pulse.append(h.t_ms)
        if len(h.spindle.writes) > writes_before:
            spindle.append(h.t_ms)
    h.drain(3)
    return {"pulse": pulse, "spindle": spindle, "telemetry": [t.time_ms for t in h.telemetry()[n_tel:]]}


def test_speed_loop_spindle_and_telemetry_never_share_a_tick(rw_core):
    h = _homed_airborne_moving(rw_core)
    ticks = _profile_ticks(h, 400)
    assert h.spindle.moving and h.state == S.AIRBORNE, "the scenario must keep the guide moving and the rope flying"
    tel, spindle, pulse = ticks["telemetry"], ticks["spindle"], ticks["pulse"]
    assert len(tel) >= 20 and len(spindle) == 40, (len(tel), len(spindle))
    assert not set(tel) & set(spindle), "telemetry pack and spindle step in the same tick"
    # the pulse moves only on speed ticks (one parity): never in a telemetry or spindle tick
    assert not set(pulse) & (set(tel) | set(spindle))
    assert len(pulse) > 10 and len({t % 2 for t in pulse}) == 1, pulse
    # both jobs keep their periods with the other one present
    assert {b - a for a, b in zip(tel, tel[1:])} == {20}
    assert {b - a for a, b in zip(spindle, spindle[1:])} == {10}


@pytest.mark.parametrize("phase", [0, 1])
def test_estop_cuts_the_esc_in_the_tick_it_arrives_on_either_phase(rw_core, phase):
    h = _homed_airborne_moving(rw_core)
    h.run_ms(50 + phase)
    assert h.pulse_us > 1100
    reply = h.command(proto.Estop())
    assert isinstance(reply, Ack) and reply.state == S.ESTOP
    assert h.pulse_us == round(h.get_param_value("esc_min_us"))


def test_telemetry_held_back_by_the_schedule_keeps_the_period(rw_core):
    """100 Hz telemetry with a spindle at 100 Hz: telemetry goes first, the spindle step waits for the next
    free tick; both keep a 10 ms period and never meet."""
    h = CoreHarness(rw_core, params={"telemetry_rate_hz": 100.0}, spindle=FakeSpindle())
    h.tick()
    ticks = _profile_ticks(h, 300)
    tel, spindle = ticks["telemetry"], ticks["spindle"]
    assert len(tel) >= 29 and len(spindle) >= 29
    assert not set(tel) & set(spindle)
    assert {b - a for a, b in zip(spindle, spindle[1:])} == {10}
    times = [t.time_ms for t in h.telemetry()]
    assert times[0] == 0 and {b - a for a, b in zip(times, times[1:])} == {10}
