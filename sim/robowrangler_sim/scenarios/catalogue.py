"""The scenarios a user runs (``wrangler sil --scenario NAME``): one wrangle per Table I object, the door handle.

Every grasp scenario uses the same script (GraspScript defaults, as the plant-level Table I does) and the
same firmware settings; only the object differs. Nothing here depends on the object's shape class.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from robowrangler_sim.chain.door import DoorLeaf
from robowrangler_sim.chain.grasp import GraspScript
from robowrangler_sim.chain.table_i import TABLE_I_OBJECTS


class ScenarioError(ValueError):
    """Unknown scenario or bad scenario option; the message names the argument, the choices and the value."""


@dataclass(frozen=True, kw_only=True)
class ScenarioSpec:
    """One scenario.

    Attributes:
        name: what the user types.
        kind: "grasp" (loop around a free object on the floor, GRASP, pull) or "door" (loop over a door's
            lever handle, GRASP, pull).
        object_name: catalogue object (chain/objects.py).
        description: one line for --help.
        script: geometry and timing shared with the plant-level grasp (phi, roll, exit height, object
            position in the loop, airborne speed, hold and pull).
        firmware_params: PARAM_SET sent before homing, {name: value} (protocol units).
        chain_params: ChainParams overrides of this scenario, ((field, value), ...) (n_links comes from the run).
        door_leaf: kind "door": the leaf, hinge and closer the handle is on (chain/door.py); None = the
            catalogue's handle on a fixed door.
    """

    name: str
    kind: str
    object_name: str
    description: str
    script: GraspScript = field(default_factory=GraspScript)
    firmware_params: tuple[tuple[str, float], ...] = ()
    chain_params: tuple[tuple[str, float], ...] = ()
    door_leaf: DoorLeaf | None = None


GRASP_FIRMWARE_PARAMS = (("homing_speed_mmps", 10.0), ("retract_speed_mmps", 15.0), ("guide_max_mm", 178.0))
"""Homing and retracting faster than the defaults (3 and 5 mm/s; the AX-12A tops out at 59 rpm x 8 mm = 7.9
mm/s unloaded, so 15 means "full speed"), so that a scenario takes seconds, not minutes. The soft limit 2 mm
short of the lead screw's hard stop: with the default 180 mm (= the hard stop) a retract with nothing to
hold stalls on the stop before its noisy position reads 180, and the stall load is taken for a secured
object (LOAD_SECURED at the end stop; seen in this SIL, reported in docs/table_i.md)."""

DOOR_FIRMWARE_PARAMS = GRASP_FIRMWARE_PARAMS + (("grasp_secure_load_pct", 5.0),)
"""The whole stroke (178 mm, as every grasp) and the secure threshold at its minimum, 5 %: the AX-12A's load
register reads (screw friction 0.05 N m + F x 8 mm / 2 pi / 0.35) / 1.5 N m, so 5 % means a guide load of
(0.075 - 0.05) / 0.003638 = 6.9 N (3.4 N in each strand) held for spindle_stall_time_s (0.3 s). The default 12 %
means 35.7 N on the guide: more than this chain keeps on a 19 mm bar (docs/table_i.md, door section)."""

DOOR_CHAIN_PARAMS = (("timestep_s", 0.002),)
"""The door's chain steps at 2 ms instead of 5 ms. Why: once the loop is taut on the bar, the bar sits in the V of
two 10 cm links near the loop's middle joint, and the soft closure leaves the lower strand nearly slack, so the
upper strand drags the rope round the bar (capstan: T1 / T2 far over e^(0.3 pi) = 2.6); 10 cm links can only
pass round a 19 mm bar through it. At 5 ms MuJoCo lets the bar through link 10 at about 12 N of guide load
(penetration 4-7 mm), at 2 ms (and 1 ms) at about 27 N, over the 6.9 N the firmware needs for LOAD_SECURED."""

DOOR_LEAF = DoorLeaf(closing_moment_nm=7.0, closer_stiffness_nm_per_rad=5.0, hinge_friction_nm=0.5)
"""The door the handle is on: an 0.86 m x 2.0 m, 25 kg leaf on hinges 0.80 m from the handle, held shut by a
light closer: 7 N m with the door shut (+ 5 N m/rad as it opens, 0.5 N m hinge friction): 9.4 N square to the
leaf at the handle to open it, a light interior door (BS 8300 / Approved Document M allow up to 30 N at the
handle for 0-30 deg). The leaf moves on a real MuJoCo hinge (chain/door.py). Why a door that gives: pinned
between the module and a welded bar, the inextensible chain can only take the guide's shortening in its
contact with the bar. Why this closer: the door is chosen where this chain model can open it. The guide load at
which the leaf starts to move (about 12 N: the rope pulls up and back from the module 0.41 m above the bar, so
more than the 10.4 N square to the leaf at the bar) must be about what the firmware needs to see sustained
(5 %: 6.9 N mean, about 12-14 N to pass 30 noisy 10 ms reads in a row), and the pull that opens the door must
stay under the ~20-27 N at which the bar passes a link of the 2 ms chain. With 7 N m the door is still (within
a degree) shut when RETRACT ends on LOAD_SECURED and the pull peaks near 18.5 N. A 9 N m closer (11.9 N) held
here too, but its pull peaked near 21 N, at the edge: lost in the pull in 4 of 5 N = 20 rollouts with the
rope on the floor and the module moving with a real velocity (docs/chain_model.md); 7 N m held in all of them. Heavier doors
(a 20 N m closer: 25.6 N) are outside what this chain model can open (docs/table_i.md)."""

DOOR_PULL_M = 0.2
"""The robot's pull once the firmware holds: 0.2 m back over 2 s, about 15 degrees of the leaf at 0.80 m."""


def _catalogue() -> dict[str, ScenarioSpec]:
    specs = [ScenarioSpec(name=obj, kind="grasp", object_name=obj,
                          description=f"lasso the {obj.replace('_', ' ')} on the floor, GRASP, pull it 30 cm",
                          firmware_params=GRASP_FIRMWARE_PARAMS)
             for obj in TABLE_I_OBJECTS]
    specs.append(ScenarioSpec(name="door_handle", kind="door", object_name="door_handle",
                              description="thread the loop over a door's lever handle, GRASP until the load says "
                                          "secured (HOLD), pull the door open 0.2 m",
                              script=GraspScript(phi_deg=0.0, roll_deg=0.0, pull_s=2.0, pull_m=DOOR_PULL_M,
                                                 retract_guide_mm=178.0),
                              firmware_params=DOOR_FIRMWARE_PARAMS, chain_params=DOOR_CHAIN_PARAMS,
                              door_leaf=DOOR_LEAF))
    return {s.name: s for s in specs}


SCENARIOS: dict[str, ScenarioSpec] = _catalogue()


def scenario_names() -> tuple[str, ...]:
    return tuple(SCENARIOS)


def get_scenario(name: str) -> ScenarioSpec:
    """The scenario called name; ScenarioError naming the choices otherwise."""
    try:
        return SCENARIOS[name]
    except (KeyError, TypeError):
        raise ScenarioError(f"scenario: expected one of {', '.join(SCENARIOS)}, got {name!r}") from None
