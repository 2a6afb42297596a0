"""The spindle proof set: screw_backlash and servo_deadband, each plain and concealed three ways, plus
effect-free runs (the spindle's counterpart of cases.py).

Concealments:
  under_noise  backlash 0.1-0.25 mm / a dead band just above the friction stop, with the load read three times
               noisier (25 per mille) than the plant's nominal 8
  one_regime   backlash only on a worn stretch of thread (nut beyond 42 mm) / a dead band only moving out
  confounded   backlash with short moves, so the friction missing inside the gap looks like less screw friction /
               a dead band of 30-50, where the screw's friction already stops the servo (about 34)
Truth forms unlike the library's: the backlash takes up softly (smoothstep over its last 30 %); the dead band
differs moving in and out (plain: out 10-25 % wider). Truth values are drawn from the case's seed. KEY_PARAM
names the parameter scored, its truth in the library's terms (backlash: b (1 - soft/2), where the soft take-up
is half engaged; dead band: the mean of the in and out thresholds where both act, the acting one otherwise).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robowrangler_sim.diagnose.proof.spindle_generator import (SpindleTruthCase, generate_spindle_recording,
                                                               spindle_program)

EFFECTS = ("screw_backlash", "servo_deadband")
CONCEALMENTS = ("plain", "under_noise", "one_regime", "confounded")
KEY_PARAM = {"screw_backlash": "backlash_mm", "servo_deadband": "deadband_raw"}
SOFT = 0.3


@dataclass(frozen=True)
class SpindleProofCase:
    name: str
    seed: int
    effect_id: str | None
    concealment: str
    duration_s: float = 10.0

    def generate(self, path: str | Path) -> SpindleTruthCase:
        rng = np.random.default_rng([self.seed, 0x5CA5E])
        c, e = self.concealment, self.effect_id
        noise = 25.0 if c == "under_noise" else 8.0
        program = None
        if e is None:
            return generate_spindle_recording(path, truth=None, seed=self.seed, duration_s=self.duration_s)
        if e == "screw_backlash":
            b = rng.uniform(0.1, 0.25) if c == "under_noise" else rng.uniform(0.5, 1.5)
            truth = {"backlash_mm": b, "soft_fraction": SOFT}
            if c == "one_regime":
                truth["backlash_region_mm"] = 42.0
            if c == "confounded":
                program = spindle_program(np.random.default_rng([self.seed, 0x5B1D, 1]), self.duration_s,
                                          short_moves=True)
            key = b * (1.0 - SOFT / 2.0)
        elif e == "servo_deadband":
            if c == "plain":
                d_in = rng.uniform(50, 100)
                d_out = d_in * rng.uniform(1.1, 1.25)
            elif c == "under_noise":
                d_in = d_out = rng.uniform(45, 60)
            elif c == "one_regime":
                d_in, d_out = 0.0, rng.uniform(50, 100)
            else:
                d_in = d_out = rng.uniform(30, 50)
            truth = {"deadband_in_raw": d_in, "deadband_out_raw": d_out}
            key = d_out if d_in == 0.0 else 0.5 * (d_in + d_out)
        else:
            raise ValueError(f"effect_id: unknown spindle effect {e!r}")
        return generate_spindle_recording(path, truth=truth, seed=self.seed, duration_s=self.duration_s,
                                          program=program, load_noise_permille=noise, effect_id=e,
                                          truth_for_scoring={KEY_PARAM[e]: key})


def spindle_proof_cases(*, seeds: list[int], clean_seeds: list[int],
                        duration_s: float = 10.0) -> list[SpindleProofCase]:
    cases = [SpindleProofCase(f"{e}/{c}/{s}", s * 100 + 50 + i * 10 + j, e, c, duration_s)
             for s in seeds for i, e in enumerate(EFFECTS) for j, c in enumerate(CONCEALMENTS)]
    cases += [SpindleProofCase(f"none/-/{s}", s, None, "-", duration_s) for s in clean_seeds]
    return cases
