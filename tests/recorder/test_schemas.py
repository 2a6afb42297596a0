"""The recording schemas: generated fresh from the protocol spec, complete, and enforced."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from robowrangler.protocol import generated as gen
from robowrangler.recorder import schemas_generated as sg
from robowrangler.recorder.json_schema_check import SchemaKeywordError, check_keywords, first_error

ROOT = Path(__file__).resolve().parents[2]
SCHEMA_DIR = ROOT / "protocol" / "recording" / "schemas"
WIRE_TO_RECORDING = {"_ms": "_s", "_mmps": "_mps", "_mv": "_v", "_um": "_m", "_third_us": "_fine_us"}


def test_generated_schemas_are_fresh() -> None:
    result = subprocess.run([sys.executable, str(ROOT / "protocol" / "recording" / "generate_schemas.py"), "--check"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr


def test_schema_files_are_the_ones_the_host_uses_and_use_only_checked_keywords() -> None:
    files = {p.name for p in SCHEMA_DIR.glob("*.schema.json")}
    assert files == {fname for _, fname, _ in sg.CHANNELS.values()} | {"meta.schema.json"}
    for _, fname, text in sg.CHANNELS.values():
        assert (SCHEMA_DIR / fname).read_text() == text
        check_keywords(json.loads(text))
    check_keywords(json.loads(sg.META_SCHEMA))
    with pytest.raises(SchemaKeywordError, match="oneOf"):
        check_keywords({"type": "object", "properties": {"x": {"oneOf": []}}})


def test_every_telemetry_and_event_field_of_the_protocol_is_a_recording_field() -> None:
    for topic, cls in (("/device/telemetry", gen.Telemetry), ("/device/event", gen.Event)):
        props = json.loads(sg.CHANNELS[topic][2])["properties"]
        expected = {"seq"}
        for f in cls.FIELDS:
            name = f.name
            for wire, si in WIRE_TO_RECORDING.items():
                if name.endswith(wire):
                    name = name[: -len(wire)] + si
            expected.add(name)
        assert set(props) == expected, topic
    commands = json.loads(sg.CHANNELS["/host/command"][2])["properties"]["message"]["enum"]
    assert set(commands) == {c.NAME for c in gen.MESSAGES.values() if c.KIND == gen.MsgKind.COMMAND}


def _telemetry_record() -> dict:
    schema = json.loads(sg.CHANNELS["/device/telemetry"][2])
    record = {}
    for name, prop in schema["properties"].items():
        if "anyOf" in prop:
            record[name] = prop["anyOf"][0]["enum"][0]
        elif prop.get("type") == "array":
            record[name] = []
        elif prop.get("type") == "integer":
            record[name] = 0
        else:
            record[name] = 0.0
    return record


def test_validator_names_the_field_expected_and_actual() -> None:
    schema = json.loads(sg.CHANNELS["/device/telemetry"][2])
    good = _telemetry_record()
    assert first_error(good, schema) is None
    assert "expected <= 65535" in first_error({**good, "seq": 70000}, schema)
    assert "/rope_speed_mps: expected number, got '3'" in first_error({**good, "rope_speed_mps": "3"}, schema)
    assert "missing required field 'battery_v'" in first_error({k: v for k, v in good.items() if k != "battery_v"},
                                                                schema)
    assert "unexpected field 'battery_mv'" in first_error({**good, "battery_mv": 12000}, schema)
    assert "/state" in first_error({**good, "state": "FLYING"}, schema)
    assert first_error({**good, "state": "UNKNOWN_42"}, schema) is None  # a newer firmware's state
    assert "expected integer" in first_error({**good, "motor_rpm": True}, schema)
    assert "finite" in first_error({**good, "battery_v": float("nan")}, schema)


def test_command_schema_ties_fields_to_the_message() -> None:
    schema = json.loads(sg.CHANNELS["/host/command"][2])
    base = {"seq": 3, "transmissions": 1, "verdict": "ACK", "reason": None, "state": "SPINUP", "detail": None,
            "reply_latency_s": 0.002}
    assert first_error({**base, "message": "SET_ROPE_SPEED", "fields": {"rope_speed_mps": 4.0}}, schema) is None
    assert first_error({**base, "message": "ARM", "fields": {}}, schema) is None
    assert first_error({**base, "message": "ARM", "fields": {"rope_speed_mps": 4.0}}, schema) is not None
    assert first_error({**base, "message": "SET_ROPE_SPEED", "fields": {}}, schema) is not None


def test_plant_truth_takes_extra_values_only_with_a_unit_suffix() -> None:
    schema = json.loads(sg.CHANNELS["/sim/plant_truth"][2])
    assert first_error({"time_s": 1.0, "rope_tension_n": 0.02, "tip_height_m": None}, schema) is None
    assert "unexpected field 'tension'" in first_error({"time_s": 1.0, "tension": 0.02}, schema)
    assert "expected number or null" in first_error({"time_s": 1.0, "drag_n": "high"}, schema)
    assert "missing required field 'time_s'" in first_error({"rope_speed_mps": 1.0}, schema)


def test_loop_observation_points_are_x_z_pairs() -> None:
    schema = json.loads(sg.CHANNELS["/loop/observation"][2])
    obs = {"time_s": 0.5, "camera_id": "cam0", "phi_rad": 0.2, "points_m": [[0.0, 0.0], [0.3, 0.1]]}
    assert first_error(obs, schema) is None
    assert "/points_m/1: expected at most 2 items" in first_error({**obs, "points_m": [[0, 0], [0.3, 0.1, 0.0]]},
                                                                  schema)
    assert "expected at least 2 items" in first_error({**obs, "points_m": [[0.0, 0.0]]}, schema)
