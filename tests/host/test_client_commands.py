"""Client commands against a scripted UDP device: retries reuse the seq, NACKs become CommandRefused,
silence becomes LinkTimeout, ARM waits out NOT_READY with new seqs."""

from __future__ import annotations

import math
import time

import pytest

from conftest import FAST
from robowrangler.client import Client
from robowrangler.errors import CommandRefused, InvalidArgument, LinkTimeout, NotConnected, UnknownParameter
from robowrangler.protocol.generated import PARAMS, MsgId, NackReason, State
from scripted_device import ScriptedDevice


def test_lost_ack_is_retransmitted_with_the_same_seq_and_bytes_and_executed_once(device: ScriptedDevice) -> None:
    device.drop_replies[MsgId.ARM] = 2
    with Client(device.url, **FAST) as rw:
        assert rw.arm() == State.ARMED
        stats = rw.stats
    frames = device.received_commands(MsgId.ARM)
    assert len(frames) == 3
    assert len({seq for seq, _ in frames}) == 1 and len({raw for _, raw in frames}) == 1
    assert device.executed_names() == ["ARM"]
    assert device.duplicates == 2
    assert stats.retransmissions == 2


def test_each_new_command_gets_a_new_seq(device: ScriptedDevice) -> None:
    with Client(device.url, first_seq=65534, **FAST) as rw:
        rw.arm()
        rw.spin(5.0)
        rw.spin(6.0)
    seqs = [seq for seq, _ in device.received_commands(MsgId.SET_ROPE_SPEED)] + \
        [seq for seq, _ in device.received_commands(MsgId.ARM)]
    assert len(set(seqs)) == 3
    assert device.executed_names() == ["ARM", "SET_ROPE_SPEED", "SET_ROPE_SPEED"]


def test_every_frame_the_client_sends_has_a_fresh_seq_across_the_wrap(device: ScriptedDevice) -> None:
    with Client(device.url, first_seq=65530, **FAST) as rw:
        for _ in range(8):
            rw.get_param("tov_mps")
    with device.lock:
        seqs = [f.seq for f, _ in device.received]
    assert seqs[0] == 65530 and 0 in seqs
    assert len(seqs) == len(set(seqs))  # heartbeats and commands share one counter


def test_nack_raises_command_refused_with_reason_state_detail_and_advice(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        rw.arm()
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=1.0)
        with pytest.raises(CommandRefused) as info:
            rw.spin(2.0)
    err = info.value
    assert err.reason == NackReason.BELOW_TOV_GUARD and err.state == State.AIRBORNE and err.detail == 2990
    assert str(err) == ("SET_ROPE_SPEED refused: BELOW_TOV_GUARD: 2 m/s is under the ToV guard 2.99 m/s "
                        "while airborne; command spindown to land")
    assert device.executed_names().count("SET_ROPE_SPEED") == 1


@pytest.mark.parametrize("first_command, reason, text", [
    ("spin", NackReason.BAD_STATE, "not accepted in state DISARMED; arm first"),
    ("disarm", NackReason.BAD_STATE, "not accepted in state DISARMED"),
])
def test_bad_state_nack_says_what_to_do(device: ScriptedDevice, first_command: str, reason: NackReason,
                                        text: str) -> None:
    with Client(device.url, **FAST) as rw, pytest.raises(CommandRefused) as info:
        getattr(rw, first_command)(*([5.0] if first_command == "spin" else []))
    assert info.value.reason == reason and text in str(info.value)


def test_out_of_range_values_are_sent_for_the_device_to_refuse(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
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
    assert len(device.received_commands(MsgId.SET_ROPE_SPEED)) == 2
    assert len(device.received_commands(MsgId.PARAM_SET)) == 1


def test_silent_device_gives_link_timeout_after_retries_plus_one_ack_timeouts(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        device.silent = True
        start = time.monotonic()
        with pytest.raises(LinkTimeout) as info:
            rw.arm()
        elapsed = time.monotonic() - start
    budget = (FAST["retries"] + 1) * FAST["ack_timeout_s"]
    assert budget <= elapsed < budget + 0.3  # slack for a loaded 2-core machine
    assert info.value.url == device.url and device.url in str(info.value) and "4 attempts" in str(info.value)
    frames = device.received_commands(MsgId.ARM)
    assert len(frames) == FAST["retries"] + 1 and len({seq for seq, _ in frames}) == 1
    assert device.executed_names() == []


def test_arm_retries_not_ready_with_new_seqs_until_the_hold_ends() -> None:
    with ScriptedDevice(arm_hold_s=0.4) as device, Client(device.url, **FAST) as rw:
        assert rw.arm(timeout_s=2.0) == State.ARMED
    seqs = [seq for seq, _ in device.received_commands(MsgId.ARM)]
    assert device.nacks_sent == len(seqs) - 1 >= 1  # every ARM but the last was refused NOT_READY
    assert len(seqs) == len(set(seqs))
    assert device.executed_names() == ["ARM"]


def test_arm_gives_up_on_not_ready_at_its_timeout() -> None:
    with ScriptedDevice(arm_hold_s=5.0) as device, Client(device.url, **FAST) as rw:
        start = time.monotonic()
        with pytest.raises(CommandRefused) as info:
            rw.arm(timeout_s=0.3)
        assert time.monotonic() - start < 0.8
    assert info.value.reason == NackReason.NOT_READY and "retry in a moment" in str(info.value)


def test_arm_does_not_retry_other_refusals(device: ScriptedDevice) -> None:
    device.nack_script[MsgId.ARM] = [(NackReason.BAD_STATE, 0)]
    with Client(device.url, **FAST) as rw, pytest.raises(CommandRefused):
        rw.arm(timeout_s=2.0)
    assert len(device.received_commands(MsgId.ARM)) == 1


def test_connect_to_nobody_is_a_link_timeout_naming_the_url() -> None:
    with ScriptedDevice(telemetry_hz=0) as quiet:
        rw = Client(quiet.url, **{**FAST, "connect_timeout_s": 0.3})
        start = time.monotonic()
        with pytest.raises(LinkTimeout) as info:
            rw.connect()
        assert 0.3 <= time.monotonic() - start < 0.9
        assert quiet.url in str(info.value) and not rw.connected
        assert len(quiet.received_commands(MsgId.HEARTBEAT)) >= 2  # connecting = heartbeats, then telemetry


def test_commands_need_a_connection(device: ScriptedDevice) -> None:
    rw = Client(device.url, **FAST)
    with pytest.raises(NotConnected, match="connect"):
        rw.arm()


def test_params_get_set_and_list(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        assert rw.get_param("tov_mps") == 2.6
        assert rw.set_param("tov_margin", 1.25) == 1.25
        assert rw.get_param("tov_margin") == 1.25
        values = rw.params()
        rw.arm()
        with pytest.raises(CommandRefused) as locked:
            rw.set_param("wheel_radius_m", 0.02)
    assert values["tov_margin"] == 1.25 and values["encoder_counts_per_rev"] == 64.0 and len(values) == len(PARAMS)
    assert locked.value.reason == NackReason.PARAM_LOCKED and "disarm first" in str(locked.value)


def test_lost_param_value_is_asked_again(device: ScriptedDevice) -> None:
    device.drop_param_values = 1
    with Client(device.url, **FAST) as rw:
        assert rw.set_param("tov_mps", 3.0) == 3.0
    assert device.executed_names() == ["PARAM_SET", "PARAM_GET"]


def test_local_argument_errors_send_nothing(device: ScriptedDevice) -> None:
    with Client(device.url, **FAST) as rw:
        with pytest.raises(UnknownParameter, match="did you mean tov_mps"):
            rw.get_param("tov")
        with pytest.raises(InvalidArgument, match="tov_mps: expected a real number, not NaN"):
            rw.set_param("tov_mps", math.nan)
        with pytest.raises(InvalidArgument, match="rope_speed_mps"):
            rw.spin(math.nan)
        with pytest.raises(InvalidArgument, match="rope_speed_mps"):
            rw.spin("5")
    assert {m.NAME for _, m in device.received} == {"HELLO", "HEARTBEAT"}


def test_an_injected_transport_is_used_and_closed(device: ScriptedDevice) -> None:
    from robowrangler.transport_udp import UdpTransport

    transport = UdpTransport("127.0.0.1", device.port)
    with Client(transport=transport, **FAST) as rw:
        assert rw.url == device.url and rw.arm() == State.ARMED
    assert transport.recv(0.01) is None and transport._closed


def test_a_frame_damaged_on_the_way_is_sent_again_at_once_with_the_same_seq(device: ScriptedDevice) -> None:
    device.nack_script[MsgId.ARM] = [(NackReason.BAD_CHECKSUM, 0), (NackReason.TRUNCATED, 0)]
    with Client(device.url, **FAST) as rw:
        start = time.monotonic()
        assert rw.arm() == State.ARMED
        assert time.monotonic() - start < FAST["ack_timeout_s"]  # no timeout was waited out
        stats = rw.stats
    frames = device.received_commands(MsgId.ARM)
    assert len(frames) == 3 and len({seq for seq, _ in frames}) == 1
    assert device.executed_names() == ["ARM"] and stats.transit_nacks == 2


def test_a_link_that_damages_every_attempt_ends_in_the_last_refusal(device: ScriptedDevice) -> None:
    device.nack_script[MsgId.ARM] = [(NackReason.BAD_CHECKSUM, 0)] * (FAST["retries"] + 1)
    with Client(device.url, **FAST) as rw, pytest.raises(CommandRefused) as info:
        rw.arm()
    assert info.value.reason == NackReason.BAD_CHECKSUM and "the link corrupts data" in str(info.value)
    assert len(device.received_commands(MsgId.ARM)) == FAST["retries"] + 1 and device.executed_names() == []


def test_a_command_the_firmware_does_not_know_is_refused_without_retries(device: ScriptedDevice) -> None:
    device.nack_script[MsgId.ESTOP] = [(NackReason.UNKNOWN_MESSAGE, 0)]
    with Client(device.url, **FAST) as rw, pytest.raises(CommandRefused) as info:
        rw.estop()
    assert "firmware does not know this command" in str(info.value)
    assert len(device.received_commands(MsgId.ESTOP)) == 1


def test_late_duplicates_of_older_param_values_are_not_taken_for_the_answer(device: ScriptedDevice) -> None:
    device.stale_param_values = [9.5, 1.0]
    with Client(device.url, **FAST) as rw:
        assert rw.set_param("tov_mps", 3.25) == 3.25
        assert rw.get_param("tov_mps") == 3.25
        stats = rw.stats
    assert stats.stale_param_values == 6 and device.executed_names() == ["PARAM_SET", "PARAM_GET"]
