"""Spindle and grasp commands from the client side, against the real firmware core and a lead-screw servo
(core_device.py, FakeSpindle): SI arguments on the wire, refusals with advice, spindle telemetry and events in SI."""

from __future__ import annotations

import math

import pytest

from host_settings import FAST
from core_device import CoreDevice
from core_harness import FakeSpindle
from robowrangler.client import Client
from robowrangler.errors import CommandRefused, InvalidArgument, StateTimeout
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import Cause, EventKind, MsgId, NackReason, SpindleFlag, State

LEAD_MM_PER_REV = 20.0  # a fast lead screw (the servo's 59 rpm give about 20 mm/s) keeps the tests short
FAST_SPINDLE = {"arm_hold_s": 0.2, "lead_mm_per_rev": LEAD_MM_PER_REV, "spindle_max_speed_mmps": 15.0,
                "homing_speed_mmps": 15.0}


def spindle_device(core_lib, **spindle_options) -> CoreDevice:
    spindle = FakeSpindle(lead_mm_per_rev=LEAD_MM_PER_REV, **spindle_options)
    return CoreDevice(core_lib, params=FAST_SPINDLE, spindle=spindle, boot_s=0.25, speedup=2.0)


def client(device: CoreDevice) -> Client:
    return Client(transport=device.transport(), key=device.key, **FAST)


def homed(rw: Client) -> None:
    rw.home()
    rw.wait_for(lambda s: SpindleFlag.HOMED in s.spindle_flags, timeout_s=5.0, expected="a homed spindle")


def test_home_then_set_loop_moves_the_guide_in_si(core_lib) -> None:
    with spindle_device(core_lib) as device, client(device) as rw:
        rw.arm()
        with pytest.raises(CommandRefused) as not_homed:
            rw.set_loop(0.05)
        homed(rw)
        assert rw.set_loop(0.0225) == State.ARMED
        rw.wait_for(lambda s: any(e.kind == EventKind.SPINDLE_TARGET_REACHED for e in rw.events), timeout_s=5.0)
        reached = rw.wait_for(lambda s: True, timeout_s=1.0)
        events = rw.events
    assert not_homed.value.reason == NackReason.NOT_HOMED and "command home first" in str(not_homed.value)
    assert reached.guide_target_m == 0.0225 and SpindleFlag.HOMED in reached.spindle_flags
    assert reached.guide_position_m == pytest.approx(0.0225, abs=0.6e-3)  # within spindle_tolerance_mm
    on_wire_um = [gen.decode_message(gen.encode_frame(gen.SetLoop.unpack(f.payload), f.seq))[1].guide_position_um
                  for f in device.host_sent(MsgId.SET_LOOP)]
    assert set(on_wire_um) == {50000, 22500}
    kinds = [e.kind for e in events]
    assert EventKind.SPINDLE_HOMED in kinds and events[kinds.index(EventKind.SPINDLE_HOMED)].homed_by == "stall"
    target = [e for e in events if e.kind == EventKind.SPINDLE_TARGET_REACHED][-1]
    assert target.guide_position_m == pytest.approx(0.0225, abs=0.6e-3)
    assert target.describe().startswith("SPINDLE_TARGET_REACHED") and "(guide at 22." in target.describe()


def test_set_loop_outside_the_soft_limits_is_sent_and_refused(core_lib) -> None:
    with spindle_device(core_lib) as device, client(device) as rw:
        rw.arm()
        homed(rw)
        with pytest.raises(CommandRefused) as info:
            rw.set_loop(0.2)
        with pytest.raises(InvalidArgument, match="guide_position_m"):
            rw.set_loop(math.nan)
    assert info.value.reason == NackReason.OUT_OF_RANGE
    assert "guide position 200 mm is outside the soft limits (limit crossed: 180 mm" in str(info.value)


def test_grasp_relaxes_retracts_and_holds_the_object(core_lib) -> None:
    with spindle_device(core_lib) as device, client(device) as rw:
        device.spindle.object_mm = 15.0
        rw.arm()
        homed(rw)
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=2.0)
        assert rw.grasp() == State.RELAX
        held = rw.wait_for_state([State.HOLD, State.ARMED], timeout_s=10.0)
        assert rw.release() == State.ARMED
        rw.wait_for_state(State.ARMED, timeout_s=1.0)  # telemetry after the ACK: its event is in by then
        events = [e for e in rw.events if e.kind == EventKind.STATE_CHANGED]
    assert held.state == State.HOLD and held.rope_speed_mps == 0.0
    assert held.guide_position_m == pytest.approx(0.015, abs=1e-3)
    path = [(e.state_to, e.cause) for e in events][-4:]
    assert path == [(State.RELAX, Cause.COMMAND), (State.RETRACT, Cause.SPEED_REACHED),
                    (State.HOLD, Cause.LOAD_SECURED), (State.ARMED, Cause.COMMAND)]


def test_retract_without_an_object_ends_at_the_stroke_end(core_lib) -> None:
    with spindle_device(core_lib) as device, client(device) as rw:
        rw.set_param("guide_max_mm", 30.0)  # a short stroke keeps the test short
        rw.arm()
        homed(rw)
        assert rw.retract() == State.RETRACT
        rw.wait_for_state(State.RETRACT, timeout_s=1.0)  # a sample packed before the command may still arrive
        end = rw.wait_for_state(State.ARMED, timeout_s=10.0)
        last = [e for e in rw.events if e.kind == EventKind.STATE_CHANGED][-1]
    assert end.guide_position_m == pytest.approx(0.03, abs=1e-3) and last.cause == Cause.STROKE_END


@pytest.mark.parametrize("call, advice", [
    ("grasp", "grasp needs AIRBORNE: spin up above the ToV guard first"),
    ("release", "release needs HOLD"),
    ("relax", "relax needs a spinning rope"),
])
def test_grasp_commands_in_the_wrong_state_say_what_they_need(core_lib, call: str, advice: str) -> None:
    with spindle_device(core_lib) as device, client(device) as rw:
        rw.arm()
        homed(rw)
        with pytest.raises(CommandRefused) as info:
            getattr(rw, call)()
    assert info.value.reason == NackReason.BAD_STATE and advice in str(info.value)


def test_an_unanswering_spindle_is_reported_with_its_fault_bits(core_lib) -> None:
    with spindle_device(core_lib) as device, client(device) as rw, pytest.raises(CommandRefused) as info:
        device.spindle.answering = False
        rw.wait_for(lambda s: SpindleFlag.ANSWERING not in s.spindle_flags, timeout_s=2.0)
        rw.home()
    assert info.value.reason == NackReason.SPINDLE_UNAVAILABLE and "fault bits 0x10" in str(info.value)


def test_wait_for_a_condition_that_never_comes_names_it(device: CoreDevice) -> None:
    with client(device) as rw, pytest.raises(StateTimeout) as info:
        rw.wait_for(lambda s: s.guide_position_m > 1.0, timeout_s=0.1, expected="the guide past 1 m")
    assert str(info.value) == "state: expected the guide past 1 m within 0.1 s, still DISARMED"
