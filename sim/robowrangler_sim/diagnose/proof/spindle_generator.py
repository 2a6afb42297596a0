"""Spindle recordings from a truth model for the diagnose proof (the spindle's counterpart of generator.py).

The rope runs at one steady speed (as `wrangler excite --profile spindle` holds it at 5 m/s) while the spindle,
open loop, gets a program of moving-speed commands: moves in and out with frequent reversals, fast, medium and
slow moves, rests, a few long travels (what the spindle excitation profile makes the firmware do). The spindle
plant is the per-tick SpindleTruthPlant (spindle_truth.py) with its class estimates perturbed 3-10 % from
nominal, the register noise of the plant (load 8 per mille, position 0.6 units) and the telemetry's units (guide
position in um, load in per mille). Written in the documented schema; /sim/plant_truth carries the nut position
for scoring only.

    case = generate_spindle_recording("r.mcap", truth={"backlash_mm": 0.8}, seed=3, duration_s=8.0)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robowrangler.recorder import RecordingWriter
from robowrangler_sim.diagnose.proof.spindle_truth import SpindleTruthPlant
from robowrangler_sim.plants import DriveParams, DrivePlant
from robowrangler_sim.plants.spindle import SpindleInputs, SpindleParams

TELEMETRY_PERIOD_TICKS = 20
MM_PER_POSITION_UNIT = 300.0 / 1023.0 * 8.0 / 360.0
DRIVE_PULSE_US = 1320.0  # about 5 m/s
SPEED_FILTER_TAU_S = 0.01
PERTURBED = ("no_load_speed_rpm", "response_time_s", "friction_torque_nm")


@dataclass(frozen=True)
class SpindleTruthCase:
    path: Path
    seed: int
    effect_id: str | None
    truth: dict[str, float]
    params: SpindleParams
    duration_s: float
    truth_spans_s: tuple[tuple[float, float], ...]
    plant_truth: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)
    """SpindleTruthPlant's keyword arguments the recording was made with (empty: effect-free)."""
    program: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)
    """The moving-speed register per 1 ms tick from the first (after the spin-up second)."""
    sample_truth: dict[str, np.ndarray] = dataclasses.field(default_factory=dict, repr=False, compare=False)
    """At each telemetry record, before the registers' noise: guide_position_mm, load_permille (the motor's torque
    over the stall torque, x 1000). For the identifiability oracle (proof/spindle_oracle.py)."""


SPINUP_TICKS = 1000  # one second of drive spin-up first, the spindle still


def _truth_sample(sp: SpindleTruthPlant) -> tuple[float, float]:
    return sp.guide_position_mm, sp.torque_nm / sp.params.stall_torque_nm * 1000.0


def run_spindle_truth(params: SpindleParams, plant_truth: dict | None, seed: int,
                      program: np.ndarray) -> dict[str, np.ndarray]:
    """The truth spindle (SpindleTruthPlant with plant_truth's effect, or none) driven by program as the generator
    drives it: per telemetry record, guide_position_mm and load_permille before the registers' noise (as
    SpindleTruthCase.sample_truth)."""
    sp = SpindleTruthPlant(params, seed=seed, **(plant_truth or {}))
    guide, load = [], []
    for k in range(-SPINUP_TICKS, program.size):
        if k % TELEMETRY_PERIOD_TICKS == 0:
            g, f = _truth_sample(sp)
            guide.append(g)
            load.append(f)
        sp.update(SpindleInputs(moving_speed_raw=int(program[k]) if k >= 0 else 0), 1e-3)
    return {"guide_position_mm": np.asarray(guide), "load_permille": np.asarray(load)}


def perturbed_spindle_params(rng: np.random.Generator, *, low: float = 0.03, high: float = 0.10,
                             load_noise_permille: float = 8.0) -> SpindleParams:
    base = SpindleParams()
    changes = {n: getattr(base, n) * (1.0 + rng.uniform(low, high) * rng.choice((-1.0, 1.0))) for n in PERTURBED}
    return dataclasses.replace(base, load_noise_permille=load_noise_permille, **changes)


def spindle_program(rng: np.random.Generator, duration_s: float, *, short_moves: bool = False,
                    start_mm: float = 40.0) -> np.ndarray:
    """Moving-speed register per 1 ms tick: 0.5 s still, then moves (0.2-1.0 s; 0.1-0.3 s when short_moves) at
    fast (300-1000, 30 %), medium (100-300, 25 %) or slow (10-120, 45 %) commands, reversing often, with rests;
    keeps the guide    between 8 and 170 mm; changes only at telemetry ticks."""
    n = int(round(duration_s * 1000))
    raw = np.zeros(n, dtype=np.int64)
    k = 500
    pos = start_mm
    direction = 1
    while k < n:
        q = TELEMETRY_PERIOD_TICKS
        if rng.random() < 0.2:
            hold = int(rng.uniform(0.1, 0.4) * 1000) // q * q
            k += hold
            continue
        kind = rng.random()
        mag = int(rng.integers(300, 1000) if kind < 0.3 else rng.integers(100, 300) if kind < 0.55
                  else rng.integers(10, 120))
        if rng.random() < 0.6:
            direction = -direction
        dur = rng.uniform(0.1, 0.3) if short_moves else rng.uniform(0.2, 1.0)
        travel = direction * mag * 0.0077 * dur
        if not 8.0 < pos + travel < 170.0:
            direction = -direction
            travel = -travel
        hold = max(q, int(dur * 1000) // q * q)
        raw[k:k + hold] = mag | (0x400 if direction < 0 else 0)
        pos += travel
        k += hold
    return raw


def _telemetry(t_s: float, seq: int, speed_mps: float, pulse_us: float, battery_v: float, guide_mm: float,
               load_permille: int, raw: int) -> dict:
    rpm = int(round(speed_mps / (2.0 * math.pi * DriveParams().wheel_radius_m) * 60.0))
    return {"time_s": round(t_s, 3), "state": "AIRBORNE", "fault_bits": [], "rope_speed_target_mps": 5.0,
            "rope_speed_setpoint_mps": 5.0, "rope_speed_mps": round(speed_mps, 3), "motor_rpm": rpm,
            "esc_pulse_us": int(pulse_us), "battery_v": round(battery_v, 3), "heartbeat_age_s": 0.02,
            "rx_ok": seq % 65536, "rx_bad": 0, "rx_duplicates": 0, "nacks": 0, "events": 0, "tick_overruns": 0,
            "guide_position_m": round(guide_mm * 1e-3, 6), "guide_target_m": 0.0,
            "spindle_load_permille": int(load_permille), "spindle_flags": ["HOMED"], "spindle_rejected": 0,
            "rx_auth_failed": 0, "rx_replayed": 0, "tx_dropped": 0, "seq": seq % 65536,
            "esc_pulse_fine_us": float(pulse_us), "spindle_moving_speed_raw": int(raw), "encoder_counts": 0,
            "encoder_edge_us": 0}


def _signed_load(load_raw: int) -> int:
    return -(load_raw & 0x3FF) if load_raw & 0x400 else load_raw & 0x3FF


def generate_spindle_recording(path: str | Path, *, truth: dict[str, float] | None, seed: int,
                               duration_s: float = 8.0, params: SpindleParams | None = None,
                               program: np.ndarray | None = None, load_noise_permille: float = 8.0,
                               effect_id: str | None = None, truth_spans_s: tuple = (),
                               truth_for_scoring: dict[str, float] | None = None) -> SpindleTruthCase:
    """truth: SpindleTruthPlant keyword arguments (deadband_in_raw, deadband_out_raw, backlash_mm, soft_fraction,
    backlash_region_mm) or None for an effect-free recording. program: moving-speed register per tick (None:
    spindle_program with this seed)."""
    path = Path(path)
    rng = np.random.default_rng([seed, 0x5B1D])
    if params is None:
        params = perturbed_spindle_params(rng, load_noise_permille=load_noise_permille)
    if program is None:
        program = spindle_program(rng, duration_s)
    sp = SpindleTruthPlant(params, seed=seed, **(truth or {}))
    drive = DrivePlant(DriveParams(), seed=seed)
    meas = 0.0
    n = program.size
    with RecordingWriter(path, source="simulator", seed=seed, time_base="simulation",
                         clock_ns=lambda: drive.time_us * 1000,
                         description=f"diagnose spindle proof generator (effect {effect_id or 'none'})") as w:
        w.add_metadata("/device/params", {"speed_filter_tau_s": str(SPEED_FILTER_TAU_S), "wheel_radius_m": "0.015",
                                          "encoder_counts_per_rev": "64", "esc_min_us": "1000",
                                          "telemetry_rate_hz": "50"})
        seq = 0
        true_guide, true_load = [], []
        for k in range(-SPINUP_TICKS, n):  # one second of spin-up first, the spindle still
            pulse = 1000.0 if k < -600 else DRIVE_PULSE_US
            raw = int(program[k]) if k >= 0 else 0
            t_s = drive.time_us * 1e-6
            meas += (drive.rope_speed_mps - meas) * (1e-3 / (SPEED_FILTER_TAU_S + 1e-3))
            if k % TELEMETRY_PERIOD_TICKS == 0:
                o = sp.outputs()
                g, f = _truth_sample(sp)
                true_guide.append(g)
                true_load.append(f)
                noisy_mm = o.guide_position_mm + rng.normal(0.0, params.position_noise_units) * MM_PER_POSITION_UNIT
                w.write("/device/telemetry", _telemetry(t_s, seq, meas, pulse, drive.battery_adc_v, noisy_mm,
                                                        _signed_load(o.load_raw), raw))
                w.write("/sim/plant_truth", {"time_s": round(t_s, 3), "rope_speed_mps": drive.rope_speed_mps,
                                             "battery_v": drive.battery_v,
                                             "guide_position_m": sp.nut_position_mm * 1e-3})
                seq += 1
            drive.step_us(esc_pulse_us=pulse, dt_us=1000)
            sp.update(SpindleInputs(moving_speed_raw=raw), 1e-3)
    return SpindleTruthCase(path=path, seed=seed, effect_id=effect_id, truth=dict(truth_for_scoring or {}),
                            params=params, duration_s=duration_s, truth_spans_s=tuple(truth_spans_s),
                            plant_truth=dict(truth or {}), program=program,
                            sample_truth={"guide_position_mm": np.asarray(true_guide),
                                          "load_permille": np.asarray(true_load)})
