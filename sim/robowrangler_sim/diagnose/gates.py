"""Regime gates: an effect of the library confined to one speed range of the run, as a real fault often is (a
latency that appears at high rpm, a rope that flutters above some speed, a bearing that drags only when slow).

A gate is a condition on the rope's speed, so a fitted model carries it to a new run (the SIL evaluates it on the
plant's speed every tick, sil_effects.py): rope speed at least / below a band edge of regimes.SPEED_BANDS_MPS. On a
recording it is the mask of the replay's ticks where the recorded speed satisfies it. Gates on the transients'
sign were tried and left out: confined to the spin-ups, any law turns into a generic transient correction (a drag
switched off during spin-ups was "found" on an effect-free recording). The gates a diagnosis tries are the two sides
of the speed that splits the refitted nominal model's residual most unevenly (``uneven_split``): a gated candidate
is one more model, counted with one parameter more (the gate's choice), judged by the same rule as every other
(select.accepted).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_SHARE = 0.05
"""A gate must leave at least this share of the fit samples both in and out (else it is the whole run, or nothing)."""


@dataclass(frozen=True)
class RegimeGate:
    """Where an effect acts: rope speed in [speed_min_mps, speed_max_mps)."""

    speed_min_mps: float = 0.0
    speed_max_mps: float = float("inf")

    @property
    def key(self) -> str:
        if np.isfinite(self.speed_max_mps):
            return f"speed<{self.speed_max_mps:g}"
        return f"speed>={self.speed_min_mps:g}"

    @property
    def description(self) -> str:
        if np.isfinite(self.speed_max_mps):
            return f"only below {self.speed_max_mps:g} m/s"
        return f"only at {self.speed_min_mps:g} m/s and above"

    def on(self, speed_mps):
        """Where the gate is open (rope speeds, array or scalar)."""
        v = np.abs(speed_mps)
        return (v >= self.speed_min_mps) & (v < self.speed_max_mps)

    def to_json(self) -> dict[str, float]:
        """The gate's terms in a model file's effect (only those that restrict)."""
        out: dict[str, float] = {}
        if self.speed_min_mps > 0.0:
            out["gate_speed_min_mps"] = float(self.speed_min_mps)
        if np.isfinite(self.speed_max_mps):
            out["gate_speed_max_mps"] = float(self.speed_max_mps)
        return out

    @classmethod
    def from_json(cls, values: dict[str, float]) -> RegimeGate | None:
        """The gate of a model file's effect terms (None when the effect acts everywhere); ValueError when the
        range is empty or negative."""
        if not any(k in values for k in GATE_TERMS):
            return None
        lo, hi = float(values.get("gate_speed_min_mps", 0.0)), float(values.get("gate_speed_max_mps", float("inf")))
        if not 0.0 <= lo < hi:
            raise ValueError(f"gate_speed_min_mps, gate_speed_max_mps: expected 0 <= min < max, got {lo}, {hi}")
        return cls(lo, hi)


GATE_TERMS = ("gate_speed_min_mps", "gate_speed_max_mps")

SPLITS_MPS = (2.0, 5.0, 8.0)
"""The speeds a gate may start or end at: the speed bands' edges (regimes.SPEED_BANDS_MPS) above rest."""


def tick_speed(data) -> np.ndarray:
    """The recorded rope speed on the replay's tick grid (T,) (telemetry, interpolated)."""
    n = data.pulse_us.size
    t_tick = data.tel_time_s[0] + (np.arange(n) - data.preroll_ticks) * 1e-3
    return np.interp(t_tick, data.tel_time_s, data.tel_speed_mps)


REST_MPS = 0.3
"""The rest band's top (regimes.SPEED_BANDS_MPS): where the recorded rope and the model both stay below it, the drive
is off and no law of the library acts."""


def uneven_split(speed_mps: np.ndarray, z2: np.ndarray, *, model_speed_mps: np.ndarray | None = None
                 ) -> tuple[RegimeGate, RegimeGate] | None:
    """The two sides (at and above, below) of the split speed (SPLITS_MPS) that divides the mean squared weighted
    residual z2 most unevenly between them, either way, with at least MIN_SHARE of the samples on each side; None
    when no split leaves that many. Either way, because the refit moves what it cannot explain: an effect above
    5 m/s that the refit's drag and friction half absorb leaves its residual below 5 m/s. Both sides are tried.
    The samples where the rope and the model (model_speed_mps, when given) both rest are left out of the
    comparison: their residual is zero whatever acts elsewhere, and counted they make the lowest split look the
    most uneven (a run that rests 2 s of 12 puts them all below 2 m/s)."""
    best, best_score = None, -1.0
    v = np.abs(speed_mps)
    if model_speed_mps is not None:
        moving = (v >= REST_MPS) | (np.abs(model_speed_mps) >= REST_MPS)
        v, z2 = v[moving], z2[moving]
    for x in SPLITS_MPS:
        m = v >= x
        if not MIN_SHARE <= m.mean() <= 1.0 - MIN_SHARE:
            continue
        score = abs(np.log(max(z2[m].mean(), 1e-12) / max(z2[~m].mean(), 1e-12)))
        if score > best_score:
            best, best_score = x, score
    return None if best is None else (RegimeGate(speed_min_mps=best), RegimeGate(speed_max_mps=best))
