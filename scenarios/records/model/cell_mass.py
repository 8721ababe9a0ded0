"""The mass the load cells weigh with their pans' acceleration that the lab did not compensate.

A rig's load cell sits under the wheelpan: it reads the tire force plus the pan plate's mass times
the pan's acceleration, and the lab subtracts its estimate of that mass times an accelerometer's
reading (:class:`rigsim.scenarios.core.lab.LabChain`). What is left, ``m_u a_pan`` with ``m_u`` the
cell's mass less the lab's estimate, grows with frequency squared: a few kilograms of it are a
few percent of the tire force at 20-30 Hz, which the truck model does not have and the linear
correction carries into the corrected force.

The record holds it: the pan's acceleration is the LVDT's second derivative, and the force the
model does not explain is linear in ``m_u``. So the calibration fits ``m_u`` alongside the truck's
values by variable projection: at each model run the least-squares ``m_u`` of the (weighted)
residual on the (weighted) acceleration is solved in closed form and taken out, at no cost in
model runs; the correction subtracts ``m_u a_pan`` from the measured force before it corrects it.

One mass for the four cells: one lab compensates four like pans with one estimate. A mass per
wheel lets each wheel's own model error pass for a mass (a mismatch the model lacks, a channel
skew that looks like tire damping and, through it, like mass), and the correction then adds that
error back: measured with ``benchmarks/mismatch_suite.py`` (its first 6 plants, 24 wheels, the
typical lab's compensation 7.5 kg too large): worst DLC error 3.1 % with a mass per wheel, 1.9 %
with one shared (both read by plain least squares, below), 2.6 % without the fit.

The acceleration is band-limited by the correction's own low-pass H
(:data:`~rigsim.correction.output.lowpass.BAND_LOWPASS`, zero-phase): the LVDT's noise
differentiated twice dominates above the truck's band, and the correction passes nothing above it.
The cells' force in the residual is not band-limited, so the mass is read against ``H a``
(``test``: the regressor band-limited twice) over ``|H a|^2``: ``(H^2 a) . (m a) = m |H a|^2``
holds for any H, where the plain least squares on ``H a`` would read ``m (H a) . a / |H a|^2``, too
large by the acceleration's power in the low-pass's transition band (30 % on the paper's medium
case).
"""

from __future__ import annotations

import numpy as np

from rigsim.correction.output.apply import band_limit
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.scenarios.core.lab import pan_acceleration

__all__ = ["band_acceleration", "without_cell_mass", "mass_of", "mass_sigma"]


def band_acceleration(x_a_m, fs: float) -> np.ndarray:
    """The pans' acceleration (m/s^2, (n, k)) from their measured positions (m, (n, k)) at ``fs``
    (Hz): central second differences through the correction's band limit, zero-phase."""
    return band_limited(pan_acceleration(np.asarray(x_a_m, dtype=float), float(fs)), fs)


def without_cell_mass(force_N, x_a_m, fs: float, mass_kg: float) -> np.ndarray:
    """The measured forces (N, (n, k)) with ``mass_kg`` (kg, the fitted load cells' mass) times the
    pans' band-limited acceleration (:func:`band_acceleration` of ``x_a_m``, m, at ``fs``, Hz) taken
    out; the forces as given where the mass is 0."""
    force = np.asarray(force_N, dtype=float)
    return force - mass_kg * band_acceleration(x_a_m, fs) if mass_kg else force


def band_limited(x, fs: float) -> np.ndarray:
    """``x`` ((n, k)) through the correction's band limit at ``fs`` (Hz), zero-phase."""
    return band_limit(np.asarray(x, dtype=float), float(fs), BAND_LOWPASS, BAND_MODE)


def mass_of(error_N, acc_m_s2, weights, test=None) -> float:
    """The one mass (kg) whose force ``m a`` best explains ``-error`` over every column: ``error``
    the model's force less the measured one (N, (n, k)), ``acc`` the pans' band-limited
    acceleration (m/s^2, (n, k)), ``weights`` per column (1/N^2, (k,); 0 leaves a column out),
    ``test`` the acceleration band-limited once more (default ``acc``: the plain least squares);
    ``-sum w (test . error) / sum w (acc . acc)``; 0 where the acceleration is nil."""
    e, a, w = np.asarray(error_N, dtype=float), np.asarray(acc_m_s2, dtype=float), np.asarray(weights, dtype=float)
    t = a if test is None else np.asarray(test, dtype=float)
    den = float(w @ np.einsum("ij,ij->j", a, a))
    return -float(w @ np.einsum("ij,ij->j", t, e)) / den if den > 0.0 else 0.0


def mass_sigma(residual_N, acc_m_s2, weights, block: int, test=None) -> float:
    """Block-robust 1-sigma (kg) of :func:`mass_of`'s mass given the rest of the fit: the sandwich
    over blocks of ``block`` rows of the ``residual`` left after the mass (N, (n, k)), which holds
    for a residual correlated over less than a block."""
    r, a, w = np.asarray(residual_N, dtype=float), np.asarray(acc_m_s2, dtype=float), np.asarray(weights, dtype=float)
    t = a if test is None else np.asarray(test, dtype=float)
    den = float(w @ np.einsum("ij,ij->j", a, a))
    if den <= 0.0:
        return 0.0
    per_row = (t * r) @ w
    n = per_row.size // max(int(block), 1) * max(int(block), 1)
    scores = per_row[:n].reshape(-1, max(int(block), 1)).sum(axis=1)
    if n < per_row.size:
        scores = np.append(scores, per_row[n:].sum())
    return float(np.sqrt(scores @ scores) / den)
