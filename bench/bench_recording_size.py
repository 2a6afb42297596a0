"""Size of a recording, zstd chunks (what `wrangler record` writes) against uncompressed chunks.

    uv run python bench/bench_recording_size.py [--seconds 10]

Records the live SIL (real time, signed link) for SECONDS while the rope spins up to 4 m/s, flies and lands,
through the same LinkRecorder as `wrangler record`, then writes the very same records again with
compression="none" and prints both sizes, the ratio and bytes per second of recording.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from robowrangler.client import Client
from robowrangler.recorder import read_recording
from robowrangler.recorder.link import LinkRecorder, RecordingTransport
from robowrangler.recorder.writer import RecordingWriter
from robowrangler.transport import open_transport
from robowrangler_sim.sil import SilSession

KEY = bytes(range(16))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        zstd_path, plain_path = Path(tmp) / "zstd.mcap", Path(tmp) / "plain.mcap"
        with SilSession(speedup=1.0, key=KEY) as sil:
            sil.run_in_background()
            sil.wait_until(0.6)
            writer = RecordingWriter(zstd_path, source="sil", device_url=sil.cmd_url)
            recorder = LinkRecorder(writer)
            with Client(sil.cmd_url, key=KEY, transport=RecordingTransport(open_transport(sil.cmd_url),
                                                                            recorder)) as rw:
                rw.arm()
                start = time.monotonic()
                while time.monotonic() - start < args.seconds:
                    rw.spin(4.0)
                    time.sleep(min(2.0, max(0.0, args.seconds - (time.monotonic() - start))))
                    rw.spindown()
                    time.sleep(min(1.0, max(0.0, args.seconds - (time.monotonic() - start))))
            recorder.finish()
            writer.close()
        rec = read_recording(zstd_path)
        with RecordingWriter(plain_path, source="sil", compression="none") as plain:
            for topic, records in rec.records.items():
                for r in records:
                    plain.write(topic, r.data, log_time_ns=r.log_time_ns, publish_time_ns=r.publish_time_ns)
        zstd_b, plain_b = zstd_path.stat().st_size, plain_path.stat().st_size
        n = sum(len(v) for v in rec.records.values())
        print(f"recording of {rec.duration_s:.1f} s: {len(rec.telemetry['seq'])} telemetry, {len(rec.events)} events, "
              f"{len(rec.commands)} commands ({n} messages)")
        print(f"uncompressed chunks: {plain_b / 1024:.1f} KiB ({plain_b / rec.duration_s / 1024:.1f} KiB/s)")
        print(f"zstd chunks:         {zstd_b / 1024:.1f} KiB ({zstd_b / rec.duration_s / 1024:.1f} KiB/s), "
              f"{plain_b / zstd_b:.1f}x smaller")


if __name__ == "__main__":
    main()
