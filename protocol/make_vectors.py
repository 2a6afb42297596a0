#!/usr/bin/env python3
"""Write protocol/vectors/vectors.json: the golden frames both codecs must decode identically.

Valid frames are laid out here byte by byte from the spec (independently of the generated codecs) and
cross-checked against the generated Python encoder; invalid frames are mutations of valid ones, each
with the NACK reason a receiver must give. Rerun only when the spec changes on purpose:
    uv run python protocol/make_vectors.py && uv run python protocol/generate.py
"""

from __future__ import annotations

import binascii
import json
import struct
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from generate import HEADER_LEN, VECTORS_PATH, load_spec  # noqa: E402

# one set of field values per message: edge values where they catch byte-order and sign mistakes
FIELD_VALUES = {
    "HEARTBEAT": {"host_time_ms": 0x01020304},
    "ACK": {"cmd_msg_id": 12, "cmd_seq": 0xBEEF, "state": 2},
    "NACK": {"cmd_msg_id": 12, "cmd_seq": 513, "reason": 9, "state": 3, "detail": -2147483648},
    "TELEMETRY": {"time_ms": 4294967295, "state": 3, "fault_bits": 0x0005, "rope_speed_target_mmps": 6000,
                  "rope_speed_setpoint_mmps": 5990, "rope_speed_mmps": 65535, "motor_rpm": 3820,
                  "esc_pulse_us": 1342, "battery_mv": 12150, "heartbeat_age_ms": 100, "rx_ok": 1,
                  "rx_bad": 2, "rx_duplicates": 3, "nacks": 4, "events": 5, "tick_overruns": 0,
                  "guide_position_um": -12345, "guide_target_um": 180000, "spindle_load_permille": -350,
                  "spindle_flags": 0x0B, "spindle_rejected": 65535, "rx_auth_failed": 6, "rx_replayed": 7, "tx_dropped": 8,
                  "esc_pulse_third_us": 4027, "spindle_moving_speed_raw": 1024 + 77, "encoder_counts": 0xFFFFFFFE,
                  "encoder_edge_us": 0x80000001},
    "EVENT": {"time_ms": 1500, "event_seq": 7, "event": 1, "state_from": 2, "state_to": 3, "arg": 1},
    "PARAM_VALUE": {"param_id": 0, "value": 2.5999999046325684, "param_count": 33},
    "ARM": {}, "DISARM": {}, "SPINDOWN": {}, "ESTOP": {},
    "SET_ROPE_SPEED": {"rope_speed_mmps": 4000},
    "PARAM_GET": {"param_id": 16},
    "PARAM_SET": {"param_id": 1, "value": -1.5},
    "SIL_SENSORS": {"time_us": 123456789, "encoder_counts": 4294967290, "encoder_last_edge_us": 123456000,
                    "battery_mv": 12600, "host_frames_sent": 3, "spindle_position_raw": 1023,
                    "spindle_speed_raw": 1024 + 500, "spindle_load_raw": 1024 + 350, "spindle_answered": 1,
                    "limit_switch": 0},
    "SIL_ACTUATORS": {"time_us": 123456789, "esc_pulse_us": 1000, "spindle_moving_speed_raw": 1024 + 1023,
                      "esc_pulse_third_us": 3001},
    "BURST_START": {"samples": 1000},
    "BURST_DATA": {"burst_id": 0xFFFF, "start_time_ms": 70000, "start_time_us": 0xFFFFFF00, "tick_us": 1000,
                   "sample_count": 1000, "first_sample": 996,
                   "samples": "0100fffe1f0fbc2f" "0200200020 0fbc2f".replace(" ", "") + "ffff2100ff17ff2f" "0000ffff000000ff"
                   + "00" * 16},
    "SET_LOOP": {"guide_position_um": 90000},
    "HELLO": {"host_nonce": 0xDEADBEEF},
    "SESSION_INFO": {"host_nonce": 0xDEADBEEF, "session_id": 42, "key_set": 1, "schema_hash": 0x1234},
    "PROVISION_SET_KEY": {"key": "000102030405060708090a0b0c0d0e0f"},
    "PROVISION_SET_WIFI_SSID": {"ssid": "lab-wifi é"},
    "PROVISION_SET_WIFI_PASSWORD": {"password": "x" * 63},
    "PROVISION_COMMIT": {"session_epoch": 0x2BADCAFE}, "PROVISION_GET": {},
    "PROVISION_STATUS": {"key_set": 1, "password_set": 1, "wifi_ssid": "lab", "boot_counter": 17, "commits": 3,
                         "config_version": 2, "dirty": 0},
    "RELAX": {}, "RETRACT": {}, "GRASP": {}, "RELEASE": {}, "HOME": {},
}


def frame(version: int, flags: int, msg_id: int, seq: int, payload: bytes, crc_extra: int, magic: int) -> bytes:
    body = struct.pack("<BBBBHB", magic, version, flags, msg_id, seq, len(payload)) + payload
    crc = binascii.crc_hqx(struct.pack("<H", crc_extra), binascii.crc_hqx(body[1:], 0xFFFF))
    return body + struct.pack("<H", crc)


def main() -> None:
    spec = load_spec()
    from_name = {m.name: m for m in spec.messages}
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "host"))
    from robowrangler.protocol import generated as gen

    vectors = []
    for seq, m in enumerate(spec.messages, start=1):
        values = FIELD_VALUES[m.name]
        fmt = "<" + "".join(f.struct_fmt for f in m.fields)

        def wire(f, value):
            if f.array:  # uint8[N] as hex in the JSON, char[N] as text
                return value.encode("utf-8") if f.array[0] == "char" else bytes.fromhex(value)
            return value

        payload = struct.pack(fmt, *(wire(f, values[f.name]) for f in m.fields))
        data = frame(spec.version, 0, m.id, seq * 257, payload, m.crc_extra, spec.magic)
        msg = gen.MESSAGES[m.id](*(bytes.fromhex(values[f.name]) if f.array and f.array[0] == "uint8"
                                   else values[f.name] for f in m.fields))
        assert gen.encode_frame(msg, seq * 257) == data, f"generated encoder disagrees on {m.name}"
        vectors.append({"name": f"valid_{m.name.lower()}", "hex": data.hex(), "expect": "ok",
                        "message": m.name, "seq": seq * 257, "fields": values})

    srs = from_name["SET_ROPE_SPEED"]
    good = bytes.fromhex(next(v["hex"] for v in vectors if v["message"] == "SET_ROPE_SPEED"))
    good_seq = next(v["seq"] for v in vectors if v["message"] == "SET_ROPE_SPEED")
    payload = good[HEADER_LEN:-2]

    def bad(name: str, data: bytes, reason: str, *, readable: bool = True, msg_id: int | None = None) -> None:
        v = {"name": name, "hex": data.hex(), "expect": reason}
        if readable:
            v["msg_id"] = srs.id if msg_id is None else msg_id
            v["seq"] = good_seq
        vectors.append(v)

    bad("empty", b"", "TRUNCATED", readable=False)
    bad("truncated_header", good[:5], "TRUNCATED", readable=False)
    bad("truncated_payload", good[:-3], "TRUNCATED")
    bad("bad_magic", bytes([0x55]) + good[1:], "BAD_MAGIC", readable=False)
    bad("wrong_version", frame(spec.version - 1, 0, srs.id, good_seq, payload, srs.crc_extra, spec.magic),
        "BAD_VERSION")
    bad("unsupported_flags", frame(spec.version, 0x02, srs.id, good_seq, payload, srs.crc_extra, spec.magic),
        "UNSUPPORTED_FLAGS")
    bad("oversize", frame(spec.version, 0, srs.id, good_seq, bytes(spec.max_payload_len + 1), srs.crc_extra,
                          spec.magic), "OVERSIZE")
    bad("trailing_bytes", good + b"\x00", "BAD_LENGTH")
    bad("bad_checksum", good[:-1] + bytes([good[-1] ^ 0x01]), "BAD_CHECKSUM")
    bad("flipped_payload_bit", good[:HEADER_LEN] + bytes([payload[0] ^ 0x80]) + good[HEADER_LEN + 1:],
        "BAD_CHECKSUM")
    bad("unknown_message", frame(spec.version, 0, 200, good_seq, payload, 0, spec.magic), "UNKNOWN_MESSAGE",
        msg_id=200)
    bad("payload_too_short_for_message", frame(spec.version, 0, srs.id, good_seq, payload[:2], srs.crc_extra,
                                               spec.magic), "BAD_LENGTH")
    bad("other_schema_crc_extra", frame(spec.version, 0, srs.id, good_seq, payload, srs.crc_extra ^ 0x1111,
                                        spec.magic), "BAD_CHECKSUM")

    # signed frames: a fixed test key (never a real one), tag checked by both codecs
    key = bytes(range(16))
    signed = gen.encode_frame(gen.SetRopeSpeed(4000), good_seq, key=key, session_id=7, counter=1_000_001)
    vectors.append({"name": "signed_set_rope_speed", "hex": signed.hex(), "expect": "ok", "message": "SET_ROPE_SPEED",
                    "seq": good_seq, "fields": FIELD_VALUES["SET_ROPE_SPEED"], "session_id": 7, "counter": 1_000_001,
                    "tag_valid": True})
    hb = gen.encode_frame(gen.Heartbeat(5), 9, key=key, session_id=0xFFFFFFFF, counter=2**64 - 1)
    vectors.append({"name": "signed_heartbeat_extremes", "hex": hb.hex(), "expect": "ok", "message": "HEARTBEAT",
                    "seq": 9, "fields": {"host_time_ms": 5}, "session_id": 0xFFFFFFFF, "counter": 2**64 - 1,
                    "tag_valid": True})
    # tampered payload with a recomputed checksum: structurally fine, the tag gives it away
    body = bytearray(signed[:HEADER_LEN + 4])
    body[HEADER_LEN] ^= 0x01
    crc = binascii.crc_hqx(struct.pack("<H", srs.crc_extra), binascii.crc_hqx(bytes(body[1:]), 0xFFFF))
    tampered = bytes(body) + struct.pack("<H", crc) + signed[HEADER_LEN + 6:]
    vectors.append({"name": "signed_tampered_payload", "hex": tampered.hex(), "expect": "ok",
                    "message": "SET_ROPE_SPEED", "seq": good_seq, "fields": {"rope_speed_mmps": 4001},
                    "session_id": 7, "counter": 1_000_001, "tag_valid": False})
    replay_other_session = bytearray(signed)
    replay_other_session[HEADER_LEN + 6] ^= 0x01  # session 7 -> 6 without re-signing
    vectors.append({"name": "signed_session_edited", "hex": bytes(replay_other_session).hex(), "expect": "ok",
                    "message": "SET_ROPE_SPEED", "seq": good_seq, "fields": FIELD_VALUES["SET_ROPE_SPEED"],
                    "session_id": 6, "counter": 1_000_001, "tag_valid": False})
    other_key = gen.encode_frame(gen.SetRopeSpeed(4000), good_seq, key=bytes(16), session_id=7, counter=1_000_001)
    vectors.append({"name": "signed_with_another_key", "hex": other_key.hex(), "expect": "ok",
                    "message": "SET_ROPE_SPEED", "seq": good_seq, "fields": FIELD_VALUES["SET_ROPE_SPEED"],
                    "session_id": 7, "counter": 1_000_001, "tag_valid": False})
    bad("signed_truncated_tag", signed[:-1], "TRUNCATED")
    bad("signed_flag_on_unsigned_frame", bytes([signed[0], signed[1], gen.FLAG_SIGNED]) + good[3:], "TRUNCATED")

    VECTORS_PATH.parent.mkdir(parents=True, exist_ok=True)
    VECTORS_PATH.write_text(json.dumps({"schema_hash": spec.schema_hash, "test_key_hex": key.hex(),
                                        "vectors": vectors}, indent=1) + "\n")
    print(f"wrote {len(vectors)} vectors to {VECTORS_PATH}")


if __name__ == "__main__":
    main()
