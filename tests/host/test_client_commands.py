"""Client commands against the real firmware core (core_device.py): retries reuse the seq and execute once,
NACKs become CommandRefused, silence becomes LinkTimeout, ARM waits out NOT_READY with new seqs.

Assertions are on attempts, sequence numbers and what the core did; wall time only as a lower bound."""

from __future__ import annotations

import math
import time

import pytest

from host_settings import FAST, QUICK_ARM
from core_device import CoreDevice, damage, lose_acks, lose_messages
from robowrangler.client import Client
from robowrangler.errors import CommandRefused, InvalidArgument, LinkTimeout, NotConnected, UnknownParameter
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import PARAMS, MsgId, NackReason, State

PAST_HOLD = dict(params=QUICK_ARM, boot_s=0.25)  # booted past the arming hold: ARM is taken at once


def client(device: CoreDevice, **options) -> Client:
    return Client(transport=device.transport(), key=device.key, **{**FAST, **options})


def armed_count(device: CoreDevice) -> int:
    """How many ARMs the core executed (each ACKed once; its ACK leaves in the tick, while the STATE_CHANGED EVENT
    may still be being signed when the test ends)."""
    return device.executed_names().count("ARM")


def test_lost_ack_is_retransmitted_with_the_same_seq_and_executed_once(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        device.to_host.append(lose_acks(MsgId.ARM, 2))
        with client(device) as rw:
            assert rw.arm() == State.ARMED
            stats = rw.stats
            dups = rw.wait_for(lambda s: s.rx_duplicates >= 2, timeout_s=1.0).rx_duplicates
    arms = device.host_sent(MsgId.ARM)
    assert len(arms) == 3 == stats.retransmissions + 1
    assert len({f.seq for f in arms}) == 1 and len({f.payload for f in arms}) == 1
    assert len({f.counter for f in arms}) == 3  # each attempt signed afresh
    assert armed_count(device) == 1 and dups == 2  # the core's duplicate cache answered the copies


def test_each_new_command_gets_a_new_seq(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        with client(device, first_seq=65534) as rw:
            rw.arm()
            rw.spin(5.0)
            rw.spin(6.0)
            target = rw.wait_for(lambda s: s.rope_speed_target_mps == 6.0, timeout_s=1.0).rope_speed_target_mps
    seqs = {f.seq for f in device.host_sent(MsgId.SET_ROPE_SPEED)} | {f.seq for f in device.host_sent(MsgId.ARM)}
    assert len(seqs) == 3
    assert target == 6.0 and armed_count(device) == 1


def test_every_frame_the_client_sends_has_a_fresh_seq_across_the_wrap(device: CoreDevice) -> None:
    with client(device, first_seq=65530) as rw:
        for _ in range(8):
            rw.get_param("tov_mps")
        retransmissions = rw.stats.retransmissions
    seqs = [f.seq for f in device.host_sent()]
    assert seqs[0] == 65530 and 0 in seqs
    assert len(set(seqs)) == len(seqs) - retransmissions  # heartbeats and commands share one counter


def test_nack_raises_command_refused_with_reason_state_detail_and_advice(device: CoreDevice) -> None:
    with client(device) as rw:
        rw.arm(timeout_s=2.0)
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=2.0)
        with pytest.raises(CommandRefused) as info:
            rw.spin(2.0)
        target = rw.wait_for(lambda s: True, timeout_s=1.0).rope_speed_target_mps
    err = info.value
    assert err.reason == NackReason.BELOW_TOV_GUARD and err.state == State.AIRBORNE and err.detail == 2990
    assert str(err) == ("SET_ROPE_SPEED refused: BELOW_TOV_GUARD: 2 m/s is under the ToV guard 2.99 m/s "
                        "while airborne; command spindown to land")
    assert target == 5.0  # the refused setpoint changed nothing


def test_bad_state_nack_says_what_to_do(device: CoreDevice) -> None:
    with client(device) as rw, pytest.raises(CommandRefused) as info:
        rw.spin(5.0)
    assert info.value.reason == NackReason.BAD_STATE and "not accepted in state DISARMED; arm first" in str(info.value)


def test_out_of_range_values_are_sent_for_the_device_to_refuse(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device) as rw:
        rw.arm()
        with pytest.raises(CommandRefused) as speed:
            rw.spin(-1.0)
        with pytest.raises(CommandRefused) as too_fast:
            rw.spin(30.0)
        with pytest.raises(CommandRefused) as param:
            rw.set_param("tov_mps", math.inf)
    assert speed.value.reason == NackReason.OUT_OF_RANGE
    assert too_fast.value.reason == NackReason.OUT_OF_RANGE and "limit crossed: 20 m/s" in str(too_fast.value)
    assert param.value.reason == NackReason.OUT_OF_RANGE and "tov_mps = inf is outside [0.5, 10] m/s" in str(param.value)
    assert len({f.seq for f in device.host_sent(MsgId.SET_ROPE_SPEED)}) == 2
    assert len({f.seq for f in device.host_sent(MsgId.PARAM_SET)}) == 1


def test_a_device_that_never_hears_gives_link_timeout_after_retries_plus_one_ack_timeouts(device: CoreDevice) -> None:
    with client(device) as rw:
        device.to_device.append(lose_messages(gen.Arm))  # telemetry flows, the ARMs are lost on the way
        start = time.monotonic()
        with pytest.raises(LinkTimeout) as info:
            rw.arm()
        elapsed = time.monotonic() - start
    assert elapsed >= (FAST["retries"] + 1) * FAST["ack_timeout_s"]
    assert info.value.url == device.url and device.url in str(info.value) and "4 attempts" in str(info.value)
    arms = device.host_sent(MsgId.ARM)
    assert len(arms) == FAST["retries"] + 1 and len({f.seq for f in arms}) == 1
    assert armed_count(device) == 0


def test_arm_retries_not_ready_with_new_seqs_until_the_hold_ends(core_lib) -> None:
    first_arm_s: list[float] = []  # the device's time when the first ARM reached it

    def note_arm(data: bytes) -> bytes:
        if not first_arm_s and gen.decode_frame(data).msg_id == MsgId.ARM:
            first_arm_s.append(device.time_s)
        return data

    with CoreDevice(core_lib, params={"arm_hold_s": 1.0}) as device:
        device.to_device.append(note_arm)
        with client(device) as rw:
            # timeout: a bound; the hold runs on the device's clock, which a busy machine slows
            assert rw.arm(timeout_s=15.0) == State.ARMED
            nacks = rw.stats.nacks
    seqs = {f.seq for f in device.host_sent(MsgId.ARM)}
    assert armed_count(device) == 1 and nacks >= len(seqs) - 1  # every ARM but the last was refused NOT_READY
    if first_arm_s[0] < 0.95:  # asked inside the hold (always, unless a very busy machine delayed the host 1 s)
        assert len(seqs) >= 2, first_arm_s


def test_arm_waits_out_the_hold_on_the_devices_clock_when_the_device_runs_slow(core_lib) -> None:
    # a device at a quarter of real time (a SIL on a busy machine): its 0.4 s hold takes 1.6 s of wall time,
    # longer than ARM's 1 s timeout, which counts the device's time
    with CoreDevice(core_lib, speedup=0.25, params={"arm_hold_s": 0.4}) as device, client(device) as rw:
        rw.wait_for(lambda s: True, timeout_s=10.0)  # the device's clock is known
        start_s = time.monotonic()
        assert rw.arm(timeout_s=1.0) == State.ARMED
        waited_s = time.monotonic() - start_s
        nacks = rw.stats.nacks
    assert nacks >= 1 and len({f.seq for f in device.host_sent(MsgId.ARM)}) == nacks + 1  # refused, then ACKed
    assert waited_s > 1.0  # lower bound: the wait outlasted the timeout in wall time, as the slow clock needs


def test_arm_gives_up_on_not_ready_at_its_timeout(core_lib) -> None:
    with CoreDevice(core_lib, params={"arm_hold_s": 5.0}) as device, client(device) as rw:
        with pytest.raises(CommandRefused) as info:
            rw.arm(timeout_s=0.3)
    assert info.value.reason == NackReason.NOT_READY and "retry in a moment" in str(info.value)
    assert len({f.seq for f in device.host_sent(MsgId.ARM)}) >= 2 and armed_count(device) == 0


def test_arm_does_not_retry_other_refusals(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device) as rw:
        rw.arm()
        rw.spin(5.0)
        with pytest.raises(CommandRefused) as info:  # spinning: BAD_STATE, not worth a retry
            rw.arm(timeout_s=2.0)
    assert info.value.reason == NackReason.BAD_STATE
    assert len({f.seq for f in device.host_sent(MsgId.ARM)}) == 2


def test_connect_to_a_device_that_does_not_run_is_a_link_timeout_naming_the_url(core_lib) -> None:
    quiet = CoreDevice(core_lib, link="serial")  # never started: no tick, no answer
    rw = Client(transport=quiet.transport(), **{**FAST, "connect_timeout_s": 0.3})
    start = time.monotonic()
    with pytest.raises(LinkTimeout) as info:
        rw.connect()
    assert time.monotonic() - start >= 0.3
    assert quiet.url in str(info.value) and not rw.connected
    sent = [f.msg_id for f in quiet.host_sent()]
    assert sent[0] == MsgId.HELLO and MsgId.HEARTBEAT in sent  # connecting = HELLO, heartbeats, then telemetry


def test_commands_need_a_connection(device: CoreDevice) -> None:
    rw = client(device)
    with pytest.raises(NotConnected, match="connect"):
        rw.arm()


def test_params_get_set_and_list(device: CoreDevice) -> None:
    with client(device) as rw:
        assert rw.get_param("tov_mps") == 2.6
        assert rw.set_param("tov_margin", 1.25) == 1.25
        assert rw.get_param("tov_margin") == 1.25
        values = rw.params()
        rw.arm(timeout_s=2.0)
        with pytest.raises(CommandRefused) as locked:
            rw.set_param("wheel_radius_m", 0.02)
    assert values["tov_margin"] == 1.25 and values["encoder_counts_per_rev"] == 64.0 and len(values) == len(PARAMS)
    assert locked.value.reason == NackReason.PARAM_LOCKED and "disarm first" in str(locked.value)


def test_lost_param_value_is_asked_again(device: CoreDevice) -> None:
    device.to_host.append(lose_messages(gen.ParamValue, 1))
    with client(device) as rw:
        assert rw.set_param("tov_mps", 3.0) == 3.0
    assert len({f.seq for f in device.host_sent(MsgId.PARAM_SET)}) == 1
    assert len({f.seq for f in device.host_sent(MsgId.PARAM_GET)}) == 1


def test_local_argument_errors_send_nothing(device: CoreDevice) -> None:
    with client(device) as rw:
        with pytest.raises(UnknownParameter, match="did you mean tov_mps"):
            rw.get_param("tov")
        with pytest.raises(InvalidArgument, match="tov_mps: expected a real number, not NaN"):
            rw.set_param("tov_mps", math.nan)
        with pytest.raises(InvalidArgument, match="rope_speed_mps"):
            rw.spin(math.nan)
        with pytest.raises(InvalidArgument, match="rope_speed_mps"):
            rw.spin("5")
    assert {f.msg_id for f in device.host_sent()} == {MsgId.HELLO, MsgId.HEARTBEAT}


def test_an_injected_udp_transport_is_used_and_closed(core_lib) -> None:
    from robowrangler.transport_udp import UdpTransport

    with CoreDevice(core_lib, **PAST_HOLD) as device:
        transport = UdpTransport("127.0.0.1", device.port)
        with Client(transport=transport, key=device.key, **FAST) as rw:
            assert rw.url == device.url and rw.arm() == State.ARMED
        assert transport.recv(0.01) is None and transport._closed


def test_a_frame_damaged_on_the_way_is_sent_again_at_once_with_the_same_seq(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        device.to_device.append(damage(MsgId.ARM, 2))  # the core answers BAD_CHECKSUM twice
        with client(device) as rw:
            assert rw.arm() == State.ARMED
            stats = rw.stats
    arms = device.host_sent(MsgId.ARM)
    assert len(arms) == 3 and len({f.seq for f in arms}) == 1
    assert stats.transit_nacks == 2 and stats.retransmissions == 2  # no ack timeout was waited out
    assert armed_count(device) == 1


def test_a_link_that_damages_every_attempt_ends_in_the_last_refusal(device: CoreDevice) -> None:
    device.to_device.append(damage(MsgId.ARM, FAST["retries"] + 1))
    with client(device) as rw, pytest.raises(CommandRefused) as info:
        rw.arm()
    assert info.value.reason == NackReason.BAD_CHECKSUM and "the link corrupts data" in str(info.value)
    assert len(device.host_sent(MsgId.ARM)) == FAST["retries"] + 1 and armed_count(device) == 0


def test_late_duplicates_of_older_param_values_are_not_taken_for_the_answer(core_lib) -> None:
    """On the (unsigned) serial link a late PARAM_VALUE of an older request looks like any other; the client
    takes a value only after its request's ACK (PARAM_GET), or only the value it wrote (PARAM_SET)."""
    with CoreDevice(core_lib, link="serial") as device:
        with Client(transport=device.transport(), **FAST) as rw:
            old = []
            for value in (9.5, 1.0):  # answers the core really sent for earlier requests
                rw.set_param("tov_mps", value)
                old.append(next(o.raw for o in reversed(device.outputs()) if isinstance(o.msg, gen.ParamValue)))

            def around_answers(data: bytes):
                _, msg = gen.decode_message(data)
                if isinstance(msg, gen.Ack) and msg.cmd_msg_id == MsgId.PARAM_SET:
                    return old + [data] + old  # on both sides of the ACK
                if isinstance(msg, gen.Ack) and msg.cmd_msg_id == MsgId.PARAM_GET:
                    return old + [data]
                return data

            device.to_host.append(around_answers)
            before = rw.stats.stale_param_values
            assert rw.set_param("tov_mps", 3.25) == 3.25
            assert rw.get_param("tov_mps") == 3.25
            stale = rw.stats.stale_param_values - before
    assert stale == 6
