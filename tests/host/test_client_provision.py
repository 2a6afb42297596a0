"""Provisioning over USB serial, against the real firmware core on a pseudo-terminal (core_device.py): key and
WiFi credentials reach the core's flash record, the key takes effect on WiFi at the commit, nothing secret
travels over WiFi or is echoed in an error."""

from __future__ import annotations

import pytest

from core_device import CoreDevice
from core_harness import TEST_KEY
from host_settings import FAST, QUICK_ARM
from robowrangler.client import Client
from robowrangler.errors import AuthenticationError, CommandRefused, InvalidArgument
from robowrangler.protocol.generated import MsgId, NackReason, State

KEY = bytes(range(0x70, 0x80))


def serial_client(device: CoreDevice) -> Client:
    return Client(f"serial://{device.open_pty()}?baud=115200", **{**FAST, "ack_timeout_s": 0.1})


def test_provisioning_writes_key_and_wifi_the_key_works_at_once_and_nothing_secret_is_reported(core_lib) -> None:
    with CoreDevice(core_lib, provisioned=False, params=QUICK_ARM, boot_s=0.25) as device:
        with serial_client(device) as rw:
            before = rw.provision_status()
            after = rw.provision(key=KEY, wifi_ssid="lab-5G", wifi_password="correct horse")
        with Client(transport=device.transport("wifi"), key=KEY, **FAST) as wifi:  # the new key, over WiFi
            assert wifi.arm() == State.ARMED
        flash = device.harness.flash
    assert not before.key_set and before.commits == 0
    assert after.key_set and after.password_set and after.wifi_ssid == "lab-5G" and after.commits == 1
    assert not after.dirty
    assert flash is not None and KEY in flash and b"correct horse" in flash  # the one record in the flash
    order = [f.msg_id for f in device.host_sent() if f.msg_id not in (MsgId.HELLO, MsgId.HEARTBEAT)]
    assert order == [MsgId.PROVISION_GET, MsgId.PROVISION_SET_KEY, MsgId.PROVISION_SET_WIFI_SSID,
                     MsgId.PROVISION_SET_WIFI_PASSWORD, MsgId.PROVISION_COMMIT, MsgId.PROVISION_GET, MsgId.ARM]
    assert KEY.hex() not in repr(after) and "correct horse" not in repr(after)


def test_without_commit_the_status_says_dirty_and_the_flash_is_untouched(core_lib) -> None:
    with CoreDevice(core_lib, provisioned=False, boot_s=0.01) as device, serial_client(device) as rw:
        booted = device.harness.flash  # the boot wrote its boot counter back
        status = rw.provision(wifi_ssid="lab", commit=False)
        flash = device.harness.flash
    assert status.dirty and status.wifi_ssid == "lab" and status.commits == 0  # staged in RAM only
    assert booted is not None and flash == booted and b"lab" not in flash


def test_a_short_password_is_refused_by_the_device_and_not_echoed(core_lib) -> None:
    with CoreDevice(core_lib, provisioned=False) as device, serial_client(device) as rw, \
            pytest.raises(CommandRefused) as info:
        rw.provision(wifi_password="hunter2")
    assert info.value.reason == NackReason.OUT_OF_RANGE and "hunter2" not in str(info.value)


def test_secrets_never_leave_over_wifi(device: CoreDevice) -> None:
    with Client(transport=device.transport(), key=device.key, **FAST) as rw:
        with pytest.raises(InvalidArgument, match="url: expected a serial:// link"):
            rw.provision(key=KEY)
        with pytest.raises(InvalidArgument, match="serial://"):
            rw.provision_status()
    assert {f.msg_id for f in device.host_sent()} <= {MsgId.HELLO, MsgId.HEARTBEAT}


def test_an_old_key_is_refused_over_wifi_after_a_new_one_is_committed(core_lib) -> None:
    with CoreDevice(core_lib, params=QUICK_ARM, boot_s=0.25) as device:
        with serial_client(device) as rw:
            rw.provision(key=KEY)
        with pytest.raises(AuthenticationError, match="link keys differ"):
            Client(transport=device.transport("wifi"), key=TEST_KEY, **FAST).connect()


def test_local_refusals_do_not_echo_the_password(core_lib) -> None:
    with CoreDevice(core_lib, provisioned=False) as device, serial_client(device) as rw:
        with pytest.raises(InvalidArgument) as info:
            rw.provision(wifi_password="x" * 64)
        with pytest.raises(InvalidArgument, match="key: expected 16 bytes"):
            rw.provision(key=b"short")
    assert "xxxxxxxx" not in str(info.value) and "64 bytes (not shown)" in str(info.value)
    assert [f for f in device.host_sent() if f.msg_id not in (MsgId.HELLO, MsgId.HEARTBEAT)] == []
