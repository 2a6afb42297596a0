"""Sequence-gap detection on a stream of uint16 frame sequence numbers (wraps at 65536).

The device numbers every frame it sends from one counter (TELEMETRY, EVENT, ACK, NACK, PARAM_VALUE), so
feed the seq of every frame received from it, not only the telemetry.

Each received frame's seq is compared with the last one, modulo 65536:
    +1                 in order, nothing lost;
    0                  a duplicate: ignored;
    +2 .. +32768       a gap: (delta - 1) frames were lost, from last+1 to seq-1 (across the wrap too);
    -1 .. -REORDER_WINDOW   an older frame arriving late (UDP reordering): counted, the baseline stays;
    anything further back   the sender restarted its numbering (device reboot): counted as a restart, a
                        gap with unknown extent is reported, and the new seq becomes the baseline.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass
from typing import Any

SEQ_MODULUS = 0x10000
HALF_RANGE = 0x8000
REORDER_WINDOW = 64


@dataclass(frozen=True)
class SeqGap:
    """Frames missing between two received ones.

    from_seq: first missing seq; to_seq: last missing seq (inclusive; None if unknown: restart or
    still silent); missing: frame count (None with to_seq); last_time_s: device time of the last
    TELEMETRY/EVENT before the gap, resume_time_s: of the frame after it [s] (None if unknown, e.g. an
    ACK resumed it); silent_s: host time between the receptions either side [s].
    """

    from_seq: int
    to_seq: int | None
    missing: int | None
    last_time_s: float | None
    resume_time_s: float | None
    silent_s: float

    def to_record(self, *, stream: str = "device") -> dict[str, Any]:
        """The /link/gap record."""
        return {"stream": stream, **asdict(self)}


class SeqGapDetector:
    """Feed every received seq in arrival order; returns a SeqGap when one is detected.

    Counters: received, duplicates, reordered, restarts, gaps, missing (frames lost in closed gaps).
    """

    def __init__(self) -> None:
        self.last_seq: int | None = None
        self.last_time_s: float | None = None
        self.last_host_s: float | None = None
        self.received = 0
        self.duplicates = 0
        self.reordered = 0
        self.restarts = 0
        self.gaps = 0
        self.missing = 0

    def feed(self, seq: int, *, host_s: float, time_s: float | None = None) -> SeqGap | None:
        """One received frame: seq (0..65535), host reception time [s], device time [s] if known."""
        if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq < SEQ_MODULUS:
            raise ValueError(f"seq: expected an integer in [0, 65535], got {seq!r}")
        self.received += 1
        if self.last_seq is None:
            self._advance(seq, host_s, time_s)
            return None
        delta = (seq - self.last_seq) % SEQ_MODULUS
        if delta == 0:
            self.duplicates += 1
            return None
        if delta == 1:
            self._advance(seq, host_s, time_s)
            return None
        if delta <= HALF_RANGE:
            gap = SeqGap(from_seq=(self.last_seq + 1) % SEQ_MODULUS, to_seq=(seq - 1) % SEQ_MODULUS,
                         missing=delta - 1, last_time_s=self.last_time_s, resume_time_s=time_s,
                         silent_s=max(0.0, host_s - self.last_host_s))
            self.gaps += 1
            self.missing += delta - 1
            self._advance(seq, host_s, time_s)
            return gap
        if SEQ_MODULUS - delta <= REORDER_WINDOW:
            self.reordered += 1
            return None
        gap = SeqGap(from_seq=(self.last_seq + 1) % SEQ_MODULUS, to_seq=None, missing=None,
                     last_time_s=self.last_time_s, resume_time_s=time_s, silent_s=max(0.0, host_s - self.last_host_s))
        self.restarts += 1
        self.gaps += 1
        self._advance(seq, host_s, time_s)
        return gap

    def open_gap(self, *, host_s: float) -> SeqGap | None:
        """The gap still open at host_s (nothing received since the last frame): to_seq None.

        None if nothing was ever received. Used at the end of a recording whose link went silent.
        """
        if self.last_seq is None:
            return None
        return SeqGap(from_seq=(self.last_seq + 1) % SEQ_MODULUS, to_seq=None, missing=None,
                      last_time_s=self.last_time_s, resume_time_s=None, silent_s=max(0.0, host_s - self.last_host_s))

    def _advance(self, seq: int, host_s: float, time_s: float | None) -> None:
        self.last_seq = seq
        self.last_host_s = host_s
        if time_s is not None:  # frames without a device time (ACK, ...) keep the last known one
            self.last_time_s = time_s


def find_gaps(seqs: Iterable[int], *, host_s: Iterable[float] | None = None,
              time_s: Iterable[float | None] | None = None) -> list[SeqGap]:
    """Every gap in a sequence of received seqs (arrival order). host_s/time_s: per-frame times [s]."""
    seqs = list(seqs)
    hosts = list(host_s) if host_s is not None else [0.0] * len(seqs)
    times = list(time_s) if time_s is not None else [None] * len(seqs)
    if not len(hosts) == len(times) == len(seqs):
        raise ValueError(f"host_s/time_s: expected {len(seqs)} values each (one per seq), "
                         f"got {len(hosts)} and {len(times)}")
    detector = SeqGapDetector()
    gaps = []
    for seq, h, t in zip(seqs, hosts, times):
        gap = detector.feed(int(seq), host_s=float(h), time_s=t)
        if gap is not None:
            gaps.append(gap)
    return gaps
