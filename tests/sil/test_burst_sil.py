"""A burst in the SIL (the same firmware core, the plant in lockstep, the real signed UDP link), recorded through
the public recording API (RecordingSession fed by the simulator's RecordingHost): the firmware samples every
tick, the recording gets every sample on /device/burst, the samples are the pulses the plant received and the
battery it reported, and the speed loop does exactly what it does without the burst."""

from __future__ import annotations

from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler.recorder import RecordingSession, read_recording
from robowrangler.recorder.burst import bursts
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.recording_host import RecordingHost, read_params

SAMPLES = 600


def _run(path: Path, *, burst: bool) -> tuple[list[float], list[gen.Telemetry], int]:
    """Spin up to 5 m/s, then BURST_START (or a PARAM_GET in the same tick), run 3.5 s: the pulse the plant got
    each tick, the telemetry, and the tick at which the command went out."""
    pulses: list[float] = []
    with SilSession(speedup=None, seed=3) as sil, RecordingSession(
            path, source="sil", seed=3, time_base="simulation", clock_ns=lambda: sil.plant.time_us * 1000) as rec:
        sil.tick_hooks.append(lambda s: pulses.append(s.last_esc_pulse_fine_us))
        host = RecordingHost(sil, rec)
        host.run_for(0.6)
        read_params(host)
        host.arm_and_spin(5000, settle_s=1.5)
        tick = len(pulses)
        if burst:
            verdict = host.command(gen.BurstStart(SAMPLES))
            assert isinstance(verdict, gen.Ack), verdict
        else:
            host.command(gen.ParamGet(0))  # a command in the same tick, answered the same way
        host.run_for(3.5)  # 0.6 s of capture, then about 50 frames a second at 50 Hz telemetry
        rec.close(host_s=sil.time_s)
        host.close()
        return pulses, list(host.received.telemetry), tick


def test_burst_in_sil_is_complete_exact_and_changes_nothing(native_build_dir: Path, tmp_path: Path) -> None:
    pulses, telemetry, tick = _run(tmp_path / "burst.mcap", burst=True)
    pulses0, telemetry0, tick0 = _run(tmp_path / "plain.mcap", burst=False)
    assert tick == tick0
    assert pulses == pulses0, "the speed loop's output is the same tick for tick"
    assert [t.rope_speed_mmps for t in telemetry] == [t.rope_speed_mmps for t in telemetry0]
    assert telemetry[-1].tick_overruns == 0 and telemetry[-1].tx_dropped == 0
    assert [t.time_ms for t in telemetry] == [t.time_ms for t in telemetry0], "telemetry on time, none displaced"

    rec = read_recording(tmp_path / "burst.mcap")  # validates every record against its schema
    got, = bursts(rec)
    assert got.complete and got.sample_count == SAMPLES and got.frames == -(-SAMPLES // gen.BURST_SAMPLES_PER_FRAME)
    assert "/device/params" in rec.metadata
    # sample 0 is the tick that took the command; the plant received the pulse one lockstep exchange later
    start = next(k for k in range(tick, tick + 20) if pulses[k:k + SAMPLES] == list(got.esc_pulse_fine_us))
    assert start - tick <= 3
    assert any(p != round(p) for p in got.esc_pulse_fine_us), "1/3 us resolution reaches the plant and the recording"
    volts = [t.battery_mv / 1000 for t in telemetry]
    assert min(volts) - 0.05 <= min(got.battery_v) and max(got.battery_v) <= max(volts) + 0.05
    assert not bursts(read_recording(tmp_path / "plain.mcap"))
