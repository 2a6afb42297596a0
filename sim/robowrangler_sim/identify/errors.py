"""Typed errors of shape identification; every message names the file it is about."""

from __future__ import annotations

from pathlib import Path

from robowrangler.errors import RoboWranglerError


class IdentifyError(RoboWranglerError, ValueError):
    """Shape identification cannot use its input. ``path`` is the file concerned (None: the whole set)."""

    def __init__(self, path: str | Path | None, message: str) -> None:
        super().__init__(f"{path}: {message}" if path is not None else message)
        self.path = None if path is None else Path(path)


class PhotoUnreadable(IdentifyError):
    """The file does not exist or is not an image OpenCV can read."""


class ManifestError(IdentifyError):
    """The manifest or the file names do not give a usable phi / rope speed / geometry for every photo."""


class PhotoSetError(IdentifyError):
    """The photos do not make a table: a phi repeated at one speed, missing at another, fewer than two angles."""


class CalibrationError(IdentifyError):
    """No calibration in a photo (marker not found, several found) or one that does not fit the loop."""


class NoLoopFound(IdentifyError):
    """No thin closed rope component touches the exit point."""


class SeveralLoops(IdentifyError):
    """More than one thin closed component touches the exit point: which one is the loop is ambiguous."""
