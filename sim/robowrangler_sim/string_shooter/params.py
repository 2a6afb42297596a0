"""Parameters of the first-principles string shooter: rope, air, nip, module geometry, numerics.

Every number is SI and carries its unit in its name. The rope is the shared RopeParams (robowrangler_sim/rope.py:
the RoboWrangler wool rope, 0.221 g/m, with C_f calibrated so that the takeoff condition f_t(v*) = lambda g holds
at v* = 2.6 m/s in standard air); the other defaults are justified in docs/string_shooter.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

# RopeParams is the one rope of every model (robowrangler_sim/rope.py); ShooterParams.rope holds it
from robowrangler_sim.rope import GRAVITY_MPS2, STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams


class StringShooterParamError(ValueError):
    """A parameter is out of range; the message names the argument, the expected range and the value."""


def _check(name: str, value: float, *, low: float, high: float = math.inf, low_open: bool = False) -> None:
    ok = np.isfinite(value) if high == math.inf else True
    ok = ok and (value > low if low_open else value >= low) and value <= high
    if not ok:
        bound = f"({low}" if low_open else f"[{low}"
        raise StringShooterParamError(f"{name}: expected a value in {bound}, {high}], got {value!r}")


@dataclass(frozen=True)
class AirParams:
    """Still air (plus an optional uniform wind).

    Attributes:
        density_kg_per_m3: rho; 0 switches all air drag off (the loop must then hang).
        wind_mps: shape (3,), uniform air velocity in the world frame.
    """

    density_kg_per_m3: float = STANDARD_AIR_DENSITY_KG_PER_M3
    wind_mps: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        _check("density_kg_per_m3", self.density_kg_per_m3, low=0.0)
        if len(self.wind_mps) != 3 or not all(np.isfinite(self.wind_mps)):
            raise StringShooterParamError(f"wind_mps: expected 3 finite numbers, got {self.wind_mps!r}")


@dataclass(frozen=True)
class NipParams:
    """The wheel nip: it drives the interior rope toward the wheel surface speed, up to a friction limit.

    Attributes:
        grip_n_per_mps: slope of the traction force versus slip speed (viscous grip, stiff).
        max_traction_n: friction limit mu N of the nip; above it the rope slips.
    """

    grip_n_per_mps: float = 50.0
    max_traction_n: float = 0.3

    def __post_init__(self) -> None:
        _check("grip_n_per_mps", self.grip_n_per_mps, low=0.0, low_open=True)
        _check("max_traction_n", self.max_traction_n, low=0.0)


@dataclass(frozen=True)
class ModuleGeometry:
    """Where the rope leaves and re-enters the module, in the module frame.

    The module frame: e1 = launch axis (inclined phi above the horizontal, heading yaw), e2 = horizontal
    lateral axis, e3 = e1 x e2 ("up" at phi = 0). The guide eyelet sits on e1 at
    ``guide_base_m + guide_travel`` from the module origin; the rope leaves it ``exit_offset_m`` above
    the axis (along e3) and comes back ``return_offset_m`` below it. Inside the module the rope runs
    from the return point back to the nip and forward to the exit: ``interior_length_m`` at zero guide
    travel, 2 m more per metre of guide travel (both strands lengthen).

    Attributes:
        guide_base_m: eyelet distance from the module origin at zero guide travel.
        exit_offset_m, return_offset_m: half-separation of the two strands in the eyelet.
        interior_length_m: rope inside the module at zero guide travel.
        guide_stroke_m: admissible guide travel (spindle stroke).
        span_m: 0 (the product): one eyelet, the rope returns into it. > 0: a test rig with a separate
            return eyelet span_m ahead of the exit on the launch axis, the rope running on through it
            along e1 (a straight moving span, used for the wave test).
    """

    guide_base_m: float = 0.10
    exit_offset_m: float = 0.004
    return_offset_m: float = 0.004
    interior_length_m: float = 0.30
    guide_stroke_m: float = 0.18
    span_m: float = 0.0

    def __post_init__(self) -> None:
        _check("span_m", self.span_m, low=0.0)
        _check("guide_base_m", self.guide_base_m, low=0.0)
        _check("exit_offset_m", self.exit_offset_m, low=0.0)
        _check("return_offset_m", self.return_offset_m, low=0.0)
        _check("interior_length_m", self.interior_length_m, low=0.0, low_open=True)
        _check("guide_stroke_m", self.guide_stroke_m, low=0.0)


@dataclass(frozen=True)
class NumericsParams:
    """Discretisation.

    Attributes:
        segment_length_m: rest length of a rope segment (node spacing) in the air.
        cfl: time step as a fraction of the axial-wave crossing time of one segment (ds / sqrt(EA/lambda)).
        max_nodes: capacity of the node arrays.
    """

    segment_length_m: float = 0.025
    cfl: float = 0.4
    max_nodes: int = 4000

    def __post_init__(self) -> None:
        _check("segment_length_m", self.segment_length_m, low=1e-4, high=0.5)
        _check("cfl", self.cfl, low=0.0, high=0.9, low_open=True)
        if int(self.max_nodes) < 8:
            raise StringShooterParamError(f"max_nodes: expected >= 8, got {self.max_nodes!r}")


@dataclass(frozen=True)
class ShooterParams:
    """Everything the simulator needs besides the inputs (wheel speed, module motion)."""

    rope: RopeParams = field(default_factory=RopeParams)
    air: AirParams = field(default_factory=AirParams)
    nip: NipParams = field(default_factory=NipParams)
    geometry: ModuleGeometry = field(default_factory=ModuleGeometry)
    numerics: NumericsParams = field(default_factory=NumericsParams)
    gravity_mps2: float = GRAVITY_MPS2

    def __post_init__(self) -> None:
        _check("gravity_mps2", self.gravity_mps2, low=0.0)

    def with_(self, **changes) -> "ShooterParams":
        return replace(self, **changes)

    @property
    def time_step_s(self) -> float:
        """Explicit step, seconds: cfl x the axial-wave (sqrt(EA/lambda)) crossing time of one segment."""
        c_axial = math.sqrt(self.rope.axial_stiffness_n / self.rope.linear_density_kg_per_m)
        return self.numerics.cfl * self.numerics.segment_length_m / c_axial


def takeoff_speed_estimate_mps(rope: RopeParams, air: AirParams, *, gravity_mps2: float = GRAVITY_MPS2) -> float:
    """v* from f_t(v*) = lambda g: sqrt(2 lambda g / (rho C_f pi d)); inf when there is no axial drag."""
    return rope.takeoff_speed_mps(air_density_kg_per_m3=air.density_kg_per_m3, gravity_mps2=gravity_mps2)
