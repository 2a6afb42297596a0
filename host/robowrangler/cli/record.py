"""Recording commands: record (a live link to an MCAP file), inspect (what a file holds), replay (plot it).

The file format is protocol/recording/schema.md; the work is done by robowrangler.recorder.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import click

from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.progress import Progress
from robowrangler.cli.signals import sigterm_as_interrupt
from robowrangler.client import Client
from robowrangler.errors import InvalidArgument, LinkTimeout, RoboWranglerError
from robowrangler.recorder.plot import plot_recording
from robowrangler.recorder.reader import read_recording
from robowrangler.recorder.summary import format_summary, summarize
from robowrangler.recorder.session import RecordingSession, read_device_params
from robowrangler.transport import UdpUrl, open_transport, parse_url

TICK_S = 0.1
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")


def default_source(url: str) -> str:
    parsed = parse_url(url)
    return "sil" if isinstance(parsed, UdpUrl) and parsed.host in LOOPBACK_HOSTS else "board"


def check_recording_path(out: Path, *, force: bool) -> None:
    """OUT for a new recording: an .mcap name (a .csv would hold MCAP bytes), not an existing file unless
    --force. Usage errors, raised before anything is opened."""
    if out.suffix.lower() != ".mcap":
        raise InvalidArgument("OUT", "a file name ending in .mcap (recordings are MCAP; `wrangler inspect --json` "
                              "and the mcap tools export them)", str(out))
    if out.exists() and not force:
        raise InvalidArgument("OUT", "a file that does not exist yet (add --force to replace it)", str(out))
    if not out.parent.is_dir():
        raise InvalidArgument("OUT", "a path in an existing folder", str(out))


@click.command("record")
@click.argument("out", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--duration", "duration_s", type=Seconds(positive=True), default=None,
              metavar="SECONDS", help="Stop after this long (default: until Ctrl-C).")
@click.option("--source", type=click.Choice(["board", "sil", "other"]), default=None,
              help="What is recorded (meta source) [default: sil for a loopback UDP URL, else board].")
@click.option("--seed", type=int, default=None, help="Seed of the SIL run, stored in the meta record.")
@click.option("--description", default="", help="Free text stored in the meta record.")
@click.option("--no-params", is_flag=True, help="Do not read the device parameters into /device/params.")
@click.option("--force", is_flag=True, help="Replace OUT if it exists (else an existing file is refused).")
@pass_context
def record(ctx: CliContext, out: Path, duration_s: float | None, source: str | None, seed: int | None,
           description: str, no_params: bool, force: bool) -> ExitStatus:
    """Record telemetry, events and commands to OUT (MCAP, zstd chunks) until Ctrl-C, SIGTERM or --duration.

    On link loss the gap is recorded and the recording goes on, waiting for the device; if no telemetry
    came at all the file is still written and the exit status is LINK_TIMEOUT. Ctrl-C and SIGTERM both
    finish the file (summary and footer), so any MCAP reader opens it.

    This process becomes the device's host: beside another commanding tool, record through
    `wrangler proxy --record OUT` instead (it records everything the link carries).
    """
    check_recording_path(out, force=force)
    start_s = time.monotonic()
    deadline_s = None if duration_s is None else start_s + duration_s
    recording = RecordingSession(out, source=source or default_source(ctx.url), seed=seed, device_url=ctx.url,
                                 description=description)
    recorder = recording.recorder
    progress = Progress(ctx)
    client: Client | None = None
    waiting_noted = lost = interrupted = False
    try:
        with sigterm_as_interrupt() as stop:
            while True:
                stop.check()
                now_s = time.monotonic()
                remaining_s = None if deadline_s is None else deadline_s - now_s
                if remaining_s is not None and remaining_s <= 0:
                    break
                if client is None:
                    connect_s = ctx.timeout_s if remaining_s is None else min(ctx.timeout_s, remaining_s)
                    try:
                        client = Client(ctx.url, connect_timeout_s=connect_s, key=ctx.key,
                                        transport=recording.transport(open_transport(ctx.url))).connect()
                    except LinkTimeout:
                        if not waiting_noted:
                            progress.note(f"no telemetry from {ctx.url} yet; recording goes on, waiting for the device")
                            waiting_noted = True
                        continue
                    progress.note(f"recording {ctx.url} to {out}"
                                  + ("" if duration_s is None else f" for {duration_s:g} s")
                                  + " (Ctrl-C or SIGTERM ends it)")
                    if not no_params:
                        _record_params(client, recording, progress)
                    continue
                time.sleep(TICK_S if remaining_s is None else max(0.0, min(TICK_S, remaining_s)))
                now_s = time.monotonic()
                last_s = recorder.last_telemetry_host_s
                silent_s = 0.0 if last_s is None else now_s - last_s
                if not lost and silent_s > ctx.timeout_s:
                    lost = True
                    progress.note(f"link lost: no telemetry for {silent_s:.1f} s; still recording, waiting for it")
                elif lost and silent_s < ctx.timeout_s:
                    lost = False
                    progress.note(f"link back: telemetry again ({recorder.frames_missing} frames missing so far)")
                progress.show(f"{out.name}: {now_s - start_s:6.1f} s, {recorder.telemetry_count} telemetry, "
                              f"{recorder.event_count} events, {recorder.command_count} commands, "
                              f"{recorder.gaps_written} gaps, state {recorder.latest_state or '-'}", now_s)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        progress.end_line()
        if client is not None:
            client.close()
        recording.close()
    elapsed_s = time.monotonic() - start_s
    if recorder.telemetry_count == 0:
        raise LinkTimeout(f"no TELEMETRY from {ctx.url} during the whole recording ({elapsed_s:.1f} s); {out} was "
                          "written but holds none", url=ctx.url, waited_s=elapsed_s)
    counts = {"telemetry": recorder.telemetry_count, "events": recorder.event_count,
              "commands": recorder.command_count, "gaps": recorder.gaps_written,
              "missing_frames": recorder.frames_missing}
    ctx.result({"command": "record", "path": str(out), "duration_s": round(elapsed_s, 3),
                "interrupted": interrupted, **counts},
               f"recorded {elapsed_s:.1f} s to {out}: " + ", ".join(f"{v} {k}" for k, v in counts.items()))
    return ExitStatus.OK


def _record_params(client: Client, recording: RecordingSession, progress: Progress) -> None:
    """Read every device parameter into the "/device/params" metadata record (best effort)."""
    try:
        params = read_device_params(client.get_param)
    except RoboWranglerError as err:
        progress.note(f"device parameters not recorded: {err}")
        return
    recording.write_params(params)


@click.command("inspect")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@pass_context
def inspect(ctx: CliContext, file: Path) -> ExitStatus:
    """Summarise a recording: channels, message counts, duration, gaps, truncation."""
    rec = read_recording(file)
    if rec.truncated:
        ctx.note(f"{file} is truncated ({rec.truncation_reason})")
    for damage in rec.damaged:
        ctx.note(f"{file}: {damage}")
    summary = summarize(rec)
    ctx.result({"command": "inspect", **summary}, format_summary(summary))
    return ExitStatus.OK


@click.command("replay")
@click.argument("file", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              metavar="OUT.png", help="Write the plot here (PNG).")
@click.option("--from", "from_s", type=float, default=None, metavar="SECONDS",
              help="Start of the window (device time).")
@click.option("--to", "to_s", type=float, default=None, metavar="SECONDS", help="End of the window (device time).")
@pass_context
def replay(ctx: CliContext, file: Path, plot_path: Path, from_s: float | None, to_s: float | None) -> ExitStatus:
    """Plot a recording: rope speed with setpoint and ToV guard, ESC pulse, guide and its target, spindle load,
    battery, state timeline; events and gaps in every panel and in the legend."""
    for name, value in (("--from", from_s), ("--to", to_s)):
        if value is not None and not math.isfinite(value):
            raise InvalidArgument(name, "a finite device time in seconds", value)
    if from_s is not None and to_s is not None and to_s <= from_s:
        raise InvalidArgument("--to", f"a time after --from ({from_s:g} s)", to_s)
    rec = read_recording(file)
    if rec.truncated:
        ctx.note(f"{file} is truncated ({rec.truncation_reason}); plotting what it holds")
    for damage in rec.damaged:
        ctx.note(f"{file}: {damage}")
    out = plot_recording(rec, plot_path, from_s=from_s, to_s=to_s)
    ctx.result({"command": "replay", "path": str(file), "plot": str(out),
                "telemetry": len(rec.telemetry["log_time_ns"])}, f"wrote {out}")
    return ExitStatus.OK
