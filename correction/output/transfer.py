"""Actuator transfer functions: the paper's eq. 4, frequency responses, bandwidth, filtering.

The paper (Correction of dynamic wheel forces measured on road simulators) models the
servo-hydraulic wheelpan actuator by the transfer function from drive signal (road profile)
to pan displacement, eq. 4::

    T_a(s) = X_a(s) / X_p(s) = (b1 s + b0) / (a4 s^4 + a3 s^3 + a2 s^2 + a1 s + a0)

This module builds it from plain numbers (no simulator needed), evaluates transfer functions
and discrete-time state-space models in Hz, finds their -3 dB bandwidth, and applies a
continuous-time transfer function to a sampled signal (what the output correction of measured
wheel forces needs). Frequencies are in Hz at the interfaces, rad/s inside Laplace variables.
"""

from __future__ import annotations

import math
import sys
from typing import TYPE_CHECKING

import numpy as np

from rigsim.correction.output.eq4 import eq4_coefficients_from

if TYPE_CHECKING:  # python-control is imported where it is used (it loads matplotlib)
    import control

__all__ = [
    "eq4_transfer_function",
    "frequency_response_hz",
    "state_space_frequency_response",
    "bandwidth_hz",
    "transfer_bandwidth_hz",
    "describe_roots",
    "is_transfer_function",
    "apply_transfer_function",
]


def eq4_transfer_function(**parameters: float) -> control.TransferFunction:
    """The paper's eq. 4, ``T_a(s) = X_a(s) / X_p(s)`` of one wheelpan actuator, as a transfer function.

    A thin wrapper of :func:`rigsim.correction.output.eq4.eq4_coefficients_from`, the one implementation of
    the formula and of its parameter checks (see there for the coefficients).

    Parameters
    ----------
    **parameters : float
        Exactly the keyword arguments of :func:`rigsim.correction.output.eq4.eq4_coefficients_from` (names
        and SI units in :data:`rigsim.correction.output.eq4.EQ4_PARAMETERS`): ``ksv`` (1), ``kq_m3_s``
        (m^3/s per unit spool), ``kc_m3_s_Pa`` (m^3/(s Pa), leakage included), ``kp_per_m``
        (1/m), ``kdp_per_Pa`` (1/Pa), ``piston_area_m2`` (m^2), ``fluid_volume_m3`` (m^3),
        ``bulk_modulus_Pa`` (Pa), ``mass_kg`` (kg), ``damping_N_s_m`` (N s/m),
        ``tire_N_per_m`` (N/m) and optionally ``ti_s`` (s, default 1 s as printed;
        ``math.inf`` is a P-only loop).

    Returns
    -------
    control.TransferFunction
        Continuous time, s in rad/s, input x_p (m), output x_a (m). Static gain 1 and a zero
        at ``-1 / Ti`` rad/s (``-1`` rad/s as printed) for any valid parameters; for a P-only
        loop the common root at ``s = 0`` of ``b0 = a0 = 0`` is cancelled.

    Raises
    ------
    ValueError
        If a parameter is not a finite real number or out of its range (raised by
        :func:`rigsim.correction.output.eq4.eq4_coefficients_from`, naming the parameter).
    TypeError
        If a parameter is missing or unknown.

    Notes
    -----
    Eq. 4 hides these assumptions (Merritt, *Hydraulic Control Systems*, ch. 5; Wang's
    linearization cited by the paper):

    * **Static valve.** The spool follows the controller output instantly (``xv = Ksv u``). A
      real three-stage servovalve has second-order dynamics at ~100-200 Hz, whose phase lag is
      already ~10 degrees at 20-30 Hz; eq. 4 omits it.
    * **Small signals about one operating point.** ``Kq`` and ``Kc`` are slopes of the orifice
      law at one spool position and load pressure; a symmetric, matched, critically lapped
      valve and equal piston areas, so one load pressure ``PL = P1 - P2`` describes both
      chambers; both chambers at mid-stroke volume ``Vf / 2``; constant bulk modulus; no flow
      or command saturation, no cavitation.
    * **Tire as a spring to rigid ground.** The load on the pan is ``kt x_a`` only: no
      unsprung mass, no tire damping, no suspension or sprung mass, no coupling to the other
      wheels, tire always on the pan. ``T_a`` depends on the vehicle through ``kt``.
    * **PI position loop with Ti = 1 s** plus differential-pressure feedback, without
      saturation: this makes ``b0 = b1 = a0`` as printed.
    """
    import control

    num, den = eq4_coefficients_from(**parameters)
    if num[-1] == 0.0 and den[-1] == 0.0:  # P only (ti_s = inf): cancel the common root at s = 0
        num, den = num[:-1], den[:-1]
    return control.tf(num, den, inputs="x_p_m", outputs="x_a_m", name="T_a_eq4")


def frequency_response_hz(system, f_hz) -> np.ndarray:
    """Complex frequency response of a SISO or MIMO python-control system at ``f_hz``.

    Parameters
    ----------
    system : control.TransferFunction or control.StateSpace, or (num, den)
        Continuous (evaluated at ``s = j 2 pi f``) or discrete (``z = exp(j 2 pi f dt)``); a
        tuple of two coefficient arrays (descending powers of s) is a continuous SISO one.
    f_hz : array_like, Hz
        Frequencies.

    Returns
    -------
    numpy.ndarray of complex
        Shape ``(len(f_hz),)`` for a SISO system, else ``(len(f_hz), noutputs, ninputs)``.
    """
    f = np.atleast_1d(np.asarray(f_hz, dtype=float))
    w = 2.0 * np.pi * f
    if isinstance(system, tuple):
        num, den = system
        return np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    if system.isdtime(strict=True):
        x = np.exp(1j * w * system.dt)
    else:
        x = 1j * w
    h = np.asarray(system(x))  # (noutputs, ninputs, nf)
    h = np.moveaxis(h.reshape(system.noutputs, system.ninputs, f.size), -1, 0)
    if system.noutputs == 1 and system.ninputs == 1:
        return h[:, 0, 0]
    return h


def state_space_frequency_response(a, b, c, f_hz, dt_s: float | None = None, d=None) -> np.ndarray:
    """``H(f) = C (x I - A)^-1 B + D`` of a state-space model, MIMO, at ``f_hz``.

    Parameters
    ----------
    a, b, c : array_like
        State matrix (n, n), input matrix (n, m), output matrix (p, n).
    f_hz : array_like, Hz
        Frequencies.
    dt_s : float, s, optional
        Sample time of a discrete model ``x[k+1] = A x[k] + B u[k]`` (then
        ``x = exp(j 2 pi f dt)``); ``None`` for a continuous model (``x = j 2 pi f``).
    d : array_like, optional
        Feedthrough (p, m); zero by default.

    Returns
    -------
    numpy.ndarray of complex, shape (len(f_hz), p, m)
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c = np.asarray(c, dtype=float)
    if b.ndim == 1:
        b = b[:, None]
    if c.ndim == 1:
        c = c[None, :]
    n = a.shape[0]
    if a.shape != (n, n) or b.shape[0] != n or c.shape[1] != n:
        raise ValueError(f"inconsistent shapes A {a.shape}, B {b.shape}, C {c.shape}")
    f = np.atleast_1d(np.asarray(f_hz, dtype=float))
    w = 2.0 * np.pi * f
    if dt_s is None:
        x = 1j * w
    else:
        if not dt_s > 0:
            raise ValueError(f"dt_s must be > 0, got {dt_s!r}")
        x = np.exp(1j * w * dt_s)
    # Hessenberg-free but exact: one solve per frequency (n is a few dozen states).
    out = np.empty((f.size, c.shape[0], b.shape[1]), dtype=complex)
    eye = np.eye(n)
    for i, xi in enumerate(x):
        out[i] = c @ np.linalg.solve(xi * eye - a, b)
    if d is not None:
        out += np.asarray(d, dtype=float)[None]
    return out


def bandwidth_hz(f_hz, h, *, reference: float | None = None, drop_db: float = 3.0) -> float:
    """First frequency at which ``|h|`` falls ``drop_db`` below ``reference``.

    Parameters
    ----------
    f_hz : array_like, Hz
        Increasing frequencies.
    h : array_like of complex or float
        Frequency response (or its magnitude) at ``f_hz``.
    reference : float, optional
        Reference magnitude (the static gain); default ``|h[0]|``.
    drop_db : float, dB
        The drop defining the bandwidth (3 dB).

    Returns
    -------
    float, Hz
        Interpolated linearly in dB over log-frequency between the grid points bracketing the
        first crossing; ``nan`` if ``|h|`` never falls that far on the grid.
    """
    f = np.asarray(f_hz, dtype=float)
    mag = np.abs(np.asarray(h))
    if f.shape != mag.shape or f.size < 2:
        raise ValueError("f_hz and h must be 1-D of the same length (at least 2)")
    ref = mag[0] if reference is None else float(reference)
    db = 20.0 * np.log10(np.maximum(mag, 1e-300) / ref)
    below = np.nonzero(db <= -drop_db)[0]
    if below.size == 0:
        return math.nan
    i = int(below[0])
    if i == 0:
        return float(f[0])
    x0, x1 = math.log(f[i - 1]), math.log(f[i])
    y0, y1 = db[i - 1] + drop_db, db[i] + drop_db
    return float(math.exp(x0 + (x1 - x0) * y0 / (y0 - y1)))


def transfer_bandwidth_hz(system, *, drop_db: float = 3.0, f_min_hz: float = 1e-3,
                          f_max_hz: float = 1e4) -> float:
    """-3 dB bandwidth (Hz) of a SISO system relative to its static gain, to 1e-9 Hz.

    Parameters
    ----------
    system : control.TransferFunction or control.StateSpace, or (num, den)
        SISO, continuous or discrete, with a finite non-zero static gain; a tuple of two
        coefficient arrays (descending powers of s) is a continuous transfer function.
    drop_db : float, dB
    f_min_hz, f_max_hz : float, Hz
        Search range (log grid, then Brent's method on the first bracket).

    Returns
    -------
    float, Hz
        ``nan`` if the gain never falls ``drop_db`` below the static gain in the range.
    """
    from scipy import optimize

    if isinstance(system, tuple):
        num, den = (np.atleast_1d(np.asarray(c, dtype=float)) for c in system)
        system = (num, den)
        dc = abs(num[-1] / den[-1]) if den[-1] != 0 else math.inf
    else:
        dc = abs(complex(np.squeeze(system.dcgain())))
    if not (math.isfinite(dc) and dc > 0):
        raise ValueError("the system needs a finite, non-zero static gain")
    if not isinstance(system, tuple) and system.isdtime(strict=True):
        f_max_hz = min(f_max_hz, 0.5 / system.dt * (1 - 1e-9))
    f = np.geomspace(f_min_hz, f_max_hz, 4000)
    mag = np.abs(frequency_response_hz(system, f))
    target = dc * 10 ** (-drop_db / 20.0)
    below = np.nonzero(mag <= target)[0]
    if below.size == 0:
        return math.nan
    i = int(below[0])
    if i == 0:
        return float(f[0])

    def g(x):
        return abs(frequency_response_hz(system, [x])[0]) - target

    return float(optimize.brentq(g, f[i - 1], f[i], xtol=1e-9))


def is_transfer_function(obj) -> bool:
    """Whether ``obj`` is a ``control.TransferFunction``, without importing python-control (and
    with it matplotlib) for the question: an object can only be one once the package is loaded."""
    control = sys.modules.get("control")
    return control is not None and isinstance(obj, control.TransferFunction)


def describe_roots(roots, dt_s: float | None = None) -> list[dict]:
    """Poles or zeros as plain numbers: real and imaginary part (rad/s), Hz and damping ratio.

    Parameters
    ----------
    roots : array_like of complex
        Continuous roots in rad/s, or discrete ones (then give ``dt_s``; each maps to
        ``log(z) / dt``).
    dt_s : float, s, optional

    Returns
    -------
    list of dict
        One per root with a non-negative imaginary part (one of each conjugate pair), sorted
        by magnitude: ``real_rad_s``, ``imag_rad_s``, ``frequency_hz`` (``|s| / 2 pi``) and
        ``damping_ratio`` (``-Re s / |s|``; 1 for a root at 0).
    """
    r = np.asarray(roots, dtype=complex).ravel()
    if dt_s is not None:
        r = np.log(r) / dt_s
    out = []
    for s in sorted(r[r.imag >= -1e-9 * np.maximum(1.0, np.abs(r))], key=abs):
        mag = abs(s)
        out.append({
            "real_rad_s": float(s.real),
            "imag_rad_s": float(abs(s.imag)),
            "frequency_hz": float(mag / (2 * math.pi)),
            "damping_ratio": float(-s.real / mag) if mag > 0 else 1.0,
        })
    return out


def apply_transfer_function(system, u, dt_s: float, *, derivative: bool = False) -> np.ndarray:
    """Pass a sampled signal through a continuous-time SISO transfer function (zero-order hold).

    The input is held constant over each sample (how a controller or a simulator with time
    step ``dt_s`` applies it) and the output is sampled at the start of each interval, so
    ``y[k]`` depends on ``u[0..k-1]`` -- the convention of ``x[k+1] = Ad x[k] + Bd u[k]``,
    ``y[k] = C x[k]``. The discretization is exact: the system is split into first-order
    modes (partial fractions of its distinct poles), each discretized exactly and run as a
    first-order recursive filter (``scipy.signal.lfilter``), so minutes of data at 10 kHz take
    well under a second. The system starts at rest.

    Parameters
    ----------
    system : control.TransferFunction or control.StateSpace
        Continuous-time, SISO, strictly proper (or proper), with distinct poles.
    u : array_like, shape (N,) or (N, k)
        Input samples (any unit); a 2-D input is filtered column by column.
    dt_s : float, s
        Sample interval.
    derivative : bool
        Return the time derivative of the output (``s T(s)`` applied; needs a strictly proper
        system), e.g. a pan velocity from a pan displacement model.

    Returns
    -------
    numpy.ndarray
        Output samples, the shape of ``u`` (unit of ``u`` times the system's gain; per second
        with ``derivative``).

    Raises
    ------
    ValueError
        For a discrete, MIMO or improper system, repeated poles, or a bad ``dt_s``.
    """
    import control
    from scipy import signal

    if system.isdtime(strict=True):
        raise ValueError("apply_transfer_function needs a continuous-time system")
    if system.ninputs != 1 or system.noutputs != 1:
        raise ValueError("apply_transfer_function needs a SISO system")
    if not (isinstance(dt_s, (int, float, np.floating)) and dt_s > 0):
        raise ValueError(f"dt_s must be > 0, got {dt_s!r}")
    tf = control.tf(system)
    num = np.atleast_1d(np.squeeze(np.asarray(tf.num[0][0], dtype=float)))
    den = np.atleast_1d(np.squeeze(np.asarray(tf.den[0][0], dtype=float)))
    num = np.trim_zeros(num, "f")
    if num.size == 0:
        return np.zeros_like(np.asarray(u, dtype=float))
    if derivative:
        num = np.append(num, 0.0)
    if num.size > den.size:
        raise ValueError("the system (or its derivative) is improper; cannot filter it")
    # Partial fractions: T(s) = sum r_i / (s - p_i) + k.
    r, p, k = signal.residue(num, den)
    if p.size > 1:
        gaps = np.abs(p[:, None] - p[None, :])
        np.fill_diagonal(gaps, np.inf)
        if np.min(gaps) < 1e-9 * max(1.0, float(np.max(np.abs(p)))):
            raise ValueError("apply_transfer_function needs distinct poles")
    u = np.asarray(u, dtype=float)
    flat = u.reshape(u.shape[0], -1)
    y = np.zeros(flat.shape, dtype=float)
    for ri, pi in zip(r, p):
        ad = np.exp(pi * dt_s)
        bd = ri * (dt_s if pi == 0 else np.expm1(pi * dt_s) / pi)
        for j in range(flat.shape[1]):
            # x[k+1] = ad x[k] + bd u[k]; y[k] = x[k]: a one-sample-delayed first-order filter.
            y[:, j] += np.real(signal.lfilter([0.0, bd], [1.0, -ad], flat[:, j].astype(complex)))
    if k.size:
        y += float(np.real(k[0])) * flat  # proper systems: feedthrough
    return y.reshape(u.shape)
