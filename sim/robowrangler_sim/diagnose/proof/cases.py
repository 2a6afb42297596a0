"""The proof set: one truth effect per recording, each plain and concealed three ways, plus effect-free runs.

Concealments (the issue's three):
  under_noise  the effect's size a fraction of the plain one, near the raw noise floor;
  one_regime   present in one regime only (above 5 m/s, or only in the spin-down for the low-speed effects);
  confounded   a form a nominal parameter can mostly mimic (a delay about the ESC lag, a drag with exponent 2,
               a dead band without hysteresis, a sag faster than the samples, a Stribeck speed spanning the
               range, a load over the whole run).
Truth values are drawn from the case's seed, never from a tuning loop. ``KEY_PARAM`` names the one parameter
per effect the parameter error and interval coverage are scored on (truth in the library's terms).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robowrangler_sim.diagnose.proof.generator import excite_edges_s
from robowrangler_sim.diagnose.proof.truth_effects import (DeadbandTruth, DragTruth, FrictionTruth, LatencyTruth,
                                                          LoadTruth, SagTruth, TruthEffect)

EFFECTS = ("esc_latency", "rope_drag_law", "esc_deadband", "battery_sag", "low_speed_friction", "external_rope_load")
CONCEALMENTS = ("plain", "under_noise", "one_regime", "confounded")
KEY_PARAM = {"esc_latency": "delay_s", "rope_drag_law": "drag_exponent", "esc_deadband": "deadband_us",
             "battery_sag": "polarisation_resistance_ohm", "low_speed_friction": "stribeck_force_n",
             "external_rope_load": "external_load_n"}


@dataclass(frozen=True)
class ProofCase:
    name: str
    seed: int
    effect_id: str | None
    concealment: str
    duration_s: float

    def truth_effect(self) -> tuple[TruthEffect | None, tuple[tuple[float, float], ...]]:
        """The truth effect and the spans where it acts (empty = everywhere / not scored)."""
        if self.effect_id is None:
            return None, ()
        rng = np.random.default_rng([self.seed, 0xCA5E])
        c = self.concealment
        dur = self.duration_s
        fast = (lambda t, v: v > 5.0)
        # low speeds come twice in an excite run (spin-up and spin-down): "one regime" is the spin-down only
        down = float(excite_edges_s(dur)[-1])
        spin_down = (down, down + 1.0)
        in_down = (lambda t, v: t >= spin_down[0])
        gate = {"one_regime": fast}.get(c)
        spans: tuple[tuple[float, float], ...] = ()
        e = self.effect_id
        if e == "esc_latency":
            d = {"plain": rng.uniform(0.006, 0.015), "under_noise": rng.uniform(0.0015, 0.003),
                 "one_regime": rng.uniform(0.006, 0.015), "confounded": rng.uniform(0.003, 0.005)}[c]
            eff = LatencyTruth(e, {"delay_s": d}, delay_s=d, jitter_s=0.001)
        elif e == "rope_drag_law":
            n1 = 2.0 if c == "confounded" else float(rng.choice([rng.uniform(1.3, 1.7), rng.uniform(2.3, 2.7)]))
            a = rng.uniform(0.1, 0.2) * 4.0 ** (2 - n1) / 4.0  # 0.1-0.2 N at 4 m/s
            if c == "under_noise":
                a *= 0.15
            eff = DragTruth(e, {"drag_exponent": n1}, a=a, n1=n1, b=0.1 * a, n2=1.0)
        elif e == "esc_deadband":
            w, h = {"plain": (rng.uniform(30, 60), rng.uniform(5, 20)), "under_noise": (rng.uniform(13, 17), 0.0),
                    "one_regime": (rng.uniform(30, 60), rng.uniform(5, 20)),
                    "confounded": (rng.uniform(20, 30), 0.0)}[c]
            eff = DeadbandTruth(e, {"deadband_us": w, "hysteresis_us": h}, width_us=w, hysteresis_us=h)
            if c == "one_regime":
                gate, spans = in_down, (spin_down,)
        elif e == "battery_sag":
            r1, r2 = rng.uniform(0.1, 0.2), rng.uniform(0.05, 0.1)
            tau1 = 0.02 if c == "confounded" else rng.uniform(0.3, 0.6)
            if c == "under_noise":
                r1, r2 = 0.1 * r1, 0.1 * r2
            eff = SagTruth(e, {"polarisation_resistance_ohm": r1 + r2}, r1_ohm=r1, tau1_s=tau1, r2_ohm=r2,
                           tau2_s=rng.uniform(2.0, 4.0))
        elif e == "low_speed_friction":
            fs = rng.uniform(0.3, 0.6) * (0.15 if c == "under_noise" else 1.0)
            vs = 3.0 if c == "confounded" else rng.uniform(0.4, 0.8)
            eff = FrictionTruth(e, {"stribeck_force_n": fs, "stribeck_speed_mps": vs}, fs_n=fs, vs_mps=vs)
            if c == "one_regime":
                gate, spans = in_down, (spin_down,)
        elif e == "external_rope_load":
            load = rng.uniform(0.3, 0.6) * (0.1 if c == "under_noise" else 1.0)
            if c == "confounded":
                t0, t1 = 0.0, dur + 1.0
            else:
                t0 = rng.uniform(0.25, 0.5) * dur
                t1 = t0 + rng.uniform(0.15, 0.3) * dur
                spans = ((t0, t1),)
            eff = LoadTruth(e, {"external_load_n": load}, load_n=load, t0_s=t0, t1_s=t1)
            if c == "one_regime":
                gate = fast
        else:
            raise ValueError(f"effect_id: unknown {e!r}")
        if gate is not None:
            eff.regime = gate
        return eff, spans


def proof_cases(*, seeds: list[int], clean_seeds: list[int], duration_s: float = 12.0,
                effects: tuple[str, ...] = EFFECTS, concealments: tuple[str, ...] = CONCEALMENTS) -> list[ProofCase]:
    """Every effect x concealment for each seed, plus one effect-free case per clean seed."""
    cases = [ProofCase(f"{e}/{c}/{s}", s * 100 + i * 10 + j, e, c, duration_s)
             for s in seeds for i, e in enumerate(effects) for j, c in enumerate(concealments)]
    cases += [ProofCase(f"none/-/{s}", s, None, "-", duration_s) for s in clean_seeds]
    return cases
