"""rw_core grasp states with a fake AX-12A spindle: HOME (stall or switch), GRASP = RELAX -> RETRACT ->
HOLD with their STATE_CHANGED causes, RELEASE, stroke end, ESTOP and heartbeat loss in the grasp
states, spindle refusals (SPINDLE_UNAVAILABLE, NOT_HOMED), the spindle still while DISARMED/ESTOP."""

from __future__ import annotations

import pytest

from core_harness import CoreHarness, FakeSpindle
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import (
    Ack, Arm, Cause, Disarm, Estop, EventKind, Fault, Nack, NackReason, SetRopeSpeed, State,
)

S = State
C = Cause
FAST = {"retract_speed_mmps": 15.0, "homing_speed_mmps": 10.0}


def _ack(reply) -> State:
    assert isinstance(reply, Ack), f"expected ACK, got {reply}"
    return State(reply.state)


def _nack(reply, reason: NackReason) -> Nack:
    assert isinstance(reply, Nack) and reply.reason == reason, f"expected NACK {reason.name}, got {reply}"
    return reply


def _ticks(h: CoreHarness, ms: int, *, heartbeat: bool = True) -> None:
    for _ in range(ms):
        if heartbeat and h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()


def _homed(rw_core, **spindle_kw) -> CoreHarness:
    h = CoreHarness(rw_core, params=FAST, spindle=FakeSpindle(**spindle_kw))
    h.tick()
    h.run_ms(600)
    assert _ack(h.command(proto.Home())) == S.DISARMED
    h.run_until(lambda: h.events(EventKind.SPINDLE_HOMED) != [], max_ms=3000, what="SPINDLE_HOMED")
    return h


def _grasp_to(h: CoreHarness, state: State) -> None:
    """From homed + DISARMED through ARM, flight, GRASP, landing and retraction to `state`."""
    assert _ack(h.command(Arm())) == S.ARMED
    h.spin_to_airborne(target_mmps=4000)
    assert _ack(h.command(proto.Grasp())) == S.RELAX
    if state == S.RELAX:
        return
    h.follow_setpoint(until=lambda: h.state not in (S.AIRBORNE, S.RELAX), max_ms=2000, what="landed, retracting")
    if state == S.RETRACT:
        assert h.state == S.RETRACT
        return
    for _ in range(20000):
        if h.state != S.RETRACT:
            break
        _ticks(h, 1)
    h.drain(3)
    assert h.state == state


def test_spindle_commands_without_a_spindle_are_refused_unavailable(rw_core):
    h = CoreHarness(rw_core)  # no spindle fitted
    h.tick()
    h.run_ms(600)
    _nack(h.command(proto.Home()), NackReason.SPINDLE_UNAVAILABLE)
    h.command(Arm())
    h.spin_to_airborne(target_mmps=4000)
    _nack(h.command(proto.Grasp()), NackReason.SPINDLE_UNAVAILABLE)
    _nack(h.command(proto.SetLoop(50_000)), NackReason.SPINDLE_UNAVAILABLE)
    h.drain(3)
    assert h.state == S.AIRBORNE


def test_spindle_moves_need_homing_first(rw_core):
    h = CoreHarness(rw_core, spindle=FakeSpindle())
    h.boot_and_arm()
    _nack(h.command(proto.SetLoop(50_000)), NackReason.NOT_HOMED)
    _nack(h.command(proto.Retract()), NackReason.NOT_HOMED)
    h.spin_to_airborne(target_mmps=4000)
    _nack(h.command(proto.Grasp()), NackReason.NOT_HOMED)
    h.drain(3)
    assert h.state == S.AIRBORNE
    assert not h.spindle.moving


@pytest.mark.parametrize("has_switch, arg", [(False, 1), (True, 2)])
def test_home_against_the_end_stop_or_switch(rw_core, has_switch, arg):
    h = _homed(rw_core, has_switch=has_switch, start_mm=6.0)
    (homed,) = h.events(EventKind.SPINDLE_HOMED)
    assert homed.arg == arg, "1 = by stall, 2 = by switch"
    assert h.spindle.x_mm == pytest.approx(0.0, abs=0.6)
    h.run_ms(50)
    tel = h.telemetry()[-1]
    assert tel.spindle_flags & proto.SpindleFlag.HOMED
    assert abs(tel.guide_position_um) < 600
    assert not h.spindle.moving, "stopped once homed"


def test_grasp_relaxes_lands_retracts_and_holds_the_object(rw_core):
    h = _homed(rw_core)
    h.spindle.object_mm = 60.0
    _grasp_to(h, S.HOLD)
    steps = [(f, t, c) for _, f, t, c in h.transitions()]
    assert steps[-3:] == [(S.AIRBORNE, S.RELAX, C.COMMAND), (S.RELAX, S.RETRACT, C.SPEED_REACHED),
                          (S.RETRACT, S.HOLD, C.LOAD_SECURED)]
    assert h.pulse_us == 1000, "the rope is not driven while retracting or holding"
    assert h.spindle.x_mm == pytest.approx(60.0, abs=0.5)
    assert not h.spindle.moving
    # RELEASE: back to ARMED, the guide extends by release_mm (20 mm).
    assert _ack(h.command(proto.Release())) == S.ARMED
    for _ in range(10000):  # a host stays on the link (a silent one would stop the guide: heartbeat loss)
        if h.events(EventKind.SPINDLE_TARGET_REACHED):
            break
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
    assert h.events(EventKind.SPINDLE_TARGET_REACHED), "released"
    (reached,) = h.events(EventKind.SPINDLE_TARGET_REACHED)
    assert reached.arg == pytest.approx(40_000, abs=600), "arg = guide position, um"
    assert h.spindle.x_mm == pytest.approx(40.0, abs=0.6)


def test_retract_with_nothing_caught_ends_at_the_stroke(rw_core):
    h = _homed(rw_core)
    h.set_param("guide_max_mm", 40.0)
    _grasp_to(h, S.ARMED)
    assert h.transitions()[-1][1:] == (S.RETRACT, S.ARMED, C.STROKE_END)
    assert h.spindle.x_mm == pytest.approx(40.0, abs=0.5)


@pytest.mark.parametrize("state", [S.RELAX, S.RETRACT, S.HOLD])
def test_estop_in_a_grasp_state_stops_rope_and_spindle_at_once(rw_core, state):
    h = _homed(rw_core)
    h.spindle.object_mm = 30.0
    _grasp_to(h, state)
    assert _ack(h.command(Estop())) == S.ESTOP
    assert h.pulse_us == 1000
    assert h.spindle.writes[-1] == 0, "the spindle is stopped in the ESTOP tick"
    _ticks(h, 300)
    assert set(h.spindle.writes[-30:]) == {0}
    _nack(h.command(proto.Release()), NackReason.BAD_STATE)
    _nack(h.command(proto.Retract()), NackReason.BAD_STATE)


def test_heartbeat_loss_while_retracting_stops_the_spindle(rw_core):
    h = _homed(rw_core)
    _grasp_to(h, S.RETRACT)
    h.heartbeat()
    h.tick()
    t_last = h.t_ms
    h.run_ms(520)
    h.drain(3)
    t, f, to, cause = h.transitions()[-1]
    assert (f, to, cause) == (S.RETRACT, S.ARMED, C.HEARTBEAT_LOST)
    assert 500 < t - t_last <= 501
    assert not h.spindle.moving


def test_spindle_silence_while_retracting_is_a_fault_and_makes_it_unavailable(rw_core):
    h = _homed(rw_core)
    _grasp_to(h, S.RETRACT)
    h.spindle.answering = False
    _ticks(h, 400)
    h.drain(3)
    (raised,) = h.events(EventKind.FAULT_RAISED)
    assert raised.arg == Fault.SPINDLE_NO_ANSWER
    assert h.transitions()[-1][1:] == (S.RETRACT, S.ARMED, C.FAULT)
    assert not h.spindle.moving
    h.spindle.answering = True
    reply = _nack(h.command(proto.Retract()), NackReason.SPINDLE_UNAVAILABLE)
    assert reply.detail & Fault.SPINDLE_NO_ANSWER


def test_spindle_still_while_disarmed_except_homing(rw_core):
    h = CoreHarness(rw_core, spindle=FakeSpindle())
    h.tick()
    h.run_ms(600)
    _nack(h.command(proto.SetLoop(50_000)), NackReason.BAD_STATE)
    h.run_ms(100)
    assert h.spindle.writes and set(h.spindle.writes) == {0}


def test_grasp_is_refused_unless_airborne(rw_core):
    h = _homed(rw_core)
    h.command(Arm())
    _nack(h.command(proto.Grasp()), NackReason.BAD_STATE)
    h.command(SetRopeSpeed(2000))
    _nack(h.command(proto.Grasp()), NackReason.BAD_STATE)
    _nack(h.command(Disarm()), NackReason.BAD_STATE)


def test_set_loop_is_range_checked_with_the_limit_and_moves_the_guide(rw_core):
    h = _homed(rw_core)
    h.command(Arm())
    reply = _nack(h.command(proto.SetLoop(180_001)), NackReason.OUT_OF_RANGE)
    assert reply.detail == 180_000, "detail = guide_max_mm, um"
    h.set_param("guide_min_mm", 5.0)
    reply = _nack(h.command(proto.SetLoop(4_999)), NackReason.OUT_OF_RANGE)
    assert reply.detail == 5_000
    assert not h.spindle.moving
    assert _ack(h.command(proto.SetLoop(25_000))) == S.ARMED
    for _ in range(10000):
        if h.events(EventKind.SPINDLE_TARGET_REACHED):
            break
        _ticks(h, 1)
    (reached,) = h.events(EventKind.SPINDLE_TARGET_REACHED)
    assert reached.arg == pytest.approx(25_000, abs=600)
    assert h.spindle.x_mm == pytest.approx(25.0, abs=0.6)
