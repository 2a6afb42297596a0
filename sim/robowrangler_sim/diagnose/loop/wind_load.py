"""A uniform wind on the running rope loop, about the chain's (string) shape: the uniform_wind law.

The rope runs along its tangent t at speed v; a uniform wind w e_x (e_x the launch heading, in the loop plane) makes
the air's velocity relative to the rope u = w e_x - v t. Its axial part u_t = w t_x - v changes the skin-friction drag
along the rope, 0.5 rho C_f pi d |u_t| u_t: less on the outgoing (upper) branch and more on the returning one in a
tail wind (w > 0), the reverse in a head wind; its normal part u_n = -w sin(theta) makes a pressure drag
0.5 rho C_n d |u_n| u_n across the rope, largest where the rope crosses the wind (the tip). In still air the steady
loop feels neither (the table's loop: f_t = 0.5 rho C_f pi d v^2 along -t everywhere, no normal drag).

The law: that extra load on the table's contour and the string's response to it with the end tangents and the end
point held (moving_elastica.load_displacement_m), applied in LOAD_STEPS equal parts, each solved about the contour
the previous parts left (at 1-2 m/s the wind changes each branch's drag by tens of per cent; the tension each step
linearises about is the still-air balance of that contour). The exit's reaction is free in each step and the end
tangents are held, so the response is a lift and tilt of the branches with the reach kept (0.93-0.94 m for any head
wind up to 5 m/s at 5 m/s and phi 0.1 rad, with 4 or 16 steps): right while the loop stays steady (tail winds, head
winds to about 0.5 m/s at 5 m/s). A stronger head wind puts the outgoing branch in material compression; the
truth's rope buckles and folds there, its reach halves and the contour flutters: outside this law, and refused or
flagged as such (flutter.py).
"""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop.moving_elastica import N_NODES, load_displacement_m
from robowrangler_sim.rope import STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams

LOAD_STEPS = 4


def wind_displacement_m(contours_m: np.ndarray, *, speed_mps, wind_mps: float, rope: RopeParams,
                        n_nodes: int = N_NODES, steps: int = LOAD_STEPS) -> np.ndarray:
    """Displacement, metres, of contours (G, K, 2) (metres, table frame, exit first, equally spaced in arc length)
    flown at speed_mps ((G,) or scalar) in a uniform wind of wind_mps along the launch heading (x, > 0: with the
    outgoing rope); rope: the table's rope (lambda, d, C_f, C_n, B0)."""
    c0 = np.asarray(contours_m, dtype=float)
    w = float(wind_mps)
    if w == 0.0:
        return np.zeros_like(c0)
    k_t = 0.5 * STANDARD_AIR_DENSITY_KG_PER_M3 * rope.cf_pi_d_m
    k_n = 0.5 * STANDARD_AIR_DENSITY_KG_PER_M3 * rope.normal_drag_coeff * rope.diameter_m

    def load(th: np.ndarray, v: np.ndarray) -> np.ndarray:
        t = np.stack([np.cos(th), np.sin(th)], axis=-1)
        nrm = np.stack([-np.sin(th), np.cos(th)], axis=-1)
        u_t = w * t[..., 0] - v[:, None]
        u_n = -w * np.sin(th)
        extra_axial = k_t * (np.abs(u_t) * u_t + v[:, None] ** 2)  # along t: the drag -k_t v^2 t of still air removed
        return (extra_axial[..., None] * t + (k_n * np.abs(u_n) * u_n)[..., None] * nrm) / steps

    c = c0.copy()
    for _ in range(steps):
        c = c + load_displacement_m(c, speed_mps=speed_mps, load=load, rope=rope, n_nodes=n_nodes)
    return c - c0
