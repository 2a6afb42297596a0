"""A deterministic host for scenarios and tests: commands at simulated times over the real UDP link.

The host sends its frames to the SIL firmware's command port and announces how many it has sent in
each SIL_SENSORS (host_frames_sent), so the firmware processes each frame at a known tick whatever
the machine's speed. Everything the firmware sends back is decoded and kept, in order.
"""

from __future__ import annotations

import socket
from dataclasses import dataclass, field

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil.session import SilSession


@dataclass
class Received:
    """What the host got back, in arrival order, with the simulated time it was read."""

    telemetry: list[gen.Telemetry] = field(default_factory=list)
    events: list[gen.Event] = field(default_factory=list)
    acks: list[gen.Ack] = field(default_factory=list)
    nacks: list[gen.Nack] = field(default_factory=list)
    param_values: list[gen.ParamValue] = field(default_factory=list)
    raw: list[bytes] = field(default_factory=list)
    decode_errors: int = 0


class ScriptedHost:
    """Drives a SilSession tick by tick. Heartbeats at heartbeat_period_s unless paused."""

    def __init__(self, sil: SilSession, *, heartbeat_period_s: float = 0.1) -> None:
        self.sil = sil
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.setblocking(False)
        self._dest = ("127.0.0.1", sil.cmd_port)
        self.frames_sent = 0
        self.seq = 0
        self.heartbeat_period_s = heartbeat_period_s
        self.heartbeats_enabled = True
        self._next_heartbeat_us = 0
        self.received = Received()

    # ---------------------------------------------------------------------------------------------
    def send_raw(self, data: bytes) -> None:
        """Send bytes as one datagram (malformed frames too); counted for the lockstep barrier."""
        self._sock.sendto(data, self._dest)
        self.frames_sent += 1

    def send(self, message: gen.Message, *, seq: int | None = None) -> int:
        """Frame and send a message; returns the seq used."""
        if seq is None:
            seq = self.seq
            self.seq = (self.seq + 1) & 0xFFFF
        self.send_raw(gen.encode_frame(message, seq))
        return seq

    def tick(self) -> None:
        sil = self.sil
        if self.heartbeats_enabled and sil.plant.time_us >= self._next_heartbeat_us:
            self.send(gen.Heartbeat(sil.plant.time_us // 1000 & 0xFFFFFFFF))
            self._next_heartbeat_us = sil.plant.time_us + round(self.heartbeat_period_s * 1e6)
        sil.step(host_frames_sent=self.frames_sent)
        self._drain()

    def run_for(self, duration_s: float) -> None:
        end_us = self.sil.plant.time_us + round(duration_s * 1e6)
        while self.sil.plant.time_us < end_us:
            self.tick()

    def run_until(self, predicate, *, timeout_s: float) -> bool:
        """Tick until predicate(self) is true or timeout_s simulated seconds pass; returns whether it became true."""
        end_us = self.sil.plant.time_us + round(timeout_s * 1e6)
        while self.sil.plant.time_us < end_us:
            if predicate(self):
                return True
            self.tick()
        return bool(predicate(self))

    def _drain(self) -> None:
        r = self.received
        while True:
            try:
                data = self._sock.recv(2048)
            except BlockingIOError:
                return
            r.raw.append(data)
            try:
                _, msg = gen.decode_message(data)
            except gen.FrameError:
                r.decode_errors += 1
                continue
            if isinstance(msg, gen.Telemetry):
                r.telemetry.append(msg)
            elif isinstance(msg, gen.Event):
                r.events.append(msg)
            elif isinstance(msg, gen.Ack):
                r.acks.append(msg)
            elif isinstance(msg, gen.Nack):
                r.nacks.append(msg)
            elif isinstance(msg, gen.ParamValue):
                r.param_values.append(msg)

    # ---------------------------------------------------------------------------------------------
    @property
    def last_telemetry(self) -> gen.Telemetry | None:
        return self.received.telemetry[-1] if self.received.telemetry else None

    def verdict_for(self, seq: int) -> gen.Ack | gen.Nack | None:
        for reply in reversed(self.received.acks + self.received.nacks):
            if reply.cmd_seq == seq:
                return reply
        return None

    def command(self, message: gen.Message, *, timeout_s: float = 0.05) -> gen.Ack | gen.Nack:
        """Send a command and tick until its verdict arrives (AssertionError if none within timeout_s)."""
        seq = self.send(message)
        self.run_until(lambda h: h.verdict_for(seq) is not None, timeout_s=timeout_s)
        verdict = self.verdict_for(seq)
        assert verdict is not None, f"no ACK/NACK for {message.NAME} seq {seq} within {timeout_s} s"
        return verdict

    def arm_and_spin(self, rope_speed_mmps: int, *, settle_s: float = 1.5) -> None:
        """ARM, SET_ROPE_SPEED, then run settle_s; AssertionError if either command is refused."""
        for message in (gen.Arm(), gen.SetRopeSpeed(rope_speed_mmps)):
            verdict = self.command(message)
            assert isinstance(verdict, gen.Ack), f"{message.NAME} refused: {verdict}"
        self.run_for(settle_s)

    def telemetry_series(self, field_name: str, *, since_ms: int = 0) -> tuple[list[float], list[int]]:
        """(times in s, values) of one TELEMETRY field from since_ms on."""
        rows = [t for t in self.received.telemetry if t.time_ms >= since_ms]
        return [t.time_ms / 1000.0 for t in rows], [getattr(t, field_name) for t in rows]

    def close(self) -> None:
        self._sock.close()
