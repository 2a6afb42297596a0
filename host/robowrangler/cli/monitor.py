"""Telemetry commands: status (one sample) and watch (a stream)."""

from __future__ import annotations

import click

from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.stream import stream_telemetry, telemetry_table


@click.command()
@pass_context
def status(ctx: CliContext) -> None:
    """Print one telemetry sample (a table, or one JSON object with --json)."""
    with ctx.client() as rw:
        sample = rw.latest_telemetry
        ctx.result({"command": "status", "telemetry": sample.to_dict()}, telemetry_table(sample))


@click.command()
@click.option("--duration", "duration_s", type=Seconds(), default=None, metavar="SECONDS",
              help="Stop after this long (default: until Ctrl-C).")
@pass_context
def watch(ctx: CliContext, duration_s: float | None) -> None:
    """Stream telemetry and events (JSON lines with --json)."""
    with ctx.client() as rw:
        count = stream_telemetry(ctx, rw, duration_s=duration_s)
        if not ctx.json_mode:
            ctx.note(f"{count} samples")
