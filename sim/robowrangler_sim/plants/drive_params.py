"""Parameters of the drive plant: ESC, two BLDC motors with wheels, the rope they pinch, the battery, the encoder.

Every field carries its unit in its name; the comment after it says where the number comes from
(docs/drive_plant.md gives the longer derivations). "Class estimate" marks a number picked as typical
for the hardware class, not read from a datasheet of the exact part: the diagnose tool is meant to
fit such numbers from recordings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from robowrangler_sim.rope import STANDARD_AIR_DENSITY_KG_PER_M3, RopeParams

# Motor constant of a 1250 rpm/V motor (T-MOTOR AS2317 is sold in 880/1250/1400 KV; 1250 KV gives the
# 15000 rpm maximum at 12 V). Kt = Ke = 1 / (Kv in rad/s/V) = 60 / (2 pi 1250) = 7.64e-3 N m/A.
_KV_RPM_PER_V = 1250.0
_KT_NM_PER_A = 60.0 / (2.0 * math.pi * _KV_RPM_PER_V)
# No-load current class estimate for a 23xx outrunner of this KV: about 0.7 A at 10 V (12500 rpm,
# 1309 rad/s). 0.2 A of it is taken as speed-independent (bearings), 0.5 A as proportional to speed
# (iron losses, windage), so T_friction = Kt * (0.2 A) + Kt * (0.5 A) * omega / 1309 rad/s.
_NO_LOAD_OMEGA_RAD_S = 10.0 * _KV_RPM_PER_V * 2.0 * math.pi / 60.0
_COULOMB_NM = _KT_NM_PER_A * 0.2
_VISCOUS_NM_S_PER_RAD = _KT_NM_PER_A * 0.5 / _NO_LOAD_OMEGA_RAD_S


class DriveParamsError(ValueError):
    """A DriveParams field is out of range; the message names the field, the expected range and the value."""


@dataclass(frozen=True)
class DriveParams:
    """Physical parameters of the rope drive (SI units, unit suffix on every name).

    The plant treats the two motors as identical and rigidly coupled through the rope (no wheel-rope
    slip): one rotational degree of freedom, the wheel angle. Torques and currents are per motor unless a
    name says otherwise.
    """

    # --- motors (per motor; T-MOTOR AS2317-class outrunner, 1250 KV) ---
    motor_count: int = 2
    """Motors driving the rope, all with the same ESC command (hardware: two, pinching the rope)."""
    motor_kv_rpm_per_v: float = _KV_RPM_PER_V
    """Speed constant: 15000 rpm maximum / 12 V = 1250 rpm/V, an AS2317 KV option."""
    motor_resistance_ohm: float = 0.075
    """Winding resistance line to line. Class estimate for a 23xx 1250 KV outrunner (60-90 mOhm)."""
    esc_resistance_ohm: float = 0.010
    """ESC high+low side MOSFET on-resistance plus motor leads in series with the winding. Class estimate."""
    motor_coulomb_friction_nm: float = _COULOMB_NM
    """Speed-independent friction torque (bearings): Kt x 0.2 A of the ~0.7 A no-load current. Class estimate."""
    motor_viscous_friction_nm_s_per_rad: float = _VISCOUS_NM_S_PER_RAD
    """Speed-proportional loss torque (iron, windage): Kt x 0.5 A at 1309 rad/s. Class estimate."""
    rotor_inertia_kg_m2: float = 3.5e-6
    """Outrunner bell + magnets: about 20 g on a 12.5 mm mean radius (m r^2 = 3.1e-6) plus shaft."""
    wheel_inertia_kg_m2: float = 7.0e-7
    """15 mm rubber wheel: ~3.8 g tyre ring (r 10-15 mm, 8 mm wide) 6.2e-7 plus a ~2 g hub 1e-7."""
    wheel_radius_m: float = 0.015
    """Rubber wheel radius (hardware description)."""

    # --- rope ---
    rope: RopeParams = field(default_factory=RopeParams)
    """The rope's material: density (its mass adds to the inertia), diameter and C_f (its air drag, hence ToV);
    the one RopeParams of every model (robowrangler_sim/rope.py)."""
    rope_loop_length_m: float = 2.0
    """Closed loop length (hardware description); all of it moves, so its mass adds m r^2 to the inertia."""
    rope_exposed_length_m: float = 2.0
    """Rope length moving through air that carries skin-friction drag. Default: the whole loop."""
    air_density_kg_per_m3: float = STANDARD_AIR_DENSITY_KG_PER_M3
    """Dry air at 20 degC, 101.325 kPa."""
    guide_friction_n: float = 0.04
    """Coulomb friction of the rope in the guide, rope side. Class estimate (tension is only mN)."""
    nip_friction_n: float = 0.08
    """Rolling resistance of the two rubber wheels pinching the rope, rope side. Class estimate."""
    nip_viscous_n_s_per_m: float = 0.004
    """Speed-proportional part of the nip loss (rubber hysteresis), rope side. Class estimate."""
    airborne_hysteresis_mps: float = 0.05
    """loop_airborne turns on above ToV + this and off below ToV - this (plots only)."""

    # --- ESC (BLHeli_32, 400 Hz PWM input) ---
    esc_frame_us: int = 2500
    """Input PWM period: 400 Hz. The ESC takes a new pulse width once per frame."""
    esc_min_pulse_us: float = 1000.0
    """Zero-throttle pulse (BLHeli_32 default PWM range 1000-2000 us)."""
    esc_max_pulse_us: float = 2000.0
    """Full-throttle pulse; longer pulses give full throttle."""
    esc_invalid_below_us: float = 990.0
    """Pulses shorter than this (and no pulse, 0) are not a valid signal: the motor stops and the ESC disarms.
    10 us under the minimum so timer jitter at exactly 1000 us stays valid. Assumption."""
    esc_deadband_us: float = 10.0
    """Pulses up to min + deadband are zero throttle. Assumption (BLHeli: small zero-throttle zone)."""
    esc_arm_hold_us: int = 200_000
    """Valid zero-throttle signal needed before the ESC arms (BLHeli_32: about 200 ms; docs/drive_plant.md)."""
    esc_lag_s: float = 0.003
    """First-order lag from the latched throttle to the applied duty (ESC input filtering and commutation
    update), on top of the up-to-one-frame latching delay. Assumption."""
    esc_max_duty: float = 1.0
    """Duty at full throttle (BLHeli_32 reaches 100 %)."""
    esc_current_limit_a: float = 40.0
    """Phase-current clamp per motor, stand-in for BLHeli_32 current protection / ramp-up power limits on a
    35-45 A class ESC. Assumption."""
    esc_damped_light: bool = True
    """BLHeli damped light (complementary PWM): current may reverse, so a throttle drop brakes actively."""

    # --- battery (3S LiPo, 12 V class) ---
    battery_open_circuit_v: float = 12.0
    """Open-circuit voltage at start: 3S at 4.0 V/cell (12.6 V full, 11.1 V nominal); 12 V per the issue."""
    battery_internal_resistance_ohm: float = 0.030
    """Pack (3 cells of ~6 mOhm) plus XT60 and leads ~12 mOhm. Class estimate for a 1500 mAh 3S pack."""
    battery_capacity_ah: float = 1.5
    """Pack capacity (used only for state of charge). Class estimate."""
    battery_ocv_slope_v_per_ah: float = 0.85
    """Open-circuit voltage drop per Ah drawn: 3S LiPo plateau falls ~0.9 V over ~70 % of capacity."""
    battery_empty_v: float = 9.9
    """Open-circuit voltage floor (3.3 V/cell)."""
    battery_aux_current_a: float = 0.1
    """Other loads on the pack (board, encoder, ESC logic). Class estimate."""
    battery_adc_noise_v: float = 0.01
    """Standard deviation of the battery-voltage ADC reading. Assumption."""
    battery_adc_lsb_v: float = 16.5 / 4096.0
    """ADC step: 12-bit SAMD21 ADC at 3.3 V behind a 1:5 divider (16.5 V full scale). Assumption."""

    # --- encoder (magnetic, on one motor shaft) ---
    encoder_counts_per_rev: int = 64
    """Edges per shaft revolution (configurable; 16 lines x 4 quadrature edges; 16 kHz at 15000 rpm)."""

    # --- integration ---
    max_substep_s: float = 0.25e-3
    """Longest internal substep (a tenth of the fastest mechanical time constant is ~0.8 ms)."""
    max_step_s: float = 0.005
    """Longest dt_s accepted by DrivePlant.step."""

    def __post_init__(self) -> None:
        if not isinstance(self.rope, RopeParams):
            raise DriveParamsError(f"rope: expected RopeParams, got {self.rope!r}")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "rope":
                continue
            if f.type in ("bool", bool):
                if not isinstance(value, bool):
                    raise DriveParamsError(f"{f.name}: expected bool, got {value!r}")
                continue
            if f.type in ("int", int):
                if isinstance(value, bool) or not isinstance(value, int):
                    raise DriveParamsError(f"{f.name}: expected int, got {value!r}")
            if not isinstance(value, (int, float)) or not math.isfinite(value):
                raise DriveParamsError(f"{f.name}: expected a finite number, got {value!r}")
            nonneg = f.name in _NON_NEGATIVE
            if (value < 0.0) if nonneg else (value <= 0.0):
                expected = ">= 0" if nonneg else "> 0"
                raise DriveParamsError(f"{f.name}: expected {expected}, got {value!r}")
        if not self.esc_min_pulse_us < self.esc_max_pulse_us <= self.esc_frame_us:
            raise DriveParamsError(
                "esc_min_pulse_us < esc_max_pulse_us <= esc_frame_us expected, got "
                f"{self.esc_min_pulse_us}, {self.esc_max_pulse_us}, {self.esc_frame_us}")
        if not self.esc_invalid_below_us <= self.esc_min_pulse_us:
            raise DriveParamsError(
                f"esc_invalid_below_us: expected <= esc_min_pulse_us {self.esc_min_pulse_us}, "
                f"got {self.esc_invalid_below_us}")
        if not self.esc_deadband_us < self.esc_max_pulse_us - self.esc_min_pulse_us:
            raise DriveParamsError(f"esc_deadband_us: expected < pulse range, got {self.esc_deadband_us}")
        if self.esc_max_duty > 1.0:
            raise DriveParamsError(f"esc_max_duty: expected <= 1, got {self.esc_max_duty}")
        if self.rope_exposed_length_m > self.rope_loop_length_m:
            raise DriveParamsError(
                f"rope_exposed_length_m: expected <= rope_loop_length_m {self.rope_loop_length_m}, "
                f"got {self.rope_exposed_length_m}")
        if self.max_substep_s > self.max_step_s:
            raise DriveParamsError(f"max_substep_s: expected <= max_step_s {self.max_step_s}, got {self.max_substep_s}")

    # --- derived quantities (plain properties, not fields) ---
    @property
    def kv_rad_per_s_per_v(self) -> float:
        """Speed constant in rad/s per volt."""
        return self.motor_kv_rpm_per_v * 2.0 * math.pi / 60.0

    @property
    def torque_constant_nm_per_a(self) -> float:
        """Kt = Ke = 1 / Kv (SI), N m/A = V s/rad."""
        return 1.0 / self.kv_rad_per_s_per_v

    @property
    def circuit_resistance_ohm(self) -> float:
        """Winding plus ESC resistance in series, per motor."""
        return self.motor_resistance_ohm + self.esc_resistance_ohm

    @property
    def rope_linear_density_kg_per_m(self) -> float:
        """The rope's mass per metre (self.rope)."""
        return self.rope.linear_density_kg_per_m

    @property
    def rope_cf_pi_d_m(self) -> float:
        """C_f pi d of the rope (self.rope): axial drag per metre is 0.5 rho (C_f pi d) v^2."""
        return self.rope.cf_pi_d_m

    @property
    def takeoff_speed_mps(self) -> float:
        """ToV: the loop lifts above this rope speed, where axial drag per metre equals weight per metre in this
        air (2.6 m/s for the default rope in standard air: the calibration of C_f, robowrangler_sim/rope.py)."""
        return self.rope.takeoff_speed_mps(air_density_kg_per_m3=self.air_density_kg_per_m3)

    @property
    def rope_mass_kg(self) -> float:
        """Mass of the whole rope loop."""
        return self.rope_linear_density_kg_per_m * self.rope_loop_length_m

    @property
    def total_inertia_kg_m2(self) -> float:
        """All rotating and moving mass referred to one wheel shaft: motors, wheels, rope (m r^2)."""
        return (self.motor_count * (self.rotor_inertia_kg_m2 + self.wheel_inertia_kg_m2)
                + self.rope_mass_kg * self.wheel_radius_m ** 2)

    @property
    def rope_drag_coeff_n_s2_per_m2(self) -> float:
        """k in F_drag = k v^2 for the exposed rope: 0.5 rho C_f pi d L_exposed."""
        return 0.5 * self.air_density_kg_per_m3 * self.rope_cf_pi_d_m * self.rope_exposed_length_m


_NON_NEGATIVE = frozenset({
    "esc_resistance_ohm", "motor_coulomb_friction_nm", "guide_friction_n", "nip_friction_n",
    "nip_viscous_n_s_per_m", "airborne_hysteresis_mps", "esc_deadband_us", "esc_lag_s",
    "battery_internal_resistance_ohm", "battery_ocv_slope_v_per_ah", "battery_aux_current_a",
    "battery_adc_noise_v", "rope_exposed_length_m", "esc_invalid_below_us", "battery_empty_v",
})
