"""Errors of the diagnose engine: each names what is missing or wrong, so the CLI can say it in one line."""

from __future__ import annotations


class DiagnoseError(ValueError):
    """Base: a recording or a model the diagnosis cannot work on (the message says why and what would do)."""


class MissingChannelsError(DiagnoseError):
    """The recording lacks a channel or field the diagnosis needs (the message names them)."""


class NoUsableSpanError(DiagnoseError):
    """The recording has no span the drive model can be compared on (no run above rest, too short)."""


class ModelMismatchError(DiagnoseError):
    """A model file does not fit the recording (other wheel radius, other rope, other encoder), or is malformed."""


class UnknownEffectError(DiagnoseError):
    """An effect id not in the candidate library."""
