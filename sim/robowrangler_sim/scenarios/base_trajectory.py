"""The robot's leg: the pose of the module (its exit point) over simulated time, built segment by segment.

A scenario appends moves as it goes (``move_to(pos_m, start_s=..., duration_s=...)``): the exit point
follows a smooth, rest-to-rest profile (s = (1 - cos(pi u)) / 2 over the segment) from where it is to the
new position; the orientation is fixed for the whole trajectory. ``pose_at(t_s)`` is pure, so the same
segments give the same poses.
"""

from __future__ import annotations

import math

import numpy as np

from robowrangler_sim.chain.errors import ChainModelError


class BaseTrajectory:
    """Piecewise rest-to-rest moves of the module's exit point, fixed orientation.

    Args:
        start_pos_m: shape (3,), exit point at t = 0, world frame, metres.
        quat_wxyz: shape (4,), module orientation (unit quaternion, see chain.plant.pitch_quat_wxyz).
    """

    def __init__(self, *, start_pos_m, quat_wxyz) -> None:
        pos = np.asarray(start_pos_m, dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ChainModelError(f"start_pos_m: expected 3 finite numbers, got {start_pos_m!r}")
        q = np.asarray(quat_wxyz, dtype=float)
        if q.shape != (4,) or not np.all(np.isfinite(q)) or abs(np.linalg.norm(q) - 1.0) > 1e-6:
            raise ChainModelError(f"quat_wxyz: expected a unit quaternion (w, x, y, z), got {quat_wxyz!r}")
        self.quat_wxyz: tuple[float, float, float, float] = tuple(float(v) for v in q)
        self._segments: list[tuple[float, float, np.ndarray, np.ndarray]] = []  # (t0, t1, p0, p1)
        self._start = pos

    @property
    def end_pos_m(self) -> np.ndarray:
        """Where the last segment ends, shape (3,)."""
        return (self._segments[-1][3] if self._segments else self._start).copy()

    @property
    def end_time_s(self) -> float:
        return self._segments[-1][1] if self._segments else 0.0

    def move_to(self, pos_m, *, start_s: float, duration_s: float) -> None:
        """Move from the end of the last segment to pos_m during [start_s, start_s + duration_s]."""
        p1 = np.asarray(pos_m, dtype=float)
        if p1.shape != (3,) or not np.all(np.isfinite(p1)):
            raise ChainModelError(f"pos_m: expected 3 finite numbers, got {pos_m!r}")
        if not (math.isfinite(duration_s) and duration_s > 0):
            raise ChainModelError(f"duration_s: expected > 0 s, got {duration_s}")
        if not start_s >= self.end_time_s - 1e-12:
            raise ChainModelError(f"start_s: expected >= the end of the last move ({self.end_time_s} s), "
                                  f"got {start_s}")
        self._segments.append((float(start_s), float(start_s + duration_s), self.end_pos_m, p1))

    def pos_at(self, t_s: float) -> np.ndarray:
        """Exit point at simulated time t_s, shape (3,), metres."""
        pos = self._start
        for t0, t1, p0, p1 in self._segments:
            if t_s < t0:
                break
            if t_s >= t1:
                pos = p1
                continue
            s = 0.5 * (1.0 - math.cos(math.pi * (t_s - t0) / (t1 - t0)))
            return p0 + s * (p1 - p0)
        return pos.copy()
