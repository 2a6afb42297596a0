"""Incremental (magnetic, ABI) encoder on one motor shaft: edge count and interpolated last-edge time.

The shaft position in counts is x = x0 + theta * cpr / (2 pi); an edge lies at every integer x. The count
is floor(x) - floor(x0) (signed: it falls when the shaft turns backwards). Within one integration substep
the angle is taken as linear in time, so the time of the last edge crossed is interpolated between the
substep's ends and floored to the microsecond, as a hardware timer capture running at 1 MHz latches it.
x0 (the magnet's phase at reset) comes from the plant's seeded generator.
"""

from __future__ import annotations

import math


class Encoder:
    """Encoder state. Attributes: counts (int, cumulative signed edges), last_edge_us (int, plant clock)."""

    def __init__(self, *, counts_per_rev: int, phase_counts: float) -> None:
        """counts_per_rev: edges per revolution (> 0); phase_counts: initial position in [0, 1) counts."""
        self._cpr_per_rad = counts_per_rev / (2.0 * math.pi)
        self._x = phase_counts
        self._floor0 = math.floor(phase_counts)
        self._floor = self._floor0
        self.counts = 0
        self.last_edge_us = 0

    def advance(self, dtheta_rad: float, t_start_us: float, dt_us: float) -> None:
        """Move the shaft by dtheta_rad over [t_start_us, t_start_us + dt_us] (plant-clock microseconds)."""
        x0 = self._x
        x1 = x0 + dtheta_rad * self._cpr_per_rad
        self._x = x1
        f1 = math.floor(x1)
        if f1 == self._floor:
            return
        edge = f1 if f1 > self._floor else f1 + 1  # last integer crossed, going up or down
        self._floor = f1
        self.counts = f1 - self._floor0
        t_edge = t_start_us + dt_us * (edge - x0) / (x1 - x0)
        self.last_edge_us = math.floor(t_edge)
