"""The spindle half of the diagnose proof: generated recordings (proof/spindle_cases.py) with a concealed truth
spindle effect (or none), diagnosed blind on the spindle channels (diagnose/spindle_stage.py, which reads only
/device/telemetry). Scored: named (top-1), confusion, key-parameter error and 95 % interval coverage, held-out
load / guide-motion RMS before (nominal refit) / after, false alarms on effect-free runs, wall time per recording;
whether each effect is identifiable from its recording at all (proof/spindle_oracle.py: the truth's own candidate
under the engine's rule; `--no-oracle` skips it) and how many of the identifiable ones were named.

Two seed sets: dev (looked at while building) and heldout (run once, at the end); printed separately.

Run:  uv run --locked python bench/bench_diagnose_spindle.py [--set dev|heldout|both] [--only ID,...] [--no-oracle]
      [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from robowrangler_sim.diagnose.candidates import SPINDLE_LIBRARY
from robowrangler_sim.diagnose.proof.spindle_cases import KEY_PARAM, spindle_proof_cases
from robowrangler_sim.diagnose.spindle_stage import diagnose_spindle
from robowrangler_sim.plants.spindle import SpindleParams

DEV_SEEDS = [1, 2, 3]
HELDOUT_SEEDS = [24748, 96423, 46480]  # drawn at random for this round (9001-9003, 9201-9210, 11091, 27738, 60861,
# 36818-36827: looked at)
DEV_CLEAN = list(range(201, 211))
HELDOUT_CLEAN = list(range(39789, 39799))


def run_case(case, tmp: Path, oracle: bool = True) -> dict:
    t0 = time.perf_counter()
    truth = case.generate(tmp / f"{case.name.replace('/', '_')}.mcap")
    t1 = time.perf_counter()
    res = diagnose_spindle(truth.path, base=SpindleParams(), candidates=[c() for c in SPINDLE_LIBRARY.values()])
    row = {"name": case.name, "effect": case.effect_id, "concealment": case.concealment, "verdict": res.verdict,
           "named": list(res.chosen), "gen_s": t1 - t0, "diag_s": time.perf_counter() - t1,
           "rms_before": res.heldout_rms_before, "rms_after": res.heldout_rms_after}
    if oracle and res.nominal_basis is not None:  # identifiable from this recording at all? (proof/spindle_oracle.py)
        from robowrangler_sim.diagnose.proof.spindle_oracle import judge_spindle

        row.update(judge_spindle(truth, res).row())
    if case.effect_id in res.chosen:
        key = KEY_PARAM[case.effect_id]
        p = next(e for e in res.effects if e.effect_id == case.effect_id).params[key]
        true = truth.truth[key]
        row.update(param=p["value"], truth=true, err=abs(p["value"] - true) / true,
                   covered=bool(p["ci95"][0] <= true <= p["ci95"][1]))
    return row


def table(rows: list[dict], label: str) -> None:
    print(f"\n== {label}: {len(rows)} recordings ==")
    print(f"{'effect':16s} {'concealment':12s} {'n':>2s} {'named':>6s} {'med err':>8s} {'CI cov':>7s} "
          f"{'load RMS before->after':>24s} {'guide um/0.1s':>16s} {'ident':>6s} {'named/ident':>11s}")
    groups = defaultdict(list)
    for r in rows:
        if r["effect"]:
            groups[(r["effect"], r["concealment"])].append(r)
    for (e, c), rs in sorted(groups.items()):
        named = sum(e in r["named"] for r in rs)
        errs = [r["err"] for r in rs if "err" in r]
        cov = [r["covered"] for r in rs if "covered" in r]
        lb = np.mean([r["rms_before"]["spindle_load_permille"] for r in rs])
        la = np.mean([r["rms_after"]["spindle_load_permille"] for r in rs])
        gb = np.mean([r["rms_before"]["guide_step_mm"] for r in rs]) * 1e3
        ga = np.mean([r["rms_after"]["guide_step_mm"] for r in rs]) * 1e3
        judged = [r for r in rs if "identifiable" in r]
        ident = [r for r in judged if r["identifiable"]]
        print(f"{e:16s} {c:12s} {len(rs):2d} {named:3d}/{len(rs):<2d} "
              f"{(f'{100 * np.median(errs):.0f} %' if errs else '-'):>8s} "
              f"{(f'{sum(cov)}/{len(cov)}' if cov else '-'):>7s} {lb:10.1f} -> {la:5.1f} per mille "
              f"{gb:6.1f} -> {ga:5.1f} "
              + (f"{len(ident):3d}/{len(judged):<2d} {sum(e in r['named'] for r in ident):7d}/{len(ident):<3d}"
                 if judged else f"{'-':>6s} {'-':>11s}"))
    eff = [r for r in rows if r["effect"]]
    named = sum(r["effect"] in r["named"] for r in eff)
    errs = [r["err"] for r in eff if "err" in r]
    cov = [r["covered"] for r in eff if "covered" in r]
    clean = [r for r in rows if not r["effect"]]
    fa = sum(r["verdict"] != "none" for r in clean)
    conf = Counter((r["effect"], "+".join(r["named"]) or r["verdict"]) for r in eff)
    print(f"named {named}/{len(eff)}; median parameter error {100 * np.median(errs) if errs else float('nan'):.0f} %; "
          f"95 % CI covers the truth {sum(cov)}/{len(cov)}; false alarms {fa}/{len(clean)} effect-free")
    judged = [r for r in eff if "identifiable" in r]
    if judged:  # the oracle (proof/spindle_oracle.py): the truth's own candidate under the engine's rule
        ident = [r for r in judged if r["identifiable"]]
        rest = [r for r in judged if not r["identifiable"]]
        n_named = sum(r["effect"] in r["named"] for r in ident)
        print(f"named of identifiable: {n_named}/{len(ident)}"
              + (f" ({n_named / len(ident):.0%})" if ident else "")
              + f"; not identifiable {len(rest)} (answered none/not_identifiable "
              f"{sum(r['verdict'] in ('none', 'not_identifiable') for r in rest)}, named anyway "
              f"{sum(r['effect'] in r['named'] for r in rest)})")
        clean_judged = [r for r in clean if "identifiable" in r]
        if clean_judged:
            print(f"oracle on effect-free recordings: the truth accepted over the nominal refit on "
                  f"{sum(r['identifiable'] for r in clean_judged)} of {len(clean_judged)} (should be 0)")
    print("confusion (truth -> answer):", dict(conf))
    print(f"wall per recording: generate {np.mean([r['gen_s'] for r in rows]):.1f} s, "
          f"diagnose (spindle half) {np.mean([r['diag_s'] for r in rows]):.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--set", choices=("dev", "heldout", "both"), default="dev")
    ap.add_argument("--json")
    ap.add_argument("--only", default=None, help="effect ids (comma-separated) to run, and no effect-free runs")
    ap.add_argument("--oracle", action=argparse.BooleanOptionalAction, default=True,
                    help="judge each recording identifiable or not with the truth (proof/spindle_oracle.py)")
    args = ap.parse_args()
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for label, seeds, clean in (("dev", DEV_SEEDS, DEV_CLEAN), ("heldout", HELDOUT_SEEDS, HELDOUT_CLEAN)):
            if args.set not in (label, "both"):
                continue
            cases = spindle_proof_cases(seeds=seeds, clean_seeds=[] if args.only else clean)
            if args.only:
                cases = [c for c in cases if c.effect_id in args.only.split(",")]
            rows = [run_case(c, Path(d), args.oracle) for c in cases]
            table(rows, f"spindle proof, {label} seeds")
            out[label] = rows
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1, default=float))


if __name__ == "__main__":
    main()
