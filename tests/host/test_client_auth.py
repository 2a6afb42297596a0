"""Signed links (protocol v2) against the real firmware core: HELLO -> SESSION_INFO, every frame signed with a
growing counter, retransmissions re-signed, wrong keys and missing keys reported as AuthenticationError, the
device's frames judged by the one link session (robowrangler.link_session)."""

from __future__ import annotations

import pytest

from host_settings import FAST, QUICK_ARM
from core_device import CoreDevice, lose_acks
from core_harness import SESSION_ID, TEST_KEY
from robowrangler.client import Client
from robowrangler.errors import AuthenticationError, InvalidArgument
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import MsgId, State
from wire import make

OTHER_KEY = bytes(range(1, 17))
PAST_HOLD = dict(params=QUICK_ARM, boot_s=0.25)


def client(device: CoreDevice, **options) -> Client:
    return Client(transport=device.transport(), **{**FAST, "key": TEST_KEY, **options})


def link_counters(device: CoreDevice) -> tuple[int, int]:
    """(rx_auth_failed, rx_replayed) of the core, read by a host with the right key."""
    with client(device) as rw:
        t = rw.wait_for(lambda s: True, timeout_s=1.0)
    return t.rx_auth_failed, t.rx_replayed


def test_a_signed_session_commands_the_device_and_retransmissions_are_re_signed(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        device.to_host.append(lose_acks(MsgId.ARM, 1))
        with client(device) as rw:
            assert rw.session_id == SESSION_ID
            assert rw.arm() == State.ARMED
            assert rw.spin(5.0) == State.SPINUP
            t = rw.wait_for(lambda s: True, timeout_s=1.0)
            stats = rw.stats
    frames = [f for f in device.host_sent() if f.msg_id != MsgId.HELLO]
    arms = [f for f in frames if f.msg_id == MsgId.ARM]
    assert all(f.signed and f.session_id == SESSION_ID for f in frames)
    counters = [f.counter for f in frames]
    assert counters == sorted(counters) and len(set(counters)) == len(counters)
    assert len(arms) == 2 and arms[0].seq == arms[1].seq and arms[0].counter < arms[1].counter
    assert t.rx_auth_failed == 0 and t.rx_replayed == 0 and stats.auth_failures == 0 and stats.replayed == 0


def test_counters_keep_growing_across_clients_of_one_session(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        for command in ("arm", "disarm", "arm"):
            with client(device) as rw:
                assert getattr(rw, command)() in (State.ARMED, State.DISARMED)
        assert link_counters(device) == (0, 0)
    assert [new for _, _, new, _ in device.transitions()] == [State.ARMED, State.DISARMED, State.ARMED]


def test_a_wrong_key_is_reported_at_connect_without_sending_a_signed_frame(device: CoreDevice) -> None:
    with pytest.raises(AuthenticationError, match="link keys differ"):
        client(device, key=OTHER_KEY).connect()
    assert [f for f in device.host_sent() if f.signed] == []


def test_a_keyless_host_is_told_that_the_device_needs_a_key(device: CoreDevice) -> None:
    with pytest.raises(AuthenticationError, match="requires signed frames .* no link key was given"):
        client(device, key=None, connect_timeout_s=1.0).connect()
    auth_failed, _ = link_counters(device)
    assert auth_failed >= 1  # its unsigned heartbeats were dropped


def test_a_device_without_a_key_is_reported(core_lib) -> None:
    with CoreDevice(core_lib, provisioned=False) as device, pytest.raises(AuthenticationError,
                                                                          match="no link key provisioned"):
        client(device).connect()


def test_forged_device_frames_are_dropped_and_counted(device: CoreDevice) -> None:
    with client(device) as rw:
        forged = gen.encode_frame(make(gen.Telemetry, time_ms=999000, state=State.ESTOP), 1, key=OTHER_KEY,
                                  session_id=SESSION_ID, counter=10**15)
        for _ in range(3):
            device.send_to_host(forged)
        samples = [next(rw.telemetry()) for _ in range(5)]
        assert rw.stats.auth_failures == 3
        assert all(s.time_s != 999.0 for s in samples) and rw.latest_telemetry.state == State.DISARMED


def test_a_replayed_device_frame_is_dropped_and_counted(device: CoreDevice) -> None:
    with client(device) as rw:
        rw.wait_for_state(State.DISARMED, timeout_s=1.0)
        captured = [o.raw for o in device.outputs() if isinstance(o.msg, gen.Telemetry)][-1]
        before = rw.stats.replayed
        device.send_to_host(captured)  # validly signed, already seen
        rw.wait_for(lambda s: True, timeout_s=1.0)
        rw.wait_for(lambda s: True, timeout_s=1.0)
        assert rw.stats.replayed == before + 1


def test_a_host_signing_for_an_older_session_is_not_heard(core_lib) -> None:
    """Host -> device: the core takes only its own session (device_takes); a host follows the device, not
    the other way round."""
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device) as rw:
        for session in (SESSION_ID - 1, SESSION_ID + 1):  # either side of the core's session: both dropped
            device.submit(gen.encode_frame(gen.Arm(), 9, key=TEST_KEY, session_id=session, counter=1 << 60), None)
        t = rw.wait_for(lambda s: s.rx_replayed >= 2, timeout_s=1.0)
        assert t.state == State.DISARMED and rw.arm() == State.ARMED


def test_key_must_be_16_bytes() -> None:
    with pytest.raises(InvalidArgument, match="key: expected 16 bytes"):
        Client("udp://127.0.0.1:14550", key=b"short")


def test_a_forged_session_answer_does_not_beat_the_real_one(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        def forge_first(data: bytes):  # an attacker answers the HELLO first, unsigned, "no key"
            frame, msg = gen.decode_message(data)
            if frame.msg_id == MsgId.HELLO:
                device.send_to_host(gen.encode_frame(gen.SessionInfo(msg.host_nonce, 1, 0, gen.SCHEMA_HASH), 0))
            return data

        device.to_device.append(forge_first)
        with client(device) as rw:
            assert rw.session_id == SESSION_ID and rw.arm() == State.ARMED
