"""The one error of the measured-data readers and writers (:mod:`correction.io.measured`)."""

from __future__ import annotations

__all__ = ["MeasuredDataError"]


class MeasuredDataError(ValueError):
    """A measured-data file that cannot be used as written; the message is one sentence."""
