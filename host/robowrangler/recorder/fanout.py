"""Fanout: one LinkRecorder feeding several sinks (an MCAP RecordingWriter, a FoxgloveLiveView).

A sink has write(topic, record, *, log_time_ns=None, publish_time_ns=None) and now_ns(); the first sink's
clock stamps every record, so the file and the live view carry the same log times.
"""

from __future__ import annotations

from typing import Any


class Fanout:
    """Writes each record to every sink, in order; now_ns() is the first sink's."""

    def __init__(self, sinks: list[Any]) -> None:
        if not sinks:
            raise ValueError("sinks: expected at least one sink, got none")
        self.sinks = list(sinks)

    def now_ns(self) -> int:
        return self.sinks[0].now_ns()

    def write(self, topic: str, record: dict[str, Any], *, log_time_ns: int | None = None,
              publish_time_ns: int | None = None) -> None:
        log_ns = self.now_ns() if log_time_ns is None else log_time_ns
        for sink in self.sinks:
            sink.write(topic, record, log_time_ns=log_ns, publish_time_ns=publish_time_ns)
