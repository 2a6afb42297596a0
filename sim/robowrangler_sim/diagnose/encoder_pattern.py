"""The encoder's edge pattern, calibrated from the recording itself.

A real incremental encoder's edges are not equally spaced: a magnetic ring's lines are a little off and the two
quadrature channels are not exactly 90 degrees apart (a few per cent of an edge pitch is ordinary). The edge
with absolute count c then lies at c + E[c mod N] pitches (N edges per revolution, sum E = 0), and a speed taken
over a few edges (a 1 kHz burst sample sees 2-10) carries that error: tens of mm/s, fixed by the edge index, not
noise. The recorded counts are absolute (edges since boot), so every observation says which edges it spans: E is
identifiable from the recording, jointly with a smooth shaft position X(t) (a cubic B-spline with knots every
KNOT_S: it follows the drive's steps, while the pattern repeats with the edge index, which the rope's speed
keeps sweeping), on the densely sampled stretches (the 1 kHz bursts, where the pattern matters: a 100 Hz
record's speed spans ten times the travel), by linear least squares:

    c_k = X(t_k) - E[c_k mod N]     for every distinct (latest-edge time t_k, count c_k) the records hold

The corrected edge position of count c is c + E[c mod N] (pitches); speeds over corrected positions are free of
the pattern. With an ideal encoder E comes out at the level of the edge clock's noise (< 1e-3 pitch).
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.interpolate import BSpline
from scipy.sparse.linalg import spsolve

KNOT_S = 0.005
MIN_ROWS_PER_EDGE = 8  # distinct moving observations per edge index needed before the pattern is estimated
MAX_COUNTS_PER_REV = 4096
DENSE_GAP_S = 2.5e-3  # distinct edges at most this far apart: a densely sampled stretch


def estimate_edge_pattern(edge_t_s: np.ndarray, counts: np.ndarray, counts_per_rev: int, *,
                          knot_s: float = KNOT_S) -> np.ndarray | None:
    """E (counts_per_rev,) in pitches (zero mean) from (S,) latest-edge times and absolute edge counts (NaN: none),
    or None when the recording holds too few distinct edges in densely sampled stretches (no bursts: telemetry
    only), or counts_per_rev is not a whole number of edges in 1..MAX_COUNTS_PER_REV."""
    n = int(round(counts_per_rev))
    if n != counts_per_rev or not 1 <= n <= MAX_COUNTS_PER_REV:
        return None
    ok = np.isfinite(edge_t_s) & np.isfinite(counts)
    t = np.asarray(edge_t_s, float)[ok]
    c = np.round(np.asarray(counts, float)[ok]).astype(np.int64)
    if c.size == 0:
        return None
    # one row per distinct edge (the same latest edge is seen by many records while the rope is slow)
    c_u, first = np.unique(c, return_index=True)
    t_u = t[first]
    if c_u.size < MIN_ROWS_PER_EDGE * n:
        return None
    order = np.argsort(t_u, kind="stable")
    t_u, c_u = t_u[order], c_u[order]
    t0, t1 = float(t_u[0]), float(t_u[-1])
    # only rows of densely sampled stretches (the 1 kHz bursts): between 100 Hz records the drive's steps and
    # chirps move more than a smooth curve through them can follow, and the pattern's share of a 10 ms interval's
    # speed is small anyway; knot spans without such rows get no rows (their coefficients stay free)
    gap = np.diff(t_u)
    dense = np.zeros(t_u.size, dtype=bool)
    dense[1:] |= gap <= DENSE_GAP_S
    dense[:-1] |= gap <= DENSE_GAP_S
    t_u, c_u = t_u[dense], c_u[dense]
    if c_u.size < MIN_ROWS_PER_EDGE * n:
        return None
    t0, t1 = float(t_u[0]), float(t_u[-1])
    inner = np.linspace(t0, t1, max(1, int(np.ceil((t1 - t0) / knot_s))) + 1)
    knots = np.concatenate(([t0] * 3, inner, [t1] * 3))
    basis = BSpline.design_matrix(np.clip(t_u, t0, t1), knots, 3).tocsr()
    m = basis.shape[1]
    idx = np.mod(c_u, n)
    pattern = sparse.csr_matrix((-np.ones(c_u.size), (np.arange(c_u.size), idx)), shape=(c_u.size, n))
    a = sparse.hstack([basis, pattern]).tocsr()
    y = c_u.astype(float) - float(c_u[0])  # positions from the first edge (the spline carries the offset)
    # sum E = 0 (the spline carries the mean); a faint ridge keeps knot spans without data defined
    ata = (a.T @ a).tocsc()
    atb = a.T @ y
    scale = float(ata.diagonal().mean())
    con = sparse.csc_matrix((np.ones(n), (np.arange(m, m + n), np.zeros(n, dtype=int))), shape=(m + n, 1))
    ata = ata + 1e3 * scale * (con @ con.T) + 1e-10 * scale * sparse.identity(m + n, format="csc")
    sol = spsolve(ata, atb)
    e = sol[m:]
    return e - e.mean()


def corrected_counts(counts: np.ndarray, pattern: np.ndarray | None) -> np.ndarray:
    """The edge positions in pitches of (S,) absolute counts (NaN kept): c + E[c mod N]."""
    counts = np.asarray(counts, float)
    if pattern is None:
        return counts
    out = counts.copy()
    ok = np.isfinite(counts)
    out[ok] = counts[ok] + pattern[np.mod(np.round(counts[ok]).astype(np.int64), pattern.size)]
    return out
