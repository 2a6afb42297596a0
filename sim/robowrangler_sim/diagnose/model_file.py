"""The extended drive model diagnose writes (nominal parameters refitted + the chosen effect terms), as JSON.

    {"format": "robowrangler.drive_model", "format_version": 1,
     "drive_params": {DriveParams field: value, ...},           # refitted class estimates folded in
     "effects": {"esc_latency": {"delay_s": 0.0061}, ...},     # library laws, their parameters in SI
     "external_load_spans_s": [[t0, t1], ...],                 # where external_rope_load acts (recording time)
     "esc_input_delay_s": 0.0012,                              # the ESC's own input delay the refit found
     "spindle_params": {SpindleParams field: value, ...},       # refitted spindle estimates + its diagnosed terms
     "source_recording": "run.mcap"}

The spindle's effects (screw_backlash: backlash_mm; servo_deadband: deadband_raw, hysteresis_raw) are listed under
"effects" and carried by "spindle_params" (screw_backlash_mm, servo_deadband_raw, servo_deadband_hysteresis_raw),
which the spindle plant applies; a file without "spindle_params" is the nominal spindle.

"esc_input_delay_s" (optional, default 0; the refit finds 0-3 ms, a file may hold up to MAX_INPUT_DELAY_S) is the
refit's ESC input delay, a unit property DriveParams has no field for; the SIL applies it on its actuator seam. An esc_latency effect acting everywhere carries the whole delay
(the same term), one confined to a speed range acts inside it and this delay outside.

``load_model(path)`` reads it back (ModelMismatchError naming the field when it is malformed);
``DiagnosedModel.sil_drive_params()`` and ``install(session)`` put it into a SilSession
(``SilSession(model=path)`` does both).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler_sim.diagnose.errors import ModelMismatchError
from robowrangler_sim.diagnose.gates import GATE_TERMS, RegimeGate
from robowrangler_sim.plants import DriveParams, DriveParamsError
from robowrangler_sim.plants import drive_batch as db
from robowrangler_sim.plants.spindle import SpindleParams, SpindleParamsError
from robowrangler_sim.rope import RopeParams

FORMAT = "robowrangler.drive_model"
FORMAT_VERSION = 1
MAX_INPUT_DELAY_S = 0.05
EFFECT_COLUMNS = {
    "rope_drag_law": {"drag_exponent": db.TH_DRAG_EXP},
    "esc_latency": {"delay_s": db.TH_LATENCY},
    "esc_deadband": {"hysteresis_us": db.TH_HYST},
    "battery_sag": {"polarisation_resistance_ohm": db.TH_POL_R, "polarisation_time_constant_s": db.TH_POL_TAU},
    "low_speed_friction": {"stribeck_force_n": db.TH_STRIBECK_N, "stribeck_speed_mps": db.TH_STRIBECK_V},
    "external_rope_load": {"external_load_n": db.TH_EXT_LOAD},
}
GATED_COLUMNS = {
    "esc_deadband": {"deadband_us": db.TH_DEADBAND},
    "rope_drag_law": {"rope_drag_coeff_n_s2_per_m2": db.TH_DRAG_K},
}
"""An effect confined to one regime (gates.py) also carries these, which the drive parameters hold otherwise."""
SPINDLE_EFFECT_FIELDS = {
    "screw_backlash": {"backlash_mm": "screw_backlash_mm"},
    "servo_deadband": {"deadband_raw": "servo_deadband_raw", "hysteresis_raw": "servo_deadband_hysteresis_raw"},
}
"""Spindle effect parameters -> the SpindleParams fields that carry them."""


def params_from_theta(base: DriveParams, theta: np.ndarray) -> DriveParams:
    """DriveParams whose theta_from_params equals theta's nominal columns (class estimates scaled together)."""
    p = base
    th0 = db.theta_from_params(p)
    kt = theta[db.TH_KT]
    f_coul = theta[db.TH_COULOMB_N] / th0[db.TH_COULOMB_N]
    f_visc = theta[db.TH_VISCOUS_N_S_PER_M] / th0[db.TH_VISCOUS_N_S_PER_M]
    rope_j = p.rope_mass_kg * p.wheel_radius_m ** 2
    f_j = (theta[db.TH_INERTIA] - rope_j) / (th0[db.TH_INERTIA] - rope_j)
    return dataclasses.replace(
        p, motor_kv_rpm_per_v=60.0 / (2.0 * math.pi * kt),
        motor_resistance_ohm=max(1e-4, theta[db.TH_R_CIRCUIT] - p.esc_resistance_ohm),
        motor_coulomb_friction_nm=p.motor_coulomb_friction_nm * f_coul, guide_friction_n=p.guide_friction_n * f_coul,
        nip_friction_n=p.nip_friction_n * f_coul,
        motor_viscous_friction_nm_s_per_rad=p.motor_viscous_friction_nm_s_per_rad * f_visc,
        nip_viscous_n_s_per_m=p.nip_viscous_n_s_per_m * f_visc,
        rotor_inertia_kg_m2=p.rotor_inertia_kg_m2 * f_j, wheel_inertia_kg_m2=p.wheel_inertia_kg_m2 * f_j,
        rope=dataclasses.replace(p.rope, skin_friction_coeff=p.rope.skin_friction_coeff * theta[db.TH_DRAG_K]
                                 / th0[db.TH_DRAG_K]),
        battery_internal_resistance_ohm=float(theta[db.TH_BATT_R]),
        battery_open_circuit_v=float(theta[db.TH_BATT_OCV]), esc_lag_s=float(theta[db.TH_ESC_LAG]),
        esc_deadband_us=float(theta[db.TH_DEADBAND]))


@dataclass
class DiagnosedModel:
    """A drive model: DriveParams plus effect terms (effect id -> {param: value}) and external-load spans."""

    drive_params: DriveParams
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    external_load_spans_s: list[tuple[float, float]] = field(default_factory=list)
    source_recording: str = ""
    spindle_params: SpindleParams = field(default_factory=SpindleParams)
    esc_input_delay_s: float = 0.0
    """The ESC's input delay (the refit's unit property; an esc_latency effect everywhere replaces it)."""

    @classmethod
    def nominal(cls) -> DiagnosedModel:
        return cls(DriveParams())

    def gated_effects(self) -> dict[str, RegimeGate]:
        """The effects confined to one regime, with their gates."""
        out = {}
        for eid, values in self.effects.items():
            g = RegimeGate.from_json(values)
            if g is not None:
                out[eid] = g
        return out

    def theta(self) -> np.ndarray:
        """The model's row of the batched plant (an effect confined to a regime is not in it: gated_effects)."""
        th = db.theta_from_params(self.drive_params)
        th[db.TH_LATENCY] = self.esc_input_delay_s
        gated = self.gated_effects()
        for eid, values in self.effects.items():
            if eid in gated:
                continue
            for name, col in EFFECT_COLUMNS.get(eid, {}).items():
                if name in values:
                    th[col] = values[name]
        return th

    def check_fits(self, data) -> None:
        """ModelMismatchError when the recording's device parameters contradict the model's geometry."""
        dp = data.device_params
        checks = (("wheel_radius_m", self.drive_params.wheel_radius_m, 1e-3),
                  ("encoder_counts_per_rev", float(self.drive_params.encoder_counts_per_rev), 0.0),
                  ("esc_min_us", self.drive_params.esc_min_pulse_us, 0.0))
        for name, model_value, rel in checks:
            if name in dp and abs(dp[name] - model_value) > rel * abs(model_value) + 1e-9:
                raise ModelMismatchError(f"model does not fit {data.path.name}: the recording's device has "
                                         f"{name} = {dp[name]:g}, the model {model_value:g}")

    def extended(self, theta: np.ndarray, *, effects: list[str], load_spans_s, recording: str,
                 gates: dict | None = None) -> DiagnosedModel:
        """This model with theta's refitted parameters and the given effects' terms. gates: effect id ->
        (gates.RegimeGate, the theta row without the effect) for an effect confined to one regime: its terms carry
        the gate and its own values; the drive parameters take the row's values (what acts outside the regime)."""
        eff = {}
        base_theta = np.array(theta, dtype=float)
        for eid in effects:
            eff[eid] = {name: float(theta[col]) for name, col in EFFECT_COLUMNS.get(eid, {}).items()}
            if gates and eid in gates:
                gate, off_row = gates[eid]
                eff[eid].update({name: float(theta[col]) for name, col in GATED_COLUMNS.get(eid, {}).items()})
                eff[eid].update(gate.to_json())
                for col in {**EFFECT_COLUMNS.get(eid, {}), **GATED_COLUMNS.get(eid, {})}.values():
                    base_theta[col] = off_row[col]
        # the delay column is the ESC's own input delay unless a latency acting everywhere holds it
        delay = 0.0 if "esc_latency" in effects and not (gates and "esc_latency" in gates) \
            else float(base_theta[db.TH_LATENCY])
        return DiagnosedModel(params_from_theta(self.drive_params, base_theta), eff,
                              [(float(a), float(b)) for a, b in load_spans_s], recording, self.spindle_params,
                              delay)

    def to_json(self) -> dict:
        return {"format": FORMAT, "format_version": FORMAT_VERSION,
                "drive_params": dataclasses.asdict(self.drive_params), "effects": self.effects,
                "external_load_spans_s": [list(s) for s in self.external_load_spans_s],
                "source_recording": self.source_recording, "esc_input_delay_s": self.esc_input_delay_s,
                "spindle_params": dataclasses.asdict(self.spindle_params)}

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        path.write_text(json.dumps(self.to_json(), indent=1) + "\n")
        return path

    def sil_drive_params(self) -> DriveParams:
        return self.drive_params

    def sil_spindle_params(self) -> SpindleParams:
        """The spindle plant's parameters: refitted estimates and the diagnosed dead band / backlash terms."""
        return self.spindle_params

    def install(self, session) -> None:
        """Put the effect terms into a SilSession through its seams (actuator filter: latency and dead-band
        hysteresis; tick hook: drag law, Stribeck friction, external load, polarisation sag)."""
        from robowrangler_sim.diagnose.sil_effects import install_effects
        install_effects(session, self)


def read_model_document(path: Path, *, what: str, fmt: str, version: int) -> dict:
    """The JSON object of a model file whose format and format_version are fmt and version; ModelMismatchError
    naming `what` (e.g. "model file") and the path otherwise."""
    try:
        doc = json.loads(path.read_text())
    except OSError as err:
        raise ModelMismatchError(f"{what} {path}: cannot read: {err}") from err
    except json.JSONDecodeError as err:
        raise ModelMismatchError(f"{what} {path}: not JSON: {err}") from err
    if not isinstance(doc, dict) or doc.get("format") != fmt:
        raise ModelMismatchError(f"{what} {path}: expected format {fmt!r}, got "
                                 f"{doc.get('format') if isinstance(doc, dict) else type(doc).__name__!r}")
    if doc.get("format_version") != version:
        raise ModelMismatchError(f"{what} {path}: expected format_version {version}, "
                                 f"got {doc.get('format_version')!r}")
    return doc


def load_model(path: str | Path) -> DiagnosedModel:
    """Read a model file; ModelMismatchError naming what is wrong."""
    path = Path(path)
    doc = read_model_document(path, what="model file", fmt=FORMAT, version=FORMAT_VERSION)
    known = {f.name for f in dataclasses.fields(DriveParams)}
    dp = doc.get("drive_params", {})
    unknown = sorted(set(dp) - known)
    if unknown:
        raise ModelMismatchError(f"model file {path}: unknown drive_params {', '.join(unknown)}")
    try:
        rope = dp.get("rope", {})
        if isinstance(rope, dict):
            dp = {**dp, "rope": RopeParams(**rope)} if rope else {k: v for k, v in dp.items() if k != "rope"}
        params = DriveParams(**dp)
    except (DriveParamsError, TypeError, ValueError) as err:
        raise ModelMismatchError(f"model file {path}: drive_params: {err}") from err
    effects = doc.get("effects", {})
    known_effects = {**EFFECT_COLUMNS, **SPINDLE_EFFECT_FIELDS}
    for eid, values in effects.items():
        if eid not in known_effects:
            raise ModelMismatchError(f"model file {path}: unknown effect {eid!r}; known: {', '.join(known_effects)}")
        allowed = set(known_effects[eid])
        if eid in EFFECT_COLUMNS:
            allowed |= set(GATED_COLUMNS.get(eid, {})) | set(GATE_TERMS)
        bad = sorted(set(values) - allowed)
        if bad:
            raise ModelMismatchError(f"model file {path}: effect {eid}: unknown parameters {', '.join(bad)}")
        for k, v in values.items():
            if not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ModelMismatchError(f"model file {path}: effect {eid}.{k}: expected a finite number, got {v!r}")
        try:
            RegimeGate.from_json(values)
        except ValueError as err:
            raise ModelMismatchError(f"model file {path}: effect {eid}: {err}") from err
    spans = [tuple(map(float, s)) for s in doc.get("external_load_spans_s", [])]
    delay = doc.get("esc_input_delay_s", 0.0)
    if isinstance(delay, bool) or not isinstance(delay, (int, float)) or not 0.0 <= delay <= MAX_INPUT_DELAY_S:
        raise ModelMismatchError(f"model file {path}: esc_input_delay_s: expected seconds in 0-{MAX_INPUT_DELAY_S}, "
                                 f"got {delay!r}")
    sp = doc.get("spindle_params", {})
    sp_known = {f.name for f in dataclasses.fields(SpindleParams)}
    if not isinstance(sp, dict) or set(sp) - sp_known:
        raise ModelMismatchError(f"model file {path}: unknown spindle_params "
                                 f"{', '.join(sorted(set(sp) - sp_known)) if isinstance(sp, dict) else sp!r}")
    try:
        spindle = SpindleParams(**sp)
    except (SpindleParamsError, TypeError, ValueError) as err:
        raise ModelMismatchError(f"model file {path}: spindle_params: {err}") from err
    # a spindle effect listed under "effects" is what spindle_params carries: they must agree
    for eid, names in SPINDLE_EFFECT_FIELDS.items():
        for name, fld in names.items():
            if eid in effects and name in effects[eid] and abs(effects[eid][name] - getattr(spindle, fld)) > 1e-9:
                if not sp:
                    spindle = dataclasses.replace(spindle, **{fld: float(effects[eid][name])})
                else:
                    raise ModelMismatchError(f"model file {path}: effect {eid}.{name} = {effects[eid][name]!r} but "
                                             f"spindle_params.{fld} = {getattr(spindle, fld)!r}")
    return DiagnosedModel(params, {k: dict(v) for k, v in effects.items()}, spans, str(doc.get("source_recording", "")),
                          spindle, float(delay))
