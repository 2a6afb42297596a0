"""The transport interface (one frame in, one frame out) and the link URL parser.

URLs:
    udp://HOST:PORT                       WiFi board or SIL firmware (default udp://127.0.0.1:14550)
    serial:///dev/ttyACM0?baud=115200     USB serial, COBS-framed; any pyserial port works after
                                          "serial://", e.g. serial://loop://?baud=115200, serial://COM3
"""

from __future__ import annotations

import abc
from dataclasses import dataclass
from urllib.parse import parse_qsl

from robowrangler.errors import InvalidArgument, LinkError

DEFAULT_URL = "udp://127.0.0.1:14550"
DEFAULT_BAUD = 115200


class Transport(abc.ABC):
    """Carries whole protocol frames (bytes from magic to checksum), thread-safe for one sender
    thread plus one receiver thread. `framing_errors` counts received data the transport itself
    could not delimit (serial only)."""

    url: str
    framing_errors: int = 0

    @abc.abstractmethod
    def send(self, frame: bytes) -> None:
        """Send one frame. OSError on a dead link."""

    @abc.abstractmethod
    def recv(self, timeout_s: float) -> bytes | None:
        """One received frame (undecoded), or None if nothing arrived within timeout_s."""

    @abc.abstractmethod
    def close(self) -> None:
        """Release the socket or port; idempotent."""


@dataclass(frozen=True)
class UdpUrl:
    host: str
    port: int


@dataclass(frozen=True)
class SerialUrl:
    port: str
    baud: int


def parse_url(url: object) -> UdpUrl | SerialUrl:
    """Parse a link URL; InvalidArgument naming what is wrong."""
    if not isinstance(url, str):
        raise InvalidArgument("url", "a string like udp://HOST:PORT or serial:///dev/ttyACM0?baud=115200", url)
    if url.startswith("udp://"):
        return _parse_udp(url)
    if url.startswith("serial://"):
        return _parse_serial(url)
    raise InvalidArgument("url", "a scheme udp:// or serial://", url)


def _parse_udp(url: str) -> UdpUrl:
    rest = url[len("udp://"):]
    if "/" in rest or "?" in rest or "#" in rest:
        raise InvalidArgument("url", "udp://HOST:PORT with no path or query", url)
    if rest.startswith("["):  # [IPv6]:port
        host, sep, port_text = rest[1:].partition("]:")
    else:
        host, sep, port_text = rest.rpartition(":")
    if not sep or not host:
        raise InvalidArgument("url", "udp://HOST:PORT (host and port both given)", url)
    if not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise InvalidArgument("url", "a UDP port in 1..65535", url)
    return UdpUrl(host, int(port_text))


def _parse_serial(url: str) -> SerialUrl:
    rest = url[len("serial://"):]
    port, _, query = rest.partition("?")
    if not port:
        raise InvalidArgument("url", "serial://PORT?baud=N with a port, e.g. serial:///dev/ttyACM0", url)
    baud = DEFAULT_BAUD
    for key, value in parse_qsl(query, keep_blank_values=True):
        if key != "baud":
            raise InvalidArgument("url", "only the query option baud=N", url)
        if not value.isdigit() or int(value) <= 0:
            raise InvalidArgument("url", "baud=N with N a positive integer", url)
        baud = int(value)
    return SerialUrl(port, baud)


def open_transport(url: str) -> Transport:
    """Open the transport a URL names (UDP socket or serial port); LinkError if it cannot be opened."""
    parsed = parse_url(url)
    try:
        if isinstance(parsed, UdpUrl):
            from robowrangler.transport_udp import UdpTransport

            return UdpTransport(parsed.host, parsed.port, url=url)
        from robowrangler.transport_serial import SerialTransport

        return SerialTransport(parsed.port, baud=parsed.baud, url=url)
    except OSError as err:  # serial.SerialException and socket.gaierror are OSErrors
        raise LinkError(f"cannot open {url}: {err}", url=url) from err
