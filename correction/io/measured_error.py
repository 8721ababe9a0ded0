"""The one error of the measured-data readers and writers (:mod:`rigsim.correction.io.measured`)."""

from __future__ import annotations

from rigsim.errors import RigsimError

__all__ = ["MeasuredDataError"]


class MeasuredDataError(RigsimError, ValueError):
    """A measured-data file that cannot be used as written; the message is one sentence.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from rigsim.correction.io.measured import MeasuredDataError, write_channels
    >>> forces = SimpleNamespace(time_s=np.arange(3) / 1000.0, data={"Fz_FL": np.full(3, 40e3)})
    >>> try:  # doctest: +ELLIPSIS
    ...     write_channels("forces.xlsx", forces)
    ... except MeasuredDataError as exc:
    ...     print(exc)
    'forces.xlsx' has extension '.xlsx'; give a .csv/.txt/.dat (text), .rsp/.drv/.tim/.rpc ...
    """
