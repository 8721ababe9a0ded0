"""The calibrated model's error where the correction uses it: in the correction's band.

The correction passes every force through its low-pass (the regularized ``T_F``, 30 Hz): an error
of the model above that band never reaches the corrected force, and neither does the load cells'
noise there. The fit NRMSE over the whole band (:attr:`Calibration.fit_nrmse`) counts both; the
model error the fallback reads is the dynamic one inside the band: the residual (model force, pans
following the measured x_a, minus the measured force; its mean on each window, a static bias the
model correction cancels, taken out) and the measured force passed through the
correction's own band limit (:func:`rigsim.correction.output.apply.band_limit`, zero-phase), the rms of
the one over the std of the other on the calibration windows. The noise that is left in the band
is the white noise's level (:func:`rigsim.correction.identification.noise.noise_rms`) through the
low-pass's noise bandwidth, over the same std: a few percent of the noise's whole-band power,
so an estimate that a lab's anti-alias filter biases (it reads the noise where the filter has
attenuated it) moves the model error little.
"""

from __future__ import annotations

import numpy as np

from rigsim.correction.identification.noise import noise_rms
from rigsim.correction.output.apply import band_limit
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE, as_lowpass
from rigsim.scenarios.records.model.result import model_error

__all__ = ["band_errors", "noise_bandwidth_hz", "record_errors"]


def noise_bandwidth_hz(fs: float, lowpass=BAND_LOWPASS) -> float:
    """Equivalent noise bandwidth of the band limit applied zero-phase, Hz: the integral of
    ``|T_F(f)|^2`` from 0 to ``fs / 2`` (zero-phase filtering applies ``|T_F|``; float, Hz)."""
    f = np.linspace(0.0, fs / 2.0, 20_001)
    h2 = np.abs(as_lowpass(lowpass).response(f)) ** 2
    return float((h2.sum() - 0.5 * (h2[0] + h2[-1])) * (f[1] - f[0]))  # the trapezoidal rule


def band_errors(model_N, force_N, windows, fs: float, noise_N) -> tuple[tuple, tuple]:
    """Per wheel: the model's error and the white noise left in the correction's band, 1.

    Parameters
    ----------
    model_N : sequence of numpy.ndarray, N
        The model's force on each window, from the window's lead-in start (``(e - a) x 4``).
    force_N : numpy.ndarray, N
        The measured force of the whole record (``n x 4``).
    windows : sequence of (int, int, int)
        Each window's lead-in start, scored start and end, samples (``a, s, e``).
    fs : float, Hz
    noise_N : array_like, N
        The white noise's rms per wheel over the whole band (``noise_rms``).

    Returns
    -------
    (tuple of float, tuple of float)
        The band-limited residual's rms (its mean on each window taken out: a static bias the
        correction cancels), and the noise's share of it, each over the std of the band-limited
        measured force on the windows' scored samples.
    """
    both = []  # per window: the residual's columns, then the force's, band-limited together
    for m, (a, s, e) in zip(model_N, windows):
        err = m[s - a:] - force_N[s:e]
        both.append(band_limit(np.hstack([err - err.mean(axis=0), force_N[s:e]]), fs, BAND_LOWPASS, BAND_MODE))
    both = np.concatenate(both)
    k = force_N.shape[1]
    residual, force = both[:, :k], both[:, k:]
    std = force.std(axis=0)
    fit = np.sqrt(np.mean(residual ** 2, axis=0)) / std
    noise = np.asarray(noise_N, float) * np.sqrt(noise_bandwidth_hz(fs) / (fs / 2.0)) / std
    return tuple(float(v) for v in fit), tuple(float(v) for v in noise)


def record_errors(model_N, force_N, first: int, fs: float) -> tuple:
    """Per wheel: the model's error over the whole run the correction uses, 1.

    :func:`band_errors`' figure on one window, from sample ``first`` (the model runs' start-up
    over) to the record's end, beyond the white noise's share there (the load cells' noise from
    the record, :func:`rigsim.correction.identification.noise.noise_rms`), as the calibration's
    model error is read on its windows.

    Parameters
    ----------
    model_N : numpy.ndarray, N, (n, 4)
        The model's force on the record, pans following the measured x_a (its run from the first sample).
    force_N : numpy.ndarray, N, (n, 4)
        The measured force.
    first : int
        The first settled sample.
    fs : float, Hz
    """
    force = np.asarray(force_N, dtype=float)
    fit, noise = band_errors([np.asarray(model_N, dtype=float)], force, [(0, int(first), force.shape[0])], fs,
                             noise_rms(force, fs))
    return model_error(fit, noise)
