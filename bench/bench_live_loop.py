"""What the Foxglove live view costs a scenario (`wrangler sil --scenario NAME --foxglove`), unpaced.

Prints (never asserts): the same scenario run without and with a ScenarioLiveView (no client connected; the
loop's contour and scene at 30 Hz of simulated time, every host frame to the link recorder), wall seconds per
simulated second of each, the extra per contour published, and whether the two runs' traces are identical (the
live view only reads the simulation).

Run:  uv run python bench/bench_live_loop.py [--scenario golf_ball] [--links 10]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from robowrangler.recorder.live_view import FoxgloveLiveView
from robowrangler_sim.scenarios import run_scenario
from robowrangler_sim.scenarios.live_loop import ScenarioLiveView


def _same_trace(a, b) -> bool:
    """Every sample of the two traces equal, bit for bit (NaN equal to NaN: the door angle of a grasp is NaN)."""
    def rows(o):
        return [{k: repr(np.asarray(v).tolist()) for k, v in row.items()} for row in o.trace]
    return rows(a) == rows(b)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenario", default="golf_ball")
    ap.add_argument("--links", type=int, default=10)
    args = ap.parse_args()
    t0 = time.perf_counter()
    plain = run_scenario(args.scenario, seed=1, n_links=args.links)
    plain_wall_s = time.perf_counter() - t0
    server = FoxgloveLiveView(port=0)
    live = ScenarioLiveView(server, speedup=None)
    try:
        t0 = time.perf_counter()
        served = run_scenario(args.scenario, seed=1, n_links=args.links, live=live)
        live_wall_s = time.perf_counter() - t0
    finally:
        live.close()
        server.close()
    per_sim_plain = plain_wall_s / plain.simulated_s
    per_sim_live = live_wall_s / served.simulated_s
    print(f"{args.scenario}, N = {args.links}, {plain.simulated_s:.1f} simulated s, unpaced")
    print(f"without live view: {plain_wall_s:.1f} s wall ({1 / per_sim_plain:.2f}x real time)")
    print(f"with live view:    {live_wall_s:.1f} s wall ({1 / per_sim_live:.2f}x real time), {live.contours} contours "
          f"+ scenes, {live.recorder.telemetry_count} telemetry, {live.recorder.command_count} commands served")
    per_contour_ms = 1e3 * live.publish_wall_s / max(live.contours, 1)
    print(f"publishing: {per_contour_ms:.2f} ms per contour + scene, {live.publish_wall_s:.2f} s in all = "
          f"{100 * live.publish_wall_s / live_wall_s:.1f} % of the run's wall time; at 30 Hz and 1x real time "
          f"{30 * per_contour_ms:.0f} ms per wall second")
    extra_s = live_wall_s - plain_wall_s
    print(f"difference: {100 * extra_s / plain_wall_s:+.1f} % ({1e3 * extra_s / max(live.contours, 1):+.2f} ms per "
          "contour; run-to-run noise on a shared machine is of the same order)")
    print(f"verdicts {plain.verdict} / {served.verdict}; traces identical: {_same_trace(plain, served)}")


if __name__ == "__main__":
    main()
