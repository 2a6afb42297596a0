"""Serial transport (USB CDC): each frame COBS-encoded and followed by one 0x00 delimiter."""

from __future__ import annotations

import collections
import threading
import time

import serial
from cobs import cobs

from robowrangler.protocol.generated import MAX_FRAME_LEN
from robowrangler.transport import Transport

DELIMITER = b"\x00"
# A COBS-encoded frame is at most MAX_FRAME_LEN + 1 bytes; anything longer without a delimiter is noise.
MAX_ENCODED_LEN = MAX_FRAME_LEN + MAX_FRAME_LEN // 254 + 2


def encode_serial_frame(frame: bytes) -> bytes:
    """One protocol frame as it travels on the serial line: COBS(frame) + 0x00."""
    return cobs.encode(frame) + DELIMITER


class SerialTransport(Transport):
    """Frames over a pyserial port (`port` is anything serial.serial_for_url accepts: /dev/ttyACM0,
    COM3, loop://). Data that cannot be COBS-decoded, or runs longer than a frame can be, is
    dropped up to the next delimiter and counted in framing_errors."""

    def __init__(self, port: str, *, baud: int = 115200, url: str | None = None,
                 read_timeout_s: float = 0.02) -> None:
        self.url = url or f"serial://{port}?baud={baud}"
        self._port = serial.serial_for_url(port, baudrate=baud, timeout=read_timeout_s)
        self._buffer = bytearray()
        self._frames: collections.deque[bytes] = collections.deque()
        self._discarding = False
        self._write_lock = threading.Lock()
        self._closed = False
        self.framing_errors = 0

    def send(self, frame: bytes) -> None:
        with self._write_lock:
            self._port.write(encode_serial_frame(frame))

    def recv(self, timeout_s: float) -> bytes | None:
        deadline = time.monotonic() + max(timeout_s, 0.0)
        while not self._frames:
            if self._closed:
                return None
            chunk = self._port.read(max(1, self._port.in_waiting))
            if chunk:
                self._feed(chunk)
            elif time.monotonic() >= deadline:
                return None
        return self._frames.popleft()

    def _feed(self, chunk: bytes) -> None:
        for byte in chunk:
            if byte == 0:
                if self._discarding:
                    self._discarding = False
                elif self._buffer:
                    try:
                        self._frames.append(cobs.decode(bytes(self._buffer)))
                    except cobs.DecodeError:
                        self.framing_errors += 1
                self._buffer.clear()
            elif not self._discarding:
                self._buffer.append(byte)
                if len(self._buffer) > MAX_ENCODED_LEN:
                    self.framing_errors += 1
                    self._buffer.clear()
                    self._discarding = True

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._port.close()
