"""The one scoring of a road/rig pair: the rig force corrected, judged against the road force.

Every study that compares a rig run with the road run of the same scenario (``rigsim paper``,
``rigsim sweep``, ``rigsim iterate``) calls :func:`score_pair`, so the same case and seed give
the same figures in all of them.

Per wheel: the road-test force (what the truck does on the road), the force measured on the
rig (the simulated load cell plus white measurement noise, as a real load cell has), and the
rig force corrected by each :class:`Method`:

- ``paper``: the paper's method. T_a(s) from eq. 4 (:func:`correction.eq4.eq4_coefficients_from`)
  with Merritt's coefficients linearized at the wheel's static actuator load (mean measured tire
  force plus the pan's weight, :func:`hydraulics.linearization.eq4_parameters`), the station's
  tire stiffness and the rig's pan mass; inverted times the paper's low-pass T_F (16 and 24 Hz,
  damping 1), applied as a causal filter.
- ``best``: this project's method. T_a identified per wheel from the rig run's own drive and
  LVDT pan displacement (what any lab records, no hydraulic parameters needed), inverted under
  the regularized low-pass (6th-order Butterworth at 30 Hz), applied offline zero-phase.

Each corrected force is compared with the road force through the same band limit (a correction
cannot restore what its low-pass removes): DLC and NRMSE (:mod:`correction.dlc`) on the samples
where that method's correction filters and its band-limit filter have all settled (the union
of their transients is left out); the corrected DLC is compared with the unfiltered road DLC on
those same samples (``dlc_road_settled``). The road and rig DLCs of the test as a lab reports
them (``dlc_road``, ``dlc_rig``) use the whole record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from correction.actuator_id import identify_actuator
from correction.apply import band_limit, correct
from correction.dlc import dlc, nrmse
from correction.eq4 import eq4_coefficients_from
from correction.filters import design_correction, reference_filter
from hydraulics.linearization import eq4_parameters
from hydraulics.params import GRAVITY_M_S2
from scenarios.core.config import ScenarioError

__all__ = ["NOISE_N", "MIN_SCORED_S", "Method", "PAPER", "BEST", "METHODS", "method_named", "MethodScore",
           "PairScore", "score_pair", "SETTLING_TOLERANCE", "identify_wheel_actuator", "measured_force"]

#: Default rms of the white measurement noise added to the rig's wheel forces, N. A strain-gauge
#: load cell rated for the 156 kN actuator force resolves ~0.05 % of its range (~80 N);
#: 100 N rms at 1 kHz is that, rounded up.
NOISE_N = 100.0

#: Fewer settled seconds than this cannot give a meaningful DLC, s.
MIN_SCORED_S = 0.25

#: Relative tolerance of the filters' transients: samples where a filter's start-up (and, zero-phase,
#: end) transient still exceeds this fraction of a step are not scored (the correction's default).
SETTLING_TOLERANCE = 1e-3

#: Orders (numerator, denominator) of the rational fit of the identified T_a(s): eq. 4 has one
#: zero and four poles; the spool dynamics (2nd order) and the truck's loading need more.
ID_ORDERS = (3, 6)


@dataclass(frozen=True)
class Method:
    """How a correction is made.

    Attributes
    ----------
    name : str
    actuator : {"eq4", "identified"}
        Where T_a comes from: eq. 4 from the actuator parameters, or identified per wheel from
        the rig run's drive and pan displacement.
    lowpass : {"paper", "regularized"}
        The low-pass T_F (:mod:`correction.lowpass`).
    mode : {"causal", "zerophase"}
        How the filter is applied (:func:`correction.apply.correct`).
    description : str
    """

    name: str
    actuator: str
    lowpass: str
    mode: str
    description: str = ""

    def __post_init__(self) -> None:
        for field, value, allowed in (("actuator", self.actuator, ("eq4", "identified")),
                                      ("lowpass", self.lowpass, ("paper", "regularized")),
                                      ("mode", self.mode, ("causal", "zerophase"))):
            if value not in allowed:
                raise ScenarioError(f"correction {field} must be one of {', '.join(allowed)}, got {value!r}")


PAPER = Method("paper", "eq4", "paper", "causal",
               "eq. 4 from the actuator parameters at each wheel's static load, paper's low-pass (16/24 Hz), causal")
BEST = Method("best", "identified", "regularized", "zerophase",
              "T_a identified per wheel from drive and LVDT (orders 3/6), 30 Hz 6th-order Butterworth, zero-phase")
METHODS = (PAPER, BEST)


def method_named(actuator: str, lowpass: str, mode: str) -> Method:
    """The :class:`Method` with these settings: ``paper`` or ``best`` when it is one of them."""
    for m in METHODS:
        if (m.actuator, m.lowpass, m.mode) == (actuator, lowpass, mode):
            return m
    return Method("custom", actuator, lowpass, mode, f"T_a {actuator}, low-pass {lowpass}, {mode}")


def identify_wheel_actuator(drive_m, pan_m, fs: float, *, orders=ID_ORDERS, f_max_hz: float = 60.0):
    """T_a(s) = (num, den) of one wheel from the rig run's drive (m) and pan displacement (m).

    ``fs`` in Hz. The fit of :func:`correction.actuator_id.identify_actuator` (H1 estimate
    weighted by coherence, anchors at T_a = 1 below the first bin, stable rational fit up to
    ``f_max_hz``, Hz), with the larger orders a truck-loaded actuator needs, then made usable as
    an inverse: right-half-plane zeros reflected, slow near-cancelling pole-zero pairs removed,
    T_a(0) = 1.
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


@dataclass(frozen=True)
class MethodScore:
    """One method's corrected forces and figures.

    Attributes
    ----------
    method : Method
    corrected_N : numpy.ndarray, N, (n, 4)
        The measured rig force filtered by T_a^-1 T_F.
    road_band_N, rig_band_N : numpy.ndarray, N, (n, 4)
        Road and measured rig force through T_F alone (same mode).
    settled : numpy.ndarray of bool, (n,)
        Samples outside every transient of this method's filters (the scored samples).
    actuators : tuple of (numpy.ndarray, numpy.ndarray)
        T_a(s) = (num, den) per wheel, descending powers of s (rad/s).
    wheels : numpy.ndarray, (4,) per figure in ``figures``
    figures : Mapping[str, numpy.ndarray]
        Per wheel: ``dlc_corrected``, ``dlc_road_settled`` (the unfiltered road force on the same
        samples: what the corrected DLC is compared with), ``dlc_road_band``, ``dlc_rig_band`` (1),
        ``nrmse_corrected``, ``nrmse_rig`` (1, against the band-limited road force).
    scored_s : float, s
    """

    method: Method
    corrected_N: np.ndarray
    road_band_N: np.ndarray
    rig_band_N: np.ndarray
    settled: np.ndarray
    actuators: tuple
    figures: Mapping
    scored_s: float


@dataclass(frozen=True)
class PairScore:
    """The corrections of one rig run and their figures against the road run.

    Attributes
    ----------
    t_s : numpy.ndarray, s
    road_N, rig_N : numpy.ndarray, N, (n, 4)
        Road-test force and measured rig force (with the measurement noise).
    noise_N : float, N
        rms of the measurement noise.
    dlc_road, dlc_rig : numpy.ndarray, (4,)
        DLC of the road and the measured rig force over the whole record.
    methods : Mapping[str, MethodScore]
    corners : tuple of str
    """

    t_s: np.ndarray
    road_N: np.ndarray
    rig_N: np.ndarray
    noise_N: float
    dlc_road: np.ndarray
    dlc_rig: np.ndarray
    methods: Mapping
    corners: tuple

    def per_wheel(self) -> dict[str, np.ndarray]:
        """Every figure per wheel, flat: ``dlc_road``, ``dlc_rig`` and ``<figure>_<method>``."""
        out = {"dlc_road": self.dlc_road, "dlc_rig": self.dlc_rig}
        for name, ms in self.methods.items():
            out.update({f"{k}_{name}": v for k, v in ms.figures.items()})
        return out

    @property
    def mean(self) -> dict[str, float]:
        """Every figure averaged over the four wheels."""
        return {k: float(np.mean(v)) for k, v in self.per_wheel().items()}

    @property
    def wheels(self) -> dict[str, dict[str, float]]:
        """Every figure of each wheel, keyed by corner."""
        per = self.per_wheel()
        return {c: {k: float(v[i]) for k, v in per.items()} for i, c in enumerate(self.corners)}

    @property
    def settled(self) -> np.ndarray:
        """Samples settled for every method (for plots that show all of them)."""
        masks = [ms.settled for ms in self.methods.values()]
        return np.logical_and.reduce(masks) if masks else np.ones(self.t_s.size, dtype=bool)

    @property
    def corrected_N(self) -> dict[str, np.ndarray]:
        return {k: ms.corrected_N for k, ms in self.methods.items()}

    @property
    def road_lowpassed_N(self) -> dict[str, np.ndarray]:
        return {k: ms.road_band_N for k, ms in self.methods.items()}

    def to_dict(self) -> dict:
        """Means, per wheel, and the methods with their scored seconds (for JSON)."""
        return {"mean": self.mean, "wheels": self.wheels, "noise_N": self.noise_N,
                "methods": {k: {"description": ms.method.description, "scored_s": ms.scored_s,
                                "actuators": [{"num": n.tolist(), "den": d.tolist()} for n, d in ms.actuators]}
                            for k, ms in self.methods.items()}}


def measured_force(rig, noise_N: float, seed: int) -> np.ndarray:
    """The rig run's tire forces as a load cell measures them: plus white noise of ``noise_N``
    (N rms) from ``numpy.random.default_rng((seed, 8))``."""
    clean = np.asarray(rig.signals["tire_force_N"], dtype=float)
    if not noise_N > 0:
        return clean.copy()
    return clean + noise_N * np.random.default_rng((int(seed), 8)).standard_normal(clean.shape)


def _actuator(method: Method, rig_model, rig, force_N: np.ndarray, i: int, fs: float):
    if method.actuator == "identified":
        return identify_wheel_actuator(rig.signals["profile_m"][:, i], rig.signals["pan_m"][:, i], fs)
    load = float(np.mean(force_N[:, i])) + rig_model.pan_mass_kg * GRAVITY_M_S2  # static actuator load
    kt = float(rig_model.tire_stiffness_N_per_m[i])
    return eq4_coefficients_from(**eq4_parameters(rig_model.params, kt, load, mass_kg=rig_model.pan_mass_kg))


def score_pair(road, rig, rig_model, *, methods=METHODS, noise_N: float = NOISE_N, seed: int = 0,
               settling_tolerance: float = SETTLING_TOLERANCE) -> PairScore:
    """Correct ``rig``'s wheel forces by each method and compare them with ``road``'s.

    Parameters
    ----------
    road, rig : scenarios.core.results.RunResult
        Road-mode and rig-mode runs of the same scenario (same drive, same time axis).
    rig_model : scenarios.core.rig.Rig
        The rig of the scenario (actuator parameters, pan mass, tire stiffness for eq. 4).
    methods : sequence of Method
    noise_N : float, N
        rms of the white measurement noise added to the rig force (0 turns it off).
    seed : int
        Seed of the noise.
    settling_tolerance : float, 1
        Samples inside the filters' transients at this tolerance are not scored.

    Raises
    ------
    ScenarioError
        A record too short to score beyond the correction's transients (one sentence).
    ValueError
        The correction filter cannot be designed for an actuator (one sentence).
    """
    if road.t_s.shape != rig.t_s.shape or not np.array_equal(road.t_s, rig.t_s):
        raise ValueError("road and rig runs must share their time axis (the same scenario)")
    if not (np.isfinite(noise_N) and noise_N >= 0):
        raise ScenarioError(f"noise_N must be >= 0 N, got {noise_N!r}")
    fs = road.rate_hz
    road_f = np.asarray(road.signals["tire_force_N"], dtype=float)
    rig_f = measured_force(rig, noise_N, seed)
    n = road_f.shape[0]
    scores = {}
    for m in methods:
        out = np.empty_like(rig_f)
        settled = np.ones(n, dtype=bool)
        tas = []
        for i in range(rig_f.shape[1]):
            ta = _actuator(m, rig_model, rig, rig_f, i, fs)
            filt = design_correction(ta, fs, m.lowpass, settling_tolerance=settling_tolerance)
            out[:, i] = correct(rig_f[:, i], filt, m.mode)
            settled &= filt.transient_mask(n, m.mode)
            tas.append((np.asarray(ta[0], float), np.asarray(ta[1], float)))
        settled &= reference_filter(fs, m.lowpass, settling_tolerance=settling_tolerance).transient_mask(n, m.mode)
        scored_s = float(np.count_nonzero(settled)) / fs
        if scored_s < MIN_SCORED_S:
            lost = (n - np.count_nonzero(settled)) / fs
            raise ScenarioError(
                f"duration_s = {n / fs:g} s leaves {scored_s:.2f} s to score after the {m.name} correction's "
                f"transients ({lost:.2f} s); use duration_s >= {lost + 1.0:.0f} s")
        road_b = band_limit(road_f, fs, m.lowpass, m.mode)
        rig_b = band_limit(rig_f, fs, m.lowpass, m.mode)
        s = settled
        figures = {"dlc_corrected": dlc(out[s]), "dlc_road_settled": dlc(road_f[s]),
                   "dlc_road_band": dlc(road_b[s]), "dlc_rig_band": dlc(rig_b[s]),
                   "nrmse_corrected": nrmse(out[s], road_b[s]), "nrmse_rig": nrmse(rig_b[s], road_b[s])}
        scores[m.name] = MethodScore(method=m, corrected_N=out, road_band_N=road_b, rig_band_N=rig_b,
                                     settled=settled, actuators=tuple(tas), figures=figures, scored_s=scored_s)
    return PairScore(t_s=road.t_s, road_N=road_f, rig_N=rig_f, noise_N=float(noise_N), dlc_road=dlc(road_f),
                     dlc_rig=dlc(rig_f), methods=scores, corners=tuple(road.corners))
