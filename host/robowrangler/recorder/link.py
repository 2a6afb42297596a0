"""Record a live link: every frame the client receives or sends goes through a RecordingTransport.

    recorder = LinkRecorder(writer)
    with Client(url, transport=RecordingTransport(open_transport(url), recorder)) as rw:
        rw.arm(); rw.spin(4.0); ...
    recorder.finish()          # NO_REPLY for unanswered commands, the open gap if the link is silent

Why a transport wrapper: the Client's public API gives TelemetrySamples without the frame sequence
number (needed for gap detection) and does not report the commands it sends. Wrapping the transport
sees the exact bytes in both directions through the Client's public `transport=` argument, decodes
them with the generated codec, and writes:
    TELEMETRY -> /device/telemetry, EVENT -> /device/event, BURST_DATA -> /device/burst, a jump in the device's frame seq -> /link/gap,
    command frames (not heartbeats) -> /host/command once the ACK/NACK arrives (or NO_REPLY).
Frames that do not decode are counted (decode_errors), never raised into the client's threads.

A gap is written once it is known to be a loss: the device sends an ACK in the tick that received the
command but queues the events that command raised (numbered first), so a STATE_CHANGED arrives right after
the ACK with a lower seq. Such a hole is held until REORDER_WINDOW newer frames have arrived (or the
recording ends); late frames fill it, and only what is still missing is written (log_time: when it was
detected). The gap detector's own counters still count every hole as it opens (live progress).
A LinkRecorder outlives transports: reconnecting with a new transport keeps its gap state.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field, replace

from robowrangler.protocol import generated as gen
from robowrangler.recorder.burst import burst_record
from robowrangler.recorder.gaps import REORDER_WINDOW, SEQ_MODULUS, SeqGap, SeqGapDetector
from robowrangler.recorder.records import command_record, event_record, telemetry_record
from robowrangler.recorder.writer import RecordingWriter
from robowrangler.transport import Transport

NO_REPLY_AFTER_S = 10.0  # a command unanswered this long is recorded as NO_REPLY
SILENCE_S = 0.5  # no TELEMETRY for this long when the recording ends: the open gap is recorded


@dataclass
class _Pending:
    message: gen.Message
    seq: int
    first_sent_ns: int
    first_sent_s: float
    transmissions: int = 1


@dataclass
class _HeldGap:
    gap: SeqGap
    log_ns: int
    missing: set[int] = field(default_factory=set)


class LinkRecorder:
    """Turns frames seen on a link into recording records (thread-safe).

    Attributes: telemetry_count, event_count, burst_frame_count, command_count, decode_errors, gap_detector (SeqGapDetector),
    last_telemetry_host_s (time.monotonic() of the latest TELEMETRY, None before), latest_state (name),
    gaps_written / frames_missing (the /link/gap records written and the frames they count: holes that late
    frames filled are not among them), reordered_filled (frames that arrived late into a held hole).
    """

    def __init__(self, writer: RecordingWriter, *, no_reply_after_s: float = NO_REPLY_AFTER_S,
                 silence_s: float = SILENCE_S) -> None:
        self.writer = writer
        self.no_reply_after_s = no_reply_after_s
        self.silence_s = silence_s
        self.gap_detector = SeqGapDetector()
        self.telemetry_count = 0
        self.event_count = 0
        self.burst_frame_count = 0
        self.command_count = 0
        self.heartbeats_sent = 0
        self.decode_errors = 0
        self.last_telemetry_host_s: float | None = None
        self.latest_state: str | None = None
        self.gaps_written = 0
        self.frames_missing = 0
        self.reordered_filled = 0
        self._pending: dict[tuple[int, int], _Pending] = {}
        self._held: list[_HeldGap] = []
        self._lock = threading.Lock()

    # ---------------------------------------------------------------------------------------------
    def on_received(self, frame: bytes, host_s: float | None = None) -> None:
        """A frame as received from the device (undecoded)."""
        host_s = time.monotonic() if host_s is None else host_s
        log_ns = self.writer.now_ns()
        try:
            header, msg = gen.decode_message(frame)
        except Exception:  # noqa: BLE001 - bad data is counted, as the client does
            with self._lock:
                self.decode_errors += 1
            return
        with self._lock:
            # the device numbers every frame it sends (TELEMETRY, EVENT, ACK, NACK, PARAM_VALUE) from one
            # counter, so gaps are looked for over all of them
            time_s = msg.time_ms / 1000 if isinstance(msg, (gen.Telemetry, gen.Event)) else None
            gap = self.gap_detector.feed(header.seq, host_s=host_s, time_s=time_s)
            self._fill_held(header.seq)
            if gap is not None:
                if gap.missing is not None and gap.missing <= REORDER_WINDOW:
                    seqs = {(gap.from_seq + i) % SEQ_MODULUS for i in range(gap.missing)}
                    self._held.append(_HeldGap(gap, log_ns, seqs))
                else:  # a restart or a long loss: late frames cannot fill it
                    self._release_held(everything=True)
                    self._write_gap(gap, log_ns)
            self._release_held(everything=False)
            if isinstance(msg, gen.Telemetry):
                record = telemetry_record(msg, seq=header.seq)
                self.writer.write("/device/telemetry", record, log_time_ns=log_ns)
                self.telemetry_count += 1
                self.last_telemetry_host_s = host_s
                self.latest_state = record["state"]
            elif isinstance(msg, gen.Event):
                self.writer.write("/device/event", event_record(msg, seq=header.seq), log_time_ns=log_ns)
                self.event_count += 1
            elif isinstance(msg, gen.BurstData):
                self.writer.write("/device/burst", burst_record(msg, seq=header.seq), log_time_ns=log_ns)
                self.burst_frame_count += 1
            elif isinstance(msg, (gen.Ack, gen.Nack)):
                pending = self._pending.pop((msg.cmd_msg_id, msg.cmd_seq), None)
                if pending is not None:  # else: a reply to a retransmission already answered, or not ours
                    self._write_command(pending, msg, log_ns, host_s)
            self._expire(host_s)

    def on_sent(self, frame: bytes, host_s: float | None = None) -> None:
        """A frame the host is about to send."""
        host_s = time.monotonic() if host_s is None else host_s
        try:
            header, msg = gen.decode_message(frame)
        except Exception:  # noqa: BLE001
            with self._lock:
                self.decode_errors += 1
            return
        with self._lock:
            if msg.KIND != gen.MsgKind.COMMAND:
                if msg.KIND == gen.MsgKind.HEARTBEAT:
                    self.heartbeats_sent += 1
                return
            key = (msg.MSG_ID, header.seq)
            if key in self._pending:
                self._pending[key].transmissions += 1
            else:
                self._pending[key] = _Pending(msg, header.seq, self.writer.now_ns(), host_s)

    def idle(self, host_s: float | None = None) -> None:
        """Housekeeping while nothing arrives: commands unanswered for no_reply_after_s become NO_REPLY."""
        with self._lock:
            self._expire(time.monotonic() if host_s is None else host_s)

    def finish(self, host_s: float | None = None) -> None:
        """End of recording: every pending command is NO_REPLY; a silent link leaves an open gap."""
        host_s = time.monotonic() if host_s is None else host_s
        with self._lock:
            for pending in list(self._pending.values()):
                self._write_command(pending, None, self.writer.now_ns(), host_s)
            self._pending.clear()
            self._release_held(everything=True)
            last = self.last_telemetry_host_s
            if last is not None and host_s - last > self.silence_s:
                gap = self.gap_detector.open_gap(host_s=host_s)
                if gap is not None:
                    self._write_gap(gap, self.writer.now_ns())

    # ---------------------------------------------------------------------------------------------
    def _write_gap(self, gap: SeqGap, log_ns: int) -> None:
        self.writer.write("/link/gap", gap.to_record(), log_time_ns=log_ns)
        self.gaps_written += 1
        self.frames_missing += gap.missing or 0

    def _fill_held(self, seq: int) -> None:
        for held in self._held:
            if seq in held.missing:
                held.missing.discard(seq)
                self.reordered_filled += 1
                return

    def _release_held(self, *, everything: bool) -> None:
        """Write held gaps that late frames can no longer fill (all of them with everything=True), in order;
        a hole partly filled is written as the runs still missing."""
        last = self.gap_detector.last_seq
        while self._held:
            held = self._held[0]
            gap = held.gap
            if not everything and last is not None and (last - gap.to_seq) % SEQ_MODULUS <= REORDER_WINDOW:
                return
            self._held.pop(0)
            run_start = None
            for i in range(gap.missing + 1):
                seq = (gap.from_seq + i) % SEQ_MODULUS
                if i < gap.missing and seq in held.missing:
                    if run_start is None:
                        run_start = i
                elif run_start is not None:
                    self._write_gap(replace(gap, from_seq=(gap.from_seq + run_start) % SEQ_MODULUS,
                                            to_seq=(gap.from_seq + i - 1) % SEQ_MODULUS, missing=i - run_start),
                                    held.log_ns)
                    run_start = None

    def _write_command(self, pending: _Pending, reply: gen.Message | None, log_ns: int, host_s: float) -> None:
        latency_s = max(0.0, host_s - pending.first_sent_s) if reply is not None else None
        record = command_record(pending.message, seq=pending.seq, transmissions=pending.transmissions,
                                reply=reply, reply_latency_s=latency_s)
        self.writer.write("/host/command", record, log_time_ns=pending.first_sent_ns,
                          publish_time_ns=log_ns if reply is not None else pending.first_sent_ns)
        self.command_count += 1

    def _expire(self, host_s: float) -> None:
        for key, pending in list(self._pending.items()):
            if host_s - pending.first_sent_s > self.no_reply_after_s:
                del self._pending[key]
                self._write_command(pending, None, self.writer.now_ns(), host_s)


class RecordingTransport(Transport):
    """A Transport that hands every frame it carries to a LinkRecorder, then to/from `inner`."""

    def __init__(self, inner: Transport, recorder: LinkRecorder) -> None:
        self.inner = inner
        self.recorder = recorder
        self.url = inner.url

    @property
    def framing_errors(self) -> int:  # type: ignore[override]
        return self.inner.framing_errors

    def send(self, frame: bytes) -> None:
        self.recorder.on_sent(frame)
        self.inner.send(frame)

    def recv(self, timeout_s: float) -> bytes | None:
        data = self.inner.recv(timeout_s)
        if data is None:
            self.recorder.idle()
        else:
            self.recorder.on_received(data)
        return data

    def close(self) -> None:
        self.inner.close()
