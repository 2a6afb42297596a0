"""The candidate-effect library: one class per effect, keyed by its stable id."""

from __future__ import annotations

from robowrangler_sim.diagnose.candidates.base import Candidate, Identifiability
from robowrangler_sim.diagnose.candidates.battery_sag import BatterySag
from robowrangler_sim.diagnose.candidates.encoder_quantisation import EncoderQuantisation
from robowrangler_sim.diagnose.candidates.esc_deadband import EscDeadband
from robowrangler_sim.diagnose.candidates.esc_latency import EscLatency
from robowrangler_sim.diagnose.candidates.external_rope_load import ExternalRopeLoad
from robowrangler_sim.diagnose.candidates.low_speed_friction import LowSpeedFriction
from robowrangler_sim.diagnose.candidates.motor_cogging import MotorCogging
from robowrangler_sim.diagnose.candidates.rope_drag_law import RopeDragLaw
from robowrangler_sim.diagnose.candidates.screw_backlash import ScrewBacklash
from robowrangler_sim.diagnose.candidates.servo_deadband import ServoDeadband
from robowrangler_sim.diagnose.candidates.wheel_slip import WheelSlip

LIBRARY: dict[str, type[Candidate]] = {c.effect_id: c for c in (
    RopeDragLaw, EscLatency, EscDeadband, BatterySag, LowSpeedFriction, ExternalRopeLoad, MotorCogging,
    EncoderQuantisation, WheelSlip)}
"""Every drive effect by id."""

SPINDLE_LIBRARY: dict[str, type[Candidate]] = {c.effect_id: c for c in (ScrewBacklash, ServoDeadband)}
"""Every spindle effect by id (fitted on the spindle channels by diagnose/spindle_stage.py)."""

__all__ = ["LIBRARY", "SPINDLE_LIBRARY", "Candidate", "Identifiability"]
