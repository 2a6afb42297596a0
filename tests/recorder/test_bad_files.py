"""Files that are not usable recordings: a typed RecordingError naming the file and the reason, and
`wrangler inspect` / `wrangler replay` exit 1 (ERROR) with one line on stderr."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.writer import CompressionType, Writer

from robowrangler.cli.exit_status import ExitStatus
from robowrangler.protocol import generated as gen
from robowrangler.recorder import (LinkRecorder, NotARecording, RecordingSchemaError,
                                   RecordingWriter, read_recording)
from robowrangler.recorder import schemas_generated as sg
from robowrangler.recorder.errors import RecordingError


def _good_recording(path: Path, n: int = 50, flush_messages: int = 200) -> Path:
    with RecordingWriter(path, source="other", compression="none", flush_messages=flush_messages) as w:
        rec = LinkRecorder(w)
        for i in range(n):
            msg = gen.Telemetry(**{f.name: 0 for f in gen.Telemetry.FIELDS})
            rec.on_received(gen.encode_frame(msg, i))
    return path


def _mcap(path: Path, *, meta: dict | None, topic: str, schema_name: str, schema: bytes, messages: list[bytes]) -> Path:
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.NONE)
        w.start()
        if meta is not None:
            w.add_metadata("/meta", meta)
        sid = w.register_schema(name=schema_name, encoding="jsonschema", data=schema)
        cid = w.register_channel(topic=topic, message_encoding="json", schema_id=sid)
        for i, data in enumerate(messages):
            w.add_message(cid, log_time=i * 1000, publish_time=i * 1000, data=data)
        w.finish()
    return path


META = {"format": sg.FORMAT, "format_version": "1", "source": "board", "schema_hash": f"0x{sg.SCHEMA_HASH:04X}",
        "units": sg.UNITS_CONVENTION, "time_base": "unix"}


def bad_files(tmp: Path) -> dict[str, tuple[Path, type, str]]:
    """name -> (file, expected error class, text the message must contain)."""
    rng = np.random.default_rng(3)
    random_bytes = tmp / "random.mcap"
    random_bytes.write_bytes(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
    empty = tmp / "empty.mcap"
    empty.write_bytes(b"")
    foreign = _mcap(tmp / "foreign.mcap", meta=None, topic="/imu", schema_name="Imu", schema=b"{}",
                    messages=[b'{"ax": 0.1}'] * 5)
    name, fname, text = sg.CHANNELS["/link/gap"]
    violating = _mcap(tmp / "violating.mcap", meta=META, topic="/link/gap", schema_name=name, schema=text.encode(),
                      messages=[json.dumps({"stream": "device", "from_seq": 1, "to_seq": 2, "missing": 2,
                                            "last_time_s": 1.0, "resume_time_s": 1.1, "silent_s": -0.5}).encode()])
    wrong_schema = _mcap(tmp / "wrong_schema.mcap", meta=META, topic="/device/telemetry", schema_name="my.Telemetry",
                         schema=b"{}", messages=[b"{}"])
    not_json = _mcap(tmp / "not_json.mcap", meta=META, topic="/link/gap", schema_name=name, schema=text.encode(),
                     messages=[b"\x00\x01 not json"])
    bad_meta = _mcap(tmp / "bad_meta.mcap", meta={**META, "source": "robot"}, topic="/link/gap", schema_name=name,
                     schema=text.encode(), messages=[])
    return {
        "random bytes": (random_bytes, NotARecording, "not an MCAP file"),
        "empty file": (empty, NotARecording, "the file is empty"),
        "foreign MCAP": (foreign, NotARecording, "no /meta metadata record"),
        "schema violation": (violating, RecordingSchemaError, "/link/gap message #1"),
        "wrong channel schema": (wrong_schema, RecordingSchemaError, "schema 'my.Telemetry'"),
        "not JSON": (not_json, RecordingSchemaError, "is not JSON"),
        "bad meta": (bad_meta, RecordingSchemaError, "/source"),
    }


CASES = ["random bytes", "empty file", "foreign MCAP", "schema violation", "wrong channel schema", "not JSON",
         "bad meta"]


@pytest.mark.parametrize("case", CASES)
def test_reader_raises_a_typed_error_naming_file_and_reason(tmp_path: Path, case: str) -> None:
    path, cls, text = bad_files(tmp_path)[case]
    with pytest.raises(cls) as raised:
        read_recording(path)
    assert isinstance(raised.value, RecordingError)
    assert str(path) in str(raised.value) and text in str(raised.value)
    assert raised.value.path == str(path)


def test_schema_violation_names_the_field_expected_and_actual(tmp_path: Path) -> None:
    path, _, _ = bad_files(tmp_path)["schema violation"]
    with pytest.raises(RecordingSchemaError, match=r"/silent_s: expected >= 0, got -0\.5"):
        read_recording(path)


@pytest.mark.parametrize("case", ["random bytes", "foreign MCAP", "schema violation"])
def test_cli_exits_error_with_one_line_on_stderr(tmp_path: Path, wrangler, case: str) -> None:
    path, _, text = bad_files(tmp_path)[case]
    for argv in (["inspect", str(path)], ["replay", str(path), "--plot", str(tmp_path / "p.png")]):
        status, out, err = wrangler(*argv)
        assert status == ExitStatus.ERROR, (argv, err)
        assert err.count("\n") == 1 and text in err and str(path) in err
        assert out == ""
    assert not (tmp_path / "p.png").exists()


def test_cli_missing_file_is_a_usage_error(tmp_path: Path, wrangler) -> None:
    status, _, err = wrangler("inspect", str(tmp_path / "nope.mcap"))
    assert status == ExitStatus.USAGE and "does not exist" in err


def _flip_in_chunk(path: Path, chunk_number: int) -> None:
    """Flip one bit inside the chunk_number-th chunk's message data (its CRC no longer matches)."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        starts = sorted(ci.chunk_start_offset for ci in make_reader(f).get_summary().chunk_indexes)
    data = bytearray(path.read_bytes())
    payload = data.index(b'"rope_speed_mps"', starts[chunk_number - 1])
    assert chunk_number == len(starts) or payload < starts[chunk_number]
    data[payload + 3] ^= 0x20
    path.write_bytes(bytes(data))


def test_a_damaged_chunk_is_skipped_and_reported_and_the_rest_is_read(tmp_path: Path, wrangler) -> None:
    """One flipped bit costs the chunk it is in, not the recording (as the mcap library's tools read it)."""
    path = _good_recording(tmp_path / "damaged.mcap", n=50, flush_messages=10)
    intact = read_recording(path)
    assert intact.chunks == 5 and intact.damaged == []
    _flip_in_chunk(path, 2)
    rec = read_recording(path)
    assert len(rec.damaged) == 1 and rec.damaged[0].startswith("chunk 2 at byte ") and "CRC mismatch" in rec.damaged[0]
    assert rec.chunks == 4 and len(rec.telemetry["seq"]) == 40
    assert list(rec.telemetry["seq"]) == [*range(10), *range(20, 50)]
    status, out, err = wrangler("--json", "inspect", str(path))
    assert status == ExitStatus.OK and "DAMAGED" not in out
    summary = json.loads(out)
    assert summary["damaged"] == rec.damaged and summary["channels"]["/device/telemetry"] == 40
    assert err.startswith(f"wrangler: {path}: chunk 2 at byte ")
    status, out, _ = wrangler("inspect", str(path))
    assert status == ExitStatus.OK and "DAMAGED: chunk 2" in out


def test_a_file_cut_inside_its_header_record_is_called_truncated(tmp_path: Path) -> None:
    """Bytes 9..42 end inside the MCAP Header record (after the 8-byte magic): truncation, named as such."""
    whole = _good_recording(tmp_path / "whole.mcap").read_bytes()
    for cut in (9, 12, 17, 30, 42):
        path = tmp_path / f"cut{cut}.mcap"
        path.write_bytes(whole[:cut])
        with pytest.raises(NotARecording) as raised:
            read_recording(path)
        text = str(raised.value)
        assert "truncated before its /meta record" in text, text
        assert "claims" not in text and "at byte 8" in text, text


def test_replay_plots_a_window_and_refuses_an_empty_or_backwards_one(tmp_path: Path, wrangler) -> None:
    """--from/--to pick device time; the six panels (speed, ESC, guide, load, battery, state) come out."""
    path = _good_recording(tmp_path / "r.mcap", n=50)  # device time 0 (all-zero telemetry): one instant
    whole = tmp_path / "whole.png"
    status, _, err = wrangler("replay", str(path), "--plot", str(whole))
    assert status == ExitStatus.OK, err
    status, _, err = wrangler("replay", str(path), "--plot", str(tmp_path / "none.png"), "--from", "5")
    assert status == ExitStatus.ERROR and "nothing to plot between 5 and - s of device time" in err
    assert not (tmp_path / "none.png").exists()
    status, _, err = wrangler("replay", str(path), "--plot", str(tmp_path / "x.png"), "--from", "2", "--to", "1")
    assert status == ExitStatus.USAGE and "--to: expected a time after --from (2 s)" in err
