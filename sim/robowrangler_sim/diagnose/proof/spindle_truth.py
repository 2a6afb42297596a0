"""Truth spindle effects for the proof, in forms that are NOT the library's laws:

    SpindleTruthPlant(deadband_in_raw, deadband_out_raw)  a dead band that differs moving in and moving out
                                                           (the library's is one threshold with hysteresis)
    SpindleTruthPlant(backlash_mm, soft_fraction)          backlash with a soft take-up: over the last
                                                           soft_fraction of the gap the screw's friction comes in
                                                           gradually (smoothstep), not at once (library: a play
                                                           operator that engages at once)
    backlash_region_mm                                     backlash only where the nut is beyond a position (a
                                                           worn stretch of thread: present in one regime only)

A subclass of the per-tick SpindlePlant that overrides only its dead-band and engagement seams, so everything else
(torque-speed line, response, end stops, registers and their noise) is the plant's own.
"""

from __future__ import annotations

from robowrangler_sim.plants.spindle import SpindleParams, SpindlePlant


def _smoothstep(x: float) -> float:
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


class SpindleTruthPlant(SpindlePlant):
    def __init__(self, params: SpindleParams, *, seed: int, deadband_in_raw: float = 0.0,
                 deadband_out_raw: float = 0.0, backlash_mm: float = 0.0, soft_fraction: float = 0.3,
                 backlash_region_mm: float | None = None) -> None:
        self.deadband_in_raw = deadband_in_raw
        self.deadband_out_raw = deadband_out_raw
        self.backlash_mm = backlash_mm
        self.soft_fraction = soft_fraction
        self.backlash_region_mm = backlash_region_mm
        super().__init__(params, seed=seed)

    def _gap_mm(self) -> float:
        if self.backlash_region_mm is not None and self.nut_position_mm < self.backlash_region_mm:
            return 0.0
        return self.backlash_mm

    def _servo_fraction(self, raw: int) -> float:
        m = raw & 0x3FF
        outward = bool(raw & 0x400)
        if m <= (self.deadband_out_raw if outward else self.deadband_in_raw):
            return 0.0
        return m / 1023.0 * (-1.0 if outward else 1.0)

    def _engagement(self, u: float) -> float:
        b = self._gap_mm()
        if b <= 0.0 or u == 0.0:
            return 1.0
        w = max(self.soft_fraction * b, 1e-6)
        if u > 0.0:
            return _smoothstep((self.play_mm - (b - w)) / w)
        return _smoothstep((w - self.play_mm) / w)

    def _move_play(self, dx_mm: float) -> None:
        self.play_mm = min(max(self.play_mm + dx_mm, 0.0), self._gap_mm())

    def step(self, dt_s: float) -> None:
        if self.backlash_mm > 0.0 and self.params.screw_backlash_mm == 0.0:
            # the base plant moves the play only when its own backlash term is on: do it here
            before = self.guide_position_mm
            super().step(dt_s)
            self._move_play(self.guide_position_mm - before)
        else:
            super().step(dt_s)
