"""Closed-loop before/after: the SIL firmware fed the recording's commands, with the model as given (nominal) and
with the diagnosed model, each compared with the recording on the same channels.

The commands are the recording's /host/command records (ARM, DISARM, HOME, SPINDOWN, SET_ROPE_SPEED, SET_LOOP,
PARAM_SET;
others are listed as not replayed), sent at the device time they were sent: a record is written when its reply
arrives, so the send time is its log time less reply_latency_s, moved onto the device clock by the median offset
between the telemetry's log times and its time_s. Everything else (heartbeats, the firmware's own loops) is the
SIL's. Compared per channel over the recording's telemetry times: rope_speed_mps, guide_position_m,
spindle_load_permille (RMS of recording - SIL; the spindle's two from the first sample whose spindle_flags has
HOMED on).

    cmp = closed_loop_compare("run.mcap", nominal=DiagnosedModel.nominal(), fitted=result.model)
    cmp["rms"]["guide_position_m"]  ->  {"nominal": 0.0021, "fitted": 0.0004}
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robowrangler import units
from robowrangler.protocol import generated as gen
from robowrangler.recorder import read_recording
from robowrangler_sim.diagnose.errors import DiagnoseError

CHANNELS = ("rope_speed_mps", "guide_position_m", "spindle_load_permille")
_NO_FIELDS = {"ARM": gen.Arm, "DISARM": gen.Disarm, "HOME": gen.Home, "SPINDOWN": gen.Spindown}


def _message(record: dict) -> gen.Message | None:
    name, fields = record.get("message"), record.get("fields") or {}
    if name in _NO_FIELDS:
        return _NO_FIELDS[name]()
    if name == "SET_ROPE_SPEED" and "rope_speed_mps" in fields:
        return gen.SetRopeSpeed(units.mps_to_mmps(fields["rope_speed_mps"]))
    if name == "SET_LOOP" and "guide_position_m" in fields:
        return gen.SetLoop(units.m_to_um(fields["guide_position_m"]))
    if name == "PARAM_SET" and "param_id" in fields and "value" in fields:
        return gen.ParamSet(int(fields["param_id"]), float(fields["value"]))
    return None


def recorded_commands(path: str | Path) -> tuple[list[tuple[float, gen.Message]], list[str], dict[str, np.ndarray]]:
    """([(device time_s, message), ...], names not replayed, the recording's telemetry columns).
    DiagnoseError when the recording has no telemetry or no command to replay."""
    rec = read_recording(path)
    tel_records = rec.records.get("/device/telemetry", [])
    if not tel_records:
        raise DiagnoseError(f"{path}: no /device/telemetry: nothing to compare a closed-loop run with")
    offset_s = float(np.median([r.log_time_ns * 1e-9 - r.data["time_s"] for r in tel_records]))
    out, skipped = [], []
    for r in rec.records.get("/host/command", []):
        msg = _message(r.data)
        if msg is None:
            skipped.append(str(r.data.get("message")))
            continue
        latency = r.data.get("reply_latency_s") or 0.0
        out.append((r.log_time_ns * 1e-9 - latency - offset_s, msg))
    if not out:
        raise DiagnoseError(f"{path}: no /host/command the closed-loop replay can send (it replays "
                            f"{', '.join(list(_NO_FIELDS) + ['SET_ROPE_SPEED', 'SET_LOOP', 'PARAM_SET'])})")
    out.sort(key=lambda c: c[0])
    return out, sorted(set(skipped)), rec.telemetry


def run_closed_loop(model, commands: list[tuple[float, gen.Message]], end_s: float, *, seed: int = 0
                    ) -> dict[str, np.ndarray]:
    """The SIL firmware with `model` (a DiagnosedModel) fed the commands at their device times until end_s;
    its telemetry as columns in the recording's units."""
    from robowrangler_sim.sil import SilSession
    from robowrangler_sim.sil.scripted_host import ScriptedHost

    with SilSession(model=model, speedup=None, seed=seed) as sil:
        host = ScriptedHost(sil)
        try:
            for at_s, msg in commands:
                while sil.time_s < at_s:
                    host.tick()
                host.send(msg)
            while sil.time_s < end_s:
                host.tick()
            tel = list(host.received.telemetry)
        finally:
            host.close()
    return {"time_s": np.array([t.time_ms * 1e-3 for t in tel]),
            "rope_speed_mps": np.array([t.rope_speed_mmps * 1e-3 for t in tel]),
            "guide_position_m": np.array([t.guide_position_um * 1e-6 for t in tel]),
            "spindle_load_permille": np.array([float(t.spindle_load_permille) for t in tel])}


def closed_loop_compare(path: str | Path, *, nominal, fitted, seed: int = 0) -> dict:
    """{"rms": {channel: {"nominal": x, "fitted": y}}, "replayed_commands": n, "not_replayed": [...],
    "span_s": [t0, t1], "series": {...}} (series: recording and both runs on the recording's times)."""
    commands, skipped, tel = recorded_commands(path)
    t_rec = np.asarray(tel["time_s"], dtype=float)
    runs = {name: run_closed_loop(m, commands, float(t_rec[-1]) + 0.05, seed=seed)
            for name, m in (("nominal", nominal), ("fitted", fitted))}
    rms: dict[str, dict[str, float]] = {}
    series: dict[str, np.ndarray] = {"time_s": t_rec}
    homed_from_s = float(t_rec[0])
    if "spindle_flags" in tel:
        homed = np.array(["HOMED" in (f if isinstance(f, (list, tuple, np.ndarray)) else str(f).split(","))
                          for f in tel["spindle_flags"]])
        if homed.any():
            homed_from_s = float(t_rec[int(np.argmax(homed))])
    for ch in CHANNELS:
        if ch not in tel:
            continue
        y = np.asarray(tel[ch], dtype=float)
        rms[ch] = {}
        series[ch] = y
        # the spindle's channels from the first homed sample on (before it, the position counts from power-up and
        # homing ends on a stall spike whose timing a few ticks either way would decide the RMS)
        t_from = homed_from_s if ch != "rope_speed_mps" else float(t_rec[0])
        for name, run in runs.items():
            sim = np.interp(t_rec, run["time_s"], run[ch])
            ok = (t_rec >= max(run["time_s"][0], t_from)) & (t_rec <= run["time_s"][-1]) & np.isfinite(y)
            rms[ch][name] = float(np.sqrt(np.mean((y[ok] - sim[ok]) ** 2)))
            series[f"{name}_{ch}"] = sim
    return {"rms": rms, "replayed_commands": len(commands), "not_replayed": skipped,
            "span_s": [float(t_rec[0]), float(t_rec[-1])], "series": series}
