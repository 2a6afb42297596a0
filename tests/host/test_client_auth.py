"""Signed links (protocol v2): HELLO -> SESSION_INFO, every frame signed with a growing counter,
retransmissions re-signed, wrong keys and missing keys reported as AuthenticationError."""

from __future__ import annotations

import time

import pytest

from conftest import FAST
from robowrangler.client import Client
from robowrangler.errors import AuthenticationError
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import MsgId, State
from scripted_device import ScriptedDevice, make

KEY = bytes(range(16))
OTHER_KEY = bytes(range(1, 17))


def signed_frames(device: ScriptedDevice) -> list[gen.Frame]:
    with device.lock:
        return [f for f, _ in device.received if f.msg_id != MsgId.HELLO]


def test_a_signed_session_commands_the_device_and_retransmissions_are_re_signed() -> None:
    with ScriptedDevice(key=KEY, session_id=7) as device:
        device.drop_replies[MsgId.ARM] = 1
        with Client(device.url, key=KEY, **FAST) as rw:
            assert rw.session_id == 7
            assert rw.arm() == State.ARMED
            assert rw.spin(5.0) == State.SPINUP
            stats = rw.stats
        frames = signed_frames(device)
        arms = [f for f in frames if f.msg_id == MsgId.ARM]
        assert all(f.signed and f.session_id == 7 for f in frames)
        counters = [f.counter for f in frames]
        assert counters == sorted(counters) and len(set(counters)) == len(counters)
        assert len(arms) == 2 and arms[0].seq == arms[1].seq and arms[0].counter < arms[1].counter
        assert device.executed_names() == ["ARM", "SET_ROPE_SPEED"]
        assert device.auth_failed == 0 and device.replayed == 0 and stats.auth_failures == 0


def test_counters_keep_growing_across_clients_of_one_session() -> None:
    with ScriptedDevice(key=KEY) as device:
        for command in ("arm", "disarm", "arm"):
            with Client(device.url, key=KEY, **FAST) as rw:
                getattr(rw, command)()
        assert device.replayed == 0 and device.executed_names() == ["ARM", "DISARM", "ARM"]


def test_a_wrong_key_is_reported_at_connect_without_sending_a_signed_frame() -> None:
    with ScriptedDevice(key=KEY) as device:
        start = time.monotonic()
        with pytest.raises(AuthenticationError, match="link keys differ"):
            Client(device.url, key=OTHER_KEY, **FAST).connect()
        assert time.monotonic() - start < 0.5
        assert signed_frames(device) == [] and device.auth_failed == 0


def test_a_keyless_host_is_told_that_the_device_needs_a_key() -> None:
    with ScriptedDevice(key=KEY) as device:
        with pytest.raises(AuthenticationError, match="requires signed frames .* no link key was given"):
            Client(device.url, **{**FAST, "connect_timeout_s": 0.3}).connect()
        assert device.auth_failed >= 1  # its unsigned heartbeats were dropped


def test_a_device_without_a_key_is_reported() -> None:
    with ScriptedDevice() as device, pytest.raises(AuthenticationError, match="no link key provisioned"):
        Client(device.url, key=KEY, **FAST).connect()


def test_forged_device_frames_are_dropped_and_counted() -> None:
    with ScriptedDevice(key=KEY) as device, Client(device.url, key=KEY, **FAST) as rw:
        forged = gen.encode_frame(make(gen.Telemetry, time_ms=999000, state=State.ESTOP), 1, key=OTHER_KEY,
                                  session_id=7, counter=10**15)
        for _ in range(3):
            device.send_raw(forged)
        samples = [next(rw.telemetry()) for _ in range(5)]
        assert rw.stats.auth_failures == 3
        assert all(s.time_s != 999.0 for s in samples) and rw.latest_telemetry.state == State.DISARMED


def test_the_client_follows_the_device_into_a_new_session() -> None:
    with ScriptedDevice(key=KEY, session_id=7) as device, Client(device.url, key=KEY, **FAST) as rw:
        with device.lock:  # the device rebooted: boot counter 8
            device.session_id = 8
        rw.wait_for(lambda s: True, timeout_s=0.5)  # a signed telemetry frame of session 8 arrives
        assert rw.arm() == State.ARMED
        assert rw.session_id == 8 and rw.stats.session_changes == 1


def test_key_must_be_16_bytes() -> None:
    from robowrangler.errors import InvalidArgument

    with pytest.raises(InvalidArgument, match="key: expected 16 bytes"):
        Client("udp://127.0.0.1:14550", key=b"short")


def test_a_forged_session_answer_does_not_beat_the_real_one() -> None:
    with ScriptedDevice(key=KEY, session_id=9) as device:
        original = device._on_datagram

        def forge_first(data: bytes, addr) -> None:  # an attacker answers the HELLO first, unsigned, "no key"
            frame, msg = gen.decode_message(data)
            if frame.msg_id == MsgId.HELLO:
                device._sock.sendto(gen.encode_frame(gen.SessionInfo(msg.host_nonce, 1, 0, gen.SCHEMA_HASH), 0), addr)
                time.sleep(0.03)  # the real answer comes clearly later
            original(data, addr)

        device._on_datagram = forge_first
        with Client(device.url, key=KEY, **FAST) as rw:
            assert rw.session_id == 9 and rw.arm() == State.ARMED
