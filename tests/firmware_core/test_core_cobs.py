"""rw_cobs (the USB serial framing of the firmware core, through ctypes) against the Python cobs package the
host uses: each decodes what the other encodes, the encodings hold no zero byte and match byte for byte,
and malformed input (what the cobs package refuses) decodes to 0."""

from __future__ import annotations

import ctypes
import random

import pytest
from cobs import cobs


def _max_encoded(n: int) -> int:
    """RW_COBS_MAX_ENCODED(n) (rw_cobs.h)."""
    return n + n // 254 + 1


@pytest.fixture(scope="module")
def codec(rw_core: ctypes.CDLL) -> ctypes.CDLL:
    for name in ("rw_cobs_encode", "rw_cobs_decode"):
        fn = getattr(rw_core, name)
        fn.restype = ctypes.c_size_t
        fn.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t]
    return rw_core


def c_encode(lib: ctypes.CDLL, data: bytes, *, cap: int | None = None) -> bytes | None:
    """rw_cobs_encode of data; None when it returns 0 (does not fit)."""
    cap = _max_encoded(len(data)) if cap is None else cap
    out = ctypes.create_string_buffer(cap + 16)
    n = lib.rw_cobs_encode(data, len(data), out, cap)
    return out.raw[:n] if n else None


def c_decode(lib: ctypes.CDLL, data: bytes, *, cap: int = 1024) -> bytes | None:
    """rw_cobs_decode of data; None when it returns 0 (malformed, or does not fit in cap)."""
    out = ctypes.create_string_buffer(cap + 16)
    n = lib.rw_cobs_decode(data, len(data), out, cap)
    return out.raw[:n] if n else None


def _samples(seed: int, count: int) -> list[bytes]:
    """Byte strings with zero runs, zero-free stretches around 254 bytes, and plain random bytes."""
    rng = random.Random(seed)
    out = []
    for _ in range(count):
        kind = rng.randrange(3)
        if kind == 0:  # short runs of zeros between short runs of other bytes
            parts = []
            while sum(map(len, parts)) < rng.randrange(1, 300):
                parts.append(bytes(rng.randrange(0, 5)))
                parts.append(bytes(rng.randrange(1, 256) for _ in range(rng.randrange(0, 7))))
            out.append(b"".join(parts))
        elif kind == 1:  # a long zero-free block of 250..510 bytes, zeros around it sometimes
            block = bytes(rng.randrange(1, 256) for _ in range(rng.randrange(250, 511)))
            out.append(bytes(rng.randrange(0, 2)) + block + bytes(rng.randrange(0, 3)))
        else:
            out.append(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 120))))
    return out


def _ends_with_full_block(data: bytes) -> bool:
    """True when the last zero-free stretch is a non-zero multiple of 254 bytes long."""
    tail = len(data) - (data.rfind(b"\x00") + 1)
    return tail > 0 and tail % 254 == 0


def test_each_side_decodes_what_the_other_encodes(codec: ctypes.CDLL) -> None:
    for data in _samples(seed=1, count=400):
        ours = c_encode(codec, data)
        assert ours is not None and b"\x00" not in ours and len(ours) <= _max_encoded(len(data))
        assert cobs.decode(ours) == data
        assert c_decode(codec, cobs.encode(data)) == data
        assert c_decode(codec, ours) == data


def test_encoding_matches_the_cobs_package_byte_for_byte(codec: ctypes.CDLL) -> None:
    samples = [d for d in _samples(seed=2, count=400) if not _ends_with_full_block(d)]
    samples += [bytes(n) for n in (1, 2, 253, 254, 255)]
    samples += [bytes(range(1, 256)) * 2, b"\x11\x22\x00\x33", bytes(range(1, 254))]
    for data in samples:
        assert c_encode(codec, data) == cobs.encode(data), data.hex()


def test_final_full_block_is_encoded_canonically(codec: ctypes.CDLL) -> None:
    data = bytes(range(1, 255))
    assert c_encode(codec, data) == cobs.encode(data)


def test_malformed_input_decodes_to_zero_where_the_package_refuses(codec: ctypes.CDLL) -> None:
    rng = random.Random(3)
    refused = 0
    for _ in range(3000):
        garbage = bytes(rng.choice((0, 1, 2, 3, 0xFF, rng.randrange(256))) for _ in range(rng.randrange(1, 40)))
        try:
            expected = cobs.decode(garbage)
        except cobs.DecodeError:
            expected = None
            refused += 1
        got = c_decode(codec, garbage)
        assert got == (expected or None), garbage.hex()
    assert refused > 1000, "the sample must exercise malformed input"
    for bad in (b"\x03\x11\x00\x02\x33", b"\x05\x11\x22", b"\x00\x11", b"\x02\x11\x04\x22"):
        assert c_decode(codec, bad) is None, bad.hex()


def test_output_buffers_too_small_give_zero(codec: ctypes.CDLL) -> None:
    data = b"\x11\x22\x00\x33"
    assert c_encode(codec, data, cap=_max_encoded(len(data)) - 1) is None
    encoded = c_encode(codec, data)
    assert c_decode(codec, encoded, cap=3) is None
    assert c_decode(codec, encoded, cap=4) == data
