"""The spindle plant loaded by the rope chain: the guide feels the pull the chain reports, not a fixed object.

SpindlePlant's own load model is a stand-in object of fixed circumference (``object_circumference_m``);
in a chain scenario the load comes from the MuJoCo chain instead. The bridge (chain_bridge.py) writes
``guide_load_n`` every tick; each spindle substep turns it into the torque resisting retraction exactly
as SpindlePlant does for its own rope force (lead, screw efficiency, self-locking screw).
"""

from __future__ import annotations

import math

from robowrangler_sim.plants.spindle import SpindleParams, SpindlePlant


class ChainLoadedSpindlePlant(SpindlePlant):
    """SpindlePlant whose rope pull on the guide is set from outside.

    Attributes:
        guide_load_n: pull of the rope on the guide, N (>= 0), resisting retraction. Written by the bridge.
        rope_tension_n (read): guide_load_n / rope_per_guide_mm, the tension of each of the two strands, N.
    """

    def __init__(self, params: SpindleParams | None = None, *, seed: int = 0) -> None:
        self._guide_load_n = 0.0
        super().__init__(params, seed=seed)

    @property
    def guide_load_n(self) -> float:
        return self._guide_load_n

    @guide_load_n.setter
    def guide_load_n(self, value: float) -> None:
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0):
            raise ValueError(f"guide_load_n: expected a finite force >= 0 N, got {value!r}")
        self._guide_load_n = float(value)

    def _rope_force_n(self) -> float:
        """Pull of the rope on the guide (resisting retraction), N: the chain's load."""
        self.rope_tension_n = self._guide_load_n / self.params.rope_per_guide_mm
        return self._guide_load_n
