"""The rope chain as the plant the firmware drives: ChainPlant stepped in lockstep with a SilSession.

Installed as a SilSession tick hook (``ChainBridge(sil, chain, trajectory).install()``), it runs after
the drive and spindle plants have stepped each 1 ms control tick. Whenever the SIL clock has reached the
end of the chain's next MuJoCo step (chain timestep h = ChainParams.timestep_s, 5 ms by default), the
chain integrates [t_c, t_c + h) with the values sampled at that tick (sample and hold, as the firmware's
own sensors are). It composes the chain as the session composes the drive and the spindle, through the
plant contract only (plants/contract.py): ``outputs = chain.update(PlantInputs(...), h)``, one call per
chain step (the base pose is sampled at each step's start, so the module's motion is as fine as the chain's
own step), and the coupling below reads the PlantOutputs of the last step, the contacts as they are at the
end of that step:

Plant -> chain (SI):
  * rope speed (m/s)          = drive plant rope_speed_mps; above ToV the loop is lifted (lift.py);
  * guide position (mm)       = spindle plant guide_position_mm, clipped to 0..guide_stroke_mm (the
                                 spindle's hard stops lie there; homing may touch 0 from either side);
  * base pose (m, quaternion) = the scenario's BaseTrajectory at t_c (the robot's leg).

Chain -> plants (the coupling law):
  * Guide load (N) = | sum over the scene's objects of the net contact force (normal + friction) the
    chain exerts on them |.  Reason: the rope is nearly massless (2e-5 kg links), so whatever the
    objects push on the loop goes through the rope into the device. Both strands pass over the guide
    (rope_per_guide_mm = 2): a loop pulling an object with F carries about F / 2 in each strand and pulls
    the guide with about F (virtual work: F dx = T 2 dx). The spindle plant turns it into the torque
    resisting retraction (SpindleInputs.guide_load_n: / lead, / screw efficiency, self-locking), which is
    what the AX-12A's present-load register shows the firmware; so RETRACT ends on LOAD_SECURED only
    when the chain really pulls that hard (grasp_secure_load_pct, 12 % by default: about 36 N on the
    guide). The chain's closure force (PlantOutputs.rope_tension_n) is not used: the soft closure
    constraint on the light links carries little of a grasp's load (docs/chain_model.md).
  * Drive rope load (N) = rope_axial_friction x (sum of the normal contact forces of the chain on the
    objects and on the floor): Coulomb friction along a rope that runs through its contacts, felt by
    the wheels as DriveInputs.external_rope_load_n (it opposes the rope's motion, zero when the rope
    stands). With a 0.44 g rope this is a few mN lying on the floor; it matters when the loop runs
    over an object it presses on.
Both loads are held between chain steps in the session's ``loads`` (PlantLoads), which the session hands the
plants as their inputs (the plant contract); the firmware sees them one tick after the chain step that
produced them (the lockstep delay, 1 ms).

Determinism: the chain has no random inputs after its seeded construction, the SIL is lockstep, so the
same seed and the same host script give the same trajectory.
"""

from __future__ import annotations

import math

import numpy as np

from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, PlantOutputs
from robowrangler_sim.scenarios.base_trajectory import BaseTrajectory

DEFAULT_ROPE_AXIAL_FRICTION = 0.3
"""Coulomb friction coefficient of the rope sliding along its own axis over a contact (= rope_friction)."""


class ChainBridge:
    """Couples a ChainPlant to a SilSession (see module doc for the law and units).

    Args:
        sil: the session (a SilSession); from construction on, the chain's loads replace the spindle plant's
            stand-in object (``sil.loads.guide_load_n`` is set).
        chain: the chain plant, built with the trajectory's start pose.
        trajectory: the module's pose over simulated time.
        rope_axial_friction: friction coefficient for the drive's rope load (dimensionless, >= 0).

    After each chain step: ``outputs`` (the chain's PlantOutputs, None before the first step), ``guide_load_n``,
    ``drive_load_n`` (N), ``chain_steps``; ``peak_guide_load_n`` is the largest guide load so far.
    """

    def __init__(self, sil, chain: ChainPlant, trajectory: BaseTrajectory, *,
                 rope_axial_friction: float = DEFAULT_ROPE_AXIAL_FRICTION) -> None:
        if not (math.isfinite(rope_axial_friction) and rope_axial_friction >= 0):
            raise ValueError(f"rope_axial_friction: expected a finite value >= 0, got {rope_axial_friction!r}")
        self.sil = sil
        self.chain = chain
        self.trajectory = trajectory
        self.rope_axial_friction = float(rope_axial_friction)
        self.guide_load_n = 0.0
        self.drive_load_n = 0.0
        self.peak_guide_load_n = 0.0
        self.chain_steps = 0
        self.outputs: PlantOutputs | None = None
        self._h_s = chain.params.timestep_s
        self._stroke_mm = chain.params.guide_stroke_mm
        sil.loads.guide_load_n = 0.0  # the chain pulls on the guide from now on, not the stand-in object

    def install(self) -> ChainBridge:
        self.sil.tick_hooks.append(self)
        return self

    def inputs_at(self, t_s: float) -> PlantInputs:
        """The chain's inputs for a step starting at t_s, from the plants' present state."""
        guide = min(max(self.sil.spindle_out.guide_position_mm, 0.0), self._stroke_mm)
        return PlantInputs(rope_speed_mps=self.sil.drive_out.rope_speed_mps, guide_position_mm=guide,
                           base_pos_m=tuple(self.trajectory.pos_at(t_s)), base_quat_wxyz=self.trajectory.quat_wxyz)

    def __call__(self, sil) -> None:
        t_s = sil.time_s
        chain = self.chain
        outputs = None
        while chain.time_s + self._h_s <= t_s + 1e-9:
            # one chain step through the contract; ChainDivergenceError propagates: the run is over
            outputs = chain.update(self.inputs_at(chain.time_s), self._h_s)
            self.chain_steps += 1
        if outputs is not None:
            self.outputs = outputs
            self._couple(outputs)

    def _couple(self, outputs: PlantOutputs) -> None:
        total = np.zeros(3)
        for f in outputs.chain_object_net_force_n.values():
            total += f
        self.guide_load_n = float(np.linalg.norm(total))
        self.peak_guide_load_n = max(self.peak_guide_load_n, self.guide_load_n)
        self.drive_load_n = self.rope_axial_friction * (sum(outputs.chain_object_force_n.values())
                                                        + outputs.chain_floor_force_n)
        self.sil.loads.guide_load_n = self.guide_load_n
        self.sil.loads.external_rope_load_n = self.drive_load_n

