"""Validation sweeps and speed of the first-principles string shooter (issue 6). Prints its figures.

    uv run python bench/bench_string_shooter.py            # everything (about 2-3 min on one core)
    uv run python bench/bench_string_shooter.py --quick    # coarser sweeps
    uv run python bench/bench_string_shooter.py --only takeoff,waves --plot-dir /tmp/ss

Sections: takeoff (our rope, 2 m loop), length (0.4-2 m), angle (-30..40 deg), vacuum (no air),
shape (roundness versus phi, the paper's Fig. 5b), waves (v +- c), speed (steady state, 10 s dynamic run),
recording (the 12 s default MCAP recording: SIL firmware + plants + rope; needs the native SIL build).
Progress goes to stderr, figures to stdout.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from robowrangler_sim.shape_table import resample_by_arc_length
from robowrangler_sim.string_shooter import (ModuleMotion, NumericsParams, ShooterParams, StringShooter,
                                             takeoff_speed_estimate_mps)
from robowrangler_sim.string_shooter.shape import reach_m, roundness
from robowrangler_sim.string_shooter.takeoff import find_takeoff_speed, no_air
from robowrangler_sim.string_shooter.waves import measure_wave_speeds, measure_waves_on_loop

SECTIONS = ("takeoff", "length", "angle", "vacuum", "shape", "waves", "speed", "sensitivity", "recording")


def log(msg: str) -> None:
    print(f"  ... {msg}", file=sys.stderr, flush=True)


def speeds(quick: bool) -> np.ndarray:
    return np.arange(1.5, 3.61, 0.1 if quick else 0.05)


def bench_takeoff(args, plots):
    p = ShooterParams()
    est = takeoff_speed_estimate_mps(p.rope, p.air)
    log("takeoff sweep, 2 m loop, phi 0")
    t0 = time.perf_counter()
    r = find_takeoff_speed(p, loop_length_m=2.0, speeds_mps=speeds(args.quick))
    print("\n## Takeoff, our rope (lambda 0.221 g/m, d 2 mm, C_f 0.085, rho 1.2): 2 m loop, phi 0")
    print(f"  drag balance f_t(v*) = lambda g predicts v* = {est:.3f} m/s")
    print(f"  simulated takeoff (depth leaves the hanging branch fitted below 2.1 m/s by 3 % of L/2): {r.speed_mps:.3f} m/s "
          f"({100 * (r.speed_mps / 2.6 - 1):+.1f} % vs 2.6 m/s)   [{time.perf_counter() - t0:.0f} s]")
    print("  v [m/s] : depth / (L/2)")
    for v, d in zip(r.speeds_mps[::2], r.depth_fraction[::2]):
        print(f"    {v:4.2f} : {d:.3f}")
    plots["takeoff"] = r


def _takeoff_or_nan(**kw) -> float:
    try:
        return find_takeoff_speed(ShooterParams(), speeds_mps=kw.pop("speeds"), **kw).speed_mps
    except Exception as exc:  # noqa: BLE001 - a sweep without a clear takeoff is a figure too
        log(f"no clear takeoff: {exc}")
        return float("nan")


def bench_length(args, plots):
    print("\n## Takeoff versus loop length (phi 0)")
    out = []
    for length in (0.4, 0.7, 1.0, 1.5, 2.0):
        log(f"takeoff sweep, {length} m loop")
        out.append(_takeoff_or_nan(loop_length_m=length, speeds=speeds(args.quick)))
        print(f"  L = {length:3.1f} m : v* = {out[-1]:.3f} m/s")
    mean = float(np.nanmean(out))
    print(f"  spread: max |v* - mean| / mean = {100 * np.nanmax(abs(np.array(out) - mean)) / mean:.1f} % "
          f"(mean {mean:.3f} m/s)")


def bench_angle(args, plots):
    print("\n## Takeoff versus launch angle phi (2 m loop; and 0.4 m loop, where the exit jet matters)")
    for length in (2.0, 0.4):
        out = []
        for phi in (-30, -20, -10, 0, 10, 20, 30, 40):
            log(f"takeoff sweep, {length} m loop, phi {phi}")
            out.append(_takeoff_or_nan(loop_length_m=length, phi_rad=math.radians(phi), speeds=speeds(args.quick)))
        mean = float(np.nanmean(out))
        row = " ".join(f"{phi:+d}:{v:.2f}" for phi, v in zip((-30, -20, -10, 0, 10, 20, 30, 40), out))
        print(f"  L = {length} m: {row}")
        print(f"    spread max |v* - mean| / mean = {100 * np.nanmax(abs(np.array(out) - mean)) / mean:.1f} % "
              f"(mean {mean:.3f} m/s; nan = no clear takeoff in 1.5-3.6 m/s)")


def bench_vacuum(args, plots):
    print("\n## No air (rho = 0): spun up over 2 s from hanging, 1 m loop, last 3 s of 5 s")
    for v in (3.0, 8.0, 15.0):
        log(f"vacuum at {v} m/s")
        sim = StringShooter(no_air(ShooterParams()), loop_length_m=1.0, initial_shape="hanging",
                            motion=ModuleMotion(wheel_speed_mps=lambda t, v=v: v * np.clip(t / 2.0, 0, 1)))
        rec = sim.run(5.0, frame_interval_s=0.02)
        late = [f.loop_plane_xz_m() for f in rec.frames if f.time_s >= 2.0]
        depth = np.array([-xz[:, 1].min() for xz in late]) / 0.5
        rise = max(xz[:, 1].max() for xz in late)
        print(f"  v = {v:4.1f} m/s: depth / (L/2) mean {depth.mean():.3f} min {depth.min():.3f}, "
              f"highest point {1e3 * rise:+.1f} mm relative to the exit  -> hangs")
    p = ShooterParams()
    sim = StringShooter(p, loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=8.0))
    sim.step_for(3.0)
    print(f"  (with air at 8 m/s: depth / (L/2) = {-sim.frame().loop_plane_xz_m()[:, 1].min() / 0.5:.3f} -> flies)")


def bench_shape(args, plots):
    from robowrangler_sim.string_shooter.shape_export import steady_contour_xz_m
    print("\n## Loop shape versus phi (2 m loop): roundness 4 pi A / P^2 (1 = circle) and reach")
    shapes = {}
    for v in (4.0, 5.0, 8.0):
        row = []
        for phi in (-30, -20, -10, 0, 10, 20, 30, 40):
            log(f"shape v {v} phi {phi}")
            c = steady_contour_xz_m(ShooterParams(), phi_deg=phi, rope_speed_mps=v, loop_length_m=2.0, n_points=80,
                                    settle_s=4.0 if args.quick else 6.0)
            shapes[(v, phi)] = c
            row.append(f"{phi:+d}:{roundness(c):.2f}/{reach_m(c):.2f}m")
        print(f"  v = {v} m/s: " + " ".join(row))
    plots["shape"] = shapes


def bench_waves(args, plots):
    print("\n## Waves: pluck on a straight moving span (no gravity, no air, B = 0); lab speeds of the two pulses")
    for v, c in ((4.0, 2.0), (1.0, 2.0), (3.0, 3.0), (6.0, 1.5), (2.0, 5.0)):
        log(f"waves v {v} c {c}")
        r = measure_wave_speeds(rope_speed_mps=v, wave_speed_mps=c, span_m=3.0, segment_length_m=0.01)
        print(f"  v = {v:3.1f}, c = sqrt(T/lambda) = {r.wave_speed_mps:.3f} m/s: measured "
              f"{r.measured_mps[0]:+.3f} / {r.measured_mps[1]:+.3f}, predicted v-c {r.predicted_mps[0]:+.3f} / "
              f"v+c {r.predicted_mps[1]:+.3f} m/s, error {100 * r.relative_error.max():.2f} % of v+c")
    print("  pluck on the flying 2 m loop (phi 0), out of plane, followed along the loop; prediction integrates"
          " ds/dt = v -+ sqrt(T(s)/lambda) over the loop's steady tension profile:")
    for v, frac in ((5.0, 0.6), (5.0, 0.75), (8.0, 0.6), (8.0, 0.75)):
        log(f"waves on the loop v {v} at {frac}")
        r = measure_waves_on_loop(rope_speed_mps=v, start_fraction=frac)
        c0 = math.sqrt(r.tension_n / ShooterParams().rope.linear_density_kg_per_m)
        err = np.abs(r.measured_mps - r.predicted_mps).max() / (v + c0)
        print(f"    v = {v}, pluck at s = {r.start_arc_m:.2f} m (T = {1e3 * r.tension_n:.1f} mN, c = {c0:.2f} m/s): "
              f"measured {r.measured_mps[0]:+.2f} / {r.measured_mps[1]:+.2f}, predicted {r.predicted_mps[0]:+.2f} / "
              f"{r.predicted_mps[1]:+.2f} m/s, error {100 * err:.1f} % of v+c")


def _steady(sim, tol_m=2e-3):
    prev, calm = None, 0
    while sim.time_s < 20.0:
        sim.step_for(0.1)
        c = resample_by_arc_length(sim.frame().loop_plane_xz_m(), 100)
        if prev is not None and np.abs(c - prev).max() < tol_m:
            calm += 1
            if calm >= 5:
                return sim.time_s
        else:
            calm = 0
        prev = c
    return float("nan")


def bench_speed(args, plots):
    print("\n## Speed (one core, numba-compiled kernel; first call compiles, not timed)")
    StringShooter(ShooterParams(), loop_length_m=0.5).step_for(0.01)  # compile / load cache
    for ds in (0.025, 0.0125):
        p = ShooterParams(numerics=NumericsParams(segment_length_m=ds))
        sim = StringShooter(p, loop_length_m=2.0, motion=ModuleMotion(wheel_speed_mps=5.0))
        log(f"steady state, ds {ds}")
        w0 = time.perf_counter()
        t_ss = _steady(sim)
        wall = time.perf_counter() - w0
        steps = t_ss / sim.dt_s
        print(f"  2 m loop at 5 m/s, ds = {100 * ds:.2f} cm ({sim.n_nodes} nodes, dt = {1e6 * sim.dt_s:.1f} us): "
              f"steady (contour still to 2 mm) after {t_ss:.1f} s simulated in {wall:.2f} s wall "
              f"= {t_ss / wall:.1f} sim s / wall s, {1e6 * wall / steps:.2f} us/step")
        motion = ModuleMotion(
            wheel_speed_mps=lambda t: 4.0 + 2.0 * np.clip(t - 2.0, 0, 1) - 1.5 * np.clip(t - 6.0, 0, 1),
            phi_rad=lambda t: np.radians(10.0 + 25.0 * np.sin(0.8 * t)),
            yaw_rad=lambda t: 0.3 * np.sin(0.5 * t),
            base_position_m=lambda t: np.column_stack([0.1 * np.sin(1.3 * t), np.zeros_like(t), 0.05 * np.sin(2.1 * t)]),
            guide_travel_m=lambda t: 0.09 + 0.08 * np.sin(0.4 * t),
        )
        sim = StringShooter(p, loop_length_m=2.0, motion=motion)
        log(f"10 s dynamic run, ds {ds}")
        w0 = time.perf_counter()
        rec = sim.run(10.0, frame_interval_s=0.01, progress=True)
        wall = time.perf_counter() - w0
        print(f"  10 s dynamic run (phi, yaw, translation, wheel speed and guide travel all moving, 100 Hz frames): "
              f"{wall:.2f} s wall = {10.0 / wall:.1f} sim s / wall s; loop length now {sim.loop_length_m():.3f} m, "
              f"{len(rec.frames)} frames")
    print("  limit: explicit step dt = 0.4 ds / sqrt(EA/lambda) (axial wave 150 m/s); cost ~ nodes x steps, so"
          " halving ds costs 4x")


def bench_sensitivity(args, plots):
    """Takeoff (1 m loop, phi 0) when the numerical and secondary physical choices change."""
    print("\n## Sensitivity of the takeoff speed (1 m loop, phi 0) to choices that should not matter")
    base = ShooterParams()
    rope = base.rope
    cases = [
        ("defaults", base),
        ("bending B x 0.2", base.with_(rope=rope.with_(bending_stiffness_n_m2=rope.bending_stiffness_n_m2 * 0.2))),
        ("bending B x 5", base.with_(rope=rope.with_(bending_stiffness_n_m2=rope.bending_stiffness_n_m2 * 5))),
        ("normal drag C_n x 0.5", base.with_(rope=rope.with_(normal_drag_coeff=rope.normal_drag_coeff * 0.5))),
        ("normal drag C_n x 2", base.with_(rope=rope.with_(normal_drag_coeff=rope.normal_drag_coeff * 2))),
        ("axial stiffness EA x 0.5", base.with_(rope=rope.with_(axial_stiffness_n=rope.axial_stiffness_n * 0.5))),
        ("axial stiffness EA x 4", base.with_(rope=rope.with_(axial_stiffness_n=rope.axial_stiffness_n * 4))),
        ("no compression stiffness", base.with_(rope=rope.with_(compression_stiffness_ratio=0.0))),
        ("bending damping off", base.with_(rope=rope.with_(bending_damping_s=0.0))),
        ("segment 1.25 cm", base.with_(numerics=NumericsParams(segment_length_m=0.0125))),
        ("segment 5 cm", base.with_(numerics=NumericsParams(segment_length_m=0.05))),
    ]
    for name, params in cases:
        log(f"sensitivity: {name}")
        try:
            v = find_takeoff_speed(params, loop_length_m=1.0, speeds_mps=speeds(True), settle_s=4.0).speed_mps
        except Exception as exc:  # noqa: BLE001
            log(f"failed: {exc}")
            v = float("nan")
        print(f"  {name:28s}: v* = {v:.3f} m/s")
    from robowrangler_sim.string_shooter.shape_export import steady_contour_xz_m
    print("  shape (2 m loop, phi 0) when the exit cannot push (compression stiffness 0) versus the default 1 %:")
    for v in (5.0, 8.0):
        row = []
        for ratio in (0.01, 0.1, 0.0):
            p = base.with_(rope=rope.with_(compression_stiffness_ratio=ratio))
            sim = StringShooter(p, loop_length_m=2.0, motion=ModuleMotion(wheel_speed_mps=v))
            sim.step_for(4.0)
            c = steady_contour_xz_m(p, phi_deg=0.0, rope_speed_mps=v, loop_length_m=2.0, n_points=80, settle_s=5.0)
            row.append(f"{ratio:g}: reach {reach_m(c):.2f} m, roundness {roundness(c):.2f}, exit tension "
                       f"{1e3 * sim.segment_tensions_n()[0]:+.1f} mN")
        print(f"    v = {v} m/s  " + " | ".join(row))
    sim = StringShooter(base, loop_length_m=2.0, motion=ModuleMotion(wheel_speed_mps=8.0))
    sim.step_for(4.0)
    ten = sim.segment_tensions_n()
    print(f"  (2 m loop at 8 m/s: tension {1e3 * ten.min():.1f} .. {1e3 * ten.max():.1f} mN, max strain "
          f"{100 * ten.max() / base.rope.axial_stiffness_n:.2f} % at EA = {base.rope.axial_stiffness_n} N)")


def bench_recording(args, plots):
    import json
    import tempfile

    from robowrangler.recorder import read_recording
    from robowrangler_sim.string_shooter.recording import record_string_shooter
    from robowrangler_sim.string_shooter.recording_script import RecordingScript

    print("\n## Recording (SIL firmware + drive/spindle plants in lockstep, rope beside them, 30 Hz camera, "
          "100 Hz plant truth, MCAP)")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "default.mcap"
        s = record_string_shooter(path, script=RecordingScript.default(), seed=0, progress=True)
        rec = read_recording(path)
        size_kb = path.stat().st_size / 1024
    tov = json.loads(rec.metadata["/device/params"]["tov_mps"])
    tel = rec.telemetry
    above_s = float(tel["time_s"][tel["rope_speed_mps"] > tov][0])
    print(f"  {s.duration_s:g} s simulated in {s.wall_s:.1f} s wall = {s.sim_s_per_wall_s:.2f} sim s / wall s, "
          f"{size_kb:.0f} KiB")
    print(f"  messages: {s.telemetry} telemetry, {s.events} events, {s.commands} commands, {s.gaps} gaps, "
          f"{s.observations} observations, {s.plant_truth} plant truth")
    print(f"  firmware telemetry above ToV {tov} m/s from {above_s:.2f} s; camera sees the loop flying from "
          f"{s.first_airborne_s:.2f} s (lift-off takes {s.first_airborne_s - above_s:.2f} s)")


def save_plots(plots, plot_dir: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plot_dir.mkdir(parents=True, exist_ok=True)
    if "takeoff" in plots:
        r = plots["takeoff"]
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(r.speeds_mps, r.depth_fraction, "o-")
        ax.axvline(r.speed_mps, color="k", ls="--", label=f"takeoff {r.speed_mps:.2f} m/s")
        ax.set_xlabel("rope speed [m/s]"), ax.set_ylabel("depth / (L/2)"), ax.legend(), ax.grid()
        fig.savefig(plot_dir / "takeoff.png", dpi=100)
    if "shape" in plots:
        fig, axs = plt.subplots(1, 3, figsize=(15, 5))
        for ax, v in zip(axs, (4.0, 5.0, 8.0)):
            for (vv, phi), c in plots["shape"].items():
                if vv == v:
                    ax.plot(c[:, 0], c[:, 1], label=f"{phi:+d} deg")
            ax.set_aspect("equal"), ax.grid(), ax.legend(fontsize=7), ax.set_title(f"{v} m/s")
        fig.savefig(plot_dir / "shapes.png", dpi=100)
    print(f"\nplots written to {plot_dir}", file=sys.stderr)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="coarser sweeps")
    ap.add_argument("--only", default=",".join(SECTIONS), help=f"comma-separated subset of {','.join(SECTIONS)}")
    ap.add_argument("--plot-dir", type=Path, default=None, help="also save PNG figures here")
    args = ap.parse_args(argv)
    chosen = [s.strip() for s in args.only.split(",") if s.strip()]
    unknown = [s for s in chosen if s not in SECTIONS]
    if unknown:
        ap.error(f"--only: unknown section(s) {unknown}; expected some of {list(SECTIONS)}")
    plots = {}
    t0 = time.perf_counter()
    for name in chosen:
        globals()[f"bench_{name}"](args, plots)
        sys.stdout.flush()
    print(f"\n(total {time.perf_counter() - t0:.0f} s wall)")
    if args.plot_dir:
        save_plots(plots, args.plot_dir)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
