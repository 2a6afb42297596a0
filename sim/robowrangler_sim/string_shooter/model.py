"""The string-shooter simulator: an axially moving rope loop driven by a wheel nip through a guide eyelet.

``StringShooter`` owns the state (material nodes in the air, the interior rope speed) and advances it
with the compiled kernel (kernel.py). Inputs come from a ``ModuleMotion``; outputs are ``Frame``
snapshots every ``frame_interval_s``.
"""

from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from . import kernel as K
from .contact import pack_obstacles, sdf_one
from .motion import ModuleMotion
from .params import ShooterParams, StringShooterParamError


class StringShooterDivergedError(RuntimeError):
    """The integration blew up or ran out of nodes; the message says when and why."""


@dataclass(frozen=True)
class Frame:
    """One snapshot.

    Attributes:
        time_s: simulation time.
        points_m: shape (M, 3), the airborne rope from the exit point through every node to the return
            point (flow order), world frame.
        labels_m: shape (M - 2,), material coordinate of each node (rope length paid out when it left).
        rope_speed_mps: interior rope speed u (what the encoder sees).
        wheel_speed_mps: commanded wheel surface speed.
        traction_n: nip traction on the rope (positive drives it forward).
        exit_tension_n, return_tension_n: tension of the first and last rope segment.
        phi_rad: inclination; e1, e3: module launch and "up" axes, shape (3,).
    """

    time_s: float
    points_m: np.ndarray
    labels_m: np.ndarray
    rope_speed_mps: float
    wheel_speed_mps: float
    traction_n: float
    exit_tension_n: float
    return_tension_n: float
    phi_rad: float
    e1: np.ndarray
    e3: np.ndarray

    def loop_plane_xz_m(self) -> np.ndarray:
        """Points in the shape-table frame: origin at the exit, x horizontal along the launch heading,
        z up. Shape (M, 2)."""
        heading = np.array([self.e1[0], self.e1[1], 0.0])
        norm = np.linalg.norm(heading)
        heading = heading / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
        rel = self.points_m - self.points_m[0]
        return np.column_stack([rel @ heading, rel[:, 2]])


@dataclass
class Recording:
    """Frames of a run plus per-frame scalars as arrays (shape (F,))."""

    frames: list[Frame] = field(default_factory=list)

    @property
    def time_s(self) -> np.ndarray:
        return np.array([f.time_s for f in self.frames])

    @property
    def rope_speed_mps(self) -> np.ndarray:
        return np.array([f.rope_speed_mps for f in self.frames])


def _circle_curve(exit_m, return_m, e1, e3, length_m, n_samples=4000):
    """Initial loop: a circle standing on the guide, in the module plane, exit at the top of the gap."""
    gap = np.linalg.norm(exit_m - return_m)
    arc = max(length_m - gap, 1e-6)
    r = arc / (2 * math.pi)
    mid = 0.5 * (exit_m + return_m)
    center = mid + r * e1
    th = np.linspace(math.pi, -math.pi, n_samples)  # from the guide, up and over, back from below
    pts = center + r * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e3)
    pts[0], pts[-1] = exit_m, return_m
    return pts


def _hanging_curve(exit_m, return_m, e1, e3, length_m, n_samples=4000):
    """Initial loop: two strands hanging straight down, 4 cm apart (ahead of and behind the eyelet),
    joined at the bottom by a semicircle."""
    down = np.array([0.0, 0.0, -1.0])
    heading = np.array([e1[0], e1[1], 0.0])
    heading = heading / np.linalg.norm(heading) if np.linalg.norm(heading) > 1e-9 else np.array([1.0, 0.0, 0.0])
    r = 0.02
    top_out = exit_m + r * heading
    top_back = return_m - r * heading
    straight = max((length_m - math.pi * r - 2 * r - abs(top_out[2] - top_back[2])) / 2, 0.01)
    bottom_out = top_out + straight * down
    bottom_back = np.array([top_back[0], top_back[1], bottom_out[2]])
    center = 0.5 * (bottom_out + bottom_back)
    th = np.linspace(0.0, math.pi, n_samples // 4)
    arc = center[None] + r * (np.cos(th)[:, None] * heading[None] + np.sin(th)[:, None] * down[None])
    t = np.linspace(0.0, 1.0, n_samples // 4)[:, None]
    pieces = [exit_m + t * (top_out - exit_m), top_out + t * (bottom_out - top_out), arc,
              bottom_back + t * (top_back - bottom_back), top_back + t * (return_m - top_back)]
    return np.vstack(pieces)


def _straight_curve(exit_m, return_m, e1, e3, length_m, n_samples=4000):
    """Initial rope: the straight line from the exit to the return point."""
    t = np.linspace(0.0, 1.0, n_samples)
    return exit_m[None] + t[:, None] * (return_m - exit_m)[None]


_SHAPES = {"circle": _circle_curve, "hanging": _hanging_curve, "straight": _straight_curve}


def _sample_by_arc(curve: np.ndarray, s_targets: np.ndarray) -> np.ndarray:
    seg = np.linalg.norm(np.diff(curve, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    s_targets = s_targets * (s[-1] / (s_targets.max() + s_targets.min()))  # stretch onto the curve
    return np.column_stack([np.interp(s_targets, s, curve[:, c]) for c in range(3)])


class StringShooter:
    """First-principles string shooter.

    Args:
        params: rope, air, nip, geometry, numerics.
        loop_length_m: rope length outside the eyelet at start (the loop), metres, 0.1 .. 20.
        motion: wheel speed and module pose over time.
        obstacles: Sphere / Cylinder / Box / HalfSpace objects (contact.py), static, outside the initial loop.
        initial_shape: "circle" (standing loop), "hanging" (two strands down, 4 cm apart) or "straight" (the line from
            exit to return, stretched or compressed to the loop length; for the span test rig).
        initial_rope_speed_mps: rope speed at t = 0 (None: the wheel speed at t = 0).
    """

    def __init__(self, params: ShooterParams | None = None, *, loop_length_m: float = 2.0,
                 motion: ModuleMotion | None = None, obstacles=(), initial_shape: str = "circle",
                 initial_rope_speed_mps: float | None = None) -> None:
        self.params = params or ShooterParams()
        self.motion = motion or ModuleMotion()
        if not (np.isfinite(loop_length_m) and 0.1 <= loop_length_m <= 20.0):
            raise StringShooterParamError(f"loop_length_m: expected a value in [0.1, 20], got {loop_length_m!r}")
        if initial_shape not in _SHAPES:
            raise StringShooterParamError(f"initial_shape: expected one of {sorted(_SHAPES)}, got {initial_shape!r}")
        p = self.params
        self.dt_s = p.time_step_s
        self.obstacles = pack_obstacles(obstacles)
        rope = p.rope
        ds = p.numerics.segment_length_m
        if loop_length_m < 4 * ds:
            raise StringShooterParamError(
                f"loop_length_m: expected at least 4 segments ({4 * ds} m), got {loop_length_m}"
            )
        cap = int(p.numerics.max_nodes)
        self.prm = np.zeros(K.N_PRM)
        lam, ea = rope.linear_density_kg_per_m, rope.axial_stiffness_n
        self.prm[K.P_LAMBDA] = lam
        self.prm[K.P_EA] = ea
        self.prm[K.P_ETA] = 2 * rope.axial_damping_ratio * ds * math.sqrt(ea * lam / 2)
        self.prm[K.P_B] = rope.bending_stiffness_n_m2
        self.prm[K.P_ETAB] = rope.bending_damping_s * rope.bending_stiffness_n_m2
        self.prm[K.P_RHO] = p.air.density_kg_per_m3
        self.prm[K.P_CF] = rope.skin_friction_coeff
        self.prm[K.P_CN] = rope.normal_drag_coeff
        self.prm[K.P_D] = rope.diameter_m
        self.prm[K.P_G] = p.gravity_mps2
        self.prm[K.P_WX:K.P_WZ + 1] = p.air.wind_mps
        self.prm[K.P_DS] = ds
        self.prm[K.P_GRIP] = p.nip.grip_n_per_mps
        self.prm[K.P_FMAX] = p.nip.max_traction_n
        node_mass = lam * ds
        self.prm[K.P_KC] = 0.1 * node_mass / self.dt_s ** 2
        self.prm[K.P_CC] = 2 * 0.5 * math.sqrt(self.prm[K.P_KC] * node_mass)
        self.prm[K.P_RCONTACT] = 0.5 * rope.diameter_m
        self.prm[K.P_VREG] = 0.01
        self.prm[K.P_COMPRESSION] = rope.compression_stiffness_ratio
        self.prm[K.P_DT] = self.dt_s

        self.pos = np.zeros((cap, 3))
        self.vel = np.zeros((cap, 3))
        self.rest = np.zeros(cap)
        self.label = np.zeros(cap)
        self.sc = np.zeros(K.N_SC)
        self._work = (np.zeros((cap + 4, 3)), np.zeros((cap + 4, 3)), np.zeros(cap + 4),
                      np.zeros((cap + 4, 3)), np.zeros(cap + 4))
        self._last = None
        self.time_s = 0.0

        s0 = self.motion.sample(np.array([0.0]), p.geometry)
        exit_m, return_m, e1, e3 = s0["exit_m"][0], s0["return_m"][0], s0["e1"][0], s0["e3"][0]
        self._interior0_m = p.geometry.interior_length_m + 2 * s0["travel_m"][0]
        self.ring_length_m = loop_length_m + self._interior0_m
        n_inner = int(round(loop_length_m / ds)) - 2
        n = n_inner + 1
        if n + 8 > cap:
            raise StringShooterParamError(f"numerics.max_nodes: expected > {n + 8} for this loop, got {cap}")
        rest_b = 0.5 * (loop_length_m - n_inner * ds)
        curve = _SHAPES[initial_shape](exit_m, return_m, e1, e3, loop_length_m)
        s_nodes = rest_b + (n - 1 - np.arange(n)) * ds  # arc length from the exit, node 0 nearest return
        self.pos[:n] = _sample_by_arc(curve, s_nodes)
        u0 = float(s0["wheel"][0]) if initial_rope_speed_mps is None else float(initial_rope_speed_mps)
        # material flows from the exit toward the return: against the node order
        tang = np.gradient(self.pos[:n], axis=0)
        tang /= np.linalg.norm(tang, axis=1, keepdims=True)
        # plus the module's own velocity (that of the eyelet at t = 0): a loop carried along by the module
        s1 = self.motion.sample(np.array([self.dt_s]), p.geometry)
        v_module = (s1["exit_m"][0] - exit_m) / self.dt_s
        self.vel[:n] = -u0 * tang + v_module[None]
        self.rest[: n - 1] = ds
        self.label[:n] = -s_nodes
        for i, row in enumerate(self.obstacles):
            normal = np.zeros(3)
            depth = min(sdf_one(row, x, normal) for x in self.pos[:n])
            if depth < 0.0:
                raise StringShooterParamError(
                    f"obstacles[{i}]: expected outside the initial loop, it cuts {-depth * 1e3:.1f} mm into it "
                    f"(move it or choose another initial_shape)"
                )
        self.sc[K.S_N] = n
        self.sc[K.S_REST_RET] = rest_b
        self.sc[K.S_REST_EXIT] = rest_b
        self.sc[K.S_U] = u0

    # ------------------------------------------------------------------------------------------
    @property
    def n_nodes(self) -> int:
        return int(self.sc[K.S_N])

    @property
    def rope_speed_mps(self) -> float:
        return float(self.sc[K.S_U])

    def loop_length_m(self) -> float:
        """Rope length outside the eyelet (sum of rest lengths), metres."""
        n = self.n_nodes
        return float(self.rest[: n - 1].sum() + self.sc[K.S_REST_RET] + self.sc[K.S_REST_EXIT])

    def segment_tensions_n(self) -> np.ndarray:
        """Elastic tension of each inner segment in flow order (exit side first), shape (n-1,), newtons."""
        n = self.n_nodes
        ln = np.linalg.norm(np.diff(self.pos[:n], axis=0), axis=1)
        eps = ln / self.rest[: n - 1] - 1.0
        ten = np.where(eps > 0, 1.0, self.prm[K.P_COMPRESSION]) * self.prm[K.P_EA] * eps
        return ten[::-1]

    def tap(self, *, label_m: float, impulse_n_s: float, direction, width_m: float = 0.05) -> None:
        """Give the rope a transverse tap: a velocity kick with a Gaussian profile over material labels.

        Args:
            label_m: material coordinate of the tap centre (see Frame.labels_m).
            impulse_n_s: total impulse, N s.
            direction: shape (3,), direction of the kick (normalised here).
            width_m: Gaussian standard deviation along the rope.
        """
        d = np.asarray(direction, dtype=float)
        if d.shape != (3,) or np.linalg.norm(d) == 0:
            raise StringShooterParamError(f"direction: expected a non-zero 3-vector, got {direction!r}")
        if not width_m > 0:
            raise StringShooterParamError(f"width_m: expected > 0, got {width_m!r}")
        d = d / np.linalg.norm(d)
        n = self.n_nodes
        w = np.exp(-0.5 * ((self.label[:n] - label_m) / width_m) ** 2)
        lam_line = self.params.rope.linear_density_kg_per_m
        dv = impulse_n_s / (lam_line * width_m * math.sqrt(2 * math.pi))
        self.vel[:n] += dv * w[:, None] * d[None]

    def pluck(self, *, label_m: float, amplitude_m: float, direction, width_m: float = 0.05) -> None:
        """Displace the rope sideways: a Gaussian bump over material labels, nodes keep their velocity.

        Args:
            label_m: material coordinate of the bump centre; amplitude_m: peak displacement, metres;
            direction: shape (3,), displacement direction; width_m: Gaussian standard deviation.
        """
        d = np.asarray(direction, dtype=float)
        if d.shape != (3,) or np.linalg.norm(d) == 0:
            raise StringShooterParamError(f"direction: expected a non-zero 3-vector, got {direction!r}")
        if not width_m > 0:
            raise StringShooterParamError(f"width_m: expected > 0, got {width_m!r}")
        d = d / np.linalg.norm(d)
        n = self.n_nodes
        w = np.exp(-0.5 * ((self.label[:n] - label_m) / width_m) ** 2)
        self.pos[:n] += amplitude_m * w[:, None] * d[None]

    def frame(self) -> Frame:
        n = self.n_nodes
        s = self._last if self._last is not None else self.motion.sample(np.array([self.time_s]),
                                                                          self.params.geometry)
        k = -1
        pts = np.vstack([s["exit_m"][k], self.pos[:n][::-1], s["return_m"][k]])
        return Frame(time_s=self.time_s, points_m=pts, labels_m=self.label[:n][::-1].copy(),
                     rope_speed_mps=float(self.sc[K.S_U]), wheel_speed_mps=float(s["wheel"][k]),
                     traction_n=float(self.sc[K.S_TRACTION]), exit_tension_n=float(self.sc[K.S_T_EXIT]),
                     return_tension_n=float(self.sc[K.S_T_RET]), phi_rad=float(s["phi"][k]),
                     e1=s["e1"][k].copy(), e3=s["e3"][k].copy())

    def step_for(self, duration_s: float) -> None:
        """Advance by ``duration_s`` (rounded to whole steps)."""
        steps = int(round(duration_s / self.dt_s))
        if steps <= 0:
            return
        dt = self.dt_s
        t = self.time_s + dt * np.arange(steps + 1)
        s = self.motion.sample(t, self.params.geometry)
        vE = np.diff(s["exit_m"], axis=0) / dt
        vR = np.diff(s["return_m"], axis=0) / dt
        grate = np.diff(s["travel_m"]) / dt
        interior = self.params.geometry.interior_length_m + 2 * s["travel_m"][:-1]
        code = K.advance(self.pos, self.vel, self.rest, self.label, self.sc, self.prm, self.obstacles,
                         np.ascontiguousarray(s["exit_m"][:-1]), vE, np.ascontiguousarray(s["return_m"][:-1]),
                         vR, np.ascontiguousarray(s["e1"][:-1]), np.ascontiguousarray(s["return_dir"][:-1]),
                         s["wheel"][:-1].copy(), grate,
                         interior, dt, *self._work)
        self.time_s = float(self.time_s + steps * dt)
        self._last = {k: v[-1:] for k, v in s.items()}
        if code != 0:
            why = {1: "node capacity exhausted (numerics.max_nodes)", 2: "fewer than 3 nodes left in the air",
                   3: "non-finite state (time step too large for the parameters?)"}[code]
            raise StringShooterDivergedError(f"string shooter stopped near t = {self.time_s:.4f} s: {why}")

    def run(self, duration_s: float, *, frame_interval_s: float = 0.01, progress: bool = False) -> Recording:
        """Run for ``duration_s`` seconds, recording a Frame every ``frame_interval_s`` (first at start).

        With ``progress`` a progress line goes to stderr about once a second of wall time.
        """
        if not (np.isfinite(duration_s) and duration_s >= 0):
            raise StringShooterParamError(f"duration_s: expected >= 0, got {duration_s!r}")
        if not (np.isfinite(frame_interval_s) and frame_interval_s >= self.dt_s):
            raise StringShooterParamError(
                f"frame_interval_s: expected >= the time step {self.dt_s:.2e} s, got {frame_interval_s!r}"
            )
        rec = Recording([self.frame()])
        n_frames = int(round(duration_s / frame_interval_s))
        wall0 = last = time.perf_counter()
        for i in range(n_frames):
            self.step_for(frame_interval_s)
            rec.frames.append(self.frame())
            now = time.perf_counter()
            if progress and now - last > 1.0:
                last = now
                print(f"\r  string shooter: t = {self.time_s:7.2f} / {duration_s:.2f} s sim, "
                      f"{self.time_s / max(now - wall0, 1e-9) if i else 0:6.2f} sim s per wall s",
                      end="", file=sys.stderr, flush=True)
        if progress:
            print("", file=sys.stderr)
        return rec
