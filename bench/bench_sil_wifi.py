#!/usr/bin/env python3
"""SIL WiFi figures from the NINA module model (firmware/hal/sil/sil_nina.h): how long the bounded waits hold
the link, and what they cost the SIL. Plant time unless said; these are the model's figures, not a board's.

    nice -n 5 uv run python bench/bench_sil_wifi.py

Prints one line per case: a module that never answers at boot (time to NO_MODULE, ticks then run, late ticks);
the access point lost in flight for 0.7 s (when the loss is seen, how long the re-opened socket waited for the
landing, the counters); a module busy 3 ms after each call (expired waits and busy passes per second); and the
wall-clock real-time factor of an unpaced SIL flight with a healthy module and with the slow one.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import build_native  # noqa: E402

from robowrangler.protocol import generated as gen  # noqa: E402
from robowrangler_sim.sil import SilSession, UsbNotes, WifiModule  # noqa: E402
from robowrangler_sim.sil.scripted_host import ScriptedHost  # noqa: E402

ROPE_DOWN = {gen.State.DISARMED, gen.State.ARMED, gen.State.RETRACT, gen.State.HOLD, gen.State.FAULT, gen.State.ESTOP}


def hung_boot() -> str:
    with SilSession(speedup=None, wifi="boot=never", trace_every=0) as sil:
        t_note = sil.usb_notes[0][0]
        ScriptedHost(sil, handshake=False).run_for(2.0)
    w, led = sil.wifi_counters(), sil.led_counters()
    return (f"hung module at boot: NO_MODULE at {t_note:.3f} s (bound 2 s), {w['calls']} calls into it; then "
            f"{led['ticks']} ticks, {led['overruns']} late, LED on {led['on_ticks']} of them")


def flight(wifi: str | None, *, end_s: float = 7.0) -> tuple[SilSession, ScriptedHost, list, float]:
    sil = SilSession(speedup=None, wifi=wifi, trace_every=0).start()
    usb = UsbNotes(sil.serial_path)
    notes: list = []
    sil.tick_hooks.append(lambda s: notes.extend((s.time_s, x) for x in usb.read()))
    host = ScriptedHost(sil)
    host.run_for(0.6)
    host.command_accepted(gen.ParamSet(gen.PARAMS_BY_NAME["heartbeat_timeout_s"].id, 2.0))
    host.arm_and_spin(5000, settle_s=1.85)
    t0 = time.perf_counter()
    host.run_for(end_s - sil.time_s)
    wall_s = time.perf_counter() - t0
    host.close()
    usb.close()
    sil.stop()
    return sil, host, notes, wall_s


def lost_in_flight() -> str:
    sil, host, notes, _ = flight("lost=2.6-3.3")
    t_down = next(t for t, x in notes if x == "wifi CONNECTING")
    t_up = next(t for t, x in notes if x == "wifi UP")
    w = sil.wifi_counters()
    landed = [t.time_ms / 1000 for t in host.received.telemetry if t.time_ms / 1000 > t_up and t.state in ROPE_DOWN]
    return (f"access point lost 2.6-3.3 s in flight: loss seen at {t_down:.3f} s, socket re-opened at {t_up:.3f} s "
            f"({t_up - 3.3:.2f} s after the module re-associated, the rope down by then: first telemetry after it "
            f"{'rope down' if landed else '?'}); losses={w['losses']} deferred={w['deferred']} "
            f"connects={w['connects']} datagrams lost {w['lost_rx']} in, {w['lost_tx']} out")


def slow_module() -> str:
    with SilSession(speedup=None, wifi="busy_us=3000", trace_every=0) as sil:
        ScriptedHost(sil, handshake=False).run_for(5.0)
    w = sil.wifi_counters()
    slow, _, _, wall_slow = flight("busy_us=3000,slow_from=2.6")
    ws = slow.wifi_counters()
    _, _, _, wall_ok = flight(None)
    run_s = 7.0 - 2.5
    return (f"module busy 3 ms after each call from boot: {w['state']} after 5 s, {w['ready_waits_expired']} "
            f"expired waits, {w['module_busy']} busy passes, longest background pass {w['max_pass_us']} us, "
            f"{sil.led_counters()['overruns']} late ticks; the same from 2.6 s in flight: {ws['state']}, "
            f"{ws['module_busy']} busy passes, {slow.led_counters()['overruns']} late ticks; unpaced flight "
            f"{run_s / wall_slow:.1f}x real time (healthy module {run_s / wall_ok:.1f}x)")


def main() -> None:
    build_native()
    for case in (hung_boot, lost_in_flight, slow_module):
        print(case(), flush=True)


if __name__ == "__main__":
    main()
