"""The spindle half of the diagnose proof: generated recordings (proof/spindle_cases.py) with a concealed truth
spindle effect (or none), diagnosed blind on the spindle channels (diagnose/spindle_stage.py, which reads only
/device/telemetry). Scored: named (top-1), confusion, key-parameter error and 95 % interval coverage, held-out
load / guide-motion RMS before (nominal refit) / after, false alarms on effect-free runs, wall time per recording.

Two seed sets: dev (looked at while building) and heldout (run once, at the end); printed separately.

Run:  uv run --locked python bench/bench_diagnose_spindle.py [--set dev|heldout|both] [--json OUT]
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
HELDOUT_SEEDS = [9001, 9002, 9003]
DEV_CLEAN = list(range(201, 211))
HELDOUT_CLEAN = list(range(9201, 9211))


def run_case(case, tmp: Path) -> dict:
    t0 = time.perf_counter()
    truth = case.generate(tmp / f"{case.name.replace('/', '_')}.mcap")
    t1 = time.perf_counter()
    res = diagnose_spindle(truth.path, base=SpindleParams(), candidates=[c() for c in SPINDLE_LIBRARY.values()])
    row = {"name": case.name, "effect": case.effect_id, "concealment": case.concealment, "verdict": res.verdict,
           "named": list(res.chosen), "gen_s": t1 - t0, "diag_s": time.perf_counter() - t1,
           "rms_before": res.heldout_rms_before, "rms_after": res.heldout_rms_after}
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
          f"{'load RMS before->after':>24s} {'guide um/0.1s':>16s}")
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
        print(f"{e:16s} {c:12s} {len(rs):2d} {named:3d}/{len(rs):<2d} "
              f"{(f'{100 * np.median(errs):.0f} %' if errs else '-'):>8s} "
              f"{(f'{sum(cov)}/{len(cov)}' if cov else '-'):>7s} {lb:10.1f} -> {la:5.1f} per mille "
              f"{gb:6.1f} -> {ga:5.1f}")
    eff = [r for r in rows if r["effect"]]
    named = sum(r["effect"] in r["named"] for r in eff)
    errs = [r["err"] for r in eff if "err" in r]
    cov = [r["covered"] for r in eff if "covered" in r]
    clean = [r for r in rows if not r["effect"]]
    fa = sum(r["verdict"] != "none" for r in clean)
    conf = Counter((r["effect"], "+".join(r["named"]) or r["verdict"]) for r in eff)
    print(f"named {named}/{len(eff)}; median parameter error {100 * np.median(errs) if errs else float('nan'):.0f} %; "
          f"95 % CI covers the truth {sum(cov)}/{len(cov)}; false alarms {fa}/{len(clean)} effect-free")
    print("confusion (truth -> answer):", dict(conf))
    print(f"wall per recording: generate {np.mean([r['gen_s'] for r in rows]):.1f} s, "
          f"diagnose (spindle half) {np.mean([r['diag_s'] for r in rows]):.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--set", choices=("dev", "heldout", "both"), default="dev")
    ap.add_argument("--json")
    args = ap.parse_args()
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for label, seeds, clean in (("dev", DEV_SEEDS, DEV_CLEAN), ("heldout", HELDOUT_SEEDS, HELDOUT_CLEAN)):
            if args.set not in (label, "both"):
                continue
            rows = [run_case(c, Path(d)) for c in spindle_proof_cases(seeds=seeds, clean_seeds=clean)]
            table(rows, f"spindle proof, {label} seeds")
            out[label] = rows
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1, default=float))


if __name__ == "__main__":
    main()
