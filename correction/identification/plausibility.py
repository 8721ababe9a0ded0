"""Is an identified ``T_a`` an actuator's? The wiring of a drive/LVDT pair judged from its data.

A drive ``x_ref`` and the LVDT ``x_a`` of its own post give a response an actuator has: at low
frequency the pan follows its drive (``|T_a| ~ 1``) and lags it, and a stable rational function
predicts the response at frequencies it was not fitted on. A pair wired wrongly does not:

* **the same channel twice**: ``H = 1`` exactly (:func:`check_signals`, before any fit);
* **swapped** (the LVDT given as the drive): ``H = 1 / T_a``, which leads where ``T_a`` lags and
  rises where ``T_a`` falls, so that no anchored, strictly proper fit predicts it (the best
  held-out error 0.97-1.47 on the project's simulated rigs, eq. 4 records and second-order loops);
* **another corner's LVDT**: with independent road tracks (the project's default, and any rig
  driven by independent random drives for the identification) the LVDT does not follow the drive
  at all, coherence near 0 (:data:`UNRELATED_COHERENCE`, refused in
  :func:`rigsim.correction.identification.actuator_fit.fit_frequency_response`); the other axle's LVDT on
  the same track follows the drive delayed by wheelbase over speed (0.1-1 s), a phase that turns
  through the low band as no actuator's does (:data:`PHASE_RESULTANT_MIN`) and that no stable
  ``T_a`` predicts (the best held-out error 0.97-1.05). Where left and right tracks are the same
  (a road given as identical or strongly coherent tracks, or the same drive on both posts of an
  axle), the other side's LVDT follows this drive as its own does: the data cannot tell it, and
  it is not refused;
* **an inverted channel** (a sign convention): antiphase at low frequency;
* **a unit or scale mistake** (an LVDT in mm read as m): a static gain far from 1.

:func:`check_actuator` applies the criteria to an
:class:`~rigsim.correction.identification.actuator_result.ActuatorFit` (in this order: gain, phase spread,
antiphase, lead, held-out error), :func:`plausibility` gives the numbers they read; a refusal is a
:class:`WiringError`, an :class:`~rigsim.correction.identification.actuator_fit_rules.ActuatorFitError`
that names the likely cause (:attr:`WiringError.cause`). Frequencies in Hz, phases in degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rigsim.correction.identification.actuator_fit_rules import TRUSTED_COHERENCE, ActuatorFitError

__all__ = ["WiringError", "Plausibility", "LOW_BAND_HZ", "GAIN_LIMITS", "PHASE_RESULTANT_MIN", "ANTIPHASE_DEG",
           "LEAD_LIMIT_DEG", "HELD_OUT_LIMIT", "UNRELATED_COHERENCE", "check_signals", "plausibility", "check_actuator"]

#: Band whose trusted points the gain and phase criteria read, Hz: above the drives' high-pass
#: (0.1 Hz) and below the bandwidth of a road simulator's actuator (-3 dB at 10-14 Hz on the
#: project's simulated rigs, docs/results/walkthrough_identify.md), where an actuator's pan follows
#: its drive with a lag below 90 deg (a 5 Hz second-order loop, damping 0.7: 45 deg on average).
LOW_BAND_HZ = (0.1, 5.0)
#: Least and largest static gain, the median ``|H|`` in :data:`LOW_BAND_HZ`, 1. A position loop with
#: integral action tracks its drive at steady state (``T_a(0) = 1``); the project's simulated rigs
#: give 0.98-1.02 in that band, eq. 4 records 0.94, second-order loops of 3-5 Hz 0.83-1.25 (their
#: resonance inside the band). A factor 2 (6 dB) is well beyond those and well inside the factors
#: a unit mistake gives (mm read as m 1000, cm 100, inch 25.4, V of a +-10 V LVDT over a 0.1 m
#: stroke 100).
GAIN_LIMITS = (0.5, 2.0)
#: Least resultant length of the unit phasors ``H / |H|`` at the trusted points of
#: :data:`LOW_BAND_HZ` (1: one phase throughout the band, 0: phases spread around the circle), 1.
#: An actuator's phase drifts slowly there: 0.99 on the project's rigs and eq. 4 records, 0.90 for
#: a 5 Hz second-order loop, 0.61-0.79 for a 3 Hz one (damping 0.3-0.7). A delay of ``tau``
#: turns it by ``360 tau`` deg per Hz: the other axle's LVDT on the project's simulated rigs
#: (0.23-0.39 s behind or ahead) gives 0.05-0.20. Below 0.5 the displacement is the drive delayed.
PHASE_RESULTANT_MIN = 0.5
#: Phase (circular mean in :data:`LOW_BAND_HZ`) beyond which the displacement is in antiphase with
#: the drive, deg: an actuator below its bandwidth lags less than 90 deg (a second-order loop
#: reaches 90 deg at its natural frequency); an inverted channel gives 180 deg less that lag
#: (166-168 deg on the project's simulated rigs and eq. 4 records).
ANTIPHASE_DEG = 90.0
#: Lead beyond which the displacement leads its drive, deg (circular mean in :data:`LOW_BAND_HZ`):
#: an actuator lags (3-55 deg on the project's rigs and eq. 4 records, LVDT filters included), a
#: swapped pair leads by as much. At the least coherence the fit trusts (0.9) and 8 averages, one
#: point's phase scatters by ``sqrt(1 - g^2) / (g sqrt(2 n))`` = 4.8 deg (Bendat & Piersol,
#: *Random Data*, 4th ed., 2010, eq. 9.52); the mean over the band's 12 or more points by 1.4 deg.
#: 5 deg is 3.5 of those; a swapped pair of a loop faster than 25-40 Hz (lightly to well damped)
#: leads by less and is refused by its held-out error with any lead.
LEAD_LIMIT_DEG = 5.0
#: Largest held-out error of the best candidate fit (raw or usable, whichever is smaller), 1. An
#: error of 1 is what ``T = 0`` scores (``|0 / H - 1| = 1``): a fit near it predicts nothing of the
#: points it was not fitted on. A drive and its own LVDT score 0.002-0.1 (eq. 4 records, the
#: project's simulated rigs with a lab's 150 Hz LVDT filter and up to 10 ms of skew, second-order
#: loops of 5-100 Hz), 0.2 for a 3 Hz loop and up to 0.8 with an undeclared 8th-order 20 Hz LVDT
#: filter inside the band; swapped pairs 0.97-1.47, the other axle's LVDT 0.97-1.05
#: (tests/correction/identification/test_plausibility.py).
HELD_OUT_LIMIT = 0.9
#: Median coherence in the fit's coherence band below which the displacement does not follow the
#: drive at all, 1. Two unrelated channels give ``1 / n`` on average over ``n`` averaged segments
#: (Carter, Knapp & Nuttall, IEEE Trans. Audio Electroacoust. 21, 1973): 0.07-0.125 for the 8 to
#: 15 segments of the fit's default estimate (0.04-0.05 between the two sides of the project's
#: simulated rigs); a right pair whose LVDT noise is three times its motion still gives 0.59.
UNRELATED_COHERENCE = 0.2


class WiringError(ActuatorFitError):
    """A drive/LVDT pair whose data are not an actuator's: one sentence, ``finding; fix``.

    Attributes
    ----------
    cause : str
        One of ``"same channel"``, ``"swapped"``, ``"wrong corner"``, ``"inverted"``, ``"scale"``.
    finding : str
        What the data show and the likely cause (no fix).
    fix : str
        What to give instead, in words that hold for any caller.
    """

    def __init__(self, cause: str, finding: str, fix: str):
        super().__init__(f"{finding}; {fix}")
        self.cause, self.finding, self.fix = cause, finding, fix


@dataclass(frozen=True)
class Plausibility:
    """The numbers the criteria read from one fit.

    Attributes
    ----------
    gain : float, 1
        Median ``|H|`` at the trusted points of :data:`LOW_BAND_HZ` (NaN if none).
    phase_deg : float, deg
        Circular mean of ``arg H`` there (positive: the displacement leads; NaN if none).
    phase_resultant : float, 1
        Length of the mean of the unit phasors ``H / |H|`` there (1: one phase; NaN if none).
    points : int
        Those points.
    held_out_error : float, 1
        The least held-out error of the candidate fits, raw or usable.
    """

    gain: float
    phase_deg: float
    phase_resultant: float
    points: int
    held_out_error: float


def check_signals(drive, displacement) -> None:
    """Refuse a drive and a displacement that hold the same samples (the same channel twice).

    Raises
    ------
    WiringError
        ``cause == "same channel"``.
    """
    u, y = np.asarray(drive), np.asarray(displacement)
    if u.shape == y.shape and np.array_equal(u, y):
        raise WiringError("same channel", "the drive and the displacement hold the same samples (the same channel "
                          "twice)", "give the post's drive and its LVDT (pan displacement), two channels")


def plausibility(fit, coherence_min: float = TRUSTED_COHERENCE) -> Plausibility:
    """The gain, phase and held-out error the criteria read from ``fit``.

    Parameters
    ----------
    fit : rigsim.correction.identification.actuator_result.ActuatorFit
    coherence_min : float, 1
        Coherence from which a point of the estimate is trusted (the fit's).
    """
    f, h = np.asarray(fit.f_hz, dtype=float), np.asarray(fit.h, dtype=complex)
    coh = np.nan_to_num(np.asarray(fit.coherence, dtype=float), nan=0.0)
    sel = (f >= LOW_BAND_HZ[0]) & (f <= LOW_BAND_HZ[1]) & (coh >= coherence_min) & np.isfinite(h) & (h != 0)
    errors = [e for v in fit.candidates.values() for e in (v.get("held_out_error"), v.get("model_error"))
              if e is not None and math.isfinite(e)]
    best = min(errors) if errors else float(fit.held_out_error)
    if not sel.any():
        return Plausibility(math.nan, math.nan, math.nan, 0, best)
    mean = complex(np.mean(h[sel] / np.abs(h[sel])))
    return Plausibility(float(np.median(np.abs(h[sel]))), math.degrees(math.atan2(mean.imag, mean.real)), abs(mean),
                        int(np.count_nonzero(sel)), best)


def _band() -> str:
    return f"{LOW_BAND_HZ[0]:g}-{LOW_BAND_HZ[1]:g} Hz"


def check_actuator(fit, coherence_min: float = TRUSTED_COHERENCE) -> Plausibility:
    """Refuse a fit whose data are not an actuator's; its :class:`Plausibility` otherwise.

    The criteria, in this order (each constant's notes give its source): the static gain within
    :data:`GAIN_LIMITS`, one phase through the band (:data:`PHASE_RESULTANT_MIN`), the phase within
    :data:`ANTIPHASE_DEG`, a lead below :data:`LEAD_LIMIT_DEG`, the best held-out error below
    :data:`HELD_OUT_LIMIT` (above it, a leading pair is swapped, a lagging one not this drive's
    post). Gain and phase are judged only where :data:`LOW_BAND_HZ` holds trusted points.

    Parameters
    ----------
    fit : rigsim.correction.identification.actuator_result.ActuatorFit
    coherence_min : float, 1
        Coherence from which a point of the estimate is trusted (the fit's).

    Raises
    ------
    WiringError
        One sentence: what the data show, the likely cause and the fix.
    """
    p = plausibility(fit, coherence_min)
    if p.points and not GAIN_LIMITS[0] <= p.gain <= GAIN_LIMITS[1]:
        raise WiringError("scale", f"the displacement is {p.gain:.3g} times the drive in {_band()}, where an "
                          f"actuator's pan follows its drive ({GAIN_LIMITS[0]:g}-{GAIN_LIMITS[1]:g} times): the two "
                          "channels are in different units or scales", "give both as lengths with their unit "
                          "in the header (m or mm), the drive and the LVDT of the same post")
    if p.points and p.phase_resultant < PHASE_RESULTANT_MIN:
        raise WiringError("wrong corner", f"the displacement's phase against the drive turns through {_band()} as a "
                          f"delay's does (resultant {p.phase_resultant:.2f}, an actuator's at least "
                          f"{PHASE_RESULTANT_MIN:g}): the LVDT is not this drive's post (the wrong corner: the other "
                          "axle's LVDT follows the same road delayed)", "pair the drive with the LVDT of its own post")
    if p.points and abs(p.phase_deg) > ANTIPHASE_DEG:
        raise WiringError("inverted", f"the displacement is in antiphase with the drive ({p.phase_deg:+.0f} deg in "
                          f"{_band()}, where an actuator lags by less than {ANTIPHASE_DEG:g} deg): one of the two "
                          "channels is inverted", "give the LVDT with the drive's sign convention (or invert the "
                          "channel in the file)")
    leads = p.points > 0 and p.phase_deg > 0
    if leads and (p.phase_deg > LEAD_LIMIT_DEG or p.held_out_error > HELD_OUT_LIMIT):
        raise WiringError("swapped", f"the displacement leads the drive by {p.phase_deg:.1f} deg in {_band()} where an "
                          f"actuator's pan lags its drive (best held-out error {p.held_out_error:.2f}, limit "
                          f"{HELD_OUT_LIMIT:g}): the drive and the LVDT are swapped",
                          "give the drive first and the LVDT second")
    if p.held_out_error > HELD_OUT_LIMIT:
        raise WiringError("wrong corner", f"no stable T_a predicts this pair's response (best held-out error "
                          f"{p.held_out_error:.2f}, limit {HELD_OUT_LIMIT:g}): the LVDT is not this drive's post "
                          "(the wrong corner: the other axle's LVDT follows the same road delayed)",
                          "pair the drive with the LVDT of its own post")
    return p

