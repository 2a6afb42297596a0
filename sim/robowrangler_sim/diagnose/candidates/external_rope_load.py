"""external_rope_load: a force on the rope over one stretch of the run (a snag, a hand, an object), F_ext there.

The stretch is fitted with the force: a window t0..t1 with logistic edges (drive_batch EXT_EDGE_S), started from a
coarse grid of windows over the recording, so a load is found where it acts even when the residual alone does
not flag it (a speed loop that pushes against the load hides most of the speed dip). Confined to a speed range
(gates.py), the load acts only within its stretch while the rope runs in that range (a snag that holds only a fast
rope, an object dragged only above its breakaway speed).
"""

from __future__ import annotations

import itertools

import numpy as np

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability
from robowrangler_sim.diagnose.parameters import ParamSpec
from robowrangler_sim.plants import drive_batch as db


START_LOAD_N = 0.3
"""The force of every start window (the proof's loads are 0.3-0.6 N, 0.03-0.06 N under the noise)."""


class ExternalRopeLoad(Candidate):
    effect_id = "external_rope_load"
    law = "F_ext over t0..t1 (logistic edges of 30 ms), 0 elsewhere"
    channels = ("rope_speed_mps", "motor_rpm", "battery_v")
    regime = "one stretch of the run (loaded)"
    params = (ParamSpec("external_load_n", db.TH_EXT_LOAD, "N", 0.0, 5.0, 0.3),
              ParamSpec("load_start_s", db.TH_EXT_T0, "s", 0.0, 1.0, 1.0),
              ParamSpec("load_end_s", db.TH_EXT_T1, "s", 0.0, 1.0, 1.0))
    neutral = {db.TH_EXT_LOAD: 0.0, db.TH_EXT_T0: 0.0, db.TH_EXT_T1: 0.0}
    separating_measurement = "rope tension at the guide (spindle load) or a camera on the rope during the span"
    confused_with = ("coulomb_friction_n",)
    gateable = True
    project_starts = True
    time_params = ("load_start_s", "load_end_s")
    """Parameters on the replay's time grid (the report shifts them onto the recording's clock)."""

    def identifiable(self, data) -> Identifiability:
        # the window's bounds are the replay grid of this recording
        self._grid_s = data.pulse_us.size * 1e-3
        pre = data.preroll_ticks * 1e-3
        self.params = (self.params[0],
                       ParamSpec("load_start_s", db.TH_EXT_T0, "s", pre, self._grid_s, 1.0),
                       ParamSpec("load_end_s", db.TH_EXT_T1, "s", pre, self._grid_s, 1.0))
        return Identifiability(True)

    def start_grid(self, theta: np.ndarray) -> tuple[list[int], np.ndarray]:
        lo, hi = self.params[1].lo, self.params[1].hi
        # one force: the windows are ranked with the nominal parameters re-adjusted to each (ModelFitter's projected
        # starts), which matters more than the force's level, and the solver sets the force
        rows = [[START_LOAD_N, t0, min(hi, t0 + length)] for t0, length in
                itertools.product(np.arange(lo + 0.5, hi - 0.5, 1.0), (1.0, 2.0, 3.5))]
        return [db.TH_EXT_LOAD, db.TH_EXT_T0, db.TH_EXT_T1], np.asarray(rows)

    def untested_reason(self, values: dict[str, float], *, heldout_gap_s: float) -> str | None:
        """A window no longer than the gap between held-out blocks can sit wholly in fit samples: a force there is
        a correction of one transient, never tested on held-out data."""
        length_s = values["load_end_s"] - values["load_start_s"]
        if length_s <= heldout_gap_s:
            return (f"the load's window ({length_s:.2f} s) is no longer than the {heldout_gap_s:g} s between held-out "
                    "blocks: never tested on held-out samples")
        return None

    def starts_in_gate(self, grid: np.ndarray, mask_on: np.ndarray) -> np.ndarray:
        """Confined to a regime, the windows where the gate is open on at least half the ticks (elsewhere the
        window is mostly no load at all, and a window that holds the open part better is in the grid)."""
        on = np.concatenate(([0.0], np.cumsum(np.asarray(mask_on, dtype=float))))
        tick_s = db.TICK_US * 1e-6
        i0 = np.clip(np.round(grid[:, 1] / tick_s).astype(int), 0, on.size - 1)
        i1 = np.clip(np.round(grid[:, 2] / tick_s).astype(int), 0, on.size - 1)
        share = (on[i1] - on[i0]) / np.maximum(i1 - i0, 1)
        return grid[share >= 0.5]
