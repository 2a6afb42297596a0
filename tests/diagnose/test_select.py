"""The selection rule: a candidate is kept for how much better it predicts held-out blocks, not how consistently.

Residuals here are white Gaussian noise plus a model error, on one channel; the base model and the candidate differ
only in their model error, so what the rule should say is known.
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.select import accepted, effective_counts, equivalent, heldout_lr, heldout_p, score_model

N = 1200  # 12 s at 100 Hz
BLOCK = 50
SIGMA = 0.004  # 4 mm/s


def _setup(seed: int):
    rng = np.random.default_rng(seed)
    block_id = np.arange(N) // BLOCK
    held_blocks = np.arange(2, block_id.max() + 1, 3)  # every third block held out
    fit_mask = ~np.isin(block_id, held_blocks)
    # the speed estimate's low-pass makes the measurement noise correlated from sample to sample
    white = rng.normal(0.0, SIGMA, N)
    noise = np.empty(N)
    noise[0] = white[0]
    for k in range(1, N):
        noise[k] = 0.7 * noise[k - 1] + np.sqrt(1 - 0.49) * white[k]
    return block_id, held_blocks, fit_mask, noise


def _score(name, k, r, block_id, held_blocks, fit_mask, n_eff):
    w = {"rope_speed_mps": np.full(N, 1.0 / SIGMA)}
    return score_model(name, k, {"rope_speed_mps": r}, w, fit_mask, block_id, held_blocks, n_eff)


def test_an_error_confined_to_one_loaded_stretch_is_accepted():
    block_id, held, fit_mask, noise = _setup(1)
    load = np.zeros(N)
    load[400:600] = -0.015  # the rope 15 mm/s slower over 2 s: an external load the base model lacks
    r_base, r_cand = noise + load, noise.copy()
    n_eff = effective_counts({"rope_speed_mps": r_base}, fit_mask)
    base = _score("base", 8, r_base, block_id, held, fit_mask, n_eff)
    cand = _score("load", 11, r_cand, block_id, held, fit_mask, n_eff)
    ok, ev = accepted(cand, base)
    assert ok and ev["heldout_lr"] > 10 and ev["delta_bic"] < -10
    # the same load a tenth as large (1.5 mm/s under 4 mm/s of noise): what these samples cannot show is refused
    base_small = noise + 0.1 * load
    n_eff_small = effective_counts({"rope_speed_mps": base_small}, fit_mask)
    ok_small, ev_small = accepted(_score("load", 11, noise, block_id, held, fit_mask, n_eff_small),
                                  _score("base", 8, base_small, block_id, held, fit_mask, n_eff_small))
    assert not ok_small and ev_small["heldout_lr"] < 10


def test_a_tiny_gain_kept_on_every_sample_is_not_evidence():
    block_id, held, fit_mask, noise = _setup(2)
    r_base = noise
    r_cand = noise * (1.0 - 1e-4)  # better on every sample by a hair
    n_eff = effective_counts({"rope_speed_mps": r_base}, fit_mask)
    base = _score("base", 8, r_base, block_id, held, fit_mask, n_eff)
    cand = _score("hair", 10, r_cand, block_id, held, fit_mask, n_eff)
    ok, ev = accepted(cand, base)
    assert not ok and abs(ev["heldout_lr"]) < 1
    assert heldout_p(cand, base) < 0.01  # what a Diebold-Mariano test calls significant


def test_a_candidate_that_only_fits_noise_is_refused_and_two_alike_are_equivalent():
    block_id, held, fit_mask, noise = _setup(3)
    rng = np.random.default_rng(30)
    # an overfit: matches some noise on the fit blocks, adds its own error on the held-out ones
    wiggle = rng.normal(0.0, 0.3 * SIGMA, N)
    r_cand = np.where(fit_mask, 0.9 * noise, noise + wiggle)
    n_eff = effective_counts({"rope_speed_mps": noise}, fit_mask)
    base = _score("base", 8, noise, block_id, held, fit_mask, n_eff)
    cand = _score("overfit", 10, r_cand, block_id, held, fit_mask, n_eff)
    ok, ev = accepted(cand, base)
    assert not ok and ev["heldout_lr"] < 0 and ev["delta_bic"] < -10  # the fit set alone would have taken it
    other = _score("same", 10, r_cand + 1e-6 * SIGMA, block_id, held, fit_mask, n_eff)
    assert equivalent(cand, other) and not equivalent(cand, base)


def test_a_start_grid_is_judged_with_the_rest_of_the_model_readjusted():
    """best_start(project=True): a step of 2 at t = 5 s on a slope of 1, where the slope was fitted with the step
    put at the end (it absorbed the step, as a refit absorbs a load into friction). With that slope held, no start
    of the grid beats the start itself; judged with the slope re-adjusted to each start, the true step time wins and
    comes with the true slope."""
    from robowrangler_sim.diagnose.fit import best_start

    t = np.linspace(0.0, 10.0, 201)
    y = 1.0 * t + 2.0 * (t >= 5.0)

    def simulate(xs: np.ndarray) -> np.ndarray:
        return np.stack([y - (a * t + 2.0 * (t >= t0)) for a, t0 in xs])

    a_absorbed = float(np.linalg.lstsq(t[:, None], y - 2.0 * (t >= 9.5), rcond=None)[0][0])
    x0 = np.array([a_absorbed, 9.5])
    lo, hi, scales = np.array([0.5, 0.0]), np.array([2.0, 10.0]), np.ones(2)
    starts = np.arange(1.0, 10.0, 1.0)[:, None]
    held = best_start(simulate, x0, starts, [1], scales, lo, hi, 3.0)
    np.testing.assert_array_equal(held, x0)
    np.testing.assert_allclose(best_start(simulate, x0, starts, [1], scales, lo, hi, 3.0, project=True), [1.0, 5.0],
                               atol=1e-6)
