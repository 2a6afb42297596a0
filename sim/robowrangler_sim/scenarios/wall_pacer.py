"""Pacing a simulated clock against the wall clock, for what a person watches (the MuJoCo viewer, the Foxglove
live view): simulated time runs at `speedup` x wall time (None: unpaced); a machine that falls behind by more
than half a second re-anchors instead of racing to catch up."""

from __future__ import annotations

from collections.abc import Callable

BEHIND_RESET_S = 0.5


class WallPacer:
    """pace(t_s) sleeps until simulated time t_s is due at speedup x wall time (anchored at its first call)."""

    def __init__(self, speedup: float | None, *, clock_s: Callable[[], float],
                 sleep_s: Callable[[float], None]) -> None:
        self.speedup = speedup
        self._clock_s = clock_s
        self._sleep_s = sleep_s
        self._origin: tuple[float, float] | None = None  # (wall s, simulated s) at the first call

    def pace(self, t_s: float) -> None:
        if self.speedup is None:
            return
        now = self._clock_s()
        if self._origin is None:
            self._origin = (now, t_s)
            return
        wall0, sim0 = self._origin
        ahead_s = (t_s - sim0) / self.speedup - (now - wall0)
        if ahead_s > 0.0:
            self._sleep_s(ahead_s)
        elif ahead_s < -BEHIND_RESET_S:  # the machine fell behind: do not race to catch up
            self._origin = (now, t_s)
