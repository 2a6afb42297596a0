"""Drive recordings made OUTSIDE the project: an independent simulator that writes the documented schema.

Nothing of robowrangler or robowrangler_sim is imported: the physics below is written from first principles and
datasheet-like constants (the hardware description: two 1250 KV 23xx outrunners on 15 mm rubber wheels pinching a
2 mm, 0.221 g/m rope of a 2 m loop, BLHeli_32 ESCs at 400 Hz PWM, a 3S pack, a 64-edge magnetic encoder), and the
file is written with the `mcap` library and the schema files of protocol/recording/schemas/ only (schema.md,
section 4), so the project's writer conventions are judged as well as its physics.

How this simulator differs in STRUCTURE from the project's plant (on purpose: a real rig is not our model):
  * two motors with their own constants (KV, resistance, friction a per cent or two apart), each with its winding
    inductance (electrical time constant ~0.15 ms), on one rigid shaft;
  * the ESC latches the pulse at its 400 Hz frame, measures it at the pulse's falling edge, averages the last two
    frames and applies it after a processing delay (no first-order lag), maps throttle to duty from its own
    calibrated zero, loses a little duty to PWM dead time, and freewheels at zero throttle (damped light above);
  * motor losses as no-load current (hysteresis: constant, eddy: proportional to speed) plus bearing stiction
    with stick/slip, a tiny cogging torque at 84 per revolution (12 slots, 14 poles);
  * rope: skin-friction air drag on the exposed part, a capstan term in the guide (friction on the rope's
    centrifugal tension, lambda v^2), nip rolling resistance;
  * battery: open-circuit voltage on a LiPo curve of the charge drawn, series resistance (no polarisation);
    the board reads it through an RC anti-alias filter, ADC noise and 12-bit steps;
  * encoder: 16 magnet lines x 4 quadrature edges with a line-spacing error and a quadrature phase error, edge
    capture on a 1 us timer with jitter;
  * the firmware: its own M/T estimate and low-pass, a PI with conditional integration and a battery
    feed-forward updated every 10 ms, setpoint ramps; telemetry at 100 Hz on the device clock (booted long
    before: time_s does not start at 0), the device's one frame counter shared with events, ACKs and burst
    frames; a few frames lost on the link (with their /link/gap records) and host-side reception jitter;
  * the run is a compressed `wrangler excite --profile drive`: ARM, steps with a 1 kHz burst each, a ramp, a
    high-throttle hold, a step down, chirps, spin-down; every command in /host/command with its ACK.

Effects (one at a time, or none), each in a form that is NOT the library's law, with the key parameter named as the
library's parameter of the same meaning (OUTSIDE_EFFECTS):
  esc_latency          extra ESC delay that varies with the frame phase (ESC clock drifting against the board's)
  esc_deadband         a dead band in DUTY (not in pulse), with hysteresis in duty
  battery_sag          diffusion-like polarisation: an RC ladder whose step response grows as sqrt(t)
  low_speed_friction   extra friction F0 / (1 + v / v0) (no exponential Stribeck curve)
  rope_drag_law        a fuzzy rope: drag k v^1.7 (no v^2)
  external_rope_load   a caught object lifted: a load that rises on a ramp, holds, and is let go

    truth = write_outside_recording("r.mcap", seed=3, effect="esc_latency")
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from mcap.writer import CompressionType, Writer

ROOT = Path(__file__).resolve().parents[1]
SCHEMA_DIR = ROOT / "protocol" / "recording" / "schemas"

G_MPS2 = 9.81
AIR_DENSITY_KG_PER_M3 = 1.204
TICK_US = 1000
SUBSTEPS = 4
PWM_PERIOD_US = 2500

# --- the datasheet / hardware description (nominal; every recording draws its own unit from these) ---
DATASHEET = {
    "kv_rpm_per_v": 1250.0,            # AS2317-class outrunner, 1250 KV
    "r_phase_ohm": 0.075,              # line-to-line winding resistance
    "r_esc_ohm": 0.010,                # MOSFETs + leads
    "l_phase_h": 14e-6,                # line-to-line inductance of a 23xx outrunner
    "i_noload_hyst_a": 0.2,            # no-load current, speed-independent part (bearings, hysteresis)
    "i_noload_eddy_a_at_1309": 0.5,    # no-load current part proportional to speed, at 1309 rad/s (10 V)
    "rotor_inertia_kg_m2": 3.5e-6,
    "wheel_inertia_kg_m2": 7.0e-7,
    "wheel_radius_m": 0.015,
    "rope_density_kg_per_m": 0.221e-3,
    "rope_diameter_m": 2.0e-3,
    "rope_loop_m": 2.0,
    "rope_exposed_m": 1.9,             # part of the loop in the air (the rest is in the module)
    "takeoff_speed_mps": 2.6,          # measured ToV: calibrates the skin friction
    "guide_friction_n": 0.04,
    "guide_capstan_mu_theta": 0.5,     # friction coefficient x wrap angle in the guide (on lambda v^2)
    "nip_friction_n": 0.08,
    "nip_viscous_n_s_per_m": 0.004,
    "battery_ocv_v": 12.0,
    "battery_r_ohm": 0.030,
    "battery_capacity_ah": 1.5,
    "aux_current_a": 0.1,
    "esc_zero_us": 10.0,               # the ESC's zero-throttle zone above 1000 us
    "esc_proc_delay_s": 0.4e-3,        # ESC input processing before the new throttle applies
    "esc_dead_time_duty": 0.003,       # PWM dead time as a duty loss (0.12 us at 24 kHz)
    "adc_tau_s": 0.5e-3,               # battery divider's anti-alias RC
    "adc_noise_v": 0.008,
    "edge_jitter_us": 0.4,
    "esc_average_frames": 2,           # input frames the ESC averages
}
PERTURBED = ("r_phase_ohm", "r_esc_ohm", "l_phase_h", "i_noload_hyst_a", "i_noload_eddy_a_at_1309",
             "rotor_inertia_kg_m2", "guide_friction_n", "guide_capstan_mu_theta", "nip_friction_n",
             "nip_viscous_n_s_per_m", "battery_r_ohm", "takeoff_speed_mps", "esc_zero_us", "esc_proc_delay_s",
             "adc_tau_s", "rope_exposed_m")


@dataclass(frozen=True)
class OutsideEffect:
    """An effect in this simulator's own form. key: the library's parameter of the same meaning; truth: its true
    value (and any other comparable ones) in the library's units."""

    effect_id: str
    key: str
    params: dict
    describe: str


def default_effect(effect_id: str, rng: np.random.Generator) -> OutsideEffect:
    """The plain (clearly present) form of each outside effect, with per-seed strengths."""
    if effect_id == "esc_latency":
        d = rng.uniform(0.005, 0.008)
        return OutsideEffect(effect_id, "delay_s", {"delay_s": d, "phase_swing": 0.35, "drift_ppm": 800.0},
                             f"ESC delay {d * 1e3:.1f} ms +-35 % with the frame phase")
    if effect_id == "esc_deadband":
        db = rng.uniform(0.04, 0.06)
        return OutsideEffect(effect_id, "deadband_us", {"duty_deadband": db, "duty_hysteresis": 0.4 * db},
                             f"duty dead band {db:.3f} (hysteresis {0.4 * db:.3f})")
    if effect_id == "battery_sag":
        r = rng.uniform(0.035, 0.06)
        return OutsideEffect(effect_id, "polarisation_resistance_ohm", {"ladder_r_ohm": r, "tau_min_s": 0.03,
                                                                       "tau_max_s": 8.0},
                             f"diffusion sag, ladder {r * 1e3:.0f} mOhm (sqrt-t, 0.03-8 s)")
    if effect_id == "low_speed_friction":
        f0, v0 = rng.uniform(0.4, 0.7), rng.uniform(0.6, 1.2)
        return OutsideEffect(effect_id, "stribeck_force_n", {"f0_n": f0, "v0_mps": v0},
                             f"friction {f0:.2f} N / (1 + v / {v0:.2f} m/s)")
    if effect_id == "rope_drag_law":
        gain = rng.uniform(2.0, 3.0)
        return OutsideEffect(effect_id, "drag_exponent", {"exponent": 1.7, "gain_at_8mps": gain},
                             f"drag k v^1.7, {gain:.1f}x the smooth rope's at 8 m/s")
    if effect_id == "external_rope_load":
        f = rng.uniform(0.3, 0.5)
        t0 = rng.uniform(6.0, 6.6)
        return OutsideEffect(effect_id, "external_load_n", {"load_n": f, "t_start_s": t0, "rise_s": 0.6,
                                                            "t_release_s": t0 + rng.uniform(1.8, 2.4)},
                             f"object lifted: 0 -> {f:.2f} N over 0.6 s from {t0:.2f} s, let go after ~2 s")
    raise ValueError(f"effect: expected one of {', '.join(OUTSIDE_EFFECTS)}, got {effect_id!r}")


OUTSIDE_EFFECTS = ("esc_latency", "esc_deadband", "battery_sag", "low_speed_friction", "rope_drag_law",
                   "external_rope_load")


def draw_unit(rng: np.random.Generator) -> dict:
    """One unit's constants: each datasheet value off by 3-10 % (random sign); battery OCV per its charge."""
    unit = dict(DATASHEET)
    for name in PERTURBED:
        unit[name] = DATASHEET[name] * (1.0 + rng.uniform(0.03, 0.10) * rng.choice((-1.0, 1.0)))
    unit["battery_ocv_v"] = rng.uniform(11.6, 12.4)
    # the second motor is a different unit of the same part: a per cent or two apart
    unit["motor2_scale"] = {k: 1.0 + rng.uniform(-0.02, 0.02) for k in ("kv", "r", "i0")}
    unit["encoder_line_error"] = rng.normal(0.0, 0.005, 16)     # fraction of an edge pitch, per magnet line
    unit["encoder_quad_error"] = rng.uniform(-0.03, 0.03, 2)    # quadrature phase / duty error, fraction of pitch
    unit["pwm_phase_us"] = rng.uniform(0.0, PWM_PERIOD_US)
    unit["cog_nm"] = 0.08e-3
    unit["shaft_angle0_rad"] = rng.uniform(0.0, 2.0 * math.pi)
    return unit


# --------------------------------------------------------------------------------------------------------------
# the plant
# --------------------------------------------------------------------------------------------------------------

class _Battery:
    """3S LiPo: OCV on a plateau curve of the charge drawn, series resistance, optional diffusion ladder."""

    def __init__(self, unit: dict, ladder: dict | None) -> None:
        self.ocv0 = unit["battery_ocv_v"]
        self.r = unit["battery_r_ohm"]
        self.cap_as = unit["battery_capacity_ah"] * 3600.0
        self.drawn_as = 0.0
        self.branches: list[tuple[float, float]] = []  # (R, tau) of the ladder
        self.vp = []
        if ladder is not None:
            # a finite diffusion line's impedance as RC branches with log-spaced time constants; branch resistances
            # proportional to sqrt(tau) make the step response grow as sqrt(t) between tau_min and tau_max
            taus = np.geomspace(ladder["tau_min_s"], ladder["tau_max_s"], 8)
            w = np.sqrt(taus)
            rs = ladder["ladder_r_ohm"] * w / w.sum()
            self.branches = list(zip(rs.tolist(), taus.tolist()))
            self.vp = [0.0] * len(self.branches)

    def ocv(self) -> float:
        soc_used = self.drawn_as / self.cap_as
        # per cell: a plateau falling 0.25 V over the first 30 % used, with a gentle curvature
        return self.ocv0 - 3.0 * (0.8 * soc_used + 0.4 * soc_used * soc_used)

    def terminal_v(self, i_a: float) -> float:
        return self.ocv() - self.r * i_a - sum(self.vp)

    def step(self, i_a: float, dt_s: float) -> None:
        self.drawn_as += i_a * dt_s
        for k, (r, tau) in enumerate(self.branches):
            a = math.exp(-dt_s / tau)
            self.vp[k] = self.vp[k] * a + r * i_a * (1.0 - a)


class _Esc:
    """BLHeli_32-like: latches at the 400 Hz frame, measures the width, averages two frames, applies after its
    processing delay; throttle -> duty from its calibrated zero; damped light; freewheel at zero throttle."""

    def __init__(self, unit: dict, effect: OutsideEffect | None) -> None:
        self.zero_us = 1000.0 + unit["esc_zero_us"]
        self.proc_s = unit["esc_proc_delay_s"]
        self.dead_time = unit["esc_dead_time_duty"]
        self.effect = effect
        self.n_avg = int(unit["esc_average_frames"])
        self.last_frames = [0.0] * self.n_avg
        self.pending: list[tuple[float, float]] = []  # (apply time s, throttle)
        self.throttle = 0.0
        self.running = False  # the duty dead band's hysteresis state

    def frame(self, start_s: float, pulse_us: float, frame_index: int) -> None:
        thr = min(max((pulse_us - self.zero_us) / (2000.0 - self.zero_us), 0.0), 1.0)
        self.last_frames = self.last_frames[1:] + [thr]
        avg = sum(self.last_frames) / self.n_avg
        t_apply = start_s + pulse_us * 1e-6 + self.proc_s
        if self.effect is not None and self.effect.effect_id == "esc_latency":
            p = self.effect.params
            # the ESC's loop clock drifts against the board's PWM: the frame's phase in the ESC's 2.5 ms loop
            # sweeps slowly, and the delay swings with it
            phase = (frame_index * p["drift_ppm"] * 1e-6 * 40.0) % 1.0
            t_apply += p["delay_s"] * (1.0 + p["phase_swing"] * math.sin(2.0 * math.pi * phase))
        self.pending.append((t_apply, avg))

    def duty(self, t_s: float) -> tuple[float, bool]:
        """(duty, driving): driving False = phases floating (zero throttle)."""
        while self.pending and self.pending[0][0] <= t_s:
            self.throttle = self.pending.pop(0)[1]
        thr = self.throttle
        if thr <= 0.0:
            self.running = False
            return 0.0, False
        d = thr
        if self.effect is not None and self.effect.effect_id == "esc_deadband":
            p = self.effect.params
            on_at = p["duty_deadband"] + p["duty_hysteresis"] if not self.running else p["duty_deadband"]
            if d <= on_at:
                self.running = False
                return 0.0, False
            self.running = True
            d = (d - p["duty_deadband"]) / (1.0 - p["duty_deadband"])
        return max(d - self.dead_time, 0.0), True


class _Drive:
    """Two motors with windings on one rigid shaft, the wheels, the rope; rope-side loads; stick/slip."""

    def __init__(self, unit: dict, effect: OutsideEffect | None) -> None:
        self.u = unit
        self.effect = effect
        kv = unit["kv_rpm_per_v"] * 2.0 * math.pi / 60.0
        s2 = unit["motor2_scale"]
        self.ke = [1.0 / kv, 1.0 / (kv * s2["kv"])]
        self.r = [unit["r_phase_ohm"] + unit["r_esc_ohm"], (unit["r_phase_ohm"] + unit["r_esc_ohm"]) * s2["r"]]
        self.l = unit["l_phase_h"]
        self.i0_h = [unit["i_noload_hyst_a"], unit["i_noload_hyst_a"] * s2["i0"]]
        self.i0_e = [unit["i_noload_eddy_a_at_1309"] / 1309.0, unit["i_noload_eddy_a_at_1309"] / 1309.0 * s2["i0"]]
        self.rw = unit["wheel_radius_m"]
        lam = unit["rope_density_kg_per_m"]
        self.lam = lam
        self.j = (2.0 * (unit["rotor_inertia_kg_m2"] + unit["wheel_inertia_kg_m2"])
                  + lam * unit["rope_loop_m"] * self.rw ** 2)
        # skin friction from the takeoff speed: 0.5 rho C_f pi d v*^2 = lambda g
        cf_pi_d = 2.0 * lam * G_MPS2 / (AIR_DENSITY_KG_PER_M3 * unit["takeoff_speed_mps"] ** 2)
        self.k_drag = 0.5 * AIR_DENSITY_KG_PER_M3 * cf_pi_d * unit["rope_exposed_m"]
        self.i = [0.0, 0.0]
        self.omega = 0.0
        self.theta = 0.0
        self.ext_load_n = 0.0

    def rope_load_n(self, v: float, t_s: float) -> float:
        """Rope-side load at speed v > 0, excluding the Coulomb parts (handled with stick/slip)."""
        u = self.u
        if self.effect is not None and self.effect.effect_id == "rope_drag_law":
            p = self.effect.params
            k17 = p["gain_at_8mps"] * self.k_drag * 8.0 ** 2 / 8.0 ** p["exponent"]
            drag = k17 * v ** p["exponent"]
        else:
            drag = self.k_drag * v * v
        load = drag + u["guide_capstan_mu_theta"] * self.lam * v * v + u["nip_viscous_n_s_per_m"] * v
        if self.effect is not None and self.effect.effect_id == "low_speed_friction":
            p = self.effect.params
            load += p["f0_n"] / (1.0 + v / p["v0_mps"])
        load += self.ext_load_n
        return load

    def coulomb_n(self) -> float:
        u = self.u
        return u["guide_friction_n"] + u["nip_friction_n"]

    def step(self, duty: float, driving: bool, v_bus: float, t_s: float, h: float) -> float:
        """Advance h seconds; returns the motors' battery current."""
        w = self.omega
        i_batt = 0.0
        torque = 0.0
        fric_t = 0.0
        for m in range(2):
            if driving:
                v_m = duty * v_bus
                i_inf = (v_m - self.ke[m] * w) / self.r[m]
                a = math.exp(-h * self.r[m] / self.l)
                self.i[m] = i_inf + (self.i[m] - i_inf) * a
            else:  # phases floating: the current decays through the body diodes to zero, never reverses
                self.i[m] = max(0.0, self.i[m] * math.exp(-h * self.r[m] / self.l) - 1e-3)
            torque += self.ke[m] * self.i[m]
            i_batt += duty * self.i[m] if driving else 0.0
            fric_t += self.ke[m] * (self.i0_h[m] + self.i0_e[m] * abs(w))
        # cogging (84 per revolution), the rope's loads
        v = w * self.rw
        torque += self.u["cog_nm"] * math.sin(84.0 * self.theta)
        t_load = self.rope_load_n(abs(v), t_s) * self.rw if w > 0 else self.ext_load_n * self.rw
        t_coul = fric_t + self.coulomb_n() * self.rw
        if w <= 0.0 and torque - t_load <= t_coul:
            self.omega = 0.0  # stuck
            return i_batt
        dw = (torque - t_load - t_coul) / self.j * h
        w_new = w + dw
        if w_new < 0.0:
            w_new = 0.0
        self.theta += 0.5 * (w + w_new) * h
        self.omega = w_new
        return i_batt


class _Encoder:
    """16 lines x 4 quadrature edges on motor 1's shaft; line-spacing and quadrature errors; 1 us capture."""

    def __init__(self, unit: dict, rng: np.random.Generator, boot_us: int, theta0_rad: float) -> None:
        pitch = 2.0 * math.pi / 64.0
        pos = []
        for line in range(16):
            for q in range(4):
                err = unit["encoder_line_error"][line] + (unit["encoder_quad_error"][q % 2] if q in (1, 3) else 0.0)
                pos.append((line * 4 + q + err) * pitch)
        self.edge_pos = pos
        self.pitch = pitch
        self.rng = rng
        self.jitter = unit["edge_jitter_us"]
        self.count = 0
        self.next_k = 0  # index of the next edge (absolute): the first one beyond the shaft's rest angle
        while self.edge_pos[self.next_k % 64] + (self.next_k // 64) * 2.0 * math.pi <= theta0_rad:
            self.next_k += 1
        self.last_edge_us = boot_us

    def advance(self, theta0: float, theta1: float, t0_us: float, h_us: float) -> None:
        if theta1 <= theta0:
            return
        while True:
            k = self.next_k
            pos = (k // 64) * 2.0 * math.pi + self.edge_pos[k % 64]
            if pos > theta1:
                break
            frac = (pos - theta0) / (theta1 - theta0)
            t = t0_us + max(0.0, frac) * h_us + self.rng.normal(0.0, self.jitter)
            self.last_edge_us = max(self.last_edge_us, int(math.floor(t)))
            self.count += 1
            self.next_k += 1


# --------------------------------------------------------------------------------------------------------------
# the firmware
# --------------------------------------------------------------------------------------------------------------

class _Firmware:
    """Speed loop as the device runs it: M/T estimate (edges since the last estimate over their time) with a
    first-order low-pass, setpoint ramps, battery feed-forward (updated every 10 ms), PI with conditional
    integration; the pulse at the PWM timer's 1/3 us."""

    def __init__(self, params: dict) -> None:
        self.p = params
        self.k_edge_m = 2.0 * math.pi * params["wheel_radius_m"] / params["encoder_counts_per_rev"]
        self.state = "DISARMED"
        self.target = 0.0
        self.setpoint = 0.0
        self.integ = 0.0
        self.raw = 0.0
        self.speed = 0.0
        self.last_count = None
        self.last_edge = 0
        self.batt_ff_v = 12.0
        self.pulse_third = 3000

    def estimate(self, count: int, edge_us: int, now_us: int, dt_s: float) -> None:
        if self.last_count is None:
            self.last_count, self.last_edge = count, edge_us
        elif count != self.last_count and edge_us > self.last_edge:
            self.raw = (count - self.last_count) * self.k_edge_m / ((edge_us - self.last_edge) * 1e-6)
            self.last_count, self.last_edge = count, edge_us
        elif now_us - self.last_edge > 100_000:
            self.raw = 0.0
        tau = self.p["speed_filter_tau_s"]
        self.speed += (self.raw - self.speed) * dt_s / (tau + dt_s)

    def control(self, dt_s: float) -> None:
        if self.state in ("DISARMED", "ARMED"):
            self.setpoint, self.integ = 0.0, 0.0
            self.pulse_third = 3 * 1000
            return
        goal = 0.0 if self.state == "SPINDOWN" else self.target
        up, down = self.p["ramp_up_mps2"] * dt_s, self.p["ramp_down_mps2"] * dt_s
        self.setpoint = min(self.setpoint + up, goal) if goal > self.setpoint else max(self.setpoint - down, goal)
        if self.state == "SPINDOWN" and self.setpoint <= 0.0:
            self.integ = 0.0
            self.pulse_third = 3 * 1000
            return
        v_per_throttle = self.batt_ff_v * self.p["motor_kv_rpm_per_v"] / 60.0 * 2.0 * math.pi * self.p["wheel_radius_m"]
        ff = self.setpoint / v_per_throttle
        err = self.setpoint - self.speed
        u = ff + self.p["speed_kp"] * err + self.integ
        # conditional integration: the integrator only moves when the output is not pushing against a limit
        if (u < 1.0 or err < 0.0) and (u > 0.0 or err > 0.0):
            self.integ += self.p["speed_ki"] * err * dt_s
        u = min(max(ff + self.p["speed_kp"] * err + self.integ, 0.0), 1.0)
        self.pulse_third = int(round(3.0 * (1000.0 + 1000.0 * u)))


# --------------------------------------------------------------------------------------------------------------
# the run: a compressed `wrangler excite --profile drive`
# --------------------------------------------------------------------------------------------------------------

def excite_commands(rng: np.random.Generator, duration_s: float) -> list[tuple[float, str, dict]]:
    """(host send time s from the recording's start, message, fields): ARM; burst + steps; a ramp; a high
    hold; a step down; chirps (setpoints at 50 Hz) and a ramp (20 Hz); burst + SPINDOWN; DISARM. Scaled to
    duration_s (>= 10 s)."""
    if duration_s < 10.0:
        raise ValueError(f"duration_s: expected >= 10 s, got {duration_s}")
    s = duration_s / 12.0
    v1, v2, v3 = rng.uniform(3.6, 4.6), rng.uniform(5.5, 7.0), rng.uniform(9.0, 10.5)
    v4, v5 = rng.uniform(11.5, 12.5), rng.uniform(8.0, 9.5)
    cmds: list[tuple[float, str, dict]] = [(0.2 * s, "ARM", {})]

    def burst_speed(t, v):
        cmds.append((t, "BURST_START", {"samples": 1000}))
        cmds.append((t + 0.004, "SET_ROPE_SPEED", {"rope_speed_mps": round(v, 3)}))

    def ramp(t0, dur, a, b, hz=20.0):
        n = max(1, math.ceil(dur * hz))
        for k in range(1, n + 1):
            cmds.append((t0 + k / hz, "SET_ROPE_SPEED", {"rope_speed_mps": round(a + (b - a) * k / n, 3)}))

    def chirp(t0, dur, c, amp, f0, f1, hz=50.0):
        n = max(1, math.ceil(dur * hz))
        for k in range(n + 1):
            tt = k / hz
            v = c + amp * math.sin(2.0 * math.pi * (f0 * tt + 0.5 * (f1 - f0) / dur * tt * tt))
            cmds.append((t0 + tt, "SET_ROPE_SPEED", {"rope_speed_mps": round(v, 3)}))

    burst_speed(0.45 * s, v1)
    burst_speed(1.8 * s, v2)
    ramp(3.0 * s, 0.9 * s, v2, v3)
    burst_speed(4.5 * s, v4)
    burst_speed(6.0 * s, v5)
    chirp(6.4 * s, 1.7 * s, v5, 1.5, 0.3, 4.0)
    ramp(8.1 * s, 0.8 * s, v5, 5.0)
    chirp(8.95 * s, 1.3 * s, 5.0, 1.0, 0.3, 4.0)
    cmds.append((10.45 * s, "BURST_START", {"samples": 1000}))
    cmds.append((10.455 * s, "SPINDOWN", {}))
    cmds.append((duration_s - 0.15, "DISARM", {}))
    cmds.sort(key=lambda c: c[0])
    return cmds


DEVICE_PARAMS = {"tov_mps": 2.6, "tov_margin": 1.15, "collapse_time_s": 0.3, "speed_kp": 0.04, "speed_ki": 0.4,
                 "ramp_up_mps2": 20.0, "ramp_down_mps2": 10.0, "wheel_radius_m": 0.015,
                 "encoder_counts_per_rev": 64.0, "heartbeat_timeout_s": 0.5, "max_rope_speed_mps": 20.0,
                 "motor_kv_rpm_per_v": 1250.0, "esc_min_us": 1000.0, "speed_filter_tau_s": 0.01,
                 "telemetry_rate_hz": 100.0, "arm_hold_s": 0.5, "encoder_timeout_s": 0.25}


def _schema(stem: str) -> tuple[str, bytes, dict]:
    text = (SCHEMA_DIR / f"{stem}.schema.json").read_bytes()
    schema = json.loads(text)
    version = schema["$id"].split(":")[3]
    return f"robowrangler.{stem}.v{version}", text, schema


@dataclass
class OutsideTruth:
    """What a written recording holds, for scoring (never written into the file)."""

    path: Path
    seed: int
    effect_id: str | None
    key: str | None
    truth: dict[str, float]
    spans_s: list[tuple[float, float]]
    describe: str
    unit: dict = field(repr=False, default_factory=dict)
    edge_pattern: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(64))
    """The encoder's true pattern as the recording sees it: the edge with count c lies at c + edge_pattern[c % 64]
    pitches from the edge at count 0 (zero mean)."""


def _truth_values(effect: OutsideEffect | None, unit: dict, recording_t0_s: float) -> tuple[dict, list]:
    """The effect's key parameter (and comparable ones) in the library's units; spans on the device clock."""
    if effect is None:
        return {}, []
    p = effect.params
    if effect.effect_id == "esc_latency":
        return {"delay_s": p["delay_s"]}, []
    if effect.effect_id == "esc_deadband":
        zero = unit["esc_zero_us"]
        return {"deadband_us": zero + p["duty_deadband"] * (1000.0 - zero),
                "hysteresis_us": p["duty_hysteresis"] * (1000.0 - zero)}, []
    if effect.effect_id == "battery_sag":
        return {"polarisation_resistance_ohm": p["ladder_r_ohm"]}, []
    if effect.effect_id == "low_speed_friction":
        return {"stribeck_force_n": p["f0_n"], "stribeck_speed_mps": p["v0_mps"]}, []
    if effect.effect_id == "rope_drag_law":
        return {"drag_exponent": p["exponent"]}, []
    if effect.effect_id == "external_rope_load":
        span = (recording_t0_s + p["t_start_s"], recording_t0_s + p["t_release_s"])
        return {"external_load_n": p["load_n"]}, [span]
    return {}, []


def write_outside_recording(path: str | Path, *, seed: int, effect: str | OutsideEffect | None = None,
                            duration_s: float = 12.0, loss: float = 0.003,
                            unix_start_s: float = 1_790_000_000.0, unit_overrides: dict | None = None) -> OutsideTruth:
    """Simulate one excite run of a unit drawn with this seed (effect: an id of OUTSIDE_EFFECTS in its default
    strength, an OutsideEffect, or None) and write it to path. loss: share of device frames lost on the link.
    unit_overrides: replace some of the drawn unit's constants (draw_unit's keys), to take one structural difference
    out at a time when looking for the cause of a finding."""
    path = Path(path)
    rng = np.random.default_rng([seed, 0x0C75])
    unit = draw_unit(rng)
    for name, value in (unit_overrides or {}).items():
        if name not in unit:
            raise ValueError(f"unit_overrides: unknown constant {name!r}; known: {', '.join(sorted(unit))}")
        unit[name] = value
    if isinstance(effect, str):
        effect = default_effect(effect, np.random.default_rng([seed, 0xEFF]))
    boot_ms = int(rng.integers(20_000, 900_000))       # the device booted this long before the recording
    t0_us = boot_ms * 1000
    noise_rng = np.random.default_rng([seed, 0x2015E])
    battery = _Battery(unit, effect.params if effect is not None and effect.effect_id == "battery_sag" else None)
    esc = _Esc(unit, effect)
    drive = _Drive(unit, effect)
    drive.theta = unit["shaft_angle0_rad"]  # where the shaft came to rest last time
    encoder = _Encoder(unit, noise_rng, t0_us - 500_000, drive.theta)
    err = np.array([p / encoder.pitch - i for i, p in enumerate(encoder.edge_pos)])
    edge_pattern = err[(encoder.next_k + np.arange(64) - 1) % 64]  # count c = c edges crossed: edge next_k + c - 1
    edge_pattern -= edge_pattern.mean()
    fw = _Firmware(DEVICE_PARAMS)
    fw.state = "DISARMED"
    cmds = excite_commands(rng, duration_s)
    truth, spans = _truth_values(effect, unit, t0_us * 1e-6)

    # records: (log_time_ns, publish_time_ns, topic, payload) collected, then written in log_time order
    out: list[tuple[int, int, str, dict]] = []
    unix0_ns = int(unix_start_s * 1e9)

    def host_ns(dev_us: float) -> int:
        return unix0_ns + int(round((dev_us - t0_us) * 1000.0))

    seq = int(rng.integers(0, 65536))
    events = int(rng.integers(3, 40))
    rx_ok = int(rng.integers(100, 5000))
    lost_seqs: list[tuple[int, float, float]] = []  # (seq, device time of the frame before, host ns)
    last_dev_time_s = [None]
    counters = {"rx_ok": rx_ok, "nacks": 0}

    def emit(topic: str | None, payload: dict | None, dev_us: float, extra_ns: int = 0) -> None:
        """The device sends a frame (seq numbered); it reaches the host unless the link loses it."""
        nonlocal seq
        s = seq % 65536
        seq += 1
        lost = topic is not None and noise_rng.random() < loss  # a lost ACK is retransmitted: never a gap
        if payload is not None:
            payload["seq"] = s
        if lost:
            lost_seqs.append((s, last_dev_time_s[0], host_ns(dev_us)))
            return
        if topic is not None:
            arrive = host_ns(dev_us) + extra_ns + int(noise_rng.gamma(2.0, 1.2e6))
            out.append((arrive, arrive, topic, payload))
            if "time_s" in payload:
                last_dev_time_s[0] = payload["time_s"]

    def state_event(new: str, dev_us: float, arg: int) -> None:
        nonlocal events
        old = fw.state
        fw.state = new
        events += 1
        emit("/device/event", {"time_s": (dev_us // 1000) / 1000.0, "event_seq": events % 65536,
                               "event": "STATE_CHANGED", "state_from": old, "state_to": new, "arg": arg}, dev_us)

    # command arrival at the device (host send + one-way latency), the ACK's round trip
    pending_cmds = []
    for t_send, msg, fields_ in cmds:
        one_way = float(noise_rng.gamma(2.0, 1.5e-3))
        pending_cmds.append((t0_us + (t_send + one_way) * 1e6, t_send, msg, fields_, one_way))
    cmd_i = 0
    host_seq = int(rng.integers(1, 1000))
    burst = None  # (burst_id, start_tick, start_us, samples list)
    burst_id = int(rng.integers(0, 50))
    stream_queue: list[dict] = []
    n_ticks = int(round(duration_s * 1000))
    h_s = TICK_US * 1e-6 / SUBSTEPS
    v_bus = battery.terminal_v(0.0)
    adc_v = v_bus
    i_batt = 0.0
    pwm_next_us = t0_us - PWM_PERIOD_US + unit["pwm_phase_us"]
    frame_index = 0
    register_third = 3000
    fw.batt_ff_v = v_bus
    lifted = effect is not None and effect.effect_id == "external_rope_load"
    loaded_spans = spans
    for k in range(n_ticks):
        now_us = t0_us + k * TICK_US
        t_rel = k * 1e-3
        # --- host commands that arrived since the last tick
        while cmd_i < len(pending_cmds) and pending_cmds[cmd_i][0] <= now_us:
            arrive_us, t_send, msg, fields_, one_way = pending_cmds[cmd_i]
            cmd_i += 1
            counters["rx_ok"] += 1
            if msg == "ARM" and fw.state == "DISARMED":
                state_event("ARMED", now_us, 1)
            elif msg == "SET_ROPE_SPEED":
                fw.target = fields_["rope_speed_mps"]
                if fw.state == "ARMED":
                    fw.setpoint = 0.0
                    state_event("SPINUP", now_us, 1)
            elif msg == "SPINDOWN" and fw.state in ("SPINUP", "AIRBORNE"):
                state_event("SPINDOWN", now_us, 1)
            elif msg == "DISARM" and fw.state == "ARMED":
                state_event("DISARMED", now_us, 1)
            verdict, reason, detail = "ACK", None, None
            if msg == "BURST_START":
                if burst is None and not stream_queue:
                    burst_id += 1
                    burst = (burst_id, k, now_us, [])
                else:  # the device refuses while a burst is captured or streamed
                    verdict, reason = "NACK", "BURST_BUSY"
                    detail = (1000 - len(burst[3]) if burst is not None else 0) + 6 * len(stream_queue)
                    counters["nacks"] += 1
            emit(None, None, now_us)  # the reply frame spends a device seq
            reply_s = (now_us - arrive_us) * 1e-6 + 2.0 * one_way + float(noise_rng.gamma(2.0, 0.4e-3))
            send_ns = unix0_ns + int(round(t_send * 1e9))
            out.append((send_ns, send_ns + int(reply_s * 1e9), "/host/command",
                        {"seq": host_seq % 65536, "message": msg, "fields": fields_, "transmissions": 1,
                         "verdict": verdict, "reason": reason, "state": fw.state, "detail": detail,
                         "reply_latency_s": round(reply_s, 6)}))
            host_seq += 1
        # --- the tick: read encoder and battery, estimate, control, write the pulse register
        count, edge_us = encoder.count, encoder.last_edge_us
        adc_reading = adc_v + noise_rng.normal(0.0, unit["adc_noise_v"])
        battery_mv = int(round(round(adc_reading / (16.5 / 4096.0)) * (16.5 / 4096.0) * 1000.0))
        fw.estimate(count, edge_us, now_us, 1e-3)
        if k % 10 == 0:
            fw.batt_ff_v = battery_mv / 1000.0
        fw.control(1e-3)
        register_third = fw.pulse_third
        if fw.state == "SPINUP" and fw.speed > DEVICE_PARAMS["tov_mps"]:
            state_event("AIRBORNE", now_us, 0)
        if fw.state == "SPINDOWN" and fw.setpoint <= 0.0 and fw.speed < 0.05:
            state_event("ARMED", now_us, 0)
        if burst is not None:
            burst[3].append((count % 65536, edge_us % 65536, register_third / 3.0, battery_mv / 1000.0))
            if len(burst[3]) == 1000:
                bid, btick, bus, samples = burst
                for j in range(0, 1000, 6):
                    ch = samples[j:j + 6]
                    stream_queue.append({"burst_id": bid % 65536, "start_time_s": (bus // 1000) / 1000.0,
                                         "start_time_us": bus % 2 ** 32, "tick_us": TICK_US, "sample_count": 1000,
                                         "first_sample": j, "encoder_counts": [c[0] for c in ch],
                                         "encoder_edge_us": [c[1] for c in ch],
                                         "esc_pulse_fine_us": [round(c[2], 4) for c in ch],
                                         "battery_v": [round(c[3], 3) for c in ch]})
                burst = None
        # --- telemetry at 100 Hz; else one burst frame into an idle outbox
        if k % 10 == 0:
            pulse_us = register_third / 3.0
            tel = {"time_s": (now_us // 1000) / 1000.0, "state": fw.state, "fault_bits": [],
                   "rope_speed_target_mps": round(fw.target if fw.state != "ARMED" else 0.0, 3),
                   "rope_speed_setpoint_mps": round(fw.setpoint, 3), "rope_speed_mps": round(max(fw.speed, 0.0), 3),
                   "motor_rpm": int(round(max(fw.speed, 0.0) / (2 * math.pi * 0.015) * 60.0)),
                   "esc_pulse_us": int(round(pulse_us)), "battery_v": battery_mv / 1000.0,
                   "heartbeat_age_s": round(float(noise_rng.uniform(0.0, 0.1)), 3),
                   "rx_ok": counters["rx_ok"] % 65536, "rx_bad": 0, "rx_duplicates": 0,
                   "nacks": counters["nacks"] % 65536,
                   "events": events % 65536, "tick_overruns": 0, "guide_position_m": 0.0412,
                   "guide_target_m": 0.0412, "spindle_load_permille": int(noise_rng.integers(-8, 9)),
                   "spindle_flags": ["HOMED", "ANSWERING"], "spindle_rejected": 0, "rx_auth_failed": 0,
                   "rx_replayed": 0, "tx_dropped": 0, "esc_pulse_fine_us": round(pulse_us, 4),
                   "spindle_moving_speed_raw": 0, "encoder_counts": count % 2 ** 32,
                   "encoder_edge_us": edge_us % 2 ** 32}
            emit("/device/telemetry", tel, now_us)
        elif stream_queue:
            emit("/device/burst", stream_queue.pop(0), now_us)
        # --- the plant between this tick and the next: PWM frames, ESC, motors, battery, encoder
        for sub in range(SUBSTEPS):
            ts_us = now_us + sub * TICK_US / SUBSTEPS
            while pwm_next_us <= ts_us:
                esc.frame(pwm_next_us * 1e-6, register_third / 3.0, frame_index)
                frame_index += 1
                pwm_next_us += PWM_PERIOD_US
            t_s = ts_us * 1e-6
            if lifted:
                p = effect.params
                tr = t_rel + sub * 1e-3 / SUBSTEPS
                ramp = min(max((tr - p["t_start_s"]) / p["rise_s"], 0.0), 1.0)
                drive.ext_load_n = p["load_n"] * ramp if tr < p["t_release_s"] else 0.0
            duty, driving = esc.duty(t_s)
            theta0 = drive.theta
            i_m = drive.step(duty, driving, v_bus, t_s, h_s)
            encoder.advance(theta0, drive.theta, ts_us, TICK_US / SUBSTEPS)
            i_batt = i_m + unit["aux_current_a"]
            battery.step(i_batt, h_s)
            v_bus = battery.terminal_v(i_batt)
            adc_v += (v_bus - adc_v) * (1.0 - math.exp(-h_s / unit["adc_tau_s"]))
    _write(path, out, lost_seqs, seed, host_ns(t0_us + n_ticks * TICK_US),
           effect.describe if effect is not None else "none")
    return OutsideTruth(path=path, seed=seed, effect_id=effect.effect_id if effect else None,
                        key=effect.key if effect else None, truth=truth, spans_s=loaded_spans,
                        describe=effect.describe if effect else "effect-free", unit=unit, edge_pattern=edge_pattern)


def _write(path: Path, out: list, lost: list, seed: int, end_ns: int, describe: str) -> None:
    tele_name, _, tele_schema = _schema("device_telemetry")
    schema_hash = tele_schema["$comment"].split("hash ")[1].rstrip(".")
    # the link gaps a recorder writes for the lost frames: consecutive lost seqs are one gap
    gaps = []
    for s, last_t, ns in lost:
        if gaps and (gaps[-1]["to_seq"] + 1) % 65536 == s:
            gaps[-1]["to_seq"] = s
            gaps[-1]["missing"] += 1
            continue
        gaps.append({"stream": "device", "from_seq": s, "to_seq": s, "missing": 1, "last_time_s": last_t,
                     "resume_time_s": None, "silent_s": 0.02, "_ns": ns + 650_000_000})  # held for 64 frames
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD, chunk_size=256 * 1024)
        w.start(profile="", library="outside-drive-sim 0.1")
        w.add_metadata("/meta", {"format": "robowrangler.recording", "format_version": "1", "source": "other",
                                 "schema_hash": schema_hash, "units": "si-suffixed/1", "time_base": "unix",
                                 "seed": str(seed), "writer": "outside-drive-sim 0.1 (bench/outside_writer.py)",
                                 "description": f"independent drive simulator, excite-like run; {describe}"})
        w.add_metadata("/device/params", {k: repr(float(v)) for k, v in DEVICE_PARAMS.items()})
        channels = {}
        for topic, stem in (("/device/telemetry", "device_telemetry"), ("/device/event", "device_event"),
                            ("/device/burst", "device_burst"), ("/host/command", "host_command"),
                            ("/link/gap", "link_gap")):
            name, text, _ = _schema(stem)
            sid = w.register_schema(name=name, encoding="jsonschema", data=text)
            channels[topic] = w.register_channel(topic=topic, message_encoding="json", schema_id=sid)
        for g in gaps:
            ns = g.pop("_ns")
            out.append((min(ns, end_ns), min(ns, end_ns), "/link/gap", g))
        out.sort(key=lambda r: r[0])
        timed = [(r[0], r[3]["time_s"]) for r in out if r[2] in ("/device/telemetry", "/device/event")]
        for r in out:
            if r[2] == "/link/gap":  # the device time of the first frame received after the gap
                detect = r[0] - 650_000_000
                r[3]["resume_time_s"] = next((ts for ns, ts in timed if ns > detect), None)
        last_flush = out[0][0] if out else 0
        for log_ns, pub_ns, topic, payload in out:
            w.add_message(channels[topic], log_time=log_ns, publish_time=max(pub_ns, log_ns),
                          data=json.dumps(payload, separators=(",", ":")).encode())
            if log_ns - last_flush > 400_000_000:  # a chunk at least every 0.4 s
                w.flush()
                last_flush = log_ns
        w.finish()


if __name__ == "__main__":  # a quick look: write one and print what it is
    import argparse
    import time as _time

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--effect", choices=OUTSIDE_EFFECTS)
    args = ap.parse_args()
    t = _time.perf_counter()
    tr = write_outside_recording(args.out, seed=args.seed, effect=args.effect)
    print(f"{tr.path}: {tr.describe}; truth {tr.truth}; {_time.perf_counter() - t:.1f} s")
