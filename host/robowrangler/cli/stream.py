"""Telemetry and event output shared by `watch`, `status` and `spin --hold`."""

from __future__ import annotations

import time
from collections.abc import Callable

from robowrangler import units
from robowrangler.cli.context import CliContext
from robowrangler.client import Client
from robowrangler.telemetry import DeviceEvent, TelemetrySample

HUMAN_LINE_PERIOD_S = 0.1  # human output is thinned to 10 lines/s; --json gets every sample


def telemetry_line(s: TelemetrySample) -> str:
    """One fixed-width human line for a sample."""
    faults = ",".join(f.name for f in type(s.fault_bits) if f in s.fault_bits) or "-"
    return (f"{s.time_s:9.3f} s  {s.state.name:<9} speed {s.rope_speed_mps:6.2f} m/s "
            f"(setpoint {s.rope_speed_setpoint_mps:6.2f}, target {s.rope_speed_target_mps:6.2f})  "
            f"{s.motor_rpm:5d} rpm  esc {s.esc_pulse_us:4d} us  {s.battery_v:5.2f} V  "
            f"guide {units.m_to_mm(s.guide_position_m):6.1f} mm  load {s.spindle_load_pct:5.1f} %  faults {faults}")


def telemetry_table(s: TelemetrySample) -> str:
    """A multi-line human table of one sample (`wrangler status`)."""
    rows = [(k, v.name if hasattr(v, "name") and not isinstance(v, (int, float)) else v)
            for k, v in s.to_dict().items() if k != "received_s"]
    rows = [(k, ", ".join(v) or "none") if isinstance(v, list) else (k, v) for k, v in rows]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def event_line(e: DeviceEvent) -> str:
    return f"{e.time_s:9.3f} s  event #{e.event_seq}: {e.describe()}"


def stream_telemetry(ctx: CliContext, client: Client, *, duration_s: float | None,
                     events_from: int | None = None,
                     until: Callable[[TelemetrySample], bool] | None = None) -> int:
    """Print telemetry (and new events) until duration_s has passed (None: until Ctrl-C).

    --json: every sample as a JSON line {"type": "telemetry", ...}, events as {"type": "event", ...}.
    Human: at most 10 telemetry lines per second, events as they come. events_from: index in
    client.events of the first event to print (default: events arriving from now on); until: stop early
    after the first sample for which until(sample) is true. Returns the sample count.
    """
    start_s = time.monotonic()
    seen_events = len(client.events) if events_from is None else events_from
    count = 0
    last_human_s = -1.0
    for sample in client.telemetry(timeout_s=ctx.timeout_s):
        events = client.events
        for ev in events[seen_events:]:
            if ctx.json_mode:
                ctx.json_line({"type": "event", **ev.to_dict()})
            else:
                ctx.human_line(event_line(ev))
        seen_events = len(events)
        if ctx.json_mode:
            ctx.json_line({"type": "telemetry", **sample.to_dict()})
        elif sample.received_s - last_human_s >= HUMAN_LINE_PERIOD_S:
            ctx.human_line(telemetry_line(sample))
            last_human_s = sample.received_s
        count += 1
        if until is not None and until(sample):
            break
        if duration_s is not None and time.monotonic() - start_s >= duration_s:
            break
    return count
