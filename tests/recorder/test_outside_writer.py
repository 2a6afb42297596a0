"""A recording written by someone outside the project - only the `mcap` library, `json` and the schema
files of protocol/recording/schemas/ - is read by the reader like one of ours.

Everything the writer side needs comes from the schema files (names from their $id, fields from
their properties); no robowrangler import is used to write.
"""

from __future__ import annotations

import json
from pathlib import Path

from mcap.writer import CompressionType, Writer

ROOT = Path(__file__).resolve().parents[2]
SCHEMA_DIR = ROOT / "protocol" / "recording" / "schemas"


def _schema(stem: str) -> tuple[str, bytes, dict]:
    text = (SCHEMA_DIR / f"{stem}.schema.json").read_bytes()
    schema = json.loads(text)
    version = schema["$id"].split(":")[3]
    return f"robowrangler.{stem}.v{version}", text, schema


def write_like_a_rope_simulator(path: Path, *, seconds: int = 2) -> dict:
    """A first-principles simulator's recording: meta, telemetry, plant truth, loop observations."""
    tele_name, tele_text, tele_schema = _schema("device_telemetry")
    state_names = tele_schema["properties"]["state"]["anyOf"][0]["enum"]
    assert {"SPINUP", "AIRBORNE"} <= set(state_names)
    meta_schema = json.loads((SCHEMA_DIR / "meta.schema.json").read_text())
    with open(path, "wb") as f:
        w = Writer(f, compression=CompressionType.NONE)
        w.start(profile="", library="rope-sim 0.3")
        w.add_metadata("/meta", {
            "format": meta_schema["properties"]["format"]["const"],
            "format_version": meta_schema["properties"]["format_version"]["const"],
            "source": "simulator",
            "schema_hash": tele_schema["$comment"].split("hash ")[1].rstrip("."),
            "units": meta_schema["properties"]["units"]["const"],
            "time_base": "simulation",
            "seed": "42",
        })
        channels = {}
        for topic, stem in (("/device/telemetry", "device_telemetry"), ("/sim/plant_truth", "sim_plant_truth"),
                            ("/loop/observation", "loop_observation")):
            name, text, _ = _schema(stem)
            schema_id = w.register_schema(name=name, encoding="jsonschema", data=text)
            channels[topic] = w.register_channel(topic=topic, message_encoding="json", schema_id=schema_id)
        rate_hz = 50
        for i in range(seconds * rate_hz):
            t_s = i / rate_hz
            t_ns = i * 20_000_000
            speed = min(5.0, 2.5 * t_s)
            tele = {}
            for field, prop in tele_schema["properties"].items():  # every field the schema requires
                kind = prop.get("type")
                tele[field] = [] if kind == "array" else 0 if kind == "integer" else 0.0
            tele.update(time_s=t_s, seq=i % 65536, state="AIRBORNE" if speed > 2.99 else "SPINUP",
                        rope_speed_mps=speed, rope_speed_setpoint_mps=speed, rope_speed_target_mps=5.0,
                        battery_v=12.1, esc_pulse_us=1000 + int(80 * speed), motor_rpm=int(speed * 636.6))
            w.add_message(channels["/device/telemetry"], log_time=t_ns, publish_time=t_ns,
                          data=json.dumps(tele).encode(), sequence=i)
            truth = {"time_s": t_s, "rope_speed_mps": speed * 1.01, "external_rope_load_n": 0.0,
                     "loop_airborne": speed > 2.6, "rope_tension_n": 0.0055 * speed ** 2}
            w.add_message(channels["/sim/plant_truth"], log_time=t_ns, publish_time=t_ns,
                          data=json.dumps(truth).encode(), sequence=i)
            if i % 10 == 0:
                obs = {"time_s": t_s, "camera_id": "sim-cam", "frame_index": i // 10, "phi_rad": 0.17,
                       "rope_speed_mps": speed, "points_m": [[0.0, 0.0], [0.4, 0.1], [0.8, 0.0], [0.4, -0.05],
                                                             [0.0, -0.02]]}
                w.add_message(channels["/loop/observation"], log_time=t_ns, publish_time=t_ns,
                              data=json.dumps(obs).encode(), sequence=i // 10)
        w.finish()
    return {"telemetry": seconds * rate_hz, "observations": seconds * rate_hz // 10}


def test_a_recording_written_with_only_mcap_and_the_schema_files_reads_back(tmp_path: Path) -> None:
    path = tmp_path / "sim.mcap"
    written = write_like_a_rope_simulator(path)

    from robowrangler.recorder import read_recording
    from robowrangler.recorder.summary import summarize

    rec = read_recording(path)
    assert not rec.truncated and rec.meta["source"] == "simulator" and rec.meta["time_base"] == "simulation"
    assert len(rec.telemetry["time_s"]) == written["telemetry"]
    assert rec.telemetry["rope_speed_mps"][-1] == 2.5 * 1.98 and rec.telemetry["time_s"].dtype.kind == "f"
    truth = rec.table("/sim/plant_truth")
    assert truth["loop_airborne"].dtype == bool and truth["rope_tension_n"][-1] > 0.1
    obs = rec.records["/loop/observation"]
    assert len(obs) == written["observations"] and obs[3].data["points_m"][1] == [0.4, 0.1]
    summary = summarize(rec)
    assert summary["channels"] == {"/device/telemetry": 100, "/loop/observation": 10, "/sim/plant_truth": 100}
    assert summary["telemetry"]["states"] == ["SPINUP", "AIRBORNE"]


def test_the_example_in_schema_md_writes_a_readable_recording(tmp_path: Path, monkeypatch) -> None:
    import re

    text = (ROOT / "protocol" / "recording" / "schema.md").read_text()
    code = re.search(r"## 4\..*?```python\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(ROOT)
    exec(code.replace('"run.mcap"', repr(str(tmp_path / "run.mcap"))), {})

    from robowrangler.recorder import read_recording

    rec = read_recording(tmp_path / "run.mcap")
    assert rec.topic_counts == {"/sim/plant_truth": 500} and rec.chunks == 20 and not rec.truncated
