"""Truth recordings for the loop diagnosis' proof: the first-principles string shooter (string_shooter/, richer than
the chain: a continuum rope with axial and normal air drag, bending, waves, wind, the nip) driven through a script of
rope-speed holds and module inclinations, one physical change made to it (or none), filmed by a camera at 30 Hz
with Gaussian contour noise. Written in the documented schema: /loop/observation (rope speed at capture filled in,
rounded to mm/s as telemetry is) and /sim/plant_truth (scoring only).

The rope is settled for SETTLE_S before the recording starts (a recording starts with the loop already flying).

    case = generate_loop_recording("r.mcap", truth=LoopTruth("uniform_wind", wind_mps=1.5), seed=3)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler.recorder import RecordingWriter
from robowrangler_sim.shape_table import resample_by_arc_length
from robowrangler_sim.string_shooter.model import StringShooter
from robowrangler_sim.string_shooter.motion import ModuleMotion
from robowrangler_sim.string_shooter.params import AirParams, ShooterParams

SETTLE_S = 3.0
CAMERA_HZ = 30.0
N_POINTS = 40


@dataclass(frozen=True)
class LoopScript:
    """Rope speed and inclination knots (time_s, value), linear in between, constant outside.

    speed_points: (t, rope speed m/s); phi_points: (t, phi rad); duration_s: recorded time after the settle."""

    duration_s: float
    speed_points: tuple[tuple[float, float], ...]
    phi_points: tuple[tuple[float, float], ...]

    def speed(self, t: np.ndarray) -> np.ndarray:
        p = np.asarray(self.speed_points)
        return np.interp(t - SETTLE_S, p[:, 0], p[:, 1])

    def phi(self, t: np.ndarray) -> np.ndarray:
        p = np.asarray(self.phi_points)
        return np.interp(t - SETTLE_S, p[:, 0], p[:, 1])


@dataclass(frozen=True)
class LoopTruth:
    """The change made to the string shooter. effect_id None: none. Values in the law's own units where the law has
    a counterpart: skin_friction_coeff (C_f), wind_speed_mps, bending_stiffness_n_m2 (bending_factor x the rope's
    5e-7 N m^2); the wave dynamics have no one-to-one parameter in the chain's terms and are scored on naming only."""

    effect_id: str | None
    cf_factor: float = 1.0
    wind_mps: float = 0.0
    bending_factor: float = 1.0
    cn_factor: float = 1.0
    truth: dict = field(default_factory=dict)

    def params(self) -> ShooterParams:
        base = ShooterParams()
        rope = dataclasses.replace(base.rope, skin_friction_coeff=base.rope.skin_friction_coeff * self.cf_factor,
                                   bending_stiffness_n_m2=base.rope.bending_stiffness_n_m2 * self.bending_factor,
                                   normal_drag_coeff=base.rope.normal_drag_coeff * self.cn_factor)
        return dataclasses.replace(base, rope=rope, air=AirParams(wind_mps=(self.wind_mps, 0.0, 0.0)))


@dataclass(frozen=True)
class LoopCase:
    path: Path
    seed: int
    effect_id: str | None
    truth: dict
    script: LoopScript
    true_part: str | None = None


def generate_loop_recording(path: str | Path, *, truth: LoopTruth, script: LoopScript, seed: int,
                            noise_m: float = 0.002, loop_length_m: float = 2.0, true_part: str | None = None,
                            branch_bump_m: float = 0.0, branch: str = "upper_branch") -> LoopCase:
    """Run the string shooter through the script and write the recording (see module doc).

    branch_bump_m: an effect confined to one branch (a stretch of rope that flies differently, e.g. a stiffer or
    heavier piece): the true contour pushed outward along its normal by a Gaussian bump of this height, centred a
    quarter of the arc from the exit (upper_branch) or from the return point (lower_branch), 8 % of the arc wide."""
    path = Path(path)
    rng = np.random.default_rng([seed, 0x100F])
    motion = ModuleMotion(wheel_speed_mps=script.speed, phi_rad=script.phi)
    shooter = StringShooter(truth.params(), loop_length_m=loop_length_m, motion=motion, initial_shape="circle")
    shooter.step_for(SETTLE_S)
    n = int(round(script.duration_s * CAMERA_HZ))
    with RecordingWriter(path, source="simulator", seed=seed, time_base="simulation",
                         clock_ns=lambda: int(round((shooter.time_s - SETTLE_S) * 1e9)),
                         description=f"loop diagnosis proof (string shooter truth, effect {truth.effect_id})") as w:
        for k in range(n + 1):
            t_rec = k / CAMERA_HZ
            target = SETTLE_S + t_rec
            if target - shooter.time_s > 0.5 * shooter.dt_s:
                shooter.step_for(target - shooter.time_s)
            fr = shooter.frame()
            pts = resample_by_arc_length(fr.loop_plane_xz_m(), N_POINTS)
            if branch_bump_m:
                pts = pts + _bump(pts, branch_bump_m, branch)
            obs = pts + rng.normal(0.0, noise_m, size=pts.shape) if noise_m > 0 else pts
            phi = math.atan2(math.sin(fr.phi_rad), math.cos(fr.phi_rad))
            w.write("/loop/observation", {"time_s": round(t_rec, 6), "camera_id": "proof0", "frame_index": k,
                                          "phi_rad": phi, "rope_speed_mps": round(fr.rope_speed_mps, 3),
                                          "points_m": [[float(x), float(z)] for x, z in obs]},
                    log_time_ns=round(t_rec * 1e9))
            w.write("/sim/plant_truth", {"time_s": round(t_rec, 6), "rope_speed_mps": fr.rope_speed_mps,
                                         "phi_rad": phi, "loop_reach_m": float(np.max(pts[:, 0]))},
                    log_time_ns=round(t_rec * 1e9))
    return LoopCase(path, seed, truth.effect_id, dict(truth.truth), script, true_part or (branch if branch_bump_m
                                                                                           else None))


def _bump(pts: np.ndarray, height_m: float, branch: str) -> np.ndarray:
    if branch not in ("upper_branch", "lower_branch"):
        raise ValueError(f"branch: expected 'upper_branch' or 'lower_branch', got {branch!r}")
    s = np.linspace(0.0, 1.0, pts.shape[0])
    centre = 0.25 if branch == "upper_branch" else 0.75
    tang = np.gradient(pts, axis=0)
    tang /= np.maximum(np.linalg.norm(tang, axis=1, keepdims=True), 1e-12)
    normal = np.column_stack([-tang[:, 1], tang[:, 0]])
    return height_m * np.exp(-0.5 * ((s - centre) / 0.08) ** 2)[:, None] * normal
