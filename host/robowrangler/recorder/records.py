"""Protocol messages -> channel records (JSON-ready dicts), with the tables generated from the spec.

Every value is converted exactly as robowrangler.units does (wire integer / 1000 etc.), so a record's
rope_speed_mps equals the TelemetrySample's bit for bit. Enum values become their names; a value this
host does not know becomes "UNKNOWN_<value>" (the schemas allow that form).
"""

from __future__ import annotations

from typing import Any

from robowrangler.protocol import generated as gen
from robowrangler.recorder.schemas_generated import COMMAND_FIELDS, EVENT_FIELDS, TELEMETRY_FIELDS


def _enum_name(enum_cls: type, value: int) -> str:
    try:
        return enum_cls(value).name
    except ValueError:
        return f"UNKNOWN_{value}"


def _bit_names(enum_cls: type, value: int) -> list[str]:
    names = []
    bit = 1
    while bit <= value:
        if value & bit:
            names.append(_enum_name(enum_cls, bit))
        bit <<= 1
    return names


def _convert(msg: gen.Message, table: tuple[dict, ...]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for entry in table:
        raw = getattr(msg, entry["wire"])
        kind = entry["kind"]
        if kind == "scaled":
            out[entry["name"]] = raw / entry["divisor"]
        elif kind == "enum":
            out[entry["name"]] = _enum_name(getattr(gen, entry["enum"]), raw)
        elif kind == "bitmask":
            out[entry["name"]] = _bit_names(getattr(gen, entry["enum"]), raw)
        elif kind == "number":
            out[entry["name"]] = float(raw)
        else:
            out[entry["name"]] = raw
    return out


def telemetry_record(msg: gen.Telemetry, *, seq: int) -> dict[str, Any]:
    """A /device/telemetry record from a decoded TELEMETRY and its frame seq."""
    return {**_convert(msg, TELEMETRY_FIELDS), "seq": seq}


def event_record(msg: gen.Event, *, seq: int) -> dict[str, Any]:
    """A /device/event record from a decoded EVENT and its frame seq."""
    return {**_convert(msg, EVENT_FIELDS), "seq": seq}


def command_fields(msg: gen.Message) -> dict[str, Any]:
    """The `fields` object of a /host/command record (SI units)."""
    return _convert(msg, COMMAND_FIELDS[msg.NAME])


def command_record(msg: gen.Message, *, seq: int, transmissions: int, reply: gen.Message | None,
                   reply_latency_s: float | None) -> dict[str, Any]:
    """A /host/command record: the command as sent and the ACK/NACK that answered it (None: NO_REPLY)."""
    record: dict[str, Any] = {"seq": seq, "message": msg.NAME, "fields": command_fields(msg),
                              "transmissions": transmissions, "verdict": "NO_REPLY", "reason": None,
                              "state": None, "detail": None, "reply_latency_s": None}
    if isinstance(reply, gen.Ack):
        record.update(verdict="ACK", state=_enum_name(gen.State, reply.state), reply_latency_s=reply_latency_s)
    elif isinstance(reply, gen.Nack):
        record.update(verdict="NACK", reason=_enum_name(gen.NackReason, reply.reason),
                      state=_enum_name(gen.State, reply.state), detail=reply.detail, reply_latency_s=reply_latency_s)
    return record
