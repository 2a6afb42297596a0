"""Shape table -> in-plane joint targets of the chain, per inclination phi (and rope speed).

The paper's recipe: contour points per phi, cubic splines over phi, converted to joint targets.
Here the spline (ShapeTable.contour) is evaluated once on a dense phi grid (default 0.1 deg), each
contour resampled to ``n_links + 1`` points equally spaced in arc length, and turned into joint angles:

    alpha_i = atan2(dz_i, dx_i)                     absolute angle of segment i (world-aligned frame)
    q_0     = alpha_0 - phi                         first joint, relative to the module's launch axis
    q_i     = wrap(alpha_i - alpha_(i-1)), i >= 1   relative turning angle between links

Joint angles do not depend on scale, so a table taken at one loop length gives the shape (similar
figure) at any loop length the guide sets. The plant interpolates the dense grid linearly in phi
(error of the linear step on a 0.1 deg grid of a cubic spline is far below a millimetre).

Sign convention: in-plane hinge axis is -y of the module frame, so a positive angle turns the chain
from +x towards +z (up), matching atan2 in the (x, z) plane.
"""

from __future__ import annotations

import bisect

import numpy as np

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.shape_table import ShapeTable, resample_by_arc_length


def wrap_rad(angle_rad: np.ndarray) -> np.ndarray:
    """Wrap angles to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angle_rad), 2 * np.pi)


def contour_to_joint_targets(contour_m: np.ndarray, *, n_links: int, phi_rad: float) -> np.ndarray:
    """Joint targets of a chain of ``n_links`` equal links laid on a contour.

    Args:
        contour_m: shape (M, 2), (x, z) points in the table frame (exit first, return point last).
        n_links: number of chain links.
        phi_rad: module inclination the contour belongs to.
    Returns: shape (n_links,), in-plane joint angles in rad (joint 0 relative to the launch axis).
    """
    pts = resample_by_arc_length(contour_m, n_links + 1)
    d = np.diff(pts, axis=0)
    alpha = np.arctan2(d[:, 1], d[:, 0])
    q = np.empty(n_links)
    q[0] = wrap_rad(alpha[0] - phi_rad)
    q[1:] = wrap_rad(np.diff(alpha))
    return q


def chain_points_from_targets(q_rad: np.ndarray, *, link_length_m: float, phi_rad: float) -> np.ndarray:
    """Forward kinematics of the planar chain: link end points in the table frame.

    Args:
        q_rad: shape (N,), in-plane joint angles.
    Returns: shape (N + 1, 2), (x, z) from the exit point (0, 0).
    """
    alpha = phi_rad + np.cumsum(q_rad)
    steps = link_length_m * np.column_stack([np.cos(alpha), np.sin(alpha)])
    return np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])


class ShapeTargets:
    """Dense lookup of joint targets and return point over phi, for one table and chain size.

    Args:
        table: the shape table.
        n_links: chain links (targets have this many entries).
        phi_step_deg: grid step of the dense phi lookup.
    """

    def __init__(self, table: ShapeTable, *, n_links: int, phi_step_deg: float = 0.1) -> None:
        if phi_step_deg <= 0 or phi_step_deg > 1.0:
            raise ChainModelError(f"phi_step_deg: expected in (0, 1], got {phi_step_deg}")
        self.table = table
        self.n_links = int(n_links)
        lo, hi = float(table.phi_deg[0]), float(table.phi_deg[-1])
        n_grid = int(np.ceil((hi - lo) / phi_step_deg)) + 1
        self.phi_grid_rad = np.deg2rad(np.linspace(lo, hi, n_grid))
        self._grid_lo, self._grid_hi = float(self.phi_grid_rad[0]), float(self.phi_grid_rad[-1])
        self._grid_step = float(self.phi_grid_rad[1] - self.phi_grid_rad[0])
        self._grid_n = n_grid
        self._speeds = [float(v) for v in table.rope_speed_mps]
        n_speeds = table.rope_speed_mps.size
        self._q = np.empty((n_speeds, n_grid, self.n_links))
        self._ret = np.empty((n_speeds, n_grid, 2))
        for s in range(n_speeds):
            contours = table._spline(s)(np.rad2deg(self.phi_grid_rad))  # (G, M, 2)
            for g in range(n_grid):
                c = contours[g]
                phi = self.phi_grid_rad[g]
                self._q[s, g] = contour_to_joint_targets(c, n_links=self.n_links, phi_rad=phi)
                arc = float(np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1)))
                ret = c[-1] / arc  # per metre of loop, table frame
                cph, sph = np.cos(phi), np.sin(phi)
                # rotate into the module frame (launch axis = +x): R(-phi)
                self._ret[s, g] = [cph * ret[0] + sph * ret[1], -sph * ret[0] + cph * ret[1]]

    def speed_index(self, rope_speed_mps: float) -> int:
        """Nearest tabulated speed at or below ``rope_speed_mps`` (the lowest when below all)."""
        speeds = self._speeds
        return min(max(bisect.bisect_right(speeds, rope_speed_mps) - 1, 0), len(speeds) - 1)

    def _interp(self, arr: np.ndarray, phi_rad: float, speed_index: int) -> np.ndarray:
        x = min(max(float(phi_rad), self._grid_lo), self._grid_hi)
        f = (x - self._grid_lo) / self._grid_step
        i = min(int(f), self._grid_n - 2)
        w = f - i
        return (1.0 - w) * arr[speed_index, i] + w * arr[speed_index, i + 1]

    def joint_targets(self, phi_rad: float, *, speed_index: int = -1) -> np.ndarray:
        """In-plane joint targets, shape (n_links,), rad; phi clamped to the table's range."""
        return self._interp(self._q, phi_rad, speed_index)

    def return_point_per_m(self, phi_rad: float, *, speed_index: int = -1) -> np.ndarray:
        """Return point in the module's (x, z) plane per metre of loop length, shape (2,)."""
        return self._interp(self._ret, phi_rad, speed_index)
