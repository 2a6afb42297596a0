"""FoxgloveLiveView: the recording's channels served live over Foxglove's WebSocket protocol.

    live = FoxgloveLiveView(port=8765)            # ws://127.0.0.1:8765, open it in Foxglove
    recorder = LinkRecorder(Fanout([writer, live]))

Each channel of the recording schema (/device/telemetry, /device/event, /host/command, /link/gap, ...) is
advertised with the same JSON Schema the MCAP recordings carry (schema encoding "jsonschema", message
encoding "json"), so a Foxglove layout made on a recording works live and the other way round: plot
/device/telemetry.rope_speed_mps against .rope_speed_setpoint_mps, watch .state, the events and each command
with its verdict as they happen. /device/params carries the device parameters with the ToV guard
(tov_mps x tov_margin) worked out, published when the link starts.

The server is the foxglove-sdk package's (the `robowrangler[foxglove]` extra); it binds 127.0.0.1 only.
"""

from __future__ import annotations

import json
import time
from typing import Any

from robowrangler.errors import InvalidArgument
from robowrangler.recorder import schemas_generated as sg

PARAMS_TOPIC = "/device/params"
PARAMS_SCHEMA = {
    "title": "robowrangler.DeviceParams",
    "description": "The device parameters (units as in the parameter table) and tov_guard_mps = tov_mps x tov_margin.",
    "type": "object",
    "additionalProperties": {"type": "number"},
}


class FoxgloveLiveView:
    """A Foxglove WebSocket server with one channel per recording topic; write() as RecordingWriter's.

    Args:
        host: address to bind (loopback by default: the live view stays on this machine).
        port: TCP port (0 picks a free one: see `port`).
        name: the server name Foxglove shows.
    """

    def __init__(self, *, host: str = "127.0.0.1", port: int = 8765, name: str = "RoboWrangler") -> None:
        try:
            import foxglove
        except ImportError:
            raise InvalidArgument("--foxglove", "the foxglove-sdk package (install robowrangler[foxglove])",
                                  "not installed") from None
        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(name=name, host=host, port=port, context=self._context)
        except Exception as err:  # noqa: BLE001 - the SDK raises its own error type for a taken port
            raise InvalidArgument("--foxglove", "a free local TCP port", f"{port} ({err})") from None
        self.port = self._server.port
        self._channels = {}
        for topic, (name_, _, text) in sg.CHANNELS.items():
            schema = foxglove.Schema(name=name_, encoding=sg.SCHEMA_ENCODING, data=text.encode())
            self._channels[topic] = foxglove.Channel(topic, schema=schema, message_encoding=sg.MESSAGE_ENCODING,
                                                     context=self._context)
        params_schema = foxglove.Schema(name=PARAMS_SCHEMA["title"], encoding="jsonschema",
                                        data=json.dumps(PARAMS_SCHEMA).encode())
        self._channels[PARAMS_TOPIC] = foxglove.Channel(PARAMS_TOPIC, schema=params_schema, message_encoding="json",
                                                        context=self._context)
        self.messages = 0
        self._epoch_ns = time.time_ns()
        self._mono0_ns = time.monotonic_ns()

    @property
    def context(self):
        """The foxglove.Context this server serves: more channels on it (e.g. a SceneUpdateChannel) reach the
        same clients."""
        return self._context

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    def now_ns(self) -> int:
        """Host time in ns since the epoch, advancing with the monotonic clock (as RecordingWriter's)."""
        return self._epoch_ns + (time.monotonic_ns() - self._mono0_ns)

    def write(self, topic: str, record: dict[str, Any], *, log_time_ns: int | None = None,
              publish_time_ns: int | None = None) -> None:
        """Publish one record on its topic (dropped if no Foxglove client subscribes)."""
        channel = self._channels.get(topic)
        if channel is None:
            return
        channel.log(record, log_time=self.now_ns() if log_time_ns is None else int(log_time_ns))
        self.messages += 1

    def publish_params(self, params: dict[str, float]) -> None:
        """The device parameters, with the ToV guard worked out (a Plot panel line next to the speed)."""
        record = dict(params)
        if "tov_mps" in params and "tov_margin" in params:
            record["tov_guard_mps"] = params["tov_mps"] * params["tov_margin"]
        self.write(PARAMS_TOPIC, record)

    def close(self) -> None:
        self._server.stop()
        for channel in self._channels.values():
            channel.close()
