"""A device at the far end of a pty pair (a USB serial port stand-in): COBS-framed, answers commands with
ACK, HELLO with SESSION_INFO, PROVISION_* like the board's provisioning, and sends TELEMETRY every 20 ms."""

from __future__ import annotations

import os
import select
import threading

from cobs import cobs

from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import MsgId, NackReason, State
from robowrangler.transport_serial import encode_serial_frame
from wire import make


class PtyDevice:
    """`port` is the pty path to open as serial://PORT. Records received (frame, msg); stored_key, ssid,
    password and commits show what provisioning wrote ("flash")."""

    def __init__(self) -> None:
        self.master, self._slave = os.openpty()
        self.port = os.ttyname(self._slave)
        self.received: list[tuple[gen.Frame, gen.Message]] = []
        self.state = State.DISARMED
        self.stored_key: bytes | None = None
        self.ssid = ""
        self.password: str | None = None
        self.commits = 0
        self._staged: dict[str, object] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._seq = 0

    @property
    def commands(self) -> list[tuple[int, int]]:
        return [(f.msg_id, f.seq) for f, m in self.received if m.KIND in (gen.MsgKind.COMMAND, gen.MsgKind.PROVISION)]

    def __enter__(self) -> PtyDevice:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2.0)
        os.close(self.master)
        os.close(self._slave)

    def _send(self, msg: gen.Message) -> None:
        os.write(self.master, encode_serial_frame(gen.encode_frame(msg, self._seq)))
        self._seq = (self._seq + 1) & 0xFFFF

    def _status(self) -> gen.Message:
        return gen.ProvisionStatus(int(self.stored_key is not None), int(self.password is not None), self.ssid, 3,
                                   self.commits, 1, int(bool(self._staged)))

    def _answer(self, frame: gen.Frame, msg: gen.Message) -> None:
        mid = frame.msg_id
        if mid == MsgId.HELLO:
            self._send(gen.SessionInfo(msg.host_nonce, 3, int(self.stored_key is not None), gen.SCHEMA_HASH))
            return
        if msg.KIND not in (gen.MsgKind.COMMAND, gen.MsgKind.PROVISION):
            return
        if mid == MsgId.PROVISION_SET_WIFI_PASSWORD and 0 < len(msg.password) < 8:
            self._send(gen.Nack(mid, frame.seq, NackReason.OUT_OF_RANGE, self.state, 8))
            return
        if mid == MsgId.ARM:
            self.state = State.ARMED
        elif mid == MsgId.PROVISION_SET_KEY:
            self._staged["key"] = msg.key
        elif mid == MsgId.PROVISION_SET_WIFI_SSID:
            self._staged["ssid"] = msg.ssid
        elif mid == MsgId.PROVISION_SET_WIFI_PASSWORD:
            self._staged["password"] = msg.password
        elif mid == MsgId.PROVISION_COMMIT:
            self.stored_key = self._staged.pop("key", self.stored_key)
            self.ssid = self._staged.pop("ssid", self.ssid)
            self.password = self._staged.pop("password", self.password)
            self.commits += 1
        self._send(gen.Ack(mid, frame.seq, self.state))
        if mid == MsgId.PROVISION_GET:
            self._send(self._status())

    def _run(self) -> None:
        buf = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([self.master], [], [], 0.02)
            if ready:
                buf += os.read(self.master, 1024)
                *chunks, buf = buf.split(b"\x00")
                for chunk in chunks:
                    frame, msg = gen.decode_message(cobs.decode(chunk))
                    self.received.append((frame, msg))
                    self._answer(frame, msg)
            self._send(make(gen.Telemetry, time_ms=1000, state=self.state, esc_pulse_us=1000, battery_mv=12000))
