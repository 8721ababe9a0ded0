"""Output correction of a rig run, judged against the road run of the same scenario.

One road run and one rig run of a scenario give, per wheel: the road-test force (what the
truck does on the road), the force measured on the rig (with sensor noise, as a real load
cell has), and the rig force corrected two ways:

- ``paper``: the paper's method. T_a(s) from eq. 4 with this rig's actuator parameters and
  the wheel's tire stiffness, inverted and multiplied by the paper's low-pass T_F (16 and
  24 Hz, damping 1), applied as a causal filter.
- ``best``: this project's method. T_a identified per wheel from the rig run's own drive
  signal and LVDT pan displacement (what any lab records, no hydraulic parameters needed),
  inverted with the regularized low-pass (6th-order Butterworth at 30 Hz: the inverse is
  within 0.4 % of exact up to 20 Hz), applied offline with the filter's magnitude and
  T_a^-1's phase (zero-phase mode).

Each corrected force is compared with the road force passed through the same band limit
(the correction cannot restore what its low-pass removes): DLC and
NRMSE = rms(corrected - road_lowpassed) / std(road_lowpassed), on the samples where both
filters have settled.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from correction.apply import band_limit, correct
from correction.filters import design_correction
from correction.actuator_id import identify_actuator
from scenarios.core.results import RunResult

__all__ = ["NOISE_N", "Method", "CaseEvaluation", "evaluate", "identify_wheel_actuator", "paper_actuator"]

#: Default rms of the white measurement noise added to the rig's wheel forces, N. A strain-gauge
#: load cell rated for the 156 kN actuator force resolves ~0.05 % of its range (~80 N);
#: 100 N rms at 1 kHz is that, rounded up.
NOISE_N = 100.0

#: Orders of the rational fit of the identified T_a(s): eq. 4 has one zero and four poles;
#: the spool dynamics (2nd order) and the truck's loading need more.
ID_ORDERS = (3, 6)


@dataclass(frozen=True)
class Method:
    """How a correction is made: where T_a comes from, which low-pass, which application."""

    name: str
    lowpass: str
    mode: str
    description: str


METHODS = (
    Method("paper", "paper", "causal", "eq. 4 from the actuator parameters, paper's low-pass (16/24 Hz), causal"),
    Method("best", "regularized", "zerophase",
           "T_a identified per wheel from drive and LVDT (orders 3/6), 30 Hz 6th-order Butterworth, zero-phase"),
)


@dataclass(frozen=True)
class CaseEvaluation:
    """Forces and figures of one scenario's road run, rig run and corrections.

    Attributes
    ----------
    t_s : numpy.ndarray, s
        Time of the samples (the result's rate).
    road_N, rig_N : numpy.ndarray, N
        Road-test force and measured rig force (with noise), shape (N, 4).
    corrected_N, road_lowpassed_N : dict[str, numpy.ndarray], N
        Per method: the corrected rig force and the road force through the same band limit.
    settled : numpy.ndarray of bool
        Samples where every filter has settled (the statistics use only these).
    wheels : dict[str, dict[str, float]]
        Per wheel: dlc_road, dlc_rig, and per method dlc_corrected_<m>, dlc_road_lowpassed_<m>,
        nrmse_corrected_<m>.
    mean : dict[str, float]
        The same figures averaged over the four wheels.
    noise_N : float, N
        rms of the measurement noise added to the rig force.
    """

    t_s: np.ndarray
    road_N: np.ndarray
    rig_N: np.ndarray
    corrected_N: dict
    road_lowpassed_N: dict
    settled: np.ndarray
    wheels: dict
    mean: dict
    noise_N: float
    actuators: dict = field(default_factory=dict)


def paper_actuator(params, kt_N_per_m: float, load_N: float):
    """eq. 4 coefficients (num, den) for one wheel (hydraulics' linearization at its load)."""
    from hydraulics.linearization import eq4_coefficients

    return eq4_coefficients(params, kt_N_per_m, load_N)


def identify_wheel_actuator(drive_m, pan_m, fs: float, *, orders=ID_ORDERS, f_max_hz: float = 60.0):
    """T_a(s) = (num, den) of one wheel from the rig run's drive and pan displacement.

    The fit of :func:`correction.actuator_id.identify_actuator` (H1 estimate weighted by
    coherence, anchors at T_a = 1 below the first bin, stable rational fit up to ``f_max_hz``),
    with the larger orders a truck-loaded actuator needs, then made usable as an inverse:
    right-half-plane zeros reflected, slow near-cancelling pole-zero pairs removed, T_a(0) = 1.
    """
    nperseg = int(min(8192, max(256, np.asarray(drive_m).size // 8)))
    fit = identify_actuator(drive_m, pan_m, fs, f_max_hz=f_max_hz, nperseg=nperseg, orders=orders)
    num = np.asarray(fit.num[0][0], dtype=float)
    den = np.asarray(fit.den[0][0], dtype=float)
    # A free fit may place a zero in the right half-plane where the data do not constrain it
    # (seen: 0.04 rad/s, far below the first bin). Reflect it: the magnitude is unchanged, the
    # inverse stays stable, and a position loop with PI control is minimum phase anyway.
    zeros = np.roots(num)
    if np.any(zeros.real > 0):
        zeros = np.where(zeros.real > 0, -zeros.conj(), zeros)
        num = np.real(np.poly(zeros)) * num[0]
    # Below the estimate's resolution (fs / nperseg ~ 0.12 Hz) the fit is free to add a slow
    # pole-zero pair that nearly cancels (seen: -0.29 and -0.288 rad/s). It changes the gain by
    # well under 1 % and only below ~0.1 Hz, where the high-passed drive has no content, but its
    # inverse rings for tens of seconds. Cancel such pairs.
    poles = np.roots(den)
    zeros = np.roots(num)
    slow = 2 * np.pi * 2.0 * fs / nperseg  # rad/s: twice the estimate's frequency resolution
    keep_p = np.ones(poles.size, dtype=bool)
    keep_z = np.ones(zeros.size, dtype=bool)
    for iz, z in enumerate(zeros):
        if abs(z) > slow:
            continue
        gap = np.where(keep_p, np.abs(poles - z), np.inf)
        ip = int(np.argmin(gap))
        if gap[ip] < 0.1 * max(abs(z), 1e-3) + 1e-3:
            keep_p[ip] = keep_z[iz] = False
    if not (keep_p.all() and keep_z.all()):
        num = np.atleast_1d(np.real(np.poly(zeros[keep_z]))) * num[0]
        den = np.atleast_1d(np.real(np.poly(poles[keep_p]))) * den[0]
    # The anchors pin the static gain near 1; make it exactly 1 (the PI loop's integral action).
    return num * (den[-1] / num[-1]), den


def _dlc(x: np.ndarray) -> np.ndarray:
    return x.std(axis=0) / x.mean(axis=0)


def evaluate(road: RunResult, rig: RunResult, *, params, tire_N_per_m, noise_N: float = NOISE_N,
             seed: int = 0) -> CaseEvaluation:
    """Correct ``rig``'s wheel forces and compare them with ``road``'s.

    Parameters
    ----------
    road, rig : RunResult
        Road-mode and rig-mode runs of the same scenario (same drive, same time axis).
    params : hydraulics.params.ActuatorParams
        The rig's actuator parameters (for eq. 4, the paper's method).
    tire_N_per_m : array_like of 4 floats, N/m
        Tire stiffness of each wheel station (eq. 4's kt).
    noise_N : float, N
        rms of the white measurement noise added to the rig force (0 turns it off).
    seed : int
        Seed of the noise (``numpy.random.default_rng((seed, 8))``).
    """
    if road.t_s.shape != rig.t_s.shape or not np.array_equal(road.t_s, rig.t_s):
        raise ValueError("road and rig runs must share their time axis (the same scenario)")
    fs = road.rate_hz
    road_f = np.asarray(road.signals["tire_force_N"], dtype=float)
    rig_clean = np.asarray(rig.signals["tire_force_N"], dtype=float)
    rng = np.random.default_rng((int(seed), 8))
    rig_f = rig_clean + (noise_N * rng.standard_normal(rig_clean.shape) if noise_N > 0 else 0.0)
    n = road_f.shape[0]
    settled = np.ones(n, dtype=bool)
    corrected, road_lp, actuators = {}, {}, {}
    loads = rig_clean.mean(axis=0)
    for method in METHODS:
        out = np.empty_like(rig_f)
        tas = []
        for i in range(4):
            if method.name == "paper":
                ta = paper_actuator(params, float(tire_N_per_m[i]), float(loads[i]))
            else:
                ta = identify_wheel_actuator(rig.signals["profile_m"][:, i], rig.signals["pan_m"][:, i], fs)
            filt = design_correction(ta, fs, method.lowpass)
            out[:, i] = correct(rig_f[:, i], filt, method.mode)
            settled &= filt.transient_mask(n, method.mode)  # True where settled
            tas.append(ta)
        corrected[method.name] = out
        road_lp[method.name] = band_limit(road_f, fs, method.lowpass, method.mode)
        actuators[method.name] = tas
    if settled.sum() < 5 * fs:
        raise ValueError(
            f"only {settled.sum() / fs:.1f} s of the {n / fs:.1f} s record remain once the correction filters "
            "have settled; run a longer scenario (at least ~30 s)"
        )
    s = settled
    wheels = {}
    corners = road.corners
    base = {"dlc_road": _dlc(road_f[s]), "dlc_rig": _dlc(rig_f[s])}
    for m in METHODS:
        c, r = corrected[m.name][s], road_lp[m.name][s]
        base[f"dlc_corrected_{m.name}"] = _dlc(c)
        base[f"dlc_road_lowpassed_{m.name}"] = _dlc(r)
        base[f"nrmse_corrected_{m.name}"] = np.sqrt(np.mean((c - r) ** 2, axis=0)) / r.std(axis=0)
    for i, corner in enumerate(corners):
        wheels[corner] = {k: float(v[i]) for k, v in base.items()}
    mean = {k: float(np.mean(v)) for k, v in base.items()}
    return CaseEvaluation(
        t_s=road.t_s, road_N=road_f, rig_N=rig_f, corrected_N=corrected, road_lowpassed_N=road_lp,
        settled=settled, wheels=wheels, mean=mean, noise_N=float(noise_N), actuators=actuators,
    )
