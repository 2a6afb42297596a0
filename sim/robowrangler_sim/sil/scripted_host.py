"""A deterministic host for scenarios and tests: commands at simulated times over the real UDP link.

The host sends its frames to the SIL firmware's command port and announces how many it has sent in
each SIL_SENSORS (host_frames_sent), so the firmware processes each frame at a known tick whatever
the machine's speed. Everything the firmware sends back is decoded and kept, in order.

It signs as a real host does, through the same LinkSession as the client (robowrangler.link_session): HELLO
for the session, then every frame signed with the session's key (sil.key unless another is given) and a
growing counter; device frames whose signature or freshness fails are dropped and counted in
received.auth_failed / received.replayed. The counter is a plain count from 1 (not the wall clock), so runs
stay reproducible.

Scenarios run on it (production paths): a missing answer raises LinkTimeout, a refused command
CommandRefused (robowrangler.errors), never an AssertionError.
"""

from __future__ import annotations

import socket
from dataclasses import dataclass, field

from robowrangler.errors import CommandRefused, LinkTimeout
from robowrangler.link_session import LinkSession, Verdict
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
    session_infos: list[gen.SessionInfo] = field(default_factory=list)
    raw: list[bytes] = field(default_factory=list)
    decode_errors: int = 0
    auth_failed: int = 0
    replayed: int = 0


class ScriptedHost:
    """Drives a SilSession tick by tick. Heartbeats at heartbeat_period_s unless paused."""

    def __init__(self, sil: SilSession, *, heartbeat_period_s: float = 0.1, key: bytes | None = None,
                 handshake: bool = True) -> None:
        self.sil = sil
        self.link = LinkSession(sil.key if key is None else key)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.setblocking(False)
        self._dest = ("127.0.0.1", sil.cmd_port)
        self.frames_sent = 0
        self.last_sent_us = 0
        self.seq = 0
        self.heartbeat_period_s = heartbeat_period_s
        self.heartbeats_enabled = True
        self._next_heartbeat_us = 0
        self.received = Received()
        if handshake:
            self.hello()

    @property
    def key(self) -> bytes:
        return self.link.key

    @property
    def session_id(self) -> int:
        """The session this host signs for (0 before a SESSION_INFO answered a HELLO: the device drops such frames)."""
        session = self.link.session_id
        return 0 if session is None else session

    @property
    def counter(self) -> int:
        """The counter of the last frame this host signed."""
        return self.link.counter

    @property
    def url(self) -> str:
        return self.sil.cmd_url

    def hello(self, *, timeout_s: float = 0.05) -> gen.SessionInfo:
        """HELLO -> SESSION_INFO: learn the device's session (LinkTimeout if no answer within timeout_s simulated)."""
        nonce = 0x5EED0000 + len(self.received.session_infos)
        self.send(self.link.hello(nonce))
        heartbeats, self.heartbeats_enabled = self.heartbeats_enabled, False  # nothing signed before the session
        try:
            self.run_until(lambda h: any(i.host_nonce == nonce for i in h.received.session_infos), timeout_s=timeout_s)
        finally:
            self.heartbeats_enabled = heartbeats
        info = next((i for i in self.received.session_infos if i.host_nonce == nonce), None)
        if info is None:
            raise LinkTimeout(f"no SESSION_INFO from {self.url} answered the HELLO (nonce 0x{nonce:08X}) within "
                              f"{timeout_s:g} s of simulated time: is the SIL firmware running?",
                              url=self.url, waited_s=timeout_s)
        return info

    # ---------------------------------------------------------------------------------------------
    def send_raw(self, data: bytes) -> None:
        """Send bytes as one datagram (malformed frames too); counted for the lockstep barrier."""
        self._sock.sendto(data, self._dest)
        self.frames_sent += 1
        self.last_sent_us = self.sil.plant.time_us  # the firmware takes it in the next tick

    def frame(self, message: gen.Message, seq: int, *, signed: bool = True) -> bytes:
        """The bytes of message with seq: signed for the session with the next counter (HELLO unsigned)."""
        if not signed or message.KIND == gen.MsgKind.HELLO:
            return gen.encode_frame(message, seq)
        if self.link.session_id is None:  # no session learnt (handshake=False): session 0, which the device drops
            return gen.encode_frame(message, seq, key=self.key, session_id=0, counter=self.link.next_counter())
        return self.link.sign(message, seq)

    def send(self, message: gen.Message, *, seq: int | None = None, signed: bool = True) -> int:
        """Frame (signed) and send a message; returns the seq used."""
        if seq is None:
            seq = self.seq
            self.seq = (self.seq + 1) & 0xFFFF
        self.send_raw(self.frame(message, seq, signed=signed))
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
                frame, msg = gen.decode_message(data)
            except gen.FrameError:
                r.decode_errors += 1
                continue
            verdict = self.link.check(frame, msg)
            if verdict == Verdict.BAD_TAG:
                r.auth_failed += 1
                # the one unsigned frame worth reading: an unprovisioned device's SESSION_INFO saying so
                if not (not frame.signed and isinstance(msg, gen.SessionInfo) and msg.key_set == 0):
                    continue
            elif verdict == Verdict.STALE:
                r.replayed += 1
                continue
            if isinstance(msg, gen.SessionInfo):
                r.session_infos.append(msg)
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
        """Send a command and tick until its verdict arrives (LinkTimeout if none within timeout_s simulated)."""
        seq = self.send(message)
        self.run_until(lambda h: h.verdict_for(seq) is not None, timeout_s=timeout_s)
        verdict = self.verdict_for(seq)
        if verdict is None:
            raise LinkTimeout(f"{message.NAME} (seq {seq}): no ACK/NACK from {self.url} within {timeout_s:g} s of "
                              "simulated time", url=self.url, waited_s=timeout_s)
        return verdict

    def command_accepted(self, message: gen.Message, *, timeout_s: float = 0.05) -> gen.Ack:
        """command(), and CommandRefused (reason, state, detail) if the device NACKs it."""
        verdict = self.command(message, timeout_s=timeout_s)
        if isinstance(verdict, gen.Nack):
            raise CommandRefused(command_msg_id=message.MSG_ID, reason=verdict.reason, state=verdict.state,
                                 detail=verdict.detail)
        return verdict

    def arm_and_spin(self, rope_speed_mmps: int, *, settle_s: float = 1.5) -> None:
        """ARM, SET_ROPE_SPEED, then run settle_s; CommandRefused if either command is refused."""
        for message in (gen.Arm(), gen.SetRopeSpeed(rope_speed_mmps)):
            self.command_accepted(message)
        self.run_for(settle_s)

    def telemetry_series(self, field_name: str, *, since_ms: int = 0) -> tuple[list[float], list[int]]:
        """(times in s, values) of one TELEMETRY field from since_ms on."""
        rows = [t for t in self.received.telemetry if t.time_ms >= since_ms]
        return [t.time_ms / 1000.0 for t in rows], [getattr(t, field_name) for t in rows]

    def close(self) -> None:
        self._sock.close()
