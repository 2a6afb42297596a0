"""The library's effect laws put into a SilSession through its seams (the model file's effects, in the SIL).

Actuator filter: esc_latency (the pulse of d seconds ago; the model's esc_input_delay_s where no latency acts)
and esc_deadband's hysteresis (stays at zero throttle
until min + w + h once stopped). Tick hook, through the session's ``loads`` (the plant contract's inputs):
rope_drag_law (the plant's own k v |v| drag switched off by rope_exposed_length_m = 0 and the power law applied
as external_rope_load_n), low_speed_friction (Stribeck), external_rope_load (over its spans, plant time) and
battery_sag (a polarisation voltage as extra aux current).

An effect confined to one speed range (its terms carry a gate, gates.RegimeGate) acts only while the plant's rope
speed is in that range; outside it the drive parameters' own terms act (the model file holds there what the
diagnosis fitted outside the range).
"""

from __future__ import annotations

import math
from collections import deque

from robowrangler_sim.diagnose.gates import RegimeGate
from robowrangler_sim.plants.drive_batch import V_REF_MPS


def install_effects(session, model) -> None:
    p = model.drive_params
    eff = model.effects
    tick_s = session.tick_us * 1e-6
    gates = {eid: RegimeGate.from_json(values) for eid, values in eff.items()}
    state = {"v": 0.0}  # the plant's rope speed at the last tick

    def is_on(eid: str) -> bool:
        g = gates.get(eid)
        return g is None or bool(g.on(state["v"]))

    n_in = round(model.esc_input_delay_s / tick_s)  # ticks of the ESC's own input delay
    lat_s = eff.get("esc_latency", {}).get("delay_s", 0.0)
    n_lat = max(1, round(lat_s / tick_s)) if lat_s > 0.0 else (0 if "esc_latency" in eff else n_in)
    if max(n_in, n_lat) > 0:
        n = max(n_in, n_lat)
        line: deque[int] = deque([0] * (n + 1), maxlen=n + 1)

        def delay(pulse_us: int) -> int:
            line.append(pulse_us)  # line[-1 - k]: the pulse of k ticks ago
            return line[-1 - (n_lat if is_on("esc_latency") else n_in)]
        session.actuator_filters.append(delay)
    db_terms = eff.get("esc_deadband", {})
    if db_terms and (db_terms.get("hysteresis_us", 0.0) > 0.0 or gates.get("esc_deadband") is not None):
        # everywhere: the width is the drive parameters' (the plant applies it), the filter adds the hysteresis;
        # confined: the filter applies the effect's own width and hysteresis while in the regime
        top = p.esc_min_pulse_us + db_terms.get("deadband_us", p.esc_deadband_us)
        hyst = db_terms.get("hysteresis_us", 0.0)
        zone = {"off": True}

        def deadband(pulse_us: int) -> int:
            if pulse_us < p.esc_min_pulse_us:
                return pulse_us
            if zone["off"] and pulse_us > top + hyst:
                zone["off"] = False
            elif not zone["off"] and pulse_us <= top:
                zone["off"] = True
            return int(p.esc_min_pulse_us) if zone["off"] and is_on("esc_deadband") else pulse_us
        session.actuator_filters.append(deadband)
    drag_n = eff.get("rope_drag_law", {}).get("drag_exponent")
    strib = eff.get("low_speed_friction", {})
    ext = eff.get("external_rope_load", {}).get("external_load_n", 0.0)
    sag = eff.get("battery_sag", {})
    if drag_n is None and not strib and not ext and not sag and not any(gates.values()):
        return
    k = eff.get("rope_drag_law", {}).get("rope_drag_coeff_n_s2_per_m2", p.rope_drag_coeff_n_s2_per_m2)
    base_aux = p.battery_aux_current_a
    pol = {"v": 0.0}
    exposed = {"saved": None, "drag_on": False}

    def hook(s) -> None:
        out = s.drive_out
        v = abs(out.rope_speed_mps)
        state["v"] = v
        f = 0.0
        if drag_n is not None:
            on = is_on("rope_drag_law")
            if on and not exposed["drag_on"]:
                exposed["saved"] = s.loads.rope_exposed_length_m
            elif not on and exposed["drag_on"]:
                s.loads.rope_exposed_length_m = exposed["saved"]
            exposed["drag_on"] = on
            if on:
                s.loads.rope_exposed_length_m = 0.0
                f += k * V_REF_MPS ** 2 * (v / V_REF_MPS) ** drag_n
        if strib and is_on("low_speed_friction"):
            f += strib["stribeck_force_n"] * math.exp(-(v / strib["stribeck_speed_mps"]) ** 2)
        if ext and is_on("external_rope_load") and any(a <= s.time_s <= b for a, b in model.external_load_spans_s):
            f += ext
        s.loads.external_rope_load_n = max(0.0, f)
        if sag:
            i = out.battery_current_a - out.battery_aux_current_a + base_aux
            r = sag["polarisation_resistance_ohm"] if is_on("battery_sag") else 0.0
            tau = sag["polarisation_time_constant_s"]
            pol["v"] = r * i + (pol["v"] - r * i) * math.exp(-tick_s / tau)
            s.loads.battery_aux_current_a = base_aux + max(0.0, pol["v"]) / p.battery_internal_resistance_ohm
    session.tick_hooks.append(hook)
