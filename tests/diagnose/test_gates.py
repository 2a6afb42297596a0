"""Which speed ranges a diagnosis tries a confined law in (gates.uneven_split)."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.gates import RegimeGate, uneven_split


def _run(rest_s: float):
    """A run at 100 Hz: rest, 3 s at 3.5 m/s, 4 s at 7 m/s, rest again; residual 3x larger above 5 m/s."""
    rng = np.random.default_rng(7)
    v = np.concatenate([np.zeros(int(100 * rest_s)), np.full(300, 3.5), np.full(400, 7.0),
                        np.zeros(int(100 * rest_s))])
    scale = np.where(v > 5.0, 3.0, 1.0)
    z = rng.normal(0.0, 1.0, v.size) * scale
    z[v == 0.0] *= 1e-3  # at rest the model and the rope agree: both stopped
    return v, z ** 2


def test_an_effect_above_5_mps_is_split_at_5():
    v, z2 = _run(rest_s=0.5)
    assert uneven_split(v, z2, model_speed_mps=v) == (RegimeGate(speed_min_mps=5.0), RegimeGate(speed_max_mps=5.0))


def test_resting_samples_do_not_pull_the_split_down_to_2_mps():
    v, z2 = _run(rest_s=3.0)
    # counted, the rest (zero residual, all below 2 m/s) makes 2 m/s the most uneven split
    assert uneven_split(v, z2)[0] == RegimeGate(speed_min_mps=2.0)
    # where the rope and the model both rest, nothing acts: left out, the split is where the effect starts
    assert uneven_split(v, z2, model_speed_mps=v)[0] == RegimeGate(speed_min_mps=5.0)
    # the model moving while the rope rests (a dead band the model lacks) is a residual that counts
    v_model = np.where(v == 0.0, 1.0, v)
    assert uneven_split(v, z2, model_speed_mps=v_model)[0] == RegimeGate(speed_min_mps=2.0)
