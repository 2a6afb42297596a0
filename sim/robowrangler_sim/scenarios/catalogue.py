"""The scenarios a user runs (``wrangler sil --scenario NAME``): one wrangle per Table I object, the door handle.

Every grasp scenario uses the same script (GraspScript defaults, as the plant-level Table I does) and the
same firmware settings; only the object differs. Nothing here depends on the object's shape class.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from robowrangler_sim.chain.grasp import GraspScript
from robowrangler_sim.chain.table_i import TABLE_I_OBJECTS


class ScenarioError(ValueError):
    """Unknown scenario or bad scenario option; the message names the argument, the choices and the value."""


@dataclass(frozen=True, kw_only=True)
class ScenarioSpec:
    """One scenario.

    Attributes:
        name: what the user types.
        kind: "grasp" (loop around a free object on the floor, GRASP, pull) or "door" (loop over a fixed
            lever handle, GRASP, pull).
        object_name: catalogue object (chain/objects.py).
        description: one line for --help.
        script: geometry and timing shared with the plant-level grasp (phi, roll, exit height, object
            position in the loop, airborne speed, hold and pull).
        firmware_params: PARAM_SET sent before homing, {name: value} (protocol units).
    """

    name: str
    kind: str
    object_name: str
    description: str
    script: GraspScript = field(default_factory=GraspScript)
    firmware_params: tuple[tuple[str, float], ...] = ()


GRASP_FIRMWARE_PARAMS = (("homing_speed_mmps", 10.0), ("retract_speed_mmps", 15.0), ("guide_max_mm", 178.0))
"""Homing and retracting faster than the defaults (3 and 5 mm/s; the AX-12A tops out at 59 rpm x 8 mm = 7.9
mm/s unloaded, so 15 means "full speed"), so that a scenario takes seconds, not minutes. The soft limit 2 mm
short of the lead screw's hard stop: with the default 180 mm (= the hard stop) a retract with nothing to
hold stalls on the stop before its noisy position reads 180, and the stall load is taken for a secured
object (LOAD_SECURED at the end stop; seen in this SIL, reported in docs/table_i.md)."""

DOOR_FIRMWARE_PARAMS = GRASP_FIRMWARE_PARAMS + (("guide_max_mm", 60.0), ("grasp_secure_load_pct", 5.0))
"""The lever sits 4 cm inside the loop's tip: 60 mm of guide (12 cm of rope) tightens the loop on it; the
secure threshold at its minimum (5 %: about 7 N on the guide) so RETRACT can stop on the handle's load."""


def _catalogue() -> dict[str, ScenarioSpec]:
    specs = [ScenarioSpec(name=obj, kind="grasp", object_name=obj,
                          description=f"lasso the {obj.replace('_', ' ')} on the floor, GRASP, pull it 30 cm",
                          firmware_params=GRASP_FIRMWARE_PARAMS)
             for obj in TABLE_I_OBJECTS]
    specs.append(ScenarioSpec(name="door_handle", kind="door", object_name="door_handle",
                              description="thread the loop over a door's lever handle, GRASP, pull 5 cm",
                              script=GraspScript(phi_deg=0.0, roll_deg=0.0, pull_s=1.0, pull_m=0.05,
                                                 retract_guide_mm=60.0),
                              firmware_params=DOOR_FIRMWARE_PARAMS))
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
