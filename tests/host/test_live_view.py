"""`wrangler proxy --foxglove`: the device's telemetry, events, every tool's commands and the parameters (with the
ToV guard) served live over Foxglove's WebSocket protocol with the recordings' JSON Schemas; read here by a plain
WebSocket client speaking the protocol (foxglove.sdk.v1), while a tool commands through the proxy."""

from __future__ import annotations

import io
import json
import re
import socket
import struct
import threading
import time

from websockets.sync.client import connect

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.recorder import schemas_generated as sg
from robowrangler.recorder.json_schema_check import first_error
import pytest
from core_device import CoreDevice
from core_harness import FakeSpindle
from test_cli import FAST_SPINDLE, wrangler

SUBPROTOCOL = "foxglove.sdk.v1"  # the Foxglove WebSocket protocol (formerly foxglove.websocket.v1)
MESSAGE_DATA = 0x01  # binary opcode of a message on a subscription

@pytest.fixture
def device(core_lib):
    """The real core past its arming hold on its serial link (the CLI's default: no key), reached over UDP, with a
    fast lead screw, its clock at twice the wall clock (as test_cli.py's)."""
    with CoreDevice(core_lib, link="serial", params=FAST_SPINDLE, spindle=FakeSpindle(lead_mm_per_rev=20.0),
                    boot_s=0.25, speedup=2.0) as dev:
        yield dev



def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_websocket_client_sees_the_link_live_with_the_recording_schemas(device: CoreDevice) -> None:
    port = _free_udp_port()
    runs: list = []
    err = io.StringIO()
    env = Environment(stdout=io.StringIO(), stderr=err, environ={})
    proxy = threading.Thread(target=lambda: runs.append(main(["--url", device.url, "proxy", "--listen", str(port),
                                                              "--foxglove", "0", "--duration", "4"], env)), daemon=True)
    proxy.start()
    deadline = time.monotonic() + 10
    while not (found := re.search(r"live in Foxglove at (ws://127\.0\.0\.1:\d+)", err.getvalue())):
        assert time.monotonic() < deadline and proxy.is_alive(), err.getvalue()
        time.sleep(0.05)
    with connect(found.group(1), subprotocols=[SUBPROTOCOL], open_timeout=5) as ws:
        assert ws.subprotocol == SUBPROTOCOL
        channels: dict[str, dict] = {}
        while len(channels) < len(sg.CHANNELS) + 1:
            msg = json.loads(ws.recv(timeout=5))
            if msg["op"] == "advertise":
                channels.update({c["topic"]: c for c in msg["channels"]})
        for topic, (name, _, text) in sg.CHANNELS.items():  # the recordings' schemas, byte for byte
            c = channels[topic]
            assert (c["encoding"], c["schemaName"], c["schemaEncoding"]) == ("json", name, "jsonschema")
            assert json.loads(c["schema"]) == json.loads(text)
        wanted = ["/device/telemetry", "/device/event", "/host/command", "/device/params"]
        by_sub = {i: topic for i, topic in enumerate(wanted, start=1)}
        ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": i, "channelId": channels[topic]["id"]} for i, topic in by_sub.items()]}))
        time.sleep(0.3)
        tool = ("--url", f"udp://127.0.0.1:{port}")
        assert wrangler(*tool, "arm").status == ExitStatus.OK
        assert wrangler(*tool, "spin", "5", "--hold", "0.6").status == ExitStatus.OK
        got: dict[str, list[dict]] = {topic: [] for topic in wanted}
        end = time.monotonic() + 1.2
        while time.monotonic() < end:
            try:
                frame = ws.recv(timeout=0.2)
            except TimeoutError:
                continue
            if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                sub_id, _log_time_ns = struct.unpack_from("<IQ", frame, 1)
                got[by_sub[sub_id]].append(json.loads(frame[13:]))
    proxy.join(10)
    assert runs == [ExitStatus.OK], err.getvalue()
    telemetry = got["/device/telemetry"]
    assert len(telemetry) >= 0.8 * 50 * 1.8, len(telemetry)  # the live stream, not a trickle
    schema = json.loads(sg.CHANNELS["/device/telemetry"][2])
    assert all(first_error(t, schema) is None for t in telemetry)
    assert {"AIRBORNE", "SPINDOWN"} <= {t["state"] for t in telemetry}
    assert max(t["rope_speed_setpoint_mps"] for t in telemetry) == 5.0
    events = [(e["event"], e["state_to"]) for e in got["/device/event"]]
    assert ("STATE_CHANGED", "AIRBORNE") in events
    commands = {(c["message"], c["verdict"]) for c in got["/host/command"]}
    assert {("ARM", "ACK"), ("SET_ROPE_SPEED", "ACK"), ("SPINDOWN", "ACK")} <= commands
    params = got["/device/params"][-1]
    assert params["tov_guard_mps"] == params["tov_mps"] * params["tov_margin"]


def test_watch_foxglove_serves_the_stream_it_prints(device: CoreDevice) -> None:
    err = io.StringIO()
    out = io.StringIO()
    runs: list = []
    watch = threading.Thread(target=lambda: runs.append(main(["--url", device.url, "--json", "watch", "--duration", "2",
                                                              "--foxglove", "0"], Environment(out, err, {}))),
                             daemon=True)
    watch.start()
    deadline = time.monotonic() + 10
    while not (found := re.search(r"live in Foxglove at (ws://127\.0\.0\.1:\d+)", err.getvalue())):
        assert time.monotonic() < deadline and watch.is_alive(), err.getvalue()
        time.sleep(0.02)
    got = []
    with connect(found.group(1), subprotocols=[SUBPROTOCOL], open_timeout=5) as ws:
        channel = None
        while channel is None:
            msg = json.loads(ws.recv(timeout=5))
            if msg["op"] == "advertise":
                channel = next((c["id"] for c in msg["channels"] if c["topic"] == "/device/telemetry"), None)
        ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": channel}]}))
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            try:
                frame = ws.recv(timeout=0.2)
            except TimeoutError:
                continue
            if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                got.append(json.loads(frame[13:]))
    watch.join(10)
    assert runs == [ExitStatus.OK], err.getvalue()
    assert len(got) >= 0.8 * 50 * 0.8 and {g["state"] for g in got} == {"DISARMED"}
    printed = {json.loads(line)["time_s"] for line in out.getvalue().splitlines() if '"telemetry"' in line}
    # the very samples it printed; the live view taps the link from the connection on, so it may also carry the
    # samples that arrived while connecting, before the printing began (a subscriber that came that early)
    assert all(t < min(printed) for t in {g["time_s"] for g in got} - printed), (sorted(printed)[:3], got[:3])
