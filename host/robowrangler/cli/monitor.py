"""Telemetry commands: status (one sample) and watch (a stream)."""

from __future__ import annotations

import click

from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.stream import stream_telemetry, telemetry_table
from robowrangler.client import Client
from robowrangler.recorder.link import LinkRecorder, RecordingTransport
from robowrangler.recorder.live_view import FoxgloveLiveView
from robowrangler.transport import open_transport


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
@click.option("--foxglove", "foxglove_port", type=click.IntRange(0, 65535), is_flag=False, flag_value=8765,
              default=None, metavar="[PORT]",
              help="Also serve the stream live to Foxglove (ws://127.0.0.1:PORT, default 8765; foxglove-sdk).")
@pass_context
def watch(ctx: CliContext, duration_s: float | None, foxglove_port: int | None) -> None:
    """Stream telemetry and events (JSON lines with --json); --foxglove serves them to Foxglove too.

    To watch while another tool commands, go through `wrangler proxy` (the device sends its telemetry to
    the host it heard last)."""
    live = FoxgloveLiveView(port=foxglove_port) if foxglove_port is not None else None
    try:
        if live is None:
            client = ctx.client()
        else:  # every frame also goes to the live view, through the recorder's tap
            client = Client(ctx.url, connect_timeout_s=ctx.timeout_s, key=ctx.key,
                            transport=RecordingTransport(open_transport(ctx.url), LinkRecorder(live)))
            ctx.note(f"live in Foxglove at {live.url}")
        with client as rw:
            count = stream_telemetry(ctx, rw, duration_s=duration_s)
            if not ctx.json_mode:
                ctx.note(f"{count} samples")
    finally:
        if live is not None:
            live.close()
