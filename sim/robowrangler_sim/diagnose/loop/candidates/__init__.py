"""The loop's candidate effects (one class per file), keyed by id; `wrangler diagnose --effects` selects among them
and the drive library's ids."""

from __future__ import annotations

from robowrangler_sim.diagnose.loop.candidates.axial_drag_coefficient import AxialDragCoefficient
from robowrangler_sim.diagnose.loop.candidates.base import LoopCandidate
from robowrangler_sim.diagnose.loop.candidates.gyroscopic_base_rotation import GyroscopicBaseRotation
from robowrangler_sim.diagnose.loop.candidates.loop_speed_dependence import LoopSpeedDependence
from robowrangler_sim.diagnose.loop.candidates.normal_drag_coefficient import NormalDragCoefficient
from robowrangler_sim.diagnose.loop.candidates.out_of_plane_stiffness import OutOfPlaneStiffness
from robowrangler_sim.diagnose.loop.candidates.tip_bending_stiffness import TipBendingStiffness
from robowrangler_sim.diagnose.loop.candidates.transient_wave_dynamics import TransientWaveDynamics
from robowrangler_sim.diagnose.loop.candidates.uniform_wind import UniformWind

LOOP_LIBRARY: dict[str, type[LoopCandidate]] = {c.effect_id: c for c in (
    LoopSpeedDependence, AxialDragCoefficient, NormalDragCoefficient, TipBendingStiffness, TransientWaveDynamics,
    UniformWind, OutOfPlaneStiffness, GyroscopicBaseRotation)}

__all__ = ["LOOP_LIBRARY", "LoopCandidate"]
