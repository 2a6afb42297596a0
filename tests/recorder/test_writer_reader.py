"""RecordingWriter -> read_recording: records, columns, chunk flushing, truncation at any byte, validation."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from robowrangler.protocol import generated as gen
from robowrangler.recorder import (LinkRecorder, RecordingSchemaError, RecordingWriter, read_recording)
from robowrangler.recorder.errors import RecordingError


def telemetry_frame(i: int, *, seq: int) -> bytes:
    msg = gen.Telemetry(time_ms=20 * i, state=gen.State.AIRBORNE, fault_bits=0, rope_speed_target_mmps=4000,
                        rope_speed_setpoint_mmps=3900 + i % 7, rope_speed_mmps=3876 + i % 13, motor_rpm=2500,
                        esc_pulse_us=1400 + i % 5, battery_mv=11987, heartbeat_age_ms=40, rx_ok=i, rx_bad=0,
                        rx_duplicates=0, nacks=0, events=3, tick_overruns=0,
                        **{f.name: 0 for f in gen.Telemetry.FIELDS[16:]})
    return gen.encode_frame(msg, seq)


def test_link_recorder_converts_wire_units_to_si_and_records_gaps(tmp_path: Path) -> None:
    path = tmp_path / "r.mcap"
    with RecordingWriter(path, source="other", seed=7) as w:
        rec = LinkRecorder(w)
        for i in range(60):
            if not 20 <= i < 25:  # frames 20..24 lost on the link
                rec.on_received(telemetry_frame(i, seq=(65500 + i) % 65536), host_s=i * 0.02)
        rec.on_sent(gen.encode_frame(gen.SetRopeSpeed(2000), 40), host_s=1.3)
        rec.on_received(gen.encode_frame(gen.Nack(12, 40, gen.NackReason.BELOW_TOV_GUARD, gen.State.AIRBORNE, 2990),
                                         60 - 65536 + 65500), host_s=1.31)
        rec.on_sent(gen.encode_frame(gen.Spindown(), 41), host_s=1.4)
        rec.finish(host_s=1.5)
    r = read_recording(path)
    assert not r.truncated and r.meta["source"] == "other" and r.meta["seed"] == "7"
    t = r.telemetry
    assert len(t["seq"]) == 55 and t["seq"].dtype == np.int64
    assert t["rope_speed_mps"][0] == 3876 / 1000 and t["battery_v"][0] == 11.987 and t["time_s"][1] == 0.02
    assert t["state"][0] == "AIRBORNE" and t["fault_bits"][0] == ()
    (gap,) = r.gaps
    assert (gap["from_seq"], gap["to_seq"], gap["missing"]) == ((65500 + 20) % 65536, (65500 + 24) % 65536, 5)
    assert (gap["last_time_s"], gap["resume_time_s"]) == (0.38, 0.5)
    nack, unanswered = r.commands
    assert nack["message"] == "SET_ROPE_SPEED" and nack["fields"] == {"rope_speed_mps": 2.0}
    assert (nack["verdict"], nack["reason"], nack["state"], nack["detail"]) == ("NACK", "BELOW_TOV_GUARD",
                                                                                "AIRBORNE", 2990)
    assert unanswered["message"] == "SPINDOWN" and unanswered["verdict"] == "NO_REPLY"


def test_writer_refuses_a_record_that_violates_its_schema(tmp_path: Path) -> None:
    with RecordingWriter(tmp_path / "r.mcap", source="sil") as w:
        with pytest.raises(RecordingSchemaError, match=r"/link/gap record violates its schema: /: missing"):
            w.write("/link/gap", {"stream": "device", "from_seq": 3})
        with pytest.raises(RecordingError, match="topic: expected one of"):
            w.write("/device/telemetri", {})
    with pytest.raises(RecordingError, match="source: expected one of"):
        RecordingWriter(tmp_path / "s.mcap", source="rig")


def test_chunks_are_flushed_by_time_while_the_writer_stays_open(tmp_path: Path) -> None:
    path = tmp_path / "r.mcap"
    w = RecordingWriter(path, source="other", flush_period_s=0.1, flush_messages=10_000)
    rec = LinkRecorder(w)
    for i in range(30):
        rec.on_received(telemetry_frame(i, seq=i))
    time.sleep(0.4)  # no more messages: the background flush must still write the chunk
    copy = tmp_path / "copy.mcap"
    shutil.copy(path, copy)  # what a kill -9 now would leave
    r = read_recording(copy)
    assert r.truncated and len(r.telemetry["seq"]) == 30
    w.close()


def test_a_file_cut_at_any_byte_reads_every_complete_chunk(tmp_path: Path) -> None:
    path = tmp_path / "r.mcap"
    per_chunk = 20
    with RecordingWriter(path, source="other", flush_messages=per_chunk) as w:
        rec = LinkRecorder(w)
        for i in range(10 * per_chunk):
            rec.on_received(telemetry_frame(i, seq=i))
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    chunk_ends = sorted(c.chunk_start_offset + c.chunk_length for c in summary.chunk_indexes)
    assert len(chunk_ends) == 10
    data = path.read_bytes()
    rng = np.random.default_rng(1)
    cuts = sorted({*chunk_ends[:-1], *(e - 1 for e in chunk_ends), *rng.integers(chunk_ends[0] - 500,
                                                                                    len(data), 25).tolist()})
    for cut in cuts:
        cut_path = tmp_path / "cut.mcap"
        cut_path.write_bytes(data[:cut])
        r = read_recording(cut_path)
        complete = sum(1 for e in chunk_ends if e <= cut)
        assert len(r.telemetry["log_time_ns"]) == per_chunk * complete, cut
        assert r.truncated and r.truncation_reason, cut
        assert r.telemetry["seq"].tolist() == list(range(per_chunk * complete))
    assert not read_recording(path).truncated
