"""Characterize the rig before a test, as a lab does: T_a per corner from independent random drives.

With the truck on the pans, the four actuators are driven by independent band-limited random
drives at the test drive's rms in the band the correction uses (:func:`matched_drive`). The multi-input H1 estimate separates each post's own path from what the other posts
do (the test drive cannot: front and rear are the same profile delayed, coherence ~0.997), and
each corner's diagonal path is fitted by :func:`rigsim.correction.identification.actuator_fit.fit_frequency_response`
(the one fitting policy of the project: stable, minimum phase, T_a(0) = 1, orders by held-out
error). ``rigsim identify`` writes the result as an actuators file that ``rigsim correct`` reads;
the studies (paper, sweep, iterate) correct with it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rigsim.correction.identification.actuator_fit import fit_frequency_response
from rigsim.correction.identification.identify import h1_estimate
from rigsim.correction.output.lowpass import BAND_HZ
from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.drive import IDENT_MIN_S, IDENT_SEED, IDENT_SKIP_S, Drive, identification_drive
from rigsim.correction.io.acquisition import undo_timing
from rigsim.scenarios.core.lab import LabChain, measure_lvdt
from rigsim.scenarios.core.rig import Rig

__all__ = ["MATCH_BAND_HZ", "FIT_BAND_HZ", "RigIdentification", "band_rms",
           "matched_drive", "identify_rig"]

#: The band in which the identification drive's rms is matched to the test drive's, Hz: the
#: correction's (its regularized low-pass is at 30 Hz; below 0.1 Hz the high-passed road has nothing).
MATCH_BAND_HZ = (0.1, BAND_HZ)
#: The band the T_a fit covers, Hz (beyond the correction's 30 Hz, up to the oil-column region).
FIT_BAND_HZ = (0.1, 60.0)
#: Welch segment of the H1 estimate, s (0.25 Hz resolution).
SEGMENT_S = 4.0


def band_rms(z_m, dt_s: float, band_hz: tuple[float, float]) -> np.ndarray:
    """rms (m) of each column of ``z_m`` (N, k) in ``band_hz`` (Hz), from its FFT (Parseval)."""
    z = np.asarray(z_m, dtype=float)
    z = z - z.mean(axis=0)
    n = z.shape[0]
    f = np.fft.rfftfreq(n, dt_s)
    spec = np.fft.rfft(z, axis=0)
    w = np.where((f >= band_hz[0]) & (f <= band_hz[1]), 2.0, 0.0)
    w[0] = 0.0
    if n % 2 == 0:
        w[-1] = np.where(w[-1] > 0, 1.0, 0.0)
    return np.sqrt(np.sum(w[:, None] * np.abs(spec) ** 2, axis=0)) / n


def matched_drive(test_drive: Drive, duration_s: float, *, seed: int = IDENT_SEED,
                  band_hz: tuple[float, float] = MATCH_BAND_HZ) -> tuple[Drive, float]:
    """The identification drive whose rms in ``band_hz`` equals the test drive's mean rms there.

    Four independent road-like random drives (:func:`rigsim.scenarios.core.drive.identification_drive`:
    displacement PSD flat to 1 Hz, 1/f^2 above, 0.05-60 Hz, the drive ``rigsim validate``
    identifies with), scaled so that each one's rms in ``band_hz`` equals the test drive's mean
    rms over its four posts there: a servo-hydraulic actuator is nonlinear (its valve's flow
    depends on the direction and the square root of the pressure drop), so the linear model is
    identified at the amplitude of the test.

    Parameters
    ----------
    test_drive : Drive
        The test's drive (only its analysed record, t >= 0, is measured).
    duration_s : float, s
    seed : int
    band_hz : (float, float), Hz

    Returns
    -------
    (Drive, float)
        The drive (from rest) and the matched rms per post in ``band_hz``, m.
    """
    dt = test_drive.dt_s
    target = float(np.mean(band_rms(test_drive.z_m[test_drive.t_s >= 0], dt, band_hz)))
    drive = identification_drive(duration_s, dt, seed)
    skip = int(round(IDENT_SKIP_S / dt))
    gain = target / band_rms(drive.z_m[skip:], dt, band_hz)
    return drive.scaled(gain), target


@dataclass(frozen=True)
class RigIdentification:
    """T_a of each corner of a rig, identified from independent random drives.

    Attributes
    ----------
    scenario_name : str
    fits : Mapping[str, ActuatorFit]
        Per corner (:data:`rigsim.mjcf.names.CORNERS`).
    drive_rms_m : float, m
        rms of each identification drive in :data:`MATCH_BAND_HZ` (the test drive's there).
    record_s : float, s
        Analysed record (after :data:`~rigsim.scenarios.core.drive.IDENT_SKIP_S`).
    seed : int
    events : Mapping
        Hydraulic events during the identification run (Rig format).
    """

    scenario_name: str
    fits: Mapping
    drive_rms_m: float
    record_s: float
    seed: int
    events: Mapping

    def actuators(self) -> tuple:
        """T_a = (num, den) per corner, in :data:`rigsim.mjcf.names.CORNERS` order."""
        return tuple(self.fits[c].as_tf() for c in CORNERS)

    def meta(self) -> dict:
        """The ``[meta]`` table of the actuators file: where these T_a come from."""
        return {"source": f"rigsim identify, simulated rig of {self.scenario_name}",
                "drive": "independent band-limited random drives per post",
                "drive_rms_m": self.drive_rms_m, "match_band_hz": list(MATCH_BAND_HZ),
                "record_s": self.record_s, "seed": self.seed}

    def to_dict(self) -> dict:
        return {"scenario": self.scenario_name, "drive_rms_m": self.drive_rms_m, "record_s": self.record_s,
                "match_band_hz": list(MATCH_BAND_HZ), "fit_band_hz": list(FIT_BAND_HZ), "seed": self.seed,
                "events": dict(self.events), "corners": {c: f.to_dict() for c, f in self.fits.items()}}


def identify_rig(scenario, *, test_drive: Drive | None = None, duration_s: float | None = None,
                 seed: int = IDENT_SEED, rig: Rig | None = None, lab: LabChain | None = None,
                 align: "bool | LabChain" = False) -> RigIdentification:
    """Run the identification on the simulated rig of ``scenario`` and fit T_a per corner.

    Parameters
    ----------
    scenario : Scenario
    test_drive : Drive, optional
        The drive whose band rms the identification matches (default: the scenario's road).
    duration_s : float, s, optional
        Analysed identification record (default: the scenario's duration, at least
        :data:`~rigsim.scenarios.core.drive.IDENT_MIN_S`).
    seed : int
    rig : Rig, optional
        The scenario's hydraulic rig, if already built.
    lab : rigsim.scenarios.core.lab.LabChain, optional
        The lab's measurement of the LVDTs (:func:`rigsim.scenarios.core.lab.measure_lvdt`, noise from
        ``seed``); default: the scenario's (``[lab]``).
    align : bool or rigsim.scenarios.core.lab.LabChain
        Take the LVDT channel's known filter phase and delay out before the fit
        (:func:`rigsim.scenarios.core.lab.aligned`), as ``rigsim identify --from-file --lvdt-filter`` does:
        True, the measuring chain's own; a LabChain, its settings (a lab's nominal ones).

    Raises
    ------
    rigsim.correction.identification.actuator_fit.ActuatorFitError
        If the record cannot support a fit (one sentence naming the band).
    SimulationError
        A MuJoCo warning during the run.
    """
    rig = Rig(scenario) if rig is None else rig
    test = rig.road_drive() if test_drive is None else test_drive
    record_s = max(float(scenario.duration_s if duration_s is None else duration_s), IDENT_MIN_S)
    drive, rms = matched_drive(test, record_s + IDENT_SKIP_S, seed=seed)
    rate = float(scenario.output_rate_hz)
    rec = rig.run(drive, rate_hz=rate)
    k0 = int(round(IDENT_SKIP_S * rate))
    chain = scenario.lab if lab is None else lab
    pan = measure_lvdt(rec.pan_m, rate, chain, seed)
    if align:
        pan = undo_timing(pan, rate, (align if isinstance(align, LabChain) else chain).lvdt_channel)
    u, y = rec.x_ref_m[k0:], pan[k0:]
    nperseg = int(min(round(SEGMENT_S * rate), u.shape[0] // 8))
    f, h, coh = h1_estimate(u, y, rate, nperseg)
    keep = f > 0
    fits = {c: fit_frequency_response(f[keep], h[keep, i, i], coh[keep, i], band_hz=FIT_BAND_HZ)
            for i, c in enumerate(CORNERS)}
    return RigIdentification(scenario_name=scenario.name, fits=fits, drive_rms_m=rms,
                             record_s=float(u.shape[0] / rate), seed=int(seed), events=rec.events)
