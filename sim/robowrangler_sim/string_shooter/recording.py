"""Recordings of the string shooter driven by the real SIL firmware, in the project's MCAP schema.

The stand-in for a board recording with a camera on the loop: the SIL firmware (the firmware core with the
sil HAL, its own process) and the drive and spindle plants run in lockstep (SilSession); a scripted host
(ScriptedHost, real signed UDP) sends the script's commands at their simulated times; every frame the host
sends and receives goes through the recorder's LinkRecorder, so /device/telemetry, /device/event,
/host/command and /link/gap are exactly what `wrangler record` writes for the same frames (the one public
recording API: robowrangler.recorder.RecordingSession, fed here by robowrangler_sim.sil.recording_host), and
/device/params holds the parameters read at the start (PARAM_GET, as `wrangler record` does). The
first-principles rope runs beside it: its nip speed follows the drive plant's wheel surface speed tick by
tick (np.interp over the 1 ms samples), its guide travel follows the spindle plant's guide, its inclination
follows the script (the robot arm). So the loop lifts when the firmware's rope passes the takeoff speed.
Each camera frame (camera_rate_hz) gives a /loop/observation (contour as a camera would measure it:
seeded Gaussian noise per point, rope speed unknown = null); /sim/plant_truth (truth_rate_hz) holds the
plants' true values and the rope's.

    summary = record_string_shooter("run.mcap", script=RecordingScript.default(), seed=0, progress=True)

    uv run python -m robowrangler_sim.string_shooter.recording run.mcap --seed 0 [--short] [--camera-rate-hz 30]

Time base "simulation": log times are ns of simulated time (the firmware's clock). Deterministic: the same
seed and script give the same file byte for byte except the /meta value created_utc (wall clock at start),
at any machine speed (the writer times its chunks on the simulated clock).

The coupling is one-way: the drive plant keeps its own rope-load model (drag of the exposed rope); the
string shooter's nip traction does not load the motors (about 9 mN steady, up to 25 mN while spinning up
in the default script; the drive plant's own drag is about 10 mN at 4 m/s; both are small beside what the
motors deliver).
"""

from __future__ import annotations

import argparse
import hashlib
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

import numpy as np

from robowrangler.protocol.generated import KEY_LEN
from robowrangler.recorder import RecordingSession
from robowrangler_sim.plants import DriveParams
from robowrangler_sim.plants.spindle import SpindleParams
from robowrangler_sim.sil import SilError, SilSession
from robowrangler_sim.sil.recording_host import RecordingHost, RecordingRunError, read_params

from .model import Frame, StringShooter
from .motion import ModuleMotion
from .observations import is_airborne, loop_observation_record
from .params import ShooterParams, StringShooterParamError
from .recording_script import RecordingScript

CAMERA_ID = "side0"
_OBSERVATION_SEED_SALT = 0x0B5E


@dataclass(frozen=True)
class RecordingSummary:
    """What a run wrote, and how fast.

    Attributes:
        path: the MCAP file.
        duration_s: simulated time recorded [s].
        wall_s: wall time of the run [s] (firmware start to file closed).
        telemetry, events, commands, gaps, observations, plant_truth: messages per channel.
        tov_mps: the firmware's ToV parameter as read (None when parameters were not read).
        first_airborne_s: time of the first camera frame that shows the loop flying, None if none.
    """

    path: Path
    duration_s: float
    wall_s: float
    telemetry: int
    events: int
    commands: int
    gaps: int
    observations: int
    plant_truth: int
    tov_mps: float | None
    first_airborne_s: float | None

    @property
    def sim_s_per_wall_s(self) -> float:
        return self.duration_s / self.wall_s if self.wall_s > 0 else math.inf


def sil_key_for_seed(seed: int) -> bytes:
    """The link key a recording run provisions into its SIL device: derived from the seed (reproducible runs;
    a simulated device's key, never a real one)."""
    return hashlib.sha256(f"robowrangler string-shooter recording {seed}".encode()).digest()[:KEY_LEN]


class _DriveWindow:
    """The drive and spindle plants' values per tick, as the rope's inputs (np.interp between ticks).

    Holds the samples the rope has not consumed yet, plus the one before them."""

    def __init__(self, t_s: float, wheel_speed_mps: float, guide_travel_m: float) -> None:
        self._rows: list[tuple[float, float, float]] = [(t_s, wheel_speed_mps, guide_travel_m)]
        self._arrays: np.ndarray | None = None

    def append(self, t_s: float, wheel_speed_mps: float, guide_travel_m: float) -> None:
        self._rows.append((t_s, wheel_speed_mps, guide_travel_m))
        self._arrays = None

    def consumed_until(self, t_s: float) -> None:
        """Forget samples the rope no longer needs (it has advanced to t_s)."""
        k = 0
        while k + 1 < len(self._rows) and self._rows[k + 1][0] <= t_s:
            k += 1
        if k:
            del self._rows[:k]
            self._arrays = None

    def _cols(self) -> np.ndarray:
        if self._arrays is None:
            self._arrays = np.array(self._rows, dtype=float).T
        return self._arrays

    def wheel_speed_mps(self, t_s: np.ndarray) -> np.ndarray:
        cols = self._cols()
        return np.interp(t_s, cols[0], cols[1])

    def guide_travel_m(self, t_s: np.ndarray) -> np.ndarray:
        cols = self._cols()
        return np.interp(t_s, cols[0], cols[2])


class _Run:
    """One recording run: owns the SIL session, the rope, the writer and the output schedule."""

    def __init__(self, path: Path, *, script: RecordingScript, seed: int, camera_rate_hz: float,
                 truth_rate_hz: float, shooter_params: ShooterParams, drive_params: DriveParams | None,
                 spindle_params: SpindleParams | None, observation_points: int, observation_noise_m: float,
                 read_params: bool, progress: TextIO | None) -> None:
        self.path = path
        self.script = script
        self.seed = seed
        self.camera_period_s = 1.0 / camera_rate_hz
        self.truth_period_s = 1.0 / truth_rate_hz
        self.n_camera = int(round(script.duration_s * camera_rate_hz))
        self.n_truth = int(round(script.duration_s * truth_rate_hz))
        self.shooter_params = shooter_params
        self.drive_params = drive_params
        self.spindle_params = spindle_params
        self.observation_points = observation_points
        self.observation_noise_m = observation_noise_m
        self.read_params = read_params
        self.progress = progress
        self.rng = np.random.default_rng([seed, _OBSERVATION_SEED_SALT])
        self.k_camera = 0
        self.k_truth = 0
        self.observations = 0
        self.first_airborne_s: float | None = None
        self.tov_mps: float | None = None
        self.loop_airborne = False

    # ---------------------------------------------------------------------------------------------
    def _guide_travel_m(self) -> float:
        stroke_m = self.shooter_params.geometry.guide_stroke_m
        return min(max(self.sil.spindle_out.guide_position_mm * 1e-3, 0.0), stroke_m)

    def run(self) -> RecordingSummary:
        wall0 = self._wall0 = self._last_progress = time.perf_counter()
        script = self.script
        with SilSession(drive_params=self.drive_params, spindle_params=self.spindle_params, seed=self.seed,
                        speedup=None, trace_every=0, key=sil_key_for_seed(self.seed)) as sil:
            self.sil = sil
            travel0 = self._guide_travel_m()
            self.window = _DriveWindow(0.0, sil.drive_out.rope_speed_mps, travel0)
            motion = ModuleMotion(wheel_speed_mps=self.window.wheel_speed_mps, phi_rad=script.phi_rad,
                                  guide_travel_m=self.window.guide_travel_m)
            self.shooter = StringShooter(self.shooter_params, loop_length_m=sil.spindle_out.loop_length_m,
                                         motion=motion, initial_shape="hanging", initial_rope_speed_mps=0.0)
            recording = RecordingSession(self.path, source="sil", seed=self.seed, time_base="simulation",
                                         clock_ns=lambda: sil.drive_out.time_us * 1000,
                                         description="string shooter (first-principles rope) driven by the SIL "
                                                     f"firmware; camera {CAMERA_ID} at {1 / self.camera_period_s:g} Hz")
            self.writer = writer = recording.writer
            self.recorder = recorder = recording.recorder
            try:
                self._emit_due(0.0)
                host = RecordingHost(sil, recording, after_tick=self._after_tick)
                if self.read_params:
                    self.tov_mps = read_params(host).get("tov_mps")
                for cmd in script.commands:
                    at_us = round(cmd.at_s * 1e6)
                    while sil.drive_out.time_us < at_us:
                        host.tick()
                    host.send(cmd.message)
                end_us = round(script.duration_s * 1e6)
                while sil.drive_out.time_us < end_us:
                    host.tick()
                recording.close(host_s=sil.time_s)
                host.close()
            finally:
                recording.close()
        if self.progress is not None:
            self._show_progress(final=True)
        return RecordingSummary(
            path=self.path, duration_s=script.duration_s, wall_s=time.perf_counter() - wall0,
            telemetry=recorder.telemetry_count, events=recorder.event_count, commands=recorder.command_count,
            gaps=recorder.gaps_written, observations=self.observations, plant_truth=self.k_truth,
            tov_mps=self.tov_mps, first_airborne_s=self.first_airborne_s)

    # ---------------------------------------------------------------------------------------------
    def _after_tick(self) -> None:
        sil = self.sil
        t_s = sil.time_s
        self.window.append(t_s, sil.drive_out.rope_speed_mps, self._guide_travel_m())
        self._emit_due(t_s)
        if self.progress is not None and sil.ticks % 200 == 0:
            now = time.perf_counter()
            if now - self._last_progress >= 1.0:
                self._last_progress = now
                self._show_progress(final=False)

    def _emit_due(self, t_s: float) -> None:
        """Advance the rope to each camera / truth time up to t_s and write what is due there."""
        eps = 1e-9
        while True:
            t_cam = self.k_camera * self.camera_period_s if self.k_camera < self.n_camera else math.inf
            t_truth = self.k_truth * self.truth_period_s if self.k_truth < self.n_truth else math.inf
            t_next = min(t_cam, t_truth)
            if t_next > t_s + eps:
                return
            shooter = self.shooter
            if t_next - shooter.time_s > 0.5 * shooter.dt_s:
                shooter.step_for(t_next - shooter.time_s)
            self.window.consumed_until(shooter.time_s)
            frame = shooter.frame()
            loop_length_m = shooter.loop_length_m()
            self.loop_airborne = is_airborne(frame, loop_length_m=loop_length_m)
            if t_cam <= t_next + eps:
                self._write_observation(frame, t_cam)
                self.k_camera += 1
            if t_truth <= t_next + eps:
                self._write_truth(frame, t_truth, loop_length_m)
                self.k_truth += 1

    def _write_observation(self, frame: Frame, t_s: float) -> None:
        record = loop_observation_record(frame, camera_id=CAMERA_ID, frame_index=self.k_camera,
                                         n_points=self.observation_points)
        pts = np.asarray(record["points_m"])
        if self.observation_noise_m > 0:
            pts = pts + self.rng.normal(0.0, self.observation_noise_m, size=pts.shape)
        record.update(time_s=t_s, rope_speed_mps=None, points_m=[[float(x), float(z)] for x, z in pts])
        self.writer.write("/loop/observation", record, log_time_ns=round(t_s * 1e9))
        self.observations += 1
        if self.loop_airborne and self.first_airborne_s is None:
            self.first_airborne_s = t_s

    def _write_truth(self, frame: Frame, t_s: float, loop_length_m: float) -> None:
        sil, plant = self.sil, self.sil.drive_out
        xz = frame.loop_plane_xz_m()
        record = {
            "time_s": t_s, "rope_speed_mps": plant.rope_speed_mps, "esc_pulse_us": float(sil.last_esc_pulse_us),
            "battery_v": plant.battery_v, "external_rope_load_n": plant.external_rope_load_n,
            "loop_airborne": self.loop_airborne,
            "nip_rope_speed_mps": frame.rope_speed_mps, "wheel_slip_mps": frame.wheel_speed_mps - frame.rope_speed_mps,
            "nip_traction_n": frame.traction_n, "exit_tension_n": frame.exit_tension_n,
            "return_tension_n": frame.return_tension_n, "loop_length_m": loop_length_m,
            "loop_depth_m": float(-np.min(xz[:, 1])), "loop_reach_m": float(np.max(xz[:, 0])),
            "guide_position_m": sil.spindle_out.guide_position_mm * 1e-3, "phi_rad": frame.phi_rad,
        }
        self.writer.write("/sim/plant_truth", record, log_time_ns=round(t_s * 1e9))

    def _show_progress(self, *, final: bool) -> None:
        rec, sil = self.recorder, self.sil
        wall_s = max(time.perf_counter() - self._wall0, 1e-9)
        live = bool(getattr(self.progress, "isatty", lambda: False)())  # a terminal: one line, rewritten
        print(f"{chr(13) if live else ''}  recording {self.path.name}: t = {sil.time_s:6.2f} / "
              f"{self.script.duration_s:.2f} s sim, "
              f"state {rec.latest_state or '-'}, rope {sil.drive_out.rope_speed_mps:5.2f} m/s, "
              f"loop {'flying ' if self.loop_airborne else 'hanging'}, {rec.telemetry_count} telemetry, "
              f"{self.observations} frames, {sil.time_s / wall_s:5.2f} sim s/wall s",
              end="" if live and not final else "\n", file=self.progress, flush=True)


def record_string_shooter(path: str | Path, *, script: RecordingScript | None = None, seed: int = 0,
                          camera_rate_hz: float = 30.0, truth_rate_hz: float = 100.0,
                          shooter_params: ShooterParams | None = None, drive_params: DriveParams | None = None,
                          spindle_params: SpindleParams | None = None, observation_points: int = 40,
                          observation_noise_m: float = 0.002, read_params: bool = True,
                          progress: bool | TextIO = False) -> RecordingSummary:
    """Run the SIL firmware + plants + first-principles rope through a script and write an MCAP recording.

    Args:
        path: output .mcap (replaced if it exists).
        script: commands and module inclination (default: RecordingScript.default(), 12 s).
        seed: plant noise, observation noise and the SIL device's link key; same seed -> same file.
        camera_rate_hz: camera frames per second (0.5 .. 1000); frames at k / rate for k < rate x duration.
        truth_rate_hz: /sim/plant_truth records per second (0.5 .. 1000).
        shooter_params: the rope (default ShooterParams()).
        drive_params, spindle_params: the SIL plants (defaults: the project's).
        observation_points: contour points per observation (>= 2).
        observation_noise_m: standard deviation of the camera's contour error per coordinate [m] (>= 0).
        read_params: read every device parameter into /device/params first (as `wrangler record`).
        progress: True: a progress line on stderr about once a second of wall time; or a text stream.

    Returns a RecordingSummary. Raises StringShooterParamError for bad arguments, SilError if the SIL
    firmware is missing or fails, StringShooterDivergedError if the rope integration blows up (the file is
    then closed and readable up to that point).
    """
    script = RecordingScript.default() if script is None else script
    if not isinstance(script, RecordingScript):
        raise StringShooterParamError(f"script: expected a RecordingScript, got {script!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise StringShooterParamError(f"seed: expected an integer >= 0, got {seed!r}")
    for name, rate in (("camera_rate_hz", camera_rate_hz), ("truth_rate_hz", truth_rate_hz)):
        if not (isinstance(rate, (int, float)) and math.isfinite(rate) and 0.5 <= rate <= 1000.0):
            raise StringShooterParamError(f"{name}: expected a rate in [0.5, 1000] Hz, got {rate!r}")
    if isinstance(observation_points, bool) or not isinstance(observation_points, int) or observation_points < 2:
        raise StringShooterParamError(f"observation_points: expected an integer >= 2, got {observation_points!r}")
    if not (isinstance(observation_noise_m, (int, float)) and math.isfinite(observation_noise_m)
            and observation_noise_m >= 0):
        raise StringShooterParamError(f"observation_noise_m: expected a number >= 0, got {observation_noise_m!r}")
    stream = sys.stderr if progress is True else (progress or None)
    run = _Run(Path(path), script=script, seed=seed, camera_rate_hz=float(camera_rate_hz),
               truth_rate_hz=float(truth_rate_hz), shooter_params=shooter_params or ShooterParams(),
               drive_params=drive_params, spindle_params=spindle_params, observation_points=observation_points,
               observation_noise_m=float(observation_noise_m), read_params=read_params, progress=stream)
    return run.run()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m robowrangler_sim.string_shooter.recording",
                                 description="Record the string shooter driven by the SIL firmware to an MCAP file.")
    ap.add_argument("out", type=Path, help="output .mcap")
    ap.add_argument("--seed", type=int, default=0, help="seed (plant and camera noise, link key)")
    ap.add_argument("--short", action="store_true", help="the 4 s script instead of the 12 s default")
    ap.add_argument("--camera-rate-hz", type=float, default=30.0, help="camera frames per second")
    ap.add_argument("--truth-rate-hz", type=float, default=100.0, help="/sim/plant_truth records per second")
    ap.add_argument("--noise-mm", type=float, default=2.0, help="camera contour noise (1 sigma), mm")
    args = ap.parse_args(argv)
    script = RecordingScript.short() if args.short else RecordingScript.default()
    try:
        s = record_string_shooter(args.out, script=script, seed=args.seed, camera_rate_hz=args.camera_rate_hz,
                                  truth_rate_hz=args.truth_rate_hz, observation_noise_m=args.noise_mm * 1e-3,
                                  progress=True)
    except (StringShooterParamError, SilError, RecordingRunError, OSError) as exc:
        print(f"recording: {exc}", file=sys.stderr)
        return 1
    airborne = "never" if s.first_airborne_s is None else f"from {s.first_airborne_s:.2f} s"
    print(f"wrote {s.path}: {s.duration_s:g} s simulated in {s.wall_s:.1f} s wall ({s.sim_s_per_wall_s:.2f} sim s/wall s); "
          f"{s.telemetry} telemetry, {s.events} events, {s.commands} commands, {s.gaps} gaps, {s.observations} "
          f"observations, {s.plant_truth} plant truth; loop airborne {airborne}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
