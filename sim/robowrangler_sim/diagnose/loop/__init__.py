"""wrangler diagnose for the rope loop: the engine of robowrangler_sim.diagnose (fit, select, locate's statistics,
the Candidate base) on the camera contours of /loop/observation against the chain model.

data (contours + rope speed + guide + phi, checked against the shape table's frame), shape_model (the chain's fast
steady-shape form with the effect laws, batched), replay, residuals (signed normal distance, noise from the data),
locate (loop part, phi / speed band, steady / transient, spans), flutter (a shorter loop that folds and flutters:
refused as outside the steady laws), candidates/ (one law per file), model_file (the
extended chain model), report, proof (truth recordings from the first-principles string shooter). Entry point:
api.diagnose_loop.
"""

from robowrangler_sim.diagnose.loop.api import LoopDiagnosis, diagnose_loop
from robowrangler_sim.diagnose.loop.data import ContourFrameError, has_loop_observations
from robowrangler_sim.diagnose.loop.flutter import LoopFlutterError

__all__ = ["ContourFrameError", "LoopDiagnosis", "LoopFlutterError", "diagnose_loop", "has_loop_observations"]
