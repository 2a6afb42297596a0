"""3S LiPo pack: open-circuit voltage falling with charge drawn, series internal resistance, noisy ADC reading.

    V_oc(q) = max(V_empty, V_oc0 - slope q)          q = charge drawn, Ah
    V_terminal = V_oc - R_int (I_motors + I_aux)     (sag under load, rise while regenerating)

The ADC reading adds Gaussian noise (seeded numpy Generator, drawn in blocks so a scalar draw costs no
numpy call in the hot path) and quantises to the ADC step.
"""

from __future__ import annotations

import math

import numpy as np

from robowrangler_sim.plants.drive_params import DriveParams

_NOISE_BLOCK = 4096


class Battery:
    """Battery state. Attributes: charge_drawn_ah (Ah since reset), aux_current_a (A, settable)."""

    def __init__(self, params: DriveParams, *, rng: np.random.Generator) -> None:
        self._p = params
        self.reset(rng=rng)

    def reset(self, *, rng: np.random.Generator) -> None:
        """Full reset: no charge drawn, aux current from params; ADC noise drawn from rng from now on."""
        self.charge_drawn_ah = 0.0
        self.aux_current_a = self._p.battery_aux_current_a
        self._rng = rng
        self._noise = self._rng.standard_normal(_NOISE_BLOCK).tolist()
        self._noise_i = 0

    def open_circuit_v(self) -> float:
        """Open-circuit voltage now, V."""
        p = self._p
        return max(p.battery_empty_v, p.battery_open_circuit_v - p.battery_ocv_slope_v_per_ah * self.charge_drawn_ah)

    def source_v(self) -> float:
        """Thevenin source seen by the ESCs (open-circuit voltage less the aux load's drop), V."""
        return self.open_circuit_v() - self._p.battery_internal_resistance_ohm * self.aux_current_a

    def draw(self, motors_current_a: float, dt_s: float) -> None:
        """Account motors_current_a (A, battery side, all motors; negative charges) plus aux for dt_s seconds."""
        self.charge_drawn_ah += (motors_current_a + self.aux_current_a) * dt_s / 3600.0

    def adc_reading_v(self, terminal_v: float) -> float:
        """One ADC sample of terminal_v (V): plus seeded Gaussian noise, quantised to the ADC step."""
        if self._noise_i >= _NOISE_BLOCK:
            self._noise = self._rng.standard_normal(_NOISE_BLOCK).tolist()
            self._noise_i = 0
        noisy = terminal_v + self._p.battery_adc_noise_v * self._noise[self._noise_i]
        self._noise_i += 1
        lsb = self._p.battery_adc_lsb_v
        return max(0.0, math.floor(noisy / lsb + 0.5) * lsb)
