"""Run a wrangling scenario with the firmware in the loop: SIL firmware + drive + spindle + rope chain.

    from robowrangler_sim.scenarios import run_scenario
    outcome = run_scenario("mug", seed=0, progress=print)
    outcome.secured, outcome.grasp_end, outcome.firmware_path

Grasp scenarios (a free object on the floor), all in simulated time:
  0. scene: the module is rolled by roll_deg (90: the loop plane is horizontal) with its exit
     exit_height_m above the floor, and the loop has been laid around the object (the object at
     object_x_frac of the loop's reach, centred between the branches: the plant-level grasp's
     geometry, grasp.grasp_scene). Why not bring the flying loop over the object with the robot's leg:
     the paper's out-of-plane joints have zero stiffness, so a horizontal loop has nothing holding it
     off the floor; it drapes on the floor from the exit and sweeps whatever it is moved over (tried:
     an approach from 15 cm above the mug dragged the loop across the floor and left the mug outside).
     A closed loop at floor level cannot surround an object without passing over it.
  1. boot: the SIL device is provisioned, the ESC arming hold passes (0.6 s), the rope stands, so the
     loop has no lift and lies on the floor around the object; the scenario's firmware parameters are
     set (PARAM_SET); HOME (the spindle finds its end stop by stall; the loop follows the guide).
  2. spin up: ARM, SET_ROPE_SPEED airborne_speed; the rope passes ToV x margin (AIRBORNE) and the drives
     lift the loop back into its shape around the object (lift.py).
  3. GRASP (the real command): the firmware relaxes (rope speed to 0: the loop loses lift and falls on the
     floor around the object), then retracts the guide until the spindle's load says secured
     (LOAD_SECURED -> HOLD) or the stroke ends (STROKE_END -> ARMED; the self-locking screw keeps the
     guide where it stopped).
  4. hold: hold_s, nothing moves.
  5. pull: the module moves back pull_m (and up lift_m) over pull_s. The simulation judges, over the
     second half of the pull, whether the loop keeps hold of the object and the object follows the
     module (secured.SecuredMonitor, the plant-level judgement) or it slipped out.
The door scenario positions with the robot's leg: the vertical loop (whose plane gravity does not
leave) flies up to the door beside its lever handle and the module slides sideways so that the loop
threads over the lever's free end; then GRASP: RETRACT tightens the loop on the bar until the load says
secured (LOAD_SECURED -> HOLD; the door's closer holds the leaf shut meanwhile) and the robot pulls the
module back, opening the door on its hinge (catalogue.DOOR_LEAF, chain/door.py). "held" means the rope
still touches and pulls the handle through the second half of the pull; ``door_opening_deg`` says how far
the door opened.

A ChainDivergenceError (MuJoCo blew up on the light links, known on the door handle) ends the run: it is
reported in the outcome (``diverged``), never hidden; the CLI exits non-zero on it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler.protocol import generated as gen
from robowrangler_sim.chain.default_table import default_or_synthetic_table
from robowrangler_sim.chain.door import door_placement, leaf_opening_rad
from robowrangler_sim.chain.errors import ChainDivergenceError
from robowrangler_sim.chain.grasp import grasp_scene
from robowrangler_sim.chain.objects import ObjectPlacement, get_object
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
from robowrangler_sim.chain.secured import SecuredMonitor
from robowrangler_sim.scenarios.base_trajectory import BaseTrajectory
from robowrangler_sim.scenarios.caption import VERDICT_HOLD_S, captioned, frame_caption, verdict_caption
from robowrangler_sim.scenarios.catalogue import ScenarioError, ScenarioSpec, get_scenario
from robowrangler_sim.scenarios.chain_bridge import ChainBridge
from robowrangler_sim.sil.recording_host import RecordingHost
from robowrangler_sim.sil.scripted_host import ScriptedHost
from robowrangler_sim.shape_table import ShapeTable
from robowrangler_sim.sil.session import SilSession

P = gen.PARAMS_BY_NAME

BOOT_S = 0.6                # ESC arming hold of the SIL device
RISE_S = 1.5                # after AIRBORNE: the chain rises into its shape (drives: tau = kd/kp = 0.5 s)
FORWARD_S = 1.5             # door: the sideways move that threads the loop over the lever
CLOSE_IN_S = 0.5            # hinged door: the flying loop moves up to the leaf before the sideways move
SETTLE_S = 0.5              # after positioning
HOMING_TIMEOUT_S = 30.0
GRASP_TIMEOUT_S = 30.0
SCENARIO_PLANT_TIMEOUT_S = 60  # how long the SIL firmware waits for the plant's next tick before it gives up


@dataclass
class ScenarioOutcome:
    """What the simulation says about one scenario run (SI units).

    Attributes:
        name, object_name, kind, seed, n_links, chain_noise_rad: what ran.
        verdict: "secured" / "slipped" (grasp), "held" / "lost" (door), "diverged", or "firmware: ..." when the
            firmware did not get through the script (a NACK, a fault, a state not reached).
        secured: True if secured/held, False if slipped/lost, None if the run did not reach the judgement.
        firmware_path: [(state_from, state_to, cause)] names of the STATE_CHANGED events, in order.
        grasp_end: cause that ended RETRACT ("LOAD_SECURED" -> HOLD, "STROKE_END" -> ARMED, ...), or None.
        guide_at_grasp_end_mm: spindle guide position when RETRACT ended (plant truth), mm.
        peak_guide_load_n: largest chain load on the guide (bridge), N.
        follow_ratio, touching_fraction, mean_pull_force_n: the judgement's figures (secured.SecuredMonitor).
        drag_force_n: force that slides the object on the floor (0 for a fixture), N.
        door_opening_deg: hinged door: the leaf's opening angle at the end of the pull, deg (nan otherwise).
        diverged: the ChainDivergenceError message, or None.
        simulated_s, wall_s: simulated time reached, wall time of the run.
        trace: per-sample rows (time_s, phase, state, rope_speed_mps, guide_mm, guide_load_n,
            spindle_load_permille (the firmware's last reported AX-12A load), base_pos_m, object_com_m,
            chain_force_n, loop_tip_pos_m, door_opening_deg (nan but for a hinged door)).
        frames_written: PNG/MP4 paths written with render_dir (the last PNG, NAME_verdict.png, is the run's last
            frame captioned with the verdict; the MP4 ends on it).
        frame_captions: {PNG path: its caption} (caption.py: time, firmware state, rope speed, guide, phase).
        shape_table_source: the ``source`` of the shape table the chain ran on.
    """

    name: str
    object_name: str
    kind: str
    seed: int
    n_links: int
    chain_noise_rad: float = 0.0
    verdict: str = "not run"
    secured: bool | None = None
    firmware_path: list = field(default_factory=list)
    grasp_end: str | None = None
    guide_at_grasp_end_mm: float = float("nan")
    peak_guide_load_n: float = 0.0
    follow_ratio: float = float("nan")
    touching_fraction: float = 0.0
    mean_pull_force_n: float = 0.0
    drag_force_n: float = 0.0
    door_opening_deg: float = float("nan")
    diverged: str | None = None
    simulated_s: float = 0.0
    wall_s: float = 0.0
    trace: list = field(default_factory=list)
    frames_written: list = field(default_factory=list)
    frame_captions: dict = field(default_factory=dict)
    shape_table_source: str = ""


class ScenarioInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM turned into it) during a scenario: the firmware was stopped, what was drawn so far
    written. `outcome` holds the partial run (verdict "interrupted", firmware_path, simulated_s,
    frames_written); `phase` is the script phase that was running."""

    def __init__(self, outcome: ScenarioOutcome, phase: str) -> None:
        super().__init__(f"interrupted in phase {phase} at {outcome.simulated_s:.1f} simulated s")
        self.outcome = outcome
        self.phase = phase


class _FirmwareStopped(Exception):
    """The firmware did not get through the script (message says where)."""


class _Run:
    """One scenario run: the session, the host, the chain, the bridge, sampling and rendering."""

    def __init__(self, spec: ScenarioSpec, *, seed: int, n_links: int, sample_s: float,
                 progress: Callable[[str], None] | None, render_dir: Path | None, render_every: int,
                 render_fps: float, chain_noise_rad: float, table: ShapeTable | None = None) -> None:
        self.spec = spec
        self.chain_noise_rad = chain_noise_rad
        self.script = spec.script
        self.sample_us = round(sample_s * 1e6)
        self.progress = progress
        self.render_dir = render_dir
        self.render_every = render_every
        self.firmware_params = dict(spec.firmware_params)
        self.frame_stride = max(1, round(1.0 / (sample_s * render_fps)))
        self.params = ChainParams(**{**dict(spec.chain_params), "n_links": n_links})
        self.table = default_or_synthetic_table() if table is None else table
        self.phase = "boot"
        self.outcome = ScenarioOutcome(name=spec.name, object_name=spec.object_name, kind=spec.kind, seed=seed,
                                       n_links=n_links, chain_noise_rad=float(chain_noise_rad),
                                       shape_table_source=self.table.source)
        self.seed = seed
        self.monitor: SecuredMonitor | None = None
        self._next_sample_us = 0
        self._next_report_s = 0.0
        self._renderer = None
        self._frames: list = []
        self._last_frame: tuple | None = None  # (raw RGB, caption) of the latest rendered frame
        self._sample_index = 0
        self.watch: Callable[[ChainPlant], None] | None = None
        self.live = None  # a live_loop.ScenarioLiveView: the host's frames and the loop to Foxglove

    # --- scene -------------------------------------------------------------------------------
    def build(self) -> None:
        spec, script = self.spec, self.script
        obj = get_object(spec.object_name)
        quat = pitch_quat_wxyz(math.radians(script.phi_deg), roll_rad=math.radians(script.roll_deg))
        if spec.kind == "grasp":
            placed, base = grasp_scene(obj, table=self.table, params=self.params, script=script, seed=self.seed)
            placement = placed.objects[0]
            self.grasp_pos_m = np.asarray(base, dtype=float)
            start = self.grasp_pos_m.copy()
            self.outcome.drag_force_n = max(self.params.floor_friction, obj.friction) * obj.mass_kg * 9.81
        else:
            placement, start = self._door_geometry(obj)
        self.trajectory = BaseTrajectory(start_pos_m=start, quat_wxyz=quat)
        self.placement = placement
        # the plant's side does slow work between ticks (MuJoCo contacts, an OSMesa frame, the viewer): on a busy
        # machine the first rendered frame alone took over the firmware's default 10 s wait for its sensors
        self.sil = SilSession(speedup=None, seed=self.seed, trace_every=0, plant_timeout_s=SCENARIO_PLANT_TIMEOUT_S)
        guide = min(max(self.sil.spindle_out.guide_position_mm, 0.0), self.params.guide_stroke_mm)
        self.chain = ChainPlant(table=self.table, params=self.params, objects=(placement,), floor_height_m=0.0,
                                initial=PlantInputs(rope_speed_mps=0.0, guide_position_mm=guide,
                                                    base_pos_m=tuple(start), base_quat_wxyz=quat),
                                airborne=spec.kind == "grasp", seed=self.seed,
                                initial_noise_rad=self.chain_noise_rad)
        self.bridge = ChainBridge(self.sil, self.chain, self.trajectory).install()

    def _door_geometry(self, obj) -> tuple[ObjectPlacement, np.ndarray]:
        """Door face at x = 0 facing -x, lever bar along y at x = -0.06 m, z = 1.0 m, free end at y = -0.12 m.

        The vertical loop (x-z plane) is launched towards the door with its tip 4 cm beyond the bar
        (2 cm short of the door) and its two branches above and below the bar's height; the module
        starts 0.45 m to the side of the bar and slides along y so that the loop threads over the
        bar's free end, 4 cm short of the stand-off."""
        script = self.script
        contour = self.table.contour(script.phi_deg, rope_speed_mps=script.airborne_speed_mps)
        arc = float(np.sum(np.linalg.norm(np.diff(contour, axis=0), axis=1)))
        contour = contour * (self.params.home_loop_length_m / arc)
        tip = int(np.argmax(contour[:, 0]))
        reach = float(contour[tip, 0])
        z_tip = float(contour[tip, 1])
        bar_x, bar_z = -0.060, 1.0
        exit_x = bar_x + 0.04 - reach
        exit_z = bar_z - z_tip
        self.grasp_pos_m = np.array([exit_x, -0.08, exit_z])
        if self.spec.door_leaf is None:  # the handle on a fixed door (the catalogue's fixture)
            placement = ObjectPlacement(spec=obj, pos_m=(0.0, 0.0, 0.0))
            self.approach_pos_m = self.grasp_pos_m + np.array([0.0, -0.45, 0.0])
        else:  # on a hinged leaf: it spans y -0.80..0.06, where the resting loop (0.95 m long) would reach
            # into it from 0.84 m away, so the approach starts 0.15 m further back
            placement = door_placement(self.spec.door_leaf)
            self.approach_pos_m = self.grasp_pos_m + np.array([-0.15, -0.45, 0.0])
        return placement, self.approach_pos_m.copy()

    # --- running -----------------------------------------------------------------------------
    def note(self, text: str) -> None:
        if self.progress is not None:
            self.progress(f"[{self.sil.time_s:6.2f} s] {text}")

    def tick(self) -> None:
        self.host.tick()
        if self.watch is not None:
            self.watch(self.chain)
        if self.live is not None:
            self.live.on_tick(self.chain, outputs=self.bridge.outputs, rope_speed_mps=self.sil.drive_out.rope_speed_mps)
        t_us = self.sil.drive_out.time_us
        if t_us >= self._next_sample_us:
            self._next_sample_us += self.sample_us
            self._sample()
        if self.sil.time_s >= self._next_report_s:
            self._next_report_s += 2.0
            tel = self.host.last_telemetry
            state = gen.State(tel.state).name if tel is not None else "-"
            self.note(f"{self.phase:9s} state {state:9s} rope {self.sil.drive_out.rope_speed_mps:5.2f} m/s, guide "
                      f"{self.sil.spindle_out.guide_position_mm:6.1f} mm, load {self.bridge.guide_load_n:6.2f} N, "
                      f"lift {self.chain.lift:4.2f}")

    def run_for(self, duration_s: float) -> None:
        end_us = self.sil.drive_out.time_us + round(duration_s * 1e6)
        while self.sil.drive_out.time_us < end_us:
            self.tick()

    def run_until(self, predicate, *, timeout_s: float, what: str) -> None:
        end_us = self.sil.drive_out.time_us + round(timeout_s * 1e6)
        while not predicate():
            if self.sil.drive_out.time_us >= end_us:
                raise _FirmwareStopped(f"{what} not reached within {timeout_s:g} s")
            self.tick()

    def command(self, message: gen.Message) -> None:
        seq = self.host.send(message)
        self.run_until(lambda: self.host.verdict_for(seq) is not None, timeout_s=0.1, what=f"{message.NAME} verdict")
        verdict = self.host.verdict_for(seq)
        if not isinstance(verdict, gen.Ack):
            raise _FirmwareStopped(f"{message.NAME} refused: {gen.NackReason(verdict.reason).name}")

    def state(self) -> int | None:
        tel = self.host.last_telemetry
        return None if tel is None else tel.state

    def _state_events(self) -> list:
        return [e for e in self.host.received.events if e.event == gen.EventKind.STATE_CHANGED]

    def _sample(self) -> None:
        chain, name = self.chain, self.spec.object_name
        net = chain.chain_object_net_force_n()[name]
        force = float(np.linalg.norm(net))
        com = chain.object_com_m(name) if self.spec.kind == "grasp" else chain.object_pos_m(name)
        base = self.trajectory.pos_at(chain.time_s)
        tel = self.host.last_telemetry
        opening_deg = (math.degrees(leaf_opening_rad(chain.model, chain.data))
                       if self.spec.door_leaf is not None else float("nan"))
        if self.phase == "pull":
            self.outcome.door_opening_deg = opening_deg
        self.outcome.trace.append(dict(
            time_s=self.sil.time_s, phase=self.phase, state=None if tel is None else int(tel.state),
            rope_speed_mps=self.sil.drive_out.rope_speed_mps, guide_mm=self.sil.spindle_out.guide_position_mm,
            guide_load_n=self.bridge.guide_load_n,
            spindle_load_permille=None if tel is None else int(tel.spindle_load_permille),
            base_pos_m=base, object_com_m=com, chain_force_n=force,
            loop_tip_pos_m=chain.loop_tip_pos_m(), door_opening_deg=opening_deg))
        if self.monitor is not None:
            self.monitor.update(time_s=chain.time_s, object_com_m=com, base_pos_m=base, chain_force_n=force)
        if self.render_dir is not None and self._sample_index % self.frame_stride == 0:
            self._render()
        self._sample_index += 1

    def _render(self) -> None:
        from robowrangler_sim.chain.render import ChainRenderer, write_png

        if self._renderer is None:
            self._renderer = ChainRenderer(self.chain, width_px=640, height_px=360, azimuth_deg=70.0,
                                           elevation_deg=-20.0, distance_m=1.6)
        row = self.outcome.trace[-1]
        text = frame_caption(time_s=row["time_s"], state=None if row["state"] is None else gen.State(row["state"]).name,
                             rope_speed_mps=row["rope_speed_mps"], guide_mm=row["guide_mm"], phase=self.phase)
        self._last_frame = (self._renderer.frame(), text)
        frame = captioned(*self._last_frame)
        self._frames.append(frame)
        if (len(self._frames) - 1) % self.render_every == 0:
            path = self.render_dir / f"{self.spec.name}_{self._sample_index:04d}_{self.phase}.png"
            self.outcome.frames_written.append(str(write_png(path, frame)))
            self.outcome.frame_captions[str(path)] = text

    def finish_render(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self._frames:
            from robowrangler_sim.chain.render import write_mp4, write_png

            fps = 1e6 / (self.sample_us * self.frame_stride)
            raw, text = self._last_frame
            text = f"{text}\n{self.spec.name}: {verdict_caption(self.outcome)}"
            last = captioned(raw, text)
            path = write_png(self.render_dir / f"{self.spec.name}_verdict.png", last)
            self.outcome.frames_written.append(str(path))
            self.outcome.frame_captions[str(path)] = text
            mp4 = write_mp4(self.render_dir / f"{self.spec.name}.mp4",
                            self._frames + [last] * max(1, round(VERDICT_HOLD_S * fps)), fps=fps)
            self.outcome.frames_written.append(str(mp4))

    # --- the script ----------------------------------------------------------------------------
    def script_run(self) -> None:
        script, spec = self.script, self.spec
        # with a live view, a host whose every frame also goes there (stamped with simulated time)
        self.host = ScriptedHost(self.sil) if self.live is None else RecordingHost(self.sil, self.live)
        self.run_for(BOOT_S)
        for pname, value in self.firmware_params.items():
            self.command(gen.ParamSet(P[pname].id, float(value)))
        self.phase = "home"
        self.note("HOME: the spindle seeks its end stop")
        self.command(gen.Home())
        self.run_until(lambda: self.host.last_telemetry.spindle_flags & gen.SpindleFlag.HOMED,
                       timeout_s=HOMING_TIMEOUT_S, what="spindle HOMED")
        self.phase = "spinup"
        self.note(f"ARM, SET_ROPE_SPEED {script.airborne_speed_mps:g} m/s")
        self.command(gen.Arm())
        self.command(gen.SetRopeSpeed(round(script.airborne_speed_mps * 1000)))
        self.run_until(lambda: self.state() == gen.State.AIRBORNE, timeout_s=5.0, what="AIRBORNE")
        self.run_for(RISE_S)
        self.phase = "position"
        self.note("position: the loop flies around the object" if spec.kind == "grasp"
                  else "position: the robot slides the loop over the lever's free end")
        t = self.sil.time_s
        if spec.kind == "grasp":  # the loop already lies around the object (see module doc)
            self.run_for(SETTLE_S)
        else:
            beside = np.array([self.grasp_pos_m[0], self.approach_pos_m[1], self.grasp_pos_m[2]])
            if not np.allclose(beside, self.approach_pos_m):  # hinged door: the flying loop first comes up to
                self.trajectory.move_to(beside, start_s=t, duration_s=CLOSE_IN_S)  # the leaf, clear of it
                self.run_for(CLOSE_IN_S)
                t = self.sil.time_s
            self.trajectory.move_to(self.grasp_pos_m, start_s=t, duration_s=FORWARD_S)
            self.run_for(FORWARD_S + SETTLE_S)
        self.phase = "grasp"
        self.note("GRASP: relax, then retract until the load says secured")
        n_before = len(self._state_events())
        self.command(gen.Grasp())

        def retract_over() -> bool:
            return any(e.state_from == gen.State.RETRACT or e.state_to in (gen.State.FAULT, gen.State.ESTOP)
                       for e in self._state_events()[n_before:])

        self.run_until(retract_over, timeout_s=GRASP_TIMEOUT_S, what="end of RETRACT")
        end = next(e for e in self._state_events()[n_before:]
                   if e.state_from == gen.State.RETRACT or e.state_to in (gen.State.FAULT, gen.State.ESTOP))
        self.outcome.grasp_end = gen.Cause(end.arg).name
        self.outcome.guide_at_grasp_end_mm = self.sil.spindle_out.guide_position_mm
        self.note(f"RETRACT ended: {gen.Cause(end.arg).name} -> {gen.State(end.state_to).name} at guide "
                  f"{self.sil.spindle_out.guide_position_mm:.1f} mm, load {self.bridge.guide_load_n:.2f} N")
        if end.state_to in (gen.State.FAULT, gen.State.ESTOP):
            raise _FirmwareStopped(f"RETRACT ended in {gen.State(end.state_to).name}")
        self.phase = "hold"
        self.run_for(script.hold_s)
        self.phase = "pull"
        self.note(f"pull: the robot moves the module back {script.pull_m:g} m")
        drag = self.outcome.drag_force_n if self.outcome.drag_force_n > 0 else 1.0
        self.monitor = SecuredMonitor(drag_force_n=drag, window_s=0.5 * script.pull_s,
                                      follow_fraction=script.follow_fraction,
                                      contact_fraction=script.contact_fraction)
        t = self.sil.time_s
        self.trajectory.move_to(self.grasp_pos_m + np.array([-script.pull_m, 0.0, script.lift_m]), start_s=t,
                                duration_s=script.pull_s)
        self.run_for(script.pull_s)
        self.judge()

    def judge(self) -> None:
        o, m = self.outcome, self.monitor
        o.follow_ratio = m.follow_ratio
        o.touching_fraction = m.touching_fraction
        o.mean_pull_force_n = m.mean_force_n
        if self.spec.kind == "grasp":
            o.secured = bool(m.secured and not np.isnan(m.follow_ratio))
            o.verdict = "secured" if o.secured else "slipped"
        else:  # a fixture does not follow: held = the rope keeps touching and pulling it
            o.secured = bool(m.touching_fraction >= m.contact_fraction)
            o.verdict = "held" if o.secured else "lost"


def run_scenario(name: str, *, seed: int = 0, n_links: int = 20, sample_s: float = 0.05,
                 progress: Callable[[str], None] | None = None, render_dir: str | Path | None = None,
                 render_png_every: int = 10, render_fps: float = 10.0,
                 firmware_params: dict[str, float] | None = None,
                 chain_noise_rad: float = 0.0,
                 watch: Callable[[ChainPlant], None] | None = None,
                 table: ShapeTable | None = None, live=None) -> ScenarioOutcome:
    """Run scenario ``name`` with the firmware in the loop and judge it (see module doc).

    Args:
        name: a scenario name (catalogue.scenario_names()); ScenarioError otherwise.
        seed: seeds the plants (sensor noise) and the chain; the same seed gives the same outcome and trace.
        n_links: chain links, 10..80.
        sample_s: trace (and render) sampling period, simulated s.
        progress: called with one-line progress messages (phase changes, every 2 simulated seconds).
        render_dir: if given, video frames are drawn at about render_fps (simulated time; at most one per
            sample), written as an MP4 and every render_png_every-th frame as PNG (MuJoCo offscreen: set
            MUJOCO_GL=osmesa before mujoco is imported on a headless machine; OSMesa draws ~10 frames/s here).
        firmware_params: {parameter name: value} sent with PARAM_SET before homing, on top of (and
            overriding) the scenario's own (protocol names and units, e.g. {"guide_max_mm": 120.0}).
        chain_noise_rad: standard deviation of seeded noise on the chain's initial joint angles, rad (a
            perturbed rollout: how robust an outcome is; 0 = none).
        watch: called with the ChainPlant after every control tick (1 ms of simulated time), e.g. a
            viewer.ScenarioViewer that draws the chain in MuJoCo's interactive viewer and paces the run; it must
            only read the plant (the outcome is then the same as without it).
        table: the chain's shape table (e.g. one made by `wrangler identify` from photos); default: the shipped
            default (chain/default_table.py).
        live: a live_loop.ScenarioLiveView: the run live in Foxglove (the loop's contour and scene, the host's
            telemetry, events and commands), paced to its speedup; it only reads (the outcome is the same).
    Returns:
        ScenarioOutcome. The firmware process is stopped before returning, also on errors.
    """
    spec = get_scenario(name)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ScenarioError(f"seed: expected an int >= 0, got {seed!r}")
    if not (isinstance(sample_s, (int, float)) and 0.001 <= sample_s <= 1.0):
        raise ScenarioError(f"sample_s: expected 0.001..1.0 s, got {sample_s!r}")
    if not isinstance(render_png_every, int) or render_png_every < 1:
        raise ScenarioError(f"render_png_every: expected an int >= 1, got {render_png_every!r}")
    if not (isinstance(render_fps, (int, float)) and 0 < render_fps <= 1.0 / sample_s):
        raise ScenarioError(f"render_fps: expected 0 < fps <= 1 / sample_s = {1.0 / sample_s:g}, got {render_fps!r}")
    if not (isinstance(chain_noise_rad, (int, float)) and 0.0 <= chain_noise_rad <= 0.5):
        raise ScenarioError(f"chain_noise_rad: expected 0..0.5 rad, got {chain_noise_rad!r}")
    if table is not None and not isinstance(table, ShapeTable):
        raise ScenarioError(f"table: expected a ShapeTable (ShapeTable.load(path)), got {type(table).__name__}")
    if watch is not None and not callable(watch):
        raise ScenarioError(f"watch: expected a callable(chain_plant) or None, got {type(watch).__name__}")
    if live is not None and not all(callable(getattr(live, m, None)) for m in ("tap_sent", "tap_received", "on_tick",
                                                                             "finish")):
        raise ScenarioError(f"live: expected a ScenarioLiveView (tap_sent, tap_received, on_tick, finish) or None, "
                            f"got {type(live).__name__}")
    overrides = dict(firmware_params or {})
    for pname, value in overrides.items():
        if pname not in P:
            raise ScenarioError(f"firmware_params: expected parameter names of the protocol, got {pname!r}")
        if not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise ScenarioError(f"firmware_params[{pname!r}]: expected a finite number, got {value!r}")
    out_dir = None
    if render_dir is not None:
        out_dir = Path(render_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
    run = _Run(spec, seed=seed, n_links=n_links, sample_s=sample_s, progress=progress, render_dir=out_dir,
               render_every=render_png_every, render_fps=render_fps, chain_noise_rad=chain_noise_rad, table=table)
    run.firmware_params.update(overrides)
    run.watch = watch
    run.live = live
    wall0 = time.perf_counter()
    run.build()
    interrupted = False
    try:
        run.sil.start()
        try:
            run.script_run()
        except KeyboardInterrupt:
            interrupted = True  # finish below as for any end: firmware path, frames so far, SIL stopped
            run.outcome.verdict = "interrupted"
        except ChainDivergenceError as exc:
            run.outcome.diverged = str(exc)
            run.outcome.verdict = "diverged"
            run.note(f"chain simulation diverged: {exc}")
        except _FirmwareStopped as exc:
            run.outcome.verdict = f"firmware: {exc}"
            run.note(f"firmware did not get through the script: {exc}")
        finally:
            if getattr(run, "host", None) is not None:
                run.outcome.firmware_path = [(gen.State(e.state_from).name, gen.State(e.state_to).name,
                                              gen.Cause(e.arg).name) for e in run._state_events()]
                run.host.close()
            run.outcome.peak_guide_load_n = run.bridge.peak_guide_load_n
            run.outcome.simulated_s = run.sil.time_s
            if live is not None:
                live.finish(run.sil.time_s)
            if out_dir is not None:
                run.finish_render()
    finally:
        run.sil.stop()
    run.outcome.wall_s = time.perf_counter() - wall0
    if interrupted:
        raise ScenarioInterrupted(run.outcome, run.phase)
    run.note(f"outcome: {run.outcome.verdict}")
    return run.outcome
