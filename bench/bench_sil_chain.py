#!/usr/bin/env python3
"""The full SIL real-time factor: firmware process + drive + spindle + rope chain (MuJoCo), in lockstep.

    uv run python bench/bench_sil_chain.py [--links 20] [--seconds 5]

Prints (never asserts) simulated seconds per wall second, unpaced, for:
  * the SIL without the chain (firmware + drive + spindle plants, 1 kHz lockstep over UDP),
  * the SIL with the chain, the loop airborne around a mug (chain on the floor at a few points),
  * the SIL with the chain, the loop relaxed on the floor around the mug (many contacts),
  * a whole firmware-driven scenario (`wrangler sil --scenario mug`),
and where the wall time goes (chain steps inside the tick hook vs the rest of the tick), which says
what limits the figure. 2 cores shared with other jobs: figures vary run to run by tens of percent.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import build_native  # noqa: E402

from robowrangler.protocol import generated as gen  # noqa: E402
from robowrangler_sim.chain.default_table import default_or_synthetic_table  # noqa: E402
from robowrangler_sim.chain.grasp import GraspScript, grasp_scene  # noqa: E402
from robowrangler_sim.chain.params import ChainParams  # noqa: E402
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz  # noqa: E402
from robowrangler_sim.scenarios import run_scenario  # noqa: E402
from robowrangler_sim.scenarios.base_trajectory import BaseTrajectory  # noqa: E402
from robowrangler_sim.scenarios.chain_bridge import ChainBridge  # noqa: E402
from robowrangler_sim.sil import SilSession  # noqa: E402
from robowrangler_sim.sil.scripted_host import ScriptedHost  # noqa: E402


class TimedBridge(ChainBridge):
    """ChainBridge that adds up the wall time of its tick hook (chain steps + coupling)."""

    hook_wall_s = 0.0
    couple_wall_s = 0.0

    def __call__(self, sil) -> None:
        t0 = time.perf_counter()
        super().__call__(sil)
        self.hook_wall_s += time.perf_counter() - t0

    def _couple(self) -> None:
        t0 = time.perf_counter()
        super()._couple()
        self.couple_wall_s += time.perf_counter() - t0


def _time_lockstep(sil) -> list[float]:
    """Wrap the session's lockstep exchange (UDP to the firmware process and back) with a wall-time counter."""
    spent = [0.0]
    exchange = sil._link.exchange

    def timed(**kw):
        t0 = time.perf_counter()
        try:
            return exchange(**kw)
        finally:
            spent[0] += time.perf_counter() - t0

    sil._link.exchange = timed
    return spent


def measure(*, n_links: int, seconds: float, chain: bool,
            relaxed: bool) -> tuple[float, float, int, float, float]:
    """Returns (real-time factor, share of wall time in the chain hook, chain steps, share in the lockstep
    exchange with the firmware process, wall seconds in the load pass over the contacts)."""
    script = GraspScript()
    table = default_or_synthetic_table()
    params = ChainParams(n_links=n_links)
    sil = SilSession(speedup=None, trace_every=0)
    bridge = None
    if chain:
        placed, base = grasp_scene("mug", table=table, params=params, script=script)
        quat = pitch_quat_wxyz(0.0, roll_rad=math.radians(script.roll_deg))
        plant = ChainPlant(table=table, params=params, objects=placed.objects, floor_height_m=0.0,
                           initial=PlantInputs(rope_speed_mps=0.0, guide_position_mm=40.0, base_pos_m=tuple(base),
                                               base_quat_wxyz=quat), airborne=True)
        bridge = TimedBridge(sil, plant, BaseTrajectory(start_pos_m=base, quat_wxyz=quat)).install()
    with sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        if not relaxed:
            host.arm_and_spin(4000, settle_s=1.5)
        else:
            host.run_for(1.5)  # rope stands: the loop lies on the floor around the mug
        if bridge is not None:
            bridge.hook_wall_s = 0.0
            bridge.couple_wall_s = 0.0
            steps0 = bridge.chain_steps
        lockstep = _time_lockstep(sil)
        t0 = time.perf_counter()
        host.run_for(seconds)
        wall = time.perf_counter() - t0
        if not relaxed:
            assert host.last_telemetry.state == gen.State.AIRBORNE
        host.close()
    if bridge is None:
        return seconds / wall, 0.0, 0, lockstep[0] / wall, 0.0
    return (seconds / wall, bridge.hook_wall_s / wall, bridge.chain_steps - steps0, lockstep[0] / wall,
            bridge.couple_wall_s)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--links", type=int, default=20)
    ap.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per measurement")
    args = ap.parse_args()
    build_native()
    n, s = args.links, args.seconds
    rtf0, _, _, lock0, _ = measure(n_links=n, seconds=s, chain=False, relaxed=False)
    print(f"SIL without chain (firmware + drive + spindle, 1 kHz lockstep): {rtf0:5.1f}x real time "
          f"({1e6 / (rtf0 * 1000):.0f} us wall per 1 ms tick; lockstep exchange {100 * lock0:.0f} %)")
    for relaxed in (False, True):
        rtf, share, steps, lock, couple_s = measure(n_links=n, seconds=s, chain=True, relaxed=relaxed)
        what = "loop relaxed on the floor around the mug" if relaxed else "loop airborne around the mug"
        tick_us = 1e6 / (rtf * 1000)
        step_us = share * s / rtf / max(steps, 1) * 1e6
        print(f"full SIL, N = {n}, {what}: {rtf:5.1f}x real time ({tick_us:.0f} us wall per 1 ms tick); "
              f"lockstep exchange with the firmware process {100 * lock:.0f} %, chain hook {100 * share:.0f} % "
              f"({step_us:.0f} us per 5 ms chain step, of which {couple_s / max(steps, 1) * 1e6:.0f} us the Python "
              f"pass over the contacts for the loads), the rest (Python plants, host, pacing checks) "
              f"{100 * (1 - lock - share):.0f} %")
    t0 = time.perf_counter()
    out = run_scenario("mug", seed=0, n_links=n)
    print(f"whole scenario `wrangler sil --scenario mug` (N = {n}): {out.simulated_s:.1f} simulated s in "
          f"{out.wall_s:.1f} s = {out.simulated_s / out.wall_s:.1f}x real time (verdict {out.verdict}; includes the "
          f"firmware start, provisioning, model build; {time.perf_counter() - t0:.1f} s total)")
    print("what limits it: the shares above. The lockstep exchange is one UDP datagram to the firmware process and "
          "one back per 1 ms tick; each wakes the other process, so on a loaded 2-core machine it costs a context "
          "switch or two per tick. The chain costs one MuJoCo step per 5 ticks plus the Python pass over its "
          "contacts that computes the loads it couples back.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
