"""UDP transport: one datagram = one frame; socket bound to an ephemeral port, connected to the device."""

from __future__ import annotations

import select
import socket

from robowrangler.transport import Transport

RECV_BUFFER_BYTES = 2048  # larger than any frame, so an oversize datagram is seen whole and rejected


class UdpTransport(Transport):
    """Datagram link to udp://host:port. The socket is connected, so datagrams from any other
    address are dropped by the kernel. ICMP 'port unreachable' (nobody listening yet) is ignored:
    the client's timeouts report a silent device."""

    def __init__(self, host: str, port: int, *, url: str | None = None) -> None:
        self.url = url or f"udp://{host}:{port}"
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)
        family, _, _, _, address = infos[0]
        self._sock = socket.socket(family, socket.SOCK_DGRAM)
        self._sock.bind(("::", 0) if family == socket.AF_INET6 else ("0.0.0.0", 0))
        self._sock.connect(address)
        self._closed = False
        self.unreachable = 0  # ICMP port-unreachable reports seen

    @property
    def local_address(self) -> tuple:
        """(host, port) the socket is bound to."""
        return self._sock.getsockname()

    def send(self, frame: bytes) -> None:
        try:
            self._sock.send(frame)
        except ConnectionRefusedError:  # an earlier datagram hit a closed port; this one is not lost
            self.unreachable += 1
            try:
                self._sock.send(frame)
            except ConnectionRefusedError:  # still nobody listening: the datagram is lost like on WiFi
                self.unreachable += 1

    def recv(self, timeout_s: float) -> bytes | None:
        if self._closed:
            return None
        try:
            ready, _, _ = select.select([self._sock], [], [], max(timeout_s, 0.0))
            if not ready:
                return None
            return self._sock.recv(RECV_BUFFER_BYTES)
        except ConnectionRefusedError:
            self.unreachable += 1
            return None
        except (OSError, ValueError):
            if self._closed:  # closed by another thread while waiting
                return None
            raise

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._sock.close()
