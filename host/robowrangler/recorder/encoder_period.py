"""The raw encoder period (M/T: time between edges over the edges counted) from latched count/edge-time pairs.

Both TELEMETRY (encoder_counts, encoder_edge_us: 32-bit) and a burst's samples (16-bit low halves, unwrapped by
robowrangler.recorder.burst) carry the cumulative edge count latched with the capture time of its latest edge.
Between two such pairs, (edge time difference) / (count difference) is the mean edge period over exactly the
edges counted, unfiltered: the measurement the device's filtered rope speed is made from.
"""

from __future__ import annotations

import numpy as np


def mt_period_us(counts: np.ndarray, edge_us: np.ndarray, *, modulus: int = 1 << 32) -> np.ndarray:
    """Mean edge period [us] between consecutive pairs that saw new edges; NaN where no edge came (or a pair is
    missing: NaN in, NaN out). counts and edge_us are the wire values (wrapping at modulus); the result has one
    value per pair, the first NaN. Shape (n,) -> (n,)."""
    counts = np.asarray(counts, dtype=float)
    edge_us = np.asarray(edge_us, dtype=float)
    if counts.shape != edge_us.shape or counts.ndim != 1:
        raise ValueError(f"counts, edge_us: expected two 1-D arrays of one length, got shapes {counts.shape}, "
                         f"{edge_us.shape}")
    out = np.full(counts.shape, np.nan)
    last = None  # index of the last pair that counted an edge
    for i in range(len(counts)):
        if np.isnan(counts[i]) or np.isnan(edge_us[i]):
            continue
        if last is not None:
            dn = (counts[i] - counts[last]) % modulus
            if dn > 0:
                out[i] = ((edge_us[i] - edge_us[last]) % modulus) / dn
            else:
                continue  # no new edge: keep the reference
        last = i
    return out
