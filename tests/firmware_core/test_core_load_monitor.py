"""rw_load_monitor (through ctypes): the load-loss detector of the rope drive, fed as the core feeds it (the
speed PI's integral term and the battery voltage, one step per speed tick of 2 ms).

Force scale of the reference rig: n_per_v = 2 Kt / (R r) = 12 N/V (1250 rpm/V, 0.085 ohm, 15 mm wheels), so
1 N of rope force is 1 / (12 x 12 V) = 6.9e-3 of throttle in the integral at 12 V.
"""

from __future__ import annotations

import ctypes
import math
from ctypes import c_bool, c_float

import numpy as np
import pytest

from rw_core_ctypes import Lowpass, f32

DT_S = 0.002  # the speed tick
BATTERY_V = 12.0
SETTLE_STEPS = round(0.5 / DT_S)


class Config(ctypes.Structure):
    """rw_load_monitor_config, field for field."""
    _fields_ = [("n_per_v", c_float), ("drop_n", c_float), ("time_s", c_float), ("filter_tau_s", c_float),
                ("reference_tau_s", c_float), ("rise_tau_s", c_float), ("battery_tau_s", c_float),
                ("settle_s", c_float)]


class _State(ctypes.Structure):
    _fields_ = [("load", Lowpass), ("reference", Lowpass), ("rise", Lowpass), ("battery", Lowpass),
                ("steady", c_bool), ("reported", c_bool),
                ("active", c_bool), ("steady_q16", ctypes.c_int32), ("drop_q16", ctypes.c_int32),
                ("n_per_v_q16", ctypes.c_int32), ("drop_n_q16", ctypes.c_int32), ("time_q16", ctypes.c_int32),
                ("settle_q16", ctypes.c_int32), ("prepared_dt_s", c_float), ("dt_q16", ctypes.c_int32)]


class Monitor(ctypes.Structure):
    _fields_ = [("cfg", Config), ("state", _State), ("canary", ctypes.c_uint64 * 4)]  # canary: past the C struct


@pytest.fixture(scope="module")
def lib(rw_core: ctypes.CDLL) -> ctypes.CDLL:
    m, c = ctypes.POINTER(Monitor), ctypes.POINTER(Config)
    for name, restype, argtypes in (
            ("rw_load_monitor_init", None, [m, c]), ("rw_load_monitor_config_defaults", None, [c]),
            ("rw_load_monitor_reset", None, [m]),
            ("rw_load_monitor_n_per_v", c_float, [c_float, c_float, c_float, c_float]),
            ("rw_load_monitor_step", c_bool, [m, c_bool, c_float, c_float, c_float]),
            ("rw_load_monitor_load_n", c_float, [m]), ("rw_load_monitor_drop_n", c_float, [m]),
            ("rw_load_monitor_config_is_valid", c_bool, [c]),
            ("rw_load_monitor_prepare", None, [m, c_float])):
        fn = getattr(rw_core, name)
        fn.restype, fn.argtypes = restype, argtypes
    return rw_core


class Rig:
    """One monitor with the default config (overrides by keyword); feeds forces in newtons as integrals."""

    def __init__(self, lib: ctypes.CDLL, **overrides: float) -> None:
        self.lib = lib
        cfg = Config()
        lib.rw_load_monitor_config_defaults(ctypes.byref(cfg))
        for name, value in overrides.items():
            setattr(cfg, name, value)
        self.m = Monitor()
        for i in range(4):
            self.m.canary[i] = 0xA5A5A5A5A5A5A5A5
        lib.rw_load_monitor_init(ctypes.byref(self.m), ctypes.byref(cfg))
        lib.rw_load_monitor_prepare(ctypes.byref(self.m), DT_S)  # as the core does: converted once for its dt
        self.t_s = 0.0

    def step(self, force_n: float, *, steady: bool = True, battery_v: float = BATTERY_V) -> bool:
        integral = force_n / (self.m.cfg.n_per_v * battery_v)
        fired = self.lib.rw_load_monitor_step(ctypes.byref(self.m), steady, integral, battery_v, DT_S)
        assert all(w == 0xA5A5A5A5A5A5A5A5 for w in self.m.canary), "C wrote past the mirror of rw_load_monitor"
        self.t_s += DT_S
        return fired

    def run(self, forces_n, **kw) -> list[float]:
        """Steps through forces_n; the times (s, from the rig's start) at which a loss was reported."""
        return [self.t_s for f in forces_n if self.step(f, **kw)]

    @property
    def drop_n(self) -> float:
        return self.lib.rw_load_monitor_drop_n(ctypes.byref(self.m))


def hold(force_n: float, seconds: float) -> list[float]:
    return [force_n] * round(seconds / DT_S)


def test_force_scale_of_the_reference_rig_and_bad_arguments(lib: ctypes.CDLL) -> None:
    kt = 60.0 / (2 * math.pi * 1250.0)
    assert lib.rw_load_monitor_n_per_v(2.0, 1250.0, 0.085, 0.015) == pytest.approx(2 * kt / (0.085 * 0.015), rel=1e-6)
    assert lib.rw_load_monitor_n_per_v(2.0, 1250.0, 0.085, 0.015) == pytest.approx(11.98, abs=0.01)
    for bad in ((0.0, 1250.0, 0.085, 0.015), (2.0, -1.0, 0.085, 0.015), (2.0, 1250.0, 0.0, 0.015),
                (2.0, 1250.0, 0.085, math.nan), (2.0, math.inf, 0.085, 0.015)):
        assert lib.rw_load_monitor_n_per_v(*bad) == 0.0, bad
    cfg = Config()
    lib.rw_load_monitor_config_defaults(ctypes.byref(cfg))
    assert lib.rw_load_monitor_config_is_valid(ctypes.byref(cfg))
    assert (cfg.drop_n, cfg.time_s, cfg.settle_s) == (f32(1.0), f32(0.1), f32(0.5))
    for field, value in (("n_per_v", 0.0), ("time_s", -1.0), ("reference_tau_s", math.nan)):
        bad = Config.from_buffer_copy(cfg)
        setattr(bad, field, value)
        assert not lib.rw_load_monitor_config_is_valid(ctypes.byref(bad)), field


def test_the_force_scale_follows_resistance_and_kv(lib: ctypes.CDLL) -> None:
    # twice the resistance: half the force per volt; kv doubled as well: Kt halved again
    assert lib.rw_load_monitor_n_per_v(2.0, 1250.0, 0.17, 0.015) == pytest.approx(11.98 / 2, abs=0.01)
    assert lib.rw_load_monitor_n_per_v(2.0, 2500.0, 0.17, 0.015) == pytest.approx(11.98 / 4, abs=0.01)


def test_a_load_that_vanishes_is_reported_once_after_the_set_time(lib: ctypes.CDLL) -> None:
    rig = Rig(lib)
    assert rig.run(hold(1.6, 1.0) + hold(6.6, 2.0)) == []  # friction offset, then a 5 N load comes on
    t_break = rig.t_s
    fired = rig.run(hold(1.6, 2.0))  # the load vanishes at once
    assert len(fired) == 1
    # the filtered estimate (50 ms) crosses the 1 N drop within a few ms, then it must last 0.1 s
    assert 0.1 <= fired[0] - t_break <= 0.1 + 0.02
    assert 4.5 < rig.drop_n < 5.1  # how far it fell, N


def test_a_drop_under_the_threshold_is_not_a_loss(lib: ctypes.CDLL) -> None:
    rig = Rig(lib)
    assert rig.run(hold(2.5, 2.0) + hold(1.6, 3.0)) == []  # a 0.9 N load vanishing: under drop_n = 1 N


def test_a_drop_shorter_than_the_set_time_is_not_a_loss(lib: ctypes.CDLL) -> None:
    rig = Rig(lib)
    # a 20 ms dip of 5 N: over 1 N for about 60 ms after the 50 ms filter, under the 0.1 s it must last
    assert rig.run(hold(6.0, 2.0) + hold(1.0, 0.02) + hold(6.0, 2.0)) == []


def test_a_load_that_fades_slowly_is_not_a_loss(lib: ctypes.CDLL) -> None:
    """An object let go gently (5 N to 0 over 20 s, 0.25 N/s) is a load change the reference follows."""
    rig = Rig(lib)
    fade = list(np.linspace(6.6, 1.6, round(20.0 / DT_S)))
    assert rig.run(hold(6.6, 2.0) + fade + hold(1.6, 2.0)) == []


def test_nothing_is_judged_while_not_steady_or_settling(lib: ctypes.CDLL) -> None:
    rig = Rig(lib)
    assert rig.run(hold(6.6, 2.0)) == []
    assert rig.run(hold(1.6, 1.0), steady=False) == []  # a speed step: the load changes, nobody judges
    assert rig.run(hold(1.6, 0.2) + hold(6.6, 0.2) + hold(1.6, 0.05)) == []  # settling: learnt, not judged
    assert rig.run(hold(1.6, 3.0)) == []  # steady at the new level: nothing
    assert rig.run(hold(6.6, 1.0) + hold(1.6, 0.3))  # and a real loss after that is seen


def test_reported_once_per_steady_spell(lib: ctypes.CDLL) -> None:
    rig = Rig(lib)
    assert len(rig.run(hold(6.6, 2.0) + hold(1.6, 1.0) + hold(6.6, 1.0) + hold(1.6, 1.0))) == 1
    rig.run(hold(1.6, 0.1), steady=False)  # the core lands the rope: a new spell later
    assert len(rig.run(hold(1.6, 1.0) + hold(6.6, 1.0) + hold(1.6, 1.0))) == 1


def test_off_when_the_threshold_is_zero(lib: ctypes.CDLL) -> None:
    assert Rig(lib, drop_n=0.0).run(hold(20.0, 2.0) + hold(0.0, 2.0)) == []


def sag_run(lib: ctypes.CDLL, **overrides: float) -> list[float]:
    """7.5 N held while the battery steps from 12 V to 9.4 V for 0.5 s and back; the integral follows the
    step as the speed PI does (the same I R is a larger throttle fraction at 9.4 V), first order, 0.3 s."""
    rig = Rig(lib, **overrides)
    n = rig.m.cfg.n_per_v
    integral, alpha = 7.5 / (n * 12.0), DT_S / (0.3 + DT_S)
    fired = []
    for k in range(round(6.0 / DT_S)):
        t_s = k * DT_S
        v = 9.4 if 3.0 <= t_s < 3.5 else 12.0
        integral += alpha * (7.5 / (n * v) - integral)
        if lib.rw_load_monitor_step(ctypes.byref(rig.m), True, integral, v, DT_S):
            fired.append(t_s)
    return fired


def test_a_fast_battery_sag_is_no_load_change(lib: ctypes.CDLL) -> None:
    assert sag_run(lib) == []  # the voltage filtered as the integral follows it
    assert sag_run(lib, battery_tau_s=0.0)  # with the instantaneous voltage the sag reads as a load loss


def test_noise_far_under_the_threshold_never_fires(lib: ctypes.CDLL) -> None:
    """0.2 N rms white noise on the estimate (10x the steady SIL floor) for 60 s: no false alarm."""
    rng = np.random.default_rng(7)
    rig = Rig(lib)
    assert rig.run(list(3.0 + 0.2 * rng.standard_normal(round(60.0 / DT_S)))) == []


@pytest.mark.parametrize("bad", [(math.nan, BATTERY_V, DT_S), (0.01, math.inf, DT_S), (0.01, BATTERY_V, 0.0),
                                 (0.01, BATTERY_V, -DT_S)])
def test_bad_inputs_never_report_and_restart_the_monitor(lib: ctypes.CDLL, bad) -> None:
    rig = Rig(lib)
    rig.run(hold(6.6, 2.0))
    integral, battery_v, dt_s = bad
    assert not lib.rw_load_monitor_step(ctypes.byref(rig.m), True, integral, battery_v, dt_s)
    assert rig.run(hold(1.6, 0.4)) == []  # restarted: learning again, the old level is forgotten
