"""rw_tov_guard: airborne setpoint check and loop-collapse detector (through ctypes)."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from rw_core_ctypes import TovConfig, TovGuard, f32

DT_S = 0.001


def make(lib, *, collapse_time_s: float = 0.25) -> TovGuard:
    return TovGuard(lib, tov_mps=2.6, margin=1.2, collapse_time_s=collapse_time_s)


def test_setpoint_allowed_from_tov_times_margin(rw_core):
    g = make(rw_core)
    floor_mps = g.min_airborne_mps
    assert floor_mps == pytest.approx(3.12, rel=1e-6)
    assert g.setpoint_allowed(floor_mps)
    assert g.setpoint_allowed(10.0)
    below = float(np.nextafter(np.float32(floor_mps), np.float32(0.0)))  # one float32 step under
    assert not g.setpoint_allowed(below)
    assert not g.setpoint_allowed(2.6), "ToV itself is below the margin"
    assert not g.setpoint_allowed(0.0)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), float("-inf"), -5.0])
def test_bad_setpoint_refused(rw_core, bad):
    assert not make(rw_core).setpoint_allowed(bad)


def test_invalid_config_refuses_everything_and_never_reports(rw_core):
    g = TovGuard(rw_core, tov_mps=2.6, margin=0.8, collapse_time_s=0.1)  # margin < 1
    assert not g.setpoint_allowed(100.0)
    assert not any(g.step(0.0, DT_S) for _ in range(500))
    for bad in (TovConfig(0.0, 1.2, 0.1), TovConfig(2.6, float("nan"), 0.1), TovConfig(2.6, 1.2, -0.1)):
        assert not rw_core.rw_tov_guard_config_is_valid(ctypes.byref(bad))


def run_below(g: TovGuard, n_steps: int, speed_mps: float = 1.0) -> list[int]:
    """Steps n_steps times under ToV; returns the step numbers (1-based) that reported a collapse."""
    return [k for k in range(1, n_steps + 1) if g.step(speed_mps, DT_S)]


def test_collapse_reported_once_after_the_set_time_not_before(rw_core):
    g = make(rw_core, collapse_time_s=0.25)
    for _ in range(100):
        assert not g.step(5.0, DT_S)
    fired = run_below(g, 1000)
    assert len(fired) == 1, "an edge: exactly one report per collapse"
    assert fired[0] in (250, 251), "after 0.25 s under ToV, not before"
    assert g.collapsed


def test_short_dips_under_tov_never_fire(rw_core):
    g = make(rw_core, collapse_time_s=0.25)
    for _ in range(10):
        assert run_below(g, 240) == []
        assert not g.step(2.6, DT_S)  # back at ToV: restarts the timer
    assert not g.collapsed


def test_rearms_after_recovery_and_fires_again_after_the_full_time(rw_core):
    g = make(rw_core, collapse_time_s=0.1)
    assert run_below(g, 300) in ([100], [101])
    assert not g.step(3.0, DT_S)  # recovered
    assert not g.collapsed
    again = run_below(g, 300, speed_mps=2.0)
    assert again in ([100], [101])


def test_nan_speed_is_ignored_and_bad_dt_does_not_advance(rw_core):
    g = make(rw_core, collapse_time_s=0.01)
    assert run_below(g, 5) == []
    assert not g.step(float("nan"), DT_S)
    assert not any(g.step(1.0, dt) for dt in (0.0, -1.0, float("nan"), float("inf")))
    fired = run_below(g, 10)
    assert fired in ([5], [6]), "only the five good steps before counted"


def test_reset_rearms(rw_core):
    g = make(rw_core, collapse_time_s=0.05)
    run_below(g, 100)
    assert g.collapsed
    g.reset()
    assert not g.collapsed
    assert run_below(g, 100) in ([50], [51])


def test_zero_collapse_time_fires_on_the_first_sample_under_tov(rw_core):
    g = make(rw_core, collapse_time_s=0.0)
    assert g.step(1.0, DT_S)
    assert not g.step(1.0, DT_S)


def test_defaults(rw_core):
    cfg = TovConfig()
    rw_core.rw_tov_guard_config_defaults(ctypes.byref(cfg))
    assert rw_core.rw_tov_guard_config_is_valid(ctypes.byref(cfg))
    assert cfg.tov_mps == f32(2.6)
    assert cfg.margin >= 1.0 and cfg.collapse_time_s > 0.0
