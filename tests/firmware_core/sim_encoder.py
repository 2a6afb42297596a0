"""A simulated incremental encoder with a hardware edge-capture unit, for the M/T estimator tests.

The wheel speed profile (rev/s as a function of time) is integrated on a 1 us grid; an edge happens
each time the wheel angle crosses a multiple of 1/counts_per_rev rev. The capture unit reports, at
any tick time, the cumulative edge count and the microsecond timestamp of the most recent edge,
both as free-running uint32 values (so they wrap) with chosen offsets.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

U32 = 1 << 32


class SimEncoder:
    """Edges of one encoder channel for a speed profile.

    Args (keyword-only):
        rev_per_s: wheel speed in rev/s as a vectorised function of time in seconds (>= 0).
        duration_s: simulated span, seconds.
        counts_per_rev: edges per revolution.
        phase: angle at t = 0 in edges (0..1), so the first edge falls at an arbitrary time.
        count_offset: value of the edge counter at t = 0 (wraps modulo 2^32).
        time_offset_us: value of the microsecond clock at t = 0 (wraps modulo 2^32).
        jitter_us: standard deviation of the edge timestamp noise, microseconds.
        seed: seed of the jitter noise.
    """

    def __init__(self, *, rev_per_s: Callable[[np.ndarray], np.ndarray], duration_s: float, counts_per_rev: int,
                 phase: float = 0.37, count_offset: int = 0, time_offset_us: int = 0, jitter_us: float = 0.0,
                 seed: int = 0) -> None:
        grid_s = np.arange(0.0, duration_s, 1e-6)
        edges_angle = np.cumsum(rev_per_s(grid_s)) * 1e-6 * counts_per_rev + phase
        crossings = np.arange(1, int(edges_angle[-1]) + 1)
        idx = np.searchsorted(edges_angle, crossings)
        self.edge_times_s = grid_s[np.minimum(idx, len(grid_s) - 1)]
        rng = np.random.default_rng(seed)
        self.edge_us = np.floor(self.edge_times_s * 1e6 + rng.normal(0.0, jitter_us, len(idx))).astype(np.int64)
        self.edge_us = np.maximum.accumulate(self.edge_us)  # a capture timer never runs backwards
        self.count_offset = count_offset
        self.time_offset_us = time_offset_us

    def capture(self, t_s: float) -> tuple[int, int, int]:
        """(count, edge_us, now_us) as uint32 values the firmware would read at time t_s."""
        n = int(np.searchsorted(self.edge_times_s, t_s, side="right"))
        edge_us = int(self.edge_us[n - 1]) if n > 0 else 0
        now_us = int(np.floor(t_s * 1e6))
        return ((self.count_offset + n) % U32, (self.time_offset_us + edge_us) % U32,
                (self.time_offset_us + now_us) % U32)
