"""A scenario live in Foxglove (`wrangler sil --scenario NAME --foxglove [PORT]`): the loop as the chain has it, with
the firmware's own stream beside it.

    live = FoxgloveLiveView(port=8765)                       # robowrangler.recorder.live_view (foxglove-sdk)
    outcome = run_scenario("mug", live=ScenarioLiveView(live, speedup=1.0))

On the live view's server (ws://127.0.0.1:PORT), at ``rate_hz`` per simulated second (30 by default):

* ``/loop/observation``: the recordings' loop contour (protocol/recording/schema.md, JSON Schema
  robowrangler.loop_observation.v1) with ``camera_id`` "sil-chain": the chain's N + 1 joint points (links of
  equal length: equally spaced along the rope) from the guide exit to the last link's end, in the loop plane,
  origin at the exit, x horizontal along the launch direction, z = x cross the module's out-of-plane axis: up
  for an unrolled module (the shape table's frame, phi as the tables have it), across for a rolled one (the
  grasp scenarios' horizontal loop, seen from above); ``phi_rad`` and ``rope_speed_mps`` at that instant;
* ``/loop/scene``: a foxglove.SceneUpdate in frame "world" (z up, metres) for the 3D panel: the rope as a line
  through the joint points, the module as a box, each object as a marker at its position;

and everything the scenario's host and the firmware exchange, as `wrangler proxy --foxglove` serves it: the
telemetry, the events and each command with its verdict (the recordings' channels; the host's frames, stamped
with simulated time). Log times are the host's wall clock, so Foxglove's timeline runs as the user watches.

The run is paced to ``speedup`` simulated seconds per wall second (None: as fast as it goes), so that a person
can follow it; the live view only reads the simulation: the outcome is the same with or without it. Publishing
costs one projection of N + 1 points and two small messages per 1/rate_hz simulated seconds (bench:
``uv run python bench/bench_live_loop.py``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from robowrangler.recorder.link import LinkRecorder

from robowrangler_sim.scenarios.wall_pacer import WallPacer

CAMERA_ID = "sil-chain"
CONTOUR_TOPIC = "/loop/observation"
SCENE_TOPIC = "/loop/scene"
DEFAULT_RATE_HZ = 30.0
MODULE_SIZE_M = (0.10, 0.06, 0.06)
OBJECT_MARKER_M = 0.04
ROPE_WIDTH_M = 0.004


def loop_plane_points_m(points_m: np.ndarray, exit_m: np.ndarray, module_rot: np.ndarray) -> np.ndarray:
    """World points (K, 3) in the loop plane's frame (K, 2): origin at the exit, x = the launch axis (module x)
    projected on the horizontal, z = x cross the module's out-of-plane axis (module y), projected on the plane
    normal to x (see module doc)."""
    pts = np.asarray(points_m, dtype=float) - np.asarray(exit_m, dtype=float)
    fwd = module_rot[:, 0].copy()
    fwd[2] = 0.0
    norm = float(np.linalg.norm(fwd))
    fwd = fwd / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])  # launch axis vertical: any horizontal
    y = module_rot[:, 1]
    up = np.array([fwd[1] * y[2] - fwd[2] * y[1], fwd[2] * y[0] - fwd[0] * y[2], fwd[0] * y[1] - fwd[1] * y[0]])
    up -= up.dot(fwd) * fwd
    norm = float(np.linalg.norm(up))
    up = up / norm if norm > 1e-9 else np.array([0.0, 0.0, 1.0])
    return pts @ np.stack([fwd, up], axis=1)


class ScenarioLiveView:
    """The loop, the telemetry, the events and the commands of one scenario run on a FoxgloveLiveView.

    Args:
        live: the server (robowrangler.recorder.live_view.FoxgloveLiveView); closed by its owner.
        rate_hz: loop messages per simulated second (1..200).
        speedup: simulated seconds per wall second (1 = real time); None = unpaced.
        clock_s, sleep_s: wall clock and sleep (s), injectable for the pacing.

    run_scenario calls tap_sent/tap_received with its host's frames (stamped with simulated seconds), on_tick
    once per control tick, and finish at the end. Attributes: ``contours`` (loop messages published so far),
    ``publish_wall_s`` (wall seconds spent publishing them),
    ``recorder`` (the LinkRecorder of the host's frames: telemetry_count, event_count, command_count).
    """

    def __init__(self, live, *, rate_hz: float = DEFAULT_RATE_HZ, speedup: float | None = 1.0,
                 clock_s: Callable[[], float] = time.perf_counter, sleep_s: Callable[[float], None] = time.sleep) -> None:
        if not (isinstance(rate_hz, (int, float)) and math.isfinite(rate_hz) and 1.0 <= rate_hz <= 200.0):
            raise ValueError(f"rate_hz: expected 1..200 loop messages per simulated second, got {rate_hz!r}")
        if speedup is not None and not (isinstance(speedup, (int, float)) and math.isfinite(speedup) and speedup > 0):
            raise ValueError(f"speedup: expected a positive factor or None (unpaced), got {speedup!r}")
        import foxglove.channels

        self.live = live
        self.period_s = 1.0 / float(rate_hz)
        self.speedup = speedup
        self.recorder = LinkRecorder(live)
        self._scene = foxglove.channels.SceneUpdateChannel(SCENE_TOPIC, context=live.context)
        self._next_s = -math.inf
        self._pacer = WallPacer(speedup, clock_s=clock_s, sleep_s=sleep_s)
        self.contours = 0
        self.publish_wall_s = 0.0  # wall time spent publishing (what the live view costs the run)

    # --- the host's frames (RecordingHost's recording interface) ----------------------------------------
    def tap_sent(self, frame: bytes, host_s: float | None = None) -> None:
        self.recorder.on_sent(frame, host_s)

    def tap_received(self, frame: bytes, host_s: float | None = None) -> None:
        self.recorder.on_received(frame, host_s)

    # --- the loop ---------------------------------------------------------------------------------------
    def on_tick(self, chain, *, outputs, rope_speed_mps: float) -> None:
        """After each control tick: the loop at rate_hz of simulated time, then the pacing. ``outputs``: the
        chain's PlantOutputs of its last step (None before the first)."""
        t_s = chain.time_s
        if t_s < self._next_s - 1e-9:  # simulated times are sums of steps: allow their rounding
            return
        self._next_s = t_s + self.period_s
        start_s = time.perf_counter()
        self.publish(chain, outputs=outputs, rope_speed_mps=rope_speed_mps)
        self.publish_wall_s += time.perf_counter() - start_s
        self._pacer.pace(t_s)

    def publish(self, chain, *, outputs, rope_speed_mps: float) -> None:
        """One /loop/observation and one /loop/scene of the chain now (read only: the run does not change)."""
        import mujoco

        points = chain.chain_points_m()
        rot = np.empty(9)
        quat = np.asarray(chain.module_quat_wxyz(), dtype=float)
        mujoco.mju_quat2Mat(rot, quat)
        rot = rot.reshape(3, 3)
        plane = loop_plane_points_m(points, chain.exit_pos_m(), rot)
        log_ns = self.live.now_ns()
        self.live.write(CONTOUR_TOPIC, {
            "time_s": round(float(chain.time_s), 6), "camera_id": CAMERA_ID, "frame_index": self.contours,
            "phi_rad": float(chain.phi_rad), "rope_speed_mps": float(rope_speed_mps),
            "points_m": np.round(plane, 5).tolist()}, log_time_ns=log_ns)
        objects = {} if outputs is None else outputs.object_pos_m
        self._scene.log(self._scene_update(chain, points, quat, objects), log_time=log_ns)
        self.contours += 1

    def _scene_update(self, chain, points: np.ndarray, quat_wxyz: np.ndarray, objects: dict):
        from foxglove import messages as fm

        module = chain.module_pos_m()
        w, x, y, z = (float(q) for q in quat_wxyz)
        entities = [
            fm.SceneEntity(frame_id="world", id="rope", lines=[fm.LinePrimitive(
                type=fm.LinePrimitiveLineType.LineStrip, thickness=ROPE_WIDTH_M, scale_invariant=False,
                points=[fm.Point3(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in points],
                color=fm.Color(r=0.95, g=0.55, b=0.1, a=1.0))]),
            fm.SceneEntity(frame_id="world", id="module", cubes=[fm.CubePrimitive(
                pose=fm.Pose(position=fm.Vector3(x=float(module[0]), y=float(module[1]), z=float(module[2])),
                             orientation=fm.Quaternion(x=x, y=y, z=z, w=w)),
                size=fm.Vector3(x=MODULE_SIZE_M[0], y=MODULE_SIZE_M[1], z=MODULE_SIZE_M[2]),
                color=fm.Color(r=0.2, g=0.22, b=0.26, a=1.0))]),
        ]
        for name, p in objects.items():
            entities.append(fm.SceneEntity(frame_id="world", id=f"object/{name}", spheres=[fm.SpherePrimitive(
                pose=fm.Pose(position=fm.Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2])),
                             orientation=fm.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
                size=fm.Vector3(x=OBJECT_MARKER_M, y=OBJECT_MARKER_M, z=OBJECT_MARKER_M),
                color=fm.Color(r=0.8, g=0.15, b=0.1, a=0.8))]))
        return fm.SceneUpdate(entities=entities)

    def finish(self, host_s: float) -> None:
        """End of the run: unanswered commands NO_REPLY (as a recording ends)."""
        self.recorder.finish(host_s)

    def close(self) -> None:
        self._scene.close()
