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
tangents and the end point held (one dense (n + 2) x (n + 2) solve per contour, batched over contours). Not
monotonic in B: a log ladder of starts. The same system gives the first-order response to an extra load per metre
(load_displacement_m: the uniform_wind law, wind_load.py).
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.rope import GRAVITY_MPS2, STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams

N_NODES = 121
"""Nodes of the solve along the loop: 1.7 cm on a 2 m loop, below the bending lengths of the stiff ropes it must
resolve (the response moves 1.6 mm RMS from 121 to 241 nodes, 3.3 mm at 81)."""
BATCH = 128
"""Contours solved together (a (BATCH, n + 2, n + 2) system, 16 MB)."""

_OPERATORS: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _operators(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cumulative trapezoid, second difference, third difference) on n unit-spaced nodes (scale by h, h^2, h^3)."""
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


def _interp_fraction(values: np.ndarray, src_frac: np.ndarray, dst_frac: np.ndarray) -> np.ndarray:
    """Linear interpolation along the last axis of values (..., M) from increasing fractions src_frac (M,) to
    dst_frac (N,), clamped at the ends."""
    idx = np.clip(np.searchsorted(src_frac, dst_frac, side="right") - 1, 0, src_frac.size - 2)
    w = np.clip((dst_frac - src_frac[idx]) / (src_frac[idx + 1] - src_frac[idx]), 0.0, 1.0)
    return values[..., idx] * (1.0 - w) + values[..., idx + 1] * w


def _check(contours_m, speeds_mps) -> tuple[np.ndarray, np.ndarray]:
    c = np.asarray(contours_m, dtype=float)
    if c.ndim == 2:
        c = c[None]
    if c.ndim != 3 or c.shape[-1] != 2 or c.shape[1] < 4:
        raise ValueError(f"contour_m: expected shape (K >= 4, 2) or (G, K >= 4, 2), got {np.shape(contours_m)}")
    v = np.broadcast_to(np.asarray(speeds_mps, dtype=float), (c.shape[0],))
    if not np.all(np.isfinite(c)) or not np.all(np.isfinite(v)):
        raise ValueError("contour_m, speed_mps: expected finite values")
    return c, v


def _string_balance(c: np.ndarray, v: np.ndarray, rope: RopeParams, n: int):
    """Per contour (G, K, 2), its points taken as equally spaced in arc length: node angles theta (G, n), spacing h
    (G,), T_e (G, n), f_t (G,), arc length s (G, n)."""
    cum, d2, d3 = _operators(n)
    seg = np.diff(c, axis=1)
    length_m = np.sum(np.linalg.norm(seg, axis=-1), axis=1)
    k = c.shape[1]
    th_seg = np.unwrap(np.arctan2(seg[..., 1], seg[..., 0]), axis=1)
    th = _interp_fraction(th_seg, (np.arange(k - 1) + 0.5) / (k - 1), np.linspace(0.0, 1.0, n))
    h = length_m / (n - 1)
    s = h[:, None] * np.arange(n)[None, :]
    lam_g = rope.linear_density_kg_per_m * GRAVITY_MPS2
    f_t = 0.5 * STANDARD_AIR_DENSITY_KG_PER_M3 * rope.cf_pi_d_m * v * np.abs(v)
    sn, cs = np.sin(th), np.cos(th)
    px, pz = h[:, None] * (cs @ cum.T), h[:, None] * (sn @ cum.T)
    b0, tau = rope.bending_stiffness_n_m2, rope.bending_damping_s
    moment = b0 * (th @ d2.T) / h[:, None] ** 2 + tau * b0 * v[:, None] * (th @ d3.T) / h[:, None] ** 3
    free = sn * f_t[:, None] * px - cs * (lam_g * s + f_t[:, None] * pz)
    # R (G, 2) by least squares over the interior nodes: sin R_x - cos R_z = moment - free
    a_s, a_c, y = sn[:, 1:-1], -cs[:, 1:-1], (moment - free)[:, 1:-1]
    m = np.stack([np.stack([np.sum(a_s * a_s, 1), np.sum(a_s * a_c, 1)], -1),
                  np.stack([np.sum(a_c * a_s, 1), np.sum(a_c * a_c, 1)], -1)], -2)
    r = np.linalg.solve(m, np.stack([np.sum(a_s * y, 1), np.sum(a_c * y, 1)], -1)[..., None])[..., 0]
    fx, fz = r[:, :1] + f_t[:, None] * px, r[:, 1:] + lam_g * s + f_t[:, None] * pz
    return th, h, cs * fx + sn * fz, f_t, s


def effective_tension_n(contour_m: np.ndarray, *, speed_mps: float, rope: RopeParams,
                        n_nodes: int = N_NODES) -> tuple[np.ndarray, np.ndarray]:
    """(arc length s (n,), T - lambda v^2 (n,)) of the running string whose shape is contour_m (K, 2), metres, equally
    spaced in arc length: the steady force balance F = R + lambda g s e_z + f_t (p - p0) parallel to the rope (with
    the table rope's B0), R by least squares."""
    c, v = _check(contour_m, speed_mps)
    _, _, te, _, s = _string_balance(c, v, rope, int(n_nodes))
    return s[0], te[0]


def bending_displacement_m(contour_m: np.ndarray, *, speed_mps, bending_stiffness_n_m2: float, rope: RopeParams,
                           n_nodes: int = N_NODES) -> np.ndarray:
    """Displacement, metres, of contours (K, 2) or (G, K, 2) (metres, table frame, exit first, equally spaced in arc
    length) flown at speed_mps (scalar or (G,)) when the rope's bending stiffness is bending_stiffness_n_m2 instead of
    rope.bending_stiffness_n_m2 (the table's rope); same shape as contour_m, the points keep their arc fractions.
    rope: the table's rope (lambda, d, C_f, B0, tau_B)."""
    c, v = _check(contour_m, speed_mps)
    b1 = float(bending_stiffness_n_m2)
    if not np.isfinite(b1) or b1 <= 0.0:
        raise ValueError(f"bending_stiffness_n_m2: expected a finite value > 0, got {bending_stiffness_n_m2!r}")
    b0 = float(rope.bending_stiffness_n_m2)
    out = np.zeros_like(c)
    if abs(b1 - b0) > 1e-12 * max(b0, 1e-12):
        for a in range(0, c.shape[0], BATCH):
            out[a:a + BATCH] = _solve(c[a:a + BATCH], v[a:a + BATCH], b0, b1, rope, int(n_nodes))
    return out[0] if np.ndim(contour_m) == 2 else out


def _system(c: np.ndarray, v: np.ndarray, b1: float, rope: RopeParams, n: int):
    """The linear system (G, n + 2, n + 2) of the contours' first-order response at stiffness b1, unknowns the node
    angles delta and dR:  B delta'' + eta v delta''' - T_e delta - sin(theta) dF_x + cos(theta) dF_z = rhs with
    dF = dR + f_t dp(s), dp(s) = int_0^s (-sin theta, cos theta) delta; delta(0) = delta(L) = 0, dp(L) = 0.
    Returns (matrix, theta (G, n), h (G,), 1 / h^2, eta v / h^3)."""
    cum, d2, d3 = _operators(n)
    th, h, te, f_t, _ = _string_balance(c, v, rope, n)
    g = c.shape[0]
    sn, cs = np.sin(th), np.cos(th)
    c2 = 1.0 / h ** 2
    c3 = rope.bending_damping_s * v / h ** 3
    a = np.empty((g, n + 2, n + 2))
    inner = a[:, 1:n - 1, :n]
    # f_t dp: cos(theta_i - theta_j) = cos_i cos_j + sin_i sin_j, weighted by the trapezoid
    np.matmul(cs[:, 1:n - 1, None], cs[:, None, :], out=inner)
    inner += sn[:, 1:n - 1, None] * sn[:, None, :]
    inner *= (f_t * h)[:, None, None] * cum[None, 1:n - 1]
    inner += (b1 * c2)[:, None, None] * d2[None, 1:n - 1]
    inner += (b1 * c3)[:, None, None] * d3[None, 1:n - 1]
    i = np.arange(1, n - 1)
    a[:, i, i] -= te[:, 1:n - 1]
    a[:, 1:n - 1, n] = -sn[:, 1:n - 1]
    a[:, 1:n - 1, n + 1] = cs[:, 1:n - 1]
    a[:, 0] = 0.0
    a[:, n - 1] = 0.0
    a[:, 0, 0] = 1.0
    a[:, n - 1, n - 1] = 1.0
    a[:, n, :n] = h[:, None] * cum[-1][None] * -sn
    a[:, n + 1, :n] = h[:, None] * cum[-1][None] * cs
    a[:, n:, n:] = 0.0
    return a, th, h, c2, c3


def _displace(a: np.ndarray, rhs: np.ndarray, th: np.ndarray, h: np.ndarray, k: int) -> np.ndarray:
    """Solve for delta and integrate it to point displacements (G, k, 2) at k points equally spaced in arc length."""
    n = th.shape[1]
    cum = _operators(n)[0]
    try:
        delta = np.linalg.solve(a, rhs[..., None])[..., 0][:, :n]
    except np.linalg.LinAlgError:
        delta = np.stack([np.linalg.lstsq(a[q], rhs[q], rcond=None)[0][:n] for q in range(a.shape[0])])
    sn, cs = np.sin(th), np.cos(th)
    moved = np.stack([h[:, None] * ((-sn * delta) @ cum.T), h[:, None] * ((cs * delta) @ cum.T)], axis=-1)  # (G, n, 2)
    frac_n, frac_k = np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, k)
    return np.stack([_interp_fraction(moved[..., 0], frac_n, frac_k), _interp_fraction(moved[..., 1], frac_n, frac_k)],
                    axis=-1)


def _solve(c: np.ndarray, v: np.ndarray, b0: float, b1: float, rope: RopeParams, n: int) -> np.ndarray:
    """The linear response (G, K, 2) to B - B0: _system at B with rhs -(dB theta0'' + d eta v theta0''')."""
    _, d2, d3 = _operators(n)
    a, th, h, c2, c3 = _system(c, v, b1, rope, n)
    rhs = np.zeros((c.shape[0], n + 2))
    rhs[:, 1:n - 1] = -(b1 - b0) * (c2[:, None] * (th @ d2.T) + c3[:, None] * (th @ d3.T))[:, 1:n - 1]
    return _displace(a, rhs, th, h, c.shape[1])


def load_displacement_m(contours_m: np.ndarray, *, speed_mps, load, rope: RopeParams,
                        n_nodes: int = N_NODES) -> np.ndarray:
    """Displacement, metres, of contours (G, K, 2) (metres, table frame, exit first, equally spaced in arc length)
    flown at speed_mps ((G,) or scalar) under an extra external load per metre, first order about each contour with
    the table rope's own B0. load(theta, speed) -> (G, n, 2) newtons per metre at the n solve nodes, given their
    tangent angles theta (G, n) and the contours' speeds (G,). The internal force gains G(s) = -int_0^s delta f, so
    the balance's right side is sin(theta) G_x - cos(theta) G_z; the end tangents and the end point are held."""
    c, v = _check(contours_m, speed_mps)
    n = int(n_nodes)
    cum = _operators(n)[0]
    out = np.zeros_like(c)
    for a0 in range(0, c.shape[0], BATCH):
        cb, vb = c[a0:a0 + BATCH], v[a0:a0 + BATCH]
        a, th, h, _, _ = _system(cb, vb, rope.bending_stiffness_n_m2, rope, n)
        df = np.asarray(load(th, vb))
        g_x = -h[:, None] * (df[..., 0] @ cum.T)
        g_z = -h[:, None] * (df[..., 1] @ cum.T)
        rhs = np.zeros((cb.shape[0], n + 2))
        rhs[:, 1:n - 1] = (np.sin(th) * g_x - np.cos(th) * g_z)[:, 1:n - 1]
        out[a0:a0 + BATCH] = _displace(a, rhs, th, h, c.shape[1])
    return out
