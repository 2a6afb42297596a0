"""The client's freshness check on device frames: a replayed (validly signed) device frame is dropped."""

from __future__ import annotations

import time

from conftest import FAST
from robowrangler.client import Client
from robowrangler.protocol import generated as gen
from scripted_device import ScriptedDevice


KEY = bytes(range(16))


def test_a_replayed_device_frame_is_dropped_and_counted() -> None:
    with ScriptedDevice(key=KEY) as device, Client(device.url, key=KEY, **FAST) as rw:
        rw.wait_for_state(gen.State.DISARMED, timeout_s=1.0)
        sent_before = rw.stats.replayed
        # capture one telemetry frame the device signed, and send it to the client again
        captured = device.last_sent_telemetry()
        assert captured is not None
        device.send_raw(captured)
        deadline = time.monotonic() + 1.0
        while rw.stats.replayed == sent_before and time.monotonic() < deadline:
            time.sleep(0.01)
        assert rw.stats.replayed == sent_before + 1
