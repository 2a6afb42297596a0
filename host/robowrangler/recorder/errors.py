"""Typed errors of the recorder: each names the file and the reason (and where in the file)."""

from __future__ import annotations

from pathlib import Path

from robowrangler.errors import RoboWranglerError


class RecordingError(RoboWranglerError):
    """A recording cannot be written or read. `path` names the file, `reason` says why."""

    def __init__(self, path: str | Path, reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = str(path)
        self.reason = reason


class NotARecording(RecordingError):
    """Not a RoboWrangler recording: not MCAP at all, or an MCAP file without our /meta record."""


class CorruptRecording(RecordingError):
    """An MCAP file whose bytes are damaged (CRC mismatch, impossible record) before its end."""


class RecordingSchemaError(RecordingError):
    """A record that violates its channel's JSON Schema (or a channel with the wrong schema/encoding)."""
