"""Fit: bounded least squares of a set of free parameters on the batched drive plant, with 95 % intervals.

Every Jacobian is one batched simulation (one row per parameter, forward differences), every grid of start
points one batched simulation. Intervals: the Gauss-Newton covariance s^2 (J^T J)^-1, inflated by the
residual's autocorrelation (samples that are not independent count less), +-1.96 sigma, clipped to bounds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.diagnose.residuals import effective_fraction


def huber(z: np.ndarray, c: float) -> np.ndarray:
    """Huber's rho times 2 (z^2 inside |z| <= c, 2 c |z| - c^2 outside), elementwise."""
    a = np.abs(z)
    return np.where(a <= c, z * z, 2.0 * c * a - c * c)


@dataclass(frozen=True)
class FittedParam:
    name: str
    unit: str
    value: float
    ci95: tuple[float, float]
    start: float


def batched_objective(simulate, hi: np.ndarray):
    """fun(x): the residual vector at x (the last point cached: the solver asks twice); jac(x): forward
    differences, all columns in one batched simulation (a step that would leave the upper bound goes down).
    simulate maps (B, k) parameter rows to (B, n) residuals."""
    cache: dict[bytes, np.ndarray] = {}

    def fun(x: np.ndarray) -> np.ndarray:
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = simulate(x[None, :])[0]
        return cache[key]

    def jac(x: np.ndarray) -> np.ndarray:
        f0 = fun(x)
        h = 1e-3 * np.maximum(np.abs(x), 1e-2)
        xs = np.repeat(x[None, :], x.size, axis=0)
        step = np.where(x + h <= hi, h, -h)
        xs[np.arange(x.size), np.arange(x.size)] += step
        return ((simulate(xs) - f0[None, :]) / step[:, None]).T

    return fun, jac


PROJECTED_STARTS = 3
"""Start rows re-simulated after their projection (best_start's project): the best few by the linearised cost."""


def best_start(simulate, x0: np.ndarray, starts: np.ndarray, idx: list[int], scales: np.ndarray, lo: np.ndarray,
               hi: np.ndarray, huber_scale: float, *, project: bool = False) -> np.ndarray:
    """The best of x0 and the grid of start values `starts` (G, len(idx)) for the parameters at positions idx
    (in the parameters' units; clipped to the bounds), judged in one batched simulation.

    project: also judge each grid row after one Gauss-Newton step of the other free parameters from x0 (their
    Jacobian at x0 from forward differences in the same batch): a start is then judged with the rest of the model
    re-adjusted to it, as separable least squares does. A refit that absorbed part of an effect (the friction raised
    where a load acts) otherwise makes the effect's true values look worse than a wrong start that fits the refit.
    The PROJECTED_STARTS best rows by that linearised cost are simulated once more with their projected values;
    the plain grid's best still competes, so the start is never worse than without projection."""
    grid = np.repeat(x0[None, :], len(starts), axis=0)
    grid[:, idx] = np.clip(np.asarray(starts, dtype=float) / scales[idx], lo[idx], hi[idx])
    grid = np.vstack([x0[None, :], grid])
    in_grid = set(idx)
    others = [j for j in range(x0.size) if j not in in_grid]
    if not project or not others:
        costs = np.sum(huber(simulate(grid), huber_scale), axis=1)
        return grid[int(np.argmin(costs))]
    h = 1e-3 * np.maximum(np.abs(x0[others]), 1e-2)
    step = np.where(x0[others] + h <= hi[others], h, -h)
    pert = np.repeat(x0[None, :], len(others), axis=0)
    pert[np.arange(len(others)), others] += step
    r_all = simulate(np.vstack([grid, pert]))
    r_grid, r_pert = r_all[:len(grid)], r_all[len(grid):]
    costs = np.sum(huber(r_grid, huber_scale), axis=1)
    jac = ((r_pert - r_grid[0][None, :]) / step[:, None]).T  # (n, len(others)), at x0
    delta = np.linalg.lstsq(jac, -r_grid.T, rcond=None)[0].T  # (G, len(others)): one Gauss-Newton step per row
    moved = grid.copy()
    moved[:, others] = np.clip(grid[:, others] + delta, lo[others], hi[others])
    linear = np.sum(huber(r_grid + (moved[:, others] - grid[:, others]) @ jac.T, huber_scale), axis=1)
    top = np.argsort(linear)[:PROJECTED_STARTS]
    rows = np.vstack([grid[int(np.argmin(costs))][None, :], moved[top]])
    costs_rows = np.concatenate([[costs.min()], np.sum(huber(simulate(moved[top]), huber_scale), axis=1)])
    return rows[int(np.argmin(costs_rows))]


@dataclass(frozen=True)
class GaussNewtonSpread:
    """Standard deviations at a solution (inf for a parameter the residual does not move), the robust residual
    variance s2, the autocorrelation inflation, and the Jacobian's column norms."""

    sd: np.ndarray
    s2: float
    inflation: float
    col_norm: np.ndarray


def gauss_newton_spread(r: np.ndarray, J: np.ndarray, huber_scale: float, inflation: float) -> GaussNewtonSpread:
    """s^2 (J^T J)^-1 times `inflation` with Huber IRLS weights at the solution (outlying residuals count with
    weight c/|r|). Parameters the residual does not move (a threshold never crossed, a term with no effect) are
    not determined: their sd is inf and they leave the covariance of the others."""
    n, p = r.size, J.shape[1]
    wr = np.minimum(1.0, huber_scale / np.maximum(np.abs(r), 1e-12))
    J = J * np.sqrt(wr)[:, None]
    rw = r * np.sqrt(wr)
    s2 = float(rw @ rw) / max(n - p, 1)
    col = np.linalg.norm(J, axis=0)
    live = col > 1e-9 * max(float(col.max()), 1e-300)
    sd = np.full(p, np.inf)
    if live.any():
        try:
            cov = np.linalg.inv(J[:, live].T @ J[:, live]) * s2 * inflation
            sd[live] = np.sqrt(np.maximum(np.diag(cov), 0.0))
        except np.linalg.LinAlgError:
            pass
    return GaussNewtonSpread(sd, s2, inflation, col)


class ParamRowsFitter:
    """What the drive's and the spindle's batched fitters share: the free parameters (a later spec with the same
    theta column replaces an earlier one), theta rows for a batch of their values, and the solver's scaled box."""

    def __init__(self, specs: list[ParamSpec], *, weights: dict, max_nfev: int, huber_scale: float) -> None:
        by_col: dict[int, ParamSpec] = {}
        for s in specs:
            by_col[s.column] = s
        self.specs = list(by_col.values())
        self.weights = dict(weights)
        self.max_nfev = max_nfev
        self.huber_scale = huber_scale

    def _rows(self, theta_base: np.ndarray, xs: np.ndarray) -> np.ndarray:
        rows = np.repeat(theta_base[None, :], xs.shape[0], axis=0)
        for j, s in enumerate(self.specs):
            rows[:, s.column] = xs[:, j] * s.scale
        return rows

    def _box(self, theta_base: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(scales, lo, hi, x0): the solver works on theta / scale within the specs' bounds around ref."""
        scales = np.array([s.scale for s in self.specs])
        lo = np.array([s.bounds(ref[s.column])[0] for s in self.specs]) / scales
        hi = np.array([s.bounds(ref[s.column])[1] for s in self.specs]) / scales
        x0 = np.clip(np.array([theta_base[s.column] for s in self.specs]) / scales, lo, hi)
        return scales, lo, hi, x0


class ModelFitter(ParamRowsFitter):
    """Estimator. Constructor stores config; fit(replay, theta_base, ...) returns self.

    Args:
        specs: free parameters (a later spec with the same theta column replaces an earlier one).
        weights: channel -> 1 / sigma per sample (S,) or a scalar, weighting its residuals.
        huber_scale: residuals (weighted) beyond this many sigmas count linearly (Huber loss), so a few
            samples on a step edge (timing within a frame) do not steer the fit.
        max_nfev: iteration cap of the least-squares solver.
        project_starts: judge a start grid's rows with the other free parameters projected (best_start's project).
    Fitted: theta_ (N_THETA,), params_ (list of FittedParam), prediction_ (channel -> (S,)), cost_ (weighted
    SSE on the fit samples), n_fit_ (residuals in the fit), evaluations_ (parameter sets simulated).
    """

    def __init__(self, specs: list[ParamSpec], *, weights: dict[str, np.ndarray], max_nfev: int = 25,
                 huber_scale: float = 3.0, project_starts: bool = False) -> None:
        super().__init__(specs, weights=weights, max_nfev=max_nfev, huber_scale=huber_scale)
        self.project_starts = project_starts

    def _resid(self, pred: dict[str, np.ndarray], measured: dict[str, np.ndarray], mask: np.ndarray) -> np.ndarray:
        parts = [((measured[c][None, :] - pred[c]) * w)[:, mask] for c, w in self.weights.items()]
        return np.concatenate(parts, axis=1)

    def fit(self, replay, theta_base: np.ndarray, *, fit_mask: np.ndarray, load_mask: np.ndarray | None = None,
            gate=None, starts: np.ndarray | None = None, start_columns: list[int] | None = None,
            bounds_ref: np.ndarray | None = None) -> ModelFitter:
        """fit_mask: (S,) samples in the fit; load_mask: (T,) external-load weight per tick; gate: an effect confined
        to one regime (drive_batch.TickGate; None: none); starts: (G, k) grid of
        start values for the theta columns start_columns (evaluated in one batch, the best one starts the
        solver); bounds_ref: the theta row relative bounds refer to (the model as given; default theta_base)."""
        ref = theta_base if bounds_ref is None else bounds_ref
        data = replay.data
        extra = {} if gate is None else {"gate": gate}
        # a replay with other channels (the loop's contours) says what it measured
        measured = (replay.measured() if hasattr(replay, "measured")
                    else {"rope_speed_mps": data.speed_mps, "battery_v": data.battery_v})
        scales, lo, hi, x0 = self._box(theta_base, ref)
        self.evaluations_ = 0

        def simulate(xs: np.ndarray) -> np.ndarray:
            self.evaluations_ += xs.shape[0]
            pred = replay.predict(self._rows(theta_base, xs), load_mask=load_mask, **extra)
            return self._resid(pred, measured, fit_mask)

        if starts is not None and len(starts):
            # starts: (G, k) values of the parameters in theta columns start_columns
            own = np.asarray(starts, dtype=float)
            cols = list(start_columns) if start_columns is not None else [s.column for s in self.specs[-own.shape[1]:]]
            idx = [next(j for j, s in enumerate(self.specs) if s.column == c) for c in cols]
            x0 = best_start(simulate, x0, own, idx, scales, lo, hi, self.huber_scale, project=self.project_starts)
        x_start = x0.copy()
        fun, jac = batched_objective(simulate, hi)

        span = hi - lo
        x0 = np.clip(x0, lo + 1e-9 * span, hi - 1e-9 * span)
        sol = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method="trf", max_nfev=self.max_nfev,
                            x_scale="jac", loss="huber", f_scale=self.huber_scale)
        x = sol.x
        r = fun(x)
        n = r.size
        wr = np.minimum(1.0, self.huber_scale / np.maximum(np.abs(r), 1e-12))
        inflation = 1.0 / min(effective_fraction((r * np.sqrt(wr))[: n // len(self.weights)]), 1.0)
        spread = gauss_newton_spread(r, jac(x), self.huber_scale, inflation)
        sd, col = spread.sd, spread.col_norm
        self.jac_col_norm_ = col
        self.sd_ = sd
        self._ci_inputs = (replay, theta_base, fit_mask, load_mask, gate, ref, lo, hi, scales)
        theta = self._rows(theta_base, x[None, :])[0]
        self.theta_ = theta
        self.x_ = x
        self.params_ = [FittedParam(s.name, s.unit, float(x[j] * s.scale),
                                    (float(max(lo[j], x[j] - 1.96 * sd[j]) * s.scale),
                                     float(min(hi[j], x[j] + 1.96 * sd[j]) * s.scale)),
                                    float(x_start[j] * s.scale))
                        for j, s in enumerate(self.specs)]
        pred = replay.predict(theta[None, :], load_mask=load_mask, **extra)
        self.prediction_ = {c: v[0] for c, v in pred.items()}
        self.cost_ = float(np.sum(huber(fun(x), self.huber_scale)))
        self.n_fit_ = n
        return self


def jackknife_intervals(fitter: ModelFitter, names: set[str], *, parts: int = 4, max_nfev: int = 5,
                        student_t: bool = False) -> None:
    """Widen the intervals of the named parameters by a delete-one-part jackknife over interleaved parts of
    the fit samples (refits from the solution): half-width = max(1.96 Gauss-Newton sd, q jackknife sd), q = 1.96
    or, with student_t, the 97.5 % quantile of Student's t with parts - 1 degrees of freedom (a variance
    estimated from `parts` refits is itself uncertain: 3.18 for 4 parts). The jackknife sees what the
    Gauss-Newton interval cannot: a loss that is bumpy in the parameter or a law that fits some steps better
    than others. Updates fitter.params_ in place."""
    replay, theta_base, fit_mask, load_mask, gate, ref, lo, hi, scales = fitter._ci_inputs
    idx = np.flatnonzero(fit_mask)
    estimates = []
    for k in range(parts):
        mask = fit_mask.copy()
        block = (np.arange(idx.size) // 25) % parts == k
        mask[idx[block]] = False
        sub = ModelFitter(fitter.specs, weights=fitter.weights, max_nfev=max_nfev, huber_scale=fitter.huber_scale)
        sub.fit(replay, fitter.theta_, fit_mask=mask, load_mask=load_mask, gate=gate, bounds_ref=ref)
        estimates.append(sub.x_)
    est = np.asarray(estimates)
    sd_jack = np.sqrt((parts - 1) / parts * np.sum((est - est.mean(axis=0)) ** 2, axis=0))
    q_jack = float(stats.t.ppf(0.975, parts - 1)) if student_t else 1.96
    new = []
    for j, p in enumerate(fitter.params_):
        if p.name in names:
            half = max(1.96 * float(fitter.sd_[j]), q_jack * float(sd_jack[j]))
            x = fitter.x_[j]
            p = FittedParam(p.name, p.unit, p.value, (float(max(lo[j], x - half) * scales[j]),
                                                     float(min(hi[j], x + half) * scales[j])), p.start)
        new.append(p)
    fitter.params_ = new
