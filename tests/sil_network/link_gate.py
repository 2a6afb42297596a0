"""The device's gate on its WiFi link, modelled from the protocol text: what becomes of a delivered datagram.

protocol/spec/robowrangler.toml [protocol].description: over WiFi every frame but HELLO must be signed;
the device drops, without answering, a frame whose tag is wrong (counted in rx_auth_failed), or that is
for another session or whose counter is not above the last it accepted (rx_replayed). A malformed frame
is still NACKed with its reason. The network checkers feed the gate every datagram the proxy delivered to
the firmware, in delivery order (the order the firmware reads them), so it says which frames the firmware
must act on and which it must drop, and the TELEMETRY counters are checked against it.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from enum import Enum

from robowrangler.link_session import device_takes
from robowrangler.protocol import generated as gen


class Fate(Enum):
    """What the device does with one delivered datagram."""

    EMPTY = "empty"  # a zero-length datagram reads as none (as on the board): no answer
    MALFORMED = "malformed"  # decode error: NACKed with its reason, counted in rx_bad
    HELLO = "hello"  # answered with SESSION_INFO, unsigned allowed
    AUTH_FAILED = "auth_failed"  # unsigned or a wrong tag: dropped unanswered, rx_auth_failed
    REPLAYED = "replayed"  # another session or a stale counter: dropped unanswered, rx_replayed
    ACCEPTED = "accepted"  # authentic and fresh: heartbeat, command (verdict) or a wrong-direction NACK


@dataclass(frozen=True)
class Delivery:
    """One delivered datagram as the device takes it. frame/message are None when it did not decode."""

    fate: Fate
    frame: gen.Frame | None = None
    message: gen.Message | None = None
    error: gen.FrameError | None = None


class DeviceGate:
    """The device's WiFi acceptance rule (robowrangler.link_session.device_takes). key: the provisioned 16-byte link key.

    The device's session is learnt from its own verified frames (learn_session); a new session starts a
    new counter (the device's last accepted counter is 0 after boot).
    """

    def __init__(self, *, key: bytes) -> None:
        if not isinstance(key, (bytes, bytearray)) or len(key) != gen.KEY_LEN:
            raise ValueError(f"key: expected {gen.KEY_LEN} bytes (the provisioned link key), got {key!r:.40}")
        self.key = bytes(key)
        self.session_id: int | None = None
        self.last_counter = 0

    def learn_session(self, frame: gen.Frame) -> None:
        """Take the session of a frame the device sent (ignored unless its tag verifies)."""
        if frame.signed and gen.tag_valid(frame, self.key) and frame.session_id != self.session_id:
            self.session_id = frame.session_id
            self.last_counter = 0

    def deliver(self, data: bytes) -> Delivery:
        """The fate of data delivered to the device now (updates the last accepted counter)."""
        if not data:
            return Delivery(Fate.EMPTY)
        try:
            frame, message = gen.decode_message(data)
        except gen.FrameError as err:
            return Delivery(Fate.MALFORMED, error=err)
        if message.KIND == gen.MsgKind.HELLO:
            return Delivery(Fate.HELLO, frame, message)
        if not gen.tag_valid(frame, self.key):
            return Delivery(Fate.AUTH_FAILED, frame, message)
        if not device_takes(frame, session_id=self.session_id, last_counter=self.last_counter):
            return Delivery(Fate.REPLAYED, frame, message)
        self.last_counter = frame.counter
        return Delivery(Fate.ACCEPTED, frame, message)


def seeded_key(seed: int) -> bytes:
    """A link key derived from a run's seed, so a seeded run signs the same bytes every time (16 bytes)."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed: expected an int >= 0, got {seed!r}")
    return hashlib.blake2b(seed.to_bytes(8, "little"), digest_size=gen.KEY_LEN, person=b"rw-sil-net-key").digest()
