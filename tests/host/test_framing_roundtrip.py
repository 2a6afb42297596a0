"""Every protocol message survives the client's framing on both transports, bit for bit."""

from __future__ import annotations

import socket

import pytest

from robowrangler.protocol import generated as gen
from robowrangler.transport_serial import SerialTransport
from robowrangler.transport_udp import UdpTransport


def _example(cls: type[gen.Message]) -> gen.Message:
    """An instance with every field at a distinct, non-trivial value (floats exact in float32)."""
    values = []
    for i, (spec, rng) in enumerate(zip(cls.FIELDS, cls._RANGES)):
        if rng is None:
            values.append(1.5 + i)
        elif rng[0] == "bytes":
            values.append(bytes((0xA5 + 37 * i + k) & 0xFF for k in range(rng[1])))
        elif rng[0] == "str":
            values.append("ok-" * min(5, (rng[1] - 1) // 3))
        else:
            values.append(min(rng[1], max(rng[0], 0xA5A5 + 37 * i)))
    return cls(*values)


MESSAGES = [_example(cls) for cls in gen.MESSAGES.values()]


@pytest.mark.parametrize("msg", MESSAGES, ids=[m.NAME for m in MESSAGES])
def test_every_message_round_trips_over_serial(msg: gen.Message) -> None:
    t = SerialTransport("loop://")
    try:
        t.send(gen.encode_frame(msg, 0xBEEF))
        frame, decoded = gen.decode_message(t.recv(0.5))
    finally:
        t.close()
    assert decoded == msg and frame.seq == 0xBEEF


def test_every_message_round_trips_over_udp() -> None:
    peer = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    peer.bind(("127.0.0.1", 0))
    peer.settimeout(1.0)
    t = UdpTransport("127.0.0.1", peer.getsockname()[1])
    try:
        for seq, msg in enumerate(MESSAGES):
            t.send(gen.encode_frame(msg, seq))
            data, addr = peer.recvfrom(2048)
            assert gen.decode_message(data)[1] == msg
            assert addr[1] == t.local_address[1]  # bound to an ephemeral port
            peer.sendto(data, addr)
            assert t.recv(1.0) == data
    finally:
        t.close()
        peer.close()


def test_udp_recv_times_out_with_none_and_ignores_an_absent_peer() -> None:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nobody listens there: ICMP port unreachable comes back
    t = UdpTransport("127.0.0.1", port)
    try:
        for _ in range(3):
            t.send(gen.encode_frame(gen.Heartbeat(0), 0))
            assert t.recv(0.05) is None
        assert t.unreachable >= 1
    finally:
        t.close()
