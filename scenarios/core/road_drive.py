"""A scenario's road as the four wheel-pan drives, made step range by step range.

The pipeline: the profile (synthesised from ISO 8608 or read from a CSV), tire enveloping,
high-pass, then sampled where each axle is at each step's time (left track -> fl, rl; right
track -> fr, rr; the rear drive is the front one delayed by wheelbase / speed) and faded in
from rest over the lead-in.

A road drive is a pure function of the step index, so :class:`RoadDrive` holds only the profile
and makes any range of steps on demand (:meth:`RoadDrive.chunk`): a run steps through it chunk by
chunk and never holds the drive at the step rate (at the 1e-4 s step a whole drive takes 0.7 MB per
simulated second, 2.5 MB/s while it is made). :meth:`RoadDrive.drive` makes the whole signal as a
:class:`~rigsim.scenarios.core.drive.Drive` for the studies that need it at once (identification at the
test's rms, iteration); the values are the same, bit for bit, however the steps are chunked.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core import roads
from rigsim.scenarios.core.drive import Drive, check_stroke
from rigsim.scenarios.core.profiles import Profile, ProfileError, check_positive, envelope, highpass, read_profile_csv

__all__ = ["RoadDrive", "START_MARGIN_M", "PROFILE_DX_M", "sample_wheels", "road_source", "road_drive"]

START_MARGIN_M = 1.0  # default distance, m, of the rear axle past the profile start at t = 0
PROFILE_DX_M = 0.02  # m; resolves the ISO band up to 10 cycle/m with 2.5 points per shortest wave


@dataclass(frozen=True, eq=False)
class RoadDrive:
    """The four pan drives of a profile driven over at constant speed, made on demand.

    Step k is at t_k = k / fs - lead_in (s); the front axle is then at
    s = start + v k / fs (m), the rear at s - wheelbase. Elevation: linear interpolation of each
    track; velocity: v times the centred finite-difference slope dz/dx (``numpy.gradient``, made
    for the points a chunk reads only), linearly interpolated (continuous, unlike the derivative of the linear interpolant). With a
    lead-in, a cosine fade w(t) from rest over its first half: z w and v w + z dw/dt.

    Parameters
    ----------
    profile : Profile
        The (enveloped, high-passed) road profile, m.
    speed_mps : float, m/s
    wheelbase_m : float, m
    start_m : float, m
        Front-axle distance at step 0.
    fs_hz : float, Hz
        Step rate (1 / the model's time step).
    n_steps : int
    lead_in_s : float, s
        Steps before t = 0; 0 for no fade-in.
    corners : tuple of str

    Raises
    ------
    ValueError
        If the sampling aliases the profile's band, the rear axle starts before the profile
        or the profile ends before the last step (each naming the fix).
    """

    profile: Profile
    speed_mps: float
    wheelbase_m: float
    start_m: float
    fs_hz: float
    n_steps: int
    lead_in_s: float = 0.0
    corners: tuple = CORNERS

    def __post_init__(self) -> None:
        for name in ("speed_mps", "wheelbase_m", "fs_hz"):
            check_positive(name, getattr(self, name))
        x, nmax = self.profile.x_m, self.profile.band_max_cyc_per_m
        v, fs = self.speed_mps, self.fs_hz
        if v * nmax > fs / 2 * (1 + 1e-9):
            raise ValueError(f"fs_hz = {fs} Hz aliases the profile band (up to {nmax:.6g} cycle/m "
                             f"= {v * nmax:.6g} Hz at {v:.4g} m/s); use fs_hz >= "
                             f"{2 * v * nmax:.6g} Hz or low-pass the profile.")
        if not np.isfinite(self.start_m) or self.start_m - self.wheelbase_m < x[0]:
            raise ValueError(f"start_m = {self.start_m} m puts the rear axle before the profile start "
                             f"{x[0]:.6g} m; use start_m >= {x[0] + self.wheelbase_m:.6g} m.")
        end = self.start_m + v * ((self.n_steps - 1) / fs)
        if end > x[-1] + 1e-9 * max(1.0, abs(x[-1])):
            raise ValueError(
                f"profile is too short: duration_s = {(self.n_steps - 1) / fs} s at {v} m/s from start_m = "
                f"{self.start_m:.6g} m needs distance up to {end:.6g} m, profile ends at "
                f"{x[-1]:.6g} m; shorten duration_s or use a longer profile.")

    @property
    def dt_s(self) -> float:
        """float, s: the time step."""
        return 1.0 / self.fs_hz

    def times(self, k0: int, k1: int) -> np.ndarray:
        """Times of steps ``k0`` .. ``k1 - 1``, s."""
        return np.arange(k0, k1) / self.fs_hz - self.lead_in_s

    def time_at(self, k: int) -> float:
        """Time of step ``k``, s."""
        return float(self.times(k, k + 1)[0])

    def first_step(self, t_s: float) -> int:
        """The first step at or after ``t_s`` (s); ``n_steps`` if none."""
        k = int(np.clip(np.ceil((t_s + self.lead_in_s) * self.fs_hz), 0, self.n_steps))
        while k > 0 and self.time_at(k - 1) >= t_s:
            k -= 1
        while k < self.n_steps and self.time_at(k) < t_s:
            k += 1
        return k

    def chunk(self, k0: int, k1: int) -> tuple[np.ndarray, np.ndarray]:
        """Elevation (m) and velocity (m/s) of steps ``k0`` .. ``k1 - 1``, each (k1 - k0, 4)."""
        return self._at(np.arange(k0, k1) / self.fs_hz)

    def held(self, k0: int, k1: int) -> np.ndarray:
        """The value (m) each of steps ``k0`` .. ``k1 - 1`` holds in the rig test, (k1 - k0, 4):
        the drive at mid-step, t_k + dt / 2 (see :meth:`rigsim.scenarios.core.drive.Drive.held`)."""
        return self._at((np.arange(k0, k1) + 0.5) / self.fs_hz)[0]

    def _at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Elevation (m) and velocity (m/s) at ``t`` (s from step 0), each (t.size, 4)."""
        x, v = self.profile.x_m, self.speed_mps
        s_front = np.minimum(self.start_m + v * t, x[-1])
        s_rear = s_front - self.wheelbase_m
        z, vz = np.empty((t.size, 4)), np.empty((t.size, 4))
        for col, s in ((0, s_front), (2, s_rear)):
            if s.size == 0:
                continue
            # Only the profile points this chunk reads (s rises with t): interpolating on a slice
            # gives the same values as on the whole profile, and the slopes are made here.
            i0 = max(int(np.searchsorted(x, s[0], side="right")) - 2, 0)
            i1 = min(int(np.searchsorted(x, s[-1], side="left")) + 2, x.size)
            for track, c in ((self.profile.left_m, col), (self.profile.right_m, col + 1)):
                z[:, c] = np.interp(s, x[i0:i1], track[i0:i1])
                vz[:, c] = v * np.interp(s, x[i0:i1], _slope(track, i0, i1, self.profile.dx_m))
        if self.lead_in_s > 0:
            lead, t_fade = self.lead_in_s, 0.5 * self.lead_in_s
            tau = np.clip(((t - lead) + lead) / t_fade, 0.0, 1.0)
            w = 0.5 - 0.5 * np.cos(np.pi * tau)
            dw = np.where((tau > 0) & (tau < 1), 0.5 * np.pi / t_fade * np.sin(np.pi * tau), 0.0)
            z, vz = z * w[:, None], vz * w[:, None] + z * dw[:, None]
        return z, vz

    def drive(self) -> Drive:
        """The whole drive as a :class:`~rigsim.scenarios.core.drive.Drive` (arrays at the step rate)."""
        z, vz = self.chunk(0, self.n_steps)
        return Drive(self.times(0, self.n_steps), z, vz, self.corners, held_m=self.held(0, self.n_steps))

    def check_stroke(self, half_stroke_m: float) -> None:
        """Raise ValueError if a drive leaves +-``half_stroke_m`` (m); see :func:`~rigsim.scenarios.core.drive.check_stroke`."""
        check_stroke(self, half_stroke_m)


def _slope(track: np.ndarray, i0: int, i1: int, dx_m: float) -> np.ndarray:
    """dz/dx (1) of ``track`` at points ``i0`` .. ``i1 - 1``: the centred difference inside, one-sided
    at the profile's ends, bit for bit ``numpy.gradient(track, dx_m)[i0:i1]`` without making
    the whole array."""
    j = np.arange(i0, i1)
    out = np.empty(j.size)
    inner = (j > 0) & (j < track.size - 1)
    out[inner] = (track[j[inner] + 1] - track[j[inner] - 1]) / (2.0 * dx_m)
    if i0 == 0:
        out[0] = (track[1] - track[0]) / dx_m
    if i1 == track.size:
        out[-1] = (track[-1] - track[-2]) / dx_m
    return out


def sample_wheels(profile: Profile, speed_mps: float, wheelbase_m: float, fs_hz: float,
                  duration_s: float, start_m: float | None = None) -> Drive:
    """Sample the profile in time as the four wheel-pan drives (no fade-in), t = k / fs from 0.

    N = round(duration fs) + 1 steps. Aliasing is an error, not a warning: the time sampling
    must resolve the profile's band, v n_max <= fs / 2 (n_max = ``profile.band_max_cyc_per_m``).
    See :class:`RoadDrive` for the sampling.

    Parameters
    ----------
    profile : Profile
    speed_mps : float, m/s
        Vehicle speed, > 0.
    wheelbase_m : float, m
        Front-to-rear axle distance, > 0.
    fs_hz : float, Hz
        Drive sampling rate.
    duration_s : float, s
    start_m : float, m, optional
        Front-axle distance at t = 0; default x[0] + wheelbase + ``START_MARGIN_M``.
    """
    for name, val in (("speed_mps", speed_mps), ("wheelbase_m", wheelbase_m),
                      ("fs_hz", fs_hz), ("duration_s", duration_s)):
        check_positive(name, val)
    if start_m is None:
        start_m = float(profile.x_m[0]) + wheelbase_m + START_MARGIN_M
    n = int(round(duration_s * fs_hz)) + 1
    return RoadDrive(profile, speed_mps, wheelbase_m, start_m, fs_hz, n).drive()


def _road_profile(scenario, length_m: float) -> Profile:
    from rigsim.scenarios.core.config import ScenarioError

    rc = scenario.road
    if rc.profile_csv is not None:
        try:
            return read_profile_csv(scenario.profile_path)
        except ProfileError as exc:
            raise ScenarioError(f"road.profile_csv: {exc}") from None
    band = {"waviness": rc.waviness, "tracks": rc.tracks, "n_min_cyc_per_m": rc.n_min_cyc_per_m,
            "n_max_cyc_per_m": rc.n_max_cyc_per_m}
    if rc.roughness is not None:
        spec = roads.RoadSpec.from_class(rc.roughness, **band)
    else:
        spec = roads.RoadSpec(gd_n0_m3=rc.gd_n0_m3, **band)
    rng = np.random.default_rng(scenario.seed)
    return roads.generate_profile(spec, length_m, PROFILE_DX_M, rng)


def road_source(scenario, *, dt_s: float, wheelbase_m: float, half_stroke_m: float) -> RoadDrive:
    """A scenario's road -> enveloped, high-passed profile -> the four pan drives, stroke-checked.

    Parameters
    ----------
    scenario : rigsim.scenarios.core.config.Scenario
    dt_s : float, s
        Simulation time step (the drive has one sample per step).
    wheelbase_m : float, m
        Front-to-rear axle distance of the truck.
    half_stroke_m : float, m
        The actuator's travel from mid-stroke (the stroke check's limit).

    Returns
    -------
    RoadDrive
        From t = -lead_in to duration, faded in from rest by a cosine over the first half of
        the lead-in.

    Raises
    ------
    ScenarioError
        If the profile cannot be made or read, or the drive leaves the stroke (naming the
        corner, the time and the margin).
    """
    from rigsim.scenarios.core.config import ScenarioError

    v = scenario.speed_mps
    total_s = scenario.lead_in_s + scenario.duration_s
    # Extra length: the rear axle starts a wheelbase behind, plus margins for the
    # high-pass's edge effects at both ends.
    margin = max(2.0 * scenario.road.cuton_wavelength_m, 20.0)
    length = wheelbase_m + START_MARGIN_M + v * total_s + 2 * margin
    try:
        check_positive("duration_s", total_s)
        profile = _road_profile(scenario, length)
        profile = envelope(profile, scenario.road.envelope_length_m)
        profile = highpass(profile, scenario.road.cuton_wavelength_m)
        start = float(profile.x_m[0]) + margin + wheelbase_m + START_MARGIN_M
        fs = 1.0 / dt_s
        _check_band(scenario, profile.band_max_cyc_per_m, fs)
        source = RoadDrive(profile, v, wheelbase_m, start, fs, int(round(total_s * fs)) + 1,
                           lead_in_s=scenario.lead_in_s)
    except ScenarioError:
        raise
    except ValueError as exc:  # ProfileError included
        raise ScenarioError(f"road: {exc}") from None
    try:
        source.check_stroke(half_stroke_m)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    return source


def _check_band(scenario, nmax: float, fs: float) -> None:
    """Refuse, naming the scenario's keys, a speed at which the road's band reaches above half the
    drive's rate (``1 / vehicle.timestep_s``): the sampled drive would alias."""
    from rigsim.scenarios.core.config import ScenarioError

    v = scenario.speed_mps
    if v * nmax <= fs / 2 * (1 + 1e-9):
        return
    measured = scenario.road.profile_csv is not None
    band = f"the measured profile's band (up to {nmax:.4g} cycle/m)" if measured else \
        f"road.n_max_cyc_per_m = {nmax:g} cycle/m"
    narrower = "" if measured else f"lower road.n_max_cyc_per_m to at most {fs / 2 / v:.4g} cycle/m, "
    raise ScenarioError(
        f"speed_kmh = {scenario.speed_kmh:g} km/h carries {band} to {v * nmax:.4g} Hz, above half the drive's "
        f"rate 1 / vehicle.timestep_s = {fs:g} Hz; lower speed_kmh to at most {fs / 2 / nmax * 3.6:.4g} km/h, "
        f"{narrower}or give vehicle.timestep_s at most {1 / (2 * v * nmax):.3g} s")


def road_drive(scenario, *, dt_s: float, wheelbase_m: float, half_stroke_m: float) -> Drive:
    """:func:`road_source`'s drive made whole (a :class:`~rigsim.scenarios.core.drive.Drive`)."""
    return road_source(scenario, dt_s=dt_s, wheelbase_m=wheelbase_m, half_stroke_m=half_stroke_m).drive()
