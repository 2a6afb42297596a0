"""Proof of `wrangler diagnose` on the rope loop: recordings from the first-principles string shooter (the truth,
richer than the chain) with one physical change concealed in each (under the contour noise, in one speed band only,
confounded with the shape table at a single speed) and effect-free ones, diagnosed blind against the chain's loop.

    uv run --locked python bench/bench_diagnose_loop.py                 # development seeds
    uv run --locked python bench/bench_diagnose_loop.py --heldout       # the held-out seeds (run once, at the end)
    uv run --locked python bench/bench_diagnose_loop.py --only fig6a    # the paper's Fig. 6a, quantitative (PNG)
    uv run --locked python bench/bench_diagnose_loop.py --only speed    # a 60 s recording: diagnosis wall time
    uv run --locked python bench/bench_diagnose_loop.py --only chain    # the fast form vs MuJoCo's chain plant
    uv run --locked python bench/bench_diagnose_loop.py --only interp   # the table in speed vs the truth; v^2 C_f
    uv run --locked python bench/bench_diagnose_loop.py --only headwind # head winds: compression, reach, flutter
    uv run --locked python bench/bench_diagnose_loop.py --seeds 1 2 3 --cases cf_table_confounded --candidates

Prints per case: truth, verdict, named effect, parameter error, held-out contour error before -> after, the located
part; then the table: named where identifiable, false alarms, median parameter error, held-out error ratio, and the
baselines side by side (the chain's own parameters refitted, with and without its shape table; PySINDy's sparse
regression on the contour residuals). --only chain: the judged fast form against MuJoCo's chain plant. --only
interp: the laws' speed dependence (the table continued in 1 / v^2) and the interpolation in v it replaced, against
effect-free steady truths between and below the table's speeds; and whether the truth obeys the v^2 C_f similarity
the C_f law rests on. --only headwind: what a head wind does to the truth's loop (compression, reach, flutter) and
to the wind law, and what the diagnosis answers. --cases restricts the proof to named cases, --candidates prints each candidate table.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from robowrangler_sim.diagnose import DiagnoseError
from robowrangler_sim.diagnose.loop import diagnose_loop
from robowrangler_sim.diagnose.loop.proof import LoopScript, LoopTruth, generate_loop_recording

CF0 = 0.08478874859262518
B0 = 5.0e-7
"""The string shooter's (and the shape table's) rope bending stiffness, N m^2."""
DEV_SEEDS = [1, 2, 3]
HELDOUT_SEEDS = [18524, 33976, 95918]  # drawn at random for this round (earlier rounds looked at: 19909, 37709,
# 86444; 18193, 76096, 89490; 901-903; 55529, 95904, 54682; 43441, 24071, 47917; 47849, 12577, 79749; 12188, 14125,
# 15037: run on this round's engine before its turn-only split)
"""Drawn at random (secrets.randbelow) for the final engine, never used before; 18193, 76096, 89490 and 901-903
were earlier held-out sets, now looked at."""


def _cases(seed: int):
    """(name, truth, script, kwargs, identifiable effect, truth parameter name/value) for one seed."""
    rng = np.random.default_rng(seed)
    phi = float(rng.uniform(-0.15, 0.35))
    d = 5.0
    table_v = float(rng.choice([4.0, 5.0]))
    steady = LoopScript(d, ((0.0, table_v),), ((0.0, phi),))
    out = []
    out.append(("none", LoopTruth(None), steady, {}, None, None))
    out.append(("none_slow_tilt", LoopTruth(None), LoopScript(d, ((0.0, 5.0),), ((0.0, phi), (d, phi + 0.05))), {},
                None, None))
    # speed dependence, in one speed band only: a table speed, then a speed inside one band
    v2 = float(rng.uniform(4.3, 4.8))
    out.append(("speed_one_band", LoopTruth("loop_speed_dependence"),
                LoopScript(d + 1, ((0.0, 4.0), (2.0, 4.0), (2.5, v2)), ((0.0, phi),)), {}, "loop_speed_dependence", None))
    # C_f, confounded with the shape table (one speed, one phi: it looks like a table error)
    f = float(rng.choice([rng.uniform(0.8, 0.9), rng.uniform(1.12, 1.3)]))
    out.append(("cf_table_confounded", LoopTruth("axial_drag_coefficient", cf_factor=f), steady, {},
                "axial_drag_coefficient", ("skin_friction_coeff", CF0 * f)))
    # C_f under the contour noise: a few per cent, each point's change below the camera's 2 mm
    f2 = float(rng.choice([0.96, 1.04]))
    out.append(("cf_under_noise", LoopTruth("axial_drag_coefficient", cf_factor=f2), steady, {"noise_m": 0.004},
                "axial_drag_coefficient", ("skin_friction_coeff", CF0 * f2)))
    w = float(rng.choice([-1.0, 1.0]) * rng.uniform(1.0, 2.0))
    out.append(("wind", LoopTruth("uniform_wind", wind_mps=w), steady, {}, "uniform_wind", ("wind_speed_mps", w)))
    a = float(rng.uniform(0.25, 0.4))
    out.append(("fast_turns", LoopTruth("transient_wave_dynamics"),
                LoopScript(d, ((0.0, 5.0),), ((0.0, 0.0), (1.3, 0.0), (1.7, a), (3.0, a), (3.4, 0.0))), {},
                "transient_wave_dynamics", None))
    out.append(("stiff_rope", LoopTruth("tip_bending_stiffness", bending_factor=20.0), steady, {},
                "tip_bending_stiffness", ("bending_stiffness_n_m2", B0 * 20.0)))
    # two effects together: C_f changed, flown at a table speed (2.5 s airborne) and then between the table's speeds
    # (where the truth's continuous speed dependence shows too); one effect alone does not suffice
    f3 = float(rng.choice([rng.uniform(0.75, 0.85), rng.uniform(1.15, 1.3)]))
    v3 = float(rng.uniform(4.3, 4.7))
    out.append(("cf_between_speeds", LoopTruth("axial_drag_coefficient", cf_factor=f3),
                LoopScript(d + 2, ((0.0, 4.0), (3.5, 4.0), (4.0, v3)), ((0.0, phi),)), {},
                "axial_drag_coefficient+loop_speed_dependence", ("skin_friction_coeff", CF0 * f3)))
    br = str(rng.choice(["upper_branch", "lower_branch"]))
    out.append((f"bump_{br}", LoopTruth(None), steady, {"branch_bump_m": 0.015, "branch": br}, None, None))
    return out


def _sindy_baseline(res) -> float:
    import warnings

    warnings.filterwarnings("ignore", module="pysindy")
    return _sindy(res)


def _sindy(res) -> float:
    """PySINDy's sparse regression (STLSQ on a degree-2 polynomial library of phi, v, dphi/dt) of the refit residual's
    three principal modes, fitted on the fit frames; held-out contour RMS (mm) after subtracting its prediction."""
    import pysindy as ps

    s = res.series
    replay = s["replay"]
    d = replay.data
    F, K = d.points_m.shape[:2]
    r = s["rms_before_mm"]  # noqa: F841 - kept for the reader: the refit's per-frame error
    meas = replay.measured()["contour_normal_m"].reshape(F, K)
    pred = replay.predict(s["refit_theta"][None, :])["contour_normal_m"][0].reshape(F, K)
    resid = meas - pred
    held = s["heldout"]
    fit = ~held
    try:
        u, sv, vt = np.linalg.svd(resid[fit] - resid[fit].mean(0), full_matrices=False)
        modes = vt[:3]
        amp = (resid - resid[fit].mean(0)) @ modes.T
        x = np.column_stack([d.phi_rad, d.speed_mps, replay.phidot_rad_s])
        lib = ps.PolynomialLibrary(degree=2)
        lib.fit(x[fit])
        theta = lib.transform(x)
        opt = ps.STLSQ(threshold=1e-4, alpha=1e-6)
        opt.fit(np.asarray(theta[fit]), amp[fit])
        amp_hat = np.asarray(theta) @ opt.coef_.T
        r_hat = resid[fit].mean(0) + amp_hat @ modes
        return float(np.sqrt(np.mean((resid[held] - r_hat[held]) ** 2)) * 1e3)
    except Exception as err:  # noqa: BLE001 - a baseline that fails is reported as such
        print(f"  PySINDy baseline failed: {type(err).__name__}: {err}", file=sys.stderr)
        return float("nan")


def _table_refit_baseline(res) -> float:
    """The chain's own parameters and its shape table refitted: after the servo / length refit, the table's contour
    corrected by the mean normal residual of the fit frames in each cell of 5 deg of phi x the table's speed bands
    (what re-identifying the table from these contours would give); held-out contour RMS (mm)."""
    s = res.series
    replay = s["replay"]
    d = replay.data
    F, K = d.points_m.shape[:2]
    resid = (replay.measured()["contour_normal_m"].reshape(F, K)
             - replay.predict(s["refit_theta"][None, :])["contour_normal_m"][0].reshape(F, K))
    held = s["heldout"]
    speeds = replay.model.speeds
    cell = (np.floor(np.rad2deg(d.phi_rad) / 5.0).astype(int) * 100
            + np.clip(np.searchsorted(speeds, d.speed_mps, side="right") - 1, 0, speeds.size - 1))
    corr = np.zeros_like(resid)
    for c in np.unique(cell):
        m_fit, m_all = (cell == c) & ~held, cell == c
        if m_fit.any():
            corr[m_all] = resid[m_fit].mean(axis=0)
    return float(np.sqrt(np.mean((resid[held] - corr[held]) ** 2)) * 1e3)


def run_proof(seeds: list[int], out_dir: Path, *, cases: list[str] | None = None, candidates: bool = False) -> None:
    rows = []
    t_gen = t_diag = 0.0
    for seed in seeds:
        for name, truth, script, kw, ident, par in _cases(seed):
            if cases and name not in cases:
                continue
            path = out_dir / f"{name}_{seed}.mcap"
            t0 = time.perf_counter()
            case = generate_loop_recording(path, truth=truth, script=script, seed=seed, **kw)
            t1 = time.perf_counter()
            try:
                res = diagnose_loop(path)
            except DiagnoseError as err:  # the truth left the model's domain (e.g. a loop shorter than the guide's)
                print(f"{name:22s} seed {seed:4d}: refused ({type(err).__name__}): {err}", flush=True)
                rows.append(dict(name=name, seed=seed, truth=ident, verdict="refused", refused=type(err).__name__,
                                 named=None, perr=None, first=None,
                                 before=math.nan, after=math.nan, sindy=math.nan, table=math.nan, part=None,
                                 true_part=case.true_part,
                                 noise=math.nan, wall=time.perf_counter() - t1))
                continue
            t2 = time.perf_counter()
            t_gen += t1 - t0
            t_diag += t2 - t1
            res.series["refit_theta"] = _refit_theta(res)
            named = "+".join(sorted(e.effect_id for e in res.effects)) if res.effects else None
            if res.verdict == "not_identifiable":
                named = "/".join(res.not_identifiable[0]["candidates"])
            before = res.candidates[0]["heldout_rms_mm"]
            after = res.effects[0].heldout_rms_mm_after if res.effects else before
            perr = None
            found = [e.params[par[0]] for e in res.effects if par is not None and par[0] in e.params]
            if found:
                perr = abs(found[0]["value"] - par[1]) / abs(par[1])
            sindy = _sindy_baseline(res)
            table = _table_refit_baseline(res)
            rows.append(dict(name=name, seed=seed, truth=ident, verdict=res.verdict, named=named, perr=perr,
                             first=res.effects[0].effect_id if res.effects else None,
                             before=before, after=after, sindy=sindy, table=table, part=res.located["part"],
                             true_part=case.true_part, noise=res.noise_mm, wall=t2 - t1))
            pe = f"{perr:.1%}" if perr is not None else "-"
            print(f"{name:22s} seed {seed:4d}: {res.verdict:17s} named {str(named):46s} param err {pe:>6s}  held-out "
                  f"{before:6.1f} -> {after:6.1f} mm (table refit {table:6.1f}, PySINDy {sindy:6.1f})  part {res.located['part']}  "
                  f"noise {res.noise_mm:.1f} mm  {t2 - t1:.1f} s", flush=True)
            if candidates:
                _print_candidates(res, truth, par)
    eff = [r for r in rows if r["truth"] is not None]
    clean = [r for r in rows if r["truth"] is None and r["true_part"] is None]
    bumps = [r for r in rows if r["true_part"] is not None]
    right = [r for r in eff if r["named"] == r["truth"]]
    print("\nsummary")
    for kind in sorted({r["truth"] for r in eff}):
        k_rows = [r for r in eff if r["truth"] == kind]
        print(f"  {kind:26s} named {sum(r['named'] == kind for r in k_rows)}/{len(k_rows)}")
    print(f"  right effect named: {len(right)}/{len(eff)} ({len(right) / max(1, len(eff)):.0%}); target >= 90 % where "
          "identifiable")
    fa = [r for r in clean if r["verdict"] != "none"]
    print(f"  false alarms on effect-free: {len(fa)}/{len(clean)}; target <= 5 %")
    perrs = [r["perr"] for r in rows if r["perr"] is not None and r["named"] == r["truth"] and r["truth"] !=
             "tip_bending_stiffness"]
    berrs = [r["perr"] for r in rows if r["perr"] is not None and r["named"] == r["truth"] == "tip_bending_stiffness"]
    first = [r for r in eff if r["first"] is not None and r["first"] in r["truth"].split("+")]
    print(f"  right effect named alone or first of a pair (the single-effect step's choice): {len(first)}/{len(eff)}")
    pairs = [r for r in eff if r["named"] and "+" in r["named"]]
    print(f"  two effects named together: {len(pairs)} ({sum(r['named'] == r['truth'] for r in pairs)} of them the "
          f"two-effect truth; {sum('+' in r['truth'] for r in eff)} two-effect truths)")
    print(f"  median parameter error (C_f, wind; where named): "
          f"{np.median(perrs):.1%} over {len(perrs)}; target <= 15 %" if perrs else "  no parameter scored")
    print(f"  bending stiffness B error where tip_bending_stiffness is named: median {np.median(berrs):.1%} over "
          f"{len(berrs)} (" + ", ".join(f"{e:.0%}" for e in berrs) + ")" if berrs else "  no bending stiffness scored")
    ratio = [r["after"] / r["before"] for r in right if r["before"] > 0]
    print(f"  held-out contour error after/before where named: median {np.median(ratio):.2f}; target <= 0.5"
          if ratio else "  no held-out ratio")
    print(f"  baselines (median held-out contour error over the effect recordings, mm): chain's own parameters "
          f"refitted {np.nanmedian([r['before'] for r in eff]):.1f}, with the shape table refitted per 5 deg x speed "
          f"band {np.nanmedian([r['table'] for r in eff]):.1f}, PySINDy on the contour residuals "
          f"{np.nanmedian([r['sindy'] for r in eff]):.1f}, diagnose {np.nanmedian([r['after'] for r in eff]):.1f}")
    print(f"  located part right for one-branch effects: {sum(r['part'] == r['true_part'] for r in bumps)}/{len(bumps)}")
    refused = [r for r in rows if r["verdict"] == "refused"]
    print(f"  refused: {len(refused)} (" + ", ".join(f"{r['name']} seed {r['seed']}: {r['refused']}" for r in refused)
          + "; LoopFlutterError: a shorter loop that folds and flutters, outside the steady laws)")
    print(f"  wall: string shooter {t_gen:.0f} s, diagnosis {t_diag:.0f} s for {len(rows)} recordings")


def _print_candidates(res, truth, par) -> None:
    """The engine's candidate table for one case: status, delta BIC and held-out likelihood ratio against the refitted
    chain (a pair: against its first effect), held-out contour RMS, fitted parameters; and the truth."""
    print(f"    truth: {truth.effect_id} {par[0] + ' = ' + format(par[1], '.5g') if par else ''}; not identifiable: "
          f"{[n['candidates'] for n in res.not_identifiable if 'candidates' in n]}")
    for r in res.candidates:
        if r["status"] == "base":
            print(f"    refitted chain: held-out {r['heldout_rms_mm']:6.2f} mm, {r['heldout_excess_z']:.1f} sd above the "
                  f"camera noise's {res.noise_mm:.2f} mm")
        if r["status"] in ("base", "not_identifiable"):
            continue
        cos = f" cos {r['sensitivity_cosine']:+.2f}" if "sensitivity_cosine" in r else ""
        print(f"    {r['id']:50s} {r['status']:12s} dBIC {r['delta_bic']:8.1f} LR {r['heldout_lr']:8.1f} held-out "
              f"{r['heldout_rms_mm']:6.2f} mm{cos} {r.get('params', '')}")


def run_interp(out_dir: Path) -> None:
    """The laws' speed dependence against the truth: effect-free steady string-shooter holds (noise-free) at speeds
    the table (4, 5, 8 m/s) does not hold, the table continued in 1 / v^2 (the laws' S_lin) and interpolated in v (the
    law before), contour RMS (mm) of the mean contour; then the v^2 C_f similarity the C_f law rests on: the truth at
    (v, C_f0 f) against the truth at (v sqrt f, C_f0), and each one's frame-to-frame flutter."""
    from robowrangler.recorder import read_recording
    from robowrangler_sim.diagnose.loop import shape_model as sm
    from robowrangler_sim.diagnose.loop.data import load_loop_data
    from robowrangler_sim.diagnose.loop.model_file import LoopModel
    from robowrangler_sim.diagnose.loop.replay import LoopReplay

    base = LoopModel.nominal()
    print("table continued in speed vs the truth (mean contour RMS, mm): in 1/v^2 (the laws) | in v (before)")
    for phi, v in ((0.1, 3.6), (0.1, 3.8), (0.1, 4.3), (0.1, 4.5), (0.1, 4.7), (0.1, 5.5), (0.1, 6.0), (0.1, 7.0),
                   (-0.1, 4.5), (0.3, 4.5), (0.3, 5.5)):
        case = generate_loop_recording(out_dir / f"interp_{phi}_{v}.mcap", truth=LoopTruth(None), seed=7, noise_m=0.0,
                                       script=LoopScript(2.5, ((0.0, v),), ((0.0, phi),)))
        data = load_loop_data(case.path, takeoff_speed_mps=base.takeoff_speed_mps(),
                              loop_length_of_guide=base.loop_length_m)
        shape = base.shape_model()
        rp = LoopReplay(data, shape, np.array([base.loop_length_m(g) for g in data.guide_m]))
        th = base.theta(shape)
        th[sm.TH_SPEED_GAIN] = 1.0
        obs = data.points_m.mean(0)
        nrm = rp.normals.mean(0)
        law = rp.contours(th[None])[0].mean(0)
        sp = shape.speeds
        j = int(np.clip(np.searchsorted(sp, v, side="right") - 1, 0, sp.size - 2))
        f = float(np.clip((v - sp[j]) / (sp[j + 1] - sp[j]), -0.5, 1.5))
        ph = np.full(1, np.rad2deg(phi))
        in_v = ((1 - f) * shape._at_phi(np.full(1, j), ph) + f * shape._at_phi(np.full(1, j + 1), ph))[0]
        in_v = in_v * rp.loop_length_m.mean()

        def rms(c):
            return float(np.sqrt(np.mean(np.sum((obs - c) * nrm, -1) ** 2)) * 1e3)

        print(f"  phi {phi:+.2f} rad, {v:.1f} m/s: {rms(law):6.2f} | {rms(in_v):6.2f}", flush=True)

    def truth_mean(tag, phi, v, f):
        p = out_dir / f"sim_{tag}.mcap"
        generate_loop_recording(p, truth=LoopTruth("axial_drag_coefficient" if f != 1 else None, cf_factor=f), seed=7,
                                noise_m=0.0, script=LoopScript(3.0, ((0.0, v),), ((0.0, phi),)))
        pts = np.array([r.data["points_m"] for r in read_recording(p).records["/loop/observation"]][-45:])
        return pts.mean(0), float(np.sqrt(np.mean(np.sum((pts - pts.mean(0)) ** 2, -1))) * 1e3)

    print("v^2 C_f similarity: truth at (v, f C_f0) vs truth at (v sqrt f, C_f0), mean contours RMS (mm); flutter of "
          "each (RMS about its mean, mm)")
    for phi, v, f in ((0.1, 4.0, 0.81), (0.1, 4.0, 1.2), (0.1, 5.0, 0.8), (0.1, 5.0, 1.2), (0.1, 5.0, 1.3),
                      (0.3, 5.0, 1.2)):
        a, ja = truth_mean("a", phi, v, f)
        b, jb = truth_mean("b", phi, v * math.sqrt(f), 1.0)
        d = float(np.sqrt(np.mean(np.sum((a - b) ** 2, -1))) * 1e3)
        print(f"  phi {phi:+.2f} rad, {v:.1f} m/s, C_f x {f:.2f} vs {v * math.sqrt(f):.2f} m/s: {d:6.2f} mm; flutter "
              f"{ja:.1f} / {jb:.1f} mm", flush=True)


def _refit_theta(res) -> np.ndarray:
    from robowrangler_sim.diagnose.loop import shape_model as sm

    th = np.asarray(res.series["nominal_theta"]).copy()
    th[sm.TH_TAU_S] = res.nominal_refit["servo_time_constant_s"]["fitted"]
    th[sm.TH_LEN_SCALE] = res.nominal_refit["loop_length_scale"]["fitted"]
    return th


def run_fig6a(out_dir: Path, png: Path) -> None:
    """The module turned slowly (20 deg over 4 s) and fast (20 deg in 0.4 s): the chain before and after diagnosis
    (the model the fast recording yields) against the string-shooter truth, contour error over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from robowrangler_sim.diagnose.loop.api import CHANNEL

    a = math.radians(20.0)
    scripts = {"slow": LoopScript(8.0, ((0.0, 5.0),), ((0.0, 0.0), (1.5, 0.0), (5.5, a), (8.0, a))),
               "fast": LoopScript(8.0, ((0.0, 5.0),), ((0.0, 0.0), (1.5, 0.0), (1.9, a), (4.5, a), (4.9, 0.0)))}
    fast = generate_loop_recording(out_dir / "fig6a_fast.mcap", truth=LoopTruth("transient_wave_dynamics"),
                                   script=scripts["fast"], seed=61)
    res_fast = diagnose_loop(fast.path)
    print(f"fast turns: {res_fast.first_line}")
    _print_candidates(res_fast, LoopTruth("transient_wave_dynamics"), None)
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for i, (name, script) in enumerate(scripts.items()):
        path = fast.path if name == "fast" else generate_loop_recording(
            out_dir / "fig6a_slow.mcap", truth=LoopTruth(None), script=script, seed=62).path
        res = res_fast if name == "fast" else diagnose_loop(path)
        rp = res.series["replay"]
        F, K = rp.data.points_m.shape[:2]
        meas = rp.measured()[CHANNEL].reshape(F, K)
        before = np.sqrt(np.mean((meas - rp.predict(res.series["nominal_theta"][None])[CHANNEL][0].reshape(F, K)) ** 2,
                                 axis=1)) * 1e3
        th_after = res.series["nominal_theta"].copy()
        for e in res_fast.effects:  # the model the fast recording yielded, applied to both
            from robowrangler_sim.diagnose.loop.model_file import EFFECT_COLUMNS
            for pname, col in EFFECT_COLUMNS[e.effect_id].items():
                th_after[col] = e.params[pname]["value"]
        after = np.sqrt(np.mean((meas - rp.predict(th_after[None])[CHANNEL][0].reshape(F, K)) ** 2, axis=1)) * 1e3
        ax[i].plot(rp.data.time_s, before, label=f"chain (nominal): mean {before.mean():.1f} mm")
        ax[i].plot(rp.data.time_s, after, label=f"chain + diagnosed effect: mean {after.mean():.1f} mm")
        ax[i].axhline(res.noise_mm, color="0.5", ls="--", label="camera noise")
        ax[i].set_title(f"module turned {'slowly (20 deg in 4 s)' if name == 'slow' else 'fast (20 deg in 0.4 s)'}: "
                        f"string-shooter truth vs the chain")
        ax[i].set_ylabel("contour error RMS [mm]")
        ax[i].legend(loc="upper right", fontsize=8)
        print(f"{name}: contour error mean {before.mean():.1f} -> {after.mean():.1f} mm, max {before.max():.1f} -> "
              f"{after.max():.1f} mm")
    ax[1].set_xlabel("time [s]")
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=90)
    plt.close(fig)
    print(f"wrote {png}")


def run_chain(out_dir: Path) -> None:
    """The judged replay's error: diagnose judges the chain's fast form (the shape table at phi and speed through the
    servos' first-order lag), not MuJoCo's chain plant. On effect-free string-shooter recordings (a steady hold, the
    Fig. 6a slow and fast 20 deg turns), the chain plant driven by the same rope speed and phi, against the fast form
    and against the truth: contour RMS (mean point distance, 40 points by arc length) per airborne frame."""
    from robowrangler.recorder import read_recording
    from robowrangler_sim.chain.default_table import load_default_shape_table
    from robowrangler_sim.chain.params import ChainParams
    from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
    from robowrangler_sim.shape_table import resample_by_arc_length

    a = math.radians(20.0)
    scripts = {"steady (phi 0.1 rad, 5 m/s)": LoopScript(6.0, ((0.0, 5.0),), ((0.0, 0.1),)),
               "slow turn (20 deg in 4 s)": LoopScript(8.0, ((0.0, 5.0),), ((0.0, 0.0), (1.5, 0.0), (5.5, a), (8.0, a))),
               "fast turn (20 deg in 0.4 s)": LoopScript(8.0, ((0.0, 5.0),), ((0.0, 0.0), (1.5, 0.0), (1.9, a), (4.5, a),
                                                                             (4.9, 0.0)))}
    table, prm = load_default_shape_table(), ChainParams()

    def rms(x, y):
        return np.sqrt(np.mean(np.sum((x - y) ** 2, axis=-1), axis=-1)) * 1e3

    print("contour RMS per airborne frame, mean / max (mm): chain plant vs fast form | truth vs fast form | "
          "truth vs chain plant")
    for i, (name, script) in enumerate(scripts.items()):
        case = generate_loop_recording(out_dir / f"chain_{i}.mcap", truth=LoopTruth(None), script=script, seed=70 + i,
                                       noise_m=0.0)
        res = diagnose_loop(case.path, effects=[])
        rp = res.series["replay"]
        fast = rp.contours(res.series["nominal_theta"][None])[0]
        rows = sorted((r.data for r in read_recording(case.path).records["/loop/observation"]),
                      key=lambda r: r["time_s"])
        first = rows[0]
        plant = ChainPlant(table=table, params=prm, initial=PlantInputs(rope_speed_mps=first["rope_speed_mps"]))
        plant.advance(PlantInputs(rope_speed_mps=first["rope_speed_mps"],
                                  base_quat_wxyz=pitch_quat_wxyz(first["phi_rad"])), duration_s=3.0)
        chain_at = {}
        t_prev = first["time_s"]
        for r in rows:
            plant.advance(PlantInputs(rope_speed_mps=r["rope_speed_mps"], base_quat_wxyz=pitch_quat_wxyz(r["phi_rad"])),
                          duration_s=max(r["time_s"] - t_prev, 0.0))
            t_prev = r["time_s"]
            chain_at[round(r["time_s"], 6)] = resample_by_arc_length(plant.chain_points_loop_plane_m(), fast.shape[1])
        chain = np.array([chain_at[round(t, 6)] for t in rp.data.time_s])
        obs = rp.data.points_m
        cf, tf, tc = rms(chain, fast), rms(obs, fast), rms(obs, chain)
        print(f"  {name:28s} {cf.mean():6.1f} / {cf.max():6.1f} | {tf.mean():6.1f} / {tf.max():6.1f} | "
              f"{tc.mean():6.1f} / {tc.max():6.1f}", flush=True)


def run_speed(out_dir: Path) -> None:
    """A 60 s recording with 30 Hz contours (speed holds, tilts and turns) diagnosed against the whole loop library."""
    rng = np.random.default_rng(5)
    knots_v = [(0.0, 5.0)] + [(t, float(rng.choice([4.0, 4.5, 5.0, 6.0]))) for t in range(6, 60, 6)]
    sp = []
    for (t, v) in knots_v:
        sp += [(t, v), (t + 5.5, v)]
    phis = [(0.0, 0.0)] + [(t, float(rng.uniform(-0.2, 0.4))) for t in range(4, 60, 4)]
    script = LoopScript(60.0, tuple(sp), tuple(phis))
    t0 = time.perf_counter()
    case = generate_loop_recording(out_dir / "long60.mcap", truth=LoopTruth("axial_drag_coefficient", cf_factor=1.2),
                                   script=script, seed=60)
    t1 = time.perf_counter()
    res = diagnose_loop(case.path)
    t2 = time.perf_counter()
    print(f"60 s recording ({res.frames} airborne frames): string shooter {t1 - t0:.0f} s, diagnosis {t2 - t1:.1f} s "
          f"wall (target <= 120 s on 2 cores); {res.first_line}")
    print("  stage timings: " + ", ".join(f"{k} {v:.1f}" for k, v in res.timings_s.items()))


def run_headwind(out_dir: Path) -> None:
    """Head and tail winds on the string shooter (development seeds 11-18, never the held-out ones): per wind, the
    truth's exit tension T and share of compressed rope segments, its reach against the still-air loop's and the wind
    law's at the true wind, the contour's length ratio and flutter unevenness (diagnose/loop/flutter.py), and what
    the diagnosis answers."""
    from robowrangler_sim.diagnose.loop.data import load_loop_data
    from robowrangler_sim.diagnose.loop.flutter import contour_scatter
    from robowrangler_sim.diagnose.loop.model_file import LoopModel
    from robowrangler_sim.diagnose.loop.proof import SETTLE_S
    from robowrangler_sim.diagnose.loop.replay import LoopReplay
    from robowrangler_sim.diagnose.loop.wind_load import wind_displacement_m
    from robowrangler_sim.string_shooter.model import StringShooter
    from robowrangler_sim.string_shooter.motion import ModuleMotion

    base = LoopModel.nominal()
    shape = base.shape_model()
    rope = base.chain.rope
    print("v m/s, phi rad, wind m/s: truth T_exit mN, compressed share | reach m: still air, truth, wind law | contour "
          "length ratio, flutter unevenness (flutters at >= 2) | diagnosis")
    conds = ((11, 5.0, 0.1, 1.8), (12, 5.0, 0.1, -0.5), (13, 5.0, 0.1, -0.8), (14, 5.0, 0.1, -1.0),
             (15, 5.0, 0.1, -1.8), (16, 4.0, -0.1, -1.5), (17, 4.5, -0.1, -1.2), (18, 6.0, 0.0, -1.5))
    for seed, v, phi, w in conds:
        script = LoopScript(5.0, ((0.0, v),), ((0.0, phi),))
        truth = LoopTruth("uniform_wind", wind_mps=w)
        sh = StringShooter(truth.params(), loop_length_m=2.0, initial_shape="circle",
                           motion=ModuleMotion(wheel_speed_mps=script.speed, phi_rad=script.phi))
        sh.step_for(SETTLE_S)
        t_exit, compressed = [], []
        for _ in range(10):
            sh.step_for(0.1)
            t_exit.append(sh.frame().exit_tension_n)
            compressed.append(float(np.mean(sh.segment_tensions_n() < 0.0)))
        case = generate_loop_recording(out_dir / f"headwind_{seed}.mcap", truth=truth, script=script, seed=seed)
        data = load_loop_data(case.path, takeoff_speed_mps=base.takeoff_speed_mps(),
                              loop_length_of_guide=base.loop_length_m, defer_short_loop=True)
        rp = LoopReplay(data, shape, np.array([base.loop_length_m(g) for g in data.guide_m]))
        sc = contour_scatter(data.points_m, rp.normals, data.segment)
        still = shape._steady_unit(shape.theta0()[None], np.array([[math.degrees(phi)]]), np.array([[v]]))[0] * 2.0
        law = still + wind_displacement_m(still, speed_mps=[v], wind_mps=w, rope=rope)
        try:
            res = diagnose_loop(case.path)
            said = f"{res.verdict}: " + ", ".join(f"{e.effect_id} " + " ".join(f"{k} {p['value']:.3g}" for k, p in
                                                                               e.params.items()) for e in res.effects)
        except DiagnoseError as err:
            said = f"refused: {type(err).__name__}"
        print(f"  {v:.1f}, {phi:+.1f}, {w:+.1f}: {np.mean(t_exit) * 1e3:+5.1f} mN, {np.mean(compressed):4.0%} | "
              f"{still[0, :, 0].max():.2f}, {np.median(data.points_m[:, :, 0].max(axis=1)):.2f}, "
              f"{law[0, :, 0].max():.2f} | {data.length_ratio:.3f}, {sc.unevenness:.2f} | {said}", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--heldout", action="store_true", help="run the held-out seeds (once, at the end)")
    ap.add_argument("--only", choices=("proof", "fig6a", "speed", "chain", "interp", "headwind"), default="proof")
    ap.add_argument("--seeds", type=int, nargs="*", default=None)
    ap.add_argument("--cases", nargs="*", default=None, help="proof case names to run (default: all), e.g. "
                    "cf_table_confounded cf_under_noise cf_between_speeds none none_slow_tilt")
    ap.add_argument("--candidates", action="store_true", help="print each case's candidate table and truth")
    ap.add_argument("--png", type=Path, default=Path("docs/figures/diagnose_loop_fig6a.png"))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_loop_") as tmp:
        out = Path(tmp)
        if args.only == "fig6a":
            run_fig6a(out, args.png)
        elif args.only == "speed":
            run_speed(out)
        elif args.only == "chain":
            run_chain(out)
        elif args.only == "interp":
            run_interp(out)
        elif args.only == "headwind":
            run_headwind(out)
        else:
            seeds = args.seeds or (HELDOUT_SEEDS if args.heldout else DEV_SEEDS)
            print(f"seeds {seeds} ({'held-out' if args.heldout else 'development'})")
            run_proof(seeds, out, cases=args.cases, candidates=args.candidates)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
