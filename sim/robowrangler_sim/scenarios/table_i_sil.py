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

DOOR_NOISES_RAD = (0.05, 0.1, 0.2)
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


def why_outcome(o: ScenarioOutcome, spec) -> str:
    """What the figures say happened (a reading of the judged numbers, not a rule on the shape)."""
    if o.touching_fraction < 0.8 and (math.isnan(o.follow_ratio) or abs(o.follow_ratio) < 0.1):
        lost = (f"it stayed where it was and the rope touched it in {100 * o.touching_fraction:.0f} % of the judged "
                f"half of the pull (peak guide load {o.peak_guide_load_n:.2f} N): the loop lost it")
        rope_radius_m = ChainParams().rope_radius_m
        if spec.height_m < rope_radius_m:
            return (f"{lost}; the object is {1000 * spec.height_m:.2g} mm tall and the rope, resting on the floor, has "
                    f"a {1000 * rope_radius_m:g} mm radius: the edge meets the rope below its axis, and the rope, "
                    "sliding along the edge with its friction used up, rides onto it (docs/chain_model.md, "
                    "\"The credit card\")")
        return f"{lost} before the judged half of the pull ({1000 * spec.height_m:.2g} mm tall)"
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
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    text = format(x, spec)
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text  # no "-0.0" for a rounded zero


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
                     f"{p.get('outcome', '-')}, SIL {o.verdict}: {why_outcome(o, spec)}.")
    lines += [
        "",
        "Common to the free-object grasps: RETRACT never ended on LOAD_SECURED, and for light objects that is physics,",
        "not a bug. The AX-12A feels the rope through an 8 mm-lead self-locking T8 screw of efficiency 0.35",
        "(plants/spindle.py): 1 N on the guide is 8 mm / 2 pi / 0.35 = 3.6 mN m at the servo, 0.24 % of its",
        "1.5 N m stall torque, against 0.8 % register noise (8 permille, 1 sigma) and 3.3 % screw friction",
        "(0.05 N m). A dragged 0.3 kg mug is about 1.5 N (0.36 %); the chain's load on the guide during RETRACT",
        f"stays at {max(o.peak_guide_load_n for o in sil):.1f} N or less (peak column), far under the 5 % minimum "
        "threshold (6.9 N) and the default 12 %",
        "(35.7 N). The loop lies around the object with slack: the 178 mm of guide (356 mm of rope) take up",
        "slack without closing the 2 m loop on a 4-8 cm object 0.6 m away, so RETRACT ends on STROKE_END and the",
        "grasp is made by the robot's pull, as in the plant-level script. The plant level retracts 180 mm in 3 s;",
        "the firmware retracts 178 mm in about 23 s (the AX-12A's top speed, 7.6 mm/s); an object whose outcome",
        "differs between the two columns is one whose result depends on that. No rule on the shape class was",
        "tuned to move any outcome: every object runs the same script with the same parameters.",
    ]
    lines += ["", "## Door handle on a hinged door: loop threaded over the lever, GRASP to HOLD, pull the door open", "",
              "Seed 0 unperturbed; the other rows are perturbed rollouts: seeded noise on the chain's initial joint",
              "angles (1 sigma) and on the plant sensors.", "",
              "| seed | joint noise (rad) | verdict | RETRACT end | guide at end (mm) | peak guide load (N) "
              "| rope touching | mean rope force (N) | door opened (deg) | diverged |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for o in door:
        lines.append(f"| {o.seed} | {o.chain_noise_rad:g} | {o.verdict} | {o.grasp_end or '-'} | "
                     f"{_fmt(o.guide_at_grasp_end_mm, '.1f')} | "
                     f"{_fmt(o.peak_guide_load_n)} | {100 * o.touching_fraction:.0f} % | "
                     f"{_fmt(o.mean_pull_force_n, '.3f')} | {_fmt(o.door_opening_deg, '.1f')} | {o.diverged or 'no'} |")
    lines += [
        "",
        "The door scenario positions with the robot's leg: the vertical loop flies up to the door and the module",
        "slides 0.45 m sideways so that the loop threads over the lever's free end; GRASP relaxes the loop onto",
        "the bar and retracts with the whole stroke (guide_max_mm 178) until the spindle's load says secured:",
        "threshold 5 %, i.e. (0.075 - 0.05) N m / 3.6 mN m per N = 6.9 N on the guide (3.4 N in each strand) on",
        "every 10 ms read for 0.3 s (with 8 permille of register noise that takes about 12-14 N sustained). The",
        "handle is on a door that can move (chain/door.py, catalogue.DOOR_LEAF): a 0.86 m x 2.0 m, 25 kg leaf on a",
        "MuJoCo hinge 0.80 m from the handle, shut against its stop by a light closer (7 N m + 5 N m/rad, 0.5 N m",
        "hinge friction: 9.4 N square to the leaf at the handle; BS 8300 allows up to 30 N). No latch: the loop",
        "pulls the lever up and back, which would turn no latch lever. The loop goes taut on the bar near 105 mm",
        "of guide (loop 1.79 m: exit to bar and back); the closer holds the door, the load rises past the",
        "threshold and RETRACT ends on LOAD_SECURED -> HOLD with the door still shut (within a degree: the",
        "closer was chosen so that the leaf starts to give at about the load the firmware needs to see, about",
        "12 N on the guide, and the pull stays under what the chain keeps on the bar). The robot then pulls the",
        "module back 0.2 m over 2 s: held = the rope keeps touching and pulling the handle through the second",
        "half of the pull; the last column is how far the door opened (about 14 degrees for 0.2 m at 0.80 m).",
        "",
        "Why the rope used to slip off the bar (before: a fixed door; RETRACT 60 mm then a 5 cm pull, or the",
        "whole stroke ending on STROKE_END after about 12 N): the taut loop's tip is a V of two 10 cm links",
        "hinged at the loop's middle joint, with the 19 mm bar inside the V about 1 cm from its vertex (a rope",
        "would wrap it; 10 cm links cannot). The soft closure (compliance about 0.24 m/N on the 8e-5 kg effective",
        "mass of the last link) leaves the lower strand nearly slack (0.2 N at a 5 cm closure gap) while the",
        "upper strand, anchored at the exit, carries the load: the ratio of the strand tensions is far over the",
        "capstan limit e^(0.3 pi) = 2.6, so the upper strand drags the rope round the bar, and a 10 cm link passes",
        "a 19 mm bar only by going through it. Pinned between the module and a welded bar, the inextensible chain",
        "can only take the guide's further shortening in that contact. At the chain's 5 ms step MuJoCo let the bar",
        "through link 10 at about 12 N (penetration 4-7 mm); at 2 ms (and at 1 ms) the contact holds to about",
        "27 N. Two changes follow from that: the door's chain steps at 2 ms (catalogue.DOOR_CHAIN_PARAMS), and the",
        "door gives (a hinged leaf): once the closer's force is reached, the pull opens the door instead of",
        "loading the rope without bound. The default threshold 12 % (35.7 N mean, about 42-46 N sustained) is",
        "over what this chain keeps on the bar, so the door uses 5 %; a door that needs more than about 25 N at",
        "the handle (a 20 N m closer) is outside what this chain can open. (On the fixed door the 2 ms chain",
        "also reaches HOLD, at about 14 N, but any pull of the robot is then a displacement imposed on a nearly",
        "inextensible tether: 5 cm drove the rope past the ~27 N at which the bar passes a link.)",
        "",
        "Divergence (ChainDivergenceError) is caught and listed in the last column. Perturbed rollouts show the",
        "door's weak point: the out-of-plane joints have zero stiffness (as in the paper), so nothing restores",
        "the loop's plane but the out-of-plane hinge damping (the rope's air drag, ChainParams); a loop that",
        "rose from a perturbed rest can fly in a swung plane and miss the lever: nothing loads the guide,",
        "RETRACT runs to STROKE_END and the pull finds no handle (lost). With that damping every 0.05 rad",
        "rollout threads the lever; the misses start at 0.1 rad.",
        "",
        "Firmware finding (fixed): with guide_max_mm = 180 mm (= the lead screw's hard stop in the spindle plant)",
        "a retract with nothing to hold stalled on the stop before its noisy position read 180 mm, and the stall",
        "load ended RETRACT on LOAD_SECURED -> HOLD: an empty loop was reported as secured. The firmware now",
        "counts a load held within 2 mm of guide_max as STROKE_END; the scenarios also set guide_max_mm to",
        "178 mm, a soft limit short of the hard stop.",
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
