"""The real firmware core as the device of the host tests: librw_core.so through the ctypes harness
(tests/firmware_core/core_harness.py) on simulated time, behind a Transport (in process) or a UDP port.

Nothing of the device is re-implemented here: the state machine, the duplicate cache, the NACK reasons, the
signing and the freshness rules are the core's. What this file adds is the world around it:

- Time: a device thread ticks the core every 1 ms of simulated time. Simulated time is paced to at most
  `speedup` x the wall clock and never races to catch up: when the process falls behind (a loaded machine)
  the device's clock falls behind with it instead of jumping ahead, so a slow host never sees the device's
  time run away from its own (None: unpaced, as fast as the machine goes).
- Plant: a perfect drive (the encoder turns at the setpoint of the latest TELEMETRY the core packed, as the
  harness's follow_setpoint does) and the harness's FakeSpindle (lead screw, end stops, an object to catch).
- Links: the core's WiFi link (signed: the harness's flash holds TEST_KEY, session 1) and its USB serial link
  (trusted, unsigned frames). CoreTransports (transport(link)) attach to either; the UDP port (url) to the
  device's default link; a pseudo-terminal (open_pty(): COBS-framed like the board's USB serial) to the
  serial link.
- The network between host and device, not the device: `to_device` / `to_host` are lists of filters
  f(data) -> bytes | None applied to each datagram in that direction (None: lost), e.g. lose_acks().
- Records: every datagram the host sent (host_frames, before the filters), the core's outputs (harness).
"""

from __future__ import annotations

import os
import queue
import socket
import threading
import time
from collections import deque
from collections.abc import Callable

from core_harness import TEST_KEY, CoreHarness, FakeSpindle, Out
from robowrangler.protocol import generated as gen
from cobs import cobs

from robowrangler.transport import Transport
from robowrangler.transport_serial import DELIMITER, encode_serial_frame

TICK_US = 1000
BEHIND_LIMIT_S = 0.02  # further behind the wall clock than this: re-anchor the pacing (never race)

Filter = Callable[[bytes], "bytes | list[bytes] | None"]


class CoreTransport(Transport):
    """A Transport whose far end is one of the CoreDevice's links (what a Client gets from CoreDevice.transport())."""

    def __init__(self, device: CoreDevice, link: str) -> None:
        self.url = device.url if link == device.link else f"serial://core-device-{device.port}"
        self.link = link
        self._device = device
        self._inbox: queue.Queue[bytes] = queue.Queue()
        self._closed = False

    def send(self, frame: bytes) -> None:
        if self._closed:
            raise OSError("transport closed")
        self._device.submit(bytes(frame), self, link=self.link)

    def recv(self, timeout_s: float) -> bytes | None:
        try:
            return self._inbox.get(timeout=max(0.0, timeout_s))
        except queue.Empty:
            return None

    def deliver(self, data: bytes) -> None:
        if not self._closed:
            self._inbox.put(data)

    def close(self) -> None:
        self._closed = True


class CoreDevice:
    """Run with `with CoreDevice(lib) as dev:`; then dev.transport() (a Transport) or dev.url (UDP).

    Args:
        lib: the core library (the `rw_core` fixture).
        link: "wifi" (signed frames only; key = TEST_KEY) or "serial" (the trusted USB link: unsigned frames).
        speedup: simulated seconds per wall second, at most (None: unpaced).
        params: parameters set before the first tick ({name: value}, PARAM_SET's checks).
        spindle: the servo on the lead screw (default: a FakeSpindle at 3 mm from home).
        boot_s: simulated time the core runs before start() returns (unpaced, no host): e.g. past the arming hold.
        provisioned: False boots a flash record without a link key (the core takes nothing over WiFi).
    """

    def __init__(self, lib, *, link: str = "wifi", speedup: float | None = 1.0,
                 params: dict[str, float] | None = None, spindle: FakeSpindle | None = None,
                 boot_s: float = 0.0, provisioned: bool = True) -> None:
        if link not in ("wifi", "serial"):
            raise ValueError(f"link: expected 'wifi' or 'serial', got {link!r}")
        self.link = link
        self.key = TEST_KEY if link == "wifi" else None
        self.speedup = speedup
        self.spindle = FakeSpindle() if spindle is None else spindle
        self.harness = CoreHarness(lib, params=params, spindle=self.spindle, serial=True, provisioned=provisioned)
        self.boot_s = boot_s
        self.lock = threading.RLock()  # guards the harness, the records and the filters
        self.to_device: list[Filter] = []
        self.to_host: list[Filter] = []
        self.host_frames: list[bytes] = []  # every datagram a host sent, in order, before the filters
        self._pending: dict[str, deque[tuple[bytes, object]]] = {"wifi": deque(), "serial": deque()}
        self._sender: dict[str, object] = {"wifi": None, "serial": None}  # who sent what the core reads this tick
        self._peer: dict[str, object] = {"wifi": None, "serial": None}    # where the core's own frames go
        self._pty: _PtyEnd | None = None
        self._staged_key: bytes | None = None
        self._last_commit: bytes | None = None  # the last PROVISION_COMMIT frame seen on serial
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.setblocking(False)
        self.port = self._sock.getsockname()[1]
        self.url = f"udp://127.0.0.1:{self.port}"
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: BaseException | None = None

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> CoreDevice:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.halt()
        self._sock.close()
        if self._pty is not None:
            self._pty.close()
        if self.error is not None and exc[0] is None:
            raise self.error

    def start(self) -> CoreDevice:
        with self.lock:
            while self.harness.t_us < self.boot_s * 1e6:
                self._tick()
        self._thread = threading.Thread(target=self._run, name="core-device", daemon=True)
        self._thread.start()
        return self

    def halt(self) -> None:
        """Stop the core's clock: no tick, no answer, no telemetry (a board that lost power)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)

    def transport(self, link: str | None = None) -> CoreTransport:
        """A Transport to one of the core's links (default: the device's link; one host per link at a time)."""
        link = self.link if link is None else link
        if link not in ("wifi", "serial"):
            raise ValueError(f"link: expected 'wifi' or 'serial', got {link!r}")
        return CoreTransport(self, link)

    def open_pty(self) -> str:
        """A pseudo-terminal on the core's serial link, COBS-framed as the board's USB serial; returns its path
        (serial://PATH for a Client)."""
        with self.lock:
            if self._pty is None:
                self._pty = _PtyEnd()
            return self._pty.path

    # ------------------------------------------------------------------ host side
    def submit(self, data: bytes, sender: object, *, link: str | None = None) -> None:
        """A datagram from a host (a CoreTransport, a UDP address or the pty) for a link (default: the device's),
        read by the core on a coming tick."""
        with self.lock:
            self.host_frames.append(data)
            datagrams = [data]
            for f in self.to_device:  # a filter may lose a datagram (None), change it, or add some (a list)
                datagrams = [out for d in datagrams for out in _as_list(f(d))]
            self._pending[self.link if link is None else link].extend((d, sender) for d in datagrams)

    def send_to_host(self, data: bytes) -> None:
        """Bytes on the wire towards the host the core talks to (as if from the device's address)."""
        with self.lock:
            self._emit(bytes(data), self._peer[self.link])

    def _emit(self, data: bytes, dest: object) -> None:
        datagrams = [data]
        for f in self.to_host:  # a filter may lose a datagram (None) or add some (a list)
            datagrams = [out for d in datagrams for out in _as_list(f(d))]
        for d in datagrams:
            if isinstance(dest, (CoreTransport, _PtyEnd)):
                dest.deliver(d)
            elif dest is not None:
                try:
                    self._sock.sendto(d, dest)
                except OSError:
                    pass  # the host went away: the datagram is lost, as on a network

    # ------------------------------------------------------------------ the device's clock
    def _run(self) -> None:
        try:
            origin: tuple[float, int] | None = None
            while not self._stop.is_set():
                with self.lock:
                    self._tick()
                    sim_us = self.harness.t_us
                if self.speedup is None:
                    continue
                now = time.perf_counter()
                if origin is None:
                    origin = (now, sim_us)
                ahead_s = (sim_us - origin[1]) * 1e-6 / self.speedup - (now - origin[0])
                if ahead_s > 0.002:
                    self._stop.wait(ahead_s)
                elif ahead_s < -BEHIND_LIMIT_S:
                    origin = (now, sim_us)  # fell behind: the device's clock waits for the machine, no burst
        except BaseException as err:  # noqa: BLE001 - raised by __exit__ (a core check failed)
            self.error = err

    def _tick(self) -> None:
        h = self.harness
        while True:  # UDP hosts
            try:
                data, addr = self._sock.recvfrom(2048)
            except (BlockingIOError, OSError):
                break
            self.submit(data, addr)
        if self._pty is not None:
            for frame in self._pty.frames():
                self.submit(frame, self._pty, link="serial")
        for link, inbox in (("wifi", h.hal.inbox), ("serial", h.hal.serial_inbox)):
            self._sender[link] = None
            if self._pending[link]:  # the core reads at most one datagram per link and tick
                data, self._sender[link] = self._pending[link].popleft()
                inbox.append(data)
                if link == "serial":
                    self._watch_provisioning(data)
        tel = h.telemetry()
        if tel:  # a perfect drive: the rope runs at the latest setpoint
            h.encoder.speed_mps = tel[-1].rope_speed_setpoint_mmps / 1000.0
        before_out, before_accept = len(h.hal.out), h.hal.accept_peer_calls
        h.tick(TICK_US)
        if self._sender["wifi"] is not None and h.hal.accept_peer_calls > before_accept:
            self._peer["wifi"] = self._sender["wifi"]
        if self._sender["serial"] is not None:  # a cable has one far end
            self._peer["serial"] = self._sender["serial"]
        for out in h.hal.out[before_out:]:
            to = self._sender[out.link] if out.channel == "reply" else self._peer[out.link]
            if to is None and out.link == "serial":  # a later answer (PROVISION_COMMIT once written): the cable
                to = self._peer["serial"]
            self._emit(out.raw, to)

    def _watch_provisioning(self, data: bytes) -> None:
        """The harness checks the core's signed frames with the core's key: follow a key staged and committed over
        the serial link (the core answers NACK to a bad one, which changes nothing)."""
        d = _decoded(data)
        if d is None:
            return
        if isinstance(d[1], gen.ProvisionSetKey):
            self._staged_key = bytes(d[1].key)
        elif isinstance(d[1], gen.ProvisionCommit):
            if data == self._last_commit:  # a retransmission (the ACK comes once the flash is written): no new key
                return
            self._last_commit = bytes(data)
            self.harness.expect_commit(self._staged_key)
            if self._staged_key is not None and self.link == "wifi":
                self.key = self._staged_key
            self._staged_key = None

    # ------------------------------------------------------------------ records
    def host_sent(self, msg_id: int | None = None) -> list[gen.Frame]:
        """The frames the host sent (decodable ones), optionally of one message id, in order."""
        with self.lock:
            frames = []
            for data in self.host_frames:
                try:
                    frame = gen.decode_frame(data)
                except gen.FrameError:
                    continue
                if msg_id is None or frame.msg_id == msg_id:
                    frames.append(frame)
            return frames

    def executed_names(self) -> list[str]:
        """The commands the core executed, in order: each ACKed (msg_id, seq) once (a retransmission is
        answered from the duplicate cache with the same ACK, never executed again)."""
        seen: set[tuple[int, int]] = set()
        names = []
        for o in self.outputs():
            if isinstance(o.msg, gen.Ack) and (o.msg.cmd_msg_id, o.msg.cmd_seq) not in seen:
                seen.add((o.msg.cmd_msg_id, o.msg.cmd_seq))
                names.append(gen.MESSAGES[o.msg.cmd_msg_id].NAME)
        return names

    def outputs(self, link: str | None = None) -> list[Out]:
        """The core's outputs so far on a link (default: the device's; a copy)."""
        link = self.link if link is None else link
        with self.lock:
            return [o for o in self.harness.hal.out if o.link == link]

    def transitions(self) -> list[tuple[int, int, int, int]]:
        """(time_ms, from, to, cause) of every STATE_CHANGED the core sent."""
        with self.lock:
            return self.harness.transitions()

    def latest_telemetry(self) -> gen.Telemetry | None:
        with self.lock:
            tel = self.harness.telemetry()
            return tel[-1] if tel else None

    @property
    def time_s(self) -> float:
        """The device's simulated time."""
        return self.harness.t_us * 1e-6


class _PtyEnd:
    """The device's end of a pseudo-terminal: COBS frames, each ended by a zero byte (transport_serial.py)."""

    def __init__(self) -> None:
        self.master, self._slave = os.openpty()
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self._slave)
        self._buffer = b""

    def frames(self) -> list[bytes]:
        """The whole frames received since the last call (undecodable COBS chunks are dropped, as the HAL does)."""
        try:
            self._buffer += os.read(self.master, 4096)
        except (BlockingIOError, OSError):
            pass
        *chunks, self._buffer = self._buffer.split(DELIMITER)
        out = []
        for chunk in chunks:
            try:
                out.append(cobs.decode(chunk))
            except cobs.DecodeError:
                continue
        return out

    def deliver(self, data: bytes) -> None:
        try:
            os.write(self.master, encode_serial_frame(data))
        except OSError:
            pass  # nobody has the port open: the bytes are lost

    def close(self) -> None:
        os.close(self.master)
        os.close(self._slave)


# ---- the network between them: filters for CoreDevice.to_device / to_host ----------------------------------

def _as_list(out: bytes | list[bytes] | None) -> list[bytes]:
    return [] if out is None else (list(out) if isinstance(out, list) else [out])


def _decoded(data: bytes) -> tuple[gen.Frame, gen.Message] | None:
    try:
        return gen.decode_message(data)
    except (gen.FrameError, Exception):  # noqa: BLE001 - not ours to judge: passes unchanged
        return None


def lose_acks(msg_id: int, count: int) -> Filter:
    """Loses the next `count` ACKs of commands with msg_id on their way to the host."""
    left = [count]

    def f(data: bytes) -> bytes | None:
        d = _decoded(data)
        if d and isinstance(d[1], gen.Ack) and d[1].cmd_msg_id == msg_id and left[0] > 0:
            left[0] -= 1
            return None
        return data
    return f


def lose_messages(cls: type[gen.Message], count: int | None = None,
                  when: Callable[[gen.Message], bool] = lambda _m: True) -> Filter:
    """Loses messages of cls (for which when(msg) holds): the next `count` of them, or all (None)."""
    left = [count]

    def f(data: bytes) -> bytes | None:
        d = _decoded(data)
        if d and isinstance(d[1], cls) and when(d[1]) and (left[0] is None or left[0] > 0):
            if left[0] is not None:
                left[0] -= 1
            return None
        return data
    return f


def damage(msg_id: int, count: int) -> Filter:
    """Flips a bit in the checksum of the next `count` frames with msg_id (the core answers BAD_CHECKSUM)."""
    left = [count]

    def f(data: bytes) -> bytes | None:
        if len(data) > gen.HEADER_LEN and data[3] == msg_id and left[0] > 0:
            left[0] -= 1
            frame = bytearray(data)
            frame[gen.HEADER_LEN + data[6]] ^= 0x01  # the checksum's first byte follows the payload
            return bytes(frame)
        return data
    return f
