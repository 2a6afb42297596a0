"""`wrangler sil --scenario NAME --foxglove`: the loop live in Foxglove, read by a plain WebSocket client speaking
Foxglove's protocol (foxglove.sdk.v1) while the SIL firmware drives the rope chain; in-process (main(argv, env))."""

from __future__ import annotations

import base64
import io
import json
import re
import struct
import threading
import time

import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.recorder import schemas_generated as sg
from robowrangler.recorder.json_schema_check import first_error
from robowrangler_sim.scenarios.live_loop import ScenarioLiveView, loop_plane_points_m

SUBPROTOCOL = "foxglove.sdk.v1"
MESSAGE_DATA = 0x01
LINKS = 10


def _decoder(channel: dict):
    """The protobuf class of an advertised channel, from the FileDescriptorSet the server sends (as Foxglove does)."""
    assert channel["schemaEncoding"] == "protobuf"
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


def test_a_websocket_client_sees_the_loop_and_the_firmware_live(native_build_dir) -> None:
    """The golf ball wrangle (10 links, seed 1) through the CLI with --foxglove, unpaced: its verdict as ever, and a
    WebSocket client that subscribed sees the loop's contour at 30 Hz of simulated time, the 3D scene, the
    telemetry and the commands."""
    err, out = io.StringIO(), io.StringIO()
    runs: list = []
    cli = threading.Thread(target=lambda: runs.append(main(
        ["--json", "sil", "--scenario", "golf_ball", "--links", str(LINKS), "--seed", "1", "--foxglove", "0",
         "--unpaced"], Environment(out, err, {}))), daemon=True)
    cli.start()
    deadline = time.monotonic() + 60
    while not (found := re.search(r"live in Foxglove at (ws://127\.0\.0\.1:\d+)", err.getvalue())):
        assert time.monotonic() < deadline and cli.is_alive(), err.getvalue()
        time.sleep(0.02)
    wanted = ["/loop/observation", "/loop/scene", "/device/telemetry", "/host/command"]
    got: dict[str, list[bytes]] = {topic: [] for topic in wanted}
    with connect(found.group(1), subprotocols=[SUBPROTOCOL], open_timeout=10) as ws:
        channels: dict[str, dict] = {}
        while not set(wanted) <= set(channels):
            msg = json.loads(ws.recv(timeout=10))
            if msg["op"] == "advertise":
                channels.update({c["topic"]: c for c in msg["channels"]})
        by_sub = dict(enumerate(wanted, start=1))
        ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": i, "channelId": channels[topic]["id"]} for i, topic in by_sub.items()]}))
        try:
            while True:  # until the run ends and the server closes
                frame = ws.recv(timeout=300)
                if isinstance(frame, bytes) and frame[0] == MESSAGE_DATA:
                    sub_id, _log_time_ns = struct.unpack_from("<IQ", frame, 1)
                    got[by_sub[sub_id]].append(frame[13:])
        except ConnectionClosed:
            pass
    cli.join(60)
    assert runs == [ExitStatus.OK], err.getvalue()
    result = json.loads(out.getvalue().strip().splitlines()[-1])
    # the CLI's run as without the live view (it only reads): progress on stderr, the JSON verdict, explained
    assert result["scenario"] == "golf_ball" and result["verdict"] == "slipped" and result["secured"] is False
    assert result["grasp_end"] == "STROKE_END" and result["diverged"] is None
    assert "RETRACT->ARMED (STROKE_END)" in result["firmware_path"]
    assert "GRASP" in err.getvalue() and "pull" in err.getvalue()  # progress on stderr
    explained = err.getvalue().strip().splitlines()[-1]  # what the verdict means, and what the figures say happened
    assert explained.startswith("wrangler: secured = over the judged part of the pull the object followed")
    assert "at least 0.5" in explained and "at least 80 %" in explained and ". Here: " in explained

    # /loop/observation: the recordings' schema, byte for byte, and records that meet it
    c = channels["/loop/observation"]
    assert (c["encoding"], c["schemaName"], c["schemaEncoding"]) == ("json", sg.CHANNELS["/loop/observation"][0],
                                                                     "jsonschema")
    schema = json.loads(sg.CHANNELS["/loop/observation"][2])
    assert json.loads(c["schema"]) == schema
    obs = [json.loads(b) for b in got["/loop/observation"]]
    assert len(obs) > 100, len(obs)
    assert all(first_error(o, schema) is None for o in obs)
    times = np.array([o["time_s"] for o in obs])
    steps = np.diff(times)
    assert steps.min() >= 1 / 30 - 1e-6 and np.median(steps) < 1 / 30 + 0.002  # 30 Hz of simulated time
    assert np.all(np.diff([o["frame_index"] for o in obs]) == 1)  # none lost between server and client
    assert result["foxglove_contours"] >= len(obs)
    assert all(len(o["points_m"]) == LINKS + 1 and o["points_m"][0] == [0.0, 0.0] for o in obs)
    # the loop as the firmware shapes it: it flies while the rope runs, and the retract pulls it in
    reach = np.array([max(np.hypot(*p) for p in o["points_m"]) for o in obs])
    speed = np.array([o["rope_speed_mps"] for o in obs])
    assert speed.max() > 3.5 and speed[-1] < 0.1
    flying = reach[speed > 3.5]
    assert reach[-1] < np.median(flying) - 0.1, (reach[-1], np.median(flying))

    # /loop/scene: a foxglove.SceneUpdate the 3D panel draws, decoded with the schema the server advertised
    scene_cls = _decoder(channels["/loop/scene"])
    assert channels["/loop/scene"]["schemaName"] == "foxglove.SceneUpdate"
    scenes = [scene_cls.FromString(b) for b in got["/loop/scene"]]
    assert len(scenes) == len(obs)
    last = {e.id: e for e in scenes[-1].entities}
    assert {"rope", "module", "object/golf_ball"} <= set(last)
    rope = np.array([[p.x, p.y, p.z] for p in last["rope"].lines[0].points])
    assert rope.shape == (LINKS + 1, 3) and all(e.frame_id == "world" for e in last.values())
    # the scene's rope is the contour's, in the world: same link lengths
    assert np.allclose(np.linalg.norm(np.diff(rope, axis=0), axis=1)[:-1],
                       np.linalg.norm(np.diff(np.array(obs[-1]["points_m"]), axis=0), axis=1)[:-1], atol=0.05)

    # beside the loop, the firmware's stream and the script's commands
    telemetry = [json.loads(b) for b in got["/device/telemetry"]]
    assert {"AIRBORNE", "RETRACT"} <= {t["state"] for t in telemetry}
    commands = {(json.loads(b)["message"], json.loads(b)["verdict"]) for b in got["/host/command"]}
    assert {("ARM", "ACK"), ("GRASP", "ACK")} <= commands


def test_the_contour_frame_is_the_shape_tables_for_an_upright_module_and_the_loop_plane_when_rolled() -> None:
    pts = np.array([[1.0, 2.0, 1.0], [1.3, 2.0, 1.1], [1.5, 2.0, 0.9]])
    upright = np.eye(3)  # launch axis x, out-of-plane y, up z
    np.testing.assert_allclose(loop_plane_points_m(pts, pts[0], upright), [[0, 0], [0.3, 0.1], [0.5, -0.1]],
                               atol=1e-12)
    # rolled 90 deg about the launch axis: the loop plane is horizontal, its second axis across (-y here)
    rolled = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    flat = np.array([[1.0, 2.0, 1.0], [1.3, 2.2, 1.0], [1.5, 1.9, 1.0]])
    np.testing.assert_allclose(loop_plane_points_m(flat, flat[0], rolled), [[0, 0], [0.3, -0.2], [0.5, 0.1]],
                               atol=1e-12)


def test_live_view_options_are_checked_and_foxglove_needs_a_scenario() -> None:
    with pytest.raises(ValueError, match="rate_hz"):
        ScenarioLiveView(None, rate_hz=0)
    with pytest.raises(ValueError, match="speedup"):
        ScenarioLiveView(None, speedup=float("nan"))
    err = io.StringIO()
    status = main(["sil", "--foxglove", "0"], Environment(io.StringIO(), err, {}))
    assert status == ExitStatus.USAGE and "--foxglove needs --scenario" in err.getvalue()
