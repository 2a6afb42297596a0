"""Recordings: the MCAP files of protocol/recording/schema.md - write, record a live link, read, summarise, plot.

- writer.RecordingWriter: JSON messages with JSON Schemas per channel, small chunks flushed often.
- link.LinkRecorder / RecordingTransport: records what a Client sends and receives (telemetry with seq,
  events, commands with their ACK/NACK, sequence gaps).
- reader.read_recording: per-channel records and numpy columns; tolerant of truncation, strict otherwise.
- session.RecordingSession: the one public way to record a run (writer + link recorder + /device/params), fed
  by a Client's transport or by any host that sees the frames; read_device_params reads them all.
- burst: /device/burst records put back together per burst (lost frames as missing samples).
- gaps: uint16 sequence-gap detection; summary: `wrangler inspect`; plot: `wrangler replay --plot`.
"""

from robowrangler.recorder.errors import CorruptRecording, NotARecording, RecordingError, RecordingSchemaError
from robowrangler.recorder.gaps import SeqGap, SeqGapDetector, find_gaps
from robowrangler.recorder.link import LinkRecorder, RecordingTransport
from robowrangler.recorder.reader import Record, Recording, read_recording
from robowrangler.recorder.session import RecordingSession, read_device_params
from robowrangler.recorder.writer import RecordingWriter

__all__ = ["CorruptRecording", "LinkRecorder", "NotARecording", "Record", "Recording", "RecordingError",
           "RecordingSchemaError", "RecordingSession", "RecordingTransport", "RecordingWriter", "SeqGap", "SeqGapDetector",
           "find_gaps", "read_device_params", "read_recording"]
