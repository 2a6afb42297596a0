"""RecordingWriter: an MCAP file in the RoboWrangler recording schema (protocol/recording/schema.md).

    with RecordingWriter("run.mcap", source="sil", seed=0) as rec:
        rec.write("/device/telemetry", record)          # record: a dict valid for the channel's schema

Messages are JSON (message encoding "json") with a JSON Schema per channel (schema encoding
"jsonschema"), so any MCAP tool reads them. The file is chunked and a chunk is finished (written and
flushed to the OS) every `flush_period_s` or every `flush_messages` messages, whichever comes first,
also while no message arrives (a background thread): a killed recorder loses at most that much, and
the reader reads everything up to the last complete chunk. Chunks are zstd-compressed (the host
depends on `zstandard`, which the mcap library, Foxglove and the `mcap` CLI read; compression="none"
writes them plain); close() writes the summary section (statistics, indexes) and the footer.

Thread-safe: one lock guards the MCAP writer (the client's receive and send threads both write).

Simulated recordings (a SIL run stepped as fast as the machine goes) pass their own clock:

    with RecordingWriter("sim.mcap", source="sil", time_base="simulation", clock_ns=lambda: sim_ns) as rec:

then log times default to that clock and chunks are finished every flush_period_s of it (checked at each
write, no background thread), so the same run gives the same bytes whatever the machine's speed.
"""

from __future__ import annotations

import datetime
import json
import threading
import time
from pathlib import Path
from collections.abc import Callable
from typing import Any

from mcap.writer import CompressionType, Writer

from robowrangler.recorder import schemas_generated as sg
from robowrangler.recorder.errors import RecordingError, RecordingSchemaError
from robowrangler.recorder.json_schema_check import first_error

DEFAULT_FLUSH_PERIOD_S = 0.5
DEFAULT_FLUSH_MESSAGES = 200
DEFAULT_CHUNK_SIZE_BYTES = 256 * 1024  # a hard cap; the period/count flush normally comes first
_COMPRESSION = {"zstd": CompressionType.ZSTD, "none": CompressionType.NONE}
_SCHEMAS = {topic: json.loads(text) for topic, (_, _, text) in sg.CHANNELS.items()}


def writer_identity() -> str:
    """The `writer` meta value: this package and its version."""
    try:
        from importlib.metadata import version

        return f"robowrangler {version('robowrangler')}"
    except Exception:  # noqa: BLE001 - not installed as a distribution (source checkout)
        return "robowrangler"


class RecordingWriter:
    """Writes one recording.

    Args:
        path: output file (.mcap); an existing file is replaced (the CLI refuses one without --force).
        source: "board", "sil", "simulator" or "other" (meta `source`).
        seed: random seed of a SIL/simulator run, None if none.
        time_base: "unix" (log_time = ns since the epoch, host clock) or "simulation" (ns of simulated time).
        device_url: the link recorded, "" if none.
        description: free text for the meta record.
        flush_period_s: finish a chunk at least this often while messages arrive [s].
        flush_messages: finish a chunk after this many messages.
        validate: check every record against its channel schema before writing (RecordingSchemaError).
        clock_ns: the recording's clock in integer ns (e.g. simulated time for time_base "simulation"): it
            stamps log times (now_ns()) and times the chunk flushes; None: the host clock (unix ns).
        compression: "zstd" (default) or "none": how chunks are stored.
    """

    def __init__(self, path: str | Path, *, source: str, seed: int | None = None, time_base: str = "unix",
                 device_url: str = "", description: str = "",
                 flush_period_s: float = DEFAULT_FLUSH_PERIOD_S, flush_messages: int = DEFAULT_FLUSH_MESSAGES,
                 validate: bool = True, clock_ns: Callable[[], int] | None = None,
                 compression: str = "zstd") -> None:
        self.path = Path(path)
        if source not in sg.SOURCES:
            raise RecordingError(self.path, f"source: expected one of {list(sg.SOURCES)}, got {source!r}")
        if time_base not in sg.TIME_BASES:
            raise RecordingError(self.path, f"time_base: expected one of {list(sg.TIME_BASES)}, got {time_base!r}")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
            raise RecordingError(self.path, f"seed: expected an integer or None, got {seed!r}")
        if not (isinstance(flush_period_s, (int, float)) and flush_period_s > 0):
            raise RecordingError(self.path, f"flush_period_s: expected a number > 0, got {flush_period_s!r}")
        if isinstance(flush_messages, bool) or not isinstance(flush_messages, int) or flush_messages < 1:
            raise RecordingError(self.path, f"flush_messages: expected an integer >= 1, got {flush_messages!r}")
        if compression not in _COMPRESSION:
            raise RecordingError(self.path, f"compression: expected one of {list(_COMPRESSION)}, got {compression!r}")
        if clock_ns is not None and not callable(clock_ns):
            raise RecordingError(self.path, f"clock_ns: expected a callable returning ns or None, got {clock_ns!r}")
        self._clock_ns = clock_ns
        self.flush_period_s = float(flush_period_s)
        self.flush_messages = flush_messages
        self.validate = validate
        self.meta = {
            "format": sg.FORMAT, "format_version": str(sg.FORMAT_VERSION), "source": source,
            "schema_hash": f"0x{sg.SCHEMA_HASH:04X}", "protocol_version": str(sg.PROTOCOL_VERSION),
            "units": sg.UNITS_CONVENTION, "time_base": time_base, "seed": "" if seed is None else str(seed),
            "created_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds"),
            "writer": writer_identity(), "device_url": device_url, "description": description,
        }
        for key in ("device_url", "description"):
            if not isinstance(self.meta[key], str):
                raise RecordingError(self.path, f"{key}: expected a string, got {self.meta[key]!r}")
        self._lock = threading.Lock()
        self._epoch_ns = time.time_ns()
        self._mono0_ns = time.monotonic_ns()
        try:
            self._file = open(self.path, "wb")
        except OSError as err:
            raise RecordingError(self.path, f"cannot create the file: {err.strerror or err}") from err
        self._mcap = Writer(self._file, chunk_size=DEFAULT_CHUNK_SIZE_BYTES, compression=_COMPRESSION[compression])
        self._mcap.start(profile="", library=self.meta["writer"])
        self._mcap.add_metadata(sg.META_RECORD_NAME, self.meta)
        self._file.flush()
        self._channels: dict[str, int] = {}
        self.counts: dict[str, int] = {}
        self._unflushed = 0
        self._closed = False
        self._stop = threading.Event()
        self._flusher: threading.Thread | None = None
        self._last_flush_s = self._flush_clock_s()
        if clock_ns is None:  # the host clock runs on while nothing is written: a thread finishes chunks
            self._flusher = threading.Thread(target=self._flush_loop, name="recording-flush", daemon=True)
            self._flusher.start()

    # ------------------------------------------------------------------------------------------------
    def add_metadata(self, name: str, values: dict[str, str]) -> None:
        """Another MCAP Metadata record (string values), e.g. "/device/params"; written at once."""
        if not isinstance(name, str) or not name.startswith("/") or name == sg.META_RECORD_NAME:
            raise RecordingError(self.path, f"metadata name: expected a '/name' other than "
                                 f"{sg.META_RECORD_NAME!r}, got {name!r}")
        bad = {k: v for k, v in values.items() if not isinstance(k, str) or not isinstance(v, str)}
        if bad:
            raise RecordingError(self.path, f"metadata {name}: expected string keys and values, got {bad!r}")
        with self._lock:
            if self._closed:
                raise RecordingError(self.path, f"metadata {name} after close()")
            self._flush_locked()
            self._mcap.add_metadata(name, dict(values))
            self._file.flush()

    def now_ns(self) -> int:
        """Time for log_time: the clock_ns given, else host time: ns since the epoch, advancing with the
        monotonic clock (never jumps)."""
        if self._clock_ns is not None:
            return int(self._clock_ns())
        return self._epoch_ns + (time.monotonic_ns() - self._mono0_ns)

    def _flush_clock_s(self) -> float:
        return self._clock_ns() * 1e-9 if self._clock_ns is not None else time.monotonic()

    def write(self, topic: str, record: dict[str, Any], *, log_time_ns: int | None = None,
              publish_time_ns: int | None = None) -> None:
        """Append one record to a channel. log_time_ns defaults to now_ns(), publish_time_ns to log_time_ns.

        RecordingSchemaError if validation is on and the record violates the channel's schema;
        RecordingError for an unknown topic or a closed writer.
        """
        if topic not in _SCHEMAS:
            raise RecordingError(self.path, f"topic: expected one of {sorted(_SCHEMAS)}, got {topic!r}")
        if self.validate:
            err = first_error(record, _SCHEMAS[topic])
            if err:
                raise RecordingSchemaError(self.path, f"{topic} record violates its schema: {err}")
        try:
            data = json.dumps(record, separators=(",", ":"), allow_nan=False).encode()
        except (TypeError, ValueError) as err:
            raise RecordingSchemaError(self.path, f"{topic} record is not JSON-serialisable: {err}") from err
        log_ns = self.now_ns() if log_time_ns is None else int(log_time_ns)
        pub_ns = log_ns if publish_time_ns is None else int(publish_time_ns)
        with self._lock:
            if self._closed:
                raise RecordingError(self.path, f"write to {topic} after close()")
            channel_id = self._channels.get(topic)
            if channel_id is None:
                name, _, text = sg.CHANNELS[topic]
                schema_id = self._mcap.register_schema(name=name, encoding=sg.SCHEMA_ENCODING, data=text.encode())
                channel_id = self._mcap.register_channel(topic=topic, message_encoding=sg.MESSAGE_ENCODING,
                                                         schema_id=schema_id)
                self._channels[topic] = channel_id
            self._mcap.add_message(channel_id=channel_id, log_time=log_ns, publish_time=pub_ns, data=data,
                                   sequence=self.counts.get(topic, 0))
            self.counts[topic] = self.counts.get(topic, 0) + 1
            self._unflushed += 1
            if self._unflushed >= self.flush_messages or (
                    self._clock_ns is not None and self._flush_clock_s() - self._last_flush_s >= self.flush_period_s):
                self._flush_locked()

    def flush(self) -> None:
        """Finish the chunk in progress and hand it to the OS now."""
        with self._lock:
            if not self._closed:
                self._flush_locked()

    def _flush_locked(self) -> None:
        if self._unflushed:
            self._mcap.flush()  # finishes the chunk (with its message indexes) and flushes the stream
        self._unflushed = 0
        self._last_flush_s = self._flush_clock_s()

    def _flush_loop(self) -> None:
        while not self._stop.wait(self.flush_period_s / 4):
            with self._lock:
                if self._closed:
                    return
                if self._unflushed and time.monotonic() - self._last_flush_s >= self.flush_period_s:
                    self._flush_locked()

    def close(self) -> None:
        """Finish the last chunk, write the summary and footer, close the file. Idempotent."""
        self._stop.set()
        with self._lock:
            if self._closed:
                return
            self._closed = True
            try:
                self._mcap.finish()
            finally:
                self._file.close()
        if self._flusher is not None and self._flusher is not threading.current_thread():
            self._flusher.join(timeout=2.0)

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
