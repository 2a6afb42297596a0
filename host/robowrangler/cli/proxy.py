"""`wrangler proxy`: one owner of the device link that records everything and serves local tools.

The work is robowrangler.link_proxy.LinkProxy; recording is robowrangler.recorder (as `wrangler record`).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import click

from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.progress import PROGRESS_PERIOD_S
from robowrangler.cli.record import check_recording_path, default_source
from robowrangler.cli.signals import Interrupt, sigterm_as_interrupt
from robowrangler.client import Client
from robowrangler.errors import RoboWranglerError
from robowrangler.link_proxy import DEFAULT_PROXY_PORT, LinkProxy, TeeTransport
from robowrangler.recorder.fanout import Fanout
from robowrangler.recorder.link import LinkRecorder, RecordingTransport
from robowrangler.recorder.live_view import FoxgloveLiveView
from robowrangler.recorder.writer import RecordingWriter
from robowrangler.transport import open_transport

TICK_S = 0.1
PARAMS_PERIOD_S = 1.0  # the live view's /device/params again this often


@click.command("proxy")
@click.option("--listen", "listen_port", type=click.IntRange(0, 65535), default=DEFAULT_PROXY_PORT, show_default=True,
              metavar="PORT", help="Local UDP port for the tools (127.0.0.1 only).")
@click.option("--record", "record_path", type=click.Path(dir_okay=False, path_type=Path), default=None,
              metavar="FILE.mcap", help="Record everything the link carries (every tool's commands too) to FILE.")
@click.option("--force", is_flag=True, help="Replace the --record file if it exists.")
@click.option("--foxglove", "foxglove_port", type=click.IntRange(0, 65535), is_flag=False, flag_value=8765,
              default=None, metavar="[PORT]",
              help="Serve the same channels live to Foxglove (ws://127.0.0.1:PORT, default 8765; foxglove-sdk).")
@click.option("--duration", "duration_s", type=Seconds(positive=True), default=None, metavar="SECONDS",
              help="Stop after this long (default: until Ctrl-C or SIGTERM).")
@pass_context
def proxy(ctx: CliContext, listen_port: int, record_path: Path | None, force: bool, foxglove_port: int | None,
          duration_s: float | None) -> ExitStatus:
    """Own the device link, record it, and serve local tools on udp://127.0.0.1:PORT.

    The device answers one host at a time (its telemetry goes to the host heard last), so a recorder
    beside a commanding tool sees part of the stream. Run the proxy instead, and point every tool at it:

      wrangler proxy --record run.mcap &
      wrangler --url udp://127.0.0.1:14551 spin 4 --hold 5

    Tools' commands go through the proxy (recorded with their verdicts), the device's telemetry and events
    go to every tool. The proxy keeps the device's host alive only while a tool is: a rope or guide set
    moving by a tool that exits stops heartbeat_timeout_s later, as without the proxy.

    --foxglove serves the recording's channels live over Foxglove's WebSocket protocol (open
    ws://127.0.0.1:8765 in Foxglove): telemetry, events, every tool's commands, gaps, and the parameters
    with the ToV guard, with the recordings' JSON Schemas.
    """
    if record_path is not None:
        check_recording_path(record_path, force=force)
    link_proxy = LinkProxy(key=ctx.key, listen_port=listen_port)  # a taken port fails before the device link
    writer = recorder = live = None
    client: Client | None = None
    interrupted = False
    start_s = time.monotonic()
    try:
        sinks: list = []
        if record_path is not None:
            writer = RecordingWriter(record_path, source=default_source(ctx.url), device_url=ctx.url,
                                     description="wrangler proxy")
            sinks.append(writer)
        if foxglove_port is not None:
            live = FoxgloveLiveView(port=foxglove_port)
            sinks.append(live)
        transport = open_transport(ctx.url)
        if sinks:
            recorder = LinkRecorder(Fanout(sinks))
            transport = RecordingTransport(transport, recorder)
        client = Client(ctx.url, connect_timeout_s=ctx.timeout_s, key=ctx.key,
                        transport=TeeTransport(transport, link_proxy.from_device))
        with sigterm_as_interrupt() as stop:
            try:
                client.connect()
                params = _record_params(ctx, client, writer, live) if sinks else {}
                if live is not None:
                    def on_param(name: str, value: float) -> None:  # a tool set (or read) one: the live view follows
                        params[name] = value
                        live.publish_params(params)
                    link_proxy.on_param = on_param
                link_proxy.start(client)
                local = f"udp://127.0.0.1:{link_proxy.port}"
                ctx.note(f"serving {local} for local tools (wrangler --url {local} ...)"
                         + (f", recording to {record_path}" if record_path else "")
                         + (f", live in Foxglove at {live.url}" if live else "") + "; Ctrl-C or SIGTERM ends it")
                _serve(ctx, client, link_proxy, recorder, duration_s, start_s, stop,
                       republish=(lambda: live.publish_params(params)) if live is not None and params else None)
            except KeyboardInterrupt:
                interrupted = True
    finally:
        link_proxy.close()
        if client is not None:
            client.close()
        if recorder is not None:
            recorder.finish()
        if writer is not None:
            writer.close()
        if live is not None:
            live.close()
    stats = link_proxy.stats
    counts = {"tools": stats.tools_seen, "commands_carried": stats.commands_carried,
              "frames_to_tools": stats.frames_to_tools}
    if live is not None:
        counts["foxglove_messages"] = live.messages
    if recorder is not None:
        counts |= {"telemetry": recorder.telemetry_count, "events": recorder.event_count,
                   "commands": recorder.command_count, "gaps": recorder.gaps_written}
    elapsed_s = time.monotonic() - start_s
    ctx.result({"command": "proxy", "url": ctx.url, "port": link_proxy.port, "duration_s": round(elapsed_s, 3),
                "interrupted": interrupted, "record": None if record_path is None else str(record_path), **counts},
               f"proxied {ctx.url} for {elapsed_s:.1f} s" + (f" into {record_path}" if record_path else "") + ": "
               + ", ".join(f"{v} {k}" for k, v in counts.items()))
    return ExitStatus.OK


def _serve(ctx: CliContext, client: Client, link_proxy: LinkProxy, recorder: LinkRecorder | None,
           duration_s: float | None, start_s: float, stop: Interrupt, republish) -> None:
    """Until --duration (or Ctrl-C): progress on stderr; the parameters again every PARAMS_PERIOD_S for
    Foxglove clients that connected later (its channels keep no last value)."""
    last_note_s = last_params_s = start_s
    while duration_s is None or time.monotonic() - start_s < duration_s:
        stop.check()
        time.sleep(TICK_S)
        now_s = time.monotonic()
        if republish is not None and now_s - last_params_s >= PARAMS_PERIOD_S:
            last_params_s = now_s
            republish()
        if now_s - last_note_s >= PROGRESS_PERIOD_S:
            last_note_s = now_s
            sample = client.latest_telemetry
            recorded = "" if recorder is None else (f", {recorder.telemetry_count} telemetry, {recorder.event_count} "
                                                    f"events, {recorder.command_count} commands recorded")
            ctx.note(f"proxy: {now_s - start_s:6.1f} s, {link_proxy.tools_alive(now_s)} live tools, "
                     f"{link_proxy.stats.commands_carried} commands carried{recorded}, state "
                     f"{sample.state.name if sample else '-'}")


def _record_params(ctx: CliContext, client: Client, writer: RecordingWriter | None,
                   live: FoxgloveLiveView | None) -> dict[str, float]:
    """The device parameters into the recording's /device/params metadata and the live view ({} if unread)."""
    try:
        params = client.params()
    except RoboWranglerError as err:
        ctx.note(f"device parameters not recorded: {err}")
        return {}
    if writer is not None:
        writer.add_metadata("/device/params", {name: json.dumps(value) for name, value in params.items()})
    if live is not None:
        live.publish_params(params)
    return params
