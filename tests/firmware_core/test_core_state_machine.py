"""rw_core state machine: every transition, its STATE_CHANGED event and cause, the arming hold,
ESTOP from every state, FAULT latching, AIRBORNE at ToV x margin, loop collapse (fake HAL, exact inputs)."""

from __future__ import annotations

import pytest

from core_harness import CoreHarness
from robowrangler.protocol.generated import (
    Ack, Arm, Cause, Disarm, Estop, EventKind, Fault, Nack, NackReason, SetRopeSpeed, Spindown, State,
)

S = State
C = Cause


def _ack_state(reply) -> State:
    assert isinstance(reply, Ack), f"expected ACK, got {reply}"
    return State(reply.state)


def test_arm_is_refused_not_ready_during_the_hold_then_accepted_after_hold_done_event(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(497)
    reply = h.command(Arm())  # processed at t = 498 ms
    assert isinstance(reply, Nack)
    assert (reply.reason, reply.detail, reply.state) == (NackReason.NOT_READY, 500, S.DISARMED), \
        "NOT_READY carries the hold in ms"
    assert h.events(EventKind.ARMING_HOLD_DONE) == [] or h.events(EventKind.ARMING_HOLD_DONE)[0].time_ms == 500
    h.run_ms(5)
    h.drain(3)
    done = h.events(EventKind.ARMING_HOLD_DONE)
    assert [e.time_ms for e in done] == [500], "one ARMING_HOLD_DONE, when arm_hold_s has elapsed"
    assert h.transitions() == []
    assert _ack_state(h.command(Arm())) == S.ARMED
    t_arm = h.t_ms
    h.drain(3)
    assert h.transitions() == [(t_arm, S.DISARMED, S.ARMED, C.COMMAND)]


def test_arming_hold_follows_arm_hold_s(rw_core):
    h = CoreHarness(rw_core, params={"arm_hold_s": 1.2})
    h.tick()
    h.run_ms(1000)
    reply = h.command(Arm())
    assert (reply.reason, reply.detail) == (NackReason.NOT_READY, 1200)
    h.run_ms(200)
    assert _ack_state(h.command(Arm())) == S.ARMED
    h.drain(0)
    assert [e.time_ms for e in h.events(EventKind.ARMING_HOLD_DONE)] == [1200]


def test_full_cycle_reports_every_transition_with_its_cause(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    assert _ack_state(h.command(Spindown())) == S.SPINDOWN
    h.follow_setpoint(until=lambda: h.state == S.ARMED, max_ms=2000, what="spin-down back to ARMED")
    h.tick()
    assert _ack_state(h.command(Disarm())) == S.DISARMED
    h.drain(25)
    steps = [(f, t, c) for _, f, t, c in h.transitions()]
    assert steps == [
        (S.DISARMED, S.ARMED, C.COMMAND),
        (S.ARMED, S.SPINUP, C.COMMAND),
        (S.SPINUP, S.AIRBORNE, C.SPEED_REACHED),
        (S.AIRBORNE, S.SPINDOWN, C.COMMAND),
        (S.SPINDOWN, S.ARMED, C.SPEED_REACHED),
        (S.ARMED, S.DISARMED, C.COMMAND),
    ]
    events = h.events()
    assert [e.event_seq for e in events] == list(range(1, len(events) + 1)), "no event lost, none repeated"
    assert events[0].event == EventKind.BOOT
    assert h.telemetry()[-1].events == len(events)
    times = [t for t, *_ in h.transitions()]
    assert times == sorted(times)


def test_set_rope_speed_during_spindown_spins_up_again_and_spindown_from_spinup(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    assert _ack_state(h.command(SetRopeSpeed(2000))) == S.SPINUP
    h.follow_setpoint(until=lambda: h.telemetry()[-1].rope_speed_setpoint_mmps >= 1500, max_ms=500, what="ramp")
    assert _ack_state(h.command(Spindown())) == S.SPINDOWN
    h.run_ms(5)
    assert _ack_state(h.command(SetRopeSpeed(2500))) == S.SPINUP
    h.drain(5)
    steps = [(f, t, c) for _, f, t, c in h.transitions()]
    assert steps[-3:] == [(S.ARMED, S.SPINUP, C.COMMAND), (S.SPINUP, S.SPINDOWN, C.COMMAND),
                          (S.SPINDOWN, S.SPINUP, C.COMMAND)]


def _hold_speed(h: CoreHarness, speed_mps: float, ms: int) -> None:
    h.encoder.speed_mps = speed_mps
    for _ in range(ms):
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()


def test_airborne_exactly_when_measured_reaches_tov_times_margin(rw_core):
    # Unfiltered speed (tau 0) so the measured speed is the encoder's; guard = 2.6 * 1.15 = 2.99 m/s.
    h = CoreHarness(rw_core, params={"speed_filter_tau_s": 0.0})
    h.boot_and_arm()
    assert _ack_state(h.command(SetRopeSpeed(5000))) == S.SPINUP
    _hold_speed(h, 2.96, 300)
    h.drain(3)
    assert h.state == S.SPINUP, "1 % under the guard speed the loop is not airborne"
    t_cross = h.t_ms
    _hold_speed(h, 3.02, 30)
    h.drain(3)
    assert h.state == S.AIRBORNE
    t_air, f, t, cause = h.transitions()[-1]
    assert (f, t, cause) == (S.SPINUP, S.AIRBORNE, C.SPEED_REACHED)
    assert t_cross < t_air <= t_cross + 5, "AIRBORNE within a few edges of crossing the guard"


def test_airborne_needs_the_target_above_the_guard_too(rw_core):
    h = CoreHarness(rw_core, params={"speed_filter_tau_s": 0.0})
    h.boot_and_arm()
    h.command(SetRopeSpeed(2500))  # target under 2.99 m/s
    _hold_speed(h, 3.5, 300)  # rope overspeeding (e.g. pushed) above the guard
    h.drain(3)
    assert h.state == S.SPINUP


def test_airborne_threshold_follows_tov_margin(rw_core):
    h = CoreHarness(rw_core, params={"speed_filter_tau_s": 0.0, "tov_margin": 1.5})  # guard 3.9 m/s
    h.boot_and_arm()
    h.command(SetRopeSpeed(6000))
    _hold_speed(h, 3.5, 200)
    h.drain(3)
    assert h.state == S.SPINUP
    _hold_speed(h, 3.95, 20)
    h.drain(3)
    assert h.state == S.AIRBORNE


def test_loop_collapse_after_collapse_time_goes_back_to_spinup(rw_core):
    h = CoreHarness(rw_core, params={"speed_filter_tau_s": 0.0, "collapse_time_s": 0.3})
    h.boot_and_arm()
    h.command(SetRopeSpeed(4000))
    _hold_speed(h, 4.0, 100)
    h.drain(3)
    assert h.state == S.AIRBORNE
    t_drop = h.t_ms
    _hold_speed(h, 2.0, 290)  # under tov (2.6) but not yet collapse_time_s
    h.drain(3)
    assert h.events(EventKind.LOOP_COLLAPSED) == []
    assert h.state == S.AIRBORNE
    _hold_speed(h, 2.0, 20)
    h.drain(3)
    collapsed = h.events(EventKind.LOOP_COLLAPSED)
    assert len(collapsed) == 1
    assert 300 <= collapsed[0].time_ms - t_drop <= 303
    assert collapsed[0].arg == pytest.approx(2000, abs=10), "arg = measured speed, mm/s"
    assert h.transitions()[-1][1:] == (S.AIRBORNE, S.SPINUP, C.LOOP_COLLAPSED)


def _to_state(h: CoreHarness, state: State) -> None:
    """Drives a fresh harness into state (a real path, no poking)."""
    h.tick()
    if state == S.DISARMED:
        h.run_ms(600)
        return
    h.boot_and_arm()
    if state == S.ARMED:
        return
    if state == S.FAULT:
        h.command(SetRopeSpeed(3000))  # encoder never moves: ENCODER_SILENT
        h.run_until(lambda: h.state == S.FAULT, max_ms=1000, what="FAULT")
        return
    if state == S.SPINUP:
        h.command(SetRopeSpeed(2000))
        h.follow_setpoint(until=lambda: h.telemetry()[-1].rope_speed_setpoint_mmps >= 1000, max_ms=500,
                          what="ramp")
        return
    h.spin_to_airborne(target_mmps=4000)
    if state == S.AIRBORNE:
        return
    if state == S.SPINDOWN:
        h.command(Spindown())  # the encoder keeps its speed: the rope is still running down
        h.run_ms(10)
        return
    if state == S.ESTOP:
        h.command(Estop())
        h.run_ms(5)
        return
    raise AssertionError(state)


# The rope states (the grasp states RELAX/RETRACT/HOLD need the spindle and are not reached here).
ROPE_STATES = [S.DISARMED, S.ARMED, S.SPINUP, S.AIRBORNE, S.SPINDOWN, S.FAULT, S.ESTOP]


@pytest.mark.parametrize("state", ROPE_STATES)
def test_estop_is_accepted_in_every_state_and_cuts_the_esc_in_the_same_tick(rw_core, state):
    h = CoreHarness(rw_core)
    _to_state(h, state)
    h.drain(3)
    assert h.state == state
    n_tr = len(h.transitions())
    assert _ack_state(h.command(Estop())) == S.ESTOP
    assert h.pulse_us == 1000, "ESC at esc_min_us in the very tick of the ESTOP"
    h.drain(5)
    assert all(p == 1000 for p in h.hal.pulses_us[-6:])
    new = h.transitions()[n_tr:]
    if state == S.ESTOP:
        assert new == []
    else:
        assert [(f, t, c) for _, f, t, c in new] == [(state, S.ESTOP, C.COMMAND)]
    # Latched: nothing but DISARM leaves it.
    for cmd in (Arm(), SetRopeSpeed(3000), Spindown()):
        reply = h.command(cmd)
        assert isinstance(reply, Nack) and reply.reason == NackReason.BAD_STATE and reply.state == S.ESTOP


def test_estop_latches_until_disarm_with_the_rope_stopped(rw_core):
    h = CoreHarness(rw_core)
    _to_state(h, S.AIRBORNE)
    h.command(Estop())  # encoder still reports the rope coasting at speed
    reply = h.command(Disarm())
    assert isinstance(reply, Nack) and reply.reason == NackReason.BAD_STATE
    assert reply.detail > 3000, "detail = the rope speed, mm/s, that blocks DISARM"
    h.encoder.speed_mps = 0.0
    h.run_ms(300)
    assert _ack_state(h.command(Disarm())) == S.DISARMED
    assert _ack_state(h.command(Arm())) == S.ARMED


def test_fault_latches_and_is_cleared_only_by_disarm_with_the_rope_stopped(rw_core):
    h = CoreHarness(rw_core)
    _to_state(h, S.FAULT)
    h.encoder.speed_mps = 1.0  # the rope turns (coasting, pushed by hand): not stopped
    for _ in range(2000):
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
    tel = h.telemetry()[-1]
    assert tel.state == S.FAULT and tel.fault_bits == Fault.ENCODER_SILENT, "FAULT does not clear by itself"
    for cmd in (Arm(), SetRopeSpeed(3000), Spindown()):
        reply = h.command(cmd)
        assert isinstance(reply, Nack) and reply.reason == NackReason.BAD_STATE
    reply = h.command(Disarm())
    assert isinstance(reply, Nack) and reply.reason == NackReason.BAD_STATE
    assert reply.detail == pytest.approx(1000, abs=20)
    h.encoder.speed_mps = 0.0
    h.run_ms(300)
    assert _ack_state(h.command(Disarm())) == S.DISARMED
    h.drain(25)
    tel = h.telemetry()[-1]
    assert (tel.state, tel.fault_bits) == (S.DISARMED, 0)
    assert h.transitions()[-1][1:] == (S.FAULT, S.DISARMED, C.COMMAND)


def test_disarm_while_the_rope_is_driven_is_refused(rw_core):
    for state in (S.SPINUP, S.AIRBORNE, S.SPINDOWN):
        h = CoreHarness(rw_core)
        _to_state(h, state)
        reply = h.command(Disarm())
        assert isinstance(reply, Nack) and reply.reason == NackReason.BAD_STATE and reply.state == state


def test_repeated_commands_are_idempotent_acks_without_events(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(600)
    assert _ack_state(h.command(Disarm())) == S.DISARMED
    assert _ack_state(h.command(Spindown())) == S.DISARMED
    assert _ack_state(h.command(Arm())) == S.ARMED
    assert _ack_state(h.command(Arm())) == S.ARMED
    assert _ack_state(h.command(Spindown())) == S.ARMED
    h.drain(5)
    assert [(f, t) for _, f, t, _ in h.transitions()] == [(S.DISARMED, S.ARMED)]
    tel = h.telemetry()
    assert tel[-1].nacks == 0


@pytest.mark.parametrize("extra_ticks", [0, 1, 2, 3])
def test_estop_cuts_the_esc_in_its_own_tick_whatever_the_tick_schedule(rw_core, extra_ticks):
    """The core runs the speed loop on every other tick; ESTOP must not wait for the next speed tick."""
    h = CoreHarness(rw_core)
    _to_state(h, S.AIRBORNE)
    h.follow_setpoint(until=lambda: h.t_ms > 900, max_ms=300, what="steady flight")
    for _ in range(extra_ticks):
        h.tick()
    assert h.pulse_us > 1100
    assert _ack_state(h.command(Estop())) == S.ESTOP
    assert h.pulse_us == 1000
