"""The core control blocks chained into the rope speed loop, against a simulated drive.

Chain per 1 ms tick, as the firmware runs it: encoder capture -> M/T estimator -> setpoint ramp ->
feed-forward (Kv, battery) + PI -> ESC pulse, and the ToV guard on the measured speed. The drive
plant (ESC pulse -> motor -> wheel -> rope) is first order and deliberately differs from the
feed-forward model (Kv 12 % lower, a load), so the PI has work to do.
"""

from __future__ import annotations

import ctypes
import math

import pytest

from rw_core_ctypes import (MtConfig, MtSpeedEstimator, PiConfig, PiController, RampConfig, RampLimiter,
                            ThrottleConfig, ThrottleMap, TovConfig, TovGuard)

TICK_US = 1000
TICK_S = 1e-3
U32 = 1 << 32


class DrivePlant:
    """First-order motor/wheel with a 64-edge encoder read through a capture unit.

    rope speed v (m/s): tau dv/dt = k_true * throttle(pulse) * V * 2 pi r / 60 * (1 - load) - v - brake.
    """

    def __init__(self, *, kv_true_rpm_per_v: float, radius_m: float, tau_s: float, counts_per_rev: int,
                 time_offset_us: int) -> None:
        self.kv = kv_true_rpm_per_v
        self.r = radius_m
        self.tau_s = tau_s
        self.cpr = counts_per_rev
        self.v_mps = 0.0
        self.angle_edges = 0.3
        self.t_us = time_offset_us
        self.last_edge_us = time_offset_us
        self.load = 0.0
        self.brake_mps = 0.0

    def step(self, pulse_us: int, battery_v: float) -> None:
        throttle = min(max((pulse_us - 1000) / 1000.0, 0.0), 1.0)
        v_target = throttle * self.kv * battery_v * 2.0 * math.pi * self.r / 60.0 * (1.0 - self.load)
        a = math.exp(-TICK_S / self.tau_s)
        v0 = self.v_mps
        self.v_mps = max(a * v0 + (1.0 - a) * (v_target - self.brake_mps), 0.0)
        v_mean = 0.5 * (v0 + self.v_mps)
        a0 = self.angle_edges
        self.angle_edges += v_mean / (2.0 * math.pi * self.r) * self.cpr * TICK_S
        if math.floor(self.angle_edges) > math.floor(a0):  # the last edge inside this tick
            k = math.floor(self.angle_edges)
            frac = (k - a0) / (self.angle_edges - a0)
            self.last_edge_us = self.t_us + int(frac * TICK_US)
        self.t_us += TICK_US

    def capture(self) -> tuple[int, int, int]:
        return int(self.angle_edges) % U32, self.last_edge_us % U32, self.t_us % U32


class SpeedLoop:
    """The firmware's chain of core blocks, with the rw_defaults.h configuration."""

    def __init__(self, lib) -> None:
        def defaults(cfg_type, fn):
            cfg = cfg_type()
            getattr(lib, fn)(ctypes.byref(cfg))
            return cfg

        mt = defaults(MtConfig, "rw_mt_speed_estimator_config_defaults")
        self.est = MtSpeedEstimator(lib, counts_per_rev=mt.counts_per_rev, timeout_us=mt.timeout_us,
                                    wheel_radius_m=mt.wheel_radius_m, filter_tau_s=mt.filter_tau_s)
        rc = defaults(RampConfig, "rw_ramp_config_defaults")
        self.ramp = RampLimiter(lib, rate_up_per_s=rc.rate_up_per_s, rate_down_per_s=rc.rate_down_per_s)
        self.ramp_up_per_s = rc.rate_up_per_s
        pc = defaults(PiConfig, "rw_pi_controller_config_defaults")
        self.pi = PiController(lib, kp=pc.kp, ki_per_s=pc.ki_per_s, out_min=pc.out_min, out_max=pc.out_max)
        tc = defaults(ThrottleConfig, "rw_throttle_map_config_defaults")
        self.kv_model = tc.kv_rpm_per_v
        self.map = ThrottleMap(lib, kv_rpm_per_v=tc.kv_rpm_per_v, wheel_radius_m=tc.wheel_radius_m,
                               pulse_min_us=tc.pulse_min_us, pulse_max_us=tc.pulse_max_us)
        gc = defaults(TovConfig, "rw_tov_guard_config_defaults")
        self.guard = TovGuard(lib, tov_mps=gc.tov_mps, margin=gc.margin, collapse_time_s=gc.collapse_time_s)
        self.collapse_time_s = gc.collapse_time_s
        self.airborne = False

    def tick(self, plant: DrivePlant, target_mps: float, battery_v: float) -> dict:
        measured = self.est.step(*plant.capture(), TICK_S)
        setpoint = self.ramp.step(target_mps, TICK_S)
        ff = self.map.feed_forward(setpoint, battery_v)
        u = self.pi.step(setpoint, measured, ff, TICK_S)
        pulse = self.map.pulse_us(u)
        # The guard runs only while airborne: from the tick the measured speed first reaches
        # ToV x margin (the state machine's SPINUP -> AIRBORNE), reset at that transition.
        if not self.airborne and measured >= self.guard.min_airborne_mps:
            self.airborne = True
            self.guard.reset()
        collapsed = self.guard.step(measured, TICK_S) if self.airborne else False
        plant.step(pulse, battery_v)
        return {"measured": measured, "setpoint": setpoint, "pulse": pulse, "collapsed": collapsed,
                "true": plant.v_mps}


def make(lib, *, time_offset_us: int = U32 - 2_000_000):
    loop = SpeedLoop(lib)
    plant = DrivePlant(kv_true_rpm_per_v=loop.kv_model * 0.88, radius_m=0.015, tau_s=0.08, counts_per_rev=64,
                       time_offset_us=time_offset_us)  # the clock wraps 2 s into the run
    return loop, plant


def test_spin_up_follows_the_ramp_and_holds_speed_across_battery_sag(rw_core):
    loop, plant = make(rw_core)
    plant.load = 0.05
    log = [loop.tick(plant, 10.0, 14.8) for _ in range(3000)]
    # The setpoint rises at the ramp rate; the rope follows it within a few percent of the target.
    ramp_s = 10.0 / loop.ramp_up_per_s
    mid = log[int(ramp_s / 2 / TICK_S)]
    assert mid["setpoint"] == pytest.approx(5.0, abs=0.021)  # the 251st step: 5.02 (+ the Q16.16 rounding)
    assert mid["true"] == pytest.approx(mid["setpoint"], abs=0.6)
    settled = log[2000:]
    assert all(abs(x["true"] / 10.0 - 1.0) < 0.01 for x in settled), "within 1 % of 10 m/s after 2 s"
    assert all(abs(x["measured"] / x["true"] - 1.0) < 0.01 for x in settled), "estimate within 1 %"
    # Battery sags from 14.8 V to 12.5 V: the loop holds the speed.
    sag = [loop.tick(plant, 10.0, 12.5) for _ in range(2000)]
    assert all(abs(x["true"] / 10.0 - 1.0) < 0.01 for x in sag[1000:])
    assert all(1000 <= x["pulse"] <= 2000 for x in log + sag)


def test_spin_down_never_drives_the_pulse_under_the_esc_minimum(rw_core):
    loop, plant = make(rw_core)
    for _ in range(2000):
        loop.tick(plant, 8.0, 14.8)
    down = [loop.tick(plant, 0.0, 14.8) for _ in range(3000)]
    assert min(x["pulse"] for x in down) == 1000
    assert down[-1]["true"] < 0.05
    assert down[-1]["measured"] < 0.1


def test_a_braked_loop_raises_one_collapse_after_the_set_time(rw_core):
    loop, plant = make(rw_core)
    for _ in range(2000):
        assert not loop.tick(plant, 5.0, 14.8)["collapsed"]
    assert loop.airborne
    plant.brake_mps = 40.0  # something grabs the rope: it stops although the throttle is at maximum
    log = [loop.tick(plant, 5.0, 14.8) for _ in range(1500)]
    under = [k for k, x in enumerate(log) if x["measured"] < 2.6]
    fired = [k for k, x in enumerate(log) if x["collapsed"]]
    assert len(fired) == 1
    delay_s = (fired[0] - under[0]) * TICK_S
    assert loop.collapse_time_s - 0.0015 <= delay_s <= loop.collapse_time_s + 0.0015
    assert max(x["pulse"] for x in log) == 2000, "the PI pushed to full throttle meanwhile"
