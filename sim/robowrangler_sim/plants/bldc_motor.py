"""Bank of identical BLDC motors driven from one ESC command, quasi-static electrical model.

Per motor, averaged over the ESC's PWM and commutation (winding inductance, L/R ~ 0.3 ms, is neglected):

    d V_b = Ke omega + R i          R = winding + ESC resistance, Ke = Kt = 1 / Kv (SI)
    V_b   = V_src - R_b (n d i)     battery terminal voltage, V_src = V_oc - R_b I_aux

so i = (d V_src - Ke omega) / (R + n d^2 R_b), linear in omega for one substep: i = a - b omega.
The ESC clamps |i| to ``esc_current_limit_a``. Without damped light the bridge cannot sink current, so i >= 0
(the motor freewheels when the back-EMF exceeds d V_b); with damped light i may go negative: active
(regenerative) braking when the throttle drops.
"""

from __future__ import annotations

import math


def current_law(duty: float, omega_rad_s: float, v_src_v: float, r_src_ohm: float, motor_count: int,
                ke_v_s_per_rad: float, r_circuit_ohm: float, i_limit_a: float,
                damped_light: bool) -> tuple[float, float]:
    """Per-motor current as i = a - b * omega, valid near omega_rad_s; returns (a in A, b in A s/rad).

    duty: applied duty 0..1 (0 = bridge off); omega_rad_s: shaft speed deciding the regime (clamped, freewheel
    or linear); v_src_v, r_src_ohm: battery Thevenin source (V, Ohm); the rest are motor/ESC constants.
    """
    if duty <= 0.0:
        return 0.0, 0.0
    r_eff = r_circuit_ohm + motor_count * duty * duty * r_src_ohm
    a = duty * v_src_v / r_eff
    b = ke_v_s_per_rad / r_eff
    i0 = a - b * omega_rad_s
    if i0 > i_limit_a:
        return i_limit_a, 0.0
    if i0 < 0.0:
        if not damped_light:
            return 0.0, 0.0
        if i0 < -i_limit_a:
            return -i_limit_a, 0.0
    return a, b


def battery_terminal_v(v_src_v: float, r_src_ohm: float, motor_count: int, current_a: float,
                       omega_rad_s: float, ke_v_s_per_rad: float, r_circuit_ohm: float) -> float:
    """Battery terminal voltage (V) when each of motor_count motors draws current_a at omega_rad_s.

    From power balance: the bridges draw P = n i (Ke omega + R i) = V_b I_b and V_b = V_src - R_b I_b,
    so V_b = (V_src + sqrt(V_src^2 - 4 R_b P)) / 2 (P < 0 when braking: the voltage rises).
    """
    if current_a == 0.0:
        return v_src_v
    power_w = motor_count * current_a * (ke_v_s_per_rad * omega_rad_s + r_circuit_ohm * current_a)
    disc = v_src_v * v_src_v - 4.0 * r_src_ohm * power_w
    if disc < 0.0:  # more power than the pack can deliver: maximum-power point
        return 0.5 * v_src_v
    return 0.5 * (v_src_v + math.sqrt(disc))
