"""The paper's Table I from the SIL: every Table I object through the firmware-driven scenario.

    uv run python -m robowrangler_sim.scenarios.table_i_sil --out docs/table_i.md     # about 2-3 minutes

Writes a markdown table: the paper's outcome, the plant-level grasp (chain/table_i.py: scripted inputs)
and the SIL (runner.py: the firmware's GRASP drives the chain), with the figures the simulation judged
by, then the door handle over several seeds (divergence of the chain is reported, not hidden).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from robowrangler_sim.chain.objects import OBJECTS
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.table_i import TABLE_I_OBJECTS, run_table_i
from robowrangler_sim.scenarios.runner import ScenarioOutcome, run_scenario

DOOR_NOISES_RAD = (0.01, 0.05)
"""Perturbed door rollouts: seeded noise on the chain's initial joint angles, rad (1 sigma; seed 0 unperturbed)."""

COMMAND = "uv run python -m robowrangler_sim.scenarios.table_i_sil --out docs/table_i.md"


def run_sil_rows(*, seed: int = 0, n_links: int = 20, progress=None) -> list[ScenarioOutcome]:
    rows = []
    for name in TABLE_I_OBJECTS:
        out = run_scenario(name, seed=seed, n_links=n_links)
        if progress is not None:
            progress(f"{name}: {out.verdict} ({out.wall_s:.1f} s)")
        rows.append(out)
    return rows


def _paper(spec) -> str:
    return {"slips": "slipped"}.get(spec.expected_outcome, spec.expected_outcome or "-")


def _why(o: ScenarioOutcome, spec) -> str:
    """What the figures say happened (a reading of the judged numbers, not a rule on the shape)."""
    if o.touching_fraction < 0.8 and (math.isnan(o.follow_ratio) or abs(o.follow_ratio) < 0.1):
        return (f"it stayed where it was and the rope touched it in {100 * o.touching_fraction:.0f} % of the judged "
                f"half of the pull (peak guide load {o.peak_guide_load_n:.2f} N): the loop lost it; the object is "
                f"{1000 * spec.height_m:.2g} mm tall and the rope, resting on the floor, has a "
                f"{1000 * ChainParams().rope_radius_m:g} mm radius: where the object is thinner than the rope's "
                "radius the rope rides onto it (docs/chain_model.md, \"Rope on the floor\")")
    if o.follow_ratio > 1.2 and o.touching_fraction < 0.5:
        return "knocked ahead: it rolled on out of the rope's contact faster than the module moved"
    if o.follow_ratio >= 0.5 and o.touching_fraction < 0.8:
        return (f"it moved with the module (follow {o.follow_ratio:.2f}) but the rope touched it in only "
                f"{100 * o.touching_fraction:.0f} % of the judged samples (< 80 %): the rope rides up and the object "
                "tips and rocks in the loop; a marginal case")
    if o.secured:
        return "held and dragged along"
    return "the rope lost it during the pull"


def _fmt(x: float, spec: str = ".2f") -> str:
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else format(x, spec)


def markdown(sil: list[ScenarioOutcome], plant: list[dict], door: list[ScenarioOutcome], *, seed: int,
             n_links: int, wall_s: float) -> str:
    by_name = {r["object"]: r for r in plant}
    lines = [
        "# Table I: paper vs plant-level vs SIL",
        "",
        f"Regenerate: `{COMMAND}` (seed {seed}, N = {n_links} links; {wall_s:.0f} s wall here).",
        "",
        "* paper: the qualitative outcome of the RoboWrangler paper's Table I (cylinders and boxes secured,",
        "  spheres slip; irregular shapes carry no class rule).",
        "* plant level: chain/table_i.py, the scripted grasp driving the chain's inputs directly.",
        "* SIL: `wrangler sil --scenario NAME`: the SIL firmware (GRASP = RELAX, RETRACT until the spindle's",
        "  load says secured or the stroke ends) drives the drive and spindle plants and through them the",
        "  chain; the chain's contact load on the object loads the guide (coupling law in",
        "  sim/robowrangler_sim/scenarios/chain_bridge.py). The robot then pulls the module back 0.3 m and the",
        "  simulation judges the second half of the pull: secured = the rope touches the object in >= 80 % of",
        "  the samples and the object follows >= 50 % of the module's displacement.",
        "* RETRACT end: what ended the firmware's retract (STROKE_END: guide at its 178 mm soft limit with no",
        "  load that says secured; LOAD_SECURED: the spindle load stayed over grasp_secure_load_pct).",
        "",
        "| object | class | paper | plant level | SIL | RETRACT end | peak guide load (N) | follow | rope touching"
        " | mean rope force (N) | slide force (N) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    disagree = []
    for o in sil:
        spec = OBJECTS[o.object_name]
        p = by_name.get(o.object_name, {})
        paper = _paper(spec)
        lines.append(f"| {o.object_name} | {spec.shape_class} | {paper} | {p.get('outcome', '-')} | {o.verdict} | "
                     f"{o.grasp_end or '-'} | {_fmt(o.peak_guide_load_n)} | {_fmt(o.follow_ratio)} | "
                     f"{100 * o.touching_fraction:.0f} % | {_fmt(o.mean_pull_force_n, '.3f')} | "
                     f"{_fmt(o.drag_force_n, '.3f')} |")
        if paper not in ("-", o.verdict):
            disagree.append(o)
        elif p.get("outcome") not in (None, o.verdict):
            disagree.append(o)
    agree = sum(1 for o in sil if _paper(OBJECTS[o.object_name]) == o.verdict)
    with_paper = sum(1 for o in sil if _paper(OBJECTS[o.object_name]) != "-")
    lines += ["", f"SIL agrees with the paper on {agree} of {with_paper} objects with a paper outcome.", "",
              "## Where SIL, paper and plant level disagree", ""]
    if not disagree:
        lines.append("Nowhere: every object with a paper outcome has the same outcome in the SIL, and the SIL agrees "
                     "with the plant level.")
    for o in disagree:
        spec = OBJECTS[o.object_name]
        p = by_name.get(o.object_name, {})
        lines.append(f"* {o.object_name} ({spec.shape_class}): paper {_paper(spec)}, plant level "
                     f"{p.get('outcome', '-')}, SIL {o.verdict}: {_why(o, spec)}.")
    lines += [
        "",
        "Common to all grasps: RETRACT never ended on LOAD_SECURED. The loop lies around the object with slack,",
        "and the 178 mm of guide (356 mm of rope) take up slack without closing the 2 m loop on a 4-8 cm",
        "object 0.6 m away; the chain's load on the guide during RETRACT stays near 0 N, far under the",
        "firmware's secure threshold (12 %: about 36 N on the guide). The grasp is made by the robot's pull,",
        "as in the plant-level script. The plant level retracts 180 mm in 3 s; the firmware retracts 178 mm",
        "in about 23 s (the AX-12A's top speed, 7.6 mm/s); outcomes that differ between the two columns are",
        "objects whose result depends on that (chips can at plant level: secured with 180 mm in 3 s or 23 s,",
        "slipped with 178 mm in 23 s). No rule on the shape class was tuned to move any outcome.",
        "",
        "Marginal cases move with small timing changes: the chips can slipped in this SIL with the firmware",
        "build before commits 37c9cb7/0906311 (they change the ticks at which the firmware's frames leave, so",
        "the script steps a few ticks apart): follow 1.35, rope touching 76 % (< 80 %), the can tipping in",
        "the loop; with the current build it is secured (100 %). The mug, the spheres and the low objects did",
        "not change.",
    ]
    lines += ["", "## Door handle (fixture): loop threaded over the lever, GRASP, pull 5 cm", "",
              "Seed 0 unperturbed; the other rows are perturbed rollouts: seeded noise on the chain's initial joint",
              "angles (1 sigma) and on the plant sensors.", "",
              "| seed | joint noise (rad) | verdict | RETRACT end | guide at end (mm) | peak guide load (N) "
              "| rope touching | mean rope force (N) | diverged |", "|---|---|---|---|---|---|---|---|---|"]
    for o in door:
        lines.append(f"| {o.seed} | {o.chain_noise_rad:g} | {o.verdict} | {o.grasp_end or '-'} | "
                     f"{_fmt(o.guide_at_grasp_end_mm, '.1f')} | "
                     f"{_fmt(o.peak_guide_load_n)} | {100 * o.touching_fraction:.0f} % | "
                     f"{_fmt(o.mean_pull_force_n, '.3f')} | {o.diverged or 'no'} |")
    lines += [
        "",
        "The door scenario positions with the robot's leg: the vertical loop flies beside the door and the module",
        "slides 0.45 m sideways so that the loop threads over the lever's free end; GRASP relaxes the loop onto",
        "the bar and retracts 60 mm (guide_max_mm 60, secure threshold 5 %); the 5 cm pull then loads the rope.",
        "The retract alone does not tighten the hanging loop enough to reach LOAD_SECURED. With the whole",
        "stroke (`firmware_params={'guide_max_mm': 178}`) the loop tightens on the bar to about 12 N of guide",
        "load near 100 mm of guide and then lets go of it (the rope's light links pass the bar: the known",
        "fragility of contact on this chain); the load never stays over the threshold for the 0.3 s the firmware",
        "asks, so RETRACT still ends on STROKE_END. Divergence (ChainDivergenceError) is caught and listed in",
        "the last column. Perturbed rollouts show the door's weak point: the out-of-plane joints have zero",
        "stiffness (as in the paper), so nothing restores the loop's plane; a loop that rose from a perturbed",
        "rest flies in a swung plane, and a swing of 15-20 degrees (seed 1 at 0.05 rad: the tip 0.25 m out of",
        "its plane) makes it miss the lever (lost).",
        "",
        "Firmware finding: with the default guide_max_mm = 180 mm (= the lead screw's hard stop in the spindle",
        "plant) a retract with nothing to hold stalls on the stop before its noisy position reads 180 mm, and",
        "the stall load ends RETRACT on LOAD_SECURED -> HOLD: an empty loop is reported as secured. The",
        "scenarios set guide_max_mm to 178 mm; a soft limit short of the hard stop (or STROKE_END within",
        "the position tolerance) belongs in the firmware defaults.",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None, help="markdown file to write (default: stdout)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--links", type=int, default=20)
    ap.add_argument("--door-seeds", type=int, default=5,
                    help="door handle: seed 0 unperturbed, seeds 1..N-1 at each of DOOR_NOISES_RAD")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    note = lambda s: print(s, file=sys.stderr, flush=True)  # noqa: E731
    sil = run_sil_rows(seed=args.seed, n_links=args.links, progress=note)
    plant = run_table_i(params=ChainParams(n_links=args.links))
    door = []
    runs = [(0, 0.0)] + [(seed, noise) for noise in DOOR_NOISES_RAD for seed in range(1, args.door_seeds)]
    for seed, noise in runs:
        out = run_scenario("door_handle", seed=seed, n_links=args.links, chain_noise_rad=noise)
        note(f"door_handle seed {seed}, noise {noise:g} rad: {out.verdict}")
        door.append(out)
    text = markdown(sil, plant, door, seed=args.seed, n_links=args.links, wall_s=time.perf_counter() - t0)
    if args.out:
        Path(args.out).write_text(text)
        note(f"wrote {args.out}")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
