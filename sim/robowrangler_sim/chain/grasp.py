"""Plant-level grasp: a time-scripted relax / retract / hold / pull sequence, judged by the simulation.

This drives the ChainPlant's SI inputs directly, standing in for the firmware until the lockstep SIL
drives them (the firmware's state machine: AIRBORNE -> RELAX -> RETRACT -> HOLD). The next step is the
same scenario with the firmware in the loop (`wrangler sil --scenario ...`).

Script (all times in simulated seconds, GraspScript fields):
  1. position  (position_s): the module is rolled by ``roll_deg`` about its launch axis (90: the loop
     plane is horizontal) with its exit ``exit_height_m`` above the floor, rope at
     ``airborne_speed_mps``; the object stands inside the loop's outline, at ``object_x_frac`` of the
     loop's reach, centred between the branches. (A vertical loop dropped onto an object slides off
     sideways: it cannot enclose anything standing on the floor; the lasso lies around it instead.)
  2. relax     (relax_s): rope speed ``relax_speed_mps`` (< ToV): the loop loses lift and falls onto
     the object and the floor.
  3. retract   (retract_s): the guide runs 0 -> ``retract_guide_mm`` at constant speed (loop shrinks).
  4. hold      (hold_s): guide kept; nothing moves.
  5. pull      (pull_s): the module moves back by ``pull_m`` and up by ``lift_m`` (the robot's leg);
     0.3 m in 3 s (0.1 m/s): at 0.15 m/s the chips can and the mug sat at the judgement's margin in the
     SIL (the soft closure lets the loop lengthen under their 0.7-1.2 N sliding force; docs/chain_model.md).

The inputs are evaluated at every plant step (5 ms), as the SIL bridge does: the leg and the guide move
continuously (jumps of a coarser sampling drive rope links into objects, docs/chain_model.md).

Judgement (GraspOutcome.secured, secured.SecuredMonitor), over the second half of the pull (the
first half takes up the slack between the loop and the object): the rope keeps hold of the object
(touches it in >= ``contact_fraction`` of the samples) and the object's centre of mass follows the
module (displacement along the pull >= ``follow_fraction`` of the module's). A ball knocked ahead
(rolling on, out of contact) or an object left behind has slipped. Positions and forces come from
MuJoCo contacts; nothing is decided by a rule on the object's shape.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.objects import ObjectPlacement, ObjectSpec, get_object
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
from robowrangler_sim.chain.secured import SecuredMonitor
from robowrangler_sim.shape_table import ShapeTable


@dataclass(frozen=True, kw_only=True)
class GraspScript:
    """The prescribed input sequence (see module doc); SI units."""

    phi_deg: float = 0.0
    roll_deg: float = 90.0
    airborne_speed_mps: float = 4.0
    relax_speed_mps: float = 1.0
    exit_height_m: float = 0.03
    object_x_frac: float = 0.75
    position_s: float = 1.0
    relax_s: float = 1.5
    retract_s: float = 3.0
    retract_guide_mm: float = 180.0
    hold_s: float = 0.5
    pull_s: float = 3.0
    pull_m: float = 0.3
    lift_m: float = 0.0
    follow_fraction: float = 0.5
    contact_fraction: float = 0.8

    def __post_init__(self) -> None:
        for name in ("position_s", "relax_s", "retract_s", "hold_s", "pull_s"):
            if not getattr(self, name) >= 0:
                raise ChainModelError(f"{name}: expected >= 0 s, got {getattr(self, name)}")
        if not 0.0 < self.object_x_frac < 1.0:
            raise ChainModelError(f"object_x_frac: expected in (0, 1), got {self.object_x_frac}")

    @property
    def duration_s(self) -> float:
        return self.position_s + self.relax_s + self.retract_s + self.hold_s + self.pull_s


@dataclass
class GraspOutcome:
    """What the simulation says about one grasp.

    Attributes:
        object_name: the object.
        secured: True if held (see module doc), False if it slipped out.
        follow_ratio: object displacement along the pull / module displacement, second half of the
            pull (1 = moves with the module).
        final_chain_force_n: net chain-on-object force at the end, N.
        mean_pull_force_n: mean net chain-on-object force, second half of the pull, N.
        touching_fraction: share of the second-half samples in which the rope touches the object.
        drag_force_n: force that slides the object on the floor (larger friction of the pair x weight), N.
        max_chain_force_n: the largest net chain-on-object force seen, N.
        object_displacement_m: shape (3,), object centre-of-mass change over the whole script.
        trace: per-sample dict rows (time_s, phase, object_pos_m, chain_force_n, guide_mm, base_pos_m).
    """

    object_name: str
    secured: bool
    follow_ratio: float
    final_chain_force_n: float
    mean_pull_force_n: float
    touching_fraction: float
    drag_force_n: float
    max_chain_force_n: float
    object_displacement_m: np.ndarray
    trace: list = field(default_factory=list)


def grasp_inputs(script: GraspScript, t_s: float, *, base_pos_m: np.ndarray) -> tuple[str, PlantInputs]:
    """The scripted plant inputs at time t_s (phase name, PlantInputs)."""
    q = pitch_quat_wxyz(math.radians(script.phi_deg), roll_rad=math.radians(script.roll_deg))
    t = t_s
    base = np.asarray(base_pos_m, dtype=float)
    if t < script.position_s:
        return "position", PlantInputs(rope_speed_mps=script.airborne_speed_mps, guide_position_mm=0.0,
                                       base_pos_m=tuple(base), base_quat_wxyz=q)
    t -= script.position_s
    if t < script.relax_s:
        return "relax", PlantInputs(rope_speed_mps=script.relax_speed_mps, guide_position_mm=0.0,
                                    base_pos_m=tuple(base), base_quat_wxyz=q)
    t -= script.relax_s
    if t < script.retract_s:
        guide = script.retract_guide_mm * t / script.retract_s
        return "retract", PlantInputs(rope_speed_mps=script.relax_speed_mps, guide_position_mm=guide,
                                      base_pos_m=tuple(base), base_quat_wxyz=q)
    t -= script.retract_s
    if t < script.hold_s:
        return "hold", PlantInputs(rope_speed_mps=script.relax_speed_mps, guide_position_mm=script.retract_guide_mm,
                                   base_pos_m=tuple(base), base_quat_wxyz=q)
    t -= script.hold_s
    s = min(1.0, t / script.pull_s) if script.pull_s > 0 else 1.0
    moved = base + s * np.array([-script.pull_m, 0.0, script.lift_m])
    return "pull", PlantInputs(rope_speed_mps=script.relax_speed_mps, guide_position_mm=script.retract_guide_mm,
                               base_pos_m=tuple(moved), base_quat_wxyz=q)


def grasp_scene(obj: ObjectSpec | str, *, table: ShapeTable, params: ChainParams, script: GraspScript,
                seed: int = 0) -> tuple[ChainPlant, np.ndarray]:
    """Build the plant for a grasp: object on the floor under the airborne loop. Returns (plant, base_pos_m)."""
    spec = get_object(obj) if isinstance(obj, str) else obj
    if not spec.free:
        raise ChainModelError(f"obj: expected a free object for a grasp, got the fixture {spec.name!r}")
    contour = table.contour(script.phi_deg, rope_speed_mps=script.airborne_speed_mps)
    arc = float(np.sum(np.linalg.norm(np.diff(contour, axis=0), axis=1)))
    contour = contour * (params.home_loop_length_m / arc)
    phi = math.radians(script.phi_deg)
    # contour in the module frame (launch axis = x), then the loop's centre line at the object's x
    xm = math.cos(phi) * contour[:, 0] + math.sin(phi) * contour[:, 1]
    zm = -math.sin(phi) * contour[:, 0] + math.cos(phi) * contour[:, 1]
    tip = int(np.argmax(xm))
    x_obj = script.object_x_frac * float(xm[tip])
    z_up = float(np.interp(x_obj, xm[: tip + 1], zm[: tip + 1]))
    z_low = float(np.interp(x_obj, xm[tip:][::-1], zm[tip:][::-1]))
    z_mid = 0.5 * (z_up + z_low)
    roll = math.radians(script.roll_deg)
    # module frame (x, 0, z) -> world for a launch axis along +x: y_w = -sin(roll) z, z_w = cos(roll) z
    base = np.array([0.0, 0.0, script.exit_height_m])
    obj_pos = (x_obj * math.cos(phi), -math.sin(roll) * z_mid, 0.0)
    placement = ObjectPlacement(spec=spec, pos_m=obj_pos)
    _, first = grasp_inputs(script, 0.0, base_pos_m=base)
    plant = ChainPlant(table=table, params=params, objects=(placement,), floor_height_m=0.0, initial=first,
                       airborne=True, seed=seed)
    return plant, base


def run_grasp(obj: ObjectSpec | str, *, table: ShapeTable, params: ChainParams | None = None,
              script: GraspScript | None = None, seed: int = 0, sample_s: float = 0.05,
              on_sample=None) -> GraspOutcome:
    """Run the scripted grasp on one object and judge it (see module doc).

    Args:
        obj: object spec or catalogue name.
        table: shape table.
        params: chain parameters (default ChainParams()).
        script: the input sequence (default GraspScript()).
        seed: plant seed.
        sample_s: trace sampling period, s.
        on_sample: optional callback(plant, phase) at every sample (e.g. to render frames).
    """
    params = params if params is not None else ChainParams()
    script = script if script is not None else GraspScript()
    spec = get_object(obj) if isinstance(obj, str) else obj
    plant, base = grasp_scene(spec, table=table, params=params, script=script, seed=seed)
    name = spec.name
    start = plant.object_com_m(name)
    drag = max(params.floor_friction, spec.friction) * spec.mass_kg * 9.81
    monitor = SecuredMonitor(drag_force_n=drag, window_s=0.5 * script.pull_s,
                             follow_fraction=script.follow_fraction,
                             contact_fraction=script.contact_fraction)
    trace: list[dict] = []
    max_force = 0.0
    n = int(round(script.duration_s / sample_s))
    h = params.timestep_s
    for k in range(n):
        # the inputs follow the script at every plant step (a guide and a leg that move continuously,
        # not in sample_s jumps: a jump teleports links into the object, see docs/chain_model.md)
        t_end = (k + 1) * sample_s
        while plant.time_s + 0.5 * h < t_end:
            phase, inputs = grasp_inputs(script, plant.time_s, base_pos_m=base)
            plant.step(inputs)
        force = float(np.linalg.norm(plant.chain_object_net_force_n()[name]))
        max_force = max(max_force, force)
        com = plant.object_com_m(name)
        if phase == "pull":
            monitor.update(time_s=plant.time_s, object_com_m=com, base_pos_m=np.asarray(inputs.base_pos_m),
                           chain_force_n=force)
        trace.append(dict(time_s=plant.time_s, phase=phase, object_pos_m=com, chain_force_n=force,
                          guide_mm=inputs.guide_position_mm, base_pos_m=np.asarray(inputs.base_pos_m)))
        if on_sample is not None:
            on_sample(plant, phase)
    end = plant.object_com_m(name)
    follow = monitor.follow_ratio
    final_force = trace[-1]["chain_force_n"] if trace else 0.0
    mean_pull = monitor.mean_force_n
    secured = monitor.secured and not np.isnan(follow)
    return GraspOutcome(object_name=name, secured=bool(secured), follow_ratio=follow,
                        final_chain_force_n=float(final_force), mean_pull_force_n=mean_pull,
                        touching_fraction=monitor.touching_fraction, drag_force_n=drag,
                        max_chain_force_n=float(max_force),
                        object_displacement_m=end - start, trace=trace)
