"""rw_config (the configuration record kept in flash, through ctypes): its layout as the Python side would
write it (a record packed with struct and zlib.crc32 is valid to C), defaults valid with the parameter
defaults and no key, a flipped bit anywhere caught by the CRC-32, set_key / set_params store and reseal."""

from __future__ import annotations

import ctypes
import random
import struct
import zlib

import pytest

from robowrangler.protocol import generated as proto
from rw_core_ctypes import f32

PARAM_COUNT = len(proto.PARAMS)
MAGIC = 0x46435752  # RW_CONFIG_MAGIC, "RWCF"
VERSION = 2
EPOCH_LIMIT = 1 << 31  # RW_CONFIG_EPOCH_LIMIT
BOOT_COUNTER_MAX = (1 << 31) - 1  # RW_CONFIG_BOOT_COUNTER_MAX
TEST_KEY = bytes(range(16))


class Config(ctypes.Structure):
    """rw_config (firmware/core/rw_config.h), field for field."""

    _fields_ = [("magic", ctypes.c_uint32), ("version", ctypes.c_uint16), ("size", ctypes.c_uint16),
                ("boot_counter", ctypes.c_uint32), ("commits", ctypes.c_uint32), ("session_epoch", ctypes.c_uint32),
                ("key", ctypes.c_uint8 * proto.KEY_LEN), ("key_set", ctypes.c_uint8), ("password_set", ctypes.c_uint8),
                ("reserved", ctypes.c_uint8 * 2), ("wifi_ssid", ctypes.c_char * 33), ("wifi_password", ctypes.c_char * 64),
                ("reserved2", ctypes.c_uint8 * 3), ("params", ctypes.c_float * PARAM_COUNT), ("crc32", ctypes.c_uint32)]


# The same layout as a struct format (little-endian, no padding): what a host tool writing the record uses.
RECORD_FORMAT = f"<IHHIII{proto.KEY_LEN}sBB2s33s64s3s{PARAM_COUNT}f"


@pytest.fixture(scope="module")
def lib(rw_core: ctypes.CDLL) -> ctypes.CDLL:
    p = ctypes.POINTER(Config)
    for name, restype, argtypes in (("rw_config_defaults", None, [p]), ("rw_config_valid", ctypes.c_bool, [p]),
                                    ("rw_config_seal", None, [p]), ("rw_config_set_key", None, [p, ctypes.c_char_p]),
                                    ("rw_config_set_params", None, [p, ctypes.POINTER(ctypes.c_float)]),
                                    ("rw_crc32", ctypes.c_uint32, [ctypes.c_char_p, ctypes.c_uint32]),
                                    ("rw_config_session_id", ctypes.c_uint32, [p]),
                                    ("rw_config_next_boot", ctypes.c_bool, [p]),
                                    ("rw_config_new_epoch", ctypes.c_bool, [p, ctypes.c_uint32]),
                                    ("rw_config_clear_key", None, [p])):
        fn = getattr(rw_core, name)
        fn.restype, fn.argtypes = restype, argtypes
    return rw_core


def defaults(lib: ctypes.CDLL) -> Config:
    c = Config()
    ctypes.memset(ctypes.byref(c), 0xCC, ctypes.sizeof(c))
    lib.rw_config_defaults(ctypes.byref(c))
    return c


def test_defaults_are_valid_with_the_parameter_defaults_and_no_key(lib: ctypes.CDLL) -> None:
    c = defaults(lib)
    assert c.size == ctypes.sizeof(Config) == struct.calcsize(RECORD_FORMAT) + 4, "layout of the mirror differs"
    assert lib.rw_config_valid(ctypes.byref(c))
    assert (c.magic, c.version, c.boot_counter, c.commits, c.session_epoch, c.key_set) == (MAGIC, VERSION, 0, 0, 0, 0)
    assert bytes(c.key) == bytes(proto.KEY_LEN)
    assert [c.params[i] for i in range(PARAM_COUNT)] == [f32(p.default) for p in proto.PARAMS]


def test_crc32_is_zlibs(lib: ctypes.CDLL) -> None:
    rng = random.Random(4)
    assert lib.rw_crc32(b"123456789", 9) == 0xCBF43926
    for n in (0, 1, 3, 64, 271):
        data = bytes(rng.randrange(256) for _ in range(n))
        assert lib.rw_crc32(data, n) == zlib.crc32(data)


def test_a_record_packed_in_python_is_valid_to_c(lib: ctypes.CDLL) -> None:
    params = [f32(p.default) for p in proto.PARAMS]
    params[proto.PARAMS_BY_NAME["speed_kp"].id] = f32(0.07)
    body = struct.pack(RECORD_FORMAT, MAGIC, VERSION, struct.calcsize(RECORD_FORMAT) + 4, 41, 3, 0x2BADCAFE,
                       TEST_KEY, 1, 1,
                       b"\0\0", b"ropelab", b"secret", b"\0\0\0", *params)
    record = Config.from_buffer_copy(body + struct.pack("<I", zlib.crc32(body)))
    assert lib.rw_config_valid(ctypes.byref(record))
    assert record.boot_counter == 41 and bytes(record.key) == TEST_KEY and record.wifi_ssid == b"ropelab"
    assert lib.rw_config_session_id(ctypes.byref(record)) == 0x2BADCAFE + 41
    assert record.params[proto.PARAMS_BY_NAME["speed_kp"].id] == f32(0.07)
    bad = Config.from_buffer_copy(body + struct.pack("<I", zlib.crc32(body) ^ 1))
    assert not lib.rw_config_valid(ctypes.byref(bad))


def test_any_flipped_bit_invalidates_the_record(lib: ctypes.CDLL) -> None:
    c = defaults(lib)
    lib.rw_config_set_key(ctypes.byref(c), TEST_KEY)
    raw = bytearray(bytes(c))
    for bit in range(len(raw) * 8):
        raw[bit // 8] ^= 1 << (bit % 8)
        assert not lib.rw_config_valid(ctypes.byref(Config.from_buffer(raw))), f"bit {bit} flipped went unnoticed"
        raw[bit // 8] ^= 1 << (bit % 8)
    assert lib.rw_config_valid(ctypes.byref(Config.from_buffer(raw)))


def test_set_key_and_set_params_store_and_reseal(lib: ctypes.CDLL) -> None:
    c = defaults(lib)
    crc0 = c.crc32
    lib.rw_config_set_key(ctypes.byref(c), TEST_KEY)
    assert lib.rw_config_valid(ctypes.byref(c)) and c.key_set == 1 and bytes(c.key) == TEST_KEY
    assert c.crc32 == zlib.crc32(bytes(c)[:-4]) != crc0
    values = (ctypes.c_float * PARAM_COUNT)(*[f32(p.default) for p in proto.PARAMS])
    values[proto.PARAMS_BY_NAME["speed_ki"].id] = 0.5
    lib.rw_config_set_params(ctypes.byref(c), values)
    assert lib.rw_config_valid(ctypes.byref(c))
    assert list(c.params) == list(values)
    assert bytes(c.key) == TEST_KEY, "set_params keeps the key"
    c.boot_counter += 1  # a change without a seal
    assert not lib.rw_config_valid(ctypes.byref(c))
    lib.rw_config_seal(ctypes.byref(c))
    assert lib.rw_config_valid(ctypes.byref(c))


def test_a_new_epoch_restarts_the_session_range_and_out_of_range_epochs_change_nothing(lib: ctypes.CDLL) -> None:
    c = defaults(lib)
    c.boot_counter, c.commits = 7, 2
    lib.rw_config_seal(ctypes.byref(c))
    before = bytes(c)
    for bad in (EPOCH_LIMIT, 0xFFFFFFFF):
        assert not lib.rw_config_new_epoch(ctypes.byref(c), bad)
        assert bytes(c) == before, f"epoch {bad:#x} was refused but changed the record"
    assert lib.rw_config_new_epoch(ctypes.byref(c), EPOCH_LIMIT - 1)
    assert (c.session_epoch, c.boot_counter, c.commits) == (EPOCH_LIMIT - 1, 0, 3)
    assert lib.rw_config_valid(ctypes.byref(c))
    ids = []
    for _ in range(3):
        assert lib.rw_config_next_boot(ctypes.byref(c)) and lib.rw_config_valid(ctypes.byref(c))
        ids.append(lib.rw_config_session_id(ctypes.byref(c)))
    assert ids == [EPOCH_LIMIT, EPOCH_LIMIT + 1, EPOCH_LIMIT + 2]  # epoch + boot counter, strictly growing


def test_the_boot_counter_never_wraps_the_session_id(lib: ctypes.CDLL) -> None:
    """The largest epoch plus the largest boot counter still fits a u32: no session id ever wraps to a used one."""
    c = defaults(lib)
    assert lib.rw_config_new_epoch(ctypes.byref(c), EPOCH_LIMIT - 1)
    c.boot_counter = BOOT_COUNTER_MAX - 1
    lib.rw_config_seal(ctypes.byref(c))
    assert lib.rw_config_next_boot(ctypes.byref(c))
    assert lib.rw_config_session_id(ctypes.byref(c)) == 0xFFFFFFFE  # (2^31 - 1) + (2^31 - 1)
    before = bytes(c)
    assert not lib.rw_config_next_boot(ctypes.byref(c)) and bytes(c) == before  # used up: refused, unchanged


def test_records_with_an_epoch_or_counter_out_of_range_are_not_trusted(lib: ctypes.CDLL) -> None:
    for field, value in (("session_epoch", EPOCH_LIMIT), ("boot_counter", BOOT_COUNTER_MAX + 1)):
        c = defaults(lib)
        setattr(c, field, value)
        lib.rw_config_seal(ctypes.byref(c))
        assert not lib.rw_config_valid(ctypes.byref(c)), field


def test_clear_key_forgets_the_key_and_reseals(lib: ctypes.CDLL) -> None:
    c = defaults(lib)
    lib.rw_config_set_key(ctypes.byref(c), TEST_KEY)
    lib.rw_config_clear_key(ctypes.byref(c))
    assert c.key_set == 0 and bytes(c.key) == bytes(proto.KEY_LEN) and lib.rw_config_valid(ctypes.byref(c))
