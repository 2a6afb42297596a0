"""rw_core and malformed datagrams: every frame-level NACK reason the device can send, counted in
TELEMETRY.rx_bad / nacks, never executed, never taken as the telemetry peer, never a heartbeat.

Each case runs two identical cores side by side (same inputs, deterministic): one gets the bad
datagram, the twin gets nothing; afterwards their ESC pulses and telemetry must be identical but for
the rx_bad / nacks counters."""

from __future__ import annotations

import itertools

import pytest

from core_harness import SESSION_ID, TEST_KEY, CoreHarness, raw_frame, telemetry_without
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import NackReason, SetRopeSpeed, State

SEQ = 0x1234
GOOD = proto.encode_frame(SetRopeSpeed(6000), SEQ)  # would change the target if it were executed
SPEED_ID = proto.MsgId.SET_ROPE_SPEED
UNREAD = (proto.MSG_ID_UNREADABLE, 0)


def _patched(data: bytes, index: int, value: int) -> bytes:
    b = bytearray(data)
    b[index] = value
    return bytes(b)


# (case id, datagram, reason, (cmd_msg_id, cmd_seq) the NACK must carry)
_FAR_AHEAD = itertools.count(10**12)


def _signed(msg: proto.Message) -> bytes:
    """Signed by the harness's key with counters far ahead of any the harness uses (growing, so that the
    cases stay fresh when sent in a row): authentic frames."""
    return proto.encode_frame(msg, SEQ, key=TEST_KEY, session_id=SESSION_ID, counter=next(_FAR_AHEAD))


CASES = [
    ("shorter_than_header", GOOD[:6], NackReason.TRUNCATED, UNREAD),
    ("one_byte", b"\xb7", NackReason.TRUNCATED, UNREAD),
    ("payload_cut_short", GOOD[:-1], NackReason.TRUNCATED, (SPEED_ID, SEQ)),
    ("bad_magic", _patched(GOOD, 0, 0x7B), NackReason.BAD_MAGIC, UNREAD),
    ("bad_version", _patched(GOOD, 1, proto.PROTOCOL_VERSION + 1), NackReason.BAD_VERSION, (SPEED_ID, SEQ)),
    ("flags_set", _patched(GOOD, 2, 0x02), NackReason.UNSUPPORTED_FLAGS, (SPEED_ID, SEQ)),
    ("declared_payload_over_max", _patched(GOOD, 6, proto.MAX_PAYLOAD_LEN + 1), NackReason.OVERSIZE, (SPEED_ID, SEQ)),
    ("trailing_byte", GOOD + b"\x00", NackReason.BAD_LENGTH, (SPEED_ID, SEQ)),
    ("payload_len_not_the_messages", raw_frame(SPEED_ID, SEQ, b"\x70\x17\x00\x00\x00"), NackReason.BAD_LENGTH,
     (SPEED_ID, SEQ)),
    ("checksum", _patched(GOOD, 8, GOOD[8] ^ 0x01), NackReason.BAD_CHECKSUM, (SPEED_ID, SEQ)),
    ("other_schema", raw_frame(SPEED_ID, SEQ, GOOD[7:11], crc_extra=0x1111), NackReason.BAD_CHECKSUM, (SPEED_ID, SEQ)),
    ("unknown_message", raw_frame(99, SEQ, b"\x01\x02"), NackReason.UNKNOWN_MESSAGE, (99, SEQ)),
    ("telemetry_sent_to_device", _signed(proto.Telemetry(*([0] * len(proto.Telemetry.FIELDS)))), NackReason.NOT_A_COMMAND,
     (proto.MsgId.TELEMETRY, SEQ)),
    ("ack_sent_to_device", _signed(proto.Ack(12, 1, 2)), NackReason.NOT_A_COMMAND,
     (proto.MsgId.ACK, SEQ)),
    ("sil_sensors_sent_to_device", _signed(proto.SilSensors(*([0] * len(proto.SilSensors.FIELDS)))), NackReason.NOT_A_COMMAND,
     (proto.MsgId.SIL_SENSORS, SEQ)),
]

# Datagrams longer than the longest frame: the link truncates them to RW_MAX_FRAME_LEN + 1 bytes and
# reports cap + 1; the core refuses them as the decoder refuses the whole datagram (rw_hal_link.h).
_LONG_HEADER = bytes([proto.MAGIC, proto.PROTOCOL_VERSION, 0, SPEED_ID]) + SEQ.to_bytes(2, "little")
LONG_CASES = [
    ("max_frame_plus_one_trailing", GOOD + bytes(proto.MAX_FRAME_LEN + 1 - len(GOOD)), NackReason.BAD_LENGTH,
     (SPEED_ID, SEQ)),
    ("two_hundred_bytes_trailing", GOOD + bytes(200 - len(GOOD)), NackReason.BAD_LENGTH, (SPEED_ID, SEQ)),
    ("two_hundred_bytes_declared", _LONG_HEADER + bytes([191]) + bytes(193), NackReason.OVERSIZE, (SPEED_ID, SEQ)),
    ("max_plus_one_declared", _LONG_HEADER + bytes([proto.MAX_PAYLOAD_LEN + 1]) + bytes(proto.MAX_FRAME_LEN),
     NackReason.OVERSIZE, (SPEED_ID, SEQ)),
    ("long_garbage", bytes(range(100)), NackReason.BAD_MAGIC, UNREAD),
]


def _airborne_twins(rw_core) -> tuple[CoreHarness, CoreHarness]:
    twins = []
    for _ in range(2):
        h = CoreHarness(rw_core)
        h.boot_and_arm()
        h.spin_to_airborne(target_mmps=4000)
        h.encoder.speed_mps = 4.0
        h.heartbeat()
        h.run_ms(40)
        twins.append(h)
    a, b = twins
    assert a.hal.pulses_us == b.hal.pulses_us and a.hal.out == b.hal.out, "the core is deterministic"
    return a, b


def _check_refused_and_harmless(rw_core, data: bytes, reason: NackReason, ids: tuple[int, int]) -> None:
    a, b = _airborne_twins(rw_core)
    peers_before = a.hal.accept_peer_calls
    i0 = len(a.hal.out)
    a.queue(data)
    for h in (a, b):
        h.run_ms(60)
    replies = a.replies(since=i0)
    assert len(replies) == 1
    nack = replies[0].msg
    assert isinstance(nack, proto.Nack), f"expected NACK, got {nack}"
    assert (nack.reason, (nack.cmd_msg_id, nack.cmd_seq)) == (reason, ids)
    assert nack.state == State.AIRBORNE
    assert a.hal.accept_peer_calls == peers_before, "a refused datagram must not become the telemetry peer"
    assert a.hal.pulses_us == b.hal.pulses_us, "the ESC never saw the bad datagram"
    ta, tb = a.telemetry(), b.telemetry()
    assert len(ta) >= 2
    last_a, last_b = ta[-1], tb[-1]
    assert (last_a.rx_bad, last_a.nacks) == (last_b.rx_bad + 1, last_b.nacks + 1), "counted in rx_bad and nacks"
    assert last_a.rx_ok == last_b.rx_ok
    assert telemetry_without(last_a, "rx_bad", "nacks") == telemetry_without(last_b, "rx_bad", "nacks"), \
        "state, target, setpoint, pulse and heartbeat age unchanged"
    assert last_a.rope_speed_target_mmps == 4000


@pytest.mark.parametrize("data, reason, ids", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_malformed_datagram_gets_its_nack_reason_and_changes_nothing(rw_core, data, reason, ids):
    _check_refused_and_harmless(rw_core, data, reason, ids)


@pytest.mark.parametrize("data, reason, ids", [c[1:] for c in LONG_CASES], ids=[c[0] for c in LONG_CASES])
def test_datagram_longer_than_the_max_frame_is_refused_as_the_decoder_would(rw_core, data, reason, ids):
    assert len(data) > proto.MAX_FRAME_LEN
    _check_refused_and_harmless(rw_core, data, reason, ids)


def test_every_frame_level_reason_in_a_row_counts_each_one(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    for _, data, reason, _ in CASES:
        reply = h.command(data)
        assert reply.reason == reason
    h.run_ms(30)
    tel = h.telemetry()[-1]
    assert (tel.rx_bad, tel.nacks, tel.rx_ok) == (len(CASES), len(CASES), 0)
    assert h.hal.accept_peer_calls == 0
    assert set(h.hal.pulses_us) == {1000}


def test_valid_frame_after_garbage_is_executed_and_becomes_the_peer(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.command(b"\x00" * 20)
    assert h.hal.accept_peer_calls == 0
    reply = h.command(proto.ParamGet(0))
    assert isinstance(reply, proto.Ack)
    assert h.hal.accept_peer_calls == 1
