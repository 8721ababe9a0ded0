"""The one scoring of a road/rig pair: the rig force corrected, judged against the road force.

Every study that compares a rig run with the road run of the same scenario (``rigsim paper``,
``rigsim sweep``, ``rigsim iterate``) calls :func:`score_pair`, so the same case and seed give
the same figures in all of them.

Per wheel: the road-test force (what the truck does on the road), the force measured on the
rig (the simulated load cell plus white measurement noise, as a real load cell has), and the
rig force corrected by each :class:`Method`:

- ``paper``: the paper's method. T_a(s) from eq. 4 (:func:`rigsim.correction.output.eq4.eq4_coefficients_from`)
  with Merritt's coefficients linearized at the wheel's static actuator load (mean measured tire
  force plus the pan's weight, :func:`rigsim.hydraulics.linearization.eq4_parameters`), the station's
  tire stiffness and the rig's pan mass; inverted times the paper's low-pass T_F (16 and 24 Hz,
  damping 1), applied as a causal filter.
- ``best``: this project's method. T_a identified per corner as a lab characterizes its rig
  before a test (:func:`rigsim.scenarios.studies.identify.compute.identify_rig`: independent random
  drives on the four posts at the test drive's rms, the one fitting policy of
  :mod:`rigsim.correction.identification.actuator_fit`; no hydraulic parameters needed), inverted under the
  regularized low-pass (6th-order Butterworth at 30 Hz), applied offline zero-phase.

Both are applied by the one correction function, :func:`rigsim.correction.output.pipeline.correct_forces`,
which ``rigsim correct`` also uses: the same data give the same numbers.

Each corrected force is compared with the road force through the same band limit (a correction
cannot restore what its low-pass removes): DLC and NRMSE (:mod:`rigsim.correction.metrics.dlc`) on the samples
where that method's correction filters and its band-limit filter have all settled (the union
of their transients is left out); the corrected DLC is compared with the unfiltered road DLC on
those same samples (``dlc_road_settled``). The road and rig DLCs of the test as a lab reports
them (``dlc_road``, ``dlc_rig``) use the whole record.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rigsim.correction.output.apply import band_limit
from rigsim.correction.metrics.damage import damage_equivalent_load, rainflow_cycles, stress_factor
from rigsim.correction.metrics.dlc import dlc, nrmse
from rigsim.correction.output.eq4 import eq4_coefficients_from
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.correction.output.pipeline import SETTLING_TOLERANCE, correct_forces
from rigsim.hydraulics.linearization import eq4_parameters
from rigsim.hydraulics.params import GRAVITY_M_S2
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.lab import LabChain, measure

__all__ = ["NOISE_N", "MIN_SCORED_S", "MIN_DURATION_S", "Method", "PAPER", "BEST", "METHODS", "method_named", "MethodScore",
           "PairScore", "score_pair", "SETTLING_TOLERANCE", "check_noise", "measured_force", "shortest_scorable_s",
           "best_linear"]

#: Default rms of the white measurement noise added to the rig's wheel forces, N. A strain-gauge
#: load cell rated for the 156 kN actuator force resolves ~0.05 % of its range (~80 N);
#: 100 N rms at 1 kHz is that, rounded up.
NOISE_N = 100.0


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
        The low-pass T_F (:mod:`rigsim.correction.output.lowpass`).
    mode : {"causal", "zerophase"}
        How the filter is applied (:func:`rigsim.correction.output.apply.correct`).
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
BEST = Method("best", "identified", BAND_LOWPASS, BAND_MODE,
              "T_a identified per corner from independent random drives at the test drive's rms (rigsim identify), "
              "30 Hz 6th-order Butterworth, zero-phase")
METHODS = (PAPER, BEST)


def method_named(actuator: str, lowpass: str, mode: str) -> Method:
    """The :class:`Method` with these settings: ``paper`` or ``best`` when it is one of them."""
    for m in METHODS:
        if (m.actuator, m.lowpass, m.mode) == (actuator, lowpass, mode):
            return m
    return Method("custom", actuator, lowpass, mode, f"T_a {actuator}, low-pass {lowpass}, {mode}")


#: Fewer settled seconds than this cannot give a meaningful DLC, s.
MIN_SCORED_S = 0.25

#: The shortest scenario a study scores (``rigsim paper --duration-s``, a sweep's cases), s: the
#: correction's zero-phase start-up and end transients alone take ~4 s of the record.
MIN_DURATION_S = 10.0


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
        ``nrmse_corrected``, ``nrmse_rig`` (1, against the band-limited road force), and the damage
        figures of the road, measured rig and corrected force on the same samples:
        ``stress_factor_<road|rig|corrected>`` (1, n = 4) and ``del_<road|rig|corrected>_N`` (N, m = 5).
    scored_s : float, s
    cycles : Mapping[str, list] or None
        The rainflow cycles behind the DELs, counted once: for ``road``, ``rig`` and ``corrected``
        on the settled samples, per wheel ``(ranges_N, means_N, counts)``
        (:func:`rigsim.correction.metrics.damage.rainflow_cycles`); the report's histograms read them
        where the pair is scored. None in a copy sent to another process (pickled): they are
        left out, as large as the forces and read nowhere else.
    """

    method: Method
    corrected_N: np.ndarray
    road_band_N: np.ndarray
    rig_band_N: np.ndarray
    settled: np.ndarray
    actuators: tuple
    figures: Mapping
    scored_s: float
    cycles: Mapping | None

    def __getstate__(self) -> dict:
        """Pickled without :attr:`cycles` (None in the copy)."""
        return {**self.__dict__, "cycles": None}


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


def shortest_scorable_s(rate_hz: float, method: Method) -> float:
    """A record shorter than this cannot be scored by ``method`` whatever its T_a, s: the band
    limit's own transients (:func:`rigsim.correction.output.filters.reference_filter` at
    :data:`SETTLING_TOLERANCE`, start and end) plus :data:`MIN_SCORED_S`. A necessary condition,
    checked before any run (the correction's transients, known once T_a is, come on top)."""
    from rigsim.correction.output.filters import reference_filter

    head, tail = reference_filter(rate_hz, method.lowpass,
                                  settling_tolerance=SETTLING_TOLERANCE).transient_samples(method.mode)
    return (head + tail) / float(rate_hz) + MIN_SCORED_S


def check_noise(noise_N: float) -> None:
    """Refuse a load-cell noise (N rms) that is negative or not finite (ScenarioError)."""
    if not (np.isfinite(noise_N) and noise_N >= 0):
        raise ScenarioError(f"noise_N must be >= 0 N, got {noise_N!r}")


def measured_force(rig, noise_N: float, seed: int, chain: LabChain | None = None) -> np.ndarray:
    """The rig run's tire forces as a load cell measures them: plus white noise of ``noise_N``
    (N rms, >= 0: ScenarioError otherwise) from ``numpy.random.default_rng((seed, 8))``, through
    the lab's measurement ``chain`` (:func:`rigsim.scenarios.core.lab.measure`; default: nothing more)."""
    check_noise(noise_N)
    return measure(rig, chain or LabChain(), noise_N, seed).force_N


#: The damage figures every score carries (:mod:`rigsim.correction.metrics.damage`): the dynamic load stress
#: factor E[(F/F_static)^4] (pavements: the fourth-power law) and the damage-equivalent load for
#: a Woehler exponent of 5 at one equivalent cycle per second (components), of the road, the
#: measured rig and the corrected force on the same settled samples.
DAMAGE_EXPONENT_STRESS, DAMAGE_EXPONENT_DEL = 4, 5


def _damage(road_N: np.ndarray, rig_N: np.ndarray, corrected_N: np.ndarray, fs: float) -> tuple[dict, dict]:
    """The damage figures of the three (n, k) forces, and the rainflow cycles behind them (counted once)."""
    out, cycles = {}, {}
    for name, f in (("road", road_N), ("rig", rig_N), ("corrected", corrected_N)):
        cycles[name] = rainflow_cycles(f)
        out[f"stress_factor_{name}"] = np.atleast_1d(stress_factor(f, n=DAMAGE_EXPONENT_STRESS))
        out[f"del_{name}_N"] = np.atleast_1d(damage_equivalent_load(f, DAMAGE_EXPONENT_DEL, duration_s=f.shape[0] / fs,
                                                                    cycles=cycles[name]))
    return out, cycles


def _actuators(method: Method, rig_model, force_N: np.ndarray, identified) -> list:
    if method.actuator == "identified":
        if identified is None:
            raise ValueError(f"the {method.name} method corrects with identified T_a: pass identified= "
                             "(rigsim.scenarios.studies.identify.compute.identify_rig(...).actuators())")
        return [tuple(np.asarray(x, float) for x in ta) for ta in identified]
    out = []
    for i in range(force_N.shape[1]):
        load = float(np.mean(force_N[:, i])) + rig_model.pan_mass_kg * GRAVITY_M_S2  # static actuator load
        kt = float(rig_model.tire_stiffness_N_per_m[i])
        out.append(eq4_coefficients_from(**eq4_parameters(rig_model.params, kt, load, mass_kg=rig_model.pan_mass_kg)))
    return out


def score_pair(road, rig, rig_model, *, methods=METHODS, identified=None, noise_N: float = NOISE_N,
               seed: int = 0, settling_tolerance: float = SETTLING_TOLERANCE, lab: LabChain | None = None) -> PairScore:
    """Correct ``rig``'s wheel forces by each method and compare them with ``road``'s.

    Parameters
    ----------
    road, rig : rigsim.scenarios.core.results.RunResult
        Road-mode and rig-mode runs of the same scenario (same drive, same time axis).
    rig_model : rigsim.scenarios.core.rig.Rig
        The rig of the scenario (actuator parameters, pan mass, tire stiffness for eq. 4).
    methods : sequence of Method
    identified : sequence of 4 (num, den), optional
        T_a per corner for the methods whose ``actuator`` is "identified" (:func:`identify_rig`).
    noise_N : float, N
        rms of the white measurement noise added to the rig force (0 turns it off).
    seed : int
        Seed of the noise.
    settling_tolerance : float, 1
        Samples inside the filters' transients at this tolerance are not scored.
    lab : rigsim.scenarios.core.lab.LabChain, optional
        How the lab measures the rig force (:func:`measured_force`); default: the scenario's of
        ``rig_model`` (``[lab]``).

    Raises
    ------
    ScenarioError
        A record too short to score beyond the correction's transients (one sentence).
    ValueError
        The correction filter cannot be designed for an actuator (one sentence).
    """
    if road.t_s.shape != rig.t_s.shape or not np.array_equal(road.t_s, rig.t_s):
        raise ValueError("road and rig runs must share their time axis (the same scenario)")
    check_noise(noise_N)
    fs = road.rate_hz
    road_f = np.asarray(road.signals["tire_force_N"], dtype=float)
    if lab is None and hasattr(rig_model, "scenario"):
        lab = rig_model.scenario.lab
    rig_f = measured_force(rig, noise_N, seed, lab)
    n = road_f.shape[0]
    scores = {}
    for m in methods:
        tas = _actuators(m, rig_model, rig_f, identified)
        cf = correct_forces(rig_f, tas, fs, lowpass=m.lowpass, mode=m.mode, settling_tolerance=settling_tolerance)
        out, settled = cf.corrected_N, cf.settled
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
        damage, cycles = _damage(road_f[s], rig_f[s], out[s], fs)
        figures.update(damage)
        actuators = tuple((np.asarray(num, float), np.asarray(den, float)) for num, den in tas)
        scores[m.name] = MethodScore(method=m, corrected_N=out, road_band_N=road_b, rig_band_N=rig_b, settled=settled,
                                     actuators=actuators, figures=figures, scored_s=scored_s, cycles=cycles)
    return PairScore(t_s=road.t_s, road_N=road_f, rig_N=rig_f, noise_N=float(noise_N), dlc_road=dlc(road_f),
                     dlc_rig=dlc(rig_f), methods=scores, corners=tuple(road.corners))


def best_linear(actuators, fs_hz: float):
    """The :data:`BEST` method's linear correction with T_a ``actuators`` (one per wheel) at ``fs_hz``
    (Hz), as the model correction's ``linear`` (L): forces (N, (n, 4)) -> (corrected (N), settled
    (bool, (n,))). A T_a the correction refuses raises its
    :class:`~rigsim.correction.output.pipeline.CorrectionError`."""
    def correct(forces):
        res = correct_forces(forces, actuators, fs_hz, lowpass=BEST.lowpass, mode=BEST.mode)
        return res.corrected_N, res.settled

    return correct
