"""transient_wave_dynamics: the chain follows a new target shape through its servos' first-order lag (tau = kd/kp =
0.5 s, every point at once); a moving rope carries a change along itself from the exit (waves at v +- sqrt(T/lambda),
the material itself at v) and then settles. Law: each point follows the target delayed by s / c, s its arc distance
from the exit, c the wave speed, then through a first-order settling time tau_w that replaces the servos' kd/kp.

What the string-shooter truth does in a fast module turn (0.3 rad in 0.4 s at 5 m/s, noise-free): each point's
best pure delay grows from 0.06 s at 0.3 m from the exit to about 0.48 s at the tip and falls to 0.29 s near the
return. Its tension T runs from -2 mN at the exit (the nip pushes the rope: c = 0, the change is carried at v) to
lambda v^2 at the tip (the slow wave v - c stalls there) to +14 mN at the return (c = 8 m/s), so the tip settles
last, about exponentially, the swing damped by the air's normal drag (rho C_n d |u_n| / lambda = 6-13 /s at 0.5-1 m/s
of swing). The chain's servo lag (all points at once, bounded by the servos' 0.25-1 s) does not have that form,
and without the settling the delay alone ends the transient when the change has travelled (too early at the tip):
on the held-out frames after a turn the two forms came within 1 mm of each other, so normal_drag_coefficient's
lag (phi_eff = phi - tau_n dphi/dt through the servos) was named for some turns although the turn frames prefer the
travelling change by delta BIC 30 (bench/bench_diagnose_loop.py --cases fast_turns --candidates)."""

from __future__ import annotations

import numpy as np

from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.loop.candidates.base import Identifiability, LoopCandidate, rotation_frames
from robowrangler_sim.diagnose.parameters import ParamSpec


class TransientWaveDynamics(LoopCandidate):
    effect_id = "transient_wave_dynamics"
    law = ("P(t, s) = L_tau_w[P_target(t - s / c)]: a change travels from the exit along the loop at the wave speed c, "
           "then settles through a first-order lag tau_w (the swing damped by the air), in place of the servos' kd/kp")
    regime = "transients: the module turning, the speed changing"
    params = (ParamSpec("wave_speed_mps", sm.TH_WAVE_MPS, "m/s", 0.5, 40.0, 5.0),
              ParamSpec("settling_time_s", sm.TH_TAU_S, "s", 0.02, 1.0, 0.2))
    """The settling time takes the servo time constant's column (replacing the chain's refit of it, bounded to the
    servos' 0.25-1 s): after the change has arrived the rope settles by its own damping, not through servos."""
    neutral = {sm.TH_WAVE_MPS: 0.0}
    separating_measurement = "a fast module turn filmed at a higher frame rate (the change's travel along the arc)"
    confused_with = ("normal_drag_coefficient",)

    def identifiable(self, replay) -> Identifiability:
        d = replay.data
        dv = np.abs(np.diff(d.speed_mps)) / np.maximum(np.diff(d.time_s), 1e-6)
        if rotation_frames(replay) < 10 and np.sum(dv > 0.5) < 5:
            return Identifiability(False, "no transient: the module never turns and the speed never changes",
                                   "a recording with a module turn or a speed step while the loop flies")
        return Identifiability(True)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        return np.array([[c, t] for c in (2.0, 5.0, 10.0, 20.0) for t in (0.05, 0.15, 0.4)])
