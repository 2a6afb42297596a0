"""axial_drag_coefficient: the rope's skin-friction coefficient C_f differs from the model's. The axial drag that
lifts the loop is 0.5 rho C_f pi d v^2 per metre against lambda g, so the shape depends on v^2 C_f: the loop at
speed v looks like the table's at v sqrt(C_f / C_f0) (and the takeoff speed scales by sqrt(C_f0 / C_f)). S_lin is the
table continued in that ratio (linear in 1 / v^2, shape_model.LoopShapeModel._lin), so a lower C_f at the table's
lowest speed reaches below it. The string shooter keeps this similarity within 1-2 mm where C_f is lowered; raised by
20 % it leaves it by 5 mm at 4 m/s and 26-67 mm at 5 m/s (raised by 20-30 %), where its loop flutters (5-7 mm frame
to frame: the nip pushes the rope harder against the same momentum flux lambda v^2; bench_diagnose_loop.py --only
interp), which the law does not represent."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.parameters import ParamSpec


class AxialDragCoefficient(LoopCandidate):
    effect_id = "axial_drag_coefficient"
    law = ("S(v) = S_model(v) + S_lin(v sqrt(C_f/C_f0)) - S_lin(v): the lift ratio 0.5 rho C_f pi d v^2 / (lambda g); "
           "S_lin linear in 1/v^2")
    regime = "every airborne speed (the shape at v^2 C_f)"
    params = (ParamSpec("skin_friction_coeff", sm.TH_CF, "1", 0.02, 0.3, 0.08),)
    separating_measurement = "the loop at a tabulated speed (where speed interpolation changes nothing) or the takeoff speed"
    confused_with = ("loop_speed_dependence",)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        c0 = theta[sm.TH_CF]
        return np.array([[c0 * f] for f in (0.6, 0.8, 1.25, 1.6)])
