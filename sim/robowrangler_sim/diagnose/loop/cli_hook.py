"""What `wrangler diagnose` adds for the loop: split --effects into drive and loop ids, and run the loop diagnosis
when the recording holds /loop/observation (its report.json section plus loop_report.* files)."""

from __future__ import annotations

from pathlib import Path

from robowrangler_sim.diagnose.errors import DiagnoseError
from robowrangler_sim.diagnose.loop.candidates import LOOP_LIBRARY


def split_effects(effects: list[str] | None) -> tuple[list[str] | None, list[str] | None]:
    """(drive ids, loop ids); None = the whole library of that side; [] = none of that side asked for."""
    if effects is None:
        return None, None
    return [e for e in effects if e not in LOOP_LIBRARY], [e for e in effects if e in LOOP_LIBRARY]


def diagnose_loop_section(path: Path, model, loop_ids, out_dir: Path, progress, failure: type[Exception]) -> dict | None:
    """The loop's report section (with its output paths), or None when the recording has no contours or only drive
    effects were asked for. A loop diagnosis that cannot run raises ``failure`` with the reason."""
    from robowrangler_sim.diagnose.loop import diagnose_loop, has_loop_observations
    from robowrangler_sim.diagnose.loop.report import write_loop_report

    if loop_ids == [] or not has_loop_observations(path):
        return None
    try:
        res = diagnose_loop(path, model=model, effects=loop_ids, progress=progress)
    except DiagnoseError as err:
        raise failure(f"loop: {err}") from None
    doc = res.report
    doc["outputs"] = {k: str(v) for k, v in write_loop_report(res, out_dir).items()}
    return doc
