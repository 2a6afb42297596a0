"""A burst beside 100 Hz telemetry in the SIL (the same firmware core, the plant in lockstep, the real signed UDP
link, recorded through the public recording API): the burst streams in the signing slots telemetry leaves, the
control output is the same tick for tick as in the same run without it, no tick overruns, the host gets the
whole burst; and a BURST_DATA datagram lost on the way shows in the recorded burst as a gap, never silently."""

from __future__ import annotations

import socket
from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler.recorder import RecordingSession, read_recording
from robowrangler.recorder.burst import bursts
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.recording_host import RecordingHost

SAMPLES = 300  # 50 frames
RUN_S = 5.0  # 0.3 s of capture, then the stream beside 100 Hz telemetry (about 4 s: bench/bench_burst.py)


class _LoseOneBurstFrame:
    """The host's UDP socket with the n-th BURST_DATA datagram lost on the way in (everything else passes)."""

    def __init__(self, sock: socket.socket, n: int) -> None:
        self._sock = sock
        self._n = n
        self._seen = 0
        self.lost: bytes | None = None

    def recv(self, size: int) -> bytes:
        while True:
            data = self._sock.recv(size)
            if len(data) > 3 and data[3] == gen.MsgId.BURST_DATA:
                self._seen += 1
                if self._seen == self._n:
                    self.lost = data
                    continue
            return data

    def __getattr__(self, name: str):  # noqa: ANN204
        return getattr(self._sock, name)


def _run(path: Path, *, burst: bool, lose_frame: int | None = None) -> tuple[list[float], list[gen.Telemetry],
                                                                            bytes | None]:
    """Telemetry at 100 Hz, spin up to 5 m/s, then BURST_START (or a PARAM_GET in the same tick), run RUN_S: the
    pulse the plant got each tick, the telemetry, and the datagram lost (lose_frame: the n-th BURST_DATA)."""
    pulses: list[float] = []
    with SilSession(speedup=None, seed=4) as sil, RecordingSession(
            path, source="sil", seed=4, time_base="simulation", clock_ns=lambda: sil.plant.time_us * 1000) as rec:
        sil.tick_hooks.append(lambda s: pulses.append(s.last_esc_pulse_fine_us))
        host = RecordingHost(sil, rec)
        lossy = None
        if lose_frame is not None:
            lossy = host._sock = _LoseOneBurstFrame(host._sock, lose_frame)  # noqa: SLF001 (the wire, not the API)
        host.run_for(0.6)
        rate = gen.PARAMS_BY_NAME["telemetry_rate_hz"].id
        assert isinstance(host.command(gen.ParamSet(rate, 100.0)), gen.Ack)
        host.arm_and_spin(5000, settle_s=1.5)
        verdict = host.command(gen.BurstStart(SAMPLES) if burst else gen.ParamGet(0))
        assert isinstance(verdict, gen.Ack), verdict
        host.run_for(RUN_S)
        rec.close(host_s=sil.time_s)
        host.close()
        return pulses, list(host.received.telemetry), None if lossy is None else lossy.lost


def test_burst_beside_100hz_telemetry_changes_no_tick_and_arrives_whole(native_build_dir: Path,
                                                                         tmp_path: Path) -> None:
    pulses, telemetry, _ = _run(tmp_path / "burst.mcap", burst=True)
    pulses0, telemetry0, _ = _run(tmp_path / "plain.mcap", burst=False)
    assert len(pulses) == len(pulses0) and pulses == pulses0, "the same ESC pulse, tick for tick"
    assert telemetry[-1].tick_overruns == 0 and telemetry[-1].tx_dropped == 0
    times, times0 = [t.time_ms for t in telemetry], [t.time_ms for t in telemetry0]
    # the same frames, packed at the same ticks (the last may still be being signed when the run stops)
    assert len(times0) - 1 <= len(times) <= len(times0) and times == times0[:len(times)], "telemetry on time"
    streaming = [t for t in times if t >= times[-1] - 1000 * RUN_S + 50]
    assert len(streaming) >= 100 * RUN_S - 6, "100 Hz while the burst is captured and streamed"
    got, = bursts(read_recording(tmp_path / "burst.mcap"))
    assert got.complete and got.sample_count == SAMPLES
    assert got.frames == -(-SAMPLES // gen.BURST_SAMPLES_PER_FRAME)


def test_a_burst_frame_lost_on_the_way_is_a_gap_in_the_recording(native_build_dir: Path, tmp_path: Path) -> None:
    _, telemetry, lost = _run(tmp_path / "lossy.mcap", burst=True, lose_frame=5)
    assert lost is not None, "the fifth BURST_DATA datagram was sent (and lost)"
    _, lost_msg = gen.decode_message(lost)
    first = lost_msg.first_sample
    got, = bursts(read_recording(tmp_path / "lossy.mcap"))
    n = gen.BURST_SAMPLES_PER_FRAME
    assert not got.complete and got.missing == [(first, first + n - 1)] and got.missing_samples == n
    assert got.frames == -(-SAMPLES // n) - 1
    assert all(v != v for v in got.esc_pulse_fine_us[first:first + n]), "NaN where nothing came"
    assert telemetry[-1].tx_dropped == 0, "the device sent it: the loss is the network's"
