#!/usr/bin/env python3
"""SIL figures: real-time factor, command -> ACK latency over loopback UDP, step settle times.

    uv run python bench/bench_sil.py [--latency-samples 500]

Prints one line per figure. Times depend on the machine (2 cores here, shared); the real-time factor
is the ratio of simulated to wall seconds of the whole SIL (firmware process + Python plant + UDP).
"""

from __future__ import annotations

import argparse
import socket
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import build_native  # noqa: E402

from robowrangler.protocol import generated as gen  # noqa: E402
from robowrangler_sim.sil import SilSession  # noqa: E402
from robowrangler_sim.sil.metrics import settle_time_s  # noqa: E402
from robowrangler_sim.sil.scripted_host import ScriptedHost  # noqa: E402


def real_time_factor(sim_s: float) -> tuple[float, float]:
    with SilSession(speedup=None, trace_every=0) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        host.arm_and_spin(6000, settle_s=0.0)
        t0 = time.perf_counter()
        host.run_for(sim_s)
        wall = time.perf_counter() - t0
        host.close()
    return sim_s / wall, wall / (sim_s * 1000) * 1e6


def settle_times() -> tuple[float | None, float | None]:
    with SilSession(speedup=None) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        host.command(gen.Arm())
        t4 = host.last_telemetry.time_ms
        host.command(gen.SetRopeSpeed(4000))
        host.run_for(2.0)
        t6 = host.last_telemetry.time_ms
        host.command(gen.SetRopeSpeed(6000))
        host.run_for(2.0)
        times, speeds = host.telemetry_series("rope_speed_mmps")
        host.close()
    s4 = settle_time_s(times, speeds, target=4000, start_s=t4 / 1000, end_s=(t6 - 1) / 1000)
    s6 = settle_time_s(times, speeds, target=6000, start_s=t6 / 1000)
    return s4, s6


def ack_latency(samples: int, speedup: float) -> list[float]:
    with SilSession(speedup=speedup, trace_every=0) as sil:
        sil.run_in_background()
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.settimeout(1.0)
        sock.connect(("127.0.0.1", sil.cmd_port))
        sock.send(gen.encode_frame(gen.Hello(1), 0))  # the session to sign for
        while True:
            _, info = gen.decode_message(sock.recv(256))
            if isinstance(info, gen.SessionInfo):
                break
        out: list[float] = []
        for seq in range(samples):
            # signed as every command on the link (SipHash-2-4): the figure includes the MAC on both sides
            frame = gen.encode_frame(gen.ParamGet(0), seq, key=sil.key, session_id=info.session_id, counter=seq + 1)
            t0 = time.perf_counter()
            sock.send(frame)
            while True:
                _, msg = gen.decode_message(sock.recv(256))
                if isinstance(msg, (gen.Ack, gen.Nack)) and msg.cmd_seq == seq:
                    break
            out.append(time.perf_counter() - t0)
            time.sleep(0.002)
        sock.close()
        sil.check()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--latency-samples", type=int, default=500)
    parser.add_argument("--sim-seconds", type=float, default=10.0)
    args = parser.parse_args()
    build_native()
    print("bench_sil: SIL = rw_sil process (firmware core, 1 kHz tick) + Python drive plant, lockstep over UDP",
          file=sys.stderr)
    rtf, us_per_tick = real_time_factor(args.sim_seconds)
    print(f"sil_real_time_factor_unpaced      {rtf:8.1f} x   ({us_per_tick:.0f} us wall per 1 ms tick)")
    s4, s6 = settle_times()
    print(f"settle_0_to_4_mps_2pct_s           {s4:8.3f} s   (from the command, device time)")
    print(f"settle_4_to_6_mps_2pct_s           {s6:8.3f} s")
    for speedup in (1.0,):
        lat = sorted(ack_latency(args.latency_samples, speedup))
        p99 = lat[min(len(lat) - 1, int(0.99 * len(lat)))]
        print(f"cmd_to_ack_latency_median_ms       {statistics.median(lat) * 1e3:8.3f} ms  (speed-up {speedup:g}, "
              f"{len(lat)} PARAM_GET over loopback UDP)")
        print(f"cmd_to_ack_latency_p99_ms          {p99 * 1e3:8.3f} ms")


if __name__ == "__main__":
    main()
