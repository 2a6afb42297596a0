"""Wrangling scenarios with the firmware in the loop (issue 5): the rope chain as the SIL plant.

- chain_bridge.ChainBridge: steps the ChainPlant in lockstep with a SilSession and couples the chain's
  loads back into the spindle and drive plants (the coupling law is in its docstring).
- base_trajectory.BaseTrajectory: the robot's leg (module pose over time).
- catalogue: the scenarios by name; runner.run_scenario(name, seed=...) -> ScenarioOutcome.
- table_i_sil: Table I through the firmware-driven scenarios (docs/table_i.md).
- viewer.ScenarioViewer: MuJoCo's interactive viewer following a scenario's chain (``--viewer``; needs a display).
"""

from robowrangler_sim.scenarios.catalogue import SCENARIOS, ScenarioError, ScenarioSpec, get_scenario, scenario_names
from robowrangler_sim.scenarios.runner import ScenarioOutcome, run_scenario

__all__ = ["SCENARIOS", "ScenarioError", "ScenarioOutcome", "ScenarioSpec", "get_scenario", "run_scenario",
           "scenario_names"]
