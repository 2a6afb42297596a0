"""`wrangler excite`: a designed identification run (a profile) on the device or a running SIL, recorded.

Host-only: on the SIL, start `wrangler sil` and point --url at it. Profiles are TOML files
(robowrangler/excite/profiles/, or a path); the README says which effects each can reveal.
"""

from __future__ import annotations

from pathlib import Path

import click

from robowrangler.cli.context import CliContext, pass_context
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.record import check_recording_path, default_source
from robowrangler.client import Client
from robowrangler.excite.profile import Limits, check_limits, list_profiles, load_profile
from robowrangler.excite.runner import run_profile
from robowrangler.recorder.session import RecordingSession, read_device_params
from robowrangler.transport import open_transport

PROFILE_METADATA = "/excite/profile"


@click.command("excite")
@click.option("--profile", "profile_name", default="standard", show_default=True, metavar="NAME|FILE.toml",
              help="A shipped profile (--list) or a profile file of your own.")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), default=None, metavar="REC.mcap",
              help="The recording to write (required unless --list).")
@click.option("--list", "list_only", is_flag=True, help="List the shipped profiles and exit.")
@click.option("--source", type=click.Choice(["board", "sil", "other"]), default=None,
              help="What is recorded (meta source) [default: sil for a loopback UDP URL, else board].")
@click.option("--description", default="", help="Free text stored in the meta record.")
@click.option("--force", is_flag=True, help="Replace REC.mcap if it exists (refused otherwise, as `record` does).")
@pass_context
def excite(ctx: CliContext, profile_name: str, out: Path | None, list_only: bool, source: str | None,
           description: str, force: bool) -> ExitStatus:
    """Run an excitation profile on the device and record it to REC.mcap.

    The profile is checked against the device's limits (ToV guard, top speed, guide stroke, burst size) before
    anything moves; Ctrl-C or a failing step lands the rope (SPINDOWN, DISARM) and keeps the recording.
    """
    if list_only:
        rows = [(name, load_profile(name)) for name in list_profiles()]
        ctx.result({"command": "excite", "profiles": {n: {"duration_s": p.duration_s, "description": p.description,
                                                         "reveals": list(p.reveals)} for n, p in rows}},
                   "\n".join(f"{n:10s} {p.duration_s:6.1f} s  {p.description}" for n, p in rows))
        return ExitStatus.OK
    if out is None:
        raise click.UsageError("--out REC.mcap is required (or --list)")
    profile = load_profile(profile_name)  # unknown or malformed: ProfileError (usage) before any link
    check_limits(profile, Limits.defaults())  # out of the default band: refused before connecting
    check_recording_path(out, force=force)
    with RecordingSession(out, source=source or default_source(ctx.url), device_url=ctx.url,
                          description=description or f"wrangler excite --profile {profile.name}") as recording:
        if profile.path is not None:
            recording.writer.add_metadata(PROFILE_METADATA, {"name": profile.name,
                                                             "toml": profile.path.read_text(encoding="utf-8")})
        with Client(ctx.url, connect_timeout_s=ctx.timeout_s, key=ctx.key,
                    transport=recording.transport(open_transport(ctx.url))) as client:
            params = read_device_params(client.get_param)
            recording.write_params(params)
            ctx.note(f"profile {profile.name}: {len(profile.steps)} steps, {profile.duration_s:g} s of holds and "
                     f"sweeps; recording to {out}")
            result = run_profile(client, profile, limits=Limits.from_params(params), progress=ctx.note)
    missing = result.burst_frames_expected - result.burst_frames_received
    ctx.result({"command": "excite", "path": str(out), "profile": profile.name, "steps": result.steps_done,
                "bursts": result.bursts, "burst_frames": result.burst_frames_received,
                "burst_frames_missing": max(0, missing), "duration_s": round(result.duration_s, 3),
                "final_state": result.final_state, "notes": result.notes},
               f"excited with {profile.name}: {result.steps_done} steps, {result.bursts} bursts "
               f"({max(0, missing)} frames missing), {result.duration_s:.1f} s device time -> {out}")
    return ExitStatus.OK
