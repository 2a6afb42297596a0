"""Golden vectors: the Python codec and the C codec must give the same verdict on every frame."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from robowrangler.protocol import generated as gen

ROOT = Path(__file__).resolve().parents[2]
_DOC = json.loads((ROOT / "protocol" / "vectors" / "vectors.json").read_text())
VECTORS = _DOC["vectors"]
TEST_KEY = bytes.fromhex(_DOC["test_key_hex"])


@pytest.mark.parametrize("vector", VECTORS, ids=[v["name"] for v in VECTORS])
def test_python_codec_matches_golden_vector(vector: dict) -> None:
    data = bytes.fromhex(vector["hex"])
    if vector["expect"] == "ok":
        frame, msg = gen.decode_message(data)
        assert msg.NAME == vector["message"]
        assert frame.seq == vector["seq"]
        for name, value in vector["fields"].items():
            got = getattr(msg, name)
            got = got.hex() if isinstance(got, bytes) else got
            assert (math.isclose(got, value, rel_tol=0, abs_tol=0) if isinstance(value, float) else got == value), name
        if "tag_valid" not in vector:
            assert not frame.signed and gen.encode_frame(msg, frame.seq) == data
        else:
            assert frame.signed and (frame.session_id, frame.counter) == (vector["session_id"], vector["counter"])
            assert gen.tag_valid(frame, TEST_KEY) == vector["tag_valid"]
            if vector["tag_valid"]:
                assert gen.encode_frame(msg, frame.seq, key=TEST_KEY, session_id=frame.session_id,
                                        counter=frame.counter) == data
    else:
        with pytest.raises(gen.FrameError) as info:
            gen.decode_frame(data)
        assert info.value.reason == gen.NackReason[vector["expect"]]
        if "msg_id" in vector:
            assert (info.value.msg_id, info.value.seq) == (vector["msg_id"], vector["seq"])


def test_c_codec_passes_every_golden_vector(native_build_dir: Path) -> None:
    exe = native_build_dir / "protocol_c_test" / "rw_protocol_vectors_test"
    result = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stdout + result.stderr
    assert f"{len(VECTORS) + 1} passed, 0 failed" in result.stdout


def test_vectors_cover_every_message_and_every_frame_level_reason() -> None:
    valid = {v["message"] for v in VECTORS if v["expect"] == "ok"}
    assert valid == {cls.NAME for cls in gen.MESSAGES.values()}
    frame_reasons = {"TRUNCATED", "BAD_MAGIC", "BAD_VERSION", "UNSUPPORTED_FLAGS", "OVERSIZE", "BAD_LENGTH",
                     "BAD_CHECKSUM", "UNKNOWN_MESSAGE"}
    assert frame_reasons <= {v["expect"] for v in VECTORS}


def test_generated_files_are_fresh() -> None:
    result = subprocess.run([sys.executable, str(ROOT / "protocol" / "generate.py"), "--check"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr


def test_encoder_refuses_values_that_do_not_fit_their_type() -> None:
    with pytest.raises(gen.FieldRangeError, match=r"SET_ROPE_SPEED.rope_speed_mmps: expected an integer"):
        gen.encode_frame(gen.SetRopeSpeed(2**31), 1)
    with pytest.raises(gen.FieldRangeError, match="PARAM_GET.param_id"):
        gen.encode_frame(gen.ParamGet(-1), 1)
    with pytest.raises(gen.FieldRangeError, match="seq"):
        gen.encode_frame(gen.Arm(), 70000)


def test_schema_change_changes_crc_extra() -> None:
    sys.path.insert(0, str(ROOT / "protocol"))
    import generate

    spec = generate.load_spec()
    msg = next(m for m in spec.messages if m.name == "SET_ROPE_SPEED")
    before = msg.crc_extra
    msg.fields[0].type = "uint32"
    assert msg.crc_extra != before


@settings(max_examples=2000, deadline=None)
@given(st.binary(max_size=gen.MAX_FRAME_LEN + 8))
def test_python_decoder_never_fails_other_than_frame_error(data: bytes) -> None:
    try:
        gen.decode_message(data)
    except gen.FrameError as exc:
        assert isinstance(exc.reason, gen.NackReason)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda s: s.replace('id = 12\nname = "SET_ROPE_SPEED"', 'id = 11\nname = "SET_ROPE_SPEED"'), "reused"),
        (lambda s: s.replace('type = "int32", units = "mm/s", description = "Target',
                             'type = "int24", units = "mm/s", description = "Target'), "type must be one of"),
        (lambda s: s.replace("default = 2.6\n", "default = 20.0\n"), "default must lie in"),
        (lambda s: s.replace('name = "event_kind"', 'name = "event"').replace('enum = "event_kind"', 'enum = "event"'),
         "class names clash"),
    ],
    ids=["reused_id", "unknown_type", "default_out_of_range", "class_name_clash"],
)
def test_generator_rejects_a_bad_spec_with_a_precise_message(tmp_path: Path, edit, message: str) -> None:
    sys.path.insert(0, str(ROOT / "protocol"))
    import generate

    spec_text = (ROOT / "protocol" / "spec" / "robowrangler.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(edit(spec_text))
    assert bad.read_text() != spec_text, "the edit must apply"
    with pytest.raises(generate.SpecError, match=message):
        generate.load_spec(bad)


def test_siphash_matches_the_reference_vectors() -> None:
    key = bytes(range(16))
    assert gen.siphash24(key, b"") == (0x726FDB47DD0E0E31).to_bytes(8, "little")
    assert gen.siphash24(key, bytes(range(15))) == (0xA129CA6149BE45E5).to_bytes(8, "little")


def test_signing_refuses_a_bad_key_session_or_counter() -> None:
    with pytest.raises(gen.FieldRangeError, match="key: expected 16 bytes"):
        gen.encode_frame(gen.Arm(), 1, key=b"short")
    with pytest.raises(gen.FieldRangeError, match="session_id"):
        gen.encode_frame(gen.Arm(), 1, key=TEST_KEY, session_id=-1)
    with pytest.raises(gen.FieldRangeError, match="counter"):
        gen.encode_frame(gen.Arm(), 1, key=TEST_KEY, counter=2**64)


def test_text_fields_are_bounded_and_round_trip() -> None:
    frame = gen.encode_frame(gen.ProvisionSetWifiSsid("réseau"), 3)
    assert gen.decode_message(frame)[1].ssid == "réseau"
    with pytest.raises(gen.FieldRangeError, match="at most 32 UTF-8 bytes"):
        gen.encode_frame(gen.ProvisionSetWifiSsid("x" * 33), 3)
    with pytest.raises(gen.FieldRangeError, match="16 bytes"):
        gen.encode_frame(gen.ProvisionSetKey(b"\x00" * 15), 3)
