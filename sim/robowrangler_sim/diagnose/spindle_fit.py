"""Fit on the batched spindle plant: bounded least squares (Huber loss) of free parameters, with 95 % intervals.

As fit.py does for the drive: a batched grid of start points, then scipy's trust-region solver with a batched
forward-difference Jacobian; intervals from the Gauss-Newton covariance inflated for autocorrelated residuals.
Thresholds (a dead band in register units) move the loss in steps, where a Jacobian sees nothing, so every
parameter's interval is also scanned: the values on a grid over its bounds whose loss stays within the 95 %
likelihood-ratio margin (chi2(1) = 3.84 times the residual variance, inflated the same way) of the best; the
interval is the wider of the two.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from robowrangler_sim.diagnose.fit import (FittedParam, ParamRowsFitter, batched_objective, best_start,
                                           gauss_newton_spread, huber)
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.diagnose.residuals import effective_fraction

CHI2_95_1DOF = 3.841
SCAN_POINTS = 121


class SpindleFitter(ParamRowsFitter):
    """Estimator. SpindleFitter(specs, weights=...).fit(replay, theta_base, fit_mask=...) returns self.

    weights: channel -> 1/sigma (scalar). Fitted: theta_, params_ (FittedParam list), prediction_ (channel -> (S,)),
    cost_, evaluations_."""

    def __init__(self, specs: list[ParamSpec], *, weights: dict[str, float], max_nfev: int = 30,
                 huber_scale: float = 3.0) -> None:
        super().__init__(specs, weights=weights, max_nfev=max_nfev, huber_scale=huber_scale)

    def fit(self, replay, theta_base: np.ndarray, *, fit_mask: np.ndarray, starts: np.ndarray | None = None,
            start_columns: list[int] | None = None, bounds_ref: np.ndarray | None = None,
            scan: set[str] = frozenset()) -> SpindleFitter:
        """starts (G, k): start values of theta columns start_columns; scan: parameter names whose interval is
        also scanned on a grid."""
        ref = theta_base if bounds_ref is None else bounds_ref
        scales, lo, hi, x0 = self._box(theta_base, ref)
        self.evaluations_ = 0
        measured = replay.measured

        def simulate(xs: np.ndarray) -> np.ndarray:
            self.evaluations_ += xs.shape[0]
            pred = replay.predict(self._rows(theta_base, xs))
            return np.concatenate([((measured[c][None, :] - pred[c]) * w)[:, fit_mask]
                                   for c, w in self.weights.items()], axis=1)

        if starts is not None and len(starts):
            cols = list(start_columns) if start_columns is not None else [s.column for s in self.specs]
            idx = [next(j for j, s in enumerate(self.specs) if s.column == c) for c in cols]
            x0 = best_start(simulate, x0, np.asarray(starts, dtype=float), idx, scales, lo, hi, self.huber_scale)
        fun, jac = batched_objective(simulate, hi)

        span = hi - lo
        x_start = np.clip(x0, lo + 1e-9 * span, hi - 1e-9 * span)
        sol = least_squares(fun, x_start, jac=jac, bounds=(lo, hi), method="trf", max_nfev=self.max_nfev,
                            x_scale="jac", loss="huber", f_scale=self.huber_scale)
        x = sol.x
        best = float(np.sum(huber(fun(x), self.huber_scale)))
        if best > float(np.sum(huber(fun(x_start), self.huber_scale))):
            x = x_start
            best = float(np.sum(huber(fun(x), self.huber_scale)))
        # a threshold's loss is flat between command levels: scan each scanned parameter over its bounds and move
        # to the best value found, then let the solver polish the rest from there
        for _ in range(2):
            moved = False
            for j, s in enumerate(self.specs):
                if s.name not in scan:
                    continue
                grid = np.repeat(x[None, :], SCAN_POINTS, axis=0)
                grid[:, j] = np.linspace(lo[j], hi[j], SCAN_POINTS)
                costs = np.sum(huber(simulate(grid), self.huber_scale), axis=1)
                i = int(np.argmin(costs))
                if costs[i] < best - 1e-9 * max(abs(best), 1.0):
                    x, best, moved = grid[i].copy(), float(costs[i]), True
            if not moved:
                break
            x_s = np.clip(x, lo + 1e-9 * span, hi - 1e-9 * span)
            sol = least_squares(fun, x_s, jac=jac, bounds=(lo, hi), method="trf", max_nfev=10, x_scale="jac",
                                loss="huber", f_scale=self.huber_scale)
            c = float(np.sum(huber(fun(sol.x), self.huber_scale)))
            if c < best:
                x, best = sol.x, c
        r = fun(x)
        p = x.size
        inflation = 1.0 / min(min(effective_fraction(part) for part in np.split(r, len(self.weights))), 1.0)
        spread = gauss_newton_spread(r, jac(x), self.huber_scale, inflation)
        sd, s2 = spread.sd, spread.s2
        ci = [[max(lo[j], x[j] - 1.96 * sd[j]), min(hi[j], x[j] + 1.96 * sd[j])] for j in range(p)]
        margin = CHI2_95_1DOF * s2 * inflation
        for j, s in enumerate(self.specs):
            if s.name not in scan:
                continue
            grid = np.repeat(x[None, :], SCAN_POINTS, axis=0)
            grid[:, j] = np.linspace(lo[j], hi[j], SCAN_POINTS)
            costs = np.sum(huber(simulate(grid), self.huber_scale), axis=1)
            inside = grid[costs <= best + margin, j]
            if inside.size:
                step = (hi[j] - lo[j]) / (SCAN_POINTS - 1)
                base_lo, base_hi = (ci[j] if np.isfinite(sd[j]) else (x[j], x[j]))
                ci[j] = [max(lo[j], min(base_lo, inside.min() - step)), min(hi[j], max(base_hi, inside.max() + step))]
        self.theta_ = self._rows(theta_base, x[None, :])[0]
        self.x_ = x
        self.sd_ = sd
        self.params_ = [FittedParam(s.name, s.unit, float(x[j] * s.scale),
                                    (float(ci[j][0] * s.scale), float(ci[j][1] * s.scale)), float(x0[j] * s.scale))
                        for j, s in enumerate(self.specs)]
        pred = replay.predict(self.theta_[None, :])
        self.prediction_ = {c: v[0] for c, v in pred.items()}
        self.cost_ = best
        return self
