"""Continuous low-pass filters that make the inverse actuator transfer function proper.

Two choices, both with unit static gain so the mean wheel force (the static load) passes:

``paper`` (:func:`paper_lowpass`)
    The paper's eq. 5: two second-order sections ``w_i^2 / (s^2 + 2 zeta_i w_i s + w_i^2)`` at
    16 and 24 Hz with damping ratio 1. Two critically damped sections are already 3 dB down near
    8 Hz (each is ``1 / (1 + (f/f_i)^2)`` in magnitude: 0.80 x 0.90 at 8 Hz), in the middle of the
    truck's axle-hop band (8-15 Hz), and about 6 dB down at 12 Hz, so the paper's correction also
    removes real dynamic load. Its corrected DLC should be compared with the road force passed
    through the same low-pass (:func:`rigsim.correction.output.apply.band_limit`), not with the raw road force.

``regularized`` (:func:`regularized_lowpass`)
    This project's choice: a Butterworth low-pass placed above the band of interest (default
    6th order at 30 Hz: -0.03 dB at 20 Hz, -3 dB at 30 Hz, -36 dB per octave above). Times
    ``T_a^-1`` (relative degree -3 for eq. 4) the product keeps relative degree 3, so the
    inverse is within 0.4 % of exact in magnitude from 0 to 20 Hz while the noise gain stays
    bounded (it peaks near the corner and falls as ``f^-3`` above). A Tikhonov / Wiener weighting
    ``conj(T_a) / (|T_a|^2 + 1/SNR)`` would need a noise spectrum the rig data do not carry and no
    causal form; the Butterworth needs only a corner frequency and works causally and offline.

Frequencies at the interface are in Hz; the returned zeros, poles and gain are for ``s`` in rad/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["BAND_HZ", "BAND_ORDER", "BAND_LOWPASS", "BAND_MODE", "LowPass", "paper_lowpass", "regularized_lowpass", "as_lowpass"]

#: The correction's band limit, Hz: the corner of the regularized low-pass, and the top of the band
#: in which the identification fits and checks T_a, the drive iteration updates the drive and the
#: studies compare responses. ``rigsim correct --lowpass-hz`` (``lowpass_hz=``) moves the low-pass's
#: corner for one correction.
BAND_HZ = 30.0
#: Order of the regularized low-pass (Butterworth), 1: above T_a's relative degree (3 for eq. 4),
#: so the corrected force rolls off beyond :data:`BAND_HZ`.
BAND_ORDER = 6
#: The correction's own low-pass (``rigsim correct``'s default ``--lowpass``): the regularized one,
#: at :data:`BAND_HZ`; the band limit a correction is judged through.
BAND_LOWPASS = "regularized"
#: How the correction and its band limit are applied by default
#: (:func:`rigsim.correction.output.apply.correct`): zero-phase, offline.
BAND_MODE = "zerophase"


@dataclass(frozen=True, eq=False)
class LowPass:
    """A continuous low-pass filter with unit static gain, as zeros, poles and gain.

    Attributes
    ----------
    name : str
        "paper", "regularized" or a user label.
    zeros : numpy.ndarray, rad/s
        Zeros in the s-plane (none for the built-in filters).
    poles : numpy.ndarray, rad/s
        Poles in the s-plane (all in the open left half-plane).
    gain : float
        Gain ``k`` of ``k prod(s - z) / prod(s - p)``.
    band_hz : float, Hz
        The filter's highest corner frequency: the band inside which a discretization must
        reproduce the continuous response (see :func:`rigsim.correction.output.filters.design_correction`).
    description : str
        One line for reports, e.g. "2 x 2nd order, 16/24 Hz, zeta 1/1".
    """

    name: str
    zeros: np.ndarray
    poles: np.ndarray
    gain: float
    band_hz: float
    description: str

    @property
    def relative_degree(self) -> int:
        """int: number of poles minus number of zeros (high-frequency roll-off, 20 dB/decade each)."""
        return len(self.poles) - len(self.zeros)

    def response(self, f_hz) -> np.ndarray:
        """Complex frequency response at ``f_hz`` (Hz)."""
        s = 2j * np.pi * np.asarray(f_hz, dtype=float)
        return _zpk_eval(self.zeros, self.poles, self.gain, s)


def _zpk_eval(z, p, k, s):
    out = np.full(np.shape(s), complex(k))
    for zi in z:
        out = out * (s - zi)
    for pi in p:
        out = out / (s - pi)
    return out


def _positive(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"low-pass parameter {name} must be a real number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"low-pass parameter {name} must be finite and > 0, got {value!r}")
    return v


def paper_lowpass(f1_hz: float = 16.0, f2_hz: float = 24.0, zeta1: float = 1.0,
                  zeta2: float = 1.0) -> LowPass:
    """The paper's eq. 5: two second-order low-pass sections in series.

    Parameters
    ----------
    f1_hz, f2_hz : float, Hz
        Natural frequencies ``omega_1 / 2 pi`` and ``omega_2 / 2 pi`` (paper: about 16 and 24 Hz).
    zeta1, zeta2 : float, 1
        Damping ratios (paper: 1, critically damped).

    Returns
    -------
    LowPass
        Four poles, no zeros, unit static gain; ``band_hz = max(f1_hz, f2_hz)``.
    """
    poles = []
    gain = 1.0
    for name_f, f, name_z, zeta in (("f1_hz", f1_hz, "zeta1", zeta1), ("f2_hz", f2_hz, "zeta2", zeta2)):
        w = 2.0 * np.pi * _positive(name_f, f)
        zeta = _positive(name_z, zeta)
        poles.extend(np.roots([1.0, 2.0 * zeta * w, w * w]))
        gain *= w * w
    return LowPass(name="paper", zeros=np.array([], dtype=complex), poles=np.array(poles, dtype=complex),
                   gain=gain, band_hz=max(float(f1_hz), float(f2_hz)),
                   description=f"2 x 2nd order, {float(f1_hz):g}/{float(f2_hz):g} Hz, "
                               f"zeta {float(zeta1):g}/{float(zeta2):g} (paper eq. 5)")


def regularized_lowpass(corner_hz: float = BAND_HZ, order: int = BAND_ORDER) -> LowPass:
    """A Butterworth low-pass above the band of interest (this project's regularized inverse).

    Parameters
    ----------
    corner_hz : float, Hz
        -3 dB frequency (default :data:`BAND_HZ`, 30 Hz: the inverse is within 0.4 % of exact up
        to 20 Hz).
    order : int
        Filter order (default :data:`BAND_ORDER`, 6). It must exceed the relative degree of ``T_a`` (3 for eq. 4)
        for the corrected force to roll off; at least 4 is advisable.

    Returns
    -------
    LowPass
        Butterworth poles (``scipy.signal.butter(order, 2 pi corner_hz, analog=True)``), unit
        static gain, ``band_hz = corner_hz``.
    """
    from scipy import signal  # here, not at import: the command-line parsers read BAND_HZ

    corner = _positive("corner_hz", corner_hz)
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 1:
        raise ValueError(f"low-pass parameter order must be a positive integer, got {order!r}")
    z, p, k = signal.butter(int(order), 2.0 * np.pi * corner, btype="low", analog=True, output="zpk")
    return LowPass(name="regularized", zeros=np.asarray(z, dtype=complex), poles=np.asarray(p, dtype=complex),
                   gain=float(np.real(k)), band_hz=corner,
                   description=f"Butterworth order {int(order)}, {corner:g} Hz")


def as_lowpass(lowpass) -> LowPass | None:
    """Resolve ``"paper"``, ``"regularized"``, a :class:`LowPass` or ``None`` (no low-pass).

    Parameters
    ----------
    lowpass : {"paper", "regularized"}, LowPass or None
        A name picks the default parameters; for other parameters pass
        ``paper_lowpass(...)`` or ``regularized_lowpass(...)``.

    Returns
    -------
    LowPass or None
    """
    if lowpass is None or isinstance(lowpass, LowPass):
        return lowpass
    if lowpass == "paper":
        return paper_lowpass()
    if lowpass == "regularized":
        return regularized_lowpass()
    raise ValueError(f"unknown low-pass {lowpass!r}; use 'paper', 'regularized' or a LowPass object")
