"""Link and stream figures of TELEMETRY and burst capture (BURST_START / BURST_DATA), on the SIL firmware.

Prints: the frame sizes on the wire (signed, as over WiFi) and what they cost the link at the telemetry rate;
for telemetry at 50 and 100 Hz, the bytes a second the device sends while flying, without and while streaming a
full burst (1000 samples = 1 s at 1 kHz), how long the stream takes, and whether telemetry stayed on its period
(frames and their spacing in device time) and the speed loop's pulse unchanged tick for tick (against the
same run without the burst). The tick's cycle cost on the Cortex-M0+ is bench_tick_instructions.py's.

    uv run python bench/bench_burst.py
"""

from __future__ import annotations

import math

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost

SAMPLES = 1000
UDP_IP_HEADER_B = 28  # IPv4 20 + UDP 8
WINDOW_S = 14.0  # from the command on: the capture (1 s) and the stream beside 100 Hz telemetry (about 12 s)


def frame_len(msg: gen.Message) -> int:
    return len(gen.encode_frame(msg, 0, key=bytes(16), session_id=1, counter=1))


def run(rate_hz: float, *, burst: bool) -> dict:
    with SilSession(speedup=None, seed=5) as sil:
        host = ScriptedHost(sil)
        pulses: list[float] = []
        sil.tick_hooks.append(lambda s: pulses.append(s.last_esc_pulse_fine_us))
        host.run_for(0.6)
        assert isinstance(host.command(gen.ParamSet(gen.PARAMS_BY_NAME["telemetry_rate_hz"].id, rate_hz)), gen.Ack)
        host.arm_and_spin(5000, settle_s=1.5)
        n_raw0, t0_ms = len(host.received.raw), host.sil.plant.time_us // 1000
        tel0 = len(host.received.telemetry)
        verdict = host.command(gen.BurstStart(SAMPLES) if burst else gen.ParamGet(0))
        assert isinstance(verdict, gen.Ack), verdict
        frames_expected = math.ceil(SAMPLES / gen.BURST_SAMPLES_PER_FRAME)
        last_burst_ms = None
        end_us = host.sil.plant.time_us + round(WINDOW_S * 1e6)
        n_burst = 0
        while host.sil.plant.time_us < end_us:
            host.tick()
            got = sum(1 for r in host.received.raw[n_raw0:] if r[3] == gen.MsgId.BURST_DATA)
            if got != n_burst:
                n_burst = got
                if got >= frames_expected and last_burst_ms is None:
                    last_burst_ms = host.sil.plant.time_us // 1000
        raw = host.received.raw[n_raw0:]
        tel = host.received.telemetry[tel0:]
        spacing = {b.time_ms - a.time_ms for a, b in zip(tel, tel[1:])}
        bytes_total = sum(len(r) + UDP_IP_HEADER_B for r in raw)
        out = {"bytes_per_s": bytes_total / WINDOW_S, "burst_frames": n_burst, "telemetry": len(tel),
               "spacing_ms": sorted(spacing), "pulses": pulses, "tx_dropped": tel[-1].tx_dropped,
               "stream_s": None if last_burst_ms is None else (last_burst_ms - t0_ms) / 1000 - SAMPLES / 1000}
        host.close()
        return out


def main() -> None:
    tel_b = frame_len(gen.Telemetry(*[0] * len(gen.Telemetry.FIELDS)))
    burst_b = frame_len(gen.BurstData(0, 0, 0, 0, 0, 0, bytes(48)))
    print("frames on the wire (signed, as over WiFi):")
    print(f"  TELEMETRY   {tel_b} B ({gen.Telemetry.PAYLOAD_LEN} B payload), {tel_b + UDP_IP_HEADER_B} B with IP/UDP")
    print(f"  BURST_DATA  {burst_b} B, {gen.BURST_SAMPLES_PER_FRAME} samples of {gen.BURST_SAMPLE_LEN} B; a "
          f"{SAMPLES}-sample burst = {math.ceil(SAMPLES / gen.BURST_SAMPLES_PER_FRAME)} frames, "
          f"{SAMPLES * gen.BURST_SAMPLE_LEN} B of buffer")
    for rate in (50.0, 100.0):
        print(f"  telemetry alone at {rate:g} Hz: {rate * tel_b / 1000:.1f} kB/s UDP payload, "
              f"{rate * (tel_b + UDP_IP_HEADER_B) / 1000:.1f} kB/s with IP/UDP")
    print(f"\nSIL, flying at 5 m/s, {WINDOW_S:g} s from the command on (device time):")
    print("rate    burst  link kB/s  stream s  frames  telemetry  spacing ms  tx_dropped  pulses as without")
    stream_s: dict[float, float | None] = {}
    for rate in (50.0, 100.0):
        plain = run(rate, burst=False)
        with_b = run(rate, burst=True)
        stream_s[rate] = with_b["stream_s"]
        same = with_b["pulses"] == plain["pulses"]
        for name, r in (("no", plain), ("yes", with_b)):
            stream = "-" if r["stream_s"] is None else f"{r['stream_s']:.2f}"
            print(f"{rate:5g} Hz {name:>5s} {r['bytes_per_s'] / 1000:10.1f} {stream:>9s} {r['burst_frames']:7d} "
                  f"{r['telemetry']:10d} {str(r['spacing_ms']):>11s} {r['tx_dropped']:11d}  "
                  f"{'-' if name == 'no' else ('yes' if same else 'NO')}")

    frames = math.ceil(SAMPLES / gen.BURST_SAMPLES_PER_FRAME)
    for rate, t in stream_s.items():
        shown = f"not complete in {WINDOW_S:g} s" if t is None else f"{t:.2f} s ({frames / t:.0f} BURST_DATA frames/s)"
        print(f"burst stream time beside {rate:g} Hz telemetry: {shown}")


if __name__ == "__main__":
    main()
