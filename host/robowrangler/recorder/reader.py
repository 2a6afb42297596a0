"""Load a recording (any writer: this package, a simulator, a rig) into per-channel records and arrays.

    rec = read_recording("run.mcap")
    rec.telemetry["rope_speed_mps"]      # numpy array, one value per TELEMETRY, ordered by log_time
    rec.events                           # list of dicts (/device/event records)
    rec.truncated, rec.truncation_reason

Rules (protocol/recording/schema.md):
- The file must be MCAP (magic), carry the Metadata record "/meta" valid for meta.schema.json, and each
  known channel must use message encoding "json" with the schema named for it (encoding "jsonschema").
  Every message of a known channel is checked against this package's schema for that channel.
  Channels with other topics are counted and listed, not decoded.
- A truncated file (a killed recorder) is read up to its last complete record - for a chunked file the
  last complete chunk - and reported: truncated=True with the reason. A chunk whose bytes are damaged
  (CRC mismatch, unreadable) is skipped and reported in `damaged` (where, why, how many messages its
  index says it held), the rest is read, as the mcap library's own tools do. Damage outside the chunks
  (an impossible record, a data-section CRC mismatch with every chunk intact) raises CorruptRecording; a foreign file raises NotARecording; a message
  that violates its schema raises RecordingSchemaError. All are RecordingError naming the file.
"""

from __future__ import annotations

import json
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from mcap.exceptions import McapError, UnsupportedCompressionError
from mcap.records import Channel, Chunk, Footer, Message, Metadata, Schema
from mcap.stream_reader import CRCValidationError, StreamReader, breakup_chunk

from robowrangler.recorder import schemas_generated as sg
from robowrangler.recorder.errors import CorruptRecording, NotARecording, RecordingError, RecordingSchemaError
from robowrangler.recorder.json_schema_check import first_error

MCAP_MAGIC = b"\x89MCAP0\r\n"
RECORD_HEADER_LEN = 9  # opcode u8 + length u64
PLAUSIBLE_RECORD_BYTES = 64 * 1024 * 1024  # a cut-off record longer than this is damage, not truncation
_SCHEMAS = {topic: json.loads(text) for topic, (_, _, text) in sg.CHANNELS.items()}
_META_SCHEMA = json.loads(sg.META_SCHEMA)


class Record(NamedTuple):
    """One message: log_time_ns and publish_time_ns (int ns, see meta time_base), data (the JSON object)."""

    log_time_ns: int
    publish_time_ns: int
    data: dict[str, Any]


@dataclass
class Recording:
    """A loaded recording.

    path: the file; meta: the /meta record (str -> str); records: topic -> list of Record, for the known
    channels present, each sorted by log_time (stable); topic_counts: message count of every channel in
    the file, foreign ones included; foreign_topics: topic -> schema name of channels this reader does
    not decode; truncated / truncation_reason: whether the file ended early and why; chunks: complete
    chunks read; metadata: the other Metadata records by name (e.g. "/device/params"); damaged: one line per
    damaged chunk that was skipped (empty for an intact file).
    """

    path: Path
    meta: dict[str, str]
    records: dict[str, list[Record]]
    topic_counts: dict[str, int]
    foreign_topics: dict[str, str] = field(default_factory=dict)
    truncated: bool = False
    truncation_reason: str | None = None
    chunks: int = 0
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    damaged: list[str] = field(default_factory=list)

    def table(self, topic: str) -> dict[str, np.ndarray]:
        """Columns of a channel: log_time_ns, publish_time_ns (int64) and one array per field.

        Integer fields -> int64; numbers (null -> NaN) -> float64; booleans -> bool; anything else
        (names, lists, null mixed with text) -> object arrays. Every array has one entry per message.
        A channel absent from the file gives the same columns (its schema's fields), empty.
        """
        rows = self.records.get(topic, [])
        cols: dict[str, np.ndarray] = {
            "log_time_ns": np.array([r.log_time_ns for r in rows], dtype=np.int64),
            "publish_time_ns": np.array([r.publish_time_ns for r in rows], dtype=np.int64),
        }
        names: dict[str, None] = {}
        for name in _SCHEMAS.get(topic, {}).get("properties", {}):
            names[name] = None
        for r in rows:
            for name in r.data:
                names.setdefault(name, None)
        props = _SCHEMAS.get(topic, {}).get("properties", {})
        for name in names:
            types = props.get(name, {}).get("type", ())
            types = [types] if isinstance(types, str) else list(types)
            if not rows:  # same columns, empty
                cols[name] = np.array([], dtype=np.float64 if "number" in types else
                                      np.int64 if types == ["integer"] else object)
                continue
            cols[name] = _column([r.data.get(name) for r in rows], numeric="number" in types)
        return cols

    @property
    def telemetry(self) -> dict[str, np.ndarray]:
        """/device/telemetry as columns (see table())."""
        return self.table("/device/telemetry")

    @property
    def events(self) -> list[dict[str, Any]]:
        return [r.data for r in self.records.get("/device/event", [])]

    @property
    def commands(self) -> list[dict[str, Any]]:
        return [r.data for r in self.records.get("/host/command", [])]

    @property
    def gaps(self) -> list[dict[str, Any]]:
        return [r.data for r in self.records.get("/link/gap", [])]

    @property
    def start_ns(self) -> int | None:
        times = [rs[0].log_time_ns for rs in self.records.values() if rs]
        return min(times) if times else None

    @property
    def end_ns(self) -> int | None:
        times = [max(r.log_time_ns for r in rs) for rs in self.records.values() if rs]
        return max(times) if times else None

    @property
    def duration_s(self) -> float:
        """log_time span of the decoded messages [s] (0 for fewer than two)."""
        if self.start_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) * 1e-9


def _column(values: list[Any], *, numeric: bool = False) -> np.ndarray:
    """numeric: the schema says "number", so the column is float64 even if every value is integral."""
    present = [v for v in values if v is not None]
    if numeric and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64)
    if present and all(isinstance(v, bool) for v in present) and len(present) == len(values):
        return np.array(values, dtype=bool)
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        if len(present) == len(values) and all(isinstance(v, int) for v in present):
            return np.array(values, dtype=np.int64)
        return np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64)
    out = np.empty(len(values), dtype=object)
    for i, v in enumerate(values):
        out[i] = tuple(v) if isinstance(v, list) else v
    return out


def read_recording(path: str | Path, *, validate: bool = True) -> Recording:
    """Load a recording; RecordingError (NotARecording, CorruptRecording, RecordingSchemaError) if it
    cannot be used. validate=False skips the per-message schema check (JSON is still parsed)."""
    path = Path(path)
    try:
        f = open(path, "rb")
    except OSError as err:
        raise RecordingError(path, f"cannot open: {err.strerror or err}") from err
    with f:
        size = os.fstat(f.fileno()).st_size
        head = f.read(len(MCAP_MAGIC))
        if head != MCAP_MAGIC:
            what = "the file is empty" if not head else f"it starts with {head[:8]!r}, not the MCAP magic"
            raise NotARecording(path, f"not an MCAP file: {what}")
        f.seek(0)
        return _Loader(path, f, size, validate).load()


class _Loader:
    def __init__(self, path: Path, f: Any, size: int, validate: bool) -> None:
        self.path, self.f, self.size, self.validate = path, f, size, validate
        self.schemas: dict[int, Schema] = {}
        self.channels: dict[int, Channel] = {}
        self.meta: dict[str, str] | None = None
        self.metadata: dict[str, dict[str, str]] = {}
        self.raw: dict[str, list[Record]] = {}
        self.counts: dict[str, int] = {}
        self.foreign: dict[str, str] = {}
        self.chunks = 0
        self.damaged: list[str] = []
        self.checked_channels: set[int] = set()

    def load(self) -> Recording:
        reader = StreamReader(self.f, emit_chunks=True, validate_crcs=True, record_size_limit=None)
        truncated, reason, footer = False, None, False
        records = reader.records
        position = len(MCAP_MAGIC)  # the first record (the Header) follows the magic
        while True:
            try:
                record = next(records)
            except StopIteration:
                break
            except CRCValidationError as err:
                if self.damaged:  # the data-section CRC covers the damaged chunks already reported: stop here
                    break
                raise CorruptRecording(self.path, f"CRC mismatch in the data section ({err})") from err
            except (McapError, struct.error, ValueError, UnicodeDecodeError, OverflowError, MemoryError) as err:
                # a record that cannot be read whole: truncation if it runs past the end, else damage
                truncated, reason = self._classify_cut(position, err)
                break
            start, position = position, self.f.tell()
            if isinstance(record, Chunk):
                number = self.chunks + len(self.damaged) + 1
                try:
                    inner = breakup_chunk(record, validate_crc=True)
                except UnsupportedCompressionError as err:
                    raise RecordingError(self.path, f"chunk {number} is compressed with "
                                         f"{record.compression!r}, which needs a package this host lacks ({err}); "
                                         "install zstandard/lz4 (the robowrangler package depends on zstandard)") from err
                except Exception as err:  # noqa: BLE001 - a CRC mismatch or any parse failure inside a chunk is damage
                    why = "CRC mismatch" if isinstance(err, CRCValidationError) else f"unreadable ({type(err).__name__})"
                    self.damaged.append(f"chunk {number} at byte {start} ({why}, log time {record.message_start_time}"
                                        f"..{record.message_end_time} ns): skipped")
                    continue
                self.chunks += 1
                for r in inner:
                    self._take(r)
            elif isinstance(record, Footer):
                footer = True
            else:
                self._take(record)
        if not footer and not truncated and not self.damaged:
            truncated, reason = True, "no footer: the file ends after its last complete record"
        if self.meta is None:
            if truncated:
                raise NotARecording(self.path, f"truncated before its /meta record ({reason})")
            raise NotARecording(self.path, "no /meta metadata record: an MCAP file, but not a RoboWrangler "
                                "recording (see protocol/recording/schema.md)")
        for rs in self.raw.values():
            rs.sort(key=lambda r: r.log_time_ns)
        return Recording(self.path, self.meta, self.raw, self.counts, self.foreign, truncated, reason, self.chunks,
                         self.metadata, self.damaged)

    def _classify_cut(self, position: int, err: Exception) -> tuple[bool, str]:
        """A record could not be read whole at `position`: truncation if it runs past the end of the file."""
        self.f.seek(position)
        header = self.f.read(RECORD_HEADER_LEN)
        if not header:
            return True, f"no footer: the file ends after its last complete record ({self.size} bytes)"
        if len(header) < RECORD_HEADER_LEN:
            return True, f"file ends inside a record header at byte {position} of {self.size}"
        length = int.from_bytes(header[1:], "little")
        end = position + RECORD_HEADER_LEN + length
        if end > self.size and length <= PLAUSIBLE_RECORD_BYTES:
            return True, (f"the last record (opcode 0x{header[0]:02X}, {length} bytes at byte {position}) is cut "
                          f"off at {self.size} bytes: read up to the last complete chunk")
        if end > self.size:
            raise CorruptRecording(self.path, f"record at byte {position} claims {length} bytes, more than the file "
                                   "holds and more than any recording writes")
        raise CorruptRecording(self.path, f"record at byte {position} (opcode 0x{header[0]:02X}) is malformed: {err}")

    def _take(self, record: Any) -> None:
        if isinstance(record, Metadata):
            if record.name == sg.META_RECORD_NAME:
                self._take_meta(record.metadata)
            else:
                self.metadata.setdefault(record.name, dict(record.metadata))
        elif isinstance(record, Schema):
            self.schemas.setdefault(record.id, record)
        elif isinstance(record, Channel):
            self.channels.setdefault(record.id, record)
        elif isinstance(record, Message):
            self._take_message(record)

    def _take_meta(self, meta: dict[str, str]) -> None:
        err = first_error(meta, _META_SCHEMA)
        if err:
            if meta.get("format") != sg.FORMAT:
                raise NotARecording(self.path, f"its /meta record is not a RoboWrangler one ({err})")
            if meta.get("format_version") not in (None, str(sg.FORMAT_VERSION)):
                raise RecordingSchemaError(self.path, f"recording format_version {meta['format_version']!r}: this "
                                           f"reader reads version {sg.FORMAT_VERSION}")
            raise RecordingSchemaError(self.path, f"/meta violates meta.schema.json: {err}")
        self.meta = dict(meta)

    def _take_message(self, msg: Message) -> None:
        channel = self.channels.get(msg.channel_id)
        if channel is None:
            raise CorruptRecording(self.path, f"message on channel id {msg.channel_id}, which no Channel record "
                                   "defines before it")
        topic = channel.topic
        self.counts[topic] = self.counts.get(topic, 0) + 1
        if topic not in _SCHEMAS:
            schema = self.schemas.get(channel.schema_id)
            self.foreign.setdefault(topic, schema.name if schema else "")
            return
        if self.meta is None:
            raise NotARecording(self.path, "messages before any /meta record: not a RoboWrangler recording "
                                "(the /meta metadata record must come before the first chunk)")
        if channel.id not in self.checked_channels:
            self._check_channel(channel)
            self.checked_channels.add(channel.id)
        try:
            data = json.loads(msg.data)
        except (UnicodeDecodeError, json.JSONDecodeError) as err:
            raise RecordingSchemaError(self.path, f"{topic} message #{self.counts[topic]} "
                                       f"(log_time {msg.log_time} ns) is not JSON: {err}") from err
        if self.validate:
            err = first_error(data, _SCHEMAS[topic])
            if err:
                raise RecordingSchemaError(self.path, f"{topic} message #{self.counts[topic]} (log_time "
                                           f"{msg.log_time} ns) violates {sg.CHANNELS[topic][1]}: {err}"
                                           + self._hash_hint())
        self.raw.setdefault(topic, []).append(Record(msg.log_time, msg.publish_time, data))

    def _check_channel(self, channel: Channel) -> None:
        name, fname, _ = sg.CHANNELS[channel.topic]
        if channel.message_encoding != sg.MESSAGE_ENCODING:
            raise RecordingSchemaError(self.path, f"channel {channel.topic}: message encoding "
                                       f"{channel.message_encoding!r}, expected {sg.MESSAGE_ENCODING!r}")
        schema = self.schemas.get(channel.schema_id)
        if schema is None:
            raise RecordingSchemaError(self.path, f"channel {channel.topic} has no schema; expected {name!r} "
                                       f"(encoding {sg.SCHEMA_ENCODING!r}, data = {fname})")
        if schema.encoding != sg.SCHEMA_ENCODING or schema.name != name:
            raise RecordingSchemaError(self.path, f"channel {channel.topic}: schema {schema.name!r} (encoding "
                                       f"{schema.encoding!r}), expected {name!r} (encoding {sg.SCHEMA_ENCODING!r})"
                                       + self._hash_hint())

    def _hash_hint(self) -> str:
        recorded = (self.meta or {}).get("schema_hash")
        ours = f"0x{sg.SCHEMA_HASH:04X}"
        if recorded and recorded != ours:
            return f" (recorded with protocol schema {recorded}; this reader knows {ours})"
        return ""
