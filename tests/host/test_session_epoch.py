"""The session epoch a host sends in PROVISION_COMMIT: 31 random bits from the OS CSPRNG, fresh at every commit."""

from __future__ import annotations

import pytest

from host_settings import FAST
from core_device import CoreDevice
from robowrangler.client import Client
from robowrangler.protocol import generated as gen
from robowrangler.session_epoch import EPOCH_LIMIT, new_session_epoch


def test_the_epoch_is_the_random_bytes_masked_to_31_bits() -> None:
    assert new_session_epoch(random_bytes=lambda n: b"\xff" * n) == EPOCH_LIMIT - 1 == 2**31 - 1
    assert new_session_epoch(random_bytes=lambda n: bytes([1, 2, 3, 4])) == 0x04030201
    assert new_session_epoch(random_bytes=lambda n: bytes([0, 0, 0, 0x80])) == 0  # the top bit is dropped
    epochs = {new_session_epoch() for _ in range(64)}
    assert len(epochs) == 64 and all(0 <= e < EPOCH_LIMIT for e in epochs)  # os.urandom: no repeats in 64


def test_a_bad_random_source_is_named() -> None:
    with pytest.raises(ValueError, match="^random_bytes: expected a function returning 4 bytes, got b'ab'"):
        new_session_epoch(random_bytes=lambda n: b"ab")


def test_every_commit_carries_a_fresh_epoch(core_lib) -> None:
    with CoreDevice(core_lib, link="serial") as dev, Client(f"serial://{dev.open_pty()}?baud=115200", **FAST) as rw:
        rw.provision(key=bytes(range(16)))
        rw.provision(wifi_ssid="lab")
    # by seq: a retransmission (same seq) repeats its commit's epoch, it does not draw a new one
    commits = [gen.decode_message(raw)[1] for raw in dev.host_frames if raw[3] == gen.MsgId.PROVISION_COMMIT]
    by_seq = {gen.decode_frame(raw).seq: m.session_epoch for raw, m in zip(
        [raw for raw in dev.host_frames if raw[3] == gen.MsgId.PROVISION_COMMIT], commits)}
    epochs = list(by_seq.values())
    assert len(epochs) == 2 and epochs[0] != epochs[1] and all(0 <= e < EPOCH_LIMIT for e in epochs)
