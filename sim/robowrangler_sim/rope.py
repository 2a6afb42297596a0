"""The rope: one set of numbers for every model of it (drive plant, rope chain, first-principles string shooter).

The defaults are the paper's wool rope (0.221 g/m, 2 mm). Its axial skin-friction coefficient C_f is not
measured: it is the calibration that makes the takeoff condition f_t(v*) = lambda g hold at the measured ToV,
v* = 2.6 m/s, in standard air (docs/architecture.md, "One rope"): C_f pi d = 2 lambda g / (rho v*^2). What the models then
predict (a takeoff speed independent of loop length and launch angle, the drag the drive carries) follows from
that one number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

GRAVITY_MPS2 = 9.81
STANDARD_AIR_DENSITY_KG_PER_M3 = 1.204
"""Dry air at 20 degC, 101.325 kPa."""
MEASURED_TAKEOFF_SPEED_MPS = 2.6
"""ToV of the paper's rope, the calibration target of C_f."""
PAPER_ROPE_LINEAR_DENSITY_KG_PER_M = 0.221e-3
PAPER_ROPE_DIAMETER_M = 2.0e-3


def skin_friction_coeff_for_takeoff(takeoff_speed_mps: float, *,
                                    linear_density_kg_per_m: float = PAPER_ROPE_LINEAR_DENSITY_KG_PER_M,
                                    diameter_m: float = PAPER_ROPE_DIAMETER_M,
                                    air_density_kg_per_m3: float = STANDARD_AIR_DENSITY_KG_PER_M3,
                                    gravity_mps2: float = GRAVITY_MPS2) -> float:
    """C_f such that axial drag per metre equals weight per metre at takeoff_speed_mps:
    0.5 rho C_f pi d v*^2 = lambda g."""
    for name, value in (("takeoff_speed_mps", takeoff_speed_mps), ("linear_density_kg_per_m", linear_density_kg_per_m),
                        ("diameter_m", diameter_m), ("air_density_kg_per_m3", air_density_kg_per_m3)):
        if not (math.isfinite(value) and value > 0):
            raise RopeParamsError(f"{name}: expected a finite value > 0, got {value!r}")
    return 2.0 * linear_density_kg_per_m * gravity_mps2 / (
        air_density_kg_per_m3 * math.pi * diameter_m * takeoff_speed_mps ** 2)


class RopeParamsError(ValueError):
    """A RopeParams field is out of range; the message names the field, the expected range and the value."""


@dataclass(frozen=True)
class RopeParams:
    """The rope's material (SI units, suffix names the unit). Lengths of the loop belong to the device.

    Attributes:
        linear_density_kg_per_m: lambda, mass per metre (0.221 g/m measured).
        diameter_m: d: drag areas (pi d per metre wetted, d per metre projected); the chain's collision radius
            is d / 2.
        skin_friction_coeff: C_f of the axial (tangential) drag f_t = 0.5 rho C_f pi d |w_t| w_t; default: the
            calibration to ToV 2.6 m/s in standard air (module doc).
        normal_drag_coeff: C_n of the normal (pressure) drag f_n = 0.5 rho C_n d |w_n| w_n (a cylinder in
            cross-flow at Re ~ 300: about 1.2).
        bending_stiffness_n_m2: B = EI (first-principles model only).
        bending_damping_s: internal (Kelvin-Voigt) bending damping as a time constant eta_B / B, seconds.
        axial_stiffness_n: EA of the stiff axial spring (the rope is nearly inextensible).
        compression_stiffness_ratio: fraction of EA that resists compression (a rope pushed out of its guide tube
            resists a little before it buckles; 0 = pure string).
        axial_damping_ratio: Kelvin-Voigt damping of the axial spring, as a ratio of critical damping of the
            shortest (one-segment) axial mode.
    """

    linear_density_kg_per_m: float = PAPER_ROPE_LINEAR_DENSITY_KG_PER_M
    diameter_m: float = PAPER_ROPE_DIAMETER_M
    skin_friction_coeff: float = skin_friction_coeff_for_takeoff(MEASURED_TAKEOFF_SPEED_MPS)
    normal_drag_coeff: float = 1.2
    bending_stiffness_n_m2: float = 5.0e-7
    bending_damping_s: float = 0.002
    axial_stiffness_n: float = 5.0
    compression_stiffness_ratio: float = 0.01
    axial_damping_ratio: float = 0.3

    def __post_init__(self) -> None:
        _check("linear_density_kg_per_m", self.linear_density_kg_per_m, low_open=True)
        _check("diameter_m", self.diameter_m, low_open=True)
        _check("skin_friction_coeff", self.skin_friction_coeff)
        _check("normal_drag_coeff", self.normal_drag_coeff)
        _check("bending_stiffness_n_m2", self.bending_stiffness_n_m2)
        _check("bending_damping_s", self.bending_damping_s, high=1.0)
        _check("axial_stiffness_n", self.axial_stiffness_n, low_open=True)
        _check("compression_stiffness_ratio", self.compression_stiffness_ratio, high=1.0)
        _check("axial_damping_ratio", self.axial_damping_ratio, high=1.0)

    def with_(self, **changes) -> RopeParams:
        return replace(self, **changes)

    @property
    def radius_m(self) -> float:
        return 0.5 * self.diameter_m

    @property
    def cf_pi_d_m(self) -> float:
        """C_f pi d: axial drag per metre is 0.5 rho (C_f pi d) v^2."""
        return self.skin_friction_coeff * math.pi * self.diameter_m

    def axial_drag_n_per_m(self, rope_speed_mps: float, *,
                           air_density_kg_per_m3: float = STANDARD_AIR_DENSITY_KG_PER_M3) -> float:
        """Skin-friction drag per metre of rope running axially at rope_speed_mps through still air."""
        return 0.5 * air_density_kg_per_m3 * self.cf_pi_d_m * rope_speed_mps * abs(rope_speed_mps)

    def takeoff_speed_mps(self, *, air_density_kg_per_m3: float = STANDARD_AIR_DENSITY_KG_PER_M3,
                          gravity_mps2: float = GRAVITY_MPS2) -> float:
        """v* where axial drag per metre equals weight per metre: sqrt(2 lambda g / (rho C_f pi d)); inf without
        axial drag (no air, or C_f = 0: the loop never lifts)."""
        k = air_density_kg_per_m3 * self.cf_pi_d_m
        if k <= 0:
            return math.inf
        return math.sqrt(2.0 * self.linear_density_kg_per_m * gravity_mps2 / k)


def _check(name: str, value: float, *, low_open: bool = False, high: float = math.inf) -> None:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    ok = ok and (value > 0.0 if low_open else value >= 0.0) and value <= high
    if not ok:
        bound = "(0" if low_open else "[0"
        raise RopeParamsError(f"{name}: expected a value in {bound}, {high}], got {value!r}")
