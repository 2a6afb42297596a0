"""Step-response figures computed from telemetry (used by the SIL tests, the benchmarks and the demo)."""

from __future__ import annotations

from collections.abc import Sequence


def settle_time_s(times_s: Sequence[float], values: Sequence[float], *, target: float, start_s: float,
                  end_s: float | None = None, tolerance: float = 0.02) -> float | None:
    """Time from start_s until values enter target +- tolerance*target and stay there until end_s (default: the
    last sample).

    Returns None if the last sample up to end_s is outside the band (never settled).
    """
    if len(times_s) != len(values):
        raise ValueError(f"times_s and values: expected equal lengths, got {len(times_s)} and {len(values)}")
    band = abs(target) * tolerance
    settled_at = None
    for t, v in zip(times_s, values):
        if t < start_s:
            continue
        if end_s is not None and t > end_s:
            break
        inside = abs(v - target) <= band
        if inside and settled_at is None:
            settled_at = t
        elif not inside:
            settled_at = None
    return None if settled_at is None else settled_at - start_s
