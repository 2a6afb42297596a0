"""Demo: a scripted wrangle rendered headless to MP4 and PNG frames, or shown in MuJoCo's viewer.

    MUJOCO_GL=osmesa uv run python -m robowrangler_sim.chain.demo --object mug --out /tmp/wrangle
    uv run python -m robowrangler_sim.chain.demo --object mug --viewer      # needs a display

Writes <out>/wrangle_<object>.mp4 and every ``--png-every``-th frame as PNG, and prints the outcome.
The inputs are the plant-level grasp script (grasp.py); the firmware-driven version is
``wrangler sil --scenario ...`` once the lockstep SIL exists.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")

import argparse  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

from robowrangler_sim.chain.default_table import default_or_synthetic_table  # noqa: E402
from robowrangler_sim.chain.errors import ChainModelError  # noqa: E402
from robowrangler_sim.chain.grasp import GraspScript, grasp_inputs, grasp_scene, run_grasp  # noqa: E402
from robowrangler_sim.chain.objects import get_object  # noqa: E402
from robowrangler_sim.chain.params import ChainParams  # noqa: E402


def render_grasp(object_name: str, *, out_dir: Path, fps: float = 20.0, png_every: int = 20,
                 width_px: int = 640, height_px: int = 360) -> tuple[object, Path]:
    """Run and render the scripted grasp. Returns (GraspOutcome, mp4 path)."""
    from robowrangler_sim.chain.render import ChainRenderer, write_mp4, write_png

    out_dir.mkdir(parents=True, exist_ok=True)
    table = default_or_synthetic_table()
    frames = []
    state = {"renderer": None, "k": 0}
    sample_s = 1.0 / fps

    def on_sample(plant, phase):
        if state["renderer"] is None:
            state["renderer"] = ChainRenderer(plant, width_px=width_px, height_px=height_px, azimuth_deg=70.0,
                                              elevation_deg=-20.0, distance_m=1.4)
        frame = state["renderer"].frame()
        frames.append(frame)
        if state["k"] % png_every == 0:
            write_png(out_dir / f"wrangle_{object_name}_{state['k']:04d}_{phase}.png", frame)
        state["k"] += 1

    try:
        outcome = run_grasp(object_name, table=table, sample_s=sample_s, on_sample=on_sample)
    finally:
        if state["renderer"] is not None:
            state["renderer"].close()
    mp4 = write_mp4(out_dir / f"wrangle_{object_name}.mp4", frames, fps=fps)
    return outcome, mp4


def view_grasp(object_name: str) -> None:  # pragma: no cover - needs a display
    from robowrangler_sim.chain.render import launch_viewer

    table = default_or_synthetic_table()
    script = GraspScript()
    plant, base = grasp_scene(object_name, table=table, params=ChainParams(), script=script)
    launch_viewer(plant, step_inputs=lambda t: grasp_inputs(script, t, base_pos_m=base)[1])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--object", default="mug", help="catalogue name (objects.py)")
    ap.add_argument("--out", default="wrangle_out", help="output directory")
    ap.add_argument("--viewer", action="store_true", help="MuJoCo's interactive viewer instead of files")
    args = ap.parse_args(argv)
    try:
        get_object(args.object)
        if args.viewer:
            view_grasp(args.object)
            return 0
        outcome, mp4 = render_grasp(args.object, out_dir=Path(args.out))
    except ChainModelError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    verdict = "secured" if outcome.secured else "slipped"
    print(f"{args.object}: {verdict} (follow {outcome.follow_ratio:.2f}, mean pull force "
          f"{outcome.mean_pull_force_n:.3f} N, drag {outcome.drag_force_n:.3f} N); video {mp4}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
