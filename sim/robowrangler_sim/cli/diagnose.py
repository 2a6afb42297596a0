"""`wrangler diagnose REC.mcap|DIR [--model FILE] [--out DIR] [--effects ID,...] [--json]`: where the drive model
and a recording disagree, the missing physics, and the fitted model (robowrangler_sim.diagnose).

A directory diagnoses every .mcap in it, one Ray job per recording (local by default, --address for a cluster).
Exit 0 with a report (verdict missing_physics, none or not_identifiable); exit 1 with one line on stderr when a
recording or model cannot be diagnosed (corrupt, truncated beyond use, missing channels, no moving span, model of
another drive).
"""

from __future__ import annotations

from pathlib import Path

import click

from robowrangler.cli.context import CliContext, pass_context
from robowrangler.errors import RoboWranglerError


class DiagnosisFailed(RoboWranglerError):
    """The recording or model cannot be diagnosed; the message names the file and what is missing."""


def _one(path: Path, model, effects, out: Path | None, ctx: CliContext) -> dict:
    from robowrangler_sim.diagnose import DiagnoseError, diagnose
    from robowrangler_sim.diagnose.report import write_report

    try:
        result = diagnose(path, model=model, effects=effects, progress=None if ctx.json_mode else ctx.env.stderr)
    except DiagnoseError as err:
        raise DiagnosisFailed(str(err)) from None
    out_dir = out if out is not None else path.with_suffix(".diagnosis")
    paths = write_report(result, out_dir)
    doc = result.report
    doc["outputs"] = {k: str(v) for k, v in paths.items()}
    return doc


def _ray_many(paths: list[Path], model, effects, out: Path | None, address: str | None) -> list[dict]:
    import ray  # lazy: only `wrangler diagnose DIR` needs it

    from robowrangler_sim.diagnose import DiagnoseError, diagnose
    from robowrangler_sim.diagnose.report import write_report

    @ray.remote
    def job(p: str) -> dict:
        try:
            res = diagnose(p, model=model, effects=effects)
        except DiagnoseError as err:
            return {"recording": p, "error": str(err)}
        target = (out / Path(p).stem) if out is not None else Path(p).with_suffix(".diagnosis")
        write_report(res, target)
        return res.report

    ray.init(address=address, ignore_reinit_error=True, include_dashboard=False, log_to_driver=False)
    try:
        return ray.get([job.remote(str(p)) for p in paths])
    finally:
        ray.shutdown()


@click.command("diagnose")
@click.argument("recording", type=click.Path(exists=True, path_type=Path))
@click.option("--model", "model_file", type=click.Path(exists=True, dir_okay=False, path_type=Path), default=None,
              help="Model file to start from (a model.json written by diagnose); default: the nominal drive.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Report folder (default: REC.diagnosis next to the recording).")
@click.option("--effects", default=None, metavar="ID,...", help="Candidate effects to try (default: the whole library).")
@click.option("--address", default=None, help="Ray cluster address for a folder of recordings (default: local).")
@pass_context
def diagnose_command(ctx: CliContext, recording: Path, model_file: Path | None, out_dir: Path | None,
                     effects: str | None, address: str | None) -> None:
    """Diagnose a recording's drive channels: missing physics, where, the fitted model (report.json, HTML, PNGs)."""
    from robowrangler_sim.diagnose.candidates import LIBRARY
    from robowrangler_sim.diagnose.errors import DiagnoseError
    from robowrangler_sim.diagnose.model_file import load_model

    ids = None
    if effects:
        ids = [e.strip() for e in effects.split(",") if e.strip()]
        unknown = [e for e in ids if e not in LIBRARY]
        if unknown:
            raise click.UsageError(f"--effects: unknown id(s) {', '.join(unknown)}; known: {', '.join(LIBRARY)}")
    model = None
    if model_file is not None:
        try:
            model = load_model(model_file)
        except DiagnoseError as err:
            raise DiagnosisFailed(str(err)) from None
    if recording.is_dir():
        paths = sorted(recording.glob("*.mcap"))
        if not paths:
            raise DiagnosisFailed(f"{recording}: no .mcap recordings in this folder")
        docs = _ray_many(paths, model, ids, out_dir, address)
        failed = [d for d in docs if "error" in d]
        for d in docs:
            ctx.result(d, d.get("error") or f"{Path(d['recording']).name}: {d['summary']}")
        if failed:
            raise DiagnosisFailed(f"{len(failed)} of {len(docs)} recordings could not be diagnosed")
        return
    doc = _one(recording, model, ids, out_dir, ctx)
    ctx.result(doc, f"{doc['summary']}\nreport: {doc['outputs']['html']}")
