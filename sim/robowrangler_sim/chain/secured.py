"""Is an object secured by the loop? A sliding-window judgement from simulated contacts and motion.

Over the last ``window_s`` of samples:
  * the rope keeps hold of the object: the chain-on-object force exceeds ``min_contact_force_n`` in at
    least ``contact_fraction`` of the samples;
  * if the module moved (more than ``still_m``), the object's centre of mass followed it:
    displacement along the module's >= ``follow_fraction`` of the module's.
A ball the rope knocks ahead of itself (it rolls on, out of contact) or an object left behind is not
secured. (The rope force is reported next to the force that would slide the object on the floor, but
not judged against it: a wrapped object may roll or pivot instead of sliding.)
"""

from __future__ import annotations

from collections import deque

import numpy as np

from robowrangler_sim.chain.errors import ChainModelError


class SecuredMonitor:
    """Sliding-window "secured" judgement for one object.

    Args:
        drag_force_n: force that slides the object on the floor, N (> 0).
        window_s: judgement window, s.
        follow_fraction: required object/module displacement ratio when the module moves.
        contact_fraction: share of samples in which the rope must touch the object.
        min_contact_force_n: force counted as touching, N.
        still_m: module displacement under which the module counts as still.
    """

    def __init__(self, *, drag_force_n: float, window_s: float = 1.0, follow_fraction: float = 0.5,
                 contact_fraction: float = 0.8, min_contact_force_n: float = 1e-3,
                 still_m: float = 0.01) -> None:
        if not drag_force_n > 0:
            raise ChainModelError(f"drag_force_n: expected > 0, got {drag_force_n}")
        if not window_s > 0:
            raise ChainModelError(f"window_s: expected > 0, got {window_s}")
        self.drag_force_n = float(drag_force_n)
        self.window_s = float(window_s)
        self.follow_fraction = float(follow_fraction)
        self.contact_fraction = float(contact_fraction)
        self.min_contact_force_n = float(min_contact_force_n)
        self.still_m = float(still_m)
        self._samples: deque = deque()

    def update(self, *, time_s: float, object_com_m: np.ndarray, base_pos_m: np.ndarray,
               chain_force_n: float) -> None:
        """Add one sample; samples older than window_s are dropped."""
        self._samples.append((float(time_s), np.asarray(object_com_m, dtype=float).copy(),
                              np.asarray(base_pos_m, dtype=float).copy(), float(chain_force_n)))
        while self._samples and self._samples[0][0] < time_s - self.window_s - 1e-9:
            self._samples.popleft()

    def reset(self) -> None:
        self._samples.clear()

    @property
    def mean_force_n(self) -> float:
        """Mean chain-on-object force over the window, N."""
        return float(np.mean([s[3] for s in self._samples])) if self._samples else 0.0

    @property
    def touching_fraction(self) -> float:
        """Share of the window's samples in which the rope touches the object."""
        if not self._samples:
            return 0.0
        return float(np.mean([s[3] > self.min_contact_force_n for s in self._samples]))

    @property
    def follow_ratio(self) -> float:
        """Object displacement along the module's / module displacement over the window (nan if still)."""
        if len(self._samples) < 2:
            return float("nan")
        d_base = self._samples[-1][2] - self._samples[0][2]
        norm2 = float(np.dot(d_base, d_base))
        if norm2 < self.still_m ** 2:
            return float("nan")
        d_obj = self._samples[-1][1] - self._samples[0][1]
        return float(np.dot(d_obj, d_base) / norm2)

    @property
    def secured(self) -> bool:
        """True when the rope keeps hold of the object and (if the module moved) it followed."""
        if len(self._samples) < 2:
            return False
        if self.touching_fraction < self.contact_fraction:
            return False
        follow = self.follow_ratio
        return bool(np.isnan(follow) or follow >= self.follow_fraction)
