"""out_of_plane_stiffness: the real rope resists bending out of the loop plane; the chain's out-of-plane joints
have zero stiffness. Law: a restoring moment k_oop (N m/rad) on the out-of-plane hinges. 2-D contours in the loop
plane carry no out-of-plane component: never identifiable from /loop/observation."""

from __future__ import annotations

from robowrangler_sim.diagnose.loop.candidates.base import Identifiability, LoopCandidate


class OutOfPlaneStiffness(LoopCandidate):
    effect_id = "out_of_plane_stiffness"
    law = "M = -k_oop q_oop on the out-of-plane hinges (k_oop in N m/rad)"
    regime = "out of the loop plane: side loads, yawing, contact"
    params = ()
    separating_measurement = "a second camera looking along the launch axis (3-D contours: the loop's out-of-plane deflection)"

    def identifiable(self, replay) -> Identifiability:
        return Identifiability(False, "the contours are 2-D in the loop plane: no out-of-plane component",
                               self.separating_measurement)
