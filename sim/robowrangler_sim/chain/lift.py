"""Lift of the loop: how much of the paper's shape drive is active, from the rope speed.

Above ToV the air drag on the moving rope carries its weight and the loop flies in its steady shape
(the paper's drives hold it); under ToV that support is gone and the loop falls under gravity.
The lift factor ``a`` in [0, 1] scales the drive gains (kp a, kd a). It moves towards its target
(1 at or above ToV, 0 below) at a fixed rate, so a speed change is a transition:

    a[k+1] = a[k] + clip(a_target - a[k], -dt / T, +dt / T),   T = lift_ramp_s

Falling: as ``a`` reaches 0 the drives release and the chain falls (gravity, contact, passive
damping); no state is teleported. Rising: the drives grow back and pull the chain, first-order with
time constant kd/kp once ``a`` is 1.
"""

from __future__ import annotations

from robowrangler_sim.chain.errors import ChainModelError


class LiftState:
    """Rate-limited lift factor.

    Args:
        takeoff_speed_mps: ToV.
        lift_ramp_s: time for a full 0 <-> 1 transition (0 = instantaneous).
        lift: initial factor in [0, 1].
    """

    def __init__(self, *, takeoff_speed_mps: float, lift_ramp_s: float, lift: float = 0.0) -> None:
        if not 0.0 <= lift <= 1.0:
            raise ChainModelError(f"lift: expected in [0, 1], got {lift}")
        self.takeoff_speed_mps = float(takeoff_speed_mps)
        self.lift_ramp_s = float(lift_ramp_s)
        self.lift = float(lift)

    def step(self, rope_speed_mps: float, dt_s: float) -> float:
        """Advance by dt_s with the current rope speed (m/s, magnitude used); returns the new factor."""
        target = 1.0 if abs(rope_speed_mps) >= self.takeoff_speed_mps else 0.0
        if self.lift_ramp_s <= 0.0:
            self.lift = target
        else:
            max_change = dt_s / self.lift_ramp_s
            self.lift += min(max(target - self.lift, -max_change), max_change)
        return self.lift

    def reset(self, lift: float = 0.0) -> None:
        if not 0.0 <= lift <= 1.0:
            raise ChainModelError(f"lift: expected in [0, 1], got {lift}")
        self.lift = float(lift)
