"""Recordings from a truth model for the diagnose proof: the per-tick DrivePlant with base parameters
perturbed from nominal as real hardware is, one truth effect switched on (or none), driven as a user records it
with `wrangler excite --profile drive` (the firmware's speed loop following the profile's steps, ramps and chirp,
compressed to the recording's length; 1 kHz bursts at the spin-up, a step up, a step down and the spin-down),
and the board's measurement chain: M/T speed estimate on the encoder's edges with the firmware's low-pass,
telemetry at 100 Hz (or 50 Hz) rounded to mm/s and whole rpm with the pulse at 1/3 us, the encoder's count and
latest edge time, the battery ADC's noise and step.

Writes the documented schema (/device/telemetry, /device/burst, /device/params; /sim/plant_truth for scoring
only: diagnose never reads it).

    case = generate_recording("r.mcap", effect=LatencyTruth("esc_latency", {"delay_s": 0.008}, delay_s=0.008),
                              seed=3, duration_s=12.0)
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
    effect: TruthEffect | None = dataclasses.field(default=None, repr=False, compare=False)
    """The truth effect object the recording was made with (for the oracle's replay of the truth plant)."""
    tick_truth: dict[str, np.ndarray] = dataclasses.field(default_factory=dict, repr=False, compare=False)
    """The truth plant's state at each 1 ms tick k (time k ms, where the records of tick k are taken), for the
    identifiability oracle (proof/oracle.py): rope_position_m (the wheel's travel, r x shaft angle),
    rope_speed_mps, battery_v (terminal volts, before the ADC's noise and step), esc_command_us (the pulse the
    speed loop commanded for the tick, before the effect)."""


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
    """Open-loop pulse per 1 ms tick (the older generator's program, kept for tests that need a plain pulse
    record): 0.4 s arming at 1000 us, then holds of 0.25-0.7 s at random levels across the speed range
    (1015-1450 us), rests at 1000 us and slow ramps; changes only every 20 ticks."""
    n = int(round(duration_s * 1000))
    pulse = np.full(n, 1000.0)
    k = 400
    levels = []
    while k < n:
        kind = rng.random()
        hold = int(rng.uniform(0.25, 0.7) * 1000) // 20 * 20
        if kind < 0.12:
            level = 1000.0
        elif kind < 0.35:
            level = float(rng.integers(1015, 1080))
        else:
            level = float(rng.integers(1080, 1450))
        if rng.random() < 0.15 and levels:
            ramp = np.linspace(levels[-1], level, hold // 20)
            seg = np.repeat(np.round(ramp), 20)
            pulse[k:k + seg.size] = seg[: max(0, min(seg.size, n - k))]
        else:
            pulse[k:k + hold] = level
        levels.append(level)
        k += hold
    return pulse


@dataclass(frozen=True)
class ExciteProgram:
    """A compressed `wrangler excite --profile drive` run (host/robowrangler/excite/profiles/drive.toml): speed
    targets per 1 ms tick for the firmware's speed loop (NaN: ARMED, pulse at the minimum; 0 after spindown_s:
    landing), and the ticks where a 1 kHz burst starts (spin-up, a step up, a step down, the spin-down)."""

    target_mps: np.ndarray
    burst_starts: tuple[int, ...]
    burst_samples: int
    spindown_s: float


EXCITE_EDGES_S = (0.5, 2.0, 3.5, 5.0, 6.0, 7.0, 9.5)
"""On a 12 s program: spin-up, step up, ramp start, ramp end, step down, chirp, spindown (scaled to the length)."""


def excite_edges_s(duration_s: float) -> np.ndarray:
    """The excite program's segment starts (EXCITE_EDGES_S scaled to duration_s), s."""
    return np.asarray(EXCITE_EDGES_S) * duration_s / 12.0


def excite_program(rng: np.random.Generator, duration_s: float) -> ExciteProgram:
    """The drive profile's shape on duration_s (>= 6 s): arming; spin-up to v1 (3.2-4.5 m/s) with a burst;
    a step up to v2 (5.5-7.5) with a burst; a ramp to v3 (9-12) and a hold; a step down to v4 (6-8) with a
    burst; a chirp around v4 (+-1 m/s, 0.5 -> 4 Hz, setpoints at 50 Hz); SPINDOWN with a burst; rest."""
    if duration_s < 6.0:
        raise ValueError(f"duration_s: expected >= 6 s for the excite program, got {duration_s}")
    n = int(round(duration_s * 1000))
    t = np.arange(n) * 1e-3
    v1, v2 = rng.uniform(3.2, 4.5), rng.uniform(5.5, 7.5)
    v3, v4 = rng.uniform(9.0, 12.0), rng.uniform(6.0, 8.0)
    edges = excite_edges_s(duration_s)
    tgt = np.full(n, np.nan)
    tgt[t >= edges[0]] = v1
    tgt[t >= edges[1]] = v2
    ramp = (t >= edges[2]) & (t < edges[3])
    tgt[ramp] = v2 + (v3 - v2) * np.floor((t[ramp] - edges[2]) * 20.0) / 20.0 / (edges[3] - edges[2])
    tgt[(t >= edges[3]) & (t < edges[4])] = v3
    tgt[(t >= edges[4]) & (t < edges[5])] = v4
    ch = (t >= edges[5]) & (t < edges[6])
    tc = np.floor((t[ch] - edges[5]) * 50.0) / 50.0
    f0, f1, dur = 0.5, 4.0, edges[6] - edges[5]
    tgt[ch] = v4 + 1.0 * np.sin(2 * np.pi * (f0 * tc + 0.5 * (f1 - f0) / dur * tc * tc))
    tgt[t >= edges[6]] = 0.0
    bursts = tuple(int(round(e * 1000)) for e in (edges[0], edges[1], edges[4], edges[6]))
    return ExciteProgram(target_mps=tgt, burst_starts=bursts, burst_samples=1000, spindown_s=float(edges[6]))


class _SpeedLoop:
    """The firmware's rope speed loop (firmware/core/rw_speed_loop.c, in floats): setpoint ramp (20 m/s^2 up,
    10 down), feed-forward throttle from kv and the battery volts, PI (kp 0.04 / (m/s), ki 0.4 / (m/s s)) with
    the integrator clamped so the throttle stays in 0..1, pulse at the PWM timer's 1/3 us."""

    def __init__(self, params: DriveParams) -> None:
        self.kv = params.motor_kv_rpm_per_v
        self.r = params.wheel_radius_m
        self.setpoint = 0.0
        self.integ = 0.0

    def step(self, target_mps: float, measured_mps: float, battery_v: float, dt_s: float) -> float:
        if not np.isfinite(target_mps):
            self.setpoint, self.integ = measured_mps, 0.0
            return 1000.0
        d = target_mps - self.setpoint
        self.setpoint += min(d, 20.0 * dt_s) if d > 0 else max(d, -10.0 * dt_s)
        if target_mps == 0.0 and self.setpoint <= 0.0:
            self.integ = 0.0
            return 1000.0
        ff = self.setpoint / (2.0 * math.pi * self.r * self.kv * battery_v / 60.0)
        e = self.setpoint - measured_mps
        self.integ += 0.4 * e * dt_s
        u = ff + 0.04 * e + self.integ
        if u > 1.0 or u < 0.0:
            u = min(max(u, 0.0), 1.0)
            self.integ = u - ff - 0.04 * e
        return round((1000.0 + 1000.0 * u) * 3.0) / 3.0


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


def _telemetry(t_s: float, seq: int, state: str, pulse_us: float, speed_mps: float, battery_v: float,
               counters: int, encoder_counts: int, encoder_edge_us: int, *, fine_pulse: bool, target_mps: float,
               setpoint_mps: float) -> dict:
    rpm = int(round(speed_mps / (2.0 * math.pi * DriveParams().wheel_radius_m) * 60.0))
    fine = round(pulse_us * 3.0) / 3.0 if fine_pulse else float(int(round(pulse_us)))
    return {"time_s": round(t_s, 3), "state": state, "fault_bits": [], "rope_speed_target_mps": round(target_mps, 3),
            "rope_speed_setpoint_mps": round(setpoint_mps, 3), "rope_speed_mps": round(speed_mps, 3), "motor_rpm": rpm,
            "esc_pulse_us": int(round(pulse_us)), "battery_v": round(battery_v, 3), "heartbeat_age_s": 0.02,
            "rx_ok": counters % 65536, "rx_bad": 0, "rx_duplicates": 0, "nacks": 0, "events": 0, "tick_overruns": 0,
            "guide_position_m": 0.0, "guide_target_m": 0.0, "spindle_load_permille": 0, "spindle_flags": ["HOMED"],
            "spindle_rejected": 0, "rx_auth_failed": 0, "rx_replayed": 0, "tx_dropped": 0, "seq": seq % 65536,
            "esc_pulse_fine_us": fine, "spindle_moving_speed_raw": 0,
            "encoder_counts": encoder_counts % 2 ** 32, "encoder_edge_us": encoder_edge_us % 2 ** 32}


def _burst_frames(burst_id: int, start_tick: int, samples: list[tuple[int, int, float, float]], seq0: int) -> list[dict]:
    """/device/burst records (BURST_DATA frames of 6 samples) of one burst taken from start_tick."""
    out = []
    for k in range(0, len(samples), 6):
        chunk = samples[k:k + 6]
        out.append({"burst_id": burst_id % 65536, "start_time_s": round(start_tick * 1e-3, 3),
                    "start_time_us": (start_tick * 1000) % 2 ** 32, "tick_us": 1000, "sample_count": len(samples),
                    "first_sample": k, "encoder_counts": [c % 65536 for c, _, _, _ in chunk],
                    "encoder_edge_us": [e % 65536 for _, e, _, _ in chunk],
                    "esc_pulse_fine_us": [round(p * 3.0) / 3.0 for _, _, p, _ in chunk],
                    "battery_v": [round(b, 3) for _, _, _, b in chunk], "seq": (seq0 + len(out)) % 65536})
    return out


class _TruthStep:
    """One 1 ms step of the truth plant with its effect: the effect's pulse, rope force and sag applied through the
    plant's seams (truth_effects.py), then the plant stepped. Construction resets the effect (its generator from
    the seed) and, for a drag that replaces the plant's own, switches that off."""

    def __init__(self, plant: DrivePlant, effect: TruthEffect | None, seed: int) -> None:
        self.plant = plant
        self.effect = effect
        self.sag_v = 0.0
        self.base_aux = plant.battery_aux_current_a
        if effect is not None:
            effect.reset(np.random.default_rng([seed, 0x7E]))
            if effect.replaces_drag:
                plant.rope_exposed_length_m = 0.0

    def step(self, cmd_us: float, t_s: float) -> None:
        plant, effect, params = self.plant, self.effect, self.plant.params
        applied = cmd_us
        if effect is not None:
            applied = effect.pulse(applied, t_s, plant)
            v = plant.rope_speed_mps
            f = effect.force_n(t_s, v) if effect.regime(t_s, abs(v)) else 0.0
            if effect.replaces_drag and not effect.regime(t_s, abs(v)):
                f = params.rope_drag_coeff_n_s2_per_m2 * v * v
            plant.external_rope_load_n = max(0.0, f)
            i_motors = plant.battery_current_a - plant.battery_aux_current_a
            new_sag = effect.sag_v(t_s, i_motors + self.base_aux, 1e-3) if effect.regime(t_s, abs(v)) else 0.0
            if new_sag != self.sag_v:
                self.sag_v = new_sag
                plant.battery_aux_current_a = (self.base_aux + max(0.0, new_sag)
                                               / params.battery_internal_resistance_ohm)
        plant.step_us(esc_pulse_us=min(max(applied, 0.0), params.esc_frame_us), dt_us=1000)


def run_truth(params: DriveParams, effect: TruthEffect | None, seed: int, pulse_us: np.ndarray) -> dict[str, np.ndarray]:
    """The truth plant (params, effect, seed as a recording was generated with) driven open loop by pulse_us per
    1 ms tick from power-up: per tick k (time k ms, before its step) rope_position_m, rope_speed_mps, battery_v
    (as TruthCase.tick_truth)."""
    plant = DrivePlant(params, seed=seed)
    truth_step = _TruthStep(plant, effect, seed)
    n = len(pulse_us)
    x, v, b = np.empty(n), np.empty(n), np.empty(n)
    r_wheel = params.wheel_radius_m
    for k in range(n):
        x[k], v[k], b[k] = plant.shaft_angle_rad * r_wheel, plant.rope_speed_mps, plant.battery_v
        truth_step.step(float(pulse_us[k]), plant.time_us * 1e-6)
    return {"rope_position_m": x, "rope_speed_mps": v, "battery_v": b}


def generate_recording(path: str | Path, *, effect: TruthEffect | None, seed: int, duration_s: float = 12.0,
                       params: DriveParams | None = None, pulse_us: np.ndarray | None = None,
                       truth_spans_s: tuple[tuple[float, float], ...] = (), telemetry_hz: float = 100.0,
                       fine_pulse: bool = True, bursts: bool = True) -> TruthCase:
    """Run the truth plant and write the recording; returns its TruthCase.

    By default the run is what a user records with `wrangler excite --profile drive` (compressed to
    duration_s): the firmware's speed loop (emulated, _SpeedLoop) follows excite_program's targets, telemetry
    at telemetry_hz with the pulse at 1/3 us (fine_pulse=False: whole us, as older firmware sent it) and 1 kHz
    bursts at the steps (bursts=False: none, as a plain `wrangler record` of an older board).
    params: the truth's base parameters (None: perturbed 3-10 % from nominal with this seed).
    pulse_us: an open-loop pulse program per 1 ms tick instead (no speed loop, no bursts).
    truth_spans_s: where the effect acts, for scoring the located spans (regime-limited cases).
    """
    path = Path(path)
    if telemetry_hz not in (50.0, 100.0):
        raise ValueError(f"telemetry_hz: expected 50 or 100 (the firmware's rates), got {telemetry_hz}")
    period = int(round(1000.0 / telemetry_hz))
    rng = np.random.default_rng([seed, 0xD1A6])
    if params is None:
        params = perturbed_params(rng)
    program = None
    if pulse_us is None:
        program = excite_program(rng, duration_s)
        n_ticks = program.target_mps.size
    else:
        n_ticks = pulse_us.size
    plant = DrivePlant(params, seed=seed)
    truth_step = _TruthStep(plant, effect, seed)
    mt = _MtEstimator(params.encoder_counts_per_rev, params.wheel_radius_m, SPEED_FILTER_TAU_S)
    loop = _SpeedLoop(DriveParams())  # the firmware's configured kv and wheel (class values, not the truth's)
    device_params = {"speed_filter_tau_s": str(SPEED_FILTER_TAU_S), "wheel_radius_m": "0.015",
                     "encoder_counts_per_rev": "64", "motor_kv_rpm_per_v": "1250", "esc_min_us": "1000",
                     "tov_mps": str(TOV_MPS), "telemetry_rate_hz": str(int(telemetry_hz))}
    burst_at = {} if program is None or not bursts else {b: i for i, b in enumerate(program.burst_starts)}
    with RecordingWriter(path, source="simulator", seed=seed, time_base="simulation",
                         clock_ns=lambda: plant.time_us * 1000,
                         description="diagnose proof generator (truth model, not for diagnosis: "
                                     f"effect {effect.effect_id if effect else 'none'})") as w:
        w.add_metadata("/device/params", device_params)
        seq = 0
        meas = 0.0
        burst: tuple[int, int, list] | None = None
        r_wheel = params.wheel_radius_m
        true_x, true_v, true_batt, true_cmd = (np.empty(n_ticks) for _ in range(4))
        for k in range(n_ticks):
            t_s = plant.time_us * 1e-6
            true_x[k], true_v[k], true_batt[k] = plant.shaft_angle_rad * r_wheel, plant.rope_speed_mps, plant.battery_v
            meas = mt.step(plant.encoder_counts, plant.encoder_last_edge_us, plant.time_us, 1e-3 if k else 0.0)
            if program is None:
                cmd = float(pulse_us[k])
                target = setpoint = 0.0
            else:
                target = float(program.target_mps[k])
                cmd = loop.step(target, meas, plant.battery_adc_v, 1e-3)
                setpoint = loop.setpoint if np.isfinite(target) else 0.0
                target = target if np.isfinite(target) else 0.0
            if k in burst_at and burst is None:
                burst = (burst_at[k], k, [])
            if burst is not None:
                burst[2].append((abs(plant.encoder_counts), plant.encoder_last_edge_us, cmd, plant.battery_adc_v))
                if len(burst[2]) == program.burst_samples or k == n_ticks - 1:
                    for rec in _burst_frames(burst[0], burst[1], burst[2], seq):
                        w.write("/device/burst", rec)
                        seq += 1
                    burst = None
            if k % period == 0:
                v = abs(plant.rope_speed_mps)
                state = "ARMED" if v < 0.05 else ("AIRBORNE" if v > TOV_MPS else "SPINUP")
                w.write("/device/telemetry", _telemetry(t_s, seq, state, cmd, meas, plant.battery_adc_v, k // period,
                                                        abs(plant.encoder_counts), plant.encoder_last_edge_us,
                                                        fine_pulse=fine_pulse, target_mps=target,
                                                        setpoint_mps=setpoint))
                w.write("/sim/plant_truth", {"time_s": round(t_s, 3), "rope_speed_mps": plant.rope_speed_mps,
                                             "battery_v": plant.battery_v,
                                             "external_rope_load_n": plant.external_rope_load_n})
                seq += 1
            true_cmd[k] = cmd
            truth_step.step(cmd, t_s)
    return TruthCase(path=path, seed=seed, effect_id=effect.effect_id if effect else None,
                     truth=dict(effect.truth) if effect else {}, params=params, duration_s=duration_s,
                     truth_spans_s=tuple(truth_spans_s), effect=effect,
                     tick_truth={"rope_position_m": true_x, "rope_speed_mps": true_v, "battery_v": true_batt,
                                 "esc_command_us": true_cmd})
