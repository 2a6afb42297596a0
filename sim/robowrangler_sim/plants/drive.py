"""Drive plant: ESC pulse -> two BLDC motors -> 15 mm wheels -> rope speed, with rope drag and the encoder.

The plant owns the SIL clock (integer microseconds). One rotational degree of freedom, the wheel angle theta:
both wheels pinch the rope without slip, so rope speed v = r omega. Equation of motion (all motors summed,
referred to one wheel shaft):

    J omega' = n Kt i - n (T_c sgn(omega) + b omega)
               - r [ (F_guide + F_nip + F_ext) sgn(v) + c_nip v + k v |v| ]

    J = n (J_rotor + J_wheel) + m_rope r^2,   k = 0.5 rho C_f pi d L_exposed  (axial skin-friction drag)

with i from the quasi-static motor/battery law in bldc_motor.py (i = a - b omega, clamped by the ESC) and
the ESC input stage in esc.py. Integration: substeps of at most ``max_substep_s``; in each, the drag is
linearised about the substep's start (Newton) and the resulting linear ODE omega' = (P - Q omega) / J is
solved exactly (exponential), so the stiff back-EMF damping never makes the step unstable. Coulomb terms
stick: at rest the shaft stays put while the drive torque is below the Coulomb sum, and a speed that would
cross zero within a substep stops at zero. Wheel-rope slip is not modelled (rope speed = wheel surface
speed); a slip model would add a rope degree of freedom coupled through a nip traction law.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from numbers import Real

import numpy as np

from robowrangler_sim.plants.battery import Battery
from robowrangler_sim.plants.bldc_motor import battery_terminal_v, current_law
from robowrangler_sim.plants.drive_params import DriveParams
from robowrangler_sim.plants.encoder import Encoder
from robowrangler_sim.plants.esc import Esc

_RAD_S_TO_RPM = 60.0 / (2.0 * math.pi)


@dataclass(frozen=True, kw_only=True)
class DriveInputs:
    """What drives the drive plant over one step (the plant contract, plants/contract.py).

    Attributes:
        esc_pulse_us: ESC input pulse width, us (0 = no signal, else 0 < pulse <= esc_frame_us).
        external_rope_load_n: disturbance force on the rope, N (>= 0), opposing its motion.
        rope_exposed_length_m: rope moving through air (carries the skin-friction drag), m, 0..rope_loop_length_m;
            None: the params' rope_exposed_length_m.
        battery_aux_current_a: other loads on the pack, A (>= 0); None: the params' battery_aux_current_a.
    """

    esc_pulse_us: float
    external_rope_load_n: float = 0.0
    rope_exposed_length_m: float | None = None
    battery_aux_current_a: float | None = None


@dataclass(frozen=True, kw_only=True)
class DriveOutputs:
    """The drive plant's outputs at the end of a step (SI; the sensor fields are what the board's HAL reads).

    Attributes:
        time_us: plant clock, integer microseconds since reset.
        rope_speed_mps, wheel_speed_rad_s, motor_rpm: rope / wheel / motor speed (signed).
        shaft_angle_rad: cumulative wheel angle since reset.
        motor_current_a: phase current per motor (negative while braking).
        battery_v: terminal voltage; battery_adc_v: the same through the noisy, quantised ADC (sensor).
        battery_current_a: battery-side current; battery_open_circuit_v: the pack's open-circuit voltage.
        esc_armed, esc_throttle, esc_duty: ESC state (latched throttle 0..1, applied duty 0..1).
        encoder_counts, encoder_last_edge_us: the encoder (sensor): cumulative edges, plant time of the last edge.
        rope_drag_n: aerodynamic drag on the rope, N.
        loop_airborne: rope speed above ToV (with hysteresis).
        external_rope_load_n, rope_exposed_length_m, battery_aux_current_a: the inputs in force over the step.
    """

    time_us: int
    rope_speed_mps: float
    wheel_speed_rad_s: float
    motor_rpm: float
    shaft_angle_rad: float
    motor_current_a: float
    battery_v: float
    battery_adc_v: float
    battery_current_a: float
    battery_open_circuit_v: float
    esc_armed: bool
    esc_throttle: float
    esc_duty: float
    encoder_counts: int
    encoder_last_edge_us: int
    rope_drag_n: float
    loop_airborne: bool
    external_rope_load_n: float
    rope_exposed_length_m: float
    battery_aux_current_a: float

    @property
    def time_s(self) -> float:
        return self.time_us * 1e-6


def _is_real(value: object) -> bool:
    """True for int/float/numpy real scalars, False for bool and everything else (fast path for float)."""
    if type(value) is float:
        return True
    return isinstance(value, Real) and not isinstance(value, bool)


def rope_drag_force_n(params: DriveParams, rope_speed_mps: float) -> float:
    """Axial skin-friction air drag on the exposed rope, N, signed against the motion.

    f_t = 0.5 rho C_f pi d v^2 per metre (robowrangler_sim/rope.py), times ``rope_exposed_length_m``.
    """
    return params.rope_drag_coeff_n_s2_per_m2 * rope_speed_mps * abs(rope_speed_mps)


def _load_torque_nm(params: DriveParams, omega_rad_s: float, external_rope_load_n: float) -> float:
    """Total steady load torque on the shaft (all motors) at omega_rad_s >= 0, N m."""
    r = params.wheel_radius_m
    v = r * omega_rad_s
    motor = params.motor_count * (params.motor_coulomb_friction_nm
                                  + params.motor_viscous_friction_nm_s_per_rad * omega_rad_s)
    rope = (params.guide_friction_n + params.nip_friction_n + external_rope_load_n
            + params.nip_viscous_n_s_per_m * v + rope_drag_force_n(params, v))
    return motor + r * rope


def _steady_duty(params: DriveParams, rope_speed_mps: float, external_rope_load_n: float,
                 battery_open_circuit_v: float) -> tuple[float, float]:
    """Duty and per-motor current (A) holding rope_speed_mps steady; raises ValueError if out of reach."""
    omega = rope_speed_mps / params.wheel_radius_m
    n = params.motor_count
    kt = params.torque_constant_nm_per_a
    i = _load_torque_nm(params, omega, external_rope_load_n) / (n * kt)
    if i > params.esc_current_limit_a:
        raise ValueError(f"rope_speed_mps: {rope_speed_mps} m/s needs {i:.1f} A per motor, "
                         f"above esc_current_limit_a {params.esc_current_limit_a} A")
    rb = params.battery_internal_resistance_ohm
    v_src = battery_open_circuit_v - rb * params.battery_aux_current_a
    emf_plus_ir = kt * omega + params.circuit_resistance_ohm * i
    quad = rb * n * i
    if quad == 0.0:
        duty = emf_plus_ir / v_src
    else:
        disc = v_src * v_src - 4.0 * quad * emf_plus_ir
        duty = math.inf if disc < 0.0 else (v_src - math.sqrt(disc)) / (2.0 * quad)
    if duty > params.esc_max_duty:
        raise ValueError(f"rope_speed_mps: {rope_speed_mps} m/s is out of reach at "
                         f"{battery_open_circuit_v} V (needs duty {duty:.3f} > esc_max_duty {params.esc_max_duty})")
    return duty, i


def steady_throttle_for_speed(params: DriveParams, rope_speed_mps: float, *, external_rope_load_n: float = 0.0,
                              battery_open_circuit_v: float | None = None) -> float:
    """Throttle command fraction (pulse_us - min) / (max - min) that holds rope_speed_mps in steady state.

    Exact steady state of this plant (friction, drag, winding and battery resistance, ESC deadband); the
    firmware's pulse is esc_min_pulse_us + fraction * (esc_max_pulse_us - esc_min_pulse_us). Zero speed
    returns 0. Raises ValueError naming rope_speed_mps when the speed is negative, not finite or out of reach.
    """
    if not _is_real(rope_speed_mps) or not math.isfinite(rope_speed_mps) or rope_speed_mps < 0.0:
        raise ValueError(f"rope_speed_mps: expected finite >= 0, got {rope_speed_mps!r}")
    if not _is_real(external_rope_load_n) or not math.isfinite(external_rope_load_n) or external_rope_load_n < 0.0:
        raise ValueError(f"external_rope_load_n: expected a finite force >= 0 N, got {external_rope_load_n!r}")
    if rope_speed_mps == 0.0:
        return 0.0
    voc = params.battery_open_circuit_v if battery_open_circuit_v is None else battery_open_circuit_v
    duty, _ = _steady_duty(params, rope_speed_mps, external_rope_load_n, voc)
    zero_top = params.esc_min_pulse_us + params.esc_deadband_us
    pulse = zero_top + duty / params.esc_max_duty * (params.esc_max_pulse_us - zero_top)
    return (pulse - params.esc_min_pulse_us) / (params.esc_max_pulse_us - params.esc_min_pulse_us)


def kv_throttle_for_speed(params: DriveParams, rope_speed_mps: float, *, battery_v: float) -> float:
    """The firmware's Kv feed-forward map: throttle = v / (Kv[rad/s/V] * V_batt * r_wheel) (no losses)."""
    return rope_speed_mps / (params.kv_rad_per_s_per_v * battery_v * params.wheel_radius_m)


def steady_battery_v(params: DriveParams, rope_speed_mps: float, *, external_rope_load_n: float = 0.0) -> float:
    """Battery terminal voltage (V) in steady state at rope_speed_mps (what the firmware's ADC reads)."""
    if rope_speed_mps == 0.0:
        return params.battery_open_circuit_v - params.battery_internal_resistance_ohm * params.battery_aux_current_a
    duty, i = _steady_duty(params, rope_speed_mps, external_rope_load_n, params.battery_open_circuit_v)
    v_src = params.battery_open_circuit_v - params.battery_internal_resistance_ohm * params.battery_aux_current_a
    return v_src - params.battery_internal_resistance_ohm * params.motor_count * duty * i


def speed_time_constant_s(params: DriveParams, rope_speed_mps: float) -> float:
    """Small-signal mechanical time constant J / (d torque / d omega) at a steady rope speed, s.

    Excludes the ESC's input latching (up to one 2.5 ms frame) and its duty lag ``esc_lag_s``.
    """
    duty, _ = _steady_duty(params, rope_speed_mps, 0.0, params.battery_open_circuit_v)
    n = params.motor_count
    kt = params.torque_constant_nm_per_a
    r = params.wheel_radius_m
    r_eff = params.circuit_resistance_ohm + n * duty * duty * params.battery_internal_resistance_ohm
    q = (n * kt * kt / r_eff + n * params.motor_viscous_friction_nm_s_per_rad
         + r * r * (params.nip_viscous_n_s_per_m + 2.0 * params.rope_drag_coeff_n_s2_per_m2 * rope_speed_mps))
    return params.total_inertia_kg_m2 / q


class DrivePlant:
    """The rope drive, stepped in lockstep by the SIL; it owns the plant clock.

    The contract (plants/contract.py): ``update(DriveInputs, dt_s) -> DriveOutputs``, ``outputs()``, ``reset()``.
    ``step``/``step_us`` with the inputs set as attributes below are the same integration, for scripts and tests
    that drive the plant by hand.

    Outputs (plain attributes, updated by ``step``; SI units, names carry units):
        time_us: plant clock, integer microseconds since reset.
        rope_speed_mps, wheel_speed_rad_s, motor_rpm: speed of the rope / wheel / motor (signed).
        shaft_angle_rad: cumulative wheel (= motor) angle since reset.
        motor_current_a: phase current per motor at the end of the step (negative while braking).
        battery_v: terminal voltage under load; battery_adc_v: the same read by a noisy, quantised ADC.
        battery_current_a: battery-side current of all motors plus the aux load.
        battery_open_circuit_v: the pack's open-circuit voltage now (falls with charge drawn).
        esc_armed, esc_throttle, esc_duty: ESC state (throttle latched 0..1, applied duty 0..1).
        encoder_counts: cumulative signed edge count, encoder_counts_per_rev per revolution.
        encoder_last_edge_us: plant time of the most recent edge (interpolated inside the step, floored to us;
            0 until the first edge).
        rope_drag_n: aerodynamic drag on the rope now, N.
        loop_airborne: rope speed above ToV, with +-airborne_hysteresis_mps hysteresis.
    Inputs between steps: external_rope_load_n (N >= 0, opposes the rope motion), rope_exposed_length_m
    (m, rope in moving air), battery_aux_current_a (A, other loads on the pack). reset() restores them.
    """

    def __init__(self, params: DriveParams | None = None, *, seed: int = 0) -> None:
        if params is None:
            params = DriveParams()
        if not isinstance(params, DriveParams):
            raise TypeError(f"params: expected DriveParams or None, got {type(params).__name__}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"seed: expected an int >= 0, got {seed!r}")
        self.params = params
        self.seed = int(seed)
        p = params
        # constants used in the hot loop
        self._n = p.motor_count
        self._kt = p.torque_constant_nm_per_a
        self._r = p.wheel_radius_m
        self._j = p.total_inertia_kg_m2
        self._r_circ = p.circuit_resistance_ohm
        self._rb = p.battery_internal_resistance_ohm
        self._max_step_us = round(p.max_step_s * 1e6)
        self.reset()

    def reset(self) -> None:
        """Back to power-up: clock 0, at rest, ESC disarmed, battery full, same seed as constructed."""
        p = self.params
        rng = np.random.default_rng(self.seed)
        self._esc = Esc(p)
        self._encoder = Encoder(counts_per_rev=p.encoder_counts_per_rev, phase_counts=float(rng.random()))
        self._battery = Battery(p, rng=rng)
        self._next_frame_us = 0
        self._omega = 0.0
        self._external_rope_load_n = 0.0
        self.rope_exposed_length_m = p.rope_exposed_length_m
        self.time_us = 0
        self.shaft_angle_rad = 0.0
        self.wheel_speed_rad_s = 0.0
        self.rope_speed_mps = 0.0
        self.motor_rpm = 0.0
        self.motor_current_a = 0.0
        self.battery_v = self._battery.source_v()
        self.battery_adc_v = self.battery_v
        self.battery_open_circuit_v = self._battery.open_circuit_v()
        self.battery_current_a = self._battery.aux_current_a
        self.esc_armed = False
        self.esc_throttle = 0.0
        self.esc_duty = 0.0
        self.encoder_counts = 0
        self.encoder_last_edge_us = 0
        self.rope_drag_n = 0.0
        self.loop_airborne = False

    @property
    def external_rope_load_n(self) -> float:
        """Disturbance force on the rope, N (>= 0), opposing its motion (holds it at rest like friction)."""
        return self._external_rope_load_n

    @external_rope_load_n.setter
    def external_rope_load_n(self, value: float) -> None:
        if not _is_real(value) or not math.isfinite(value) or value < 0.0:
            raise ValueError(f"external_rope_load_n: expected a finite force >= 0 N, got {value!r}")
        self._external_rope_load_n = float(value)

    @property
    def rope_exposed_length_m(self) -> float:
        """Rope length moving through air (carries the skin-friction drag), m; starts at the params' value.

        Settable between steps (e.g. by a spindle plant as the loop grows or shrinks), 0..rope_loop_length_m.
        """
        return self._exposed_length_m

    @rope_exposed_length_m.setter
    def rope_exposed_length_m(self, value: float) -> None:
        loop_m = self.params.rope_loop_length_m
        if not _is_real(value) or not math.isfinite(value) or not 0.0 <= value <= loop_m:
            raise ValueError(f"rope_exposed_length_m: expected a length in [0, {loop_m}] m, got {value!r}")
        p = self.params
        self._exposed_length_m = float(value)
        self._k_drag = 0.5 * p.air_density_kg_per_m3 * p.rope_cf_pi_d_m * self._exposed_length_m

    @property
    def battery_aux_current_a(self) -> float:
        """Current other loads draw from the pack (board, encoder, spindle servo...), A; settable, >= 0."""
        return self._battery.aux_current_a

    @battery_aux_current_a.setter
    def battery_aux_current_a(self, value: float) -> None:
        if not _is_real(value) or not math.isfinite(value) or value < 0.0:
            raise ValueError(f"battery_aux_current_a: expected a finite current >= 0 A, got {value!r}")
        self._battery.aux_current_a = float(value)

    def update(self, inputs: DriveInputs, dt_s: float) -> DriveOutputs:
        """The plant contract: advance dt_s (whole microseconds, 0 < dt_s <= max_step_s) with ``inputs`` held;
        the outputs at the end. ValueError/TypeError naming the field on a bad input."""
        if not isinstance(inputs, DriveInputs):
            raise TypeError(f"inputs: expected DriveInputs, got {type(inputs).__name__}")
        p = self.params
        self.external_rope_load_n = inputs.external_rope_load_n
        self.rope_exposed_length_m = (p.rope_exposed_length_m if inputs.rope_exposed_length_m is None
                                      else inputs.rope_exposed_length_m)
        self.battery_aux_current_a = (p.battery_aux_current_a if inputs.battery_aux_current_a is None
                                      else inputs.battery_aux_current_a)
        self.step(esc_pulse_us=inputs.esc_pulse_us, dt_s=dt_s)
        return self.outputs()

    def outputs(self) -> DriveOutputs:
        """The outputs now (the plant contract), without stepping."""
        return DriveOutputs(**{name: getattr(self, name) for name in _OUTPUT_FIELDS})

    def step(self, *, esc_pulse_us: float, dt_s: float) -> None:
        """Advance the plant by dt_s seconds (a whole number of microseconds, 0 < dt_s <= max_step_s) with the
        ESC input held at esc_pulse_us (0 = no signal, else 0 < pulse <= esc_frame_us).

        Raises ValueError naming the argument when either is not finite or out of range.
        """
        if not _is_real(dt_s) or not math.isfinite(dt_s):
            raise ValueError(f"dt_s: expected a finite number of seconds, got {dt_s!r}")
        dt_us_f = dt_s * 1e6
        dt_us = round(dt_us_f)
        if dt_us <= 0 or dt_us > self._max_step_us or abs(dt_us_f - dt_us) > 1e-3:
            raise ValueError(f"dt_s: expected whole microseconds in (0, {self.params.max_step_s}] s, got {dt_s!r}")
        self.step_us(esc_pulse_us=esc_pulse_us, dt_us=dt_us)

    def step_us(self, *, esc_pulse_us: float, dt_us: int) -> None:
        """As ``step`` with the interval in integer microseconds (1 <= dt_us <= max_step_s * 1e6)."""
        if isinstance(dt_us, bool) or not isinstance(dt_us, (int, np.integer)) or not 0 < dt_us <= self._max_step_us:
            raise ValueError(f"dt_us: expected an int in [1, {self._max_step_us}], got {dt_us!r}")
        if (not _is_real(esc_pulse_us) or not math.isfinite(esc_pulse_us)
                or not 0.0 <= esc_pulse_us <= self.params.esc_frame_us):
            raise ValueError(f"esc_pulse_us: expected a finite pulse width in [0, {self.params.esc_frame_us}] us "
                             f"(0 = no signal), got {esc_pulse_us!r}")
        esc_pulse_us = float(esc_pulse_us)
        esc = self._esc
        t = self.time_us
        t_end = t + int(dt_us)
        frame_us = self.params.esc_frame_us
        while t < t_end:
            if t >= self._next_frame_us:
                esc.on_frame(esc_pulse_us, self._kt * self._omega / self._battery.source_v())
                self._next_frame_us += frame_us
            seg_end = self._next_frame_us if self._next_frame_us < t_end else t_end
            self._integrate(t, seg_end - t)
            t = seg_end
        self.time_us = t_end
        self._publish()

    def _integrate(self, t0_us: int, span_us: int) -> None:
        """Integrate span_us microseconds with the ESC latch fixed, in equal substeps <= max_substep_s."""
        p = self.params
        span_s = span_us * 1e-6
        n_sub = max(1, math.ceil(span_s / p.max_substep_s - 1e-9))
        h = span_s / n_sub
        h_us = span_us / n_sub
        n = self._n
        kt = self._kt
        r = self._r
        j = self._j
        k_drag = self._k_drag
        r_circ = self._r_circ
        rb = self._rb
        i_lim = p.esc_current_limit_a
        damped = p.esc_damped_light
        n_kt = n * kt
        q_fixed = n * p.motor_viscous_friction_nm_s_per_rad + r * r * p.nip_viscous_n_s_per_m
        static_nm = n * p.motor_coulomb_friction_nm + r * (p.guide_friction_n + p.nip_friction_n
                                                          + self._external_rope_load_n)
        battery = self._battery
        v_src = battery.source_v()
        self.battery_open_circuit_v = battery.open_circuit_v()  # the one battery_v is computed from
        esc = self._esc
        encoder = self._encoder
        omega = self._omega
        theta = self.shaft_angle_rad
        i1 = 0.0
        v_batt = v_src
        charge_as = 0.0
        t_us = float(t0_us)
        for _ in range(n_sub):
            duty = esc.advance(h)
            a, b = current_law(duty, omega, v_src, rb, n, kt, r_circ, i_lim, damped)
            if omega == 0.0:
                drive_nm = n_kt * a
                if abs(drive_nm) <= static_nm:  # stuck: Coulomb friction holds it
                    i1 = a
                    v_batt = battery_terminal_v(v_src, rb, n, i1, 0.0, kt, r_circ)
                    charge_as += n * i1 * (r_circ * i1) / v_batt * h
                    t_us += h_us
                    continue
                sign = 1.0 if drive_nm > 0.0 else -1.0
            else:
                sign = 1.0 if omega > 0.0 else -1.0
            v0 = r * omega
            abs_v0 = abs(v0)
            pp = n_kt * a - sign * static_nm + r * k_drag * v0 * abs_v0
            qq = n_kt * b + q_fixed + 2.0 * k_drag * abs_v0 * r * r
            tau = j / qq
            omega_inf = pp / qq
            decay = math.exp(-h / tau)
            omega1 = omega_inf + (omega - omega_inf) * decay
            if omega1 * sign < 0.0:  # would reverse within the substep: Coulomb friction stops it at zero
                t_zero = tau * math.log((omega_inf - omega) / omega_inf)
                dtheta = omega_inf * t_zero + (omega - omega_inf) * (1.0 - math.exp(-t_zero / tau)) * tau
                omega1 = 0.0
            else:
                dtheta = omega_inf * h + (omega - omega_inf) * (1.0 - decay) * tau
            encoder.advance(dtheta, t_us, h_us)
            theta += dtheta
            omega = omega1
            i1 = a - b * omega
            v_batt = battery_terminal_v(v_src, rb, n, i1, omega, kt, r_circ)
            charge_as += n * i1 * (kt * omega + r_circ * i1) / v_batt * h
            t_us += h_us
        self._omega = omega
        self.shaft_angle_rad = theta
        self.motor_current_a = i1
        self.battery_v = v_batt
        self.battery_current_a = (n * i1 * (kt * omega + r_circ * i1) / v_batt) + battery.aux_current_a
        battery.draw(charge_as / span_s, span_s)

    def _publish(self) -> None:
        p = self.params
        omega = self._omega
        v = self._r * omega
        self.wheel_speed_rad_s = omega
        self.rope_speed_mps = v
        self.motor_rpm = omega * _RAD_S_TO_RPM
        self.rope_drag_n = self._k_drag * v * abs(v)
        esc = self._esc
        self.esc_armed = esc.armed
        self.esc_throttle = esc.throttle
        self.esc_duty = esc.duty if esc.bridge_on else 0.0
        self.encoder_counts = self._encoder.counts
        self.encoder_last_edge_us = self._encoder.last_edge_us
        self.battery_adc_v = self._battery.adc_reading_v(self.battery_v)
        speed = abs(v)
        if self.loop_airborne:
            if speed < p.takeoff_speed_mps - p.airborne_hysteresis_mps:
                self.loop_airborne = False
        elif speed > p.takeoff_speed_mps + p.airborne_hysteresis_mps:
            self.loop_airborne = True

    def snapshot(self) -> dict[str, float | int | bool]:
        """All outputs as one dict (for telemetry, logging and determinism checks)."""
        return {name: getattr(self, name) for name in _SNAPSHOT_FIELDS}


_OUTPUT_FIELDS = tuple(f.name for f in fields(DriveOutputs))

_SNAPSHOT_FIELDS = (
    "time_us", "rope_speed_mps", "wheel_speed_rad_s", "motor_rpm", "shaft_angle_rad", "motor_current_a",
    "battery_v", "battery_adc_v", "battery_current_a", "battery_open_circuit_v", "esc_armed", "esc_throttle", "esc_duty",
    "encoder_counts", "encoder_last_edge_us", "rope_drag_n", "loop_airborne", "external_rope_load_n", "rope_exposed_length_m", "battery_aux_current_a",
)
