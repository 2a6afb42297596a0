"""rw_mt_speed_estimator: M/T speed estimate from edge count and edge timestamps (through ctypes).

A simulated encoder (sim_encoder.SimEncoder, 64 edges/rev) is sampled at the 1 ms firmware tick.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest

from rw_core_ctypes import MtConfig, MtSpeedEstimator
from sim_encoder import U32, SimEncoder

CPR = 64
TICK_S = 0.001
RADIUS_M = 0.015
TIMEOUT_US = 100_000


def make(lib, *, filter_tau_s: float = 0.005, timeout_us: int = TIMEOUT_US) -> MtSpeedEstimator:
    return MtSpeedEstimator(lib, counts_per_rev=CPR, timeout_us=timeout_us, wheel_radius_m=RADIUS_M,
                            filter_tau_s=filter_tau_s)


def run(est: MtSpeedEstimator, enc: SimEncoder, t0_s: float, t1_s: float):
    """Steps the estimator at every tick in [t0_s, t1_s); returns times, raw rev/s, filtered rev/s, stale."""
    times = np.arange(t0_s, t1_s - 1e-12, TICK_S)
    raw, filt, stale = [], [], []
    for t in times:
        est.step(*enc.capture(t), TICK_S)
        raw.append(est.raw_rev_per_s)
        filt.append(est.rev_per_s)
        stale.append(est.stale)
    return times, np.array(raw), np.array(filt), np.array(stale)


@pytest.mark.parametrize("rpm", [1650.0, 3000.0, 8000.0, 15000.0])
@pytest.mark.parametrize("filter_tau_s", [0.0, 0.005])
def test_steady_speed_error_under_one_percent(rw_core, rpm, filter_tau_s):
    enc = SimEncoder(rev_per_s=lambda t: np.full_like(t, rpm / 60.0), duration_s=0.3, counts_per_rev=CPR,
                     jitter_us=1.0, seed=int(rpm))
    est = make(rw_core, filter_tau_s=filter_tau_s)
    _, raw, filt, stale = run(est, enc, 0.0005, 0.3)
    settled = slice(60, None)  # after 60 ms (12 filter time constants)
    assert np.max(np.abs(raw[settled] * 60.0 / rpm - 1.0)) < 0.01
    assert np.max(np.abs(filt[settled] * 60.0 / rpm - 1.0)) < 0.01
    assert not stale[settled].any()
    assert est.rpm == pytest.approx(60.0 * est.rev_per_s, rel=1e-6)
    assert est.rope_mps == pytest.approx(2.0 * math.pi * RADIUS_M * rpm / 60.0, rel=0.01)


def test_tov_speed_accurate_although_fewer_than_two_edges_per_tick(rw_core):
    """1000 rpm: 1.07 edges per tick, many ticks see none. A per-tick count (M method) would read
    0 or 2x; M/T uses the exact edge times."""
    rpm = 1000.0
    enc = SimEncoder(rev_per_s=lambda t: np.full_like(t, rpm / 60.0), duration_s=0.3, counts_per_rev=CPR)
    est = make(rw_core, filter_tau_s=0.0)
    _, raw, _, _ = run(est, enc, 0.0005, 0.3)
    assert np.max(np.abs(raw[20:] * 60.0 / rpm - 1.0)) < 0.01


def test_wraps_of_count_and_clock_are_harmless(rw_core):
    rpm = 3000.0
    # Counter wraps after about 500 edges (~0.16 s), the microsecond clock after 0.1 s.
    enc = SimEncoder(rev_per_s=lambda t: np.full_like(t, rpm / 60.0), duration_s=0.3, counts_per_rev=CPR,
                     count_offset=U32 - 500, time_offset_us=U32 - 100_000)
    est = make(rw_core, filter_tau_s=0.005)
    times, raw, filt, stale = run(est, enc, 0.0005, 0.3)
    assert np.max(np.abs(raw[20:] * 60.0 / rpm - 1.0)) < 0.01
    assert np.max(np.abs(filt[60:] * 60.0 / rpm - 1.0)) < 0.01
    assert not stale[20:].any()
    # The wraps did happen inside the checked span.
    assert enc.capture(times[-1])[0] < 10_000 and enc.capture(times[-1])[2] < 1_000_000


def test_measures_across_the_wrap_between_two_steps(rw_core):
    est = make(rw_core, filter_tau_s=0.0)
    est.step(U32 - 8, U32 - 600, U32 - 500, TICK_S)
    # 16 edges (count wrapped) in 1000 us (clock wrapped): 0.25 rev per ms = 250 rev/s.
    est.step(8, 400, 450, TICK_S)
    assert est.raw_rev_per_s == pytest.approx(250.0, rel=1e-6)
    # Silence across the wrap: bound 1 / (64 * 1000 us) = 15.6 rev/s.
    est.step(8, 400, 1400, TICK_S)
    assert est.raw_rev_per_s == pytest.approx(1e6 / (64 * 1000), rel=1e-6)
    assert not est.stale


def test_tracks_an_acceleration_without_lag_beyond_the_filter(rw_core):
    """1650 -> 15000 rpm in 0.5 s (26,700 rpm/s). The raw estimate is the mean speed over the last
    ~1 ms of edges (lag ~0.5 ms); the low-pass adds a lag of about tau."""
    def profile(t):
        return (1650.0 + np.clip(t - 0.05, 0.0, 0.5) * 26700.0) / 60.0

    enc = SimEncoder(rev_per_s=profile, duration_s=0.6, counts_per_rev=CPR)
    tau_s = 0.005
    est = make(rw_core, filter_tau_s=tau_s)
    times, raw, filt, _ = run(est, enc, 0.0005, 0.6)
    ramp = (times > 0.1) & (times < 0.54)
    truth = profile(times[ramp])
    assert np.max(np.abs(raw[ramp] / truth - 1.0)) < 0.01
    lag_rev_per_s = truth - filt[ramp]
    expected_lag = (tau_s + 0.0005) * 26700.0 / 60.0
    assert np.median(lag_rev_per_s) == pytest.approx(expected_lag, rel=0.3)


def test_stop_decays_under_the_silence_bound_then_reads_zero_and_stale(rw_core):
    rpm = 3000.0
    t_stop = 0.1

    def profile(t):
        return np.where(t < t_stop, rpm / 60.0, 0.0)

    enc = SimEncoder(rev_per_s=profile, duration_s=0.3, counts_per_rev=CPR)
    last_edge_s = enc.edge_us[-1] * 1e-6
    est = make(rw_core, filter_tau_s=0.0)
    times, raw, _, stale = run(est, enc, 0.0005, 0.3)
    silent = times > last_edge_s + 0.0025
    silence_s = times - last_edge_s
    bound = 1.0 / (CPR * silence_s)
    before_timeout = silent & (silence_s * 1e6 <= TIMEOUT_US - 1)
    # Decays: never above 1 / (counts_per_rev * silence), and monotonically down.
    assert np.all(raw[before_timeout] <= bound[before_timeout] * 1.001)
    assert np.all(np.diff(raw[silent]) <= 0.0)
    assert raw[before_timeout][-1] < 0.2, "down to ~0.16 rev/s after 0.1 s of silence"
    assert not stale[before_timeout].any(), "not stale before the timeout"
    after_timeout = silence_s * 1e6 > TIMEOUT_US + 1
    assert stale[after_timeout].all() and np.all(raw[after_timeout] == 0.0)
    assert est.rope_mps == 0.0 and est.rpm == 0.0


def test_restart_after_stale_clears_the_flag_and_recovers(rw_core):
    rpm = 2400.0

    def profile(t):
        return np.where((t < 0.05) | (t > 0.25), rpm / 60.0, 0.0)

    enc = SimEncoder(rev_per_s=profile, duration_s=0.4, counts_per_rev=CPR)
    est = make(rw_core, filter_tau_s=0.0)
    times, raw, _, stale = run(est, enc, 0.0005, 0.4)
    assert stale[(times > 0.2) & (times < 0.25)].all()
    assert not stale[times > 0.26].any()
    assert np.max(np.abs(raw[times > 0.26] * 60.0 / rpm - 1.0)) < 0.01


def test_restart_after_a_stop_longer_than_half_the_clock_range(rw_core):
    """Wheel still for 40 min (> 2^31 us) while the firmware keeps stepping, then it turns again:
    the first edge re-latches (speed 0, stale), the next ones measure."""
    est = make(rw_core, filter_tau_s=0.0)
    est.step(0, 1000, 1000, TICK_S)
    est.step(8, 2000, 2010, TICK_S)
    assert est.raw_rev_per_s == pytest.approx(125.0, rel=1e-6)
    step_us = 50_000
    now_us = 2010
    while now_us < 2000 + 40 * 60 * 1_000_000:
        now_us += step_us
        est.step(8, 2000, now_us, step_us * 1e-6)
    assert est.stale and est.raw_rev_per_s == 0.0
    # 3000 rpm again: one edge every 312.5 us
    first_edge_us = now_us + 100
    est.step(9, first_edge_us, first_edge_us + 50, TICK_S)
    assert est.stale and est.raw_rev_per_s == 0.0
    est.step(9 + 3, first_edge_us + 938, first_edge_us + 1000, TICK_S)  # 3 edges in 937.5 us
    assert not est.stale
    assert est.rpm == pytest.approx(3000.0, rel=0.01)


def test_first_step_latches_only_then_measures(rw_core):
    est = make(rw_core, filter_tau_s=0.0)
    assert est.step(1000, 5000, 5100, TICK_S) == 0.0
    assert est.stale
    # 16 edges in 2000 us at 64 edges/rev: 0.125 rev/s per ms -> 125 rev/s.
    v = est.step(1016, 7000, 7050, TICK_S)
    assert est.raw_rev_per_s == pytest.approx(125.0, rel=1e-6)
    assert v == pytest.approx(2.0 * math.pi * RADIUS_M * 125.0, rel=1e-6)
    assert not est.stale


def test_backward_count_relatches_and_keeps_the_estimate(rw_core):
    est = make(rw_core, filter_tau_s=0.0)
    est.step(1000, 5000, 5100, TICK_S)
    est.step(1016, 7000, 7050, TICK_S)
    est.step(900, 7400, 7500, TICK_S)  # counter went backwards: glitch
    assert est.raw_rev_per_s == pytest.approx(125.0, rel=1e-6)
    est.step(916, 9400, 9450, TICK_S)  # measured against the re-latched (900, 7400)
    assert est.raw_rev_per_s == pytest.approx(16 / 64 / 2000e-6, rel=1e-6)


def test_count_without_new_timestamp_is_ignored_until_consistent(rw_core):
    est = make(rw_core, filter_tau_s=0.0)
    est.step(0, 1000, 1000, TICK_S)
    est.step(8, 2000, 2010, TICK_S)  # 8 edges in 1 ms -> 125 rev/s
    est.step(16, 2000, 2500, TICK_S)  # count moved, timestamp did not: not latched together
    assert est.raw_rev_per_s == pytest.approx(125.0, rel=1e-6)
    est.step(16, 3000, 3010, TICK_S)
    assert est.raw_rev_per_s == pytest.approx(125.0, rel=1e-6)


def test_outputs_finite_and_non_negative_for_arbitrary_input(rw_core):
    rng = np.random.default_rng(7)
    est = make(rw_core)
    for _ in range(2000):
        count, edge_us, now_us = (int(x) for x in rng.integers(0, U32, 3))
        dt_s = float(rng.choice([TICK_S, 0.0, -1.0, float("nan")]))
        v = est.step(count, edge_us, now_us, dt_s)
        assert math.isfinite(v) and v >= 0.0
        assert math.isfinite(est.rpm) and est.rpm >= 0.0


def test_invalid_config_reads_zero(rw_core):
    est = MtSpeedEstimator(rw_core, counts_per_rev=0, timeout_us=TIMEOUT_US, wheel_radius_m=RADIUS_M,
                           filter_tau_s=0.0)
    est.step(0, 0, 10, TICK_S)
    assert est.step(100, 1000, 1010, TICK_S) == 0.0
    for bad in (MtConfig(0, 1, 0.01, 0.0), MtConfig(64, 0, 0.01, 0.0), MtConfig(64, 1, 0.0, 0.0),
                MtConfig(64, 1, 0.01, -1.0), MtConfig(64, 1, float("nan"), 0.0)):
        assert not rw_core.rw_mt_speed_estimator_config_is_valid(ctypes.byref(bad))


def test_defaults_match_the_rig(rw_core):
    cfg = MtConfig()
    rw_core.rw_mt_speed_estimator_config_defaults(ctypes.byref(cfg))
    assert rw_core.rw_mt_speed_estimator_config_is_valid(ctypes.byref(cfg))
    assert cfg.counts_per_rev == 64
    assert cfg.wheel_radius_m == pytest.approx(0.015)
