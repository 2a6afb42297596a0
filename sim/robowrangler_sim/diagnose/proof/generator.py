"""Recordings from a truth model for the diagnose proof: the per-tick DrivePlant with base parameters
perturbed from nominal as real hardware is, one truth effect switched on (or none), an open-loop excitation
program of ESC pulses (steps across the speed range, rests, slow ramps: what `wrangler excite` runs), and the
board's measurement chain: M/T speed estimate on the encoder's edges with the firmware's low-pass, telemetry at
50 Hz rounded to mm/s and whole rpm, the battery ADC's noise and step.

Writes the documented schema (/device/telemetry, /device/params, /sim/plant_truth for scoring only).

    case = generate_recording("r.mcap", effect=LatencyTruth("esc_latency", {"delay_s": 0.008}, delay_s=0.008),
                              seed=3, duration_s=8.0)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robowrangler.recorder import RecordingWriter
from robowrangler_sim.plants import DriveParams, DrivePlant
from robowrangler_sim.diagnose.proof.truth_effects import TruthEffect

TELEMETRY_PERIOD_TICKS = 20
SPEED_FILTER_TAU_S = 0.01
TOV_MPS = 2.6
# class estimates a real unit differs on (the nominal refit's business, not missing physics)
PERTURBED_FIELDS = ("motor_resistance_ohm", "esc_resistance_ohm", "motor_coulomb_friction_nm",
                    "motor_viscous_friction_nm_s_per_rad", "guide_friction_n", "nip_friction_n",
                    "nip_viscous_n_s_per_m", "battery_internal_resistance_ohm", "rotor_inertia_kg_m2")


@dataclass(frozen=True)
class TruthCase:
    """What a generated recording holds, for scoring: the effect (None: effect-free), the true parameters."""

    path: Path
    seed: int
    effect_id: str | None
    truth: dict[str, float]
    params: DriveParams
    duration_s: float
    truth_spans_s: tuple[tuple[float, float], ...]


def perturbed_params(rng: np.random.Generator, *, low: float = 0.03, high: float = 0.10) -> DriveParams:
    """DriveParams with each class estimate and the rope's skin friction off by 3-10 % (random sign), battery OCV
    off by up to 3 %."""
    base = DriveParams()
    changes = {}
    for name in PERTURBED_FIELDS:
        frac = rng.uniform(low, high) * rng.choice((-1.0, 1.0))
        changes[name] = getattr(base, name) * (1.0 + frac)
    changes["battery_open_circuit_v"] = base.battery_open_circuit_v * (1.0 + rng.uniform(-0.03, 0.03))
    frac = rng.uniform(low, high) * rng.choice((-1.0, 1.0))  # the rope's skin friction (its air drag)
    changes["rope"] = dataclasses.replace(base.rope, skin_friction_coeff=base.rope.skin_friction_coeff * (1.0 + frac))
    return dataclasses.replace(base, **changes)


def excitation_program(rng: np.random.Generator, duration_s: float) -> np.ndarray:
    """Pulse per 1 ms tick: 0.4 s arming at 1000 us, then holds of 0.25-0.7 s at random levels across the speed
    range (1015-1450 us), rests at 1000 us and slow ramps; changes only at telemetry ticks."""
    n = int(round(duration_s * 1000))
    pulse = np.full(n, 1000.0)
    k = 400
    levels = []
    while k < n:
        kind = rng.random()
        hold = int(rng.uniform(0.25, 0.7) * 1000) // TELEMETRY_PERIOD_TICKS * TELEMETRY_PERIOD_TICKS
        if kind < 0.12:
            level = 1000.0
        elif kind < 0.35:
            level = float(rng.integers(1015, 1080))
        else:
            level = float(rng.integers(1080, 1450))
        if rng.random() < 0.15 and levels:
            ramp = np.linspace(levels[-1], level, hold // TELEMETRY_PERIOD_TICKS)
            seg = np.repeat(np.round(ramp), TELEMETRY_PERIOD_TICKS)
            pulse[k:k + seg.size] = seg[: max(0, min(seg.size, n - k))]
        else:
            pulse[k:k + hold] = level
        levels.append(level)
        k += hold
    return pulse


class _MtEstimator:
    """The firmware's M/T speed estimate (edges over the time between the first and last edge since the last
    measurement) with its first-order low-pass, stepped every 1 ms tick."""

    def __init__(self, counts_per_rev: int, wheel_radius_m: float, tau_s: float, timeout_s: float = 0.1) -> None:
        self.k = 2.0 * math.pi * wheel_radius_m / counts_per_rev
        self.tau_s = tau_s
        self.timeout_us = timeout_s * 1e6
        self.last_count = None
        self.last_edge_us = 0
        self.raw = 0.0
        self.out = 0.0

    def step(self, count: int, edge_us: int, now_us: int, dt_s: float) -> float:
        if self.last_count is None:
            self.last_count, self.last_edge_us = count, edge_us
        elif count != self.last_count and edge_us > self.last_edge_us:
            self.raw = abs(count - self.last_count) * self.k / ((edge_us - self.last_edge_us) * 1e-6)
            self.last_count, self.last_edge_us = count, edge_us
        elif now_us - self.last_edge_us > self.timeout_us:
            self.raw = 0.0
        alpha = dt_s / (self.tau_s + dt_s)
        self.out += alpha * (self.raw - self.out)
        return self.out


def _telemetry(t_s: float, seq: int, state: str, pulse_us: int, speed_mps: float, battery_v: float,
               counters: int) -> dict:
    rpm = int(round(speed_mps / (2.0 * math.pi * DriveParams().wheel_radius_m) * 60.0))
    return {"time_s": round(t_s, 3), "state": state, "fault_bits": [], "rope_speed_target_mps": 0.0,
            "rope_speed_setpoint_mps": 0.0, "rope_speed_mps": round(speed_mps, 3), "motor_rpm": rpm,
            "esc_pulse_us": int(pulse_us), "battery_v": round(battery_v, 3), "heartbeat_age_s": 0.02,
            "rx_ok": counters % 65536, "rx_bad": 0, "rx_duplicates": 0, "nacks": 0, "events": 0, "tick_overruns": 0,
            "guide_position_m": 0.0, "guide_target_m": 0.0, "spindle_load_permille": 0, "spindle_flags": ["HOMED"],
            "spindle_rejected": 0, "rx_auth_failed": 0, "rx_replayed": 0, "tx_dropped": 0, "seq": seq % 65536}


def generate_recording(path: str | Path, *, effect: TruthEffect | None, seed: int, duration_s: float = 10.0,
                       params: DriveParams | None = None, pulse_us: np.ndarray | None = None,
                       truth_spans_s: tuple[tuple[float, float], ...] = ()) -> TruthCase:
    """Run the truth plant over an excitation program and write the recording; returns its TruthCase.

    params: the truth's base parameters (None: perturbed 3-10 % from nominal with this seed).
    pulse_us: the pulse program per 1 ms tick (None: excitation_program with this seed).
    truth_spans_s: where the effect acts, for scoring the located spans (regime-limited cases).
    """
    path = Path(path)
    rng = np.random.default_rng([seed, 0xD1A6])
    if params is None:
        params = perturbed_params(rng)
    if pulse_us is None:
        pulse_us = excitation_program(rng, duration_s)
    plant = DrivePlant(params, seed=seed)
    if effect is not None:
        effect.reset(np.random.default_rng([seed, 0x7E]))
        if effect.replaces_drag:
            plant.rope_exposed_length_m = 0.0
    mt = _MtEstimator(params.encoder_counts_per_rev, params.wheel_radius_m, SPEED_FILTER_TAU_S)
    device_params = {"speed_filter_tau_s": str(SPEED_FILTER_TAU_S), "wheel_radius_m": "0.015",
                     "encoder_counts_per_rev": "64", "motor_kv_rpm_per_v": "1250", "esc_min_us": "1000",
                     "tov_mps": str(TOV_MPS), "telemetry_rate_hz": "50"}
    sag_v = 0.0
    base_aux = plant.battery_aux_current_a
    with RecordingWriter(path, source="simulator", seed=seed, time_base="simulation",
                         clock_ns=lambda: plant.time_us * 1000,
                         description="diagnose proof generator (truth model, not for diagnosis: "
                                     f"effect {effect.effect_id if effect else 'none'})") as w:
        w.add_metadata("/device/params", device_params)
        seq = 0
        meas = 0.0
        for k in range(pulse_us.size):
            t_s = plant.time_us * 1e-6
            meas = mt.step(plant.encoder_counts, plant.encoder_last_edge_us, plant.time_us, 1e-3 if k else 0.0)
            if k % TELEMETRY_PERIOD_TICKS == 0:
                v = abs(plant.rope_speed_mps)
                state = "ARMED" if v < 0.05 else ("AIRBORNE" if v > TOV_MPS else "SPINUP")
                w.write("/device/telemetry", _telemetry(t_s, seq, state, int(pulse_us[k]), meas,
                                                        plant.battery_adc_v, k // TELEMETRY_PERIOD_TICKS))
                w.write("/sim/plant_truth", {"time_s": round(t_s, 3), "rope_speed_mps": plant.rope_speed_mps,
                                             "battery_v": plant.battery_v,
                                             "external_rope_load_n": plant.external_rope_load_n})
                seq += 1
            applied = float(pulse_us[k])
            if effect is not None:
                applied = effect.pulse(applied, t_s, plant)
                v = plant.rope_speed_mps
                f = effect.force_n(t_s, v) if effect.regime(t_s, abs(v)) else 0.0
                if effect.replaces_drag and not effect.regime(t_s, abs(v)):
                    f = params.rope_drag_coeff_n_s2_per_m2 * v * v
                plant.external_rope_load_n = max(0.0, f)
                i_motors = plant.battery_current_a - plant.battery_aux_current_a
                new_sag = effect.sag_v(t_s, i_motors + base_aux, 1e-3) if effect.regime(t_s, abs(v)) else 0.0
                if new_sag != sag_v:
                    sag_v = new_sag
                    plant.battery_aux_current_a = base_aux + max(0.0, sag_v) / params.battery_internal_resistance_ohm
            plant.step_us(esc_pulse_us=min(max(applied, 0.0), params.esc_frame_us), dt_us=1000)
    return TruthCase(path=path, seed=seed, effect_id=effect.effect_id if effect else None,
                     truth=dict(effect.truth) if effect else {}, params=params, duration_s=duration_s,
                     truth_spans_s=tuple(truth_spans_s))
