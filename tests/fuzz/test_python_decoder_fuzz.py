"""Property tests of the Python frame decoder (robowrangler.protocol.generated) on hostile input.

decode_frame / decode_message on arbitrary bytes and on mutations of valid unsigned and signed frames:
the only exception is FrameError (with a NackReason); tag_valid never raises; a signed frame that was
changed in any way never verifies, an unchanged one always does. Seeds: hypothesis runs derandomized
(the same examples on every run) so CI is reproducible; the C decoder gets the same treatment from
libFuzzer (tests/fuzz/test_fuzz_targets.py).
"""

from __future__ import annotations

import json
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robowrangler.protocol import generated as gen

ROOT = Path(__file__).resolve().parents[2]
_DOC = json.loads((ROOT / "protocol" / "vectors" / "vectors.json").read_text())
TEST_KEY = bytes.fromhex(_DOC["test_key_hex"])
VALID_FRAMES = [bytes.fromhex(v["hex"]) for v in _DOC["vectors"] if v["expect"] == "ok"]
UNSIGNED_FRAMES = [f for f in VALID_FRAMES if not gen.decode_frame(f).signed]

PROPERTY = settings(max_examples=400, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])
keys = st.binary(min_size=gen.KEY_LEN, max_size=gen.KEY_LEN)


def _decode_or_frame_error(data: bytes) -> tuple[gen.Frame, gen.Message] | None:
    """decode_message(data), or None if it raised FrameError (any other exception fails the test)."""
    try:
        return gen.decode_message(data)
    except gen.FrameError as err:
        assert isinstance(err.reason, gen.NackReason)
        assert err.msg_id is None or 0 <= err.msg_id <= 255
        assert err.seq is None or 0 <= err.seq <= 0xFFFF
        return None


@st.composite
def mutations(draw, original: bytes) -> bytes:
    """original changed by 1-4 edits: bit flips, byte overwrites, insertions, deletions, truncation."""
    data = bytearray(original)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["flip", "set", "insert", "delete", "truncate"]))
        if op == "insert" or not data:
            data.insert(draw(st.integers(0, len(data))), draw(st.integers(0, 255)))
            continue
        i = draw(st.integers(0, len(data) - 1))
        if op == "flip":
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "set":
            data[i] = draw(st.integers(0, 255))
        elif op == "delete":
            del data[i]
        else:
            del data[i:]
    return bytes(data)


@st.composite
def signed_frames(draw) -> tuple[bytes, bytes]:
    """(a valid frame signed with a drawn key, session and counter; the key)."""
    _, msg = gen.decode_message(draw(st.sampled_from(UNSIGNED_FRAMES)))
    key = draw(keys)
    data = gen.encode_frame(msg, draw(st.integers(0, 0xFFFF)), key=key,
                            session_id=draw(st.integers(0, 2**32 - 1)), counter=draw(st.integers(0, 2**64 - 1)))
    return data, key


@PROPERTY
@given(data=st.binary(max_size=2 * gen.MAX_FRAME_LEN), key=keys)
def test_arbitrary_bytes_raise_only_frame_error(data: bytes, key: bytes) -> None:
    decoded = _decode_or_frame_error(data)
    if decoded is None:
        return
    frame, msg = decoded
    assert len(data) == gen.HEADER_LEN + len(frame.payload) + gen.CHECKSUM_LEN + (gen.SIGNATURE_LEN if frame.signed else 0)
    assert isinstance(gen.tag_valid(frame, key), bool)
    if not frame.signed:
        assert gen.tag_valid(frame, key) is False


@PROPERTY
@given(data=st.binary(min_size=gen.HEADER_LEN, max_size=gen.MAX_FRAME_LEN).map(
    lambda b: bytes([gen.MAGIC, gen.PROTOCOL_VERSION]) + b[2:]))
def test_bytes_behind_a_valid_header_raise_only_frame_error(data: bytes) -> None:
    """Past the magic and version checks (where random bytes rarely get): still only FrameError."""
    _decode_or_frame_error(data)


@PROPERTY
@given(st.sampled_from(UNSIGNED_FRAMES).flatmap(lambda f: st.tuples(st.just(f), mutations(f))))
def test_mutated_unsigned_frames_raise_only_frame_error(pair: tuple[bytes, bytes]) -> None:
    original, mutated = pair
    decoded = _decode_or_frame_error(mutated)
    if decoded is not None and mutated != original:
        # an edit the CRC-16 misses (about 1 in 65536 multi-byte edits) still decodes consistently
        frame, msg = decoded
        assert msg.MSG_ID == frame.msg_id and len(frame.payload) == msg.PAYLOAD_LEN


@PROPERTY
@given(st.sampled_from(UNSIGNED_FRAMES), st.data())
def test_one_flipped_bit_of_an_unsigned_frame_is_refused(original: bytes, data: st.DataObject) -> None:
    """CRC-16/CCITT detects every single-bit error; the header checks catch the rest."""
    bit = data.draw(st.integers(0, len(original) * 8 - 1))
    mutated = bytearray(original)
    mutated[bit // 8] ^= 1 << (bit % 8)
    assert _decode_or_frame_error(bytes(mutated)) is None


@PROPERTY
@given(signed_frames().flatmap(lambda fk: st.tuples(st.just(fk), mutations(fk[0]))), keys)
def test_a_mutated_signed_frame_never_verifies(pair: tuple[tuple[bytes, bytes], bytes], other_key: bytes) -> None:
    (original, key), mutated = pair
    decoded = _decode_or_frame_error(mutated)
    if mutated == original:
        assert decoded is not None and gen.tag_valid(decoded[0], key) is True
        return
    if decoded is not None:
        assert gen.tag_valid(decoded[0], key) is False
        assert isinstance(gen.tag_valid(decoded[0], other_key), bool)


@PROPERTY
@given(signed_frames(), keys)
def test_a_signed_frame_verifies_with_its_key_only(frame_key: tuple[bytes, bytes], other_key: bytes) -> None:
    data, key = frame_key
    frame, _ = gen.decode_message(data)
    assert frame.signed and gen.tag_valid(frame, key) is True
    assert gen.tag_valid(frame, other_key) is (other_key == key)
