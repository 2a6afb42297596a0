"""`wrangler diagnose REC.mcap|DIR [--model FILE] [--out DIR] [--effects ID,...] [--closed-loop] [--json]`: where the
drive and spindle model and a recording disagree, the missing physics, and the fitted model
(robowrangler_sim.diagnose). A recording with
/loop/observation contours is diagnosed against the chain's loop as well (robowrangler_sim.diagnose.loop; its
report under "loop", loop_report.* in the report folder); --effects may name loop effects; --model may be a loop
model (loop_model.json). --closed-loop also runs the SIL firmware on the recording's commands with the model as
given and the fitted one (robowrangler_sim.diagnose.closed_loop).

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


def _one(path: Path, model, effects, out: Path | None, ctx: CliContext, loop_model=None,
         closed_loop: bool = False) -> dict:
    from robowrangler_sim.diagnose import DiagnoseError, diagnose
    from robowrangler_sim.diagnose.loop.cli_hook import diagnose_loop_section, split_effects
    from robowrangler_sim.diagnose.report import write_report

    out_dir = out if out is not None else path.with_suffix(".diagnosis")
    drive_ids, loop_ids = split_effects(effects)
    progress = None if ctx.json_mode else ctx.env.stderr
    loop_doc = diagnose_loop_section(path, loop_model, loop_ids, out_dir, progress, DiagnosisFailed)
    if loop_doc is not None and (drive_ids == [] or not _has_telemetry(path)):
        return {**loop_doc, "loop": loop_doc}  # a loop-only recording (or only loop effects asked for)
    try:
        result = diagnose(path, model=model, effects=drive_ids, progress=progress, closed_loop=closed_loop)
    except DiagnoseError as err:
        raise DiagnosisFailed(str(err)) from None
    paths = write_report(result, out_dir)
    doc = result.report
    doc["outputs"] = {k: str(v) for k, v in paths.items()}
    if loop_doc is not None:
        doc["loop"] = loop_doc
        doc["summary"] = f"{doc['summary']}\n{loop_doc['summary']}"
    return doc


def _has_telemetry(path: Path) -> bool:
    from robowrangler.recorder import read_recording

    try:
        return bool(read_recording(path).records.get("/device/telemetry"))
    except Exception:  # noqa: BLE001 - the drive diagnosis reports an unreadable file itself
        return True


def _job(p: str, model, effects, out: Path | None) -> dict:
    from robowrangler_sim.diagnose import DiagnoseError, diagnose
    from robowrangler_sim.diagnose.report import write_report

    try:
        res = diagnose(p, model=model, effects=effects)
    except DiagnoseError as err:
        return {"recording": p, "error": str(err)}
    target = (out / Path(p).stem) if out is not None else Path(p).with_suffix(".diagnosis")
    doc = res.report
    doc["outputs"] = {k: str(v) for k, v in write_report(res, target).items()}
    return doc


def _ray_many(paths: list[Path], model, effects, out: Path | None, address: str | None, ctx: CliContext) -> list[dict]:
    """One Ray job per recording (local Ray by default); if Ray cannot start (not installed, or its node does
    not come up on a loaded machine) and no --address was given, one after the other in this process."""
    try:
        import ray  # lazy: only `wrangler diagnose DIR` needs it

        ray.init(address=address, ignore_reinit_error=True, include_dashboard=False, log_to_driver=False)
    except Exception as err:  # noqa: BLE001 - Ray raises plain Exception when its node does not start
        if address is not None:
            raise DiagnosisFailed(f"--address {address}: Ray cluster not reachable: {err}") from None
        ctx.note(f"Ray could not start ({type(err).__name__}: {str(err)[:120]}); diagnosing one after the other")
        return [_job(str(p), model, effects, out) for p in paths]
    try:
        job = ray.remote(_job)
        return ray.get([job.remote(str(p), model, effects, out) for p in paths])
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
@click.option("--closed-loop", "closed_loop", is_flag=True, default=False,
              help="Also run the SIL firmware on the recording's commands with the given and the fitted model and "
                   "report both closed-loop errors (one recording; needs the native SIL build).")
@pass_context
def diagnose_command(ctx: CliContext, recording: Path, model_file: Path | None, out_dir: Path | None,
                     effects: str | None, address: str | None, closed_loop: bool) -> None:
    """Diagnose a recording's drive channels: missing physics, where, the fitted model (report.json, HTML, PNGs)."""
    from robowrangler_sim.diagnose.candidates import LIBRARY, SPINDLE_LIBRARY
    from robowrangler_sim.diagnose.errors import DiagnoseError
    from robowrangler_sim.diagnose.loop.candidates import LOOP_LIBRARY
    from robowrangler_sim.diagnose.loop.model_file import LoopModel, is_loop_model_file
    from robowrangler_sim.diagnose.model_file import load_model

    ids = None
    if effects:
        ids = [e.strip() for e in effects.split(",") if e.strip()]
        known = list(LIBRARY) + list(SPINDLE_LIBRARY) + list(LOOP_LIBRARY)
        unknown = [e for e in ids if e not in known]
        if unknown:
            raise click.UsageError(f"--effects: unknown id(s) {', '.join(unknown)}; known: {', '.join(known)}")
    model = None
    loop_model = None
    if model_file is not None:
        try:
            if is_loop_model_file(model_file):
                loop_model = LoopModel.load(model_file)
            else:
                model = load_model(model_file)
        except DiagnoseError as err:
            raise DiagnosisFailed(str(err)) from None
    if recording.is_dir():
        paths = sorted(recording.glob("*.mcap"))
        if not paths:
            raise DiagnosisFailed(f"{recording}: no .mcap recordings in this folder")
        docs = _ray_many(paths, model, ids, out_dir, address, ctx)
        failed = [d for d in docs if "error" in d]
        for d in docs:
            ctx.result(d, d.get("error") or f"{Path(d['recording']).name}: {d['summary']}")
        if failed:
            raise DiagnosisFailed(f"{len(failed)} of {len(docs)} recordings could not be diagnosed")
        return
    doc = _one(recording, model, ids, out_dir, ctx, loop_model, closed_loop=closed_loop)
    ctx.result(doc, f"{doc['summary']}\nreport: {doc['outputs']['html']}")
