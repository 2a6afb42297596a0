"""Named model parameters: a column of the batched drive plant's theta, its unit and its physical bounds.

The nominal refit frees the drive's class estimates (DriveParams marks them) within physical bounds; each
candidate effect frees its own law's parameters. Bounds are relative to the nominal value (lo, hi factors)
for nominal parameters and absolute for effect parameters.
"""

from __future__ import annotations

from dataclasses import dataclass

from robowrangler_sim.plants import drive_batch as db


@dataclass(frozen=True)
class ParamSpec:
    """One free parameter.

    name: report name (unit suffix); column: theta column (db.TH_*); unit: unit text for the report;
    lo, hi: bounds (absolute, or factors of the nominal value when relative=True); scale: typical magnitude
    (the fit works on value / scale).
    """

    name: str
    column: int
    unit: str
    lo: float
    hi: float
    scale: float
    relative: bool = False

    def bounds(self, nominal_value: float) -> tuple[float, float]:
        if self.relative:
            return self.lo * nominal_value, self.hi * nominal_value
        return self.lo, self.hi


NOMINAL_REFIT: tuple[ParamSpec, ...] = (
    ParamSpec("torque_constant_nm_per_a", db.TH_KT, "N m/A", 0.9, 1.1, 7.6e-3, relative=True),
    ParamSpec("circuit_resistance_ohm", db.TH_R_CIRCUIT, "Ohm", 0.6, 1.6, 0.085, relative=True),
    ParamSpec("coulomb_friction_n", db.TH_COULOMB_N, "N", 0.5, 1.8, 0.3, relative=True),
    ParamSpec("viscous_friction_n_s_per_m", db.TH_VISCOUS_N_S_PER_M, "N s/m", 0.5, 1.8, 0.03, relative=True),
    ParamSpec("inertia_kg_m2", db.TH_INERTIA, "kg m^2", 0.7, 1.4, 8.4e-6, relative=True),
    ParamSpec("rope_drag_coeff_n_s2_per_m2", db.TH_DRAG_K, "N s^2/m^2", 0.5, 2.0, 6.5e-4, relative=True),
    ParamSpec("battery_internal_resistance_ohm", db.TH_BATT_R, "Ohm", 0.5, 2.0, 0.03, relative=True),
    ParamSpec("battery_open_circuit_v", db.TH_BATT_OCV, "V", 0.93, 1.07, 12.0, relative=True),
    ParamSpec("esc_lag_s", db.TH_ESC_LAG, "s", 0.3, 2.0, 0.003, relative=True),
    ParamSpec("esc_zero_throttle_us", db.TH_DEADBAND, "us", 0.5, 2.0, 10.0, relative=True),
    ParamSpec("esc_input_delay_s", db.TH_LATENCY, "s", 0.0, 0.003, 0.001),
)
"""The nominal model's own parameters the refit may move (class estimates and the ESC assumptions).

The ESC's zero-throttle point (its dead band above the minimum pulse, assumed 10 us) and an input delay of up to
3 ms are unit properties of every BLHeli-class ESC, not missing physics: it times the pulse with its own oscillator
(a 1 % clock error moves 1000 us by 10 us), loses a few us' worth of duty to the bridge's dead time, and knows a
pulse's width only at its falling edge, 1-2 ms after the frame starts, before its input filter. An outside
simulator built that way (bench/outside_writer.py) was named esc_deadband (12-15 us) and esc_latency (1-2.4 ms)
on every effect-free recording while these two were fixed; a dead band or a delay beyond these bounds is still
a candidate's to claim."""
