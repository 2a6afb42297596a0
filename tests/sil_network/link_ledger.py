"""What crossed an ImpairmentProxy, decoded: the device-side truth the network tests check against.

The proxy logs every datagram it received ('in', before impairment) and delivered ('out'). So the ledger
knows every frame the firmware really got and, through the device's gate (link_gate: the protocol's rule
for the signed link), what the firmware must have done with it: act on it (authentic, with a fresh
counter), or drop it unanswered (unsigned or a wrong tag: rx_auth_failed; another session or a stale
counter, which is what a network duplicate or an overtaken frame is: rx_replayed). Among the accepted
command frames, repeats (same msg_id, seq and checksum) are host retransmissions, signed afresh: the
firmware must answer them from its duplicate cache (rx_duplicates) and not act again. The ledger also
knows every frame the firmware sent (the device's own sequence numbers, gap-free unless the device
itself lost one), whatever the impaired link then did to them.
"""

from __future__ import annotations

from collections import Counter

from link_gate import DeviceGate, Fate

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil.impairment import LoggedDatagram

COMMAND_IDS = frozenset(msg_id for msg_id, m in gen.MESSAGES.items() if m.KIND == gen.MsgKind.COMMAND)


class LinkLedger:
    """Counts and decoded frames from proxy logs; feed() it take_log() output as it comes.

    key: the device's link key (16 bytes): the ledger checks tags with it, as the device and the host do.
    """

    def __init__(self, *, key: bytes) -> None:
        self.gate = DeviceGate(key=key)
        self.command_deliveries: Counter = Counter()  # (msg_id, seq, checksum) -> times accepted by the device
        self.executed_commands: list[tuple[int, gen.Message]] = []  # first acceptances, in order
        self.auth_failed_deliveries = 0  # frames the device must drop for a missing or wrong tag
        self.replayed_deliveries = 0  # frames the device must drop as replays (session or counter)
        self.replayed_commands: list[gen.Message] = []  # command frames among them
        self.corrupted_to_device = 0  # corrupted copies the decoder refuses (NACKed)
        self.corrupted_unauthentic_to_device = 0  # corrupted copies the CRC passes and the tag refuses
        self.undecodable_clean_to_device = 0  # the host sent garbage on purpose
        self.corrupted_to_host = 0
        self.corrupted_unauthentic_to_host = 0  # of which decodable (a flip in the signature block)
        self.device_frames: list[tuple[int, int, gen.Message]] = []  # (time_us, seq, msg) sent
        self.device_seqs_sent: set[int] = set()  # unwrapped sequence numbers of device frames
        self._last_device_seq: int | None = None

    def feed(self, entries: list[LoggedDatagram]) -> None:
        for e in entries:
            if e.direction == "to_device" and e.kind == "out":
                self._to_device(e)
            elif e.direction == "to_host" and e.kind == "in":
                self._from_device(e)
            elif e.direction == "to_host" and e.kind == "out" and e.corrupted:
                self._corrupted_to_host(e)

    def _to_device(self, e: LoggedDatagram) -> None:
        d = self.gate.deliver(e.data)
        if d.fate in (Fate.EMPTY, Fate.MALFORMED):
            if e.corrupted:
                self.corrupted_to_device += 1
            else:
                self.undecodable_clean_to_device += 1
            return
        if e.corrupted:
            assert d.fate is Fate.AUTH_FAILED, \
                f"a corrupted frame got through the gate as {d.fate.name} {d.message}: CRC and tag both missed a bit flip"
            self.corrupted_unauthentic_to_device += 1
        if d.fate is Fate.AUTH_FAILED:
            self.auth_failed_deliveries += 1
            return
        if d.fate is Fate.REPLAYED:
            self.replayed_deliveries += 1
            if d.frame.msg_id in COMMAND_IDS:
                self.replayed_commands.append(d.message)
            return
        if d.fate is not Fate.ACCEPTED or d.frame.msg_id not in COMMAND_IDS:
            return
        key = (d.frame.msg_id, d.frame.seq, d.frame.checksum)
        if self.command_deliveries[key] == 0:
            self.executed_commands.append((e.time_us, d.message))
        self.command_deliveries[key] += 1

    def _from_device(self, e: LoggedDatagram) -> None:
        frame, msg = gen.decode_message(e.data)  # the firmware never sends a bad frame
        assert gen.tag_valid(frame, self.gate.key), f"the firmware sent {msg} unsigned or wrongly signed over WiFi"
        self.gate.learn_session(frame)
        seq = frame.seq if self._last_device_seq is None else \
            self._last_device_seq + ((frame.seq - self._last_device_seq + 0x8000) & 0xFFFF) - 0x8000
        self._last_device_seq = seq
        # One seq counter serves both of the device's links: until the WiFi host's first authentic frame makes
        # it the peer, telemetry still goes to the USB serial that provisioned the SIL. SESSION_INFO (the
        # answer to an unauthenticated HELLO) is therefore not a point from which to count holes.
        if not isinstance(msg, gen.SessionInfo):
            self.device_seqs_sent.add(seq)
        self.device_frames.append((e.time_us, seq, msg))

    def _corrupted_to_host(self, e: LoggedDatagram) -> None:
        self.corrupted_to_host += 1
        try:
            frame = gen.decode_frame(e.data)
        except gen.FrameError:
            return
        assert not gen.tag_valid(frame, self.gate.key), "a corrupted device frame still verifies: CRC and tag missed it"
        self.corrupted_unauthentic_to_host += 1

    @property
    def device_seqs_never_sent(self) -> int:
        """Sequence numbers the firmware used but never sent (its outbox dropped the frame): device-side loss.

        The firmware numbers a queued frame (telemetry, event) when it queues it and may send a reply (numbered
        later) first, so its frames leave slightly out of order: count holes in the range, not steps."""
        if not self.device_seqs_sent:
            return 0
        return max(self.device_seqs_sent) - min(self.device_seqs_sent) + 1 - len(self.device_seqs_sent)

    @property
    def duplicate_deliveries(self) -> int:
        """Accepted command frames the firmware got again (host retransmissions, re-signed): must not execute."""
        return sum(n - 1 for n in self.command_deliveries.values())

    @property
    def command_frames_delivered(self) -> int:
        """Command frames the firmware accepted (each answered: first verdict or its cached copy)."""
        return sum(self.command_deliveries.values())

    def device_messages(self, kind: type) -> list[gen.Message]:
        return [m for _, _, m in self.device_frames if isinstance(m, kind)]

    def device_events(self, kind: gen.EventKind) -> list[gen.Event]:
        return [m for m in self.device_messages(gen.Event) if m.event == kind]

    @property
    def last_device_telemetry(self) -> gen.Telemetry:
        return self.device_messages(gen.Telemetry)[-1]
