"""What crossed an ImpairmentProxy, decoded: the device-side truth the network tests check against.

The proxy logs every datagram it received ('in', before impairment) and delivered ('out'). So the ledger
knows every command frame the firmware really got (with repeats: retransmissions and network
duplicates) and every frame the firmware sent (the device's own sequence numbers, gap-free unless the
device itself lost one), whatever the impaired link then did to them.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil.impairment import LoggedDatagram

COMMAND_IDS = frozenset(msg_id for msg_id, m in gen.MESSAGES.items() if m.KIND == gen.MsgKind.COMMAND)


@dataclass
class LinkLedger:
    """Counts and decoded frames from proxy logs; feed() it take_log() output as it comes."""

    command_deliveries: Counter = field(default_factory=Counter)  # (msg_id, seq, checksum) -> times delivered
    executed_commands: list[tuple[int, gen.Message]] = field(default_factory=list)  # first deliveries, in order
    corrupted_to_device: int = 0
    corrupted_to_host: int = 0
    undecodable_clean_to_device: int = 0
    device_frames: list[tuple[int, int, gen.Message]] = field(default_factory=list)  # (time_us, seq, msg) sent
    device_seqs_sent: set[int] = field(default_factory=set)  # unwrapped sequence numbers of device frames
    _last_device_seq: int | None = None

    def feed(self, entries: list[LoggedDatagram]) -> None:
        for e in entries:
            if e.direction == "to_device" and e.kind == "out":
                self._to_device(e)
            elif e.direction == "to_host" and e.kind == "in":
                self._from_device(e)
            elif e.direction == "to_host" and e.kind == "out" and e.corrupted:
                self.corrupted_to_host += 1

    def _to_device(self, e: LoggedDatagram) -> None:
        try:
            frame, msg = gen.decode_message(e.data)
        except gen.FrameError:
            if e.corrupted:
                self.corrupted_to_device += 1
            else:
                self.undecodable_clean_to_device += 1  # the host sent garbage on purpose
            return
        assert not e.corrupted, f"a corrupted frame decoded as {msg}: the checksum missed a bit flip"
        if frame.msg_id not in COMMAND_IDS:
            return
        key = (frame.msg_id, frame.seq, int.from_bytes(e.data[-2:], "little"))
        if self.command_deliveries[key] == 0:
            self.executed_commands.append((e.time_us, msg))
        self.command_deliveries[key] += 1

    def _from_device(self, e: LoggedDatagram) -> None:
        frame, msg = gen.decode_message(e.data)  # the firmware never sends a bad frame
        seq = frame.seq if self._last_device_seq is None else \
            self._last_device_seq + ((frame.seq - self._last_device_seq + 0x8000) & 0xFFFF) - 0x8000
        self._last_device_seq = seq
        self.device_seqs_sent.add(seq)
        self.device_frames.append((e.time_us, seq, msg))

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
        """Command frames the firmware got again (same msg_id, seq and checksum): must not execute."""
        return sum(n - 1 for n in self.command_deliveries.values())

    @property
    def command_frames_delivered(self) -> int:
        return sum(self.command_deliveries.values())

    def device_messages(self, kind: type) -> list[gen.Message]:
        return [m for _, _, m in self.device_frames if isinstance(m, kind)]

    def device_events(self, kind: gen.EventKind) -> list[gen.Event]:
        return [m for m in self.device_messages(gen.Event) if m.event == kind]

    @property
    def last_device_telemetry(self) -> gen.Telemetry:
        return self.device_messages(gen.Telemetry)[-1]
