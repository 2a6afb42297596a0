"""Provisioning over USB serial: key and WiFi credentials reach the device's flash, never over WiFi,
never echoed in an error."""

from __future__ import annotations

import pytest

from host_settings import FAST
from pty_device import PtyDevice
from robowrangler.client import Client
from robowrangler.errors import CommandRefused, InvalidArgument
from robowrangler.protocol.generated import MsgId, NackReason
from core_device import CoreDevice

KEY = bytes(range(16))


def serial_client(dev: PtyDevice) -> Client:
    return Client(f"serial://{dev.port}?baud=115200", **{**FAST, "ack_timeout_s": 0.1})


def test_provisioning_writes_key_and_wifi_and_reports_without_secrets() -> None:
    with PtyDevice() as dev, serial_client(dev) as rw:
        before = rw.provision_status()
        after = rw.provision(key=KEY, wifi_ssid="lab-5G", wifi_password="correct horse")
    assert not before.key_set and before.commits == 0
    assert after.key_set and after.password_set and after.wifi_ssid == "lab-5G" and after.commits == 1
    assert not after.dirty
    assert dev.stored_key == KEY and dev.password == "correct horse"
    order = [m for m, _ in dev.commands]
    assert order == [MsgId.PROVISION_GET, MsgId.PROVISION_SET_KEY, MsgId.PROVISION_SET_WIFI_SSID,
                     MsgId.PROVISION_SET_WIFI_PASSWORD, MsgId.PROVISION_COMMIT, MsgId.PROVISION_GET]
    assert KEY.hex() not in repr(after) and "correct horse" not in repr(after)


def test_without_commit_the_status_says_dirty() -> None:
    with PtyDevice() as dev, serial_client(dev) as rw:
        status = rw.provision(wifi_ssid="lab", commit=False)
    assert status.dirty and status.wifi_ssid == "" and dev.commits == 0


def test_a_short_password_is_refused_by_the_device_and_not_echoed() -> None:
    with PtyDevice() as dev, serial_client(dev) as rw, pytest.raises(CommandRefused) as info:
        rw.provision(wifi_password="hunter2")
    assert info.value.reason == NackReason.OUT_OF_RANGE and "hunter2" not in str(info.value)


def test_secrets_never_leave_over_wifi(device: CoreDevice) -> None:
    with Client(transport=device.transport(), key=device.key, **FAST) as rw:
        with pytest.raises(InvalidArgument, match="url: expected a serial:// link"):
            rw.provision(key=KEY)
        with pytest.raises(InvalidArgument, match="serial://"):
            rw.provision_status()
    assert {f.msg_id for f in device.host_sent()} <= {MsgId.HELLO, MsgId.HEARTBEAT}


def test_local_refusals_do_not_echo_the_password() -> None:
    with PtyDevice() as dev, serial_client(dev) as rw:
        with pytest.raises(InvalidArgument) as info:
            rw.provision(wifi_password="x" * 64)
        with pytest.raises(InvalidArgument, match="key: expected 16 bytes"):
            rw.provision(key=b"short")
    assert "xxxxxxxx" not in str(info.value) and "64 bytes (not shown)" in str(info.value)
    assert dev.commands == []
