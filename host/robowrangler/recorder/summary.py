"""What a recording holds, as data (summarize) and as text (format_summary): `wrangler inspect`."""

from __future__ import annotations

from typing import Any

from robowrangler.recorder.reader import Recording


def summarize(rec: Recording) -> dict[str, Any]:
    """A JSON-ready summary.

    Keys: path, source, schema_hash, created_utc, truncated, truncation_reason, chunks, damaged (skipped
    damaged chunks, one line each), duration_s
    (log_time span), channels {topic: message count} (foreign channels included), foreign_channels
    {topic: schema name}, telemetry {count, rate_hz, device_time_s [first, last], states (visited, in
    order, consecutive repeats removed)}, gaps {count, missing (frames), open (gaps of unknown extent)},
    commands {count, by verdict},
    events {count, by kind}.
    """
    tele = rec.telemetry
    n = len(tele["log_time_ns"])
    telemetry: dict[str, Any] = {"count": n}
    if n:
        span_s = (tele["log_time_ns"][-1] - tele["log_time_ns"][0]) * 1e-9
        telemetry["rate_hz"] = round((n - 1) / span_s, 2) if span_s > 0 else None
        telemetry["device_time_s"] = [float(tele["time_s"][0]), float(tele["time_s"][-1])]
        states = [s for i, s in enumerate(tele["state"]) if i == 0 or s != tele["state"][i - 1]]
        telemetry["states"] = states
    gaps = rec.gaps
    verdicts: dict[str, int] = {}
    for c in rec.commands:
        verdicts[c["verdict"]] = verdicts.get(c["verdict"], 0) + 1
    kinds: dict[str, int] = {}
    for e in rec.events:
        kinds[e["event"]] = kinds.get(e["event"], 0) + 1
    return {
        "path": str(rec.path),
        "source": rec.meta.get("source"),
        "schema_hash": rec.meta.get("schema_hash"),
        "created_utc": rec.meta.get("created_utc"),
        "truncated": rec.truncated,
        "truncation_reason": rec.truncation_reason,
        "chunks": rec.chunks,
        "damaged": list(rec.damaged),
        "duration_s": round(rec.duration_s, 3),
        "channels": dict(sorted(rec.topic_counts.items())),
        "foreign_channels": rec.foreign_topics,
        "telemetry": telemetry,
        "gaps": {"count": len(gaps), "missing": int(sum(g["missing"] or 0 for g in gaps)),
                 "open": sum(1 for g in gaps if g["to_seq"] is None)},
        "commands": {"count": len(rec.commands), "verdicts": verdicts},
        "events": {"count": len(rec.events), "kinds": kinds},
    }


def format_summary(s: dict[str, Any]) -> str:
    """Human text of a summarize() result."""
    lines = [f"{s['path']}: {s['source']} recording, protocol schema {s['schema_hash']}, "
             f"{s['duration_s']:.2f} s, {s['chunks']} chunks"]
    if s["truncated"]:
        lines.append(f"TRUNCATED: {s['truncation_reason']}")
    for damage in s.get("damaged", []):
        lines.append(f"DAMAGED: {damage}")
    lines.append("channels:")
    width = max((len(t) for t in s["channels"]), default=0)
    for topic, count in s["channels"].items():
        foreign = s["foreign_channels"].get(topic)
        note = f"  (not decoded: schema {foreign!r})" if foreign is not None else ""
        lines.append(f"  {topic:<{width}}  {count:7d}{note}")
    t = s["telemetry"]
    if t["count"]:
        rate = f"{t['rate_hz']:.1f} Hz" if t.get("rate_hz") else "-"
        lines.append(f"telemetry: {t['count']} samples at {rate}, device time {t['device_time_s'][0]:.3f}.."
                     f"{t['device_time_s'][1]:.3f} s, states {' -> '.join(t['states'])}")
    else:
        lines.append("telemetry: none")
    g = s["gaps"]
    lines.append(f"gaps: {g['count']} ({g['missing']} frames missing" + (f", {g['open']} of unknown extent)"
                                                                       if g["open"] else ")"))
    if s["commands"]["count"]:
        verdicts = ", ".join(f"{k} {v}" for k, v in sorted(s["commands"]["verdicts"].items()))
        lines.append(f"commands: {s['commands']['count']} ({verdicts})")
    if s["events"]["count"]:
        kinds = ", ".join(f"{k} {v}" for k, v in sorted(s["events"]["kinds"].items()))
        lines.append(f"events: {s['events']['count']} ({kinds})")
    return "\n".join(lines)
