"""Fast form of the drive plant: one Numba kernel steps a batch of parameter sets over a whole pulse record.

The physics is drive.py's (same ESC frame latching, duty lag, arming, current law with clamp and damped
light, Coulomb stick, exponential substep, battery sag), on a fixed 250 us substep grid (the plant's own
substeps: every segment the plant integrates between ticks and ESC frames is a multiple of 250 us), plus
the diagnose library's effect terms, each neutral by default:

    rope drag        F = k v_ref^2 (|v| / v_ref)^n          (n = 2: the plant's k v |v|; v_ref = 4 m/s)
    ESC latency      the ESC sees the pulse of d seconds ago
    ESC dead band    zero throttle below min + w; once off, on again only above min + w + h (hysteresis)
    battery sag      polarisation V_p' = (R_p I_batt - V_p) / tau_p subtracted from the source
    low-speed fric.  F_s exp(-(v / v_s)^2) added to the Coulomb force (Stribeck)
    external load    F_ext x mask(t) added to the Coulomb force (the mask: a window t0..t1 with logistic
                     edges when theta gives one, else load_mask)

Parameters are rows of ``theta`` (shape (B, N_THETA)), columns named by the ``TH_*`` indices; the
``theta_from_params`` helper fills a row from DriveParams. ``latch="exact"`` latches the pulse at the
ESC's frame times exactly as DrivePlant does (for the equivalence test); ``latch="box"`` latches the
mean pulse over the frame centred on the latch time, which stands for a frame clock of unknown phase (a
change reaches the motor half a frame later on average, as with a uniform phase) and makes the delay a
smooth parameter (what the fit uses).

Shapes: pulse_us (T,) per 1 ms tick (the pulse the firmware drove during tick k); load_mask (T,);
sample_ticks (S,) tick indices to report (the state at the start of that tick, what the firmware's
sensors see). Outputs (B, S): true rope speed m/s, measured rope speed m/s (first-order low-pass of the
true speed, the firmware's M/T estimate and filter), battery terminal voltage V.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from robowrangler_sim.plants.drive_params import DriveParams

SUBSTEP_US = 250
TICK_US = 1000
V_REF_MPS = 4.0

# theta columns
TH_KT = 0  # torque constant, N m/A
TH_R_CIRCUIT = 1  # winding + ESC resistance per motor, Ohm
TH_COULOMB_N = 2  # all Coulomb friction referred to the rope, N
TH_VISCOUS_N_S_PER_M = 3  # all viscous friction referred to the rope, N s/m
TH_INERTIA = 4  # total inertia on one wheel shaft, kg m^2
TH_DRAG_K = 5  # k in F = k v |v|, N s^2/m^2
TH_BATT_R = 6  # battery internal resistance, Ohm
TH_BATT_OCV = 7  # open-circuit voltage at start, V
TH_ESC_LAG = 8  # duty lag, s
TH_DEADBAND = 9  # ESC dead band above min pulse, us
TH_DRAG_EXP = 10  # drag speed exponent (2 = nominal)
TH_LATENCY = 11  # ESC input delay, s
TH_HYST = 12  # dead-band hysteresis, us
TH_POL_R = 13  # polarisation resistance, Ohm
TH_POL_TAU = 14  # polarisation time constant, s
TH_STRIBECK_N = 15  # Stribeck excess friction at rest, N
TH_STRIBECK_V = 16  # Stribeck speed, m/s
TH_EXT_LOAD = 17  # external rope load over the mask, N
TH_EXT_T0 = 18  # external load window start (replay grid time), s; used when TH_EXT_T1 > TH_EXT_T0
TH_EXT_T1 = 19  # external load window end, s (else the load follows load_mask)
N_THETA = 20
EXT_EDGE_S = 0.03  # the window's logistic edge width, s (smooth in t0, t1 for the fit)

# consts
C_N = 0
C_R_WHEEL = 1
C_RB_AUX = 2  # aux current A
C_OCV_SLOPE = 3
C_OCV_EMPTY = 4
C_I_LIM = 5
C_DAMPED = 6
C_MAX_DUTY = 7
C_MIN_PULSE = 8
C_MAX_PULSE = 9
C_INVALID = 10
C_ARM_HOLD_US = 11
C_FRAME_US = 12
C_MEAS_TAU = 13
N_CONSTS = 14


def theta_from_params(params: DriveParams) -> np.ndarray:
    """The row of theta (N_THETA,) that reproduces DrivePlant(params) with every effect neutral."""
    p = params
    th = np.zeros(N_THETA)
    r = p.wheel_radius_m
    th[TH_KT] = p.torque_constant_nm_per_a
    th[TH_R_CIRCUIT] = p.circuit_resistance_ohm
    th[TH_COULOMB_N] = p.motor_count * p.motor_coulomb_friction_nm / r + p.guide_friction_n + p.nip_friction_n
    th[TH_VISCOUS_N_S_PER_M] = p.motor_count * p.motor_viscous_friction_nm_s_per_rad / (r * r) + p.nip_viscous_n_s_per_m
    th[TH_INERTIA] = p.total_inertia_kg_m2
    th[TH_DRAG_K] = p.rope_drag_coeff_n_s2_per_m2
    th[TH_BATT_R] = p.battery_internal_resistance_ohm
    th[TH_BATT_OCV] = p.battery_open_circuit_v
    th[TH_ESC_LAG] = p.esc_lag_s
    th[TH_DEADBAND] = p.esc_deadband_us
    th[TH_DRAG_EXP] = 2.0
    th[TH_POL_TAU] = 1.0
    th[TH_STRIBECK_V] = 0.5
    return th


def consts_from_params(params: DriveParams, *, meas_tau_s: float = 0.0) -> np.ndarray:
    """The fixed constants (geometry, ESC protocol, battery curve) the kernel needs, shape (N_CONSTS,)."""
    p = params
    if p.esc_frame_us % SUBSTEP_US or round(p.max_substep_s * 1e6) < SUBSTEP_US:
        raise ValueError(f"params: expected esc_frame_us a multiple of {SUBSTEP_US} us and max_substep_s >= "
                         f"{SUBSTEP_US} us, got {p.esc_frame_us} us and {p.max_substep_s} s")
    c = np.zeros(N_CONSTS)
    c[C_N] = p.motor_count
    c[C_R_WHEEL] = p.wheel_radius_m
    c[C_RB_AUX] = p.battery_aux_current_a
    c[C_OCV_SLOPE] = p.battery_ocv_slope_v_per_ah
    c[C_OCV_EMPTY] = p.battery_empty_v
    c[C_I_LIM] = p.esc_current_limit_a
    c[C_DAMPED] = 1.0 if p.esc_damped_light else 0.0
    c[C_MAX_DUTY] = p.esc_max_duty
    c[C_MIN_PULSE] = p.esc_min_pulse_us
    c[C_MAX_PULSE] = p.esc_max_pulse_us
    c[C_INVALID] = p.esc_invalid_below_us
    c[C_ARM_HOLD_US] = p.esc_arm_hold_us
    c[C_FRAME_US] = p.esc_frame_us
    c[C_MEAS_TAU] = meas_tau_s
    return c


@numba.njit(cache=True)
def _pulse_at(pulse_us, t_us):
    """Pulse applied at plant time t_us (ZOH over 1 ms ticks; before 0: the first tick's pulse is not known
    -> 0, no signal)."""
    if t_us < 0.0:
        return 0.0
    k = int(t_us // TICK_US)
    if k >= pulse_us.shape[0]:
        k = pulse_us.shape[0] - 1
    return pulse_us[k]


@numba.njit(cache=True)
def _cum_at(cum, t_us):
    """Integral of the pulse from 0 to t_us (us x us), cum[k] = integral to k ticks; linear inside a tick."""
    if t_us <= 0.0:
        return 0.0
    x = t_us / TICK_US
    k = int(x)
    n = cum.shape[0] - 1
    if k >= n:
        return cum[n] + (cum[n] - cum[n - 1]) * (x - n)
    return cum[k] + (cum[k + 1] - cum[k]) * (x - k)


@numba.njit(cache=True)
def _gated(theta, gate_off, gate_cols, bi, col, gate_on):
    """Column col of row bi, or gate_off's value where the gate is off and col is a gated column."""
    if gate_on or gate_cols[col] < 0.5:
        return theta[bi, col]
    return gate_off[col]


@numba.njit(cache=True, parallel=True)
def _simulate(theta, consts, pulse_us, cum, load_mask, gate_mask, gate_off, gate_cols, sample_ticks, box, out_v,
              out_meas, out_vb):
    n_b = theta.shape[0]
    n_ticks = pulse_us.shape[0]
    n_s = sample_ticks.shape[0]
    h_us = float(SUBSTEP_US)
    h = h_us * 1e-6
    sub_per_tick = TICK_US // SUBSTEP_US
    n_mot = consts[C_N]
    r = consts[C_R_WHEEL]
    aux_a = consts[C_RB_AUX]
    slope = consts[C_OCV_SLOPE]
    empty_v = consts[C_OCV_EMPTY]
    i_lim = consts[C_I_LIM]
    damped = consts[C_DAMPED] > 0.5
    max_duty = consts[C_MAX_DUTY]
    p_min = consts[C_MIN_PULSE]
    p_max = consts[C_MAX_PULSE]
    p_invalid = consts[C_INVALID]
    arm_hold = consts[C_ARM_HOLD_US]
    frame_us = consts[C_FRAME_US]
    sub_per_frame = int(frame_us // SUBSTEP_US)
    meas_tau = consts[C_MEAS_TAU]
    meas_decay = math.exp(-h / meas_tau) if meas_tau > 0.0 else 0.0
    for bi in numba.prange(n_b):  # rows are independent: one thread each (NUMBA_NUM_THREADS)
        kt = theta[bi, TH_KT]
        r_circ = theta[bi, TH_R_CIRCUIT]
        coul_n = theta[bi, TH_COULOMB_N]
        visc = theta[bi, TH_VISCOUS_N_S_PER_M]
        j = theta[bi, TH_INERTIA]
        k_drag = theta[bi, TH_DRAG_K]
        rb = theta[bi, TH_BATT_R]
        ocv0 = theta[bi, TH_BATT_OCV]
        lag = theta[bi, TH_ESC_LAG]
        ext_t0 = theta[bi, TH_EXT_T0]
        ext_t1 = theta[bi, TH_EXT_T1]
        windowed = ext_t1 > ext_t0
        ext_w = 0.0
        lag_decay = math.exp(-h / lag) if lag > 0.0 else 0.0
        lag_mean = (1.0 - lag_decay) * lag / h if lag > 0.0 else 1.0
        n_kt = n_mot * kt
        # the effect terms, (re)read at the first tick and at every change of the gate: where gate_mask is 0, the
        # gated columns take gate_off's values (an effect acting in one regime only)
        gate_on = not (gate_mask[0] > 0.5)
        dead = hyst = n_exp = k_drag = delay_us = pol_r = pol_tau = strib_n = strib_v = ext_n = 0.0
        zero_top = span = pol_decay = drag_scale = 0.0
        # state
        omega = 0.0
        duty = 0.0
        throttle = 0.0
        bridge_on = False
        armed = False
        arm_us = 0.0
        db_off = True  # dead band with hysteresis: currently in the zero zone
        charge_ah = 0.0
        v_pol = 0.0
        meas = 0.0
        v_batt = ocv0 - rb * aux_a
        i_batt_motors = 0.0
        si = 0
        n_sub = n_ticks * sub_per_tick
        for s in range(n_sub + 1):
            tick = s // sub_per_tick
            if s % sub_per_tick == 0:
                while si < n_s and sample_ticks[si] == tick:
                    out_v[bi, si] = r * omega
                    out_meas[bi, si] = meas
                    out_vb[bi, si] = v_batt
                    si += 1
            if s == n_sub:
                break
            if s % sub_per_tick == 0 and (gate_mask[tick] > 0.5) != gate_on:  # first tick: always
                gate_on = not gate_on
                dead = _gated(theta, gate_off, gate_cols, bi, TH_DEADBAND, gate_on)
                hyst = _gated(theta, gate_off, gate_cols, bi, TH_HYST, gate_on)
                n_exp = _gated(theta, gate_off, gate_cols, bi, TH_DRAG_EXP, gate_on)
                k_drag = _gated(theta, gate_off, gate_cols, bi, TH_DRAG_K, gate_on)
                delay_us = _gated(theta, gate_off, gate_cols, bi, TH_LATENCY, gate_on) * 1e6
                pol_r = _gated(theta, gate_off, gate_cols, bi, TH_POL_R, gate_on)
                pol_tau = _gated(theta, gate_off, gate_cols, bi, TH_POL_TAU, gate_on)
                strib_n = _gated(theta, gate_off, gate_cols, bi, TH_STRIBECK_N, gate_on)
                strib_v = _gated(theta, gate_off, gate_cols, bi, TH_STRIBECK_V, gate_on)
                ext_n = _gated(theta, gate_off, gate_cols, bi, TH_EXT_LOAD, gate_on)
                zero_top = p_min + dead
                span = p_max - zero_top
                pol_decay = math.exp(-h / pol_tau) if pol_tau > 0.0 else 0.0
                drag_scale = k_drag * V_REF_MPS * V_REF_MPS
            t_us = s * h_us
            ocv = ocv0 - slope * charge_ah
            if ocv < empty_v:
                ocv = empty_v
            v_src = ocv - rb * aux_a - v_pol
            if s % sub_per_frame == 0:
                # ESC frame: latch the pulse (exact, or the frame-mean for an unknown frame phase)
                p_now = _pulse_at(pulse_us, t_us - delay_us)
                if box:
                    # the mean over a frame centred on the latch: with the hold to the next frame, a change
                    # reaches the motor half a frame later on average, as with a frame phase unknown (uniform)
                    p_lat = (_cum_at(cum, t_us - delay_us + 0.5 * frame_us)
                             - _cum_at(cum, t_us - delay_us - 0.5 * frame_us)) / frame_us
                    if p_now < p_invalid:
                        p_lat = p_now
                else:
                    p_lat = p_now
                if p_lat < p_invalid:
                    armed = False
                    bridge_on = False
                    throttle = 0.0
                    duty = 0.0
                    arm_us = 0.0
                else:
                    if db_off:
                        on_level = zero_top + hyst
                        if p_lat > on_level:
                            db_off = False
                    else:
                        if p_lat <= zero_top:
                            db_off = True
                    if db_off:
                        thr = 0.0
                    elif p_lat >= p_max:
                        thr = 1.0
                    else:
                        thr = (p_lat - zero_top) / span
                        if thr < 0.0:
                            thr = 0.0
                    if not armed:
                        if thr == 0.0:
                            if arm_us >= arm_hold:
                                armed = True
                            else:
                                arm_us += frame_us
                        else:
                            arm_us = 0.0
                    else:
                        throttle = thr
                        if thr == 0.0:
                            bridge_on = False
                            duty = 0.0
                        elif not bridge_on:
                            bridge_on = True
                            bemf = kt * omega / v_src if v_src > 0.0 else 0.0
                            if bemf < 0.0:
                                bemf = 0.0
                            duty = min(thr * max_duty, bemf)
            # duty lag (mean over the substep)
            if bridge_on:
                target = throttle * max_duty
                if lag > 0.0:
                    d_mean = target + (duty - target) * lag_mean
                    duty = target + (duty - target) * lag_decay
                else:
                    duty = target
                    d_mean = target
            else:
                d_mean = 0.0
            # current law i = a - b omega
            a = 0.0
            b = 0.0
            if d_mean > 0.0:
                r_eff = r_circ + n_mot * d_mean * d_mean * rb
                a = d_mean * v_src / r_eff
                b = kt / r_eff
                i0 = a - b * omega
                if i0 > i_lim:
                    a = i_lim
                    b = 0.0
                elif i0 < 0.0:
                    if not damped:
                        a = 0.0
                        b = 0.0
                    elif i0 < -i_lim:
                        a = -i_lim
                        b = 0.0
            v0 = r * omega
            abs_v0 = abs(v0)
            if windowed:
                if s % sub_per_tick == 0 and ext_n != 0.0:
                    tt = tick * 1e-3
                    a0 = (tt - ext_t0) / EXT_EDGE_S
                    a1 = (ext_t1 - tt) / EXT_EDGE_S
                    ext_w = 0.0 if (a0 < -30.0 or a1 < -30.0) else 1.0 / ((1.0 + math.exp(-a0)) * (1.0 + math.exp(-a1)))
                static_n = coul_n + ext_n * ext_w
            else:
                static_n = coul_n + ext_n * load_mask[tick]
            if strib_n > 0.0:
                static_n += strib_n * math.exp(-(abs_v0 / strib_v) ** 2)
            static_nm = r * static_n
            stuck = False
            if omega == 0.0:
                drive_nm = n_kt * a
                if abs(drive_nm) <= static_nm:
                    stuck = True
                    sign = 0.0
                else:
                    sign = 1.0 if drive_nm > 0.0 else -1.0
            else:
                sign = 1.0 if omega > 0.0 else -1.0
            if stuck:
                i1 = a
            else:
                # drag F = k v_ref^2 (|v|/v_ref)^n, linearised about v0 (Newton), as the plant does for n = 2
                if abs_v0 > 0.0:
                    q = abs_v0 / V_REF_MPS
                    # the square law (every row but a drag law's) without the general power's exp and log
                    f_drag = drag_scale * (q * q if n_exp == 2.0 else q ** n_exp)
                    df_dv = n_exp * f_drag / abs_v0
                else:
                    f_drag = 0.0
                    df_dv = 0.0
                # signed: drag opposes motion; linearisation F(v) ~ F0 + dF (v - v0) along sign
                pp = n_kt * a - sign * static_nm - sign * r * (f_drag - df_dv * abs_v0)
                qq = n_kt * b + r * r * visc + r * r * df_dv
                tau = j / qq
                omega_inf = pp / qq
                decay = math.exp(-h / tau)
                omega1 = omega_inf + (omega - omega_inf) * decay
                if omega1 * sign < 0.0:
                    omega1 = 0.0
                omega = omega1
                i1 = a - b * omega
            # battery
            if i1 == 0.0:
                v_batt = v_src
                i_bm = 0.0
            else:
                power = n_mot * i1 * (kt * omega + r_circ * i1)
                disc = v_src * v_src - 4.0 * rb * power
                if disc < 0.0:
                    v_batt = 0.5 * v_src
                else:
                    v_batt = 0.5 * (v_src + math.sqrt(disc))
                i_bm = power / v_batt
            i_batt_motors = i_bm
            charge_ah += (i_bm + aux_a) * h / 3600.0
            if pol_r > 0.0:
                i_tot = i_bm + aux_a
                v_pol = pol_r * i_tot + (v_pol - pol_r * i_tot) * pol_decay
            if meas_tau > 0.0:
                meas = abs(r * omega) + (meas - abs(r * omega)) * meas_decay
            else:
                meas = abs(r * omega)
        while si < n_s:
            out_v[bi, si] = r * omega
            out_meas[bi, si] = meas
            out_vb[bi, si] = v_batt
            si += 1
        _ = i_batt_motors


@dataclass(frozen=True)
class TickGate:
    """An effect confined to one regime: on the ticks where ``mask_on`` is False, the theta ``columns`` take the
    values of ``off_row`` (the model without the effect there) instead of the batch row's own.

    mask_on: (T,) bool per tick; columns: theta column indices of the gated effect; off_row: (N_THETA,).
    """

    mask_on: np.ndarray
    columns: tuple[int, ...]
    off_row: np.ndarray

    def arrays(self, n_ticks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        m = np.asarray(self.mask_on)
        off = np.asarray(self.off_row, dtype=np.float64)
        if m.shape != (n_ticks,):
            raise ValueError(f"gate.mask_on: expected shape ({n_ticks},), got {m.shape}")
        if off.shape != (N_THETA,):
            raise ValueError(f"gate.off_row: expected shape ({N_THETA},), got {off.shape}")
        cols = np.zeros(N_THETA)
        for c in self.columns:
            if not 0 <= c < N_THETA:
                raise ValueError(f"gate.columns: expected theta columns in [0, {N_THETA}), got {c}")
            cols[c] = 1.0
        return np.ascontiguousarray(m, dtype=np.float64), np.ascontiguousarray(off), cols


def simulate_drive_batch(theta: np.ndarray, consts: np.ndarray, pulse_us: np.ndarray, sample_ticks: np.ndarray, *,
                         load_mask: np.ndarray | None = None, gate: TickGate | None = None,
                         latch: str = "box") -> dict[str, np.ndarray]:
    """Simulate B parameter sets over one pulse record.

    Args:
        theta: (B, N_THETA) or (N_THETA,) parameter rows (see TH_*).
        consts: (N_CONSTS,) from consts_from_params.
        pulse_us: (T,) ESC pulse per 1 ms tick, us (0 = no signal).
        sample_ticks: (S,) non-decreasing tick indices in [0, T] to report.
        load_mask: (T,) weight of the external-load term per tick (None: zeros).
        gate: an effect acting in one regime only (TickGate): its columns take the gate's off values on the
            ticks outside the regime (None: every effect everywhere).
        latch: "exact" (DrivePlant's frame latching) or "box" (frame-mean latching; smooth in the delay).
    Returns: dict of (B, S) arrays rope_speed_mps, measured_speed_mps, battery_v.
    Raises ValueError naming the argument for wrong shapes or values.
    """
    theta = np.atleast_2d(np.asarray(theta, dtype=np.float64))
    if theta.shape[1] != N_THETA:
        raise ValueError(f"theta: expected shape (B, {N_THETA}), got {theta.shape}")
    consts = np.asarray(consts, dtype=np.float64)
    if consts.shape != (N_CONSTS,):
        raise ValueError(f"consts: expected shape ({N_CONSTS},), got {consts.shape}")
    pulse_us = np.ascontiguousarray(pulse_us, dtype=np.float64)
    if pulse_us.ndim != 1 or pulse_us.size < 2 or not np.all(np.isfinite(pulse_us)):
        raise ValueError(f"pulse_us: expected a finite 1-D array of >= 2 ticks, got shape {pulse_us.shape}")
    ticks = np.ascontiguousarray(sample_ticks, dtype=np.int64)
    if ticks.ndim != 1 or (ticks.size and (ticks[0] < 0 or ticks[-1] > pulse_us.size or np.any(np.diff(ticks) < 0))):
        raise ValueError(f"sample_ticks: expected non-decreasing tick indices in [0, {pulse_us.size}]")
    if load_mask is None:
        load_mask = np.zeros(pulse_us.size)
    load_mask = np.ascontiguousarray(load_mask, dtype=np.float64)
    if load_mask.shape != pulse_us.shape:
        raise ValueError(f"load_mask: expected shape {pulse_us.shape}, got {load_mask.shape}")
    if gate is None:
        gate_mask, gate_off, gate_cols = np.ones(pulse_us.size), np.zeros(N_THETA), np.zeros(N_THETA)
    else:
        gate_mask, gate_off, gate_cols = gate.arrays(pulse_us.size)
    if latch not in ("exact", "box"):
        raise ValueError(f"latch: expected 'exact' or 'box', got {latch!r}")
    cum = np.concatenate(([0.0], np.cumsum(pulse_us * TICK_US)))
    n_b, n_s = theta.shape[0], ticks.size
    out_v = np.empty((n_b, n_s))
    out_m = np.empty((n_b, n_s))
    out_vb = np.empty((n_b, n_s))
    _simulate(theta, consts, pulse_us, cum, load_mask, gate_mask, gate_off, gate_cols, ticks, latch == "box", out_v,
              out_m, out_vb)
    return {"rope_speed_mps": out_v, "measured_speed_mps": out_m, "battery_v": out_vb}
