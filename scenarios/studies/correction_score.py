"""Judging a corrected wheel force against the road force, as the project's scoring does.

NRMSE (:func:`rigsim.correction.metrics.dlc.nrmse`) of the corrected force against the road
force, both through the correction's band limit (``band_limit(., fs, BAND_LOWPASS, BAND_MODE)``,
:data:`rigsim.correction.output.lowpass.BAND_LOWPASS`: the 30 Hz 6th-order Butterworth,
zero-phase, of the ``best`` method, as ``benchmarks/nrmse_decomposition.py`` does), on the samples
where that band limit has settled (at :data:`rigsim.correction.output.pipeline.SETTLING_TOLERANCE`)
and the caller's rows; DLC of the unfiltered corrected force against the unfiltered road force's
on the same samples (the model correction needs no low-pass, so it is judged on the whole force).
"""

from __future__ import annotations

import numpy as np

from rigsim.correction.output.apply import band_limit
from rigsim.correction.metrics.dlc import dlc, nrmse
from rigsim.correction.output.filters import reference_filter
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.correction.output.pipeline import SETTLING_TOLERANCE

__all__ = ["band_rows", "score_correction"]


def band_rows(n: int, fs: float) -> np.ndarray:
    """Samples (bool, (n,)) where the band limit's zero-phase start and end transients have settled."""
    return reference_filter(fs, BAND_LOWPASS, settling_tolerance=SETTLING_TOLERANCE).transient_mask(int(n), BAND_MODE)


def score_correction(corrected_N, road_N, fs: float, rows=None) -> dict[str, np.ndarray]:
    """Per wheel: ``nrmse`` (1, band-limited, against the band-limited road force), ``dlc``, ``dlc_road``
    (1, unfiltered) and ``dlc_error`` (1, dlc / dlc_road - 1), on the settled ``rows`` (bool, (n,)).

    Parameters
    ----------
    corrected_N, road_N : array_like, N, (n, 4)
    fs : float, Hz
    rows : array_like of bool, (n,), optional
        Samples to score (e.g. :func:`~rigsim.scenarios.records.model.differential.settled_mask`),
        further limited to the band limit's settled samples.
    """
    x, r = np.asarray(corrected_N, dtype=float), np.asarray(road_N, dtype=float)
    use = band_rows(r.shape[0], fs)
    if rows is not None:
        use &= np.asarray(rows, dtype=bool)
    xb, rb = band_limit(x, fs, BAND_LOWPASS, BAND_MODE), band_limit(r, fs, BAND_LOWPASS, BAND_MODE)
    d, d_road = dlc(x[use]), dlc(r[use])
    return {"nrmse": nrmse(xb[use], rb[use]), "dlc": d, "dlc_road": d_road, "dlc_error": d / d_road - 1.0,
            "scored_s": np.asarray(float(np.count_nonzero(use)) / fs)}
