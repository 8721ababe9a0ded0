"""How a lab measures a rig test: the channels between the simulated rig and the correction.

A simulated rig test knows each tire's force and each pan's position exactly. A lab does not: its
load cell sits under the wheelpan and so also weighs the pan's inertia (which the lab subtracts
with a mass estimate times an accelerometer's reading), its LVDT has noise, each channel has its
own anti-alias filter and its own delay (a multiplexed converter, different conditioners), and the
load cell's noise is not white (drift and low-frequency noise of the bridge amplifier). A
correction proven only on exact channels proves little; :class:`LabChain` says what a lab's
measurement does to them and :func:`measure` applies it to a rig run.

All off (``LabChain()``): the load cell measures the tire force itself plus white noise, the LVDT
the pan's position exactly: what :func:`rigsim.scenarios.studies.scoring.measured_force` has always given,
to the bit. :data:`TYPICAL_LAB` is a servo-hydraulic lab's chain (estimates; sources beside each
value).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from rigsim.correction.io.acquisition import MIN_CORNER_HZ, ChannelFilter, undo_timing

__all__ = ["LabChain", "LabMeasurement", "TYPICAL_LAB", "LAB_BOUNDS", "measure", "measure_lvdt", "aligned",
           "pan_acceleration"]

#: Bounds of the :class:`LabChain` fields, ``{field: (low, high, unit, why)}``, inclusive.
LAB_BOUNDS: dict[str, tuple[float, float, str, str]] = {
    "cell_mass_kg": (0.0, 2000.0, "kg", "the pan plate and fixtures above a load cell weigh tens to hundreds of kg"),
    "compensation_kg": (0.0, 2000.0, "kg", "the lab's estimate of the mass above the load cell"),
    "accelerometer_noise_m_s2": (0.0, 10.0, "m/s^2", "a pan accelerometer's rms noise is below 0.1 m/s^2"),
    "lvdt_noise_m": (0.0, 1e-3, "m", "an LVDT's rms noise is tens of micrometres; 1 mm is a broken channel"),
    "force_filter_hz": (MIN_CORNER_HZ, 1e4, "Hz", "an anti-alias filter sits between the band of interest and "
                        "half the sampling rate"),
    "lvdt_filter_hz": (MIN_CORNER_HZ, 1e4, "Hz", "as force_filter_hz"),
    "filter_order": (1, 8, "1", "anti-alias filters are Butterworth or Bessel of order 2 to 8"),
    "force_delay_s": (0.0, 0.01, "s", "a channel's skew (multiplexing, conditioning) is below 1 ms; 10 ms is a "
                      "misconfigured channel"),
    "lvdt_delay_s": (0.0, 0.01, "s", "as force_delay_s"),
    "drift_noise_N": (0.0, 5000.0, "N", "a bridge amplifier's low-frequency noise and drift is tens to hundreds of N "
                      "on a 150 kN cell"),
    "drift_corner_hz": (0.01, 100.0, "Hz", "the corner of the load cell's coloured noise"),
}


@dataclass(frozen=True)
class LabChain:
    """What a lab's measurement does to a rig test's channels (all SI; every field off by default).

    Parameters
    ----------
    cell_mass_kg : float, kg
        Mass between the tire and the load cell (the pan plate and its fixtures): the cell reads
        F_tire + m (g + a_pan), tared with the pan empty, so m a_pan is added to the force.
    compensation_kg : float, kg, optional
        The lab's mass compensation: this mass times the accelerometer's reading is subtracted.
        ``None``: no compensation (the pan's inertia stays in the force).
    accelerometer_noise_m_s2 : float, m/s^2
        White rms noise of the pan accelerometer the compensation reads.
    lvdt_noise_m : float, m
        White rms noise of the LVDT (the pan position the correction reads).
    force_filter_hz, lvdt_filter_hz : float, Hz, optional
        Each channel's anti-alias filter: a causal Butterworth of ``filter_order`` with its -3 dB
        corner here (``None``: none).
    filter_order : int
        Order of the anti-alias filters.
    force_delay_s, lvdt_delay_s : float, s
        Each channel's delay against the drive (linear interpolation between samples).
    drift_noise_N : float, N
        Rms of the load cell's coloured noise: white noise through a first-order low-pass at
        ``drift_corner_hz``, on top of the white noise the caller gives.
    drift_corner_hz : float, Hz
        Corner of that low-pass.
    """

    cell_mass_kg: float = 0.0
    compensation_kg: float | None = None
    accelerometer_noise_m_s2: float = 0.0
    lvdt_noise_m: float = 0.0
    force_filter_hz: float | None = None
    lvdt_filter_hz: float | None = None
    filter_order: int = 4
    force_delay_s: float = 0.0
    lvdt_delay_s: float = 0.0
    drift_noise_N: float = 0.0
    drift_corner_hz: float = 1.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None and f.name in ("compensation_kg", "force_filter_hz", "lvdt_filter_hz"):
                continue
            lo, hi, unit, why = LAB_BOUNDS[f.name]
            integer = f.name == "filter_order"
            if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
                    or (integer and int(value) != value)):
                kind = "an integer" if integer else "a finite number"
                raise ValueError(f"lab.{f.name} must be {kind}, got {value!r}")
            if not lo <= value <= hi:
                raise ValueError(f"lab.{f.name} = {value:g} {unit} is outside {lo:g} to {hi:g} {unit}: {why}")

    @property
    def ideal(self) -> bool:
        """True when the chain changes nothing but the white noise the caller adds."""
        return self == LabChain()

    @property
    def force_channel(self) -> ChannelFilter:
        """The load cells' anti-alias filter (digital, at the record's rate) and delay."""
        return ChannelFilter(self.force_filter_hz, int(self.filter_order), domain="digital", delay_s=self.force_delay_s)

    @property
    def lvdt_channel(self) -> ChannelFilter:
        """The LVDTs' anti-alias filter (digital, at the record's rate) and delay."""
        return ChannelFilter(self.lvdt_filter_hz, int(self.filter_order), domain="digital", delay_s=self.lvdt_delay_s)

    def check_rate(self, fs_hz: float) -> None:
        """Refuse an anti-alias corner at or above the Nyquist frequency of a record at ``fs_hz`` (Hz)."""
        for name in ("force_filter_hz", "lvdt_filter_hz"):
            corner = getattr(self, name)
            if corner is not None and corner >= 0.5 * fs_hz:
                raise ValueError(f"lab.{name} = {corner:g} Hz must lie below half the record's rate "
                                 f"({0.5 * fs_hz:g} Hz): lower it or raise output_rate_hz")


#: A servo-hydraulic lab's measurement (estimates): 250 kg of pan plate above the load cell, the lab
#: compensating 3 % too much mass; a 0.02 m/s^2 accelerometer; 20 micrometres of LVDT noise (about
#: 0.03 % of a 7.6 cm half-stroke); 4th-order anti-alias filters for 1 kHz sampling, 200 Hz on the
#: load cell's bridge amplifier and 150 Hz on the LVDT's demodulator (their group delays differ by
#: 0.7 ms); the force sampled 0.2 ms after the LVDT (a multiplexed converter); 50 N of load-cell
#: drift below 1 Hz.
TYPICAL_LAB = LabChain(cell_mass_kg=250.0, compensation_kg=257.5, accelerometer_noise_m_s2=0.02,
                       lvdt_noise_m=20e-6, force_filter_hz=200.0, lvdt_filter_hz=150.0, filter_order=4,
                       force_delay_s=0.0002, lvdt_delay_s=0.0, drift_noise_N=50.0, drift_corner_hz=1.0)


@dataclass(frozen=True)
class LabMeasurement:
    """A rig test as the lab's channels give it.

    Attributes
    ----------
    force_N : numpy.ndarray, (n, 4), N
        The load cells' wheel forces.
    pan_m : numpy.ndarray, (n, 4), m, or None
        The LVDTs' pan positions (None for a run without them).
    """

    force_N: np.ndarray
    pan_m: np.ndarray


def pan_acceleration(pan_m: np.ndarray, fs_hz: float) -> np.ndarray:
    """The pans' acceleration (m/s^2) from their sampled positions (m) at ``fs_hz`` (Hz): central
    second differences, the ends repeated."""
    x = np.asarray(pan_m, dtype=float)
    a = np.empty_like(x)
    a[1:-1] = (x[2:] - 2.0 * x[1:-1] + x[:-2]) * fs_hz**2
    a[0], a[-1] = a[1], a[-2]
    return a


def measure(run, chain: LabChain, noise_N: float, seed: int) -> LabMeasurement:
    """The rig run ``run`` as the lab's channels give it.

    Parameters
    ----------
    run : rigsim.scenarios.core.results.RunResult
        A rig-mode run (signals ``tire_force_N`` and ``pan_m``, rate ``rate_hz``).
    chain : LabChain
    noise_N : float, N
        White rms noise of each load cell, >= 0, from ``numpy.random.default_rng((seed, 8))``.
    seed : int
        The scenario's seed; each noise has its own stream ``(seed, k)``.

    Returns
    -------
    LabMeasurement
        With ``LabChain()`` the force is the tire force plus the white noise and the LVDT exact.
    """
    clean = np.asarray(run.signals["tire_force_N"], dtype=float)
    pan = np.asarray(run.signals["pan_m"], dtype=float) if "pan_m" in run.signals else None
    force = clean.copy() if noise_N == 0 else clean + noise_N * np.random.default_rng((int(seed), 8)).standard_normal(
        clean.shape)
    if chain.ideal:
        return LabMeasurement(force_N=force, pan_m=pan)
    fs = float(run.rate_hz)
    chain.check_rate(fs)
    if pan is None and (chain.cell_mass_kg or chain.compensation_kg is not None):
        raise ValueError("the lab chain weighs the pan's inertia: the run needs its pan_m signal (a rig-mode run)")
    if chain.cell_mass_kg or chain.compensation_kg is not None:
        acc = pan_acceleration(pan, fs)
        force = force + chain.cell_mass_kg * acc
        if chain.compensation_kg is not None:
            reading = acc + chain.accelerometer_noise_m_s2 * np.random.default_rng((int(seed), 9)).standard_normal(
                acc.shape)
            force = force - chain.compensation_kg * reading
    if chain.drift_noise_N:
        white = np.random.default_rng((int(seed), 10)).standard_normal(clean.shape)
        pole = math.exp(-2.0 * math.pi * chain.drift_corner_hz / fs)
        from scipy import signal

        drift = signal.lfilter([1.0 - pole], [1.0, -pole], white, axis=0)
        drift *= chain.drift_noise_N / math.sqrt((1.0 - pole) / (1.0 + pole))  # the first-order filter's rms gain
        force = force + drift
    force = chain.force_channel.apply(force, fs)
    return LabMeasurement(force_N=force, pan_m=None if pan is None else measure_lvdt(pan, fs, chain, seed))


def measure_lvdt(pan_m, fs_hz: float, chain: LabChain, seed: int) -> np.ndarray:
    """The pans' positions (m, (n, k)) at ``fs_hz`` (Hz) as the lab's LVDT channels give them: plus
    ``chain.lvdt_noise_m`` of white noise from ``numpy.random.default_rng((seed, 11))``, through the
    LVDT's anti-alias filter, delayed by its skew."""
    pan = np.asarray(pan_m, dtype=float)
    if chain.ideal:
        return pan
    chain.check_rate(fs_hz)
    if chain.lvdt_noise_m:
        pan = pan + chain.lvdt_noise_m * np.random.default_rng((int(seed), 11)).standard_normal(pan.shape)
    return chain.lvdt_channel.apply(pan, fs_hz)


def aligned(measurement: LabMeasurement, fs_hz: float, chain: LabChain) -> LabMeasurement:
    """``measurement`` (at ``fs_hz``, Hz) with the chain's anti-alias filters' phase and delays taken
    out of each channel (:func:`rigsim.correction.io.acquisition.undo_timing`): what a lab that knows its
    conditioners does before correcting (``rigsim correct --force-filter ... --lvdt-filter ...``)."""
    pan = measurement.pan_m
    return LabMeasurement(force_N=undo_timing(measurement.force_N, fs_hz, chain.force_channel),
                          pan_m=None if pan is None else undo_timing(pan, fs_hz, chain.lvdt_channel))
