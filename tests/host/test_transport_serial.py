"""Serial transport: COBS + 0x00 framing over pyserial's loop:// and over a real pty to a scripted peer."""

from __future__ import annotations

import pytest
from cobs import cobs
from hypothesis import given, settings
from hypothesis import strategies as st

from robowrangler.client import Client
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import MsgId, State
from robowrangler.transport import open_transport
from robowrangler.transport_serial import SerialTransport, encode_serial_frame
from core_device import CoreDevice
from host_settings import QUICK_ARM
from wire import make


@pytest.fixture
def loop():
    t = SerialTransport("loop://", baud=115200)
    yield t
    t.close()


def test_frames_with_zero_bytes_survive_the_loop(loop: SerialTransport) -> None:
    frames = [gen.encode_frame(gen.Ack(10, 0, 0), 0), gen.encode_frame(gen.SetRopeSpeed(0), 256),
              gen.encode_frame(make(gen.Telemetry), 0)]
    assert all(0 in f for f in frames)
    for f in frames:
        loop.send(f)
    assert [loop.recv(0.5) for _ in frames] == frames
    assert loop.recv(0.05) is None and loop.framing_errors == 0


def test_wire_bytes_are_cobs_with_one_trailing_delimiter() -> None:
    frame = gen.encode_frame(gen.Arm(), 0)
    wire = encode_serial_frame(frame)
    assert wire.endswith(b"\x00") and b"\x00" not in wire[:-1] and cobs.decode(wire[:-1]) == frame


def test_noise_between_frames_is_counted_and_the_next_frame_still_arrives(loop: SerialTransport) -> None:
    good = gen.encode_frame(gen.Heartbeat(123), 9)
    loop._port.write(b"\x05\x01\x00")          # COBS says 5 bytes follow, 1 does: undecodable
    loop._port.write(b"\x7f" * 300)            # no delimiter for longer than any frame
    loop._port.write(b"\x00")
    loop.send(good)
    assert loop.recv(0.5) == good
    assert loop.framing_errors == 2


@settings(max_examples=50, deadline=None)
@given(st.lists(st.binary(min_size=1, max_size=gen.MAX_FRAME_LEN), min_size=1, max_size=5))
def test_any_frame_bytes_round_trip_through_cobs_framing(payloads: list[bytes]) -> None:
    t = SerialTransport("loop://")
    try:
        for p in payloads:
            t.send(p)
        assert [t.recv(0.5) for _ in payloads] == payloads
    finally:
        t.close()


def test_serial_url_opens_the_serial_transport() -> None:
    t = open_transport("serial://loop://?baud=9600")
    try:
        assert isinstance(t, SerialTransport) and t.url == "serial://loop://?baud=9600"
    finally:
        t.close()


def test_client_commands_the_core_over_a_real_serial_port(core_lib) -> None:
    """The real core's serial link behind a pseudo-terminal (COBS-framed, as the board's USB serial)."""
    with CoreDevice(core_lib, link="serial", params=QUICK_ARM, boot_s=0.25) as dev, \
            Client(f"serial://{dev.open_pty()}?baud=115200", ack_timeout_s=0.1, connect_timeout_s=3.0) as rw:
        assert rw.latest_telemetry.battery_v == 14.8
        assert rw.arm() == State.ARMED
        assert rw.wait_for_state(State.ARMED, timeout_s=1.0).state == State.ARMED
        stats = rw.stats
    assert [f.msg_id for f in dev.host_sent() if f.msg_id not in (MsgId.HELLO, MsgId.HEARTBEAT)] == [MsgId.ARM]
    assert stats.decode_errors == 0 and stats.framing_errors == 0
