"""One public way to record a run: a RecordingSession is the writer plus the link recorder, fed by whatever host
drives the device - the Client (`wrangler record`, `wrangler excite`), a lockstep scripted host (the simulator's
recordings: robowrangler_sim.sil.recording_host) or anything else that sees the frames.

    with RecordingSession("run.mcap", source="board", device_url=url) as rec:
        with Client(url, transport=rec.transport(open_transport(url)), key=key) as client:
            rec.write_params(read_device_params(client.get_param))
            ...                                   # the run: every frame in and out is recorded
    # closed: unanswered commands NO_REPLY, an open gap if the link went silent, the file finished

A host without a Transport hands the frames over itself: rec.tap_sent(frame, host_s) before sending,
rec.tap_received(frame, host_s) for each datagram received (host_s on the recording's clock, e.g. simulated
seconds with time_base "simulation"). The device's parameters go into the "/device/params" metadata record
(JSON numbers by parameter name), as every recording of this project stores them.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from pathlib import Path

from robowrangler import units
from robowrangler.protocol.generated import PARAMS, ParamSpec
from robowrangler.recorder.link import LinkRecorder, RecordingTransport
from robowrangler.recorder.writer import RecordingWriter
from robowrangler.transport import Transport

PARAMS_METADATA = "/device/params"


def read_device_params(get: Callable[[str], float], *, specs: Iterable[ParamSpec] = PARAMS) -> dict[str, float]:
    """Every parameter by name through get(name) -> value (e.g. Client.get_param), in SI units as float32 gives
    them (units.float32_to_si). Exceptions of get propagate: a recording without its parameters is the caller's
    choice to make."""
    return {spec.name: units.float32_to_si(get(spec.name)) for spec in specs}


class RecordingSession:
    """A recording being made: owns its RecordingWriter and LinkRecorder (writer/recorder attributes).

    Args: path and the RecordingWriter's keyword arguments (source, seed, time_base, device_url, description,
    clock_ns, ...). Use as a context manager, or call close(); close is idempotent.
    """

    def __init__(self, path: str | Path, *, source: str, **writer_options) -> None:
        self.writer = RecordingWriter(path, source=source, **writer_options)
        self.recorder = LinkRecorder(self.writer)
        self.params: dict[str, float] | None = None
        self._closed = False

    @property
    def path(self) -> Path:
        return self.writer.path

    def transport(self, inner: Transport) -> RecordingTransport:
        """inner wrapped so that every frame it carries is recorded (for Client(transport=...))."""
        return RecordingTransport(inner, self.recorder)

    def tap_sent(self, frame: bytes, host_s: float | None = None) -> None:
        """A frame the host is about to send (host_s: the recording clock in s; None: time.monotonic())."""
        self.recorder.on_sent(frame, host_s)

    def tap_received(self, frame: bytes, host_s: float | None = None) -> None:
        """A datagram received from the device."""
        self.recorder.on_received(frame, host_s)

    def write_params(self, values: dict[str, float]) -> None:
        """The device's parameters into the /device/params metadata record (once per recording)."""
        self.params = dict(values)
        self.writer.add_metadata(PARAMS_METADATA, {name: json.dumps(value) for name, value in values.items()})

    def close(self, host_s: float | None = None) -> None:
        """Finish: unanswered commands become NO_REPLY, a silent link's open gap is written, the file closed."""
        if self._closed:
            return
        self._closed = True
        try:
            self.recorder.finish(host_s)
        finally:
            self.writer.close()

    def __enter__(self) -> RecordingSession:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()
