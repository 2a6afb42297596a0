"""The chain model's loop in its fast, steady-shape form, batched over parameter rows, plus the loop effects' laws.

The chain plant (chain/plant.py) drives its in-plane joints to the shape table's contour at the module's
inclination phi, for the tabulated rope speed at or below the present one, scaled to the loop length the guide
leaves outside (joint angles do not depend on scale), through overdamped servos: first order with
tau = kd/kp = 0.5 s. The fast form does the same on the contour points: the table's contour at (phi, speed)
resampled to K points, times the loop length, followed through a first-order lag of tau per camera frame.
bench/bench_diagnose_loop.py and tests/diagnose/test_diagnose_loop.py compare it with the MuJoCo chain plant.

Theta columns (TH_*): the nominal chain's own parameters, then one group per loop effect; an effect at its
neutral value leaves the nominal chain unchanged. Effect laws (all in the table's frame, on the target shape):

    speed:      S(v) = S_snap(v) + g_v [S_lin(v) - S_snap(v)] + [S_lin(v sqrt(C_f/C_f0)) - S_lin(v)]
                (S_lin: the table continued in the weight-to-drag ratio (v*/v)^2, linear in 1/v^2 between the
                table's speeds, quadratic beyond them (_lin); g_v speed_shape_gain, C_f skin friction)
    wind:       the string's response to a uniform wind's extra load on the running rope about that shape: the
                skin friction at the relative axial air speed v - w t_x (less on the outgoing branch in a tail wind,
                more on the returning one) and the normal drag of u_n = -w sin(theta) (wind_load.py)
    rotation:   phi_eff = phi - tau_n dphi/dt - k_g v dphi/dt   (normal drag lag; Coriolis on the running rope)
    bending:    the running rope's Euler-Bernoulli balance B theta'' = t x F about the table's (string) shape, at
                the rope's stiffness B instead of the table rope's B0 (moving_elastica.py)
    dynamics:   wave speed c = 0: first-order lag tau (the chain); c > 0: each point follows the target with the
                transport delay s / c, s its arc distance from the exit (a disturbance carried along the rope), then
                through the first-order lag tau (the rope's settling once the change has arrived)
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from threadpoolctl import threadpool_limits

from robowrangler_sim.diagnose.loop.moving_elastica import bending_displacement_m
from robowrangler_sim.diagnose.loop.wind_load import wind_displacement_m
from robowrangler_sim.rope import RopeParams
from robowrangler_sim.shape_table import ShapeTable, resample_by_arc_length

TH_TAU_S = 0
TH_LEN_SCALE = 1
TH_SPEED_GAIN = 2
TH_CF = 3
TH_ROT_LAG_S = 4
TH_BEND_N_M2 = 5
TH_WAVE_MPS = 6
TH_WIND_MPS = 7
TH_GYRO_S2_PER_M = 8
N_THETA = 9
PHI_STEP_DEG = 0.25
BEND_PHI_STEP_DEG = 1.0
BEND_SPEED_STEP_MPS = 0.1
BEND_LENGTH_STEP_M = 0.01
"""The bending law's solve grid (interpolated in phi and speed, nearest in loop length)."""
BEND_CACHE_SIZE = 50000
_LOAD_LAWS = {"bend": (TH_BEND_N_M2, bending_displacement_m, "bending_stiffness_n_m2"),
              "wind": (TH_WIND_MPS, wind_displacement_m, "wind_mps")}
"""The load laws solved on the grid (LoopShapeModel._load_unit): theta column, displacement function, its keyword."""


class LoopShapeModel:
    """Batched fast form of the chain's loop.

    Args:
        table: the shape table the chain replays.
        rope: the rope (C_f0, C_n, d, lambda).
        tau_s: the chain's servo time constant kd/kp.
        n_points: contour points K.
    """

    def __init__(self, table: ShapeTable, *, rope: RopeParams, tau_s: float, n_points: int) -> None:
        self.table = table
        self.rope = rope
        self.tau0_s = float(tau_s)
        self.n_points = int(n_points)
        lo, hi = float(table.phi_deg[0]), float(table.phi_deg[-1])
        self.phi_grid_deg = np.arange(lo, hi + 1e-9, PHI_STEP_DEG)
        self.speeds = np.asarray(table.rope_speed_mps, dtype=float)
        grid = np.empty((self.speeds.size, self.phi_grid_deg.size, self.n_points, 2))
        for s in range(self.speeds.size):
            cs = table._spline(s)(self.phi_grid_deg)
            for g in range(self.phi_grid_deg.size):
                c = resample_by_arc_length(cs[g], self.n_points)
                grid[s, g] = c / float(np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1)))
        self.grid = grid  # (S, G, K, 2) per metre of loop
        self._bend_cache: dict[tuple, np.ndarray] = {}

    def theta0(self) -> np.ndarray:
        th = np.zeros(N_THETA)
        th[TH_TAU_S] = self.tau0_s
        th[TH_LEN_SCALE] = 1.0
        th[TH_CF] = self.rope.skin_friction_coeff
        th[TH_BEND_N_M2] = self.rope.bending_stiffness_n_m2
        return th

    # ------------------------------------------------------------------------------------------------------------
    def _at_phi(self, s_idx: np.ndarray, phi_deg: np.ndarray) -> np.ndarray:
        """Contours (..., K, 2) at speed indices s_idx and inclinations phi_deg (same shapes), linear on the grid."""
        x = (np.clip(phi_deg, self.phi_grid_deg[0], self.phi_grid_deg[-1]) - self.phi_grid_deg[0]) / PHI_STEP_DEG
        i = np.minimum(x.astype(int), self.phi_grid_deg.size - 2)
        w = (x - i)[..., None, None]
        return (1.0 - w) * self.grid[s_idx, i] + w * self.grid[s_idx, i + 1]

    def _snap(self, v: np.ndarray, phi_deg: np.ndarray) -> np.ndarray:
        s = np.clip(np.searchsorted(self.speeds, v, side="right") - 1, 0, self.speeds.size - 1)
        return self._at_phi(s, phi_deg)

    def _lin(self, v: np.ndarray, phi_deg: np.ndarray) -> np.ndarray:
        """The table continued in rope speed (S_lin): linear in x = 1 / v^2 between the two tabulated speeds around v,
        outside them the quadratic in x through the three end speeds, at most one end gap of x beyond the table.

        The steady loop's one speed parameter is the ratio of its weight to its axial drag, lambda g / f_t =
        (v* / v)^2 (rope.py: f_t = 0.5 rho C_f pi d v^2), and the string-shooter loop is close to linear in it: on
        effect-free steady truths (phi -0.1 to 0.3 rad) the table interpolated in 1 / v^2 is 0.7-2 mm RMS off at 4.3
        to 6 m/s where interpolation in v is 7-17 mm off (bench/bench_diagnose_loop.py --only interp). Below the
        table the trend bends (the loop sags faster towards takeoff): the end quadratic halves the linear
        extrapolation's error (3.6 m/s: 6 against 13 mm), inside the table it is worse than the neighbours' line."""
        n = self.speeds.size
        v, phi_deg = np.broadcast_arrays(np.asarray(v, dtype=float), np.asarray(phi_deg, dtype=float))
        if n == 1:
            return self._at_phi(np.zeros(v.shape, dtype=int), phi_deg)
        xs = 1.0 / self.speeds ** 2  # decreasing
        x = np.clip(1.0 / np.maximum(np.abs(v), 1e-3) ** 2, xs[-1] - (xs[-2] - xs[-1]), xs[0] + (xs[0] - xs[1]))
        j = np.clip(np.searchsorted(-xs, -x, side="right") - 1, 0, n - 2)
        f = ((x - xs[j]) / (xs[j + 1] - xs[j]))[..., None, None]
        a, b = self._at_phi(j, phi_deg), self._at_phi(j + 1, phi_deg)
        out = a + f * (b - a)
        if n >= 3:
            for outside, nodes in ((x > xs[0], (0, 1, 2)), (x < xs[-1], (n - 3, n - 2, n - 1))):
                if not np.any(outside):
                    continue
                xo, po = x[outside], phi_deg[outside]
                quad = 0.0
                for p in nodes:
                    weight = np.ones_like(xo)
                    for q in nodes:
                        if q != p:
                            weight = weight * (xo - xs[q]) / (xs[p] - xs[q])
                    quad = quad + weight[:, None, None] * self._at_phi(np.full(xo.shape, p), po)
                out[outside] = quad
        return out

    def targets(self, theta: np.ndarray, *, phi_rad: np.ndarray, phidot_rad_s: np.ndarray, speed_mps: np.ndarray,
                loop_length_m: np.ndarray) -> np.ndarray:
        """Target contours (B, F, K, 2) in metres for rows theta (B, N_THETA) and frames (F,)."""
        theta = np.atleast_2d(theta)
        B = theta.shape[0]
        col = lambda c: theta[:, c][:, None]  # noqa: E731
        v = np.broadcast_to(speed_mps[None, :], (B, speed_mps.size))
        phi_eff = (phi_rad[None, :] - col(TH_ROT_LAG_S) * phidot_rad_s[None, :]
                   - col(TH_GYRO_S2_PER_M) * v * phidot_rad_s[None, :])
        phi_deg = np.rad2deg(phi_eff)
        shape = self._steady_unit(theta, phi_deg, v)
        b0 = self.rope.bending_stiffness_n_m2
        length_m = np.broadcast_to(loop_length_m[None, :] * col(TH_LEN_SCALE), phi_deg.shape)
        for b in np.flatnonzero(np.abs(theta[:, TH_BEND_N_M2] - b0) > 1e-9 * b0):
            shape[b] += self._load_unit("bend", theta[b], phi_deg[b], v[b], length_m[b])
        for b in np.flatnonzero(theta[:, TH_WIND_MPS] != 0.0):
            shape[b] += self._load_unit("wind", theta[b], phi_deg[b], v[b], length_m[b])
        scale = (loop_length_m[None, :] * col(TH_LEN_SCALE))[..., None, None]
        return shape * scale

    def _steady_unit(self, theta: np.ndarray, phi_deg: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Unit-length steady contours (B, M, K, 2) for rows theta (B, N_THETA) at effective inclinations phi_deg and
        rope speeds v (B, M): the table with the speed and C_f laws (not the bending, not the wind)."""
        col = lambda c: theta[:, c][:, None]  # noqa: E731
        snap = self._snap(v, phi_deg)
        lin_v = self._lin(v, phi_deg)
        shape = snap + col(TH_SPEED_GAIN)[..., None, None] * (lin_v - snap)
        ratio = np.sqrt(col(TH_CF) / self.rope.skin_friction_coeff)
        if np.any(np.abs(ratio - 1.0) > 1e-12):
            shape = shape + self._lin(v * ratio, phi_deg) - lin_v
        return shape

    def _load_unit(self, law: str, theta_row: np.ndarray, phi_deg: np.ndarray, v: np.ndarray,
                   length_m: np.ndarray) -> np.ndarray:
        """A load law's displacement (F, K, 2) of the unit contours (_grid_response) for one row: "bend", the running
        rope's bending (diagnose/loop/moving_elastica.py) at its stiffness B (TH_BEND_N_M2), or "wind", a uniform
        wind's load on the running rope (diagnose/loop/wind_load.py) at TH_WIND_MPS."""
        column, displacement_m, keyword = _LOAD_LAWS[law]
        value = float(theta_row[column])
        rope = dataclasses.replace(self.rope, skin_friction_coeff=float(theta_row[TH_CF]))

        def solve(contours_m, speeds):
            return displacement_m(contours_m, speed_mps=speeds, rope=rope, **{keyword: value})

        return self._grid_response((law, value), theta_row, phi_deg, v, length_m, solve)

    def _grid_response(self, law: tuple, theta_row: np.ndarray, phi_deg: np.ndarray, v: np.ndarray,
                       length_m: np.ndarray, solve) -> np.ndarray:
        """A law's displacement (F, K, 2) of the unit steady contours (the table with the speed and C_f laws), solved
        on a grid of BEND_PHI_STEP_DEG x BEND_SPEED_STEP_MPS (loop length to BEND_LENGTH_STEP_M) and interpolated
        bilinearly in phi and speed; grid solves are kept across calls (the fit re-evaluates the same rows) and
        batched, on one BLAS thread (threaded BLAS on a loaded machine is 50x slower for these small systems).
        solve(contours_m (G, K, 2), speeds (G,)) -> displacement (G, K, 2), metres."""
        sig = (*law, float(theta_row[TH_CF]), float(theta_row[TH_SPEED_GAIN]))
        pn, vn = phi_deg / BEND_PHI_STEP_DEG, v / BEND_SPEED_STEP_MPS
        p0, q0 = np.floor(pn).astype(np.int64), np.floor(vn).astype(np.int64)
        wp, wq = (pn - p0)[:, None, None], (vn - q0)[:, None, None]
        ln = np.round(length_m / BEND_LENGTH_STEP_M).astype(np.int64)
        corners = np.stack([np.stack([p0 + dp, q0 + dq, ln], axis=-1) for dp, dq in ((0, 0), (1, 0), (0, 1), (1, 1))])
        keys, inverse = np.unique(corners.reshape(-1, 3), axis=0, return_inverse=True)
        missing = [k for k in range(keys.shape[0]) if (sig, *keys[k]) not in self._bend_cache]
        if missing:
            km = keys[missing]
            phis = km[:, 0] * BEND_PHI_STEP_DEG
            speeds = np.maximum(km[:, 1] * BEND_SPEED_STEP_MPS, BEND_SPEED_STEP_MPS)
            lengths = np.maximum(km[:, 2] * BEND_LENGTH_STEP_M, BEND_LENGTH_STEP_M)
            unit = self._steady_unit(theta_row[None, :], phis[None, :], speeds[None, :])[0]
            with threadpool_limits(limits=1, user_api="blas"):
                disp = solve(unit * lengths[:, None, None], speeds) / lengths[:, None, None]
            if len(self._bend_cache) + len(missing) > BEND_CACHE_SIZE:
                self._bend_cache.clear()
            for j, k in enumerate(missing):
                self._bend_cache[(sig, *keys[k])] = disp[j]
        table = np.stack([self._bend_cache[(sig, *k)] for k in keys])
        d = table[inverse.reshape(4, -1)]  # (4, F, K, 2)
        return (1 - wp) * (1 - wq) * d[0] + wp * (1 - wq) * d[1] + (1 - wp) * wq * d[2] + wp * wq * d[3]

    def follow(self, theta: np.ndarray, targets: np.ndarray, *, time_s: np.ndarray, segment: np.ndarray,
               loop_length_m: np.ndarray) -> np.ndarray:
        """The loop following its targets (B, F, K, 2) through a first-order lag tau; with a wave speed c > 0 each
        point follows the target delayed by its arc distance over c, then settles through the lag."""
        theta = np.atleast_2d(theta)
        B, F = targets.shape[:2]
        tau = np.maximum(theta[:, TH_TAU_S], 1e-3)
        c = theta[:, TH_WAVE_MPS]
        starts = np.flatnonzero(np.r_[True, segment[1:] != segment[:-1]])
        ends = np.r_[starts[1:], F]
        src = targets
        if np.any(c > 0):
            src = targets.copy()
            s_frac = np.linspace(0.0, 1.0, self.n_points)
            kk = np.arange(self.n_points)[None, :]
            for b in np.flatnonzero(c > 0):
                delay = s_frac[None, :] * loop_length_m[:, None] / c[b]  # (F, K)
                for a, e in zip(starts, ends):
                    t = time_s[a:e]
                    tq = np.maximum(t[:, None] - delay[a:e], t[0])  # (n, K)
                    idx = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, t.size - 1)
                    nxt = np.minimum(idx + 1, t.size - 1)
                    dt = np.maximum(t[nxt] - t[idx], 1e-12)
                    wq = np.where(nxt > idx, (tq - t[idx]) / dt, 0.0)[..., None]
                    tg = targets[b, a:e]
                    src[b, a:e] = (1.0 - wq) * tg[idx, kk] + wq * tg[nxt, kk]
        out = np.empty_like(targets)
        tl = tau[:, None, None]
        for a, b in zip(starts, ends):
            out[:, a] = src[:, a]
            for f in range(a + 1, b):
                k = 1.0 - np.exp(-(time_s[f] - time_s[f - 1]) / tl)
                out[:, f] = out[:, f - 1] + k * (src[:, f] - out[:, f - 1])
        return out


def phidot(time_s: np.ndarray, phi_rad: np.ndarray, segment: np.ndarray) -> np.ndarray:
    """dphi/dt per frame (central differences within each airborne stretch), rad/s."""
    out = np.zeros_like(phi_rad)
    for s in np.unique(segment):
        m = np.flatnonzero(segment == s)
        if m.size >= 2:
            out[m] = np.gradient(phi_rad[m], time_s[m])
    return out


def takeoff_ratio(theta_row: np.ndarray, rope: RopeParams) -> float:
    """Takeoff speed ratio implied by a fitted C_f: v*/v*0 = sqrt(C_f0 / C_f)."""
    return math.sqrt(rope.skin_friction_coeff / float(theta_row[TH_CF]))
