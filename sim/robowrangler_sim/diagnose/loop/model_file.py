"""The extended chain model the loop diagnosis writes (the chain's refitted parameters + the chosen loop effect), as
JSON, and how the chain plant and the SIL load it.

    {"format": "robowrangler.loop_model", "format_version": 1,
     "chain": {"kd_upper_nms_per_rad": 5000.0, "kp_upper_nm_per_rad": 10000.0, "rope_length_m": 2.2, ...},
     "loop_length_scale": 1.0,
     "shape_table": null,                       # null: the shipped default table; else a path
     "effects": {"uniform_wind": {"wind_speed_mps": 1.9}},
     "source_recording": "run.mcap"}

``LoopModel.chain_params()`` and ``LoopModel.shape_table()`` give what ChainPlant(table=..., params=...) takes: the
steady effects (speed dependence, C_f, wind, tip bending) baked into a shape table over a dense speed grid (the
chain snaps to the speed at or below, so a 0.25 m/s grid is nearly continuous); the servo time constant as kd;
transient_wave_dynamics as the chain's best first-order stand-in (kd/kp = mean transport delay L / (2 c) plus the
settling time). The rotation laws (normal_drag_coefficient, gyroscopic_base_rotation) have no place in the chain
plant: they are kept in the file for the fast form and reported as such (`wrangler sil --scenario ... --model FILE`
says so).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler_sim.chain.default_table import load_default_shape_table
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.diagnose.errors import ModelMismatchError
from robowrangler_sim.diagnose.loop import shape_model as sm
from robowrangler_sim.diagnose.model_file import read_model_document
from robowrangler_sim.shape_table import ShapeTable

FORMAT = "robowrangler.loop_model"
FORMAT_VERSION = 1
EFFECT_COLUMNS = {
    "loop_speed_dependence": {"speed_shape_gain": sm.TH_SPEED_GAIN},
    "axial_drag_coefficient": {"skin_friction_coeff": sm.TH_CF},
    "normal_drag_coefficient": {"normal_drag_lag_s": sm.TH_ROT_LAG_S},
    "tip_bending_stiffness": {"bending_stiffness_n_m2": sm.TH_BEND_N_M2},
    "transient_wave_dynamics": {"wave_speed_mps": sm.TH_WAVE_MPS, "settling_time_s": sm.TH_TAU_S},
    "uniform_wind": {"wind_speed_mps": sm.TH_WIND_MPS},
    "gyroscopic_base_rotation": {"coriolis_gain_s2_per_m": sm.TH_GYRO_S2_PER_M},
}
NOT_IN_CHAIN = ("normal_drag_coefficient", "gyroscopic_base_rotation")
DENSE_SPEED_STEP_MPS = 0.25
_CHAIN_FIELDS = ("kp_upper_nm_per_rad", "kd_upper_nms_per_rad", "rope_length_m", "rope_inside_at_home_m",
                 "guide_take_up_ratio", "guide_stroke_mm")


@dataclass
class LoopModel:
    """A chain model of the loop: ChainParams, the shape table (None: the shipped default), the loop length scale and
    the loop effects (id -> {param: value})."""

    chain: ChainParams = field(default_factory=ChainParams)
    table_path: str | None = None
    loop_length_scale: float = 1.0
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    source_recording: str = ""

    @classmethod
    def nominal(cls) -> LoopModel:
        return cls()

    # --- what the diagnosis needs ---------------------------------------------------------------------------------
    def base_table(self) -> ShapeTable:
        if self.table_path is None:
            return load_default_shape_table()
        try:
            return ShapeTable.load(self.table_path)
        except (OSError, ValueError) as err:
            raise ModelMismatchError(f"loop model: shape table {self.table_path}: {err}") from err

    def takeoff_speed_mps(self) -> float:
        return self.chain.takeoff_speed_mps

    def loop_length_m(self, guide_m: float) -> float:
        g_mm = min(max(float(guide_m) * 1e3, 0.0), self.chain.guide_stroke_mm)
        return self.chain.loop_length_m(g_mm)

    def shape_model(self) -> sm.LoopShapeModel:
        tau = self.chain.kd_upper_nms_per_rad / self.chain.kp_upper_nm_per_rad
        return sm.LoopShapeModel(self.base_table(), rope=self.chain.rope, tau_s=tau, n_points=40)

    def theta(self, shape: sm.LoopShapeModel) -> np.ndarray:
        th = shape.theta0()
        th[sm.TH_LEN_SCALE] = self.loop_length_scale
        for eid, values in self.effects.items():
            for name, col in EFFECT_COLUMNS.get(eid, {}).items():
                if name in values:
                    th[col] = values[name]
        return th

    def extended(self, theta: np.ndarray, *, effects: list[str], recording: str) -> LoopModel:
        """This model with theta's refitted chain parameters and the given effects' terms."""
        eff = dict(self.effects)
        for eid in effects:
            eff[eid] = {name: float(theta[col]) for name, col in EFFECT_COLUMNS[eid].items()}
        chain = dataclasses.replace(self.chain, kd_upper_nms_per_rad=float(theta[sm.TH_TAU_S])
                                    * self.chain.kp_upper_nm_per_rad)
        return LoopModel(chain, self.table_path, float(theta[sm.TH_LEN_SCALE]), eff, recording)

    # --- what the chain plant and the SIL load ---------------------------------------------------------------------
    def chain_params(self) -> ChainParams:
        """ChainParams with the refitted servo time constant (or the wave dynamics' first-order stand-in: the mean
        transport delay plus the settling time, kept in kd) and the loop length scale folded into the rope length."""
        kd = self.chain.kd_upper_nms_per_rad
        wave = self.effects.get("transient_wave_dynamics", {}).get("wave_speed_mps", 0.0)
        if wave > 0:
            kd += self.chain.kp_upper_nm_per_rad * self.chain.home_loop_length_m / (2.0 * wave)
        inside = self.chain.rope_inside_at_home_m
        rope_len = inside + self.chain.home_loop_length_m * self.loop_length_scale
        return dataclasses.replace(self.chain, kd_upper_nms_per_rad=kd, rope_length_m=rope_len)

    def shape_table(self) -> ShapeTable:
        """The base table with the steady effects baked in, on a dense speed grid (unchanged when none)."""
        base = self.base_table()
        steady = {k: v for k, v in self.effects.items() if k not in NOT_IN_CHAIN and k != "transient_wave_dynamics"}
        if not steady:
            return base
        shape = sm.LoopShapeModel(base, rope=self.chain.rope, tau_s=0.5, n_points=base.n_points)
        th = self.theta(shape)
        th[sm.TH_LEN_SCALE] = 1.0
        th[sm.TH_ROT_LAG_S] = 0.0
        th[sm.TH_GYRO_S2_PER_M] = 0.0
        lo, hi = float(base.rope_speed_mps[0]), float(base.rope_speed_mps[-1])
        speeds = np.arange(lo, hi + 1e-9, DENSE_SPEED_STEP_MPS) if base.rope_speed_mps.size > 1 else base.rope_speed_mps
        phi_rad = np.deg2rad(base.phi_deg)
        out = np.empty((speeds.size, phi_rad.size, base.n_points, 2))
        for i, v in enumerate(speeds):
            c = shape.targets(th[None, :], phi_rad=phi_rad, phidot_rad_s=np.zeros_like(phi_rad),
                              speed_mps=np.full(phi_rad.size, v), loop_length_m=np.full(phi_rad.size,
                                                                                        base.loop_length_m))
            out[i] = c[0]
        return ShapeTable(phi_deg=base.phi_deg, rope_speed_mps=speeds, contours_m=out,
                          loop_length_m=base.loop_length_m,
                          source=f"{base.source} + wrangler diagnose loop effects {sorted(steady)}")

    # --- file --------------------------------------------------------------------------------------------------------
    def to_json(self) -> dict:
        return {"format": FORMAT, "format_version": FORMAT_VERSION,
                "chain": {k: getattr(self.chain, k) for k in _CHAIN_FIELDS},
                "loop_length_scale": self.loop_length_scale, "shape_table": self.table_path,
                "effects": self.effects, "not_in_chain_plant": [e for e in self.effects if e in NOT_IN_CHAIN],
                "source_recording": self.source_recording}

    def save(self, path: str | Path) -> Path:
        path = Path(path)
        path.write_text(json.dumps(self.to_json(), indent=1) + "\n")
        return path

    @classmethod
    def load(cls, path: str | Path) -> LoopModel:
        """Read a loop model file; ModelMismatchError naming what is wrong."""
        path = Path(path)
        doc = read_model_document(path, what="loop model file", fmt=FORMAT, version=FORMAT_VERSION)
        chain_doc = doc.get("chain", {})
        bad = sorted(set(chain_doc) - set(_CHAIN_FIELDS))
        if bad:
            raise ModelMismatchError(f"loop model file {path}: unknown chain fields {', '.join(bad)}")
        try:
            chain = ChainParams(**chain_doc)
        except (TypeError, ValueError) as err:
            raise ModelMismatchError(f"loop model file {path}: chain: {err}") from err
        effects = doc.get("effects", {})
        for eid, values in effects.items():
            if eid not in EFFECT_COLUMNS:
                raise ModelMismatchError(f"loop model file {path}: unknown loop effect {eid!r}; known: "
                                         f"{', '.join(EFFECT_COLUMNS)}")
            for k, v in values.items():
                if k not in EFFECT_COLUMNS[eid]:
                    raise ModelMismatchError(f"loop model file {path}: effect {eid}: unknown parameter {k!r}")
                if not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise ModelMismatchError(f"loop model file {path}: effect {eid}.{k}: expected a finite number, "
                                             f"got {v!r}")
        scale = doc.get("loop_length_scale", 1.0)
        if not isinstance(scale, (int, float)) or not 0.5 < scale < 2.0:
            raise ModelMismatchError(f"loop model file {path}: loop_length_scale: expected a number in (0.5, 2), "
                                     f"got {scale!r}")
        return cls(chain, doc.get("shape_table"), float(scale), {k: dict(v) for k, v in effects.items()},
                   str(doc.get("source_recording", "")))


def is_loop_model_file(path: str | Path) -> bool:
    """True when the file is a loop model (format robowrangler.loop_model)."""
    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError):
        return False
    return isinstance(doc, dict) and doc.get("format") == FORMAT
