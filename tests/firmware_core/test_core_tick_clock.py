"""rw_core and its tick clock: now_us wrapping across 2^32 changes nothing; a long pause between two
ticks (10 s) neither jumps the PI or the ramp nor bursts telemetry; a tick gap while the spindle moves
does not corrupt the guide position."""

from __future__ import annotations

import pytest

from core_harness import U32, CoreHarness, FakeSpindle
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import PARAMS_BY_NAME, Ack, EventKind, ParamSet, SetRopeSpeed, Spindown, State

S = State


def _scenario(h: CoreHarness) -> None:
    """Boot, arm, spin up to airborne, change speed, lose the host (spin-down), come back, ESTOP."""
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    h.command(SetRopeSpeed(6000))
    h.follow_setpoint(until=lambda: h.t_ms >= 1500, max_ms=1500, what="t = 1.5 s")
    h.follow_setpoint(until=lambda: h.state == S.ARMED, max_ms=3000, what="heartbeat-loss spin-down",
                      heartbeat_ms=None)
    h.command(ParamSet(PARAMS_BY_NAME["speed_kp"].id, 0.05))
    h.command(SetRopeSpeed(3500))
    h.follow_setpoint(until=lambda: h.t_ms >= 3500, max_ms=3000, what="t = 3.5 s")
    h.command(proto.Estop())
    h.run_ms(50)


@pytest.mark.parametrize("wrap_at_ms", [300, 650, 1900])  # arming hold, spin-up, heartbeat timing
def test_tick_clock_wrap_gives_byte_identical_behaviour(rw_core, wrap_at_ms):
    ref = CoreHarness(rw_core)
    _scenario(ref)
    wrapped = CoreHarness(rw_core, clock_offset_us=U32 - wrap_at_ms * 1000 - 333)
    _scenario(wrapped)
    assert wrapped.now_us < ref.now_us, "the clock really wrapped"
    assert wrapped.hal.pulses_us == ref.hal.pulses_us
    assert [o.raw for o in wrapped.hal.out] == [o.raw for o in ref.hal.out], "every datagram identical"
    kinds = {e.event for e in ref.events()}
    assert {EventKind.HEARTBEAT_LOST, EventKind.ARMING_HOLD_DONE, EventKind.PARAM_CHANGED} <= kinds
    assert ref.state == S.ESTOP


def test_encoder_count_wrap_gives_byte_identical_behaviour(rw_core):
    ref = CoreHarness(rw_core)
    _scenario(ref)
    wrapped = CoreHarness(rw_core, encoder_count_offset=U32 - 1500)  # wraps early in the spin-up
    _scenario(wrapped)
    assert wrapped.hal.encoder_counts < 1_000_000 and ref.encoder.counts > 1500, "the count really wrapped"
    assert wrapped.hal.pulses_us == ref.hal.pulses_us
    assert [o.raw for o in wrapped.hal.out] == [o.raw for o in ref.hal.out], "every datagram identical"
    kinds = {e.event for e in ref.events()}
    assert {EventKind.HEARTBEAT_LOST, EventKind.ARMING_HOLD_DONE, EventKind.PARAM_CHANGED} <= kinds
    assert ref.state == S.ESTOP


def _airborne_loaded(rw_core) -> CoreHarness:
    """AIRBORNE, the setpoint still ramping from 4 to 8 m/s, the rope held at 4 m/s (loaded): the PI
    integrates a steady error."""
    h = CoreHarness(rw_core, params={"heartbeat_timeout_s": 10.0, "ramp_up_mps2": 2.0})
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000, max_ms=4000)
    h.follow_setpoint(until=lambda: h.telemetry()[-1].rope_speed_setpoint_mmps >= 4000, max_ms=3000,
                      what="4 m/s")
    assert isinstance(h.command(SetRopeSpeed(8000)), Ack)
    h.encoder.speed_mps = 4.0
    h.run_ms(100)
    return h


def test_ten_second_pause_moves_the_ramp_by_one_short_step_and_sends_one_telemetry(rw_core):
    h = _airborne_loaded(rw_core)
    h.drain(25)
    sp_before = h.telemetry()[-1].rope_speed_setpoint_mmps
    n_tel = len(h.telemetry())
    h.heartbeat()
    h.tick(dt_us=10_000_000)
    t_pause = h.t_ms
    h.run_ms(5)
    h.drain(0)  # the frame packed in the pause tick is signed over the next idle ticks
    tel = [t for t in h.telemetry()[n_tel:] if t.time_ms <= t_pause + 5]
    assert len(tel) == 1, "one telemetry after the pause, not a burst of catch-up frames"
    assert tel[-1].time_ms >= t_pause, "uptime advanced by the real 10 s"
    # At most rate x 50 ms (the core's longest control step) + the 25 + 5 normal ticks around it.
    assert 0 < tel[-1].rope_speed_setpoint_mmps - sp_before <= 2.0 * (0.05 + 0.030) * 1000 + 2
    assert tel[-1].rope_speed_target_mmps == 8000 and tel[-1].state == S.AIRBORNE


def test_ten_second_pause_does_not_jump_the_esc_pulse(rw_core):
    h = _airborne_loaded(rw_core)
    h.drain(25)
    normal = [b - a for a, b in zip(h.hal.pulses_us[-21:], h.hal.pulses_us[-20:])]
    pulse_before = h.pulse_us
    h.heartbeat()
    h.tick(dt_us=10_000_000)
    jump = h.pulse_us - pulse_before
    # A 50 ms step of the PI on the 0.25 m/s error moves the pulse by ~20 us; 10 s integrated would
    # saturate it (2000 us); a false zero speed reading gives ~255 us.
    assert abs(jump) < 60, f"pulse {pulse_before} -> {h.pulse_us} us after the pause (normal steps {set(normal)})"
    h.run_ms(30)
    tel = h.telemetry()[-1]
    assert abs(tel.rope_speed_mmps - 4000) < 100, "the rope speed is still measured after the pause"


def test_ten_second_pause_with_a_silent_host_spins_down(rw_core):
    """The pause counts as silence in real time: a lost host is not forgotten by a stalled loop."""
    h = _airborne_loaded(rw_core)
    h.tick(dt_us=10_100_000)
    h.drain(3)
    assert h.transitions()[-1][1:] == (S.AIRBORNE, S.SPINDOWN, proto.Cause.HEARTBEAT_LOST)
    assert h.pulse_us < 1500


def test_spindown_after_a_pause_lands_normally(rw_core):
    h = _airborne_loaded(rw_core)
    h.heartbeat()
    h.tick(dt_us=10_000_000)
    h.command(Spindown())
    h.follow_setpoint(until=lambda: h.state == S.ARMED, max_ms=3000, what="ARMED")
    assert h.pulse_us == 1000


@pytest.mark.parametrize("gap_ms", [200, 1000])
def test_tick_gap_while_the_spindle_moves_keeps_the_guide_position(rw_core, gap_ms):
    h = CoreHarness(rw_core, params={"homing_speed_mmps": 10.0, "heartbeat_timeout_s": 10.0},
                    spindle=FakeSpindle())
    h.tick()
    h.run_ms(600)
    h.command(proto.Home())
    h.run_until(lambda: h.events(EventKind.SPINDLE_HOMED) != [], max_ms=3000, what="homed")
    h.command(proto.Arm())
    assert isinstance(h.command(proto.SetLoop(100_000)), Ack)
    h.run_ms(3000)  # moving at the spindle's top speed
    h.heartbeat()
    h.tick(dt_us=gap_ms * 1000)  # the loop stalled (WiFi, flash write) while the servo kept turning
    for _ in range(40000):
        if h.events(EventKind.SPINDLE_TARGET_REACHED):
            break
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
    (reached,) = h.events(EventKind.SPINDLE_TARGET_REACHED)
    h.run_ms(30)
    assert h.spindle.x_mm == pytest.approx(reached.arg / 1000.0, abs=0.6), \
        f"reported {reached.arg / 1000:.2f} mm, the guide is at {h.spindle.x_mm:.2f} mm"
    assert h.telemetry()[-1].spindle_rejected < 10
