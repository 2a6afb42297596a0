"""The SIL board's status lines on its USB serial, as a person at a terminal reads them.

The board writes lines of text between its protocol frames (``rw: ...\\n`` and a 0x00 delimiter; a host's COBS
reader drops them as malformed frames): the WiFi link's state when it changes and, every 10 s, its counters.
Like the board (which checks DTR), the SIL writes them only while a host has the port open, so open the reader
before the lines you want are written. Do not read with this while another program uses the same port (the
bytes would be split between the two readers).
"""

from __future__ import annotations

import os


class UsbNotes:
    """Reads the status lines from the SIL device's USB serial (a pseudo-terminal path)."""

    def __init__(self, serial_path: str) -> None:
        self.path = serial_path
        self._fd = os.open(serial_path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY)
        self._buffer = b""

    def read(self) -> list[str]:
        """The status lines written since the last read (without "rw: "); frames and partial lines are skipped.
        After close(): none."""
        while self._fd >= 0:
            try:
                chunk = os.read(self._fd, 4096)
            except BlockingIOError:
                break
            if not chunk:
                break
            self._buffer += chunk
        *complete, self._buffer = self._buffer.split(b"\0")
        lines = []
        for item in complete:
            if item.startswith(b"rw: ") and item.endswith(b"\n"):
                lines.append(item[4:-1].decode("utf-8", "replace"))
        return lines

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> UsbNotes:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
