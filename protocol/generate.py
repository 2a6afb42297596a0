#!/usr/bin/env python3
"""Generate the C codec, the Python module and the message document from protocol/spec/robowrangler.toml.

Usage:
    uv run python protocol/generate.py            # write every output
    uv run python protocol/generate.py --check    # exit 1 and list the stale outputs (CI)

The spec is validated first; a bad spec fails with SpecError naming the message/field and the rule
broken. Only the standard library is used, so the generator runs anywhere Python 3.11 does.
"""

from __future__ import annotations

import argparse
import binascii
import json
import re
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC_PATH = ROOT / "protocol" / "spec" / "robowrangler.toml"
VECTORS_PATH = ROOT / "protocol" / "vectors" / "vectors.json"
OUT_C_HEADER = ROOT / "firmware" / "core" / "generated" / "rw_protocol.h"
OUT_C_SOURCE = ROOT / "firmware" / "core" / "generated" / "rw_protocol.c"
OUT_C_VECTORS = ROOT / "firmware" / "core" / "generated" / "rw_protocol_vectors.h"
OUT_PYTHON = ROOT / "host" / "robowrangler" / "protocol" / "generated.py"
OUT_DOC = ROOT / "protocol" / "docs" / "messages.md"

HEADER_LEN = 7
CHECKSUM_LEN = 2
FLAG_SIGNED = 0x01
SIGNATURE_LEN = 20  # session_id u32 + counter u64 + tag u64
KEY_LEN = 16

# type name -> (C type, struct format char, size in bytes, min, max)
TYPES = {
    "uint8": ("uint8_t", "B", 1, 0, 0xFF),
    "int8": ("int8_t", "b", 1, -0x80, 0x7F),
    "uint16": ("uint16_t", "H", 2, 0, 0xFFFF),
    "int16": ("int16_t", "h", 2, -0x8000, 0x7FFF),
    "uint32": ("uint32_t", "I", 4, 0, 0xFFFFFFFF),
    "int32": ("int32_t", "i", 4, -0x80000000, 0x7FFFFFFF),
    "uint64": ("uint64_t", "Q", 8, 0, 0xFFFFFFFFFFFFFFFF),
    "float": ("float", "f", 4, None, None),
}
KINDS = ("command", "heartbeat", "reply", "telemetry", "event", "sil", "hello", "provision", "burst")
NAME_RE = re.compile(r"^[A-Z][A-Z0-9_]*$")
FIELD_RE = re.compile(r"^[a-z][a-z0-9_]*$")


class SpecError(ValueError):
    """The spec breaks a rule; the message names where and which."""


def crc16(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection): the frame checksum."""
    return binascii.crc_hqx(data, crc)


ARRAY_RE = re.compile(r"^(uint8|char)\[(\d+)\]$")


def is_valid_type(type_name: str) -> bool:
    m = ARRAY_RE.match(type_name)
    return type_name in TYPES or (m is not None and 1 <= int(m.group(2)) <= 255)


@dataclass
class Field:
    """A message field: a scalar of TYPES, or an array uint8[N] (bytes) / char[N] (NUL-terminated UTF-8)."""

    name: str
    type: str
    units: str
    enum: str
    description: str

    @property
    def array(self) -> tuple[str, int] | None:
        m = ARRAY_RE.match(self.type)
        return (m.group(1), int(m.group(2))) if m else None

    @property
    def c_type(self) -> str:
        if self.array:
            return "char" if self.array[0] == "char" else "uint8_t"
        return TYPES[self.type][0]

    @property
    def c_decl(self) -> str:
        return f"{self.c_type} {self.name}[{self.array[1]}]" if self.array else f"{self.c_type} {self.name}"

    @property
    def size(self) -> int:
        return self.array[1] if self.array else TYPES[self.type][2]

    @property
    def struct_fmt(self) -> str:
        return f"{self.array[1]}s" if self.array else TYPES[self.type][1]

    @property
    def py_type(self) -> str:
        if self.array:
            return "str" if self.array[0] == "char" else "bytes"
        return "float" if self.type == "float" else "int"

    @property
    def py_range(self) -> str:
        """What Message.pack checks: None (float), ('bytes', N), ('str', N), or (min, max)."""
        if self.array:
            return f"({'str' if self.array[0] == 'char' else 'bytes'!r}, {self.array[1]})"
        if self.type == "float":
            return "None"
        return f"({TYPES[self.type][3]}, {TYPES[self.type][4]})"


@dataclass
class Message:
    id: int
    name: str
    kind: str
    description: str
    fields: list[Field] = field(default_factory=list)
    layout: str = ""  # the record layout inside an array field ([burst_sample]), part of the checksum seed

    @property
    def payload_len(self) -> int:
        return sum(f.size for f in self.fields)

    @property
    def crc_extra(self) -> int:
        """Checksum seed from the message name and its fields' types and names (MAVLink's CRC_EXTRA idea); a
        record layout inside an array field counts too, so a layout change also makes old peers reject."""
        text = self.name + " " + "".join(f"{f.type} {f.name} " for f in self.fields) + self.layout
        return crc16(text.encode("ascii"))

    @property
    def c_name(self) -> str:
        return self.name.lower()

    @property
    def py_name(self) -> str:
        return "".join(part.capitalize() for part in self.name.split("_"))


@dataclass
class EnumValue:
    name: str
    value: int
    description: str


@dataclass
class Enum:
    name: str
    description: str
    bitmask: bool
    values: list[EnumValue]

    @property
    def py_name(self) -> str:
        return "".join(part.capitalize() for part in self.name.split("_"))


@dataclass
class Param:
    id: int
    name: str
    units: str
    min: float
    max: float
    default: float
    locked: bool
    integer: bool
    description: str


@dataclass
class BurstSample:
    """[burst_sample]: the fixed record packed samples_per_frame times into message.array_field."""

    message: str
    array_field: str
    samples_per_frame: int
    fields: list[Field]
    description: str

    @property
    def size(self) -> int:
        return sum(f.size for f in self.fields)

    @property
    def layout_text(self) -> str:
        return f"[{self.samples_per_frame}x " + "".join(f"{f.type} {f.name} " for f in self.fields) + "]"


@dataclass
class Constant:
    """A fixed number both sides of the link (and the firmware's internals) must agree on; not on the wire."""

    name: str
    value: int
    units: str
    description: str


@dataclass
class Spec:
    version: int
    magic: int
    max_payload_len: int
    description: str
    enums: list[Enum]
    messages: list[Message]
    params: list[Param]
    constants: list[Constant] = field(default_factory=list)
    burst_sample: BurstSample | None = None

    @property
    def schema_hash(self) -> int:
        """CRC over every message's CRC_EXTRA: one number that changes with any wire-visible edit."""
        data = b"".join(m.id.to_bytes(1, "little") + m.crc_extra.to_bytes(2, "little") for m in self.messages)
        return crc16(data)


def _require(cond: bool, where: str, rule: str) -> None:
    if not cond:
        raise SpecError(f"{SPEC_PATH.name}: {where}: {rule}")


def load_spec(path: Path = SPEC_PATH) -> Spec:
    raw = tomllib.loads(path.read_text())
    proto = raw.get("protocol", {})
    for key in ("version", "magic", "max_payload_len"):
        _require(key in proto, "[protocol]", f"missing {key}")
    _require(0 < proto["max_payload_len"] <= 255, "[protocol]", "max_payload_len must be 1..255")

    enums = []
    enum_names = set()
    for e in raw.get("enum", []):
        where = f"enum {e.get('name')!r}"
        _require(FIELD_RE.match(e.get("name", "")) is not None, where, "name must be lower_snake_case")
        _require(e["name"] not in enum_names, where, "duplicate enum name")
        enum_names.add(e["name"])
        values = [EnumValue(v["name"], int(v["value"]), v.get("description", "")) for v in e["values"]]
        _require(len({v.value for v in values}) == len(values), where, "duplicate value")
        _require(len({v.name for v in values}) == len(values), where, "duplicate value name")
        for v in values:
            _require(NAME_RE.match(v.name) is not None, where, f"value name {v.name!r} must be UPPER_SNAKE")
            _require(0 <= v.value <= 0xFFFF, where, f"value {v.name} out of 0..65535")
        enums.append(Enum(e["name"], e.get("description", ""), bool(e.get("bitmask", False)), values))

    messages = []
    ids, names = set(), set()
    for m in raw.get("message", []):
        where = f"message {m.get('name')!r}"
        _require(NAME_RE.match(m.get("name", "")) is not None, where, "name must be UPPER_SNAKE")
        _require(isinstance(m.get("id"), int) and 0 <= m["id"] <= 254, where, "id must be 0..254 (255 means unreadable)")
        _require(m["id"] not in ids, where, f"id {m['id']} reused (ids are never reused)")
        _require(m["name"] not in names, where, "duplicate name")
        _require(m.get("kind") in KINDS, where, f"kind must be one of {KINDS}")
        ids.add(m["id"])
        names.add(m["name"])
        fields = []
        for f in m.get("fields", []):
            fwhere = f"{where} field {f.get('name')!r}"
            _require(FIELD_RE.match(f.get("name", "")) is not None, fwhere, "name must be lower_snake_case")
            _require(is_valid_type(f.get("type", "")), fwhere,
                     f"type must be one of {sorted(TYPES)} or uint8[N] / char[N] with N in 1..255")
            _require(f.get("enum", "") in enum_names | {""}, fwhere, f"unknown enum {f.get('enum')!r}")
            fields.append(Field(f["name"], f["type"], f.get("units", ""), f.get("enum", ""), f.get("description", "")))
        _require(len({f.name for f in fields}) == len(fields), where, "duplicate field name")
        msg = Message(m["id"], m["name"], m["kind"], m.get("description", ""), fields)
        _require(msg.payload_len <= proto["max_payload_len"], where,
                 f"payload {msg.payload_len} bytes exceeds max_payload_len {proto['max_payload_len']}")
        messages.append(msg)

    params = []
    pids, pnames = set(), set()
    for p in raw.get("param", []):
        where = f"param {p.get('name')!r}"
        _require(FIELD_RE.match(p.get("name", "")) is not None, where, "name must be lower_snake_case")
        _require(isinstance(p.get("id"), int) and 0 <= p["id"] <= 254, where, "id must be 0..254")
        _require(p["id"] not in pids and p["name"] not in pnames, where, "duplicate id or name")
        pids.add(p["id"])
        pnames.add(p["name"])
        _require(p["min"] <= p["default"] <= p["max"], where, "default must lie in [min, max]")
        params.append(Param(p["id"], p["name"], p.get("units", ""), float(p["min"]), float(p["max"]),
                            float(p["default"]), bool(p.get("locked", False)), bool(p.get("integer", False)),
                            p.get("description", "")))
    _require(sorted(pids) == list(range(len(pids))), "[[param]]", "parameter ids must be 0..N-1 with no gap")
    py_names = [e.py_name for e in enums] + [m.py_name for m in messages]
    clashes = sorted({n for n in py_names if py_names.count(n) > 1})
    _require(not clashes, "[[enum]]/[[message]]", f"generated class names clash: {clashes} (rename the enum)")
    constants = []
    for c in raw.get("constant", []):
        where = f"constant {c.get('name')!r}"
        _require(NAME_RE.match(c.get("name", "")) is not None, where, "name must be UPPER_SNAKE")
        _require(c["name"] not in {k.name for k in constants}, where, "duplicate name")
        _require(isinstance(c.get("value"), int) and 0 <= c["value"] <= 0xFFFFFFFF, where, "value must be an integer 0..2^32-1")
        constants.append(Constant(c["name"], int(c["value"]), c.get("units", ""), c.get("description", "")))
    params.sort(key=lambda p: p.id)
    messages.sort(key=lambda m: m.id)
    burst = None
    if "burst_sample" in raw:
        b = raw["burst_sample"]
        where = "[burst_sample]"
        target = next((m for m in messages if m.name == b.get("message")), None)
        _require(target is not None, where, f"message {b.get('message')!r} not in the spec")
        arr = next((f for f in target.fields if f.name == b.get("array_field")), None)
        _require(arr is not None and arr.array is not None and arr.array[0] == "uint8", where,
                 f"array_field {b.get('array_field')!r} must be a uint8[N] field of {target.name}")
        bfields = []
        for f in b.get("fields", []):
            fwhere = f"{where} field {f.get('name')!r}"
            _require(FIELD_RE.match(f.get("name", "")) is not None, fwhere, "name must be lower_snake_case")
            _require(f.get("type") in TYPES and f.get("type") != "float", fwhere, "type must be an integer type")
            bfields.append(Field(f["name"], f["type"], f.get("units", ""), "", f.get("description", "")))
        _require(bool(bfields), where, "needs fields")
        n = b.get("samples_per_frame")
        burst = BurstSample(target.name, arr.name, n, bfields, b.get("description", ""))
        _require(isinstance(n, int) and n >= 1 and n * burst.size == arr.size, where,
                 f"samples_per_frame x sample size must equal {arr.name}'s {arr.size} bytes")
        target.layout = burst.layout_text
    return Spec(proto["version"], proto["magic"], proto["max_payload_len"], proto.get("description", "").strip(),
                enums, messages, params, constants, burst)


BANNER = "GENERATED by protocol/generate.py from protocol/spec/robowrangler.toml. DO NOT EDIT."


def _c_float(x: float) -> str:
    text = repr(float(x))
    return f"{text}f" if ("." in text or "e" in text) else f"{text}.0f"


def _c_comment(text: str) -> str:
    return " ".join(text.split()).replace("*/", "* /")


# ----------------------------------------------------------------------------------------------------
# C
def gen_c_header(spec: Spec) -> str:
    o: list[str] = []
    w = o.append
    w(f"/* {BANNER} */")
    w("#ifndef RW_PROTOCOL_H")
    w("#define RW_PROTOCOL_H")
    w("")
    w("#include <stddef.h>")
    w("#include <stdint.h>")
    w("")
    w("#ifdef __cplusplus")
    w('extern "C" {')
    w("#endif")
    w("")
    w(f"#define RW_PROTOCOL_VERSION {spec.version}u")
    w(f"#define RW_PROTOCOL_MAGIC 0x{spec.magic:02X}u")
    w(f"#define RW_PROTOCOL_SCHEMA_HASH 0x{spec.schema_hash:04X}u")
    w(f"#define RW_FRAME_HEADER_LEN {HEADER_LEN}u")
    w(f"#define RW_FRAME_CHECKSUM_LEN {CHECKSUM_LEN}u")
    w(f"#define RW_MAX_PAYLOAD_LEN {spec.max_payload_len}u")
    w(f"#define RW_FRAME_FLAG_SIGNED 0x{FLAG_SIGNED:02X}u /* a signature block follows the checksum */")
    w(f"#define RW_SIGNATURE_LEN {SIGNATURE_LEN}u /* session_id u32, counter u64, tag u64 (SipHash-2-4) */")
    w(f"#define RW_KEY_LEN {KEY_LEN}u")
    w(f"#define RW_MAX_FRAME_LEN {HEADER_LEN + spec.max_payload_len + CHECKSUM_LEN + SIGNATURE_LEN}u")
    w("#define RW_MSG_ID_UNREADABLE 255u")
    w("")
    for c in spec.constants:
        units = f" ({c.units})" if c.units else ""
        w(f"/* {_c_comment(c.description)}{units} */")
        w(f"#define RW_{c.name} {c.value}u")
    if spec.constants:
        w("")
    for e in spec.enums:
        w(f"/* {_c_comment(e.description)} */")
        w("typedef enum {")
        for v in e.values:
            w(f"    RW_{e.name.upper()}_{v.name} = {v.value}, /* {_c_comment(v.description)} */")
        w(f"}} rw_{e.name};")
        if not e.bitmask:
            w(f"#define RW_{e.name.upper()}_COUNT {max(v.value for v in e.values) + 1}u")
        w("")
    w("/* Result of rw_frame_decode: RW_DECODE_OK or an rw_nack_reason. */")
    w("#define RW_DECODE_OK 0")
    w("")
    w("typedef enum {")
    for m in spec.messages:
        w(f"    RW_MSG_ID_{m.name} = {m.id},")
    w("} rw_msg_id;")
    w("")
    w("typedef enum {")
    for i, k in enumerate(KINDS):
        w(f"    RW_MSG_KIND_{k.upper()} = {i},")
    w("} rw_msg_kind;")
    w("")
    for m in spec.messages:
        w(f"/* {m.name} (id {m.id}, {m.kind}): {_c_comment(m.description)} */")
        w(f"#define RW_MSG_{m.name}_LEN {m.payload_len}u")
        w(f"#define RW_MSG_{m.name}_CRC_EXTRA 0x{m.crc_extra:04X}u")
        w("typedef struct {")
        if not m.fields:
            w("    uint8_t unused_; /* no fields */")
        for f in m.fields:
            unit = f" [{f.units}]" if f.units else ""
            enum = f" (rw_{f.enum})" if f.enum else ""
            w(f"    {f.c_decl}; /*{unit}{enum} {_c_comment(f.description)} */")
        w(f"}} rw_msg_{m.c_name};")
        w(f"void rw_msg_{m.c_name}_pack(const rw_msg_{m.c_name} *msg, uint8_t *payload);")
        w(f"void rw_msg_{m.c_name}_unpack(rw_msg_{m.c_name} *msg, const uint8_t *payload);")
        w(f"size_t rw_msg_{m.c_name}_encode(const rw_msg_{m.c_name} *msg, uint16_t seq, uint8_t *out, size_t out_cap);")
        w("")
    w("typedef struct {")
    w("    uint8_t msg_id;")
    w("    uint8_t kind;        /* rw_msg_kind */")
    w("    uint8_t payload_len;")
    w("    uint16_t crc_extra;")
    w("    const char *name;")
    w("} rw_msg_info;")
    w("")
    w("/* A decoded frame. msg_id and seq are valid once the header was read (else 255 and 0);")
    w("   payload and bytes point into the caller's buffer. session_id, counter and tag are set for a signed")
    w("   frame (flags & RW_FRAME_FLAG_SIGNED); rw_frame_decode checks the structure and the checksum only,")
    w("   rw_frame_tag_valid checks the signature. */")
    w("typedef struct {")
    w("    uint8_t flags;")
    w("    uint8_t msg_id;")
    w("    uint16_t seq;")
    w("    uint8_t payload_len;")
    w("    const uint8_t *payload;")
    w("    const uint8_t *bytes;   /* the frame */")
    w("    uint16_t checksum;")
    w("    uint32_t session_id;")
    w("    uint64_t counter;")
    w("    uint64_t tag;")
    w("    size_t signed_len;      /* bytes the tag covers: from magic to the end of counter */")
    w("} rw_frame;")
    w("")
    w("/* CRC-16/CCITT-FALSE step: poly 0x1021, init 0xFFFF, no reflection. */")
    w("uint16_t rw_crc16_ccitt(uint16_t crc, const uint8_t *data, size_t len);")
    w("/* The message's info, or NULL for an id not in this schema. */")
    w("const rw_msg_info *rw_msg_info_find(uint8_t msg_id);")
    w("/* Check and split a received frame; returns RW_DECODE_OK or an rw_nack_reason. Never reads past len. */")
    w("int rw_frame_decode(const uint8_t *buf, size_t len, rw_frame *out);")
    w("/* Frame a payload; returns the frame length, or 0 if msg_id is unknown, payload_len is not the")
    w("   message's size or out_cap is too small. */")
    w("size_t rw_frame_encode(uint8_t msg_id, uint16_t seq, const uint8_t *payload, uint8_t payload_len,")
    w("                       uint8_t *out, size_t out_cap);")
    w("/* Sign an unsigned frame of len bytes in place: set the flag, recompute the checksum, append session_id,")
    w("   counter and the SipHash-2-4 tag. Returns the new length, 0 if it does not fit in cap or is not an")
    w("   unsigned frame. */")
    w("size_t rw_frame_sign(uint8_t *frame, size_t len, size_t cap, uint32_t session_id, uint64_t counter,")
    w("                     const uint8_t key[RW_KEY_LEN]);")
    w("/* The same in steps, so that a MAC can be spread over time and the counter taken only when the frame is")
    w("   sent: rw_frame_sign_begin sets seq and the flag, recomputes the checksum, appends session_id (returns len,")
    w("   0 as rw_frame_sign would); the first RW_FRAME_SIGN_FIXED_LEN(len) bytes of the tagged part are then")
    w("   final. rw_frame_sign_counter appends the counter and returns the length the tag covers")
    w("   (RW_FRAME_SIGN_TAGGED_LEN(len)); rw_frame_sign_tag appends the tag and returns the signed length. */")
    w("#define RW_FRAME_SIGN_FIXED_LEN(len) ((len) + 4u)")
    w("#define RW_FRAME_SIGN_TAGGED_LEN(len) ((len) + 12u)")
    w("size_t rw_frame_sign_begin(uint8_t *frame, size_t len, size_t cap, uint16_t seq, uint32_t session_id);")
    w("/* rw_frame_sign_begin without the checksum, for a caller that computes it in pieces: sets seq and the flag,")
    w("   appends session_id, gives the message's crc_extra (returns len, 0 as rw_frame_sign_begin would). The")
    w("   checksum is rw_crc16_ccitt(0xFFFF, frame + 1, len - RW_FRAME_CHECKSUM_LEN - 1) (whole or in pieces), closed")
    w("   and stored by rw_frame_checksum_put. */")
    w("size_t rw_frame_sign_open(uint8_t *frame, size_t len, size_t cap, uint16_t seq, uint32_t session_id,")
    w("                          uint16_t *crc_extra);")
    w("void rw_frame_checksum_put(uint8_t *frame, size_t len, uint16_t body_crc, uint16_t crc_extra);")
    w("/* Renumber an unsigned frame of len bytes in place: the new seq and its checksum (frames queued for the link")
    w("   are numbered when they leave, so seq grows in the order frames are sent). Returns len, 0 if malformed. */")
    w("size_t rw_frame_renumber(uint8_t *frame, size_t len, uint16_t seq);")
    w("size_t rw_frame_sign_counter(uint8_t *frame, size_t len, uint64_t counter);")
    w("size_t rw_frame_sign_tag(uint8_t *frame, size_t len, uint64_t tag);")
    w("/* True if a decoded signed frame's tag is right for key (constant-time comparison). */")
    w("int rw_frame_tag_valid(const rw_frame *frame, const uint8_t key[RW_KEY_LEN]);")
    w("")
    if spec.burst_sample is not None:
        b = spec.burst_sample
        w(f"/* {b.message}.{b.array_field}: RW_BURST_SAMPLES_PER_FRAME records of RW_BURST_SAMPLE_LEN bytes, little-endian. */")
        w(f"#define RW_BURST_SAMPLES_PER_FRAME {b.samples_per_frame}u")
        w(f"#define RW_BURST_SAMPLE_LEN {b.size}u")
        w("typedef struct {")
        for f in b.fields:
            unit = f" [{f.units}]" if f.units else ""
            w(f"    {f.c_decl}; /*{unit} {_c_comment(f.description)} */")
        w("} rw_burst_sample;")
        w("/* Write sample number index (0..RW_BURST_SAMPLES_PER_FRAME-1) into the array / read it back. */")
        w(f"void rw_burst_sample_put(uint8_t {b.array_field}[RW_BURST_SAMPLES_PER_FRAME * RW_BURST_SAMPLE_LEN], unsigned index, const rw_burst_sample *sample);")
        w(f"void rw_burst_sample_get(const uint8_t {b.array_field}[RW_BURST_SAMPLES_PER_FRAME * RW_BURST_SAMPLE_LEN], unsigned index, rw_burst_sample *sample);")
        w("")
    w("/* Parameters (SI units, float32 on the wire). */")
    w(f"#define RW_PARAM_COUNT {len(spec.params)}u")
    w("#define RW_PARAM_FLAG_LOCKED 0x01u  /* settable only while DISARMED */")
    w("#define RW_PARAM_FLAG_INTEGER 0x02u /* value must be a whole number */")
    w("typedef enum {")
    for p in spec.params:
        w(f"    RW_PARAM_{p.name.upper()} = {p.id}, /* [{p.units}] {_c_comment(p.description)} */")
    w("} rw_param_id;")
    w("/* Parameter defaults, for code that needs one as a constant (firmware/core/rw_defaults.h). */")
    for p in spec.params:
        w(f"#define RW_PARAM_DEFAULT_{p.name.upper()} {_c_float(p.default)}")
    w("typedef struct {")
    w("    const char *name;")
    w("    float min_value;")
    w("    float max_value;")
    w("    float default_value;")
    w("    uint8_t flags;")
    w("} rw_param_info;")
    w("extern const rw_param_info rw_param_table[RW_PARAM_COUNT];")
    w("")
    w("#ifdef __cplusplus")
    w("}")
    w("#endif")
    w("")
    w("#endif /* RW_PROTOCOL_H */")
    return "\n".join(o) + "\n"


def _c_put(f: Field, off: int) -> list[str]:
    if f.array:
        return [f"    memcpy(payload + {off}, msg->{f.name}, {f.size}u);"]
    if f.type == "float":
        return [f"    {{ uint32_t bits_; memcpy(&bits_, &msg->{f.name}, 4); put_u32(payload + {off}, bits_); }}"]
    if f.size == 1:
        return [f"    payload[{off}] = (uint8_t)msg->{f.name};"]
    return [f"    put_u{f.size * 8}(payload + {off}, (uint{f.size * 8}_t)msg->{f.name});"]


def _c_get(f: Field, off: int) -> list[str]:
    if f.array:
        lines = [f"    memcpy(msg->{f.name}, payload + {off}, {f.size}u);"]
        if f.array[0] == "char":
            lines.append(f"    msg->{f.name}[{f.size - 1}] = '\\0'; /* always terminated */")
        return lines
    if f.type == "float":
        return [f"    {{ uint32_t bits_ = get_u32(payload + {off}); memcpy(&msg->{f.name}, &bits_, 4); }}"]
    if f.size == 1:
        return [f"    msg->{f.name} = ({f.c_type})payload[{off}];"]
    return [f"    msg->{f.name} = ({f.c_type})get_u{f.size * 8}(payload + {off});"]


def gen_c_source(spec: Spec) -> str:
    o: list[str] = []
    w = o.append
    w(f"/* {BANNER} */")
    w('#include "rw_protocol.h"')
    w("")
    w("#include <string.h>")
    w("")
    w('#include "rw_siphash.h"')
    w("")
    w("static void put_u16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }")
    w("static void put_u32(uint8_t *p, uint32_t v) { put_u16(p, (uint16_t)v); put_u16(p + 2, (uint16_t)(v >> 16)); }")
    w("static void put_u64(uint8_t *p, uint64_t v) { put_u32(p, (uint32_t)v); put_u32(p + 4, (uint32_t)(v >> 32)); }")
    w("static uint16_t get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }")
    w("static uint32_t get_u32(const uint8_t *p) { return (uint32_t)get_u16(p) | ((uint32_t)get_u16(p + 2) << 16); }")
    w("static uint64_t get_u64(const uint8_t *p) { return (uint64_t)get_u32(p) | ((uint64_t)get_u32(p + 4) << 32); }")
    w("")
    # table-driven (one lookup a byte): the bitwise loop cost 40 % of a busy tick on the Cortex-M0+
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
        table.append(crc)
    w("/* CRC-16/CCITT-FALSE table: entry i is the CRC register after shifting byte i through (poly 0x1021), in the")
    w("   upper half of a 32-bit word: the loop keeps the register there, so the next index is its top byte (no")
    w("   masking, one shift) and a word load needs no halfword extension (~13 Cortex-M0+ cycles a byte, not ~16). */")
    w("static const uint32_t crc16_table[256] = {")
    for row in range(0, 256, 8):
        w("    " + " ".join(f"0x{v:04X}0000u," for v in table[row:row + 8]))
    w("};")
    w("")
    w("uint16_t rw_crc16_ccitt(uint16_t crc, const uint8_t *data, size_t len)")
    w("{")
    w("    uint32_t reg = (uint32_t)crc << 16;")
    w("    const uint8_t *end = data + len;")
    w("    while (data != end) {")
    w("        reg = (reg << 8) ^ crc16_table[(reg >> 24) ^ *data++];")
    w("    }")
    w("    return (uint16_t)(reg >> 16);")
    w("}")
    w("")
    w("static const rw_msg_info msg_infos[] = {")
    for m in spec.messages:
        w(f'    {{ {m.id}u, RW_MSG_KIND_{m.kind.upper()}, {m.payload_len}u, 0x{m.crc_extra:04X}u, "{m.name}" }},')
    w("};")
    w("")
    w("const rw_msg_info *rw_msg_info_find(uint8_t msg_id)")
    w("{")
    w("    for (size_t i = 0; i < sizeof msg_infos / sizeof msg_infos[0]; ++i) {")
    w("        if (msg_infos[i].msg_id == msg_id) {")
    w("            return &msg_infos[i];")
    w("        }")
    w("    }")
    w("    return NULL;")
    w("}")
    w("")
    w("static uint16_t frame_checksum(const uint8_t *frame, size_t body_len, uint16_t crc_extra)")
    w("{")
    w("    uint8_t extra[2];")
    w("    put_u16(extra, crc_extra);")
    w("    uint16_t crc = rw_crc16_ccitt(0xFFFFu, frame + 1, body_len - 1u);")
    w("    return rw_crc16_ccitt(crc, extra, 2u);")
    w("}")
    w("")
    w("int rw_frame_decode(const uint8_t *buf, size_t len, rw_frame *out)")
    w("{")
    w("    memset(out, 0, sizeof *out);")
    w("    out->msg_id = (uint8_t)RW_MSG_ID_UNREADABLE;")
    w("    if (buf == NULL || len < RW_FRAME_HEADER_LEN) {")
    w("        return RW_NACK_REASON_TRUNCATED;")
    w("    }")
    w("    if (buf[0] != RW_PROTOCOL_MAGIC) {")
    w("        return RW_NACK_REASON_BAD_MAGIC;")
    w("    }")
    w("    out->flags = buf[2];")
    w("    out->msg_id = buf[3];")
    w("    out->seq = get_u16(buf + 4);")
    w("    out->payload_len = buf[6];")
    w("    if (buf[1] != RW_PROTOCOL_VERSION) {")
    w("        return RW_NACK_REASON_BAD_VERSION;")
    w("    }")
    w("    if ((out->flags & (uint8_t)~RW_FRAME_FLAG_SIGNED) != 0u) {")
    w("        return RW_NACK_REASON_UNSUPPORTED_FLAGS;")
    w("    }")
    w("    size_t signature_len = (out->flags & RW_FRAME_FLAG_SIGNED) != 0u ? RW_SIGNATURE_LEN : 0u;")
    w("    if (out->payload_len > RW_MAX_PAYLOAD_LEN) {")
    w("        return RW_NACK_REASON_OVERSIZE;")
    w("    }")
    w("    size_t frame_len = RW_FRAME_HEADER_LEN + (size_t)out->payload_len + RW_FRAME_CHECKSUM_LEN + signature_len;")
    w("    if (len < frame_len) {")
    w("        return RW_NACK_REASON_TRUNCATED;")
    w("    }")
    w("    if (len > frame_len) {")
    w("        return RW_NACK_REASON_BAD_LENGTH;")
    w("    }")
    w("    const rw_msg_info *info = rw_msg_info_find(out->msg_id);")
    w("    if (info == NULL) {")
    w("        return RW_NACK_REASON_UNKNOWN_MESSAGE;")
    w("    }")
    w("    size_t body_len = RW_FRAME_HEADER_LEN + (size_t)out->payload_len;")
    w("    if (frame_checksum(buf, body_len, info->crc_extra) != get_u16(buf + body_len)) {")
    w("        return RW_NACK_REASON_BAD_CHECKSUM;")
    w("    }")
    w("    if (out->payload_len != info->payload_len) {")
    w("        return RW_NACK_REASON_BAD_LENGTH;")
    w("    }")
    w("    out->payload = buf + RW_FRAME_HEADER_LEN;")
    w("    out->bytes = buf;")
    w("    out->checksum = get_u16(buf + body_len);")
    w("    if (signature_len != 0u) {")
    w("        const uint8_t *sig = buf + body_len + RW_FRAME_CHECKSUM_LEN;")
    w("        out->session_id = get_u32(sig);")
    w("        out->counter = get_u64(sig + 4);")
    w("        out->tag = get_u64(sig + 12);")
    w("        out->signed_len = body_len + RW_FRAME_CHECKSUM_LEN + 12u;")
    w("    }")
    w("    return RW_DECODE_OK;")
    w("}")
    w("")
    w("/* The message info of an unsigned, well-formed frame of len bytes (cap: room for a signature, 0 if none")
    w("   needed), or NULL. */")
    w("static const rw_msg_info *unsigned_frame_info(const uint8_t *frame, size_t len, size_t cap)")
    w("{")
    w("    if (frame == NULL || len < RW_FRAME_HEADER_LEN + RW_FRAME_CHECKSUM_LEN || frame[2] != 0u ||")
    w("        len != RW_FRAME_HEADER_LEN + (size_t)frame[6] + RW_FRAME_CHECKSUM_LEN || (cap != 0u && cap < len + RW_SIGNATURE_LEN)) {")
    w("        return NULL;")
    w("    }")
    w("    return rw_msg_info_find(frame[3]);")
    w("}")
    w("")
    w("size_t rw_frame_renumber(uint8_t *frame, size_t len, uint16_t seq)")
    w("{")
    w("    const rw_msg_info *info = unsigned_frame_info(frame, len, 0u);")
    w("    if (info == NULL) {")
    w("        return 0u;")
    w("    }")
    w("    size_t body_len = len - RW_FRAME_CHECKSUM_LEN;")
    w("    put_u16(frame + 4, seq);")
    w("    put_u16(frame + body_len, frame_checksum(frame, body_len, info->crc_extra));")
    w("    return len;")
    w("}")
    w("")
    w("size_t rw_frame_sign_open(uint8_t *frame, size_t len, size_t cap, uint16_t seq, uint32_t session_id,")
    w("                          uint16_t *crc_extra)")
    w("{")
    w("    const rw_msg_info *info = unsigned_frame_info(frame, len, cap);")
    w("    if (info == NULL) {")
    w("        return 0u;")
    w("    }")
    w("    put_u16(frame + 4, seq);")
    w("    frame[2] = RW_FRAME_FLAG_SIGNED;")
    w("    put_u32(frame + len, session_id);")
    w("    *crc_extra = info->crc_extra;")
    w("    return len;")
    w("}")
    w("")
    w("void rw_frame_checksum_put(uint8_t *frame, size_t len, uint16_t body_crc, uint16_t crc_extra)")
    w("{")
    w("    uint8_t extra[2];")
    w("    put_u16(extra, crc_extra);")
    w("    put_u16(frame + len - RW_FRAME_CHECKSUM_LEN, rw_crc16_ccitt(body_crc, extra, 2u));")
    w("}")
    w("")
    w("size_t rw_frame_sign_begin(uint8_t *frame, size_t len, size_t cap, uint16_t seq, uint32_t session_id)")
    w("{")
    w("    uint16_t crc_extra = 0u;")
    w("    if (rw_frame_sign_open(frame, len, cap, seq, session_id, &crc_extra) == 0u) {")
    w("        return 0u;")
    w("    }")
    w("    size_t body_len = len - RW_FRAME_CHECKSUM_LEN;")
    w("    put_u16(frame + body_len, frame_checksum(frame, body_len, crc_extra));")
    w("    return len;")
    w("}")
    w("")
    w("size_t rw_frame_sign_counter(uint8_t *frame, size_t len, uint64_t counter)")
    w("{")
    w("    put_u64(frame + len + 4u, counter);")
    w("    return RW_FRAME_SIGN_TAGGED_LEN(len);")
    w("}")
    w("")
    w("size_t rw_frame_sign_tag(uint8_t *frame, size_t len, uint64_t tag)")
    w("{")
    w("    put_u64(frame + len + 12u, tag);")
    w("    return len + RW_SIGNATURE_LEN;")
    w("}")
    w("")
    w("size_t rw_frame_sign(uint8_t *frame, size_t len, size_t cap, uint32_t session_id, uint64_t counter,")
    w("                     const uint8_t key[RW_KEY_LEN])")
    w("{")
    w("    if (frame == NULL || len < RW_FRAME_HEADER_LEN || rw_frame_sign_begin(frame, len, cap, get_u16(frame + 4), session_id) == 0u) {")
    w("        return 0u;")
    w("    }")
    w("    size_t tagged_len = rw_frame_sign_counter(frame, len, counter);")
    w("    return rw_frame_sign_tag(frame, len, rw_siphash24(key, frame, tagged_len));")
    w("}")
    w("")
    w("int rw_frame_tag_valid(const rw_frame *frame, const uint8_t key[RW_KEY_LEN])")
    w("{")
    w("    if ((frame->flags & RW_FRAME_FLAG_SIGNED) == 0u || frame->bytes == NULL) {")
    w("        return 0;")
    w("    }")
    w("    /* constant time: every bit of the difference is folded in, no early exit */")
    w("    uint64_t diff = rw_siphash24(key, frame->bytes, frame->signed_len) ^ frame->tag;")
    w("    uint32_t folded = (uint32_t)diff | (uint32_t)(diff >> 32);")
    w("    return (int)(1u & ((folded - 1u) >> 31) & ~(folded >> 31));")
    w("}")
    w("")
    w("size_t rw_frame_encode(uint8_t msg_id, uint16_t seq, const uint8_t *payload, uint8_t payload_len,")
    w("                       uint8_t *out, size_t out_cap)")
    w("{")
    w("    const rw_msg_info *info = rw_msg_info_find(msg_id);")
    w("    size_t frame_len = RW_FRAME_HEADER_LEN + (size_t)payload_len + RW_FRAME_CHECKSUM_LEN;")
    w("    if (info == NULL || payload_len != info->payload_len || out == NULL || out_cap < frame_len) {")
    w("        return 0u;")
    w("    }")
    w("    out[0] = RW_PROTOCOL_MAGIC;")
    w("    out[1] = RW_PROTOCOL_VERSION;")
    w("    out[2] = 0u;")
    w("    out[3] = msg_id;")
    w("    put_u16(out + 4, seq);")
    w("    out[6] = payload_len;")
    w("    if (payload_len > 0u) {")
    w("        memcpy(out + RW_FRAME_HEADER_LEN, payload, payload_len);")
    w("    }")
    w("    size_t body_len = RW_FRAME_HEADER_LEN + (size_t)payload_len;")
    w("    put_u16(out + body_len, frame_checksum(out, body_len, info->crc_extra));")
    w("    return frame_len;")
    w("}")
    w("")
    used_sizes: set[int] = set()
    for m in spec.messages:
        w(f"void rw_msg_{m.c_name}_pack(const rw_msg_{m.c_name} *msg, uint8_t *payload)")
        w("{")
        if not m.fields:
            w("    (void)msg;")
            w("    (void)payload;")
        off = 0
        for f in m.fields:
            o.extend(_c_put(f, off))
            used_sizes.add(f.size)
            off += f.size
        w("}")
        w("")
        w(f"void rw_msg_{m.c_name}_unpack(rw_msg_{m.c_name} *msg, const uint8_t *payload)")
        w("{")
        if not m.fields:
            w("    msg->unused_ = 0u;")
            w("    (void)payload;")
        off = 0
        for f in m.fields:
            o.extend(_c_get(f, off))
            off += f.size
        w("}")
        w("")
        w(f"size_t rw_msg_{m.c_name}_encode(const rw_msg_{m.c_name} *msg, uint16_t seq, uint8_t *out, size_t out_cap)")
        w("{")
        w(f"    uint8_t payload[RW_MSG_{m.name}_LEN + 1u] = {{ 0u }};")
        w(f"    rw_msg_{m.c_name}_pack(msg, payload);")
        w(f"    return rw_frame_encode(RW_MSG_ID_{m.name}, seq, payload, RW_MSG_{m.name}_LEN, out, out_cap);")
        w("}")
        w("")
    if 8 not in used_sizes:
        # keep the helpers used so that -Wunused-function stays quiet when no 64-bit field exists
        w("/* no 64-bit fields in this schema */")
        w("void rw_protocol_unused_u64_(uint8_t *p);")
        w("void rw_protocol_unused_u64_(uint8_t *p) { put_u64(p, get_u64(p)); }")
        w("")
    if spec.burst_sample is not None:
        b = spec.burst_sample
        w(f"void rw_burst_sample_put(uint8_t {b.array_field}[RW_BURST_SAMPLES_PER_FRAME * RW_BURST_SAMPLE_LEN], unsigned index, const rw_burst_sample *sample)")
        w("{")
        w(f"    uint8_t *payload = {b.array_field} + index * RW_BURST_SAMPLE_LEN;")
        w("    const rw_burst_sample *msg = sample;")
        off = 0
        for f in b.fields:
            o.extend(_c_put(f, off))
            off += f.size
        w("}")
        w("")
        w(f"void rw_burst_sample_get(const uint8_t {b.array_field}[RW_BURST_SAMPLES_PER_FRAME * RW_BURST_SAMPLE_LEN], unsigned index, rw_burst_sample *sample)")
        w("{")
        w(f"    const uint8_t *payload = {b.array_field} + index * RW_BURST_SAMPLE_LEN;")
        w("    rw_burst_sample *msg = sample;")
        off = 0
        for f in b.fields:
            o.extend(_c_get(f, off))
            off += f.size
        w("}")
        w("")
    w("const rw_param_info rw_param_table[RW_PARAM_COUNT] = {")
    for p in spec.params:
        flags = " | ".join(n for n, on in (("RW_PARAM_FLAG_LOCKED", p.locked), ("RW_PARAM_FLAG_INTEGER", p.integer)) if on) or "0u"
        w(f'    {{ "{p.name}", {_c_float(p.min)}, {_c_float(p.max)}, {_c_float(p.default)}, {flags} }},')
    w("};")
    return "\n".join(o) + "\n"


def gen_c_vectors(spec: Spec, vectors: list[dict], key_hex: str) -> str:
    """The golden vectors as C data, with per-vector field checks, for the C test and the Unity test."""
    by_name = {m.name: m for m in spec.messages}
    o: list[str] = []
    w = o.append
    w(f"/* {BANNER} Source: protocol/vectors/vectors.json. */")
    w("#ifndef RW_PROTOCOL_VECTORS_H")
    w("#define RW_PROTOCOL_VECTORS_H")
    w("")
    w('#include <string.h>')
    w("")
    w('#include "rw_protocol.h"')
    w("")
    w("typedef struct {")
    w("    const char *name;")
    w("    const uint8_t *bytes;")
    w("    size_t len;")
    w("    int expect_result;   /* RW_DECODE_OK or an rw_nack_reason */")
    w("    uint8_t expect_msg_id;")
    w("    uint16_t expect_seq;")
    w("    int expect_tag_valid;  /* -1 unsigned, else 1/0 under rw_protocol_vector_key */")
    w("    uint32_t expect_session_id;")
    w("    uint64_t expect_counter;")
    w("} rw_protocol_vector;")
    w("")
    for i, v in enumerate(vectors):
        data = bytes.fromhex(v["hex"])
        body = ", ".join(f"0x{b:02X}" for b in data) or "0x00"
        w(f"static const uint8_t rw_vector_{i}_bytes[] = {{ {body} }};")
    w("")
    w("static const rw_protocol_vector rw_protocol_vectors[] = {")
    for i, v in enumerate(vectors):
        data = bytes.fromhex(v["hex"])
        result = "RW_DECODE_OK" if v["expect"] == "ok" else f"RW_NACK_REASON_{v['expect']}"
        msg_id = by_name[v["message"]].id if "message" in v else v.get("msg_id", 255)
        seq = v.get("seq", 0)
        tag = -1 if "tag_valid" not in v else int(v["tag_valid"])
        w(f'    {{ "{v["name"]}", rw_vector_{i}_bytes, {len(data)}u, {result}, {msg_id}u, {seq}u, {tag}, '
          f'{v.get("session_id", 0)}u, {v.get("counter", 0)}ull }},')
    w("};")
    w(f"#define RW_PROTOCOL_VECTOR_COUNT {len(vectors)}u")
    key = ", ".join(f"0x{b:02X}" for b in bytes.fromhex(key_hex))
    w(f"static const uint8_t rw_protocol_vector_key[RW_KEY_LEN] = {{ {key} }}; /* test key, never a real one */")
    w("")
    w("/* Unpacks the payload of valid vector `index` and compares every field with the golden value;")
    w("   returns the number of mismatching fields (0 = all equal), -1 for a vector that is not valid. */")
    w("static inline int rw_protocol_vector_check_fields(size_t index, const uint8_t *payload)")
    w("{")
    w("    int bad = 0;")
    w("    (void)payload;")
    w("    switch (index) {")
    for i, v in enumerate(vectors):
        if v["expect"] != "ok":
            continue
        m = by_name[v["message"]]
        w(f"    case {i}u: {{")
        w(f"        rw_msg_{m.c_name} msg;")
        w(f"        rw_msg_{m.c_name}_unpack(&msg, payload);")
        for f in m.fields:
            value = v["fields"][f.name]
            if f.array:
                data = value.encode("utf-8") if f.array[0] == "char" else bytes.fromhex(value)
                data = data.ljust(f.size, b"\0")
                lit = "".join(f"\\x{b:02x}" for b in data)
                w(f'        bad += (memcmp(msg.{f.name}, "{lit}", {f.size}u) != 0);')
                continue
            if f.type == "float":
                lit = _c_float(value)
            elif f.type.startswith("u"):
                lit = f"{int(value)}u"
            else:
                lit = f"({int(value)})" if int(value) != -0x80000000 else "(-2147483647 - 1)"
            w(f"        bad += (msg.{f.name} != {lit});")
        w("        return bad;")
        w("    }")
    w("    default:")
    w("        return -1;")
    w("    }")
    w("}")
    w("")
    w("#endif /* RW_PROTOCOL_VECTORS_H */")
    return "\n".join(o) + "\n"


# ----------------------------------------------------------------------------------------------------
# Python
def gen_python(spec: Spec) -> str:
    o: list[str] = []
    w = o.append
    w(f'"""{BANNER}')
    w("")
    w("Wire protocol v%d: constants, enums, message classes, the frame codec and the parameter table." % spec.version)
    w("Integer wire units as in the spec; robowrangler.units converts to SI.")
    w('"""')
    w("")
    w("from __future__ import annotations")
    w("")
    w("import binascii")
    w("import hmac")
    w("import struct")
    w("from dataclasses import dataclass")
    w("from enum import IntEnum, IntFlag")
    w("from typing import ClassVar")
    w("")
    w("import siphash24 as _siphash")
    w("")
    w(f"PROTOCOL_VERSION = {spec.version}")
    w(f"MAGIC = 0x{spec.magic:02X}")
    w(f"SCHEMA_HASH = 0x{spec.schema_hash:04X}")
    w(f"HEADER_LEN = {HEADER_LEN}")
    w(f"CHECKSUM_LEN = {CHECKSUM_LEN}")
    w(f"MAX_PAYLOAD_LEN = {spec.max_payload_len}")
    w(f"FLAG_SIGNED = 0x{FLAG_SIGNED:02X}")
    w(f"SIGNATURE_LEN = {SIGNATURE_LEN}")
    w(f"KEY_LEN = {KEY_LEN}")
    w(f"MAX_FRAME_LEN = {HEADER_LEN + spec.max_payload_len + CHECKSUM_LEN + SIGNATURE_LEN}")
    w("MSG_ID_UNREADABLE = 255")
    for c in spec.constants:
        units = f" ({c.units})" if c.units else ""
        w(f"{c.name} = {c.value}  # {' '.join(c.description.split())}{units}")
    w("")
    w("")
    for e in spec.enums:
        base = "IntFlag" if e.bitmask else "IntEnum"
        w(f"class {e.py_name}({base}):")
        w(f'    """{e.description}"""')
        w("")
        for v in e.values:
            w(f"    {v.name} = {v.value}")
            w(f'    """{v.description}"""')
        w("")
        w("")
    w("class MsgKind(IntEnum):")
    for i, k in enumerate(KINDS):
        w(f"    {k.upper()} = {i}")
    w("")
    w("")
    w("class MsgId(IntEnum):")
    for m in spec.messages:
        w(f"    {m.name} = {m.id}")
    w("")
    w("")
    w("@dataclass(frozen=True)")
    w("class FieldSpec:")
    w("    name: str")
    w("    type: str")
    w("    units: str")
    w("    enum: str")
    w("    description: str")
    w("")
    w("")
    w("class FieldRangeError(ValueError):")
    w('    """A field value does not fit its wire type; names the message, field, range and value."""')
    w("")
    w("")
    w("class Message:")
    w('    """Base of every message class: fixed little-endian layout, fields in spec order."""')
    w("")
    w("    MSG_ID: ClassVar[int]")
    w("    NAME: ClassVar[str]")
    w("    KIND: ClassVar[MsgKind]")
    w("    CRC_EXTRA: ClassVar[int]")
    w("    PAYLOAD_LEN: ClassVar[int]")
    w("    FIELDS: ClassVar[tuple[FieldSpec, ...]]")
    w("    _STRUCT: ClassVar[struct.Struct]")
    w("    _RANGES: ClassVar[tuple[tuple | None, ...]]")
    w("")
    w("    def pack(self) -> bytes:")
    w('        """The payload bytes; FieldRangeError if a value does not fit its type."""')
    w("        values = []")
    w("        for spec, rng, value in zip(self.FIELDS, self._RANGES, (getattr(self, f.name) for f in self.FIELDS)):")
    w("            if rng is None:")
    w("                if isinstance(value, bool) or not isinstance(value, (int, float)):")
    w('                    raise FieldRangeError(f"{self.NAME}.{spec.name}: expected a number, got {value!r}")')
    w('            elif rng[0] == "bytes":')
    w("                if not isinstance(value, (bytes, bytearray)) or len(value) != rng[1]:")
    w('                    raise FieldRangeError(f"{self.NAME}.{spec.name}: expected {rng[1]} bytes, got {value!r}")')
    w('            elif rng[0] == "str":')
    w('                encoded = value.encode("utf-8") if isinstance(value, str) else None')
    w("                if encoded is None or len(encoded) >= rng[1] or 0 in encoded:")
    w("                    raise FieldRangeError(f\"{self.NAME}.{spec.name}: expected text of at most {rng[1] - 1} UTF-8 \"")
    w('                                          f"bytes without NUL, got {value!r}")')
    w("                value = encoded")
    w("            elif isinstance(value, bool) or not isinstance(value, int) or not rng[0] <= value <= rng[1]:")
    w("                raise FieldRangeError(")
    w('                    f"{self.NAME}.{spec.name}: expected an integer in [{rng[0]}, {rng[1]}] ({spec.type}), got {value!r}"')
    w("                )")
    w("            values.append(value)")
    w("        return self._STRUCT.pack(*values)")
    w("")
    w("    @classmethod")
    w("    def unpack(cls, payload: bytes) -> Message:")
    w("        if len(payload) != cls.PAYLOAD_LEN:")
    w("            raise FrameError(NackReason.BAD_LENGTH, cls.MSG_ID, None,")
    w('                             f"{cls.NAME}: expected {cls.PAYLOAD_LEN} payload bytes, got {len(payload)}")')
    w("        values = [v.split(b\"\\0\", 1)[0].decode(\"utf-8\", \"replace\") if rng is not None and rng[0] == \"str\" else v")
    w("                  for v, rng in zip(cls._STRUCT.unpack(payload), cls._RANGES)]")
    w("        return cls(*values)")
    w("")
    w("")
    for m in spec.messages:
        fmt = "<" + "".join(f.struct_fmt for f in m.fields)
        w("@dataclass(frozen=True)")
        w(f"class {m.py_name}(Message):")
        w(f'    """{m.name} (id {m.id}, {m.kind}): {m.description}')
        if m.fields:
            w("")
            w("    Fields:")
            for f in m.fields:
                unit = f" [{f.units}]" if f.units else ""
                enum = f" ({f.enum})" if f.enum else ""
                w(f"        {f.name}: {f.type}{unit}{enum} {f.description}")
        w('    """')
        w("")
        w(f"    MSG_ID: ClassVar[int] = {m.id}")
        w(f'    NAME: ClassVar[str] = "{m.name}"')
        w(f"    KIND: ClassVar[MsgKind] = MsgKind.{m.kind.upper()}")
        w(f"    CRC_EXTRA: ClassVar[int] = 0x{m.crc_extra:04X}")
        w(f"    PAYLOAD_LEN: ClassVar[int] = {m.payload_len}")
        w(f'    _STRUCT: ClassVar[struct.Struct] = struct.Struct("{fmt}")')
        ranges = ", ".join(f.py_range for f in m.fields)
        w(f"    _RANGES: ClassVar[tuple[tuple | None, ...]] = ({ranges}{',' if len(m.fields) == 1 else ''})")
        specs = "".join(
            f"\n        FieldSpec({f.name!r}, {f.type!r}, {f.units!r}, {f.enum!r}, {f.description!r}),"
            for f in m.fields
        )
        w(f"    FIELDS: ClassVar[tuple[FieldSpec, ...]] = ({specs}\n    )" if m.fields else "    FIELDS: ClassVar[tuple[FieldSpec, ...]] = ()")
        if m.fields:
            w("")
            for f in m.fields:
                w(f"    {f.name}: {f.py_type}")
        w("")
        w("")
    w("MESSAGES: dict[int, type[Message]] = {")
    for m in spec.messages:
        w(f"    {m.id}: {m.py_name},")
    w("}")
    w("")
    w("")
    w("class FrameError(ValueError):")
    w('    """A frame was refused. reason maps to the NACK reason the device would send."""')
    w("")
    w("    def __init__(self, reason: NackReason, msg_id: int | None, seq: int | None, detail: str) -> None:")
    w('        super().__init__(f"{reason.name}: {detail}")')
    w("        self.reason = reason")
    w("        self.msg_id = msg_id")
    w("        self.seq = seq")
    w("")
    w("")
    w("@dataclass(frozen=True)")
    w("class Frame:")
    w('    """A decoded frame. For a signed frame (flags & FLAG_SIGNED) session_id, counter and tag are set and')
    w('    signed_bytes is what the tag covers; decode_frame checks structure and checksum, tag_valid the tag."""')
    w("")
    w("    msg_id: int")
    w("    seq: int")
    w("    flags: int")
    w("    payload: bytes")
    w("    checksum: int = 0")
    w("    session_id: int | None = None")
    w("    counter: int | None = None")
    w("    tag: bytes | None = None")
    w('    signed_bytes: bytes = b""')
    w("")
    w("    @property")
    w("    def signed(self) -> bool:")
    w("        return bool(self.flags & FLAG_SIGNED)")
    w("")
    w("")
    w("def checksum(body_without_magic: bytes, crc_extra: int) -> int:")
    w('    """CRC-16/CCITT-FALSE over the frame body (version..payload) then CRC_EXTRA (little-endian)."""')
    w('    return binascii.crc_hqx(crc_extra.to_bytes(2, "little"), binascii.crc_hqx(body_without_magic, 0xFFFF))')
    w("")
    w("")
    w("def siphash24(key: bytes, data: bytes) -> bytes:")
    w('    """SipHash-2-4 of data under a 16-byte key: the 8-byte tag, little-endian (the siphash24 package)."""')
    w("    return _siphash.siphash24(data, key=key).digest()")
    w("")
    w("")
    w("def encode_frame(message: Message, seq: int, *, key: bytes | None = None, session_id: int = 0,")
    w("                 counter: int = 0) -> bytes:")
    w('    """Frame a message with sequence number seq (0..65535); signed with key (16 bytes) when given."""')
    w("    if not isinstance(seq, int) or not 0 <= seq <= 0xFFFF:")
    w('        raise FieldRangeError(f"seq: expected an integer in [0, 65535], got {seq!r}")')
    w("    payload = message.pack()")
    w("    flags = 0 if key is None else FLAG_SIGNED")
    w('    body = struct.pack("<BBBBHB", MAGIC, PROTOCOL_VERSION, flags, message.MSG_ID, seq, len(payload)) + payload')
    w('    frame = body + checksum(body[1:], message.CRC_EXTRA).to_bytes(2, "little")')
    w("    if key is None:")
    w("        return frame")
    w("    if not isinstance(key, (bytes, bytearray)) or len(key) != KEY_LEN:")
    w('        raise FieldRangeError(f"key: expected {KEY_LEN} bytes, got {type(key).__name__} of length {len(key) if hasattr(key, \'__len__\') else \'?\'}")')
    w("    if not isinstance(session_id, int) or not 0 <= session_id <= 0xFFFFFFFF:")
    w('        raise FieldRangeError(f"session_id: expected an integer in [0, 2**32 - 1], got {session_id!r}")')
    w("    if not isinstance(counter, int) or not 0 <= counter <= 0xFFFFFFFFFFFFFFFF:")
    w('        raise FieldRangeError(f"counter: expected an integer in [0, 2**64 - 1], got {counter!r}")')
    w('    frame += struct.pack("<IQ", session_id, counter)')
    w("    return frame + siphash24(bytes(key), frame)")
    w("")
    w("")
    w("def tag_valid(frame: Frame, key: bytes) -> bool:")
    w('    """True if a signed frame\'s tag is right for key (constant-time comparison)."""')
    w("    return frame.signed and frame.tag is not None and hmac.compare_digest(siphash24(bytes(key), frame.signed_bytes), frame.tag)")
    w("")
    w("")
    w("def decode_frame(data: bytes) -> Frame:")
    w('    """Check and split a frame. Raises FrameError with the same reason, in the same order, as the C decoder."""')
    w("    data = bytes(data)")
    w("    if len(data) < HEADER_LEN:")
    w('        raise FrameError(NackReason.TRUNCATED, None, None, f"{len(data)} bytes, the header alone needs {HEADER_LEN}")')
    w("    if data[0] != MAGIC:")
    w('        raise FrameError(NackReason.BAD_MAGIC, None, None, f"first byte 0x{data[0]:02X}, expected 0x{MAGIC:02X}")')
    w('    _, version, flags, msg_id, seq, payload_len = struct.unpack_from("<BBBBHB", data)')
    w("    if version != PROTOCOL_VERSION:")
    w('        raise FrameError(NackReason.BAD_VERSION, msg_id, seq, f"version {version}, this side speaks {PROTOCOL_VERSION}")')
    w("    if flags & ~FLAG_SIGNED:")
    w('        raise FrameError(NackReason.UNSUPPORTED_FLAGS, msg_id, seq, f"flags 0x{flags:02X} not supported by version {PROTOCOL_VERSION}")')
    w("    if payload_len > MAX_PAYLOAD_LEN:")
    w('        raise FrameError(NackReason.OVERSIZE, msg_id, seq, f"payload_len {payload_len} > {MAX_PAYLOAD_LEN}")')
    w("    signature_len = SIGNATURE_LEN if flags & FLAG_SIGNED else 0")
    w("    frame_len = HEADER_LEN + payload_len + CHECKSUM_LEN + signature_len")
    w("    if len(data) < frame_len:")
    w('        raise FrameError(NackReason.TRUNCATED, msg_id, seq, f"{len(data)} bytes, the frame declares {frame_len}")')
    w("    if len(data) > frame_len:")
    w('        raise FrameError(NackReason.BAD_LENGTH, msg_id, seq, f"{len(data) - frame_len} bytes after the frame")')
    w("    cls = MESSAGES.get(msg_id)")
    w("    if cls is None:")
    w('        raise FrameError(NackReason.UNKNOWN_MESSAGE, msg_id, seq, f"message id {msg_id} not in schema 0x{SCHEMA_HASH:04X}")')
    w("    body_len = HEADER_LEN + payload_len")
    w('    crc = int.from_bytes(data[body_len:body_len + CHECKSUM_LEN], "little")')
    w("    if checksum(data[1:body_len], cls.CRC_EXTRA) != crc:")
    w('        raise FrameError(NackReason.BAD_CHECKSUM, msg_id, seq, f"checksum mismatch for {cls.NAME}")')
    w("    if payload_len != cls.PAYLOAD_LEN:")
    w('        raise FrameError(NackReason.BAD_LENGTH, msg_id, seq, f"{cls.NAME} has {cls.PAYLOAD_LEN} payload bytes, frame has {payload_len}")')
    w("    payload = data[HEADER_LEN:body_len]")
    w("    if not signature_len:")
    w("        return Frame(msg_id, seq, flags, payload, crc)")
    w("    sig = body_len + CHECKSUM_LEN")
    w('    session_id, counter = struct.unpack_from("<IQ", data, sig)')
    w("    return Frame(msg_id, seq, flags, payload, crc, session_id, counter, data[sig + 12:frame_len], data[:sig + 12])")
    w("")
    w("")
    w("def decode_message(data: bytes) -> tuple[Frame, Message]:")
    w('    """decode_frame, then the payload into its message class."""')
    w("    frame = decode_frame(data)")
    w("    return frame, MESSAGES[frame.msg_id].unpack(frame.payload)")
    w("")
    w("")
    w("@dataclass(frozen=True)")
    w("class ParamSpec:")
    w("    id: int")
    w("    name: str")
    w("    units: str")
    w("    min: float")
    w("    max: float")
    w("    default: float")
    w("    locked: bool")
    w("    integer: bool")
    w("    description: str")
    w("")
    w("")
    w("PARAMS: tuple[ParamSpec, ...] = (")
    for p in spec.params:
        w(f"    ParamSpec({p.id}, {p.name!r}, {p.units!r}, {p.min!r}, {p.max!r}, {p.default!r}, {p.locked}, {p.integer}, {p.description!r}),")
    w(")")
    w("PARAMS_BY_NAME: dict[str, ParamSpec] = {p.name: p for p in PARAMS}")
    if spec.burst_sample is not None:
        b = spec.burst_sample
        w("")
        w(f"# {b.message}.{b.array_field}: BURST_SAMPLES_PER_FRAME records of BURST_SAMPLE_LEN bytes (little-endian)")
        w(f"BURST_SAMPLES_PER_FRAME = {b.samples_per_frame}")
        w(f"BURST_SAMPLE_LEN = {b.size}")
        w(f"BURST_SAMPLE_FIELDS: tuple[FieldSpec, ...] = (")
        for f in b.fields:
            w(f"    FieldSpec({f.name!r}, {f.type!r}, {f.units!r}, '', {f.description!r}),")
        w(")")
        w(f"_BURST_SAMPLE_FMT = struct.Struct({'<' + ''.join(f.struct_fmt for f in b.fields)!r})")
        w("")
        w("")
        w(f"def unpack_burst_samples(data: bytes, count: int = BURST_SAMPLES_PER_FRAME) -> list[dict[str, int]]:")
        w(f'    """The first count samples of a {b.message}.{b.array_field} array, each a dict of BURST_SAMPLE_FIELDS."""')
        w("    if not 0 <= count <= BURST_SAMPLES_PER_FRAME:")
        w('        raise ValueError(f"count: expected 0..{BURST_SAMPLES_PER_FRAME}, got {count}")')
        w("    if len(data) != BURST_SAMPLES_PER_FRAME * BURST_SAMPLE_LEN:")
        w('        raise ValueError(f"data: expected {BURST_SAMPLES_PER_FRAME * BURST_SAMPLE_LEN} bytes, got {len(data)}")')
        w("    names = [f.name for f in BURST_SAMPLE_FIELDS]")
        w("    return [dict(zip(names, _BURST_SAMPLE_FMT.unpack_from(data, i * BURST_SAMPLE_LEN))) for i in range(count)]")
        w("")
        w("")
        w("def pack_burst_samples(samples: list[dict[str, int]]) -> bytes:")
        w(f'    """Up to BURST_SAMPLES_PER_FRAME samples as a {b.message}.{b.array_field} array (the rest zero)."""')
        w("    if len(samples) > BURST_SAMPLES_PER_FRAME:")
        w('        raise ValueError(f"samples: expected at most {BURST_SAMPLES_PER_FRAME}, got {len(samples)}")')
        w("    out = bytearray(BURST_SAMPLES_PER_FRAME * BURST_SAMPLE_LEN)")
        w("    for i, sample in enumerate(samples):")
        w("        _BURST_SAMPLE_FMT.pack_into(out, i * BURST_SAMPLE_LEN, *(sample[f.name] for f in BURST_SAMPLE_FIELDS))")
        w("    return bytes(out)")
    return "\n".join(o) + "\n"


# ----------------------------------------------------------------------------------------------------
# Markdown
def gen_doc(spec: Spec) -> str:
    o: list[str] = []
    w = o.append
    w(f"<!-- {BANNER} -->")
    w(f"# RoboWrangler wire protocol, version {spec.version}")
    w("")
    w(f"Schema hash 0x{spec.schema_hash:04X}, magic 0x{spec.magic:02X}, max payload {spec.max_payload_len} bytes.")
    w("")
    w("## Frame")
    w("")
    w(spec.description)
    w("")
    w("| offset | size | field |")
    w("|---|---|---|")
    w("| 0 | 1 | magic |")
    w("| 1 | 1 | version |")
    w("| 2 | 1 | flags (bit 0: signed; other bits must be 0) |")
    w("| 3 | 1 | msg_id |")
    w("| 4 | 2 | seq (u16, per sender) |")
    w("| 6 | 1 | payload_len |")
    w("| 7 | payload_len | payload (fields in the order below, packed, little-endian) |")
    w("| 7+payload_len | 2 | checksum |")
    w("| 9+payload_len | 4 | session_id (signed frames only: flags bit 0) |")
    w("| 13+payload_len | 8 | counter (signed frames only) |")
    w("| 21+payload_len | 8 | tag: SipHash-2-4 over bytes 0..20+payload_len (signed frames only) |")
    w("")
    w("Decoding order (C and Python alike): length < 7 TRUNCATED; magic BAD_MAGIC; version BAD_VERSION; flags "
      "UNSUPPORTED_FLAGS; payload_len > max OVERSIZE; too few bytes TRUNCATED; trailing bytes BAD_LENGTH; unknown id "
      "UNKNOWN_MESSAGE; checksum BAD_CHECKSUM; payload_len != message size BAD_LENGTH.")
    w("")
    w("Commands are answered by ACK or NACK carrying the command's msg_id and seq. A retransmitted command (same seq "
      "and checksum within the device's duplicate window) is answered again but never executed twice.")
    w("")
    if spec.constants:
        w("## Constants")
        w("")
        w("| name | value | units | description |")
        w("|---|---|---|---|")
        for c in spec.constants:
            w(f"| {c.name} | {c.value} | {c.units} | {' '.join(c.description.split())} |")
        w("")
    w("## Messages")
    w("")
    for m in spec.messages:
        w(f"### {m.name} (id {m.id}, {m.kind}, {m.payload_len} bytes, CRC_EXTRA 0x{m.crc_extra:04X})")
        w("")
        w(m.description)
        w("")
        if m.fields:
            w("| field | type | units | description |")
            w("|---|---|---|---|")
            for f in m.fields:
                desc = f.description + (f" Enum `{f.enum}`." if f.enum else "")
                w(f"| {f.name} | {f.type} | {f.units or '-'} | {desc} |")
            w("")
        b = spec.burst_sample
        if b is not None and b.message == m.name:
            w(f"`{b.array_field}` holds {b.samples_per_frame} records of {b.size} bytes, little-endian "
              "(the layout counts in CRC_EXTRA). " + " ".join(b.description.split()))
            w("")
            w("| offset | field | type | units | description |")
            w("|---|---|---|---|---|")
            off = 0
            for f in b.fields:
                w(f"| {off} | {f.name} | {f.type} | {f.units or '-'} | {f.description} |")
                off += f.size
            w("")
    w("## Enums")
    w("")
    for e in spec.enums:
        w(f"### {e.name}{' (bitmask)' if e.bitmask else ''}")
        w("")
        w(e.description)
        w("")
        w("| name | value | meaning |")
        w("|---|---|---|")
        for v in e.values:
            w(f"| {v.name} | {hex(v.value) if e.bitmask else v.value} | {v.description} |")
        w("")
    w("## Parameters")
    w("")
    w("float32 on the wire (PARAM_GET / PARAM_SET / PARAM_VALUE), SI units. Locked: settable only while DISARMED.")
    w("")
    w("| id | name | units | min | max | default | locked | description |")
    w("|---|---|---|---|---|---|---|---|")
    for p in spec.params:
        w(f"| {p.id} | {p.name} | {p.units} | {p.min:g} | {p.max:g} | {p.default:g} | {'yes' if p.locked else 'no'}"
          f"{' (integer)' if p.integer else ''} | {p.description} |")
    return "\n".join(o) + "\n"


def codec_outputs(spec: Spec) -> dict[Path, str]:
    """The codecs and the document: what depends on the spec alone."""
    return {
        OUT_C_HEADER: gen_c_header(spec),
        OUT_C_SOURCE: gen_c_source(spec),
        OUT_PYTHON: gen_python(spec),
        OUT_DOC: gen_doc(spec),
    }


def vector_outputs(spec: Spec) -> dict[Path, str]:
    """The C form of the golden vectors; SpecError if they were made for another schema."""
    if not VECTORS_PATH.exists():
        return {}
    vectors = json.loads(VECTORS_PATH.read_text())
    if vectors.get("schema_hash") != spec.schema_hash:
        raise SpecError(f"{VECTORS_PATH.relative_to(ROOT)} was made for schema 0x{vectors.get('schema_hash', 0):04X}, "
                        f"the spec is now 0x{spec.schema_hash:04X}: if the change is on purpose, run "
                        "`uv run python protocol/make_vectors.py` and generate again")
    return {OUT_C_VECTORS: gen_c_vectors(spec, vectors["vectors"], vectors["test_key_hex"])}


def _write(outputs: dict[Path, str]) -> None:
    for path, text in outputs.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="fail if any committed output differs")
    args = parser.parse_args(argv)
    try:
        spec = load_spec()
    except SpecError as exc:
        print(f"generate: {exc}", file=sys.stderr)
        return 2
    generated = codec_outputs(spec)
    try:
        generated.update(vector_outputs(spec))
    except SpecError as exc:
        if not args.check:
            _write(generated)  # make_vectors.py needs the new Python module
        print(f"generate: {exc}", file=sys.stderr)
        return 1
    if not args.check:
        _write(generated)
        return 0
    stale = [p.relative_to(ROOT) for p, text in generated.items() if not p.exists() or p.read_text() != text]
    if stale:
        print("generate: stale generated files (run `uv run python protocol/generate.py`):", file=sys.stderr)
        for p in stale:
            print(f"  {p}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
