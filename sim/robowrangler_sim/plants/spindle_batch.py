"""Fast form of the spindle plant: one Numba kernel steps a batch of parameter sets over a whole command record.

The physics is spindle.py's (wheel-mode drive fraction from the moving-speed register, linear torque-speed line
with a first-order speed response, screw friction, hard end stops, 1 ms substeps) including the two terms a
diagnosed model may switch on, each neutral (0) by default:

    servo dead band   |register| <= d does not drive; once stopped, the servo drives again only above d + h
    screw backlash    a gap of b mm between the servo output (where the position is read) and the nut: inside
                      it the servo turns without the screw's friction (its load reads ~0)

What it leaves out: the rope's pull on the guide (a recording carries no guide force; the kernel assumes none)
and the position register's dead zone (the firmware bridges it; the recorded guide position is its estimate).

Parameters are rows of ``theta`` (shape (B, N_SPINDLE_THETA)), columns ``SP_*``; ``theta_from_spindle_params``
fills a row from SpindleParams. Shapes: moving_speed_raw (T,) the register in force during each 1 ms tick;
sample_ticks (S,) tick indices to report (the state at the start of that tick, what the firmware reads).
Outputs (B, S): guide_position_mm (servo side, from home), load_permille (torque / stall torque x 1000, signed).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from robowrangler_sim.plants.spindle import SpindleParams

TICK_S = 1e-3

SP_STALL_NM = 0  # stall torque, N m
SP_NO_LOAD_RPM = 1  # no-load speed, rpm
SP_RESPONSE_S = 2  # speed time constant, s
SP_FRICTION_NM = 3  # screw + guide friction at the servo output, N m
SP_DEADBAND_RAW = 4  # servo dead band, register units
SP_HYST_RAW = 5  # dead-band hysteresis, register units
SP_BACKLASH_MM = 6  # lead-screw backlash, mm of guide travel
N_SPINDLE_THETA = 7


def theta_from_spindle_params(p: SpindleParams) -> np.ndarray:
    th = np.zeros(N_SPINDLE_THETA)
    th[SP_STALL_NM] = p.stall_torque_nm
    th[SP_NO_LOAD_RPM] = p.no_load_speed_rpm
    th[SP_RESPONSE_S] = p.response_time_s
    th[SP_FRICTION_NM] = p.friction_torque_nm
    th[SP_DEADBAND_RAW] = p.servo_deadband_raw
    th[SP_HYST_RAW] = p.servo_deadband_hysteresis_raw
    th[SP_BACKLASH_MM] = p.screw_backlash_mm
    return th


@numba.njit(cache=True)
def _kernel(theta, raw, sample_ticks, pos0_mm, play_start, lead_mm_per_rev, lo_mm, hi_mm, out_pos, out_load):
    n_b = theta.shape[0]
    n_t = raw.size
    n_s = sample_ticks.size
    mm_per_rad = lead_mm_per_rev / (2.0 * math.pi)
    h = 1e-3
    for b in range(n_b):
        ts = theta[b, 0]
        w0 = theta[b, 1] * 2.0 * math.pi / 60.0
        alpha = 1.0 - math.exp(-h / theta[b, 2])
        fr = theta[b, 3]
        dead = theta[b, 4]
        hyst = theta[b, 5]
        gap = theta[b, 6]
        pos = pos0_mm
        w = 0.0
        on = False
        torque = 0.0
        play = gap * play_start
        si = 0
        for k in range(n_t):
            while si < n_s and sample_ticks[si] == k:
                out_pos[b, si] = pos
                out_load[b, si] = torque / ts * 1000.0
                si += 1
            r = raw[k]
            m = r & 0x3FF
            if on:
                if m <= dead:
                    on = False
            elif m > dead + hyst:
                on = True
            u = 0.0
            if on:
                u = m / 1023.0
                if r & 0x400:
                    u = -u
            eng = 1.0
            if gap > 0.0:
                if u > 0.0 and play < gap - 1e-9:
                    eng = 0.0
                elif u < 0.0 and play > 1e-9:
                    eng = 0.0
            weq = 0.0
            if u > 0.0:
                weq = max(w0 * (u - eng * fr / ts), 0.0)
            elif u < 0.0:
                weq = min(w0 * (u + eng * fr / ts), 0.0)
            w += (weq - w) * alpha
            dx = w * h * mm_per_rad
            pos += dx
            if pos < lo_mm:
                pos = lo_mm
                w = 0.0
            elif pos > hi_mm:
                pos = hi_mm
                w = 0.0
            if gap > 0.0:
                play = min(max(play + dx, 0.0), gap)
            torque = ts * (u - w / w0) if u != 0.0 else 0.0
        while si < n_s:
            out_pos[b, si] = pos
            out_load[b, si] = torque / ts * 1000.0
            si += 1


def first_direction(moving_speed_raw: np.ndarray) -> float:
    """Where the backlash gap starts: 1.0 (closed on the retract side) when the first drive retracts, else 0.0
    (the first move takes the nut along at once, as an unknown start state is best assumed)."""
    raw = np.asarray(moving_speed_raw, dtype=np.int64)
    moving = raw[(raw & 0x3FF) > 0]
    if moving.size == 0:
        return 0.0
    return 0.0 if moving[0] & 0x400 else 1.0


def simulate_spindle_batch(theta: np.ndarray, moving_speed_raw: np.ndarray, sample_ticks: np.ndarray, *,
                           start_position_mm: float, params: SpindleParams | None = None,
                           play_start: float | None = None) -> dict[str, np.ndarray]:
    """Step B parameter rows over the command record; see the module docstring for shapes.

    params: the fixed constants (lead, stroke, end-stop margin); None: SpindleParams().
    play_start: the backlash gap's start as a fraction of it (0: closed on the extend side; None: first_direction).
    Raises ValueError naming the argument on bad shapes or values."""
    theta = np.ascontiguousarray(np.atleast_2d(theta), dtype=np.float64)
    if theta.shape[1] != N_SPINDLE_THETA:
        raise ValueError(f"theta: expected shape (B, {N_SPINDLE_THETA}), got {theta.shape}")
    if np.any(theta[:, [SP_STALL_NM, SP_NO_LOAD_RPM, SP_RESPONSE_S]] <= 0):
        raise ValueError("theta: stall torque, no-load speed and response time must be > 0")
    raw = np.ascontiguousarray(moving_speed_raw, dtype=np.int64)
    if raw.ndim != 1 or np.any((raw < 0) | (raw > 0x7FF)):
        raise ValueError("moving_speed_raw: expected a 1-D array of register values 0..2047")
    ticks = np.ascontiguousarray(sample_ticks, dtype=np.int64)
    if ticks.ndim != 1 or np.any(np.diff(ticks) < 0) or (ticks.size and (ticks[0] < 0 or ticks[-1] > raw.size)):
        raise ValueError(f"sample_ticks: expected non-decreasing tick indices in [0, {raw.size}]")
    p = params or SpindleParams()
    out_pos = np.empty((theta.shape[0], ticks.size))
    out_load = np.empty((theta.shape[0], ticks.size))
    play0 = first_direction(raw) if play_start is None else float(play_start)
    _kernel(theta, raw, ticks, float(start_position_mm), play0, p.lead_mm_per_rev,
            -p.end_stop_margin_mm, p.stroke_mm + p.end_stop_margin_mm, out_pos, out_load)
    return {"guide_position_mm": out_pos, "load_permille": out_load}
