"""Observation records follow the committed recording schema (fields, types, required, no extras)."""

import json
from pathlib import Path

import pytest

from robowrangler_sim.string_shooter import ModuleMotion, ShooterParams, StringShooter, StringShooterParamError
from robowrangler_sim.string_shooter.observations import loop_observation_record, plant_truth_record

SCHEMAS = Path(__file__).resolve().parents[2] / "protocol" / "recording" / "schemas"
TYPES = {"number": (int, float), "integer": (int,), "string": (str,), "array": (list,), "boolean": (bool,),
         "null": (type(None),)}


def _conforms(record: dict, schema: dict) -> None:
    """The subset of JSON Schema these two schemas use: required, additionalProperties, types, minItems."""
    props = schema["properties"]
    assert set(schema.get("required", [])) <= set(record)
    if schema.get("additionalProperties") is False:
        assert set(record) <= set(props)
    for key, value in record.items():
        spec = props[key]
        types = spec["type"] if isinstance(spec["type"], list) else [spec["type"]]
        assert isinstance(value, tuple(t for name in types for t in TYPES[name])), key
        if "minItems" in spec:
            assert len(value) >= spec["minItems"]
        if "minimum" in spec:
            assert value >= spec["minimum"]


@pytest.fixture(scope="module")
def frames():
    sim = StringShooter(ShooterParams(), loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=5.0, phi_rad=0.3))
    return sim.run(1.0, frame_interval_s=0.5).frames


def test_loop_observation_matches_schema_and_shape_table_frame(frames):
    schema = json.loads((SCHEMAS / "loop_observation.schema.json").read_text())
    rec = loop_observation_record(frames[-1], camera_id="side", frame_index=7, n_points=30)
    _conforms(rec, schema)
    assert len(rec["points_m"]) == 30 and rec["points_m"][0] == [0.0, 0.0]
    assert rec["phi_rad"] == pytest.approx(0.3)


def test_plant_truth_matches_schema_and_says_the_loop_flies(frames):
    schema = json.loads((SCHEMAS / "sim_plant_truth.schema.json").read_text())
    rec = plant_truth_record(frames[-1], loop_length_m=1.0)
    _conforms(rec, schema)
    assert rec["loop_airborne"] is True
    assert plant_truth_record(frames[0], loop_length_m=1.0)["rope_speed_mps"] == pytest.approx(5.0)


def test_bad_camera_frame_index_raises(frames):
    with pytest.raises(StringShooterParamError, match="frame_index"):
        loop_observation_record(frames[0], camera_id="side", frame_index=-1)
