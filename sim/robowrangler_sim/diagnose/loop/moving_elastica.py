"""Euler-Bernoulli bending of the running rope loop, about the chain's (string) shape: the tip_bending_stiffness law.

A rope running at speed v through still air, steady in the loop plane (x along the launch heading, z up), carries
the effective internal force F(s) = T_e t + N n (T_e = T - lambda v^2, the tension less the momentum flux; N the
bending shear), s the arc length from the exit along the flow. Per metre it feels gravity -lambda g e_z and the axial
skin-friction drag -f_t t, f_t = 0.5 rho C_f pi d v^2 (normal drag is zero in a steady loop: the air passes along
the rope), so

    F(s) = R + lambda g s e_z + f_t (p(s) - p(0))             (R: the reaction at the exit, p(s) the rope's position)
    d/ds [B theta' + eta v theta''] = sin(theta) F_x - cos(theta) F_z

theta the tangent angle, B = EI and eta = tau_B B the rope's internal (Kelvin-Voigt) bending damping: a material
element carried along the steady shape at v bends at the rate v dkappa/ds, so the moment is B kappa + eta v kappa'.
The tangent is clamped by the guide at both ends and the loop closes on the return point. With B -> 0 this is the
string (F parallel to t, T_e = F . t); the shape table is that string (with the table rope's own small B0).

T_e runs from about -(lambda v^2 - the nip's push) at the exit to + at the return (the string shooter's -7.6 / +8.2 mN
at 5 m/s, phi 0.1; the balance fitted to the contour alone gives -7.5 / +8.4 mN: bench/bench_loop_stiff_rope.py).
Along the compressed upper branch bending makes stationary waves of wavenumber sqrt(|T_e| / B), excited at the exit
and carried downstream, decaying at about tau_B v |T_e| / (2 B) per metre (without eta the two-point problem has
spurious buckling resonances); along the returning branch it makes boundary layers sqrt(T_e / B); the tip, where T_e
crosses zero, is rounded over (B / T_e')^(1/3).

The law: first order about the table's contour theta_0. R_0 of the table is fitted by least squares, the table's
defect against the balance at B0 kept as a fixed load, and the linear response to B - B0 solved with the end
tangents and the end point held (one dense (n + 2) x (n + 2) solve). Not monotonic in B: a log ladder of starts.
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.rope import GRAVITY_MPS2, STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams
from robowrangler_sim.shape_table import resample_by_arc_length

N_NODES = 121
"""Nodes of the solve along a 2 m loop: 1.7 cm, below the bending lengths of the stiff ropes it must resolve (the
response changes by < 1 mm RMS from 121 to 241 nodes)."""

_OPERATORS: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _operators(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cumulative trapezoid, second difference, third difference) on n unit-spaced nodes (scale by h)."""
    if n not in _OPERATORS:
        cum = np.tril(np.ones((n, n)))
        cum[:, 0] = 0.5
        cum[np.arange(n), np.arange(n)] = 0.5
        cum[0, 0] = 0.0
        d2 = np.zeros((n, n))
        d3 = np.zeros((n, n))
        for i in range(1, n - 1):
            d2[i, i - 1:i + 2] = (1.0, -2.0, 1.0)
        for i in range(2, n - 2):
            d3[i, i - 2:i + 3] = (-0.5, 1.0, 0.0, -1.0, 0.5)
        d3[1, 0:4] = (-1.0, 3.0, -3.0, 1.0)
        d3[n - 2, n - 4:n] = (-1.0, 3.0, -3.0, 1.0)
        _OPERATORS[n] = (cum, d2, d3)
    return _OPERATORS[n]


def effective_tension_n(contour_m: np.ndarray, *, speed_mps: float, rope: RopeParams,
                        n_nodes: int = N_NODES) -> tuple[np.ndarray, np.ndarray]:
    """(arc length s (n,), T - lambda v^2 (n,)) of the running string whose shape is contour_m (K, 2), metres: the
    steady force balance F = R + lambda g s e_z + f_t (p - p0) parallel to the rope, R by least squares."""
    s, th, _, te, _ = _string_balance(contour_m, speed_mps, rope, n_nodes)
    return s, te


def _string_balance(contour_m, speed_mps, rope, n):
    q = resample_by_arc_length(np.asarray(contour_m, dtype=float), n)
    seg = np.diff(q, axis=0)
    length_m = float(np.sum(np.linalg.norm(seg, axis=1)))
    s = np.linspace(0.0, length_m, n)
    h = s[1] - s[0]
    th = np.interp(s, 0.5 * (s[1:] + s[:-1]), np.unwrap(np.arctan2(seg[:, 1], seg[:, 0])))
    cum, d2, d3 = _operators(n)
    cum = cum * h
    lam_g = rope.linear_density_kg_per_m * GRAVITY_MPS2
    f_t = 0.5 * STANDARD_AIR_DENSITY_KG_PER_M3 * rope.cf_pi_d_m * speed_mps * abs(speed_mps)
    sn, cs = np.sin(th), np.cos(th)
    px, pz = cum @ cs, cum @ sn
    b0 = rope.bending_stiffness_n_m2
    moment = b0 * (d2 @ th) / h ** 2 + rope.bending_damping_s * b0 * speed_mps * (d3 @ th) / h ** 3
    free = sn * f_t * px - cs * (lam_g * s + f_t * pz)
    r = np.linalg.lstsq(np.column_stack([sn, -cs])[1:-1], (moment - free)[1:-1], rcond=None)[0]
    fx, fz = r[0] + f_t * px, r[1] + lam_g * s + f_t * pz
    return s, th, (cum, d2 / h ** 2, d3 / h ** 3, f_t), cs * fx + sn * fz, (sn, cs)


def bending_displacement_m(contour_m: np.ndarray, *, speed_mps: float, bending_stiffness_n_m2: float,
                           rope: RopeParams, n_nodes: int = N_NODES) -> np.ndarray:
    """Displacement (K, 2), metres, of the contour (K, 2) (metres, table frame, exit first) when the rope's bending
    stiffness is bending_stiffness_n_m2 instead of rope.bending_stiffness_n_m2 (the table's rope); the points keep
    their arc-length fractions. rope: the table's rope (lambda, d, C_f, B0, tau_B)."""
    contour_m = np.asarray(contour_m, dtype=float)
    if contour_m.ndim != 2 or contour_m.shape[1] != 2 or contour_m.shape[0] < 4:
        raise ValueError(f"contour_m: expected shape (K >= 4, 2), got {contour_m.shape}")
    b1 = float(bending_stiffness_n_m2)
    if not np.isfinite(b1) or b1 <= 0.0:
        raise ValueError(f"bending_stiffness_n_m2: expected a finite value > 0, got {bending_stiffness_n_m2!r}")
    b0 = float(rope.bending_stiffness_n_m2)
    if abs(b1 - b0) <= 1e-12 * max(b0, 1e-12):
        return np.zeros_like(contour_m)
    n = int(n_nodes)
    s, th, (cum, d2, d3, f_t), te, (sn, cs) = _string_balance(contour_m, speed_mps, rope, n)
    tau_v = rope.bending_damping_s * speed_mps
    i = np.arange(1, n - 1)
    # B delta'' + eta v delta''' - T_e delta - sin(theta) dF_x + cos(theta) dF_z = -(dB theta0'' + d eta v theta0''')
    # dF = dR + f_t dp(s), dp(s) = int_0^s (-sin theta, cos theta) delta
    a = np.zeros((n + 2, n + 2))
    rhs = np.zeros(n + 2)
    a[1:n - 1, :n] = (b1 * d2 + b1 * tau_v * d3)[1:n - 1]
    a[i, i] -= te[i]
    a[1:n - 1, :n] += f_t * cum[1:n - 1] * np.cos(th[1:n - 1, None] - th[None, :])
    a[i, n] = -sn[i]
    a[i, n + 1] = cs[i]
    rhs[1:n - 1] = -((b1 - b0) * ((d2 + tau_v * d3) @ th))[1:n - 1]
    a[0, 0] = 1.0
    a[n - 1, n - 1] = 1.0
    a[n, :n] = cum[-1] * -sn
    a[n + 1, :n] = cum[-1] * cs
    try:
        delta = np.linalg.solve(a, rhs)[:n]
    except np.linalg.LinAlgError:
        delta = np.linalg.lstsq(a, rhs, rcond=None)[0][:n]
    moved = np.column_stack([cum @ (-sn * delta), cum @ (cs * delta)])
    frac = np.linspace(0.0, 1.0, contour_m.shape[0])
    frac_nodes = np.linspace(0.0, 1.0, n)
    return np.column_stack([np.interp(frac, frac_nodes, moved[:, 0]), np.interp(frac, frac_nodes, moved[:, 1])])
