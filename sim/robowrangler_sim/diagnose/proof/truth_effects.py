"""Truth effects for the proof generator: the physics the nominal model leaves out, in forms that are NOT the
library's own laws where the issue asks for it (drag as a sum of two power laws, a delay with jitter, a dead
band whose zero zone maps with its own span, a sag with two time constants, a Lorentzian Stribeck curve, a
load with a smooth onset).

Each effect acts on the per-tick DrivePlant (drive.py) through its public seams only: the pulse the plant's
ESC gets, ``external_rope_load_n`` (the force opposing the rope), ``rope_exposed_length_m`` (0 switches the
plant's own k v^2 drag off so a truth drag can replace it) and ``battery_aux_current_a`` (an extra draw that
lowers the source voltage as a sag would). ``regime`` gates an effect to one part of the run
(concealment "one regime only"): it is a predicate of (time_s, true rope speed m/s).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from robowrangler_sim.plants import DrivePlant

Regime = Callable[[float, float], bool]


def _always(_t: float, _v: float) -> bool:
    return True


@dataclass
class TruthEffect:
    """Base: an effect on the drive plant. ``pulse`` maps the commanded pulse; ``force_n`` the extra force."""

    effect_id: str
    truth: dict[str, float]  # true parameter values in the library's terms where they exist (for scoring)
    regime: Regime = field(default=_always)
    replaces_drag: bool = False

    def reset(self, rng: np.random.Generator) -> None:
        pass

    def pulse(self, pulse_us: float, t_s: float, plant: DrivePlant) -> float:
        return pulse_us

    def force_n(self, t_s: float, v_mps: float) -> float:
        return 0.0

    def sag_v(self, t_s: float, i_batt_a: float, dt_s: float) -> float:
        return 0.0

    def systematic(self) -> TruthEffect:
        """The effect without its random part (what a model of it can predict; the identifiability oracle's
        truth): itself, for an effect with none."""
        return self


@dataclass
class DragTruth(TruthEffect):
    """F = a |v|^n1 + b |v|^n2 (two power laws; the library fits one, k v_ref^2 (|v|/v_ref)^n)."""

    a: float = 0.0
    n1: float = 2.0
    b: float = 0.0
    n2: float = 1.0
    replaces_drag: bool = True

    def force_n(self, t_s: float, v_mps: float) -> float:
        s = abs(v_mps)
        return self.a * s ** self.n1 + self.b * s ** self.n2


@dataclass
class LatencyTruth(TruthEffect):
    """Pure delay of the ESC input with Gaussian jitter per tick (the library has no jitter term)."""

    delay_s: float = 0.0
    jitter_s: float = 0.0
    averaged: bool = False
    """True: the expected delayed pulse over the jitter's distribution instead of one draw per tick."""
    _hist: list = field(default_factory=list)
    _rng: np.random.Generator | None = None
    _w: np.ndarray | None = None

    def reset(self, rng: np.random.Generator) -> None:
        self._hist = []
        self._rng = rng
        self._w = self._weights() if self.averaged else None

    def _weights(self) -> np.ndarray:
        """P(the delay, rounded to whole ticks and at least 0, is k ticks) for k = 0..K."""
        if self.jitter_s <= 0.0:
            w = np.zeros(max(0, round(self.delay_s * 1000.0)) + 1)
            w[-1] = 1.0
            return w
        from scipy import stats

        top = int(math.ceil((self.delay_s + 6.0 * self.jitter_s) * 1000.0)) + 1
        edges = (np.arange(top + 1) + 0.5) * 1e-3  # tick k takes delays in [k - 0.5, k + 0.5) ms
        cdf = stats.norm.cdf(edges, loc=self.delay_s, scale=self.jitter_s)
        return np.diff(np.concatenate(([0.0], cdf)))  # k = 0 takes every delay below 0.5 ms

    def pulse(self, pulse_us: float, t_s: float, plant: DrivePlant) -> float:
        self._hist.append(pulse_us)
        if not self.regime(t_s, plant.rope_speed_mps):
            return pulse_us
        if self.averaged:
            w = self._w
            past = [self._hist[len(self._hist) - 1 - k] if len(self._hist) - 1 - k >= 0 else 0.0
                    for k in range(w.size)]
            return float(np.dot(w, past))
        d = self.delay_s + self.jitter_s * float(self._rng.standard_normal())
        k = len(self._hist) - 1 - max(0, round(d * 1000.0))
        return self._hist[k] if k >= 0 else 0.0

    def systematic(self) -> LatencyTruth:
        """The jitter's expectation instead of its draws (a fresh copy, same regime): the pulse averaged over the
        delay's distribution, weights P(delay rounded to ticks = k)."""
        return dataclasses.replace(self, averaged=True, _hist=[], _rng=None, _w=None)


@dataclass
class DeadbandTruth(TruthEffect):
    """Zero throttle up to min + width; once off, on again only above min + width + hysteresis; above it the
    throttle spans (min + width .. max). Passed to the plant's ESC (10 us dead band) as an equivalent pulse."""

    width_us: float = 0.0
    hysteresis_us: float = 0.0
    min_us: float = 1000.0
    max_us: float = 2000.0
    nominal_deadband_us: float = 10.0
    _off: bool = True

    def reset(self, rng: np.random.Generator) -> None:
        self._off = True

    def pulse(self, pulse_us: float, t_s: float, plant: DrivePlant) -> float:
        if pulse_us < self.min_us or not self.regime(t_s, plant.rope_speed_mps):
            return pulse_us
        top = self.min_us + self.width_us
        if self._off:
            if pulse_us > top + self.hysteresis_us:
                self._off = False
        elif pulse_us <= top:
            self._off = True
        if self._off:
            return self.min_us
        thr = (pulse_us - top) / (self.max_us - top)
        nom_top = self.min_us + self.nominal_deadband_us
        return nom_top + thr * (self.max_us - nom_top)


@dataclass
class SagTruth(TruthEffect):
    """Two polarisation branches (library: one): V_k' = (R_k I - V_k) / tau_k, sag = V_1 + V_2."""

    r1_ohm: float = 0.0
    tau1_s: float = 0.3
    r2_ohm: float = 0.0
    tau2_s: float = 3.0
    _v1: float = 0.0
    _v2: float = 0.0

    def reset(self, rng: np.random.Generator) -> None:
        self._v1 = self._v2 = 0.0

    def sag_v(self, t_s: float, i_batt_a: float, dt_s: float) -> float:
        self._v1 = self.r1_ohm * i_batt_a + (self._v1 - self.r1_ohm * i_batt_a) * math.exp(-dt_s / self.tau1_s)
        self._v2 = self.r2_ohm * i_batt_a + (self._v2 - self.r2_ohm * i_batt_a) * math.exp(-dt_s / self.tau2_s)
        return self._v1 + self._v2


@dataclass
class FrictionTruth(TruthEffect):
    """Low-speed excess friction F_s / (1 + (|v| / v_s)^2) (Lorentzian; the library's Stribeck is Gaussian)."""

    fs_n: float = 0.0
    vs_mps: float = 0.5

    def force_n(self, t_s: float, v_mps: float) -> float:
        return self.fs_n / (1.0 + (abs(v_mps) / self.vs_mps) ** 2)


@dataclass
class LoadTruth(TruthEffect):
    """A rope load over [t0, t1] with raised-cosine edges of ramp_s (library: a constant over a span)."""

    load_n: float = 0.0
    t0_s: float = 0.0
    t1_s: float = 0.0
    ramp_s: float = 0.1

    def force_n(self, t_s: float, v_mps: float) -> float:
        if t_s <= self.t0_s or t_s >= self.t1_s:
            return 0.0
        edge = min(t_s - self.t0_s, self.t1_s - t_s)
        w = 1.0 if edge >= self.ramp_s else 0.5 - 0.5 * math.cos(math.pi * edge / self.ramp_s)
        return self.load_n * w


@dataclass
class SlipTruth(TruthEffect):
    """Wheel-rope slip: the rope runs slower than the wheel surface by a fraction. It changes nothing the
    motor encoder, the ESC or the battery see (the drive load is the same), so it is in the truth only."""

    slip_fraction: float = 0.0
