"""Write the fuzz targets' seed corpora (firmware/fuzz/corpus/<target>/) from the golden vectors.

    uv run python firmware/fuzz/make_corpus.py [--out DIR]   (default: firmware/fuzz/corpus)

frame_decode: every golden vector's bytes, one file each (valid, malformed and signed frames).
cobs_decode:  [output capacity byte] + the COBS encoding of each vector, plus the malformed encodings.
core:         input programs for fuzz_core.c (its header documents the layout: an options byte, an
              optional stored record, then [tag][len][bytes] chunks): every vector on each link, a flight
              (arm, spin up, heartbeats, relax, grasp, spin down), provisioning over serial then a signed
              command over WiFi, replays of signed frames, a stored record from the input, spindle and
              battery sensor events.
The output is deterministic (same vectors, same files); the script replaces the corpus directories.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shutil
import struct
import zlib
from pathlib import Path

from robowrangler.protocol import generated as gen

HERE = Path(__file__).resolve().parent
VECTORS_PATH = HERE.parents[1] / "protocol" / "vectors" / "vectors.json"

# fuzz_core.c options and chunk kinds
OPT_FUZZ_RECORD, OPT_SEAL_RECORD, OPT_NO_STORE, OPT_SAVE_FAILS = 0x01, 0x02, 0x04, 0x08
OPT_SIGN_WIFI, OPT_NO_SPINDLE, OPT_PREROLL, OPT_SESSION_STALE = 0x10, 0x20, 0x40, 0x80
SERIAL, WIFI, SENSORS, NOTHING = 0, 1, 2, 3
CONFIG_MAGIC, CONFIG_VERSION = 0x46435752, 2
CONFIG_HEAD_FORMAT = "<IHHIII16sBB2s33s64s3s"  # rw_config.h up to the parameters
CONFIG_SIZE_BYTES = struct.calcsize(CONFIG_HEAD_FORMAT) + 4 * len(gen.PARAMS) + 4  # sizeof(rw_config), CRC included
DELIVERY_CAP_BYTES = gen.MAX_FRAME_LEN + 1  # the core's receive buffer


def cobs_encode(data: bytes) -> bytes:
    """COBS without the delimiter (as rw_cobs_encode)."""
    out, block = bytearray(), bytearray()
    for byte in data:
        if byte == 0:
            out += bytes([len(block) + 1]) + block
            block.clear()
            continue
        block.append(byte)
        if len(block) == 254:
            out += bytes([255]) + block
            block.clear()
    return bytes(out + bytes([len(block) + 1]) + block)


def ticks_tag(kind: int, ticks: int) -> int:
    """The chunk tag for kind followed by about `ticks` ticks (v < 32: v ticks; else (v - 31) x 32)."""
    v = ticks if ticks < 32 else min(63, 31 + round(ticks / 32))
    return (v << 2) | kind


def chunk(kind: int, payload: bytes = b"", *, ticks: int = 1) -> bytes:
    assert len(payload) <= 255, len(payload)
    return bytes([ticks_tag(kind, ticks), len(payload)]) + payload


def sensors(*, battery_mv: int = 12000, encoder_silent: bool = False, spindle_silent: bool = False,
            spindle_load_raw: int = 0, limit_switch: bool = False, tick_us: int = 1000) -> bytes:
    return struct.pack("<HBBHBH", battery_mv, encoder_silent, spindle_silent, spindle_load_raw, limit_switch, tick_us)


def config_record(*, params: list[float], key: bytes | None, boot_counter: int, session_epoch: int = 0) -> bytes:
    """An rw_config record (rw_config.h layout, little-endian), sealed with its CRC-32."""
    body = struct.pack(CONFIG_HEAD_FORMAT, CONFIG_MAGIC, CONFIG_VERSION, CONFIG_SIZE_BYTES, boot_counter, 0,
                       session_epoch, key or bytes(16), 1 if key else 0, 0, b"", b"lab", b"", b"")
    body += struct.pack(f"<{len(params)}f", *params)
    assert len(body) == CONFIG_SIZE_BYTES - 4, len(body)
    return body + struct.pack("<I", zlib.crc32(body))


COMMIT = gen.ProvisionCommit(session_epoch=0x1234567)  # a commit with a fixed epoch (reproducible corpus)


def frame(msg: gen.Message, seq: int) -> bytes:
    return gen.encode_frame(msg, seq)


def core_programs(vectors: list[dict], test_key: bytes) -> dict[str, bytes]:
    valid = [bytes.fromhex(v["hex"]) for v in vectors if v["expect"] == "ok"]
    every = [bytes.fromhex(v["hex"]) for v in vectors]
    programs: dict[str, bytes] = {}
    programs["every_vector_serial"] = bytes([0]) + b"".join(chunk(SERIAL, f) for f in every)
    programs["every_vector_wifi_unsigned"] = bytes([0]) + b"".join(chunk(WIFI, f) for f in every)
    programs["every_vector_wifi_signed"] = bytes([OPT_SIGN_WIFI]) + b"".join(chunk(WIFI, f) for f in valid)
    programs["every_vector_wifi_stale_session"] = (bytes([OPT_SIGN_WIFI | OPT_SESSION_STALE])
                                                   + b"".join(chunk(WIFI, f) for f in valid))
    programs["oversized_datagrams"] = bytes([0]) + chunk(SERIAL, bytes(range(200))) + chunk(WIFI, b"\xb7" * 255)

    def flight(link: int, options: int) -> bytes:
        seq = iter(range(100, 1000))
        hb = lambda: chunk(link, frame(gen.Heartbeat(host_time_ms=0), next(seq)), ticks=96)  # noqa: E731
        out = bytes([options | OPT_PREROLL])
        out += chunk(link, frame(gen.Hello(host_nonce=7), next(seq)))
        out += chunk(link, frame(gen.Arm(), next(seq)))
        out += chunk(link, frame(gen.SetRopeSpeed(rope_speed_mmps=6000), next(seq)))
        out += b"".join(hb() for _ in range(6))
        out += chunk(link, frame(gen.SetRopeSpeed(rope_speed_mmps=3500), next(seq)))
        out += chunk(link, frame(gen.ParamSet(param_id=1, value=1.5), next(seq)))
        out += b"".join(hb() for _ in range(3))
        out += chunk(link, frame(gen.Relax(), next(seq)))
        out += b"".join(hb() for _ in range(4))
        out += chunk(link, frame(gen.Spindown(), next(seq)), ticks=800)
        out += chunk(link, frame(gen.Disarm(), next(seq)))
        return out

    programs["flight_serial"] = flight(SERIAL, 0)
    programs["flight_wifi_signed"] = flight(WIFI, OPT_SIGN_WIFI)
    programs["heartbeat_lost_in_flight"] = (bytes([OPT_PREROLL]) + chunk(SERIAL, frame(gen.Arm(), 1))
                                            + chunk(SERIAL, frame(gen.SetRopeSpeed(rope_speed_mmps=8000), 2), ticks=960))
    programs["encoder_silent_in_flight"] = (bytes([OPT_PREROLL]) + chunk(SERIAL, frame(gen.Arm(), 1))
                                            + chunk(SERIAL, frame(gen.SetRopeSpeed(rope_speed_mmps=8000), 2), ticks=20)
                                            + chunk(SENSORS, sensors(encoder_silent=True), ticks=400))
    programs["battery_low_in_flight"] = (bytes([OPT_PREROLL]) + chunk(SERIAL, frame(gen.Arm(), 1))
                                         + chunk(SERIAL, frame(gen.SetRopeSpeed(rope_speed_mmps=8000), 2), ticks=20)
                                         + chunk(SENSORS, sensors(battery_mv=8000), ticks=1600))
    programs["spindle_home_and_grasp"] = (
        bytes([OPT_PREROLL]) + chunk(SERIAL, frame(gen.Home(), 1), ticks=200)
        + chunk(SENSORS, sensors(spindle_load_raw=600, limit_switch=True), ticks=600)
        + chunk(SENSORS, sensors(), ticks=10) + chunk(SERIAL, frame(gen.Arm(), 2))
        + chunk(SERIAL, frame(gen.SetLoop(guide_position_um=50000), 3), ticks=300)
        + chunk(SERIAL, frame(gen.SetRopeSpeed(rope_speed_mmps=6000), 4), ticks=200)
        + chunk(SERIAL, frame(gen.Grasp(), 5), ticks=400)
        + chunk(SENSORS, sensors(spindle_load_raw=1024 + 300), ticks=400)
        + chunk(SERIAL, frame(gen.Release(), 6), ticks=100))
    programs["spindle_silent"] = (bytes([OPT_PREROLL]) + chunk(SENSORS, sensors(spindle_silent=True))
                                  + chunk(SERIAL, frame(gen.Home(), 1), ticks=400))
    programs["tick_period_jumps"] = (bytes([0]) + chunk(SENSORS, sensors(tick_us=65535), ticks=20)
                                     + chunk(SENSORS, sensors(tick_us=1), ticks=20)
                                     + chunk(SERIAL, frame(gen.Arm(), 1), ticks=5))
    new_key = bytes(range(0xA0, 0xB0))
    programs["provision_then_signed_wifi"] = (
        bytes([OPT_SIGN_WIFI | OPT_PREROLL])
        + chunk(SERIAL, frame(gen.ProvisionSetKey(key=new_key), 1))
        + chunk(SERIAL, frame(gen.ProvisionSetWifiSsid(ssid="lab"), 2))
        + chunk(SERIAL, frame(gen.ProvisionSetWifiPassword(password="correct horse"), 3))
        + chunk(SERIAL, frame(COMMIT, 4))
        + chunk(SERIAL, frame(gen.ProvisionGet(), 5), ticks=3)
        + chunk(WIFI, frame(gen.Hello(host_nonce=1), 6))
        + chunk(WIFI, frame(gen.Arm(), 7))
        + chunk(WIFI, frame(gen.ProvisionGet(), 8), ticks=3))
    programs["replays_on_wifi"] = (bytes([OPT_SIGN_WIFI | OPT_PREROLL])
                                   + chunk(WIFI, frame(gen.Arm(), 1)) + chunk(NOTHING, b"\x01", ticks=2)
                                   + chunk(WIFI, frame(gen.Heartbeat(host_time_ms=5), 2), ticks=1000)
                                   + chunk(NOTHING, b"\x01", ticks=2)
                                   + chunk(WIFI, frame(gen.Disarm(), 3), ticks=2) + chunk(NOTHING, b"\x01", ticks=2))
    # regression seed of firmware/fuzz/crashes/replay_after_key_commit (short: no wait for the duplicate window)
    programs["replay_after_same_key_commit"] = (bytes([OPT_SIGN_WIFI | OPT_PREROLL])
                                                + chunk(WIFI, frame(gen.Arm(), 1), ticks=2)
                                                + chunk(SERIAL, frame(gen.Disarm(), 2), ticks=2)
                                                + chunk(SERIAL, frame(gen.ProvisionSetKey(key=test_key), 3))
                                                + chunk(SERIAL, frame(COMMIT, 4), ticks=2)
                                                + chunk(NOTHING, b"\x01", ticks=2))
    # regression seed: a provisioning commit (a new session) while a queued frame is being signed over idle
    # ticks; that frame was finished for the old session and sent (found by the bounded fuzz run)
    programs["commit_while_signing"] = (bytes([OPT_SIGN_WIFI | OPT_PREROLL])
                                        + chunk(SERIAL, frame(gen.ProvisionSetKey(key=test_key), 1))
                                        + chunk(SERIAL, frame(COMMIT, 2), ticks=2)
                                        + b"".join(chunk(WIFI, frame(gen.Heartbeat(host_time_ms=i), 3 + 2 * i),
                                                         ticks=1 + i % 7)
                                                   + chunk(SERIAL, frame(gen.ProvisionCommit(session_epoch=0x2000 + i),
                                                                         4 + 2 * i)) for i in range(40))
                                        + chunk(NOTHING, b"\x01", ticks=10))
    programs["provision_store_fails"] = (bytes([OPT_SAVE_FAILS])
                                         + chunk(SERIAL, frame(gen.ProvisionSetKey(key=new_key), 1))
                                         + chunk(SERIAL, frame(COMMIT, 2), ticks=3))
    programs["provision_epoch_out_of_range"] = (bytes([OPT_SIGN_WIFI | OPT_PREROLL])
                                                + chunk(SERIAL, frame(gen.ProvisionSetKey(key=new_key), 1))
                                                + chunk(SERIAL, frame(gen.ProvisionCommit(session_epoch=1 << 31), 2),
                                                        ticks=2)
                                                + chunk(WIFI, frame(gen.Arm(), 3), ticks=2))
    programs["provision_no_store"] = (bytes([OPT_NO_STORE])
                                      + chunk(SERIAL, frame(COMMIT, 1), ticks=3)
                                      + chunk(WIFI, frame(gen.Arm(), 2), ticks=3))
    defaults = [p.default for p in gen.PARAMS]
    good = config_record(params=defaults, key=test_key, boot_counter=41, session_epoch=0x2345678)
    programs["stored_record_valid"] = bytes([OPT_FUZZ_RECORD]) + good + chunk(SERIAL, frame(gen.ProvisionGet(), 1))
    bad_params = [float("nan"), -1.0, 1e30] + defaults[3:]
    programs["stored_record_bad_params_sealed"] = (bytes([OPT_FUZZ_RECORD | OPT_SEAL_RECORD])
                                                   + config_record(params=bad_params, key=None, boot_counter=0x7FFFFFFF,
                                                                   session_epoch=0x7FFFFFFF)
                                                   + chunk(SERIAL, frame(gen.Arm(), 1), ticks=3))
    programs["stored_record_sessions_used_up"] = (bytes([OPT_FUZZ_RECORD])
                                                  + config_record(params=defaults, key=test_key,
                                                                  boot_counter=0x7FFFFFFF, session_epoch=0x1234567)
                                                  + chunk(WIFI, frame(gen.Arm(), 1), ticks=3))
    programs["stored_record_epoch_out_of_range"] = (bytes([OPT_FUZZ_RECORD])
                                                    + config_record(params=defaults, key=test_key, boot_counter=3,
                                                                    session_epoch=0x80000000)
                                                    + chunk(NOTHING, ticks=3))
    programs["stored_record_bad_crc"] = (bytes([OPT_FUZZ_RECORD]) + good[:-1] + bytes([good[-1] ^ 1])
                                         + chunk(NOTHING, ticks=3))
    programs["stored_record_garbage_sealed"] = (bytes([OPT_FUZZ_RECORD | OPT_SEAL_RECORD])
                                                + bytes((i * 37) & 0xFF for i in range(CONFIG_SIZE_BYTES)))
    return programs


def write_corpus(directory: Path, files: dict[str, bytes]) -> None:
    if directory.exists():
        shutil.rmtree(directory)
    directory.mkdir(parents=True)
    for name, data in sorted(files.items()):
        digest = hashlib.sha1(data).hexdigest()[:8]
        (directory / f"{name}-{digest}").write_bytes(data)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=HERE / "corpus", help="corpus root (one folder per target)")
    corpus = parser.parse_args(argv).out
    doc = json.loads(VECTORS_PATH.read_text())
    vectors = doc["vectors"]
    test_key = bytes.fromhex(doc["test_key_hex"])
    write_corpus(corpus / "frame_decode", {v["name"]: bytes.fromhex(v["hex"]) for v in vectors})
    cobs_files = {v["name"]: bytes([DELIVERY_CAP_BYTES]) + cobs_encode(bytes.fromhex(v["hex"])) for v in vectors}
    cobs_files["zero_inside"] = bytes([DELIVERY_CAP_BYTES, 3, 1, 0, 2])
    cobs_files["code_past_end"] = bytes([DELIVERY_CAP_BYTES, 9, 1, 2])
    cobs_files["capacity_too_small"] = bytes([4]) + cobs_encode(bytes(range(1, 40)))
    cobs_files["long_block"] = bytes([255]) + cobs_encode(bytes([7]) * 300)
    write_corpus(corpus / "cobs_decode", cobs_files)
    write_corpus(corpus / "core", core_programs(vectors, test_key))
    for target in ("frame_decode", "cobs_decode", "core"):
        print(f"{target}: {len(list((corpus / target).iterdir()))} files")


if __name__ == "__main__":
    main()
