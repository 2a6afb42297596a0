#!/usr/bin/env python3
"""Long soak of the SIL under network impairment: random valid and invalid commands, invariants every tick.

    uv run python bench/bench_soak.py [--minutes 30] [--seed 1]

Lockstep and deterministic (same seed, same figures except wall time; the link key derives from the seed):
the scripted host signs every frame and talks to the SIL firmware through the ImpairmentProxy (bursty
Gilbert-Elliott loss of about 9 %, duplicates, reordering, jitter, 1 % corruption, both directions, plus one
0.8 s total blackout every 15 s), retries like the Client (re-signed), and also sends malformed, unsigned,
forged and replayed frames. The checker in tests/sil_network/soak_runner.py verifies at every tick: only
authentic, fresh frames act (rx_auth_failed / rx_replayed match the drops the protocol requires), no
command executed twice (rx_duplicates = retransmissions answered from the cache), the ToV guard while
AIRBORNE, the firmware alive and the plant finite, every telemetry gap explained by the proxy (dropped,
corrupted, or overtaken and so stale at the host). Prints a progress line per simulated minute, then the
figures; exits 1 on any violation.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from conftest import build_native  # noqa: E402

sys.path.insert(0, str(ROOT / "tests" / "sil_network"))
from soak_runner import SoakConfig, SoakFigures, run_soak  # noqa: E402


def progress(f: SoakFigures) -> None:
    print(f"  t={f.simulated_s / 60:5.1f} min  wall {f.wall_s:7.1f} s  commands {f.commands_sent:6d}  "
          f"retransmissions {f.retransmissions:5d}  duplicates answered {f.duplicates_answered:5d}  "
          f"replays dropped {f.replays_dropped:5d}  violations {f.violations}", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=30.0, help="simulated minutes (default 30)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    build_native()
    f = run_soak(SoakConfig(duration_s=args.minutes * 60.0, seed=args.seed), progress=progress, progress_every_s=60.0)
    d, h = f.proxy["to_device"], f.proxy["to_host"]
    print(f"soak seed {args.seed}: {f.simulated_s:.1f} simulated s in {f.wall_s:.1f} wall s "
          f"(x{f.simulated_s / f.wall_s:.1f} real time), {f.ticks_checked} ticks checked")
    print(f"commands sent            {f.commands_sent} (+ {f.malformed_sent} malformed or wrong-direction datagrams, "
          f"{f.forged_sent} unsigned or forged commands, {f.replays_sent} replayed or other-session frames)")
    print(f"commands executed        {f.commands_executed} distinct frames reached the firmware, each acted on once "
          f"({f.commands_accepted} ACK, {f.commands_refused} NACK)")
    print(f"commands answered        {f.commands_answered} at the host, {f.commands_timed_out} given up "
          "(blackouts / bursts)")
    print(f"transmissions            {f.transmissions}, of which retransmissions {f.retransmissions} "
          f"({f.transit_nacks} at once after a NACK for a frame damaged on the way)")
    print(f"duplicates answered      {f.duplicates_answered} (re-signed retransmissions answered from the cache, "
          "TELEMETRY.rx_duplicates)")
    print(f"dropped unanswered       {f.auth_failed_dropped} for their tag (rx_auth_failed), {f.replays_dropped} as "
          "replays: network copies, overtaken frames, replays sent (rx_replayed)")
    print(f"heartbeat losses         {f.heartbeat_losses} (blackouts {f.blackouts})")
    print(f"frames host->device      received {d['received']}, dropped {d['dropped']} "
          f"({d['dropped_in_bad_state']} in bursts), duplicated {d['duplicated']}, reordered {d['reordered']}, "
          f"corrupted {d['corrupted']}")
    print(f"frames device->host      received {h['received']}, dropped {h['dropped']} "
          f"({h['dropped_in_bad_state']} in bursts), duplicated {h['duplicated']}, reordered {h['reordered']}, "
          f"corrupted {h['corrupted']}")
    print(f"device frames            {f.device_frames}, missing at the host {f.host_frames_missing} "
          f"(all dropped or corrupted by the proxy), stale at the host {f.host_frames_stale} (overtaken or copied "
          "on the way: dropped by the host as replays)")
    print(f"verdicts / telemetry     {f.verdicts_checked} verdicts and {f.telemetry_checked} telemetry samples checked")
    print(f"airborne                 {f.airborne_ticks} ticks, lowest plant speed over the guard "
          f"{f.min_airborne_margin_mps:+.3f} m/s (at t = {f.min_airborne_margin_at_s:.3f} s), "
          f"{f.airborne_ticks_under_guard} ticks under the guard")
    print(f"invariant violations     {f.violations}")
    for text in f.first_violations:
        print(f"  {text}")
    return 0 if f.violations == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
