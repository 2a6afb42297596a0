"""Shape identification (issue 16): photos of the flying loop -> the chain model's shape table.

Stages, one file each: photos.py (manifest, file names, reading), calibration.py (pixels -> plane
metres), binarise.py (rope pixels), loop_finder.py (the loop component), centreline.py (ordered centre
line), extract.py (one photo -> contour in the table frame), resample.py (N points: equal chords or
curvature-aware), table_builder.py (the table, written atomically), deviation.py (Fig. 5a measure),
figures.py, api.py. See docs/identify.md.
"""

from robowrangler_sim.identify.api import IdentifyResult, identify, identify_manifest, write_identification
from robowrangler_sim.identify.errors import (CalibrationError, IdentifyError, ManifestError, NoLoopFound,
                                              PhotoSetError, PhotoUnreadable, SeveralLoops)
from robowrangler_sim.identify.extract import ExtractOptions, PhotoResult
from robowrangler_sim.identify.photos import PhotoEntry, PhotoSet, entry_from_name, load_manifest

__all__ = [
    "CalibrationError", "ExtractOptions", "IdentifyError", "IdentifyResult", "ManifestError", "NoLoopFound",
    "PhotoEntry", "PhotoResult", "PhotoSet", "PhotoSetError", "PhotoUnreadable", "SeveralLoops", "entry_from_name",
    "identify", "identify_manifest", "load_manifest", "write_identification",
]
