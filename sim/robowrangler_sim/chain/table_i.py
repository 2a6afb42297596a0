"""The paper's Table I at plant level: the scripted grasp (grasp.py) on every Table I object.

    uv run python -m robowrangler_sim.chain.table_i        # prints a markdown table (about 10 s)

The paper's qualitative result: cylinders and boxes are secured, spheres slip. This is the plant-level
reproduction (scripted inputs); the firmware-driven one runs the same objects through the SIL.
"""

from __future__ import annotations

import sys

from robowrangler_sim.chain.default_table import default_or_synthetic_table
from robowrangler_sim.chain.grasp import GraspScript, run_grasp
from robowrangler_sim.chain.objects import OBJECTS
from robowrangler_sim.chain.params import ChainParams

TABLE_I_OBJECTS = ("chips_can", "tuna_can", "banana", "sponge", "mug", "marker", "screwdriver", "credit_card",
                   "cup", "tennis_ball", "golf_ball", "apple", "orange")


def run_table_i(*, params: ChainParams | None = None, script: GraspScript | None = None) -> list[dict]:
    """One row per object: name, shape class, expected (paper), outcome (sim) and the judged figures."""
    table = default_or_synthetic_table()
    rows = []
    for name in TABLE_I_OBJECTS:
        out = run_grasp(name, table=table, params=params, script=script)
        spec = OBJECTS[name]
        rows.append(dict(object=name, shape_class=spec.shape_class, expected=spec.expected_outcome or "-",
                         outcome="secured" if out.secured else "slipped", follow_ratio=out.follow_ratio,
                         touching=out.touching_fraction, mean_pull_force_n=out.mean_pull_force_n,
                         drag_force_n=out.drag_force_n))
    return rows


def markdown(rows: list[dict]) -> str:
    lines = ["| object | class | paper | plant level | follow | rope touching | mean rope force (N) | "
             "slide force (N) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['object']} | {r['shape_class']} | {r['expected']} | {r['outcome']} | "
                     f"{r['follow_ratio']:.2f} | {100 * r['touching']:.0f} % | {r['mean_pull_force_n']:.3f} | "
                     f"{r['drag_force_n']:.3f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.stdout.write(markdown(run_table_i()) + "\n")
