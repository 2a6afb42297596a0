"""Spindle plant: AX-12A in wheel mode -> lead screw -> rope guide -> loop length, with its registers.

What the firmware sees is register values, so the plant produces them as the servo would:

- Wheel mode is open-loop drive: the moving-speed register (0-1023, bit 10 = clockwise) sets the output
  fraction u; the geared motor follows a linear torque-speed line, tau = tau_stall (u - w / w0), with a
  small time constant, against the lead screw's friction and the rope's pull on the guide.
- Present position: 0-1023 over 0-300 degrees with reading noise; in the 60 degree dead zone the register
  holds garbage (uniform random here, the worst case the firmware must survive).
- Present speed: 0.111 rpm a unit, bit 10 = clockwise. Present load: the output torque over the stall
  torque in 0.1 % units, bit 10 = clockwise (the servo's estimate, with noise).
- The guide travels lead_mm_per_rev per output revolution (counter-clockwise = retract = +mm) between hard
  end stops at 0 and stroke_mm; the home limit switch closes within switch_travel_mm of 0 when fitted.
- Loop length = rope outside at guide 0 minus rope_per_guide_mm x guide position (both strands pass the
  guide). The rope's pull on the guide comes from outside when the input guide_load_n is given (the rope chain
  in a wrangling scenario); otherwise from a stand-in object of circumference object_circumference_m: once the
  loop is shorter than that, the rope stretches around it (stiffness rope_wrap_stiffness_n_per_m).

Two terms are off in the nominal plant and set by a diagnosed model (SpindleParams): a servo dead band
(moving speeds up to servo_deadband_raw do not drive; once stopped, the servo drives again only above dead band
+ servo_deadband_hysteresis_raw) and lead-screw backlash (screw_backlash_mm of lost motion between the servo
output, whose angle the position register reads, and the nut: after a reversal the servo turns through the gap
without the screw's friction and the rope's pull, so its load reads about 0, then takes the nut along).
``nut_position_mm`` is where the guide really is; the loop length follows it.

Numbers: AX-12A datasheet (ROBOTIS e-manual): stall torque 1.5 N m and no-load speed 59 rpm at 12 V,
300 degree position range, 0.111 rpm speed unit. Lead screw: a T8 screw, 8 mm lead, efficiency about 0.35
(trapezoidal thread, bronze nut). Friction and stiffness values are typical; diagnose can fit them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True, kw_only=True)
class SpindleInputs:
    """What drives the spindle plant over one step (the plant contract, plants/contract.py).

    Attributes:
        moving_speed_raw: the AX-12A moving-speed register the firmware writes (wheel mode): 0-1023, bit 10 = cw.
        guide_load_n: pull of the rope on the guide, N (>= 0), resisting retraction, from another plant (the rope
            chain); None: the plant's own stand-in object (object_circumference_m) decides it.
    """

    moving_speed_raw: int
    guide_load_n: float | None = None


@dataclass(frozen=True, kw_only=True)
class SpindleOutputs:
    """The spindle plant's outputs at the end of a step.

    Attributes:
        guide_position_mm: guide travel from the home stop (+ = retracted, smaller loop).
        loop_length_m: rope loop outside the device.
        output_angle_deg, speed_rpm, torque_nm: the servo's output shaft (torque = what its load estimate reads).
        rope_tension_n: tension of each strand of the rope on the guide, N.
        position_raw, speed_raw, load_raw: the AX-12A's present-position / speed / load registers (sensors).
        answering: the servo answers on its bus (False: silent, e.g. after a brown-out).
        limit_switch: the home switch is closed (only when fitted).
        moving_speed_raw: the input in force over the step.
    """

    guide_position_mm: float
    loop_length_m: float
    output_angle_deg: float
    speed_rpm: float
    torque_nm: float
    rope_tension_n: float
    position_raw: int
    speed_raw: int
    load_raw: int
    answering: bool
    limit_switch: bool
    moving_speed_raw: int


class SpindleParamsError(ValueError):
    """A spindle parameter is out of its physical range; the message names it."""


@dataclass(frozen=True)
class SpindleParams:
    stall_torque_nm: float = 1.5            # AX-12A at 12 V (datasheet)
    no_load_speed_rpm: float = 59.0         # AX-12A at 12 V (datasheet)
    response_time_s: float = 0.02           # geared motor speed time constant (typical)
    lead_mm_per_rev: float = 8.0            # T8 lead screw
    screw_efficiency: float = 0.35          # trapezoidal thread, bronze nut
    friction_torque_nm: float = 0.05        # screw + guide friction at the servo output (typical)
    stroke_mm: float = 180.0                # guide travel between the hard stops
    end_stop_margin_mm: float = 0.0         # hard stops this far outside 0 and stroke_mm
    position_noise_units: float = 0.6       # present-position reading noise, register units (1 sigma)
    load_noise_permille: float = 8.0        # present-load estimate noise (1 sigma)
    switch_fitted: bool = False             # home limit switch
    switch_travel_mm: float = 0.5           # switch closes this close to the home stop
    rope_outside_at_home_m: float = 2.0     # loop length with the guide at 0
    rope_per_guide_mm: float = 2.0          # rope drawn in per mm of guide travel (two strands)
    rope_wrap_stiffness_n_per_m: float = 3000.0  # rope + object compliance once the loop is tight
    start_angle_deg: float = 120.0          # output angle at power-up (0 = position register 0)
    # terms `wrangler diagnose` may add (0 = off, the nominal plant):
    servo_deadband_raw: float = 0.0         # wheel-mode moving speeds up to this magnitude do not drive the servo
    servo_deadband_hysteresis_raw: float = 0.0  # once stopped, it drives again only above dead band + this
    screw_backlash_mm: float = 0.0          # lost motion between the servo output (where position is read) and the nut

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool):
                continue
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise SpindleParamsError(f"{f.name}: expected a finite number, got {value!r}")
        for name in ("stall_torque_nm", "no_load_speed_rpm", "response_time_s", "lead_mm_per_rev", "stroke_mm",
                     "rope_outside_at_home_m", "rope_per_guide_mm", "rope_wrap_stiffness_n_per_m"):
            if getattr(self, name) <= 0:
                raise SpindleParamsError(f"{name}: expected > 0, got {getattr(self, name)!r}")
        for name in ("servo_deadband_hysteresis_raw", "screw_backlash_mm"):
            if getattr(self, name) < 0:
                raise SpindleParamsError(f"{name}: expected >= 0, got {getattr(self, name)!r}")
        if not 0 <= self.servo_deadband_raw < 1023:
            raise SpindleParamsError(f"servo_deadband_raw: expected in [0, 1023), got {self.servo_deadband_raw!r}")
        if not 0 < self.screw_efficiency <= 1:
            raise SpindleParamsError(f"screw_efficiency: expected in (0, 1], got {self.screw_efficiency!r}")


class SpindlePlant:
    """The spindle, stepped by the SIL.

    The contract (plants/contract.py): ``update(SpindleInputs, dt_s) -> SpindleOutputs``, ``outputs()``,
    ``reset()``. ``step(dt_s)`` with moving_speed_raw / guide_load_n set as attributes is the same integration.
    The scene, set between steps: object_circumference_m (the stand-in object). Faults a scenario can inject:
    stalled (the output is blocked), answering (False: the servo is silent).
    """

    def __init__(self, params: SpindleParams | None = None, *, seed: int = 0) -> None:
        self.params = params or SpindleParams()
        self.seed = int(seed)
        p = self.params
        self._w0_rad_s = p.no_load_speed_rpm * _TWO_PI / 60.0
        self._mm_per_rad = p.lead_mm_per_rev / _TWO_PI
        self.object_circumference_m: float | None = None
        self.stalled = False
        self.answering = True
        self.reset()

    def reset(self) -> None:
        """Back to power-up: the guide mid-stroke (homing must find 0), at rest, same seed. The scene
        (object_circumference_m) and injected faults (stalled, answering) are left as they are."""
        p = self.params
        self._rng = np.random.default_rng(self.seed + 7919)
        # the guide starts somewhere mid-stroke: homing must find 0
        self.output_angle_deg = p.start_angle_deg
        self._home_angle_deg = p.start_angle_deg - 40.0 / self._mm_per_rad * 180.0 / math.pi
        self.speed_rad_s = 0.0
        self.torque_nm = 0.0
        self.moving_speed_raw = 0
        self._guide_load_n: float | None = None
        self._servo_on = False  # the dead band's state: driving or stopped
        self.play_mm = 0.0  # backlash gap taken up on the retract side (0..screw_backlash_mm); nut = guide - play
        self.rope_tension_n = 0.0
        self.position_raw = 0
        self.speed_raw = 0
        self.load_raw = 0
        self._update_registers()

    # ------------------------------------------------------------------ geometry
    @property
    def guide_position_mm(self) -> float:
        return (self.output_angle_deg - self._home_angle_deg) * math.pi / 180.0 * self._mm_per_rad

    @property
    def nut_position_mm(self) -> float:
        """Where the nut (and the rope guide) is: the servo-side position less the backlash gap."""
        return self.guide_position_mm - self.play_mm

    @property
    def loop_length_m(self) -> float:
        return self.params.rope_outside_at_home_m - self.params.rope_per_guide_mm * self.nut_position_mm * 1e-3

    @property
    def limit_switch(self) -> bool:
        return self.params.switch_fitted and self.guide_position_mm <= self.params.switch_travel_mm

    @property
    def speed_rpm(self) -> float:
        return self.speed_rad_s * 60.0 / _TWO_PI

    @property
    def guide_load_n(self) -> float | None:
        """The rope's pull on the guide from outside, N (>= 0), or None: the stand-in object decides it."""
        return self._guide_load_n

    @guide_load_n.setter
    def guide_load_n(self, value: float | None) -> None:
        if value is not None and not (isinstance(value, (int, float)) and not isinstance(value, bool)
                                      and math.isfinite(value) and value >= 0.0):
            raise ValueError(f"guide_load_n: expected a finite force >= 0 N or None, got {value!r}")
        self._guide_load_n = None if value is None else float(value)

    # ------------------------------------------------------------------ the contract
    def update(self, inputs: SpindleInputs, dt_s: float) -> SpindleOutputs:
        """The plant contract: advance dt_s (0 < dt_s <= 0.05 s) with ``inputs`` held; the outputs at the end."""
        if not isinstance(inputs, SpindleInputs):
            raise TypeError(f"inputs: expected SpindleInputs, got {type(inputs).__name__}")
        raw = inputs.moving_speed_raw
        if isinstance(raw, bool) or not isinstance(raw, (int, np.integer)) or not 0 <= raw <= 0x7FF:
            raise ValueError(f"moving_speed_raw: expected a register value 0..2047, got {raw!r}")
        self.moving_speed_raw = int(raw)
        self.guide_load_n = inputs.guide_load_n
        self.step(dt_s)
        return self.outputs()

    def outputs(self) -> SpindleOutputs:
        """The outputs now (the plant contract), without stepping."""
        return SpindleOutputs(guide_position_mm=self.guide_position_mm, loop_length_m=self.loop_length_m,
                              output_angle_deg=self.output_angle_deg, speed_rpm=self.speed_rpm,
                              torque_nm=self.torque_nm, rope_tension_n=self.rope_tension_n,
                              position_raw=self.position_raw, speed_raw=self.speed_raw, load_raw=self.load_raw,
                              answering=self.answering, limit_switch=self.limit_switch,
                              moving_speed_raw=self.moving_speed_raw)

    # ------------------------------------------------------------------ dynamics
    def _rope_force_n(self) -> float:
        """Pull of the rope on the guide (resisting retraction), N: the outside load if given, else the
        stand-in object's wrap."""
        if self._guide_load_n is not None:
            self.rope_tension_n = self._guide_load_n / self.params.rope_per_guide_mm
            return self._guide_load_n
        c = self.object_circumference_m
        if c is None:
            self.rope_tension_n = 0.0
            return 0.0
        stretch_m = c - self.loop_length_m
        self.rope_tension_n = self.params.rope_wrap_stiffness_n_per_m * stretch_m if stretch_m > 0 else 0.0
        return self.params.rope_per_guide_mm * self.rope_tension_n

    def _servo_fraction(self, raw: int) -> float:
        """Drive fraction u in [-1, 1] from the moving-speed register, through the dead band (with hysteresis)."""
        p = self.params
        m = raw & 0x3FF
        if self._servo_on:
            if m <= p.servo_deadband_raw:
                self._servo_on = False
        elif m > p.servo_deadband_raw + p.servo_deadband_hysteresis_raw:
            self._servo_on = True
        if not self._servo_on:
            return 0.0
        return m / 1023.0 * (-1.0 if raw & 0x400 else 1.0)

    def _engagement(self, u: float) -> float:
        """1 when the servo drives the nut (the gap is closed in the drive's direction), 0 inside the gap."""
        b = self.params.screw_backlash_mm
        if b <= 0.0:
            return 1.0
        if u > 0.0:
            return 1.0 if self.play_mm >= b - 1e-9 else 0.0
        if u < 0.0:
            return 1.0 if self.play_mm <= 1e-9 else 0.0
        return 1.0

    def _move_play(self, dx_mm: float) -> None:
        self.play_mm = min(max(self.play_mm + dx_mm, 0.0), self.params.screw_backlash_mm)

    def _equilibrium_rad_s(self, u: float, load_nm: float, engagement: float = 1.0) -> float:
        """Output speed where drive, rope load and friction balance: tau_s (u - w/w0) = load + f sgn(w).

        The lead screw is self-locking (efficiency < 0.5), so the rope cannot drive it backwards: the speed
        never takes the opposite sign of the drive, and with no drive the servo brakes to a stop."""
        p = self.params
        if u == 0.0 or self.stalled:
            return 0.0
        f = engagement * (p.friction_torque_nm if u > 0 else -p.friction_torque_nm)
        w = self._w0_rad_s * (u - (load_nm + f) / p.stall_torque_nm)
        return max(w, 0.0) if u > 0 else min(w, 0.0)

    def step(self, dt_s: float) -> None:
        """Advance dt_s seconds (0 < dt_s <= 0.05) with the current moving_speed_raw."""
        if not (isinstance(dt_s, (int, float)) and math.isfinite(dt_s) and 0 < dt_s <= 0.05):
            raise ValueError(f"dt_s: expected 0 < dt_s <= 0.05 s, got {dt_s!r}")
        p = self.params
        raw = int(self.moving_speed_raw)
        u = self._servo_fraction(raw)
        n = max(1, math.ceil(dt_s / 0.001))  # substeps: the end stops and the wrap stiffness are stiff
        h = dt_s / n
        alpha = 1.0 - math.exp(-h / p.response_time_s)
        lo, hi = -p.end_stop_margin_mm, p.stroke_mm + p.end_stop_margin_mm
        for _ in range(n):
            # rope pull on the guide -> torque at the servo output, resisting retraction
            engagement = self._engagement(u)
            load_nm = engagement * self._rope_force_n() * self._mm_per_rad * 1e-3 / p.screw_efficiency
            self.speed_rad_s += (self._equilibrium_rad_s(u, load_nm, engagement) - self.speed_rad_s) * alpha
            self.output_angle_deg += math.degrees(self.speed_rad_s * h)
            if p.screw_backlash_mm > 0.0:
                self._move_play(self.speed_rad_s * h * self._mm_per_rad)
            pos = self.guide_position_mm
            if pos < lo or pos > hi:  # hard end stop
                edge = lo if pos < lo else hi
                self.output_angle_deg = self._home_angle_deg + math.degrees(edge / self._mm_per_rad)
                self.speed_rad_s = 0.0
            # what the motor produces (the servo's load estimate reads this)
            self.torque_nm = p.stall_torque_nm * (u - self.speed_rad_s / self._w0_rad_s) if u != 0.0 else 0.0
        self._update_registers()

    def _update_registers(self) -> None:
        p = self.params
        a = self.output_angle_deg % 360.0
        if a < 300.0:
            pos = a * 1023.0 / 300.0 + self._rng.normal(0.0, p.position_noise_units)
            self.position_raw = int(min(1023, max(0, round(pos))))
        else:  # dead zone: the register means nothing
            self.position_raw = int(self._rng.integers(0, 1024))
        speed_units = min(1023, round(abs(self.speed_rpm) / 0.111))
        self.speed_raw = speed_units | (0x400 if self.speed_rad_s < 0 else 0)
        load = self.torque_nm / p.stall_torque_nm * 1000.0 + self._rng.normal(0.0, p.load_noise_permille)
        load_units = min(1023, round(abs(load)))
        self.load_raw = load_units | (0x400 if load < 0 else 0)
