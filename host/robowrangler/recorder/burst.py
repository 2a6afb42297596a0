"""Burst captures: BURST_DATA frames -> /device/burst records -> whole bursts with their gaps.

A burst (BURST_START) is sampled by the device every control tick and streamed afterwards as BURST_DATA
frames of up to 6 samples, each naming its burst_id and first_sample. This module converts a frame into its
/device/burst record (the schema protocol/recording/schemas/device_burst.schema.json) and puts the records
of a recording back together: one Burst per burst_id, every sample index in place, the indices no frame
carried reported in `missing` (lost on the link, never filled in) and NaN in the arrays there.

    for burst in bursts(read_recording("run.mcap")):
        print(burst.burst_id, burst.sample_count, burst.missing)
        t_s, pulse_us = burst.time_s, burst.esc_pulse_fine_us
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robowrangler.protocol import generated as gen
from robowrangler.recorder.encoder_period import mt_period_us
from robowrangler.recorder.schemas_generated import BURST_FIELDS, BURST_SAMPLE_FIELDS

_LOW16 = 1 << 16


def burst_record(msg: gen.BurstData, *, seq: int) -> dict[str, Any]:
    """A /device/burst record from a decoded BURST_DATA and its frame seq (the samples the frame carries)."""
    record: dict[str, Any] = {}
    for entry in BURST_FIELDS:
        raw = getattr(msg, entry["wire"])
        record[entry["name"]] = raw / entry["divisor"] if entry["kind"] == "scaled" else raw
    n = max(0, min(gen.BURST_SAMPLES_PER_FRAME, msg.sample_count - msg.first_sample))
    samples = gen.unpack_burst_samples(msg.samples, n)
    for entry in BURST_SAMPLE_FIELDS:
        raw = [s[entry["wire"]] for s in samples]
        record[entry["name"]] = [r / entry["divisor"] for r in raw] if entry["kind"] == "scaled" else raw
    record["seq"] = seq
    return record


@dataclass
class Burst:
    """One burst put back together. Arrays have sample_count values, NaN at the indices no frame carried.

    burst_id, start_time_s (device time of sample 0), tick_s (time between samples), sample_count;
    encoder_counts (unwrapped from sample 0's low 16 bits: edges since the first sample received),
    encoder_edge_s (time of the latest edge relative to sample 0's tick), esc_pulse_fine_us, battery_v;
    missing: list of (first, last) index runs no frame carried (inclusive); frames: BURST_DATA frames read.
    """

    burst_id: int
    start_time_s: float
    tick_s: float
    sample_count: int
    encoder_counts: np.ndarray
    encoder_edge_s: np.ndarray
    esc_pulse_fine_us: np.ndarray
    battery_v: np.ndarray
    missing: list[tuple[int, int]] = field(default_factory=list)
    frames: int = 0

    @property
    def complete(self) -> bool:
        return not self.missing

    @property
    def missing_samples(self) -> int:
        return sum(b - a + 1 for a, b in self.missing)

    @property
    def time_s(self) -> np.ndarray:
        """Device time of each sample [s]."""
        return self.start_time_s + np.arange(self.sample_count) * self.tick_s

    def edge_period_us(self) -> np.ndarray:
        """Raw M/T encoder period per sample [us]: NaN where no new edge came since the previous edge sample."""
        edge_us = np.round(self.encoder_edge_s * 1e6)
        return mt_period_us(self.encoder_counts, edge_us, modulus=1 << 62)


def _runs(present: np.ndarray) -> list[tuple[int, int]]:
    runs, start = [], None
    for i, ok in enumerate(present):
        if not ok and start is None:
            start = i
        elif ok and start is not None:
            runs.append((start, i - 1))
            start = None
    if start is not None:
        runs.append((start, len(present) - 1))
    return runs


def assemble(records: list[dict[str, Any]]) -> list[Burst]:
    """Group /device/burst records by burst (a burst_id, in order of arrival; a burst_id seen again after
    another burst is a new burst) and put each together."""
    groups: list[list[dict[str, Any]]] = []
    for r in records:
        if groups and groups[-1][0]["burst_id"] == r["burst_id"] and groups[-1][0]["sample_count"] == r["sample_count"]:
            groups[-1].append(r)
        else:
            groups.append([r])
    return [_one(g) for g in groups]


def _one(frames: list[dict[str, Any]]) -> Burst:
    head = frames[0]
    n = int(head["sample_count"])
    tick_us = int(head["tick_us"])
    counts_lo = np.full(n, -1, dtype=np.int64)
    edge_lo = np.full(n, -1, dtype=np.int64)
    pulse = np.full(n, np.nan)
    battery = np.full(n, np.nan)
    for f in frames:
        first = int(f["first_sample"])
        for k in range(len(f["encoder_counts"])):
            i = first + k
            if 0 <= i < n:
                counts_lo[i] = f["encoder_counts"][k]
                edge_lo[i] = f["encoder_edge_us"][k]
                pulse[i] = f["esc_pulse_fine_us"][k]
                battery[i] = f["battery_v"][k]
    present = counts_lo >= 0
    counts = np.full(n, np.nan)
    edge_s = np.full(n, np.nan)
    prev: int | None = None
    total = 0
    for i in np.flatnonzero(present):
        if prev is not None:
            total += int(counts_lo[i] - prev) % _LOW16
        prev = int(counts_lo[i])
        counts[i] = total
        tick_rel_us = i * tick_us
        tick_lo = (int(head["start_time_us"]) + tick_rel_us) % _LOW16
        edge_s[i] = (tick_rel_us - (tick_lo - edge_lo[i]) % _LOW16) * 1e-6
    return Burst(burst_id=int(head["burst_id"]), start_time_s=float(head["start_time_s"]), tick_s=tick_us * 1e-6,
                 sample_count=n, encoder_counts=counts, encoder_edge_s=edge_s, esc_pulse_fine_us=pulse,
                 battery_v=battery, missing=_runs(present), frames=len(frames))


def bursts(recording: Any) -> list[Burst]:
    """The bursts of a loaded recording (robowrangler.recorder.read_recording), in order of arrival."""
    return assemble([r.data for r in recording.records.get("/device/burst", [])])
