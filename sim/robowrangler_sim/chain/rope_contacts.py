"""Where and how the rope touches an object: one record per MuJoCo contact, in the rope's own terms.

A grasp is won or lost at a few rope-object contacts. This reads them from MuJoCo's contact list and
says, for each, how the object's surface faces the rope (is the contact point level with the rope's
axis, below it, or is the rope lying on the object?), how hard the rope presses, how much of the
friction it has left, and whether the rope slides along its own axis or across it::

    for c in plant.rope_contacts("credit_card"):
        print(c.link_index, c.normal_tilt_deg, c.friction_use, c.slip_along_rope_mps)

docs/chain_model.md ("The credit card") uses it to show why a 0.76 mm card is lost: the rope slides
along the card's edge, spends its friction along its axis, and the edge's upward push lifts it on.

Slip velocities are what MuJoCo's solver sees (the joints' and the object's velocities at the contact
point). The guide's take-up rewrites the link lengths between steps and does not appear in them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np


@dataclass(frozen=True, kw_only=True)
class RopeContact:
    """One rope-object contact at one instant (SI units, world frame).

    Attributes:
        link_index: the chain link touching (0 at the exit).
        pos_m: shape (3,), contact point.
        normal_tilt_deg: angle of the contact normal (rope -> object) below the horizontal: 0 = the object
            pushes the rope sideways (a wall level with the rope's axis); > 0 = the contact point is below the
            rope's axis and the object pushes the rope up (an edge lower than the rope's radius: a ramp);
            90 = the rope lies on top of the object; < 0 = the object presses the rope down.
        penetration_m: how far the two geoms overlap (>= 0).
        normal_force_n: normal force between them.
        friction_force_n: magnitude of the tangential (friction) force.
        friction_coefficient: the contact's sliding friction (MuJoCo: the larger of the pair).
        slip_along_rope_mps: tangential velocity of the rope relative to the object along the link's axis
            (signed, + towards the link's far end).
        slip_across_rope_mps: magnitude of the rest of the tangential relative velocity.
    """

    link_index: int
    pos_m: np.ndarray
    normal_tilt_deg: float
    penetration_m: float
    normal_force_n: float
    friction_force_n: float
    friction_coefficient: float
    slip_along_rope_mps: float
    slip_across_rope_mps: float

    @property
    def friction_use(self) -> float:
        """Friction force over its Coulomb limit (1 = sliding; < 1 = the contact sticks); 0 without load."""
        limit = self.friction_coefficient * self.normal_force_n
        return self.friction_force_n / limit if limit > 0 else 0.0


def rope_object_contacts(model: mujoco.MjModel, data: mujoco.MjData, *, link_geoms: np.ndarray,
                         object_geoms: set, object_body: int) -> list[RopeContact]:
    """Every contact now between a chain link (link_geoms, in link order) and one object's geoms."""
    link_of = {int(g): i for i, g in enumerate(link_geoms)}
    force6 = np.zeros(6)
    jac_rope = np.zeros((3, model.nv))
    jac_obj = np.zeros((3, model.nv))
    out = []
    for i in range(data.ncon):
        c = data.contact[i]
        g1, g2 = int(c.geom1), int(c.geom2)
        if g1 in link_of and g2 in object_geoms:
            rope_geom, sign = g1, 1.0
        elif g2 in link_of and g1 in object_geoms:
            rope_geom, sign = g2, -1.0
        else:
            continue
        normal = sign * c.frame[:3]  # MuJoCo's frame normal points from geom1 to geom2
        mujoco.mj_contactForce(model, data, i, force6)
        pos = np.array(c.pos)
        mujoco.mj_jac(model, data, jac_rope, None, pos, int(model.geom_bodyid[rope_geom]))
        mujoco.mj_jac(model, data, jac_obj, None, pos, object_body)
        v_rel = (jac_rope - jac_obj) @ data.qvel
        v_tan = v_rel - normal * float(v_rel @ normal)
        axis = data.geom_xmat[rope_geom].reshape(3, 3)[:, 2]  # a capsule's axis is its local z
        along = float(v_tan @ axis)
        out.append(RopeContact(
            link_index=link_of[rope_geom], pos_m=pos,
            normal_tilt_deg=math.degrees(math.asin(max(-1.0, min(1.0, -float(normal[2]))))),
            penetration_m=max(0.0, -float(c.dist)), normal_force_n=abs(float(force6[0])),
            friction_force_n=float(np.hypot(force6[1], force6[2])), friction_coefficient=float(c.friction[0]),
            slip_along_rope_mps=along, slip_across_rope_mps=float(np.linalg.norm(v_tan - along * axis))))
    return out
