"""What a stiffer rope does to the string shooter's loop (the truth of the loop proof's stiff_rope case), and the
force balance that sets the bending's scale: the effective tension T - lambda v^2 along the loop.

    uv run --locked python bench/bench_loop_stiff_rope.py                       # B x 5, 20, 40 at 3.5-6 m/s
    uv run --locked python bench/bench_loop_stiff_rope.py --factors 20 --speeds 4 5 --phis -0.1 0.1

Per (B factor, rope speed, phi): the steady loop averaged over 2 s after a 3 s settle, against the table rope's (B0 =
5e-7 N m^2): contour RMS change, the flutter (mean point standard deviation over the 2 s), the change of reach and the
loop's apparent length (a folding tip shortens it), and the normal displacement along the arc (exit -> tip ->
return, every 4th of 40 points, mm, + outward). Then the effective tension at the exit and the return: the string
shooter's segment tensions minus lambda v^2, against the steady force balance of the moving string fitted to the
contour alone (F(s) = R + lambda g s e_z + f_t (p(s) - p(0)) parallel to the rope, R by least squares).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from robowrangler_sim.rope import GRAVITY_MPS2, STANDARD_AIR_DENSITY_KG_PER_M3
from robowrangler_sim.shape_table import resample_by_arc_length
from robowrangler_sim.string_shooter.model import StringShooter
from robowrangler_sim.string_shooter.motion import ModuleMotion
from robowrangler_sim.string_shooter.params import ShooterParams

N_POINTS = 40


def steady_loop(bending_factor: float, speed_mps: float, phi_rad: float, *, settle_s: float = 3.0,
                average_s: float = 2.0):
    """(mean contour (40, 2) m, flutter m, segment tensions N) of the string shooter held at speed and phi."""
    base = ShooterParams()
    rope = dataclasses.replace(base.rope, bending_stiffness_n_m2=base.rope.bending_stiffness_n_m2 * bending_factor)
    motion = ModuleMotion(wheel_speed_mps=lambda t: speed_mps + 0.0 * np.asarray(t),
                          phi_rad=lambda t: phi_rad + 0.0 * np.asarray(t))
    sh = StringShooter(dataclasses.replace(base, rope=rope), loop_length_m=2.0, motion=motion, initial_shape="circle")
    sh.step_for(settle_s)
    tension = sh.segment_tensions_n().copy()
    pts = []
    for _ in range(int(average_s * 30)):
        sh.step_for(1.0 / 30.0)
        pts.append(resample_by_arc_length(sh.frame().loop_plane_xz_m(), N_POINTS))
    p = np.array(pts)
    return p.mean(axis=0), float(np.mean(np.linalg.norm(p - p.mean(axis=0), axis=-1))), tension, base.rope


def force_balance_tension(contour_m: np.ndarray, speed_mps: float, rope) -> np.ndarray:
    """T - lambda v^2 along the contour from the moving string's steady force balance (no tension data)."""
    q = resample_by_arc_length(contour_m, 161)
    seg = np.diff(q, axis=0)
    th = np.unwrap(np.arctan2(seg[:, 1], seg[:, 0]))
    s = np.r_[0.0, np.cumsum(np.linalg.norm(seg, axis=1))][:-1] + 0.5 * np.linalg.norm(seg, axis=1)
    p = 0.5 * (q[1:] + q[:-1]) - q[0]
    f_t = 0.5 * STANDARD_AIR_DENSITY_KG_PER_M3 * rope.cf_pi_d_m * speed_mps ** 2
    lam_g = rope.linear_density_kg_per_m * GRAVITY_MPS2
    sn, cs = np.sin(th), np.cos(th)
    # F parallel to t: sin F_x - cos F_z = 0
    a = np.column_stack([sn, -cs])
    b = -(sn * f_t * p[:, 0] - cs * (lam_g * s + f_t * p[:, 1]))
    r = np.linalg.lstsq(a, b, rcond=None)[0]
    fx, fz = r[0] + f_t * p[:, 0], r[1] + lam_g * s + f_t * p[:, 1]
    return cs * fx + sn * fz


def normals(p: np.ndarray) -> np.ndarray:
    t = np.gradient(p, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return np.column_stack([-t[:, 1], t[:, 0]])


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--factors", type=float, nargs="*", default=[5.0, 20.0, 40.0])
    ap.add_argument("--speeds", type=float, nargs="*", default=[3.5, 4.0, 5.0, 6.0])
    ap.add_argument("--phis", type=float, nargs="*", default=[-0.15, 0.1, 0.35])
    args = ap.parse_args()
    ref = {}
    print("effective tension T - lambda v^2 (mN) at exit / return: string shooter | force balance of the contour")
    for v in args.speeds:
        for phi in args.phis:
            c, fl, tension, rope = steady_loop(1.0, v, phi)
            ref[(v, phi)] = c
            te = force_balance_tension(c, v, rope)
            lv2 = rope.linear_density_kg_per_m * v * v
            print(f"  v {v:3.1f} m/s phi {phi:5.2f}: {(tension[0] - lv2) * 1e3:6.2f} / {(tension[-1] - lv2) * 1e3:6.2f} | "
                  f"{te[0] * 1e3:6.2f} / {te[-1] * 1e3:6.2f}   (lambda v^2 {lv2 * 1e3:.2f})", flush=True)
    print("\nstiffer rope against the table rope (B0 = 5e-7 N m^2); dn: normal displacement exit -> tip -> return, mm")
    for f in args.factors:
        for v in args.speeds:
            for phi in args.phis:
                c, fl, _, _ = steady_loop(f, v, phi)
                c0 = ref[(v, phi)]
                dn = np.sum((c - c0) * normals(c0), axis=1) * 1e3
                rms = np.sqrt(np.mean(np.sum((c - c0) ** 2, axis=1))) * 1e3
                length = np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1))
                print(f"  B x{f:4.0f} v {v:3.1f} phi {phi:5.2f}: RMS {rms:6.1f} mm  flutter {fl * 1e3:5.1f} mm  reach "
                      f"{(c[:, 0].max() - c0[:, 0].max()) * 1e3:6.1f} mm  length {length:.3f} m  dn "
                      + " ".join(f"{x:4.0f}" for x in dn[::4]), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
