"""A lossy network between a host and the SIL firmware: a UDP proxy that impairs datagrams per direction.

    host ──UDP──► [host socket | ImpairmentProxy | device socket] ──UDP──► rw_sil command port
         ◄──────                                               ◄──────

The proxy binds its own port on 127.0.0.1 (``proxy.url``: point a Client or a ScriptedHost there),
forwards what it receives to the firmware's command port and the firmware's replies back to the host
that last wrote to it. Each direction has its own LinkImpairment: loss in bursts (a Gilbert-Elliott
chain with a good and a bad state, stepped once per datagram), duplication, reordering (a datagram held
back so later ones overtake it), a fixed delay plus uniform jitter, and corruption (one bit flipped).
Every random decision comes from a numpy Generator seeded from ``seed`` (one child stream per
direction), eleven uniform draws per datagram whatever the configuration, so runs are reproducible and
a higher loss probability drops a superset of the datagrams a lower one drops.

Two ways to drive it:

* Lockstep (deterministic): ``pump(now_us, expect_from_host=n)`` from the simulation loop reads what
  arrived, impairs it and releases every datagram due by ``now_us`` (simulated time). ImpairedLockstep
  wraps a SilSession so that a ScriptedHost talks through the proxy and the lockstep barrier counts the
  frames the proxy actually delivered: same seed, same scenario -> same bytes at the host.
* Wall clock (live clients): ``start()`` runs a thread on time.monotonic(); ``stop()`` ends it.

``counters`` say what was done per direction; with ``keep_log=True`` every datagram in and out is
recorded (``take_log()``) for invariant checks.
"""

from __future__ import annotations

import heapq
import itertools
import math
import select
import socket
import threading
import time
from dataclasses import asdict, dataclass, field
from typing import Literal

import numpy as np

Direction = Literal["to_device", "to_host"]
DIRECTIONS: tuple[Direction, Direction] = ("to_device", "to_host")
_DRAWS_PER_DATAGRAM = 11
_MAX_DATAGRAM = 2048
_MAX_DELAY_MS = 60_000.0
_RCVBUF_BYTES = 1 << 20  # bursts of datagrams (a host that sends many at once) must not overflow the kernel queue


@dataclass(frozen=True)
class LinkImpairment:
    """How one direction of the link misbehaves. Probabilities in [0, 1], times in milliseconds.

    Loss follows a two-state Gilbert-Elliott chain stepped once per datagram: in the good state a datagram
    is lost with loss_prob_good, in the bad state with loss_prob_bad; good->bad with good_to_bad_prob,
    bad->good with bad_to_good_prob (mean burst length 1 / bad_to_good_prob datagrams). Plain random loss
    is loss_prob_good alone (good_to_bad_prob = 0). A datagram that survives is sent twice with
    duplicate_prob; each copy has one bit flipped with corrupt_prob, waits delay_ms + U(0, jitter_ms), and
    with reorder_prob waits reorder_delay_ms more (later datagrams overtake it).
    """

    loss_prob_good: float = 0.0
    loss_prob_bad: float = 0.0
    good_to_bad_prob: float = 0.0
    bad_to_good_prob: float = 1.0
    duplicate_prob: float = 0.0
    corrupt_prob: float = 0.0
    reorder_prob: float = 0.0
    reorder_delay_ms: float = 5.0
    delay_ms: float = 0.0
    jitter_ms: float = 0.0

    def __post_init__(self) -> None:
        for name in ("loss_prob_good", "loss_prob_bad", "good_to_bad_prob", "bad_to_good_prob", "duplicate_prob",
                     "corrupt_prob", "reorder_prob"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
                raise ValueError(f"{name}: expected a probability in [0, 1], got {value!r}")
        for name in ("reorder_delay_ms", "delay_ms", "jitter_ms"):
            value = getattr(self, name)
            if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
                    or not 0.0 <= value <= _MAX_DELAY_MS):
                raise ValueError(f"{name}: expected a delay in [0, {_MAX_DELAY_MS:g}] ms, got {value!r}")
        if self.good_to_bad_prob > 0.0 and self.bad_to_good_prob == 0.0:
            raise ValueError("bad_to_good_prob: expected > 0 when good_to_bad_prob > 0 (else the link never "
                             f"leaves the bad state), got {self.bad_to_good_prob!r}")

    @property
    def bad_state_share(self) -> float:
        """Long-run fraction of datagrams that meet the bad state."""
        total = self.good_to_bad_prob + self.bad_to_good_prob
        return 0.0 if self.good_to_bad_prob == 0.0 else self.good_to_bad_prob / total

    @property
    def mean_loss_prob(self) -> float:
        """Long-run loss probability of the chain."""
        share = self.bad_state_share
        return (1.0 - share) * self.loss_prob_good + share * self.loss_prob_bad

    @classmethod
    def blackout(cls) -> LinkImpairment:
        """Every datagram lost."""
        return cls(loss_prob_good=1.0, loss_prob_bad=1.0)


@dataclass(frozen=True)
class ImpairmentConfig:
    """One LinkImpairment per direction: to_device (host -> firmware) and to_host (firmware -> host)."""

    to_device: LinkImpairment = field(default_factory=LinkImpairment)
    to_host: LinkImpairment = field(default_factory=LinkImpairment)

    def __post_init__(self) -> None:
        for name in DIRECTIONS:
            value = getattr(self, name)
            if not isinstance(value, LinkImpairment):
                raise ValueError(f"{name}: expected a LinkImpairment, got {type(value).__name__}")

    @classmethod
    def symmetric(cls, link: LinkImpairment) -> ImpairmentConfig:
        """The same impairment in both directions (independent random streams)."""
        return cls(to_device=link, to_host=link)


@dataclass
class DirectionCounters:
    """What the proxy did to one direction (datagram counts)."""

    received: int = 0
    dropped: int = 0
    dropped_in_bad_state: int = 0
    duplicated: int = 0
    corrupted: int = 0
    reordered: int = 0
    delivered: int = 0
    bad_state_entries: int = 0


@dataclass(frozen=True)
class LoggedDatagram:
    """One datagram seen by the proxy: kind 'in' (received, before impairment), 'drop' (lost), 'out' (delivered)."""

    direction: Direction
    kind: Literal["in", "drop", "out"]
    time_us: int
    data: bytes
    corrupted: bool = False
    original: bytes = b""  # for a corrupted copy: the datagram as it was before the bit flip


class _Lane:
    """One direction: its random stream, Gilbert-Elliott state, counters and the datagrams in flight."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng
        self.bad = False
        self.counters = DirectionCounters()
        self.in_flight: list[tuple[int, int, bytes, bool, bytes]] = []  # (release_us, order, data, corrupted, original)

    def admit(self, link: LinkImpairment, data: bytes, now_us: int, order: itertools.count) -> bool:
        """Decide the datagram's fate and queue its copies; False if it was dropped."""
        u = self.rng.random(_DRAWS_PER_DATAGRAM)
        c = self.counters
        c.received += 1
        if self.bad:
            if u[0] < link.bad_to_good_prob:
                self.bad = False
        elif u[0] < link.good_to_bad_prob:
            self.bad = True
            c.bad_state_entries += 1
        if u[1] < (link.loss_prob_bad if self.bad else link.loss_prob_good):
            c.dropped += 1
            c.dropped_in_bad_state += int(self.bad)
            return False
        copies = 2 if u[2] < link.duplicate_prob else 1
        c.duplicated += copies - 1
        for k in range(copies):
            corrupt_u, bit_u, jitter_u, reorder_u = u[3 + 4 * k: 7 + 4 * k]
            payload, corrupted = data, False
            if corrupt_u < link.corrupt_prob and data:
                bit = min(int(bit_u * len(data) * 8), len(data) * 8 - 1)
                buf = bytearray(data)
                buf[bit // 8] ^= 1 << (bit % 8)
                payload, corrupted = bytes(buf), True
                c.corrupted += 1
            delay_ms = link.delay_ms + jitter_u * link.jitter_ms
            if reorder_u < link.reorder_prob:
                delay_ms += link.reorder_delay_ms
                c.reordered += 1
            heapq.heappush(self.in_flight, (now_us + round(delay_ms * 1000.0), next(order), payload, corrupted, data))
        return True

    def due(self, now_us: int) -> list[tuple[bytes, bool, bytes]]:
        out = []
        while self.in_flight and self.in_flight[0][0] <= now_us:
            _, _, data, corrupted, original = heapq.heappop(self.in_flight)
            out.append((data, corrupted, original))
        return out


class ImpairmentProxy:
    """UDP proxy on 127.0.0.1 between a host and the firmware's command port, impairing both directions.

    Args:
        device_port: the firmware's command port on 127.0.0.1 (SilSession.cmd_port).
        config: the impairment per direction (replaceable later through ``config``).
        seed: seeds the numpy Generators (one child stream per direction).
        port: the port the proxy binds for the host (0 = a free one; see ``port`` / ``url``).
        keep_log: record every datagram in and out (``take_log()``).
    """

    def __init__(self, *, device_port: int, config: ImpairmentConfig | None = None, seed: int = 0, port: int = 0,
                 keep_log: bool = False) -> None:
        for name, value in (("device_port", device_port), ("port", port)):
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 65535:
                raise ValueError(f"{name}: expected a UDP port 0..65535, got {value!r}")
        if device_port == 0:
            raise ValueError("device_port: expected the firmware's bound command port, got 0")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed: expected an int >= 0, got {seed!r}")
        self._config = ImpairmentConfig() if config is None else config
        if not isinstance(self._config, ImpairmentConfig):
            raise ValueError(f"config: expected an ImpairmentConfig, got {type(config).__name__}")
        streams = np.random.SeedSequence(int(seed)).spawn(2)
        self._lanes = {d: _Lane(np.random.default_rng(s)) for d, s in zip(DIRECTIONS, streams)}
        self._order = itertools.count()
        self._lock = threading.RLock()
        self._host_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._host_sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, _RCVBUF_BYTES)
        self._host_sock.bind(("127.0.0.1", port))
        self._host_sock.setblocking(False)
        self._device_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._device_sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, _RCVBUF_BYTES)
        self._device_sock.bind(("127.0.0.1", 0))
        self._device_sock.connect(("127.0.0.1", device_port))
        self._device_sock.setblocking(False)
        self._host_addr: tuple[str, int] | None = None
        self.device_port = device_port
        self.keep_log = keep_log
        self._log: list[LoggedDatagram] = []
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._error: BaseException | None = None

    # ------------------------------------------------------------------------------------ properties
    @property
    def port(self) -> int:
        return self._host_sock.getsockname()[1]

    @property
    def address(self) -> tuple[str, int]:
        return ("127.0.0.1", self.port)

    @property
    def url(self) -> str:
        """Where a host talks to the firmware through this proxy."""
        return f"udp://127.0.0.1:{self.port}"

    @property
    def config(self) -> ImpairmentConfig:
        return self._config

    @config.setter
    def config(self, value: ImpairmentConfig) -> None:
        """Change the impairment from the next datagram on (datagrams in flight keep their fate)."""
        if not isinstance(value, ImpairmentConfig):
            raise ValueError(f"config: expected an ImpairmentConfig, got {type(value).__name__}")
        with self._lock:
            self._config = value

    @property
    def counters(self) -> dict[Direction, DirectionCounters]:
        """A snapshot of the counters per direction."""
        with self._lock:
            return {d: DirectionCounters(**asdict(lane.counters)) for d, lane in self._lanes.items()}

    def in_flight(self, direction: Direction) -> int:
        """Datagrams held (delayed) in one direction now."""
        with self._lock:
            return len(self._lanes[direction].in_flight)

    def take_log(self) -> list[LoggedDatagram]:
        """The datagrams logged since the last call (keep_log=True), oldest first; clears the log."""
        with self._lock:
            log, self._log = self._log, []
        return log

    # ------------------------------------------------------------------------------------ lockstep
    def pump(self, now_us: int, *, expect_from_host: int | None = None, timeout_s: float = 2.0) -> None:
        """Read what arrived on both sockets, impair it, send everything due by now_us (simulated time).

        expect_from_host: wait (up to timeout_s wall seconds) until this many datagrams in total have
        arrived from the host, so that the lockstep is exact; TimeoutError if they do not.
        """
        if self._thread is not None:
            raise RuntimeError("pump: the proxy runs its own wall-clock thread (stop() it first)")
        with self._lock:
            if expect_from_host is not None:
                deadline = time.monotonic() + timeout_s
                while self._lanes["to_device"].counters.received < expect_from_host:
                    if not self._read_host(now_us):
                        left_s = deadline - time.monotonic()
                        if left_s <= 0:
                            got = self._lanes["to_device"].counters.received
                            raise TimeoutError(f"expect_from_host: {expect_from_host} datagrams announced, "
                                               f"{got} arrived within {timeout_s} s")
                        select.select([self._host_sock], [], [], min(left_s, 0.05))
            self._read_host(now_us)
            self._read_device(now_us)
            self._release(now_us)

    @property
    def delivered_to_device(self) -> int:
        """Datagrams sent to the firmware so far (the count its lockstep barrier must wait for)."""
        return self._lanes["to_device"].counters.delivered

    # ------------------------------------------------------------------------------------ wall clock
    def start(self) -> ImpairmentProxy:
        """Run the proxy on the wall clock in a thread (for live clients) until stop()."""
        if self._thread is not None:
            raise RuntimeError("start: already running")
        self._stop.clear()
        origin_s = time.monotonic()

        def loop() -> None:
            try:
                while not self._stop.is_set():
                    now_us = round((time.monotonic() - origin_s) * 1e6)
                    with self._lock:
                        self._read_host(now_us)
                        self._read_device(now_us)
                        self._release(now_us)
                        wake_us = min((lane.in_flight[0][0] for lane in self._lanes.values() if lane.in_flight),
                                      default=now_us + 20_000)
                    wait_s = max(0.0, min(0.02, (wake_us - now_us) * 1e-6))
                    select.select([self._host_sock, self._device_sock], [], [], wait_s)
            except BaseException as exc:  # reported by check()
                self._error = exc

        self._thread = threading.Thread(target=loop, name="impairment-proxy", daemon=True)
        self._thread.start()
        return self

    def check(self) -> None:
        """Raise the wall-clock thread's error, if it stopped on one."""
        if self._error is not None:
            raise self._error

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None

    def close(self) -> None:
        self.stop()
        self._host_sock.close()
        self._device_sock.close()

    def __enter__(self) -> ImpairmentProxy:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------------------------ internals
    def _read_host(self, now_us: int) -> bool:
        """Admit every datagram waiting on the host socket; True if there was one."""
        got = False
        while True:
            try:
                data, addr = self._host_sock.recvfrom(_MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return got
            got = True
            self._host_addr = addr
            self._admit("to_device", data, now_us)

    def _read_device(self, now_us: int) -> None:
        while True:
            try:
                data = self._device_sock.recv(_MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except ConnectionRefusedError:  # the firmware is gone or not yet bound: what a network would lose
                continue
            self._admit("to_host", data, now_us)

    def _admit(self, direction: Direction, data: bytes, now_us: int) -> None:
        if self.keep_log:
            self._log.append(LoggedDatagram(direction, "in", now_us, data))
        kept = self._lanes[direction].admit(getattr(self._config, direction), data, now_us, self._order)
        if self.keep_log and not kept:
            self._log.append(LoggedDatagram(direction, "drop", now_us, data))

    def _release(self, now_us: int) -> None:
        for direction, lane in self._lanes.items():
            for data, corrupted, original in lane.due(now_us):
                try:
                    if direction == "to_device":
                        self._device_sock.send(data)
                    elif self._host_addr is not None:
                        self._host_sock.sendto(data, self._host_addr)
                    else:
                        continue
                except (ConnectionRefusedError, BlockingIOError):
                    continue
                lane.counters.delivered += 1
                if self.keep_log:
                    self._log.append(LoggedDatagram(direction, "out", now_us, data, corrupted,
                                                    original if corrupted else b""))


class ImpairedLockstep:
    """A SilSession as a ScriptedHost sees it, with an ImpairmentProxy in the link (deterministic).

    ``ScriptedHost(ImpairedLockstep(sil, proxy))`` sends to the proxy; each step pumps the proxy at the
    plant's time (waiting for every frame the host sent), steps the session with the lockstep barrier set
    to the frames the proxy delivered, then pumps again so replies released at once reach the host in
    the same tick. Everything else (plant, at(), set_rope_load(), ...) is the session's.
    """

    def __init__(self, sil, proxy: ImpairmentProxy) -> None:
        self.sil = sil
        self.proxy = proxy

    @property
    def cmd_port(self) -> int:
        return self.proxy.port

    @property
    def cmd_url(self) -> str:
        return self.proxy.url

    def step(self, *, host_frames_sent: int = 0) -> None:
        now_us = self.sil.plant.time_us
        self.proxy.pump(now_us, expect_from_host=host_frames_sent)
        self.sil.step(host_frames_sent=self.proxy.delivered_to_device)
        self.proxy.pump(now_us)

    def __getattr__(self, name: str):
        return getattr(self.sil, name)


__all__ = ["DirectionCounters", "ImpairedLockstep", "ImpairmentConfig", "ImpairmentProxy", "LinkImpairment",
           "LoggedDatagram"]
