"""Recording on a simulated clock (log times and chunking independent of the machine), and holes in the
device's seq that late frames fill (an event queued behind its command's ACK) are not written as gaps."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from robowrangler.protocol import generated as gen
from robowrangler.recorder import LinkRecorder, RecordingWriter, read_recording
from robowrangler.recorder.errors import RecordingError
from robowrangler.recorder.gaps import REORDER_WINDOW


def telemetry_frame(i: int, *, seq: int) -> bytes:
    msg = gen.Telemetry(time_ms=20 * i, state=gen.State.AIRBORNE, fault_bits=0, rope_speed_target_mmps=4000,
                        rope_speed_setpoint_mmps=4000, rope_speed_mmps=3990 + i % 7, motor_rpm=2500,
                        esc_pulse_us=1400, battery_mv=11987, heartbeat_age_ms=40, rx_ok=i, rx_bad=0,
                        rx_duplicates=0, nacks=0, events=3, tick_overruns=0,
                        **{f.name: 0 for f in gen.Telemetry.FIELDS[16:]})
    return gen.encode_frame(msg, seq)


def event_frame(i: int, *, seq: int) -> bytes:
    return gen.encode_frame(gen.Event(20 * i, 4, gen.EventKind.STATE_CHANGED, gen.State.ARMED, gen.State.SPINUP, 0),
                            seq)


def _simulated_recording(path: Path, *, sleep_s: float) -> None:
    sim_ns = [0]
    with RecordingWriter(path, source="sil", seed=3, time_base="simulation", clock_ns=lambda: sim_ns[0],
                         flush_period_s=0.5) as w:
        rec = LinkRecorder(w)
        for i in range(120):
            sim_ns[0] = i * 20_000_000
            rec.on_received(telemetry_frame(i, seq=i), host_s=i * 0.02)
            if i == 60:
                time.sleep(sleep_s)  # a busy machine: the wall clock must not change the file
        rec.finish(host_s=120 * 0.02)


def test_a_simulated_clock_stamps_log_times_and_the_file_does_not_depend_on_wall_time(tmp_path: Path) -> None:
    a, b = tmp_path / "a.mcap", tmp_path / "b.mcap"
    _simulated_recording(a, sleep_s=0.0)
    _simulated_recording(b, sleep_s=0.7)  # longer than flush_period_s of wall time
    r = read_recording(a)
    assert r.meta["time_base"] == "simulation"
    assert r.telemetry["log_time_ns"].tolist() == [i * 20_000_000 for i in range(120)]
    created_a, created_b = r.meta["created_utc"], read_recording(b).meta["created_utc"]
    assert len(created_a) == len(created_b)
    bytes_a = a.read_bytes().replace(created_a.encode(), b"")
    bytes_b = b.read_bytes().replace(created_b.encode(), b"")
    assert bytes_a == bytes_b  # same bytes apart from the wall-clock start time


def test_clock_must_be_callable(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match="clock_ns: expected a callable"):
        RecordingWriter(tmp_path / "x.mcap", source="sil", time_base="simulation", clock_ns=5)


def _record(path: Path, frames: list[bytes]) -> LinkRecorder:
    with RecordingWriter(path, source="other") as w:
        rec = LinkRecorder(w)
        for k, frame in enumerate(frames):
            rec.on_received(frame, host_s=k * 0.001)
        rec.finish(host_s=len(frames) * 0.001)
    return rec


def test_an_event_arriving_after_the_ack_numbered_after_it_is_no_gap(tmp_path: Path) -> None:
    # as the firmware does after ARM: telemetry 10, 11, the ACK 13 (sent at once), the event 12 (queued)
    frames = [telemetry_frame(0, seq=10), telemetry_frame(1, seq=11),
              gen.encode_frame(gen.Ack(10, 5, gen.State.ARMED), 13), event_frame(1, seq=12)]
    frames += [telemetry_frame(2 + i, seq=14 + i) for i in range(REORDER_WINDOW + 10)]
    rec = _record(tmp_path / "r.mcap", frames)
    r = read_recording(tmp_path / "r.mcap")
    assert r.gaps == [] and rec.gaps_written == 0 and rec.reordered_filled == 1
    assert rec.gap_detector.gaps == 1  # the live counter saw the hole when it opened


def test_a_hole_partly_filled_is_written_as_what_is_still_missing(tmp_path: Path) -> None:
    frames = [telemetry_frame(0, seq=10), telemetry_frame(1, seq=11), telemetry_frame(5, seq=15),
              event_frame(5, seq=13)]  # 12, 14 lost; 13 late
    frames += [telemetry_frame(6 + i, seq=16 + i) for i in range(REORDER_WINDOW + 10)]
    rec = _record(tmp_path / "r.mcap", frames)
    gaps = [(g["from_seq"], g["to_seq"], g["missing"]) for g in read_recording(tmp_path / "r.mcap").gaps]
    assert gaps == [(12, 12, 1), (14, 14, 1)]
    assert (rec.gaps_written, rec.frames_missing) == (2, 2)


def test_a_hole_still_open_at_the_end_is_written_and_a_restart_at_once(tmp_path: Path) -> None:
    frames = [telemetry_frame(0, seq=500), telemetry_frame(1, seq=501), telemetry_frame(4, seq=504),
              telemetry_frame(5, seq=505), telemetry_frame(0, seq=0), telemetry_frame(1, seq=1)]  # then a reboot
    _record(tmp_path / "r.mcap", frames)
    gaps = [(g["from_seq"], g["to_seq"], g["missing"]) for g in read_recording(tmp_path / "r.mcap").gaps]
    assert gaps == [(502, 503, 2), (506, None, None)]  # the held hole first: written in the order detected


def test_a_frame_as_late_as_the_detector_still_calls_reordered_fills_the_hole(tmp_path: Path) -> None:
    frames = [telemetry_frame(0, seq=10), telemetry_frame(1, seq=11)]
    frames += [telemetry_frame(i, seq=i + 10) for i in range(3, REORDER_WINDOW + 3)]  # 13 .. 12 + 64
    frames += [event_frame(2, seq=12)]  # exactly REORDER_WINDOW behind the newest frame
    rec = _record(tmp_path / "r.mcap", frames)
    assert rec.gap_detector.reordered == 1 and rec.reordered_filled == 1
    assert read_recording(tmp_path / "r.mcap").gaps == []
