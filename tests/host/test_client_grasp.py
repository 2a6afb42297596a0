"""Spindle and grasp commands from the client side: SI arguments on the wire, refusals with advice,
spindle telemetry and events in SI."""

from __future__ import annotations

import math

import pytest

from conftest import FAST
from robowrangler.client import Client
from robowrangler.errors import CommandRefused, InvalidArgument, StateTimeout
from robowrangler.protocol.generated import Cause, EventKind, MsgId, NackReason, SpindleFlag, State
from scripted_device import ScriptedDevice


def homed(rw: Client) -> None:
    rw.home()
    rw.wait_for(lambda s: SpindleFlag.HOMED in s.spindle_flags, timeout_s=1.0, expected="a homed spindle")


def test_home_then_set_loop_moves_the_guide_in_si(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        rw.arm()
        with pytest.raises(CommandRefused) as not_homed:
            rw.set_loop(0.05)
        homed(rw)
        assert rw.set_loop(0.0625) == State.ARMED
        reached = rw.wait_for(lambda s: abs(s.guide_position_m - 0.0625) < 1e-6, timeout_s=1.0)
        events = rw.events
    assert not_homed.value.reason == NackReason.NOT_HOMED and "command home first" in str(not_homed.value)
    assert reached.guide_target_m == 0.0625 and SpindleFlag.HOMED in reached.spindle_flags
    on_wire_um = [m.guide_position_um for f, m in device.received if f.msg_id == MsgId.SET_LOOP]
    assert on_wire_um == [50000, 62500]
    kinds = [e.kind for e in events]
    assert EventKind.SPINDLE_HOMED in kinds and events[kinds.index(EventKind.SPINDLE_HOMED)].homed_by == "stall"
    target = [e for e in events if e.kind == EventKind.SPINDLE_TARGET_REACHED][-1]
    assert target.guide_position_m == 0.0625 and target.describe().endswith("(guide at 62.5 mm)")


def test_set_loop_outside_the_soft_limits_is_sent_and_refused(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        rw.arm()
        homed(rw)
        with pytest.raises(CommandRefused) as info:
            rw.set_loop(0.2)
        with pytest.raises(InvalidArgument, match="guide_position_m"):
            rw.set_loop(math.nan)
    assert info.value.reason == NackReason.OUT_OF_RANGE
    assert "guide position 200 mm is outside the soft limits (limit crossed: 180 mm" in str(info.value)


def test_grasp_relaxes_retracts_and_holds_the_object(device: ScriptedDevice) -> None:
    device.object_at_m = 0.1
    with Client(device.url, **FAST) as rw:
        rw.arm()
        homed(rw)
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=1.0)
        assert rw.grasp() == State.RELAX
        held = rw.wait_for_state([State.HOLD, State.ARMED], timeout_s=2.0)
        assert rw.release() == State.ARMED
        rw.wait_for_state(State.ARMED, timeout_s=1.0)  # telemetry after the ACK: its event is in by then
        events = [e for e in rw.events if e.kind == EventKind.STATE_CHANGED]
    assert held.state == State.HOLD and held.spindle_load_pct == 15.0 and held.rope_speed_mps == 0.0
    path = [(e.state_to, e.cause) for e in events][-4:]
    assert path == [(State.RELAX, Cause.COMMAND), (State.RETRACT, Cause.SPEED_REACHED),
                    (State.HOLD, Cause.LOAD_SECURED), (State.ARMED, Cause.COMMAND)]


def test_retract_without_an_object_ends_at_the_stroke_end(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        rw.arm()
        homed(rw)
        assert rw.retract() == State.RETRACT
        end = rw.wait_for_state(State.ARMED, timeout_s=2.0)
        last = rw.events[-1]
    assert end.guide_position_m == pytest.approx(0.18) and last.cause == Cause.STROKE_END


@pytest.mark.parametrize("call, advice", [
    ("grasp", "grasp needs AIRBORNE: spin up above the ToV guard first"),
    ("release", "release needs HOLD"),
    ("relax", "relax needs a spinning rope"),
])
def test_grasp_commands_in_the_wrong_state_say_what_they_need(device: ScriptedDevice, call: str, advice: str) -> None:
    with Client(device.url, **FAST) as rw:
        rw.arm()
        with pytest.raises(CommandRefused) as info:
            getattr(rw, call)()
    assert info.value.reason == NackReason.BAD_STATE and advice in str(info.value)


def test_an_unanswering_spindle_is_reported_with_its_fault_bits(device: ScriptedDevice) -> None:
    device.spindle_unavailable = True
    with Client(device.url, **FAST) as rw, pytest.raises(CommandRefused) as info:
        rw.home()
    assert info.value.reason == NackReason.SPINDLE_UNAVAILABLE and "fault bits 0x10" in str(info.value)


def test_wait_for_a_condition_that_never_comes_names_it(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw, pytest.raises(StateTimeout) as info:
        rw.wait_for(lambda s: s.guide_position_m > 1.0, timeout_s=0.1, expected="the guide past 1 m")
    assert str(info.value) == "state: expected the guide past 1 m within 0.1 s, still DISARMED"
