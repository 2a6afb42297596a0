"""Fault injection at the plant/HAL boundary of the SIL: what a broken sensor, ESC, rope or battery looks like.

Each fault is an object with a time window [start_s, start_s + duration_s) in simulated seconds
(duration_s None = until the end) and ``install(sil)``, which hooks it into a SilSession through the
session's ``sensor_filters`` / ``actuator_filters``; ``remove(sil)`` unhooks it. Faults act on what
crosses the boundary or on the plants' settable inputs, never on plant internals:

* EncoderDropout: the encoder count and edge time the firmware reads freeze (a broken encoder cable).
* EscNotResponding: the ESCs ignore the firmware's pulse; the plant's ESC gets its minimum pulse (zero
  throttle: bridge off, the motor coasts).
* RopeBreak: the loop is gone: the external load and the exposed rope's air drag vanish
  (``external_rope_load_n`` = 0, ``rope_exposed_length_m`` = 0, re-applied every tick), and a grasped
  object is no longer held (the spindle plant's ``object_circumference_m`` = None: no rope tension). The
  rope's inertia (m_rope r^2 in the plant's total inertia) has no settable input, so it stays (reported).
* BatterySag: the pack's terminal voltage sinks linearly to target_v over ramp_s by a growing auxiliary
  load (``battery_aux_current_a``), so the motors see the sag as well as the ADC.
* SpindleStall: the lead screw jams for the window (the spindle plant's ``stalled`` input): the guide stops
  while the servo keeps pushing, so its load register rises.
* SpindleReplyLoss: the servo's status packets are lost on the bus for the window (an interrupt burst that
  overruns the UART's receiver, a noisy line): the firmware's reads get no reply, while the servo itself keeps
  executing the writes (the plant still receives the moving speed).
* StalledControlLoop: the firmware misses its ticks for duration_s (no SIL_SENSORS; the ESC keeps its last
  pulse and the plant runs on); the next tick the firmware sees one long dt.
"""

from __future__ import annotations

import math
from dataclasses import replace

from robowrangler_sim.sil.session import SensorValues, SilSession


def _check_window(start_s: object, duration_s: object) -> None:
    if isinstance(start_s, bool) or not isinstance(start_s, (int, float)) or not math.isfinite(start_s) or start_s < 0:
        raise ValueError(f"start_s: expected a simulated time >= 0 s, got {start_s!r}")
    if duration_s is not None and (isinstance(duration_s, bool) or not isinstance(duration_s, (int, float))
                                   or not math.isfinite(duration_s) or duration_s <= 0):
        raise ValueError(f"duration_s: expected a duration > 0 s or None (until the end), got {duration_s!r}")


class _WindowedFault:
    """A fault active from start_s for duration_s simulated seconds (None = for ever)."""

    def __init__(self, *, start_s: float, duration_s: float | None) -> None:
        _check_window(start_s, duration_s)
        self.start_us = round(start_s * 1e6)
        self.end_us = None if duration_s is None else self.start_us + round(duration_s * 1e6)

    def active_at(self, time_us: int) -> bool:
        return time_us >= self.start_us and (self.end_us is None or time_us < self.end_us)


class EncoderDropout(_WindowedFault):
    """The firmware's encoder readings freeze at their values when the fault starts (no more edges)."""

    def __init__(self, *, start_s: float, duration_s: float | None = None) -> None:
        super().__init__(start_s=start_s, duration_s=duration_s)
        self._frozen: SensorValues | None = None

    def __call__(self, sensors: SensorValues | None) -> SensorValues | None:
        if sensors is None or not self.active_at(sensors.time_us):
            self._frozen = None
            return sensors
        if self._frozen is None:
            self._frozen = sensors
        return replace(sensors, encoder_counts=self._frozen.encoder_counts,
                       encoder_last_edge_us=self._frozen.encoder_last_edge_us)

    def install(self, sil: SilSession) -> EncoderDropout:
        sil.sensor_filters.append(self)
        return self

    def remove(self, sil: SilSession) -> None:
        sil.sensor_filters.remove(self)


class EscNotResponding(_WindowedFault):
    """The ESCs ignore the pulse: the plant's ESC gets its minimum pulse (zero throttle, the motor coasts)."""

    def __init__(self, *, start_s: float, duration_s: float | None = None) -> None:
        super().__init__(start_s=start_s, duration_s=duration_s)
        self._sil: SilSession | None = None

    def __call__(self, pulse_us: float) -> float:
        sil = self._sil
        if sil is None or not self.active_at(sil.drive_out.time_us):
            return pulse_us
        return round(sil.drive.params.esc_min_pulse_us)

    def install(self, sil: SilSession) -> EscNotResponding:
        self._sil = sil
        sil.actuator_filters.append(self)
        return self

    def remove(self, sil: SilSession) -> None:
        sil.actuator_filters.remove(self)
        self._sil = None


class RopeBreak(_WindowedFault):
    """From start_s the rope loop is broken: external load 0 N, no exposed rope (its air drag vanishes), and no
    grasped object on the spindle (its rope tension vanishes).

    Re-applied before every tick while active (the session may set the exposed length from the spindle's
    loop length each tick). Known gap: the rope's inertia stays in the plant (no settable input for it).
    """

    def __init__(self, *, start_s: float, duration_s: float | None = None) -> None:
        super().__init__(start_s=start_s, duration_s=duration_s)
        self._sil: SilSession | None = None
        self.drag_before_n: float | None = None

    def __call__(self, sensors: SensorValues | None) -> SensorValues | None:
        sil = self._sil
        out = sil.drive_out
        if self.active_at(out.time_us):
            if self.drag_before_n is None:
                self.drag_before_n = out.rope_drag_n
            sil.loads.external_rope_load_n = 0.0
            sil.loads.rope_exposed_length_m = 0.0
            sil.loads.guide_load_n = None
            sil.spindle.object_circumference_m = None
        return sensors

    def install(self, sil: SilSession) -> RopeBreak:
        self._sil = sil
        sil.sensor_filters.insert(0, self)  # acts on the plant before any filter can skip the tick
        return self

    def remove(self, sil: SilSession) -> None:
        sil.sensor_filters.remove(self)


class BatterySag(_WindowedFault):
    """From start_s the pack's terminal voltage falls linearly to target_v over ramp_s, then stays there.

    Implemented as a growing auxiliary load: aux = aux0 + (V_oc - V_target(t)) / R_int - (the drop aux0
    already causes), recomputed every tick from the plant's open-circuit voltage. After the window (if
    duration_s is set) the auxiliary load returns to its value before the fault.
    """

    def __init__(self, *, start_s: float, target_v: float, ramp_s: float = 1.0,
                 duration_s: float | None = None) -> None:
        super().__init__(start_s=start_s, duration_s=duration_s)
        if isinstance(target_v, bool) or not isinstance(target_v, (int, float)) or not 0 < target_v < 100:
            raise ValueError(f"target_v: expected a battery voltage in (0, 100) V, got {target_v!r}")
        if isinstance(ramp_s, bool) or not isinstance(ramp_s, (int, float)) or not 0 < ramp_s < 3600:
            raise ValueError(f"ramp_s: expected a ramp time in (0, 3600) s, got {ramp_s!r}")
        self.target_v = float(target_v)
        self.ramp_s = float(ramp_s)
        self._sil: SilSession | None = None
        self._aux0_a: float | None = None
        self._loads_aux0_a: float | None = None
        self._start_v: float | None = None

    def __call__(self, sensors: SensorValues | None) -> SensorValues | None:
        sil = self._sil
        out = sil.drive_out
        now_us = out.time_us
        if self.active_at(now_us):
            r_int_ohm = sil.drive.params.battery_internal_resistance_ohm
            if self._aux0_a is None:
                self._aux0_a = out.battery_aux_current_a
                self._loads_aux0_a = sil.loads.battery_aux_current_a
                self._start_v = out.battery_open_circuit_v - r_int_ohm * self._aux0_a
            frac = min(1.0, (now_us - self.start_us) * 1e-6 / self.ramp_s)
            want_v = self._start_v + frac * (self.target_v - self._start_v)
            sil.loads.battery_aux_current_a = max(0.0, (out.battery_open_circuit_v - want_v) / r_int_ohm)
        elif self._aux0_a is not None:
            sil.loads.battery_aux_current_a = self._loads_aux0_a
            self._aux0_a = None
        return sensors

    def install(self, sil: SilSession) -> BatterySag:
        self._sil = sil
        sil.sensor_filters.insert(0, self)  # sets the load before any filter can skip the tick
        return self

    def remove(self, sil: SilSession) -> None:
        sil.sensor_filters.remove(self)


class SpindleStall(_WindowedFault):
    """The lead screw jams from start_s for duration_s (None = for ever): sets the spindle plant's ``stalled``."""

    def __init__(self, *, start_s: float, duration_s: float | None = None) -> None:
        super().__init__(start_s=start_s, duration_s=duration_s)
        self._sil: SilSession | None = None

    def __call__(self, sensors: SensorValues | None) -> SensorValues | None:
        self._sil.spindle.stalled = self.active_at(self._sil.drive_out.time_us)
        return sensors

    def install(self, sil: SilSession) -> SpindleStall:
        if getattr(sil, "spindle", None) is None:
            raise ValueError("sil: expected a SilSession with a spindle plant, got one without")
        self._sil = sil
        sil.sensor_filters.insert(0, self)
        return self

    def remove(self, sil: SilSession) -> None:
        sil.sensor_filters.remove(self)
        sil.spindle.stalled = False


class SpindleReplyLoss(_WindowedFault):
    """No status packet from the servo reaches the firmware from start_s for duration_s; the servo still
    executes the writes. Counts the ticks it blanked (``ticks_lost``)."""

    def __init__(self, *, start_s: float, duration_s: float | None = None) -> None:
        super().__init__(start_s=start_s, duration_s=duration_s)
        self.ticks_lost = 0

    def __call__(self, sensors: SensorValues | None) -> SensorValues | None:
        if sensors is None or not self.active_at(sensors.time_us) or not sensors.spindle_answered:
            return sensors
        self.ticks_lost += 1
        return replace(sensors, spindle_answered=False)

    def install(self, sil: SilSession) -> SpindleReplyLoss:
        sil.sensor_filters.append(self)
        return self

    def remove(self, sil: SilSession) -> None:
        sil.sensor_filters.remove(self)


class StalledControlLoop(_WindowedFault):
    """The firmware's control loop stalls for duration_s: it gets no SIL_SENSORS, so it runs no tick."""

    def __init__(self, *, start_s: float, duration_s: float) -> None:
        if duration_s is None:
            raise ValueError("duration_s: expected a stall duration > 0 s, got None")
        super().__init__(start_s=start_s, duration_s=duration_s)
        self.missed_ticks = 0

    def __call__(self, sensors: SensorValues | None) -> SensorValues | None:
        if sensors is not None and self.active_at(sensors.time_us):
            self.missed_ticks += 1
            return None
        return sensors

    def install(self, sil: SilSession) -> StalledControlLoop:
        sil.sensor_filters.append(self)
        return self

    def remove(self, sil: SilSession) -> None:
        sil.sensor_filters.remove(self)


__all__ = ["BatterySag", "EncoderDropout", "EscNotResponding", "RopeBreak", "SpindleReplyLoss", "SpindleStall",
           "StalledControlLoop"]
