"""tip_bending_stiffness: the rope's bending stiffness B = EI differs from the table rope's B0. On the running rope
the effective tension T - lambda v^2 is negative along the outgoing (upper) branch (compressed in the moving frame:
bending there makes waves of length 2 pi sqrt(B / |T_e|)), crosses zero at the tip (rounded over (B / T_e')^(1/3),
T_e' ~ the axial drag per metre 0.5 rho C_f pi d v^2) and is positive along the returning branch (boundary layers of
sqrt(B / T_e)); the tangent is clamped by the guide at both ends. Law: the Euler-Bernoulli balance of the running
rope, (B theta' + tau_B B v theta'')' = t x F with F = R + lambda g s e_z + f_t (p(s) - p(0)) (tau_B the rope's
internal bending damping, which carries the upper branch's waves downstream), solved to first order about the
table's shape (diagnose/loop/moving_elastica.py); B0 leaves the table unchanged."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.parameters import ParamSpec


class TipBendingStiffness(LoopCandidate):
    effect_id = "tip_bending_stiffness"
    law = ("(B theta' + tau_B B v theta'')' = t x F, F = R + lambda g s e_z + f_t (p(s) - p(0)), f_t = 0.5 rho C_f pi "
           "d v^2: the running rope's Euler-Bernoulli balance about the table's shape, at stiffness B instead of B0")
    regime = "every airborne speed: the tip (T - lambda v^2 crosses zero) and the compressed upper branch"
    params = (ParamSpec("bending_stiffness_n_m2", sm.TH_BEND_N_M2, "N m^2", 1.0, 200.0, 5.0e-6, relative=True),)
    """From the table rope's B0 up to 200 B0: a softer rope's bending lengths (B0's ~1 cm at the exit, ~4 cm at the
    tip at 5 m/s) are below the contour's point spacing (5 cm over a 2 m loop), so the law cannot tell them apart."""
    separating_measurement = ("contours at two rope speeds (the bending's share falls with the drag f_t ~ v^2, a C_f "
                              "or wind change grows with it)")
    confused_with = ("axial_drag_coefficient", "uniform_wind")

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        # the response passes through the compressed branch's buckling resonances as B grows (not monotonic in B):
        # a log-spaced ladder of starts, each refined locally
        b0 = theta[sm.TH_BEND_N_M2]
        return np.array([[b0 * f] for f in np.geomspace(2.0, 100.0, 28)])
