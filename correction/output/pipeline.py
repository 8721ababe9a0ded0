"""The one output correction of measured wheel forces: ``T_a^-1 T_F`` per column, and its settled samples.

Every caller that corrects forces (the studies' scoring, ``rigsim correct``) calls
:func:`correct_forces`: one correction filter per force column, designed from that column's
actuator ``T_a`` (:func:`rigsim.correction.output.filters.design_correction`) and applied in one mode
(:func:`rigsim.correction.output.apply.correct`); the settled mask is the AND of every filter's
:meth:`~rigsim.correction.output.correction_filter.CorrectionFilter.transient_mask` and the band-limit
reference filter's (:func:`rigsim.correction.output.filters.reference_filter`), so a corrected force and the
reference force through ``T_F`` are compared on the same samples.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rigsim.correction.identification.actuator_result import ActuatorFit
from rigsim.correction.output.apply import correct
from rigsim.correction.output.correction_filter import SETTLING_TOLERANCE
from rigsim.correction.output.filters import design_correction, reference_filter
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.correction.output.transfer import is_transfer_function
from rigsim.errors import RigsimError

__all__ = ["CorrectedForces", "CorrectionError", "correct_forces", "SETTLING_TOLERANCE"]

_MODES = ("causal", "zerophase")


class CorrectionError(RigsimError, ValueError):
    """A correction filter that cannot be designed for one ``T_a`` (one sentence, from
    :func:`rigsim.correction.output.filters.design_correction`).

    Attributes
    ----------
    column : int or None
        The force column whose ``T_a`` was refused (0-based), None when one ``T_a`` serves all.

    Examples
    --------
    A T_a with a pole in the right half-plane cannot be inverted; the error names the column:

    >>> import numpy as np
    >>> from rigsim.correction.output.pipeline import CorrectionError, correct_forces
    >>> forces = np.full((2000, 2), 40e3)
    >>> try:  # doctest: +ELLIPSIS
    ...     correct_forces(forces, [([1.0], [1e-3, 1.0]), ([1.0], [1e-3, -1.0, 1.0])], 1000.0)
    ... except CorrectionError as exc:
    ...     print(f"column {exc.column}: {exc}")
    column 1: T_a is unstable: it has a pole at 999 rad/s, not in the open left half-plane; ...
    """

    def __init__(self, message: str, column: int | None = None):
        super().__init__(message)
        self.column = column


@dataclass(frozen=True)
class CorrectedForces:
    """Forces corrected by ``T_a^-1 T_F``, and where they are settled.

    Attributes
    ----------
    corrected_N : numpy.ndarray, N
        Corrected forces, shape (n, k); (n,) when the forces were given as (n,).
    settled : numpy.ndarray of bool, (n,)
        True outside every transient of the k correction filters and of the band-limit
        reference filter (:func:`rigsim.correction.output.filters.reference_filter`) at the same tolerance.
    filters : tuple of CorrectionFilter
        The k filters, one per column (the same object repeated when the columns share ``T_a``).
    lowpass : str
        The low-pass's name ("paper", "regularized" or a LowPass's name).
    mode : str
        "causal" or "zerophase".

    Examples
    --------
    >>> import numpy as np
    >>> from rigsim.correction.output.pipeline import correct_forces
    >>> t = np.arange(5000) / 1000.0
    >>> force = 40e3 + 2e3 * np.sin(2 * np.pi * 8.0 * t)
    >>> w = 2 * np.pi * 15.0
    >>> out = correct_forces(force, ([w * w], [1.0, 1.4 * w, w * w]), 1000.0)
    >>> out.corrected_N.shape, len(out.filters)
    ((5000,), 1)
    >>> print(f"{out.settled_s:.2f} s of {t.size / 1000.0:.0f} s settled")
    4.74 s of 5 s settled
    """

    corrected_N: np.ndarray
    settled: np.ndarray
    filters: tuple
    lowpass: str
    mode: str

    @property
    def settled_s(self) -> float:
        """Duration of the settled samples, s."""
        return float(np.count_nonzero(self.settled)) / self.filters[0].fs


def _is_pair(ta) -> bool:
    """True when ``ta`` is one ``(num, den)`` pair of 1-D number sequences."""
    if not isinstance(ta, (tuple, list)) or len(ta) != 2:
        return False
    try:
        return all(np.asarray(c, dtype=float).ndim <= 1 for c in ta)
    except (TypeError, ValueError):
        return False


def _one(ta):
    """One ``T_a`` in a form :func:`design_correction` takes."""
    if isinstance(ta, ActuatorFit):
        return ta.as_tf()
    return ta


def _actuator_list(actuators, k: int) -> list:
    if isinstance(actuators, ActuatorFit) or is_transfer_function(actuators) or _is_pair(actuators):
        return [_one(actuators)]
    if not isinstance(actuators, Sequence) or isinstance(actuators, str):
        raise ValueError(f"actuators must be one T_a or a sequence of {k} (num, den), ActuatorFit or "
                         f"control.TransferFunction, got {type(actuators).__name__}")
    tas = [_one(a) for a in actuators]
    if len(tas) == 1:
        return tas
    if len(tas) != k:
        raise ValueError(f"got {len(tas)} actuators for {k} force columns; give one T_a per column "
                         "or one for all")
    return tas


def correct_forces(force_N, actuators, fs: float, *, lowpass=BAND_LOWPASS, mode: str = BAND_MODE,
                   settling_tolerance: float = SETTLING_TOLERANCE, normalize_dc: bool = False) -> CorrectedForces:
    """Correct measured wheel forces by ``T_a^-1 T_F``, each column with its own ``T_a``.

    Parameters
    ----------
    force_N : array_like, N
        Measured forces, shape (n,) or (n, k), sampled at ``fs``.
    actuators : T_a or sequence of k T_a
        Each ``T_a = X_a / X_p`` as ``(num, den)`` (descending powers of s, s in rad/s), an
        :class:`~rigsim.correction.identification.actuator_result.ActuatorFit` or a continuous SISO
        ``control.TransferFunction``; one ``T_a`` (or a sequence of one) serves every column.
    fs : float, Hz
        Sampling rate.
    lowpass : {"paper", "regularized"} or LowPass
        ``T_F`` (:mod:`rigsim.correction.output.lowpass`; default
        :data:`~rigsim.correction.output.lowpass.BAND_LOWPASS`).
    mode : {"causal", "zerophase"}
        How the filters are applied (:func:`rigsim.correction.output.apply.correct`; default
        :data:`~rigsim.correction.output.lowpass.BAND_MODE`).
    settling_tolerance : float, 1
        Tolerance of the filters' transients (:func:`rigsim.correction.output.filters.design_correction`).
    normalize_dc : bool
        Scale each ``T_a`` to ``T_a(0) = 1`` instead of refusing one that is off.

    Returns
    -------
    CorrectedForces

    Raises
    ------
    CorrectionError
        A refusal of :func:`rigsim.correction.output.filters.design_correction` (unstable or non-minimum-phase
        ``T_a``, ``T_a(0) != 1``, sampling rate too low ...), one sentence, with the column.
    ValueError
        One sentence: a bad mode or shape, a count of actuators that does not match the columns.

    Examples
    --------
    Two wheel forces (N) at 1 kHz, one T_a for both, a second-order actuator at 15 Hz:

    >>> import numpy as np
    >>> from rigsim.correction.output.pipeline import correct_forces
    >>> t = np.arange(5000) / 1000.0
    >>> forces = np.column_stack([40e3 + 2e3 * np.sin(2 * np.pi * 8.0 * t),
    ...                           38e3 + 1e3 * np.sin(2 * np.pi * 12.0 * t)])
    >>> w = 2 * np.pi * 15.0
    >>> out = correct_forces(forces, ([w * w], [1.0, 1.4 * w, w * w]), 1000.0)
    >>> out.corrected_N.shape, out.mode, out.lowpass
    ((5000, 2), 'zerophase', 'regularized')
    >>> amplitude = (np.ptp(out.corrected_N[out.settled], axis=0) / 2).round(-1)
    >>> print(amplitude)
    [2070. 1170.]
    """
    if mode not in _MODES:
        raise ValueError(f"unknown mode {mode!r}; use 'causal' or 'zerophase'")
    x = np.asarray(force_N, dtype=float)
    if x.ndim not in (1, 2) or x.shape[0] < 1:
        raise ValueError(f"force_N must have shape (n,) or (n, k), got {x.shape}")
    x2 = x[:, None] if x.ndim == 1 else x
    n, k = x2.shape
    tas = _actuator_list(actuators, k)
    filters = []
    for j, ta in enumerate(tas):
        try:
            filters.append(design_correction(ta, fs, lowpass, normalize_dc=normalize_dc,
                                             settling_tolerance=settling_tolerance))
        except ValueError as exc:
            raise CorrectionError(str(exc), j if len(tas) > 1 else None) from None
    if len(filters) == 1:
        out = correct(x2, filters[0], mode)
        filters = filters * k
    else:
        out = np.column_stack([correct(x2[:, j], filt, mode) for j, filt in enumerate(filters)])
    settled = reference_filter(fs, lowpass, settling_tolerance=settling_tolerance).transient_mask(n, mode)
    for filt in filters:
        settled = settled & filt.transient_mask(n, mode)
    return CorrectedForces(corrected_N=out[:, 0] if x.ndim == 1 else out, settled=settled, filters=tuple(filters),
                           lowpass=filters[0].lowpass.name, mode=mode)
