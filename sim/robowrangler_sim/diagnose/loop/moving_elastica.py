"""Euler-Bernoulli bending of the running rope loop, about the chain's (string) shape: the tip_bending_stiffness law.

A rope running at speed v through still air, steady in the loop plane (x along the launch heading, z up), carries
the effective internal force F(s) = T_e t + N n (T_e = T - lambda v^2, the tension less the momentum flux; N the
bending shear), s the arc length from the exit. Per metre it feels gravity -lambda g e_z and the axial skin-friction
drag -f_t t, f_t = 0.5 rho C_f pi d v^2 (normal drag is zero in a steady loop: the air passes along the rope), so

    F(s) = R + lambda g s e_z + f_t (p(s) - p(0))        (R: the reaction at the exit; p(s) the rope's position)
    B theta'' = sin(theta) F_x - cos(theta) F_z           (moment balance, theta the tangent angle, B = EI)

with the tangent clamped by the guide at both ends and the loop closed on the return point. With B -> 0 this is the
string (F parallel to t, T_e = F . t); the shape table is that string (plus the table rope's own small B0). T_e runs
from about -lambda v^2 + (push of the nip) at the exit (negative: the upper branch is compressed in the moving
frame, so bending there makes waves of length 2 pi sqrt(B / |T_e|)) to positive at the return (bending there makes
boundary layers of sqrt(B / T_e)); it crosses zero near the tip, which bending rounds over (B / T_e')^(1/3).

The law: the table's contour theta_0 is kept as the solution at B0 by a fixed defect load r_0 = B0 theta_0'' - G_0
(G_0 the moment of the force balance fitted to the table's shape, R by least squares), and the balance
B theta'' - G(theta, F) = r_0 is solved to first order about the table (one Newton step; CONTINUATION_STEPS and
NEWTON_ITERATIONS > 1 give the nonlinear solve, which jumps between buckled branches of the compressed upper branch)
with the table's end tangents and end point held. The change of the contour is the bending's effect:
displacement(B0) = 0. The linear response passes through the compressed branch's buckling resonances as B grows, so
it is not monotonic in B.
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.rope import GRAVITY_MPS2, STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams
from robowrangler_sim.shape_table import resample_by_arc_length

N_NODES = 97
CONTINUATION_STEPS = 1
NEWTON_ITERATIONS = 1
MAX_ANGLE_STEP_RAD = 0.3


def bending_displacement_m(contour_m: np.ndarray, *, speed_mps: float, bending_stiffness_n_m2: float,
                           rope: RopeParams, n_nodes: int = N_NODES) -> np.ndarray:
    """Displacement (K, 2), metres, of the contour (K, 2) (metres, table frame, exit first) when the rope's bending
    stiffness is bending_stiffness_n_m2 instead of rope.bending_stiffness_n_m2 (the table's rope). Points keep their
    arc-length fractions."""
    contour_m = np.asarray(contour_m, dtype=float)
    K = contour_m.shape[0]
    b0 = float(rope.bending_stiffness_n_m2)
    b1 = float(bending_stiffness_n_m2)
    if not np.isfinite(b1) or b1 <= 0.0:
        raise ValueError(f"bending_stiffness_n_m2: expected a finite value > 0, got {bending_stiffness_n_m2!r}")
    if abs(b1 - b0) <= 1e-12 * max(b0, 1e-12):
        return np.zeros_like(contour_m)
    q = resample_by_arc_length(contour_m, n_nodes)
    seg = np.diff(q, axis=0)
    length_m = float(np.sum(np.linalg.norm(seg, axis=1)))
    s = np.linspace(0.0, length_m, n_nodes)
    h = s[1] - s[0]
    th_seg = np.unwrap(np.arctan2(seg[:, 1], seg[:, 0]))
    th0 = np.interp(s, 0.5 * (s[1:] + s[:-1]), th_seg)
    lam_g = rope.linear_density_kg_per_m * GRAVITY_MPS2
    f_t = 0.5 * STANDARD_AIR_DENSITY_KG_PER_M3 * rope.cf_pi_d_m * speed_mps * abs(speed_mps)
    cum = np.tril(np.full((n_nodes, n_nodes), h))  # trapezoid: p(s_i) = sum_j cum_ij t(s_j)
    cum[:, 0] = h / 2
    cum[np.arange(n_nodes), np.arange(n_nodes)] = h / 2
    cum[0, 0] = 0.0

    def balance(th, r):
        sn, cs = np.sin(th), np.cos(th)
        px, pz = cum @ cs, cum @ sn
        fx, fz = r[0] + f_t * px, r[1] + lam_g * s + f_t * pz
        return sn, cs, px, pz, sn * fx - cs * fz, cs * fx + sn * fz

    sn, cs, px, pz, g_part, _ = balance(th0, np.zeros(2))
    d2 = np.zeros(n_nodes)
    d2[1:-1] = (th0[2:] - 2.0 * th0[1:-1] + th0[:-2]) / h ** 2
    a = np.column_stack([sn, -cs])[1:-1]
    r0 = np.linalg.lstsq(a, (b0 * d2 - g_part)[1:-1], rcond=None)[0]
    sn, cs, px, pz, g0, _ = balance(th0, r0)
    defect = b0 * d2 - g0
    end0 = np.array([px[-1], pz[-1]])
    x = np.r_[th0, r0]
    i = np.arange(1, n_nodes - 1)
    for bk in np.geomspace(b0, b1, CONTINUATION_STEPS + 1)[1:]:
        for _ in range(NEWTON_ITERATIONS):
            th, r = x[:n_nodes], x[n_nodes:]
            sn, cs, px, pz, g, te = balance(th, r)
            res = np.zeros(n_nodes + 2)
            jac = np.zeros((n_nodes + 2, n_nodes + 2))
            res[i] = bk * (th[i + 1] - 2.0 * th[i] + th[i - 1]) / h ** 2 - g[i] - defect[i]
            jac[i, i - 1] = bk / h ** 2
            jac[i, i + 1] = bk / h ** 2
            jac[i, i] = -2.0 * bk / h ** 2 - te[i]
            jac[1:n_nodes - 1, :n_nodes] += f_t * cum[1:-1] * np.cos(th[1:-1, None] - th[None, :])
            jac[i, n_nodes] = -sn[i]
            jac[i, n_nodes + 1] = cs[i]
            res[0], jac[0, 0] = th[0] - th0[0], 1.0
            res[n_nodes - 1], jac[n_nodes - 1, n_nodes - 1] = th[-1] - th0[-1], 1.0
            res[n_nodes], jac[n_nodes, :n_nodes] = px[-1] - end0[0], cum[-1] * -sn
            res[n_nodes + 1], jac[n_nodes + 1, :n_nodes] = pz[-1] - end0[1], cum[-1] * cs
            try:
                dx = np.linalg.solve(jac, -res)
            except np.linalg.LinAlgError:
                break
            m = float(np.max(np.abs(dx[:n_nodes])))
            x = x + (min(1.0, MAX_ANGLE_STEP_RAD / m) if m > 0 else 1.0) * dx
            if m < 1e-9:
                break
    th = x[:n_nodes]
    moved = np.column_stack([cum @ (np.cos(th) - np.cos(th0)), cum @ (np.sin(th) - np.sin(th0))])
    frac_nodes = np.linspace(0.0, 1.0, n_nodes)
    frac = np.linspace(0.0, 1.0, K)
    return np.column_stack([np.interp(frac, frac_nodes, moved[:, 0]), np.interp(frac, frac_nodes, moved[:, 1])])
