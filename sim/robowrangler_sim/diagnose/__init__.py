"""wrangler diagnose: where the drive model and a recording disagree, what physics is missing, and the fit.

Stages (estimators: the constructor stores config, fit(...) returns self, fitted fields end in _):
replay (nominal model driven by the recorded inputs), residuals (per channel, noise from the data), locate
(spans and regimes), fit (nominal refit, then each candidate effect, with 95 % intervals on the batched
plant), select (held-out error and an information criterion; none / not identifiable), model_file (the
extended model the SIL loads), report (first line, PNGs, HTML, report.json). Entry point: api.diagnose.
"""

from robowrangler_sim.diagnose.api import DiagnosisResult, diagnose
from robowrangler_sim.diagnose.errors import (
    DiagnoseError,
    MissingChannelsError,
    ModelMismatchError,
    NoUsableSpanError,
    UnknownEffectError,
)

__all__ = ["DiagnoseError", "DiagnosisResult", "MissingChannelsError", "ModelMismatchError",
           "NoUsableSpanError", "UnknownEffectError", "diagnose"]
