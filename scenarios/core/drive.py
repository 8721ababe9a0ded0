"""Drives: the four wheel-pan drive signals x_ref, from a road, for identification, or a step.

* :func:`sample_wheels` samples a two-track profile in time (left track -> fl, rl; right
  track -> fr, rr; the rear drive is the front one delayed by wheelbase / speed);
* :func:`road_drive` is a scenario's whole pipeline: profile (synthesised or read),
  tire enveloping, high-pass, sampling, a cosine fade-in over the lead-in, stroke check;
* :func:`identification_drive` gives four independent road-like random drives (for
  identifying the rig's transfer functions), :func:`step_drive` a step on every corner.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mjcf.names import CORNERS
from scenarios.core import roads
from scenarios.core.profiles import (Profile, ProfileError, check_positive, envelope, highpass, read_profile_csv,
                                     readonly_copy)

__all__ = ["Drive", "START_MARGIN_M", "PROFILE_DX_M", "sample_wheels", "road_drive", "identification_drive",
           "step_drive", "IDENT_RMS_M", "IDENT_CORNER_HZ", "IDENT_BAND_HZ", "IDENT_SEED", "IDENT_FADE_S"]

START_MARGIN_M = 1.0  # default distance, m, of the rear axle past the profile start at t = 0
PROFILE_DX_M = 0.02  # m; resolves the ISO band up to 10 cycle/m with 2.5 points per shortest wave

#: Identification drive: RMS displacement (the high-roughness 72 km/h drive has 9.5 mm RMS),
#: corner frequency above which the displacement PSD falls as 1/f^2 (a road's white
#: velocity spectrum), band edges, seed, fade-in.
IDENT_RMS_M = 9.5e-3
IDENT_CORNER_HZ = 1.0
IDENT_BAND_HZ = (0.05, 60.0)
IDENT_SEED = 20240604
IDENT_FADE_S = 1.0


@dataclass(frozen=True, eq=False)
class Drive:
    """The four wheel-pan drive signals x_ref on the simulation's time steps.

    Parameters
    ----------
    t_s : array_like, s
        Sample times, shape (N,).
    z_m : array_like, m
        Elevation per corner, shape (N, 4), columns in ``corners`` order.
    v_mps : array_like, m/s
        Vertical velocity per corner, shape (N, 4).
    corners : tuple of str
        Column names, :data:`mjcf.names.CORNERS`.

    The drive of a scenario starts with a lead-in (t < 0, faded in from rest); t = 0 starts
    the analysed record. Arrays are read-only copies.
    """

    t_s: np.ndarray
    z_m: np.ndarray
    v_mps: np.ndarray
    corners: tuple = field(default=CORNERS)

    def __post_init__(self) -> None:
        for name in ("t_s", "z_m", "v_mps"):
            object.__setattr__(self, name, readonly_copy(getattr(self, name)))
        n = self.t_s.shape[0] if self.t_s.ndim == 1 else -1
        if n < 1:
            raise ValueError(f"drive.t_s must be 1-D and non-empty, got shape {self.t_s.shape}.")
        for name in ("z_m", "v_mps"):
            if getattr(self, name).shape != (n, len(self.corners)):
                raise ValueError(f"drive.{name} has shape {getattr(self, name).shape}, "
                                 f"expected {(n, len(self.corners))}.")
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError(f"drive.{name} contains NaN or inf; check the source profile.")

    def check_stroke(self, half_stroke_m: float) -> None:
        """Raise if any drive leaves the actuator stroke.

        Parameters
        ----------
        half_stroke_m : float, m
            Allowed |z| about mid-stroke (DYNTRAC: 0.076 m).

        Raises
        ------
        ValueError
            Naming the corner, the time and the excess of the worst sample.
        """
        check_positive("half_stroke_m", half_stroke_m)
        mag = np.abs(self.z_m)
        i, c = np.unravel_index(int(np.argmax(mag)), mag.shape)
        if mag[i, c] > half_stroke_m:
            raise ValueError(
                f"drive {self.corners[c]} reaches {1e3 * self.z_m[i, c]:.1f} mm at t = "
                f"{self.t_s[i]:.3f} s, {1e3 * (mag[i, c] - half_stroke_m):.1f} mm beyond the "
                f"+-{1e3 * half_stroke_m:.1f} mm stroke; raise the high-pass cut-on frequency "
                "(shorter cut-on wavelength) or lower the roughness.")


    @classmethod
    def from_positions(cls, t_s, z_m) -> "Drive":
        """A drive from positions alone; the velocity is their centred difference (m/s)."""
        t = np.asarray(t_s, dtype=float)
        z = np.asarray(z_m, dtype=float)
        return cls(t, z, np.gradient(z, t, axis=0) if t.size > 1 else np.zeros_like(z))

    @property
    def dt_s(self) -> float:
        """float, s: the step of the time axis."""
        return float(self.t_s[1] - self.t_s[0]) if self.t_s.size > 1 else float("nan")



def sample_wheels(profile: Profile, speed_mps: float, wheelbase_m: float, fs_hz: float,
                  duration_s: float, start_m: float | None = None) -> Drive:
    """Sample the profile in time as the four wheel-pan drives.

    t = k / fs, k = 0..N-1, N = round(duration fs) + 1. The front axle is at
    s(t) = start + v t, the rear axle at s(t) - wheelbase, so the rear drive is
    the front drive delayed by wheelbase / v. Elevation: linear interpolation of
    the profile. Velocity: v times the centred finite-difference slope dz/dx of
    the profile (``numpy.gradient``), linearly interpolated; this is continuous,
    unlike the piecewise-constant derivative of the linear interpolant.

    Aliasing is an error, not a warning: the time sampling must resolve the
    profile's band, v n_max <= fs / 2, with n_max = ``profile.band_max_cyc_per_m``
    (spec band for generated profiles, else the spatial Nyquist 1 / (2 dx)).

    Parameters
    ----------
    profile : Profile
        Road profile (m).
    speed_mps : float, m/s
        Vehicle speed, > 0.
    wheelbase_m : float, m
        Front-to-rear axle distance, > 0.
    fs_hz : float, Hz
        Drive sampling rate.
    duration_s : float, s
        Drive duration.
    start_m : float, m, optional
        Front-axle distance at t = 0; default x[0] + wheelbase + ``START_MARGIN_M``.

    """
    for name, val in (("speed_mps", speed_mps), ("wheelbase_m", wheelbase_m),
                      ("fs_hz", fs_hz), ("duration_s", duration_s)):
        check_positive(name, val)
    x = profile.x_m
    nmax = profile.band_max_cyc_per_m
    if speed_mps * nmax > fs_hz / 2 * (1 + 1e-9):
        raise ValueError(f"fs_hz = {fs_hz} Hz aliases the profile band (up to {nmax:.6g} cycle/m "
                         f"= {speed_mps * nmax:.6g} Hz at {speed_mps} m/s); use fs_hz >= "
                         f"{2 * speed_mps * nmax:.6g} Hz or low-pass the profile.")
    if start_m is None:
        start_m = float(x[0]) + wheelbase_m + START_MARGIN_M
    if not np.isfinite(start_m) or start_m - wheelbase_m < x[0]:
        raise ValueError(f"start_m = {start_m} m puts the rear axle before the profile start "
                         f"{x[0]:.6g} m; use start_m >= {x[0] + wheelbase_m:.6g} m.")
    n = int(round(duration_s * fs_hz)) + 1
    t = np.arange(n) / fs_hz
    s_front = start_m + speed_mps * t
    tol = 1e-9 * max(1.0, abs(x[-1]))
    if s_front[-1] > x[-1] + tol:
        raise ValueError(
            f"profile is too short: duration_s = {duration_s} s at {speed_mps} m/s from start_m = "
            f"{start_m:.6g} m needs distance up to {s_front[-1]:.6g} m, profile ends at "
            f"{x[-1]:.6g} m; shorten duration_s or use a longer profile.")
    s_front = np.minimum(s_front, x[-1])
    s_rear = s_front - wheelbase_m
    z = np.empty((n, 4))
    vz = np.empty((n, 4))
    for track, cols in ((profile.left_m, (0, 2)), (profile.right_m, (1, 3))):
        slope = np.gradient(track, profile.dx_m)
        for col, s in zip(cols, (s_front, s_rear)):
            z[:, col] = np.interp(s, x, track)
            vz[:, col] = speed_mps * np.interp(s, x, slope)
    return Drive(t, z, vz)


def _road_profile(scenario, length_m: float) -> Profile:
    from scenarios.core.config import ScenarioError

    rc = scenario.road
    if rc.profile_csv is not None:
        base = scenario.source.parent if scenario.source is not None else None
        path = rc.profile_csv if base is None else base / rc.profile_csv
        try:
            return read_profile_csv(path)
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


def road_drive(scenario, *, dt_s: float, wheelbase_m: float, half_stroke_m: float) -> Drive:
    """A scenario's road -> enveloped, high-passed profile -> the four pan drives, stroke-checked.

    Parameters
    ----------
    scenario : scenarios.core.config.Scenario
    dt_s : float, s
        Simulation time step (the drive has one sample per step).
    wheelbase_m : float, m
        Front-to-rear axle distance of the truck.
    half_stroke_m : float, m
        The actuator's travel from mid-stroke (the stroke check's limit).

    Returns
    -------
    Drive
        From t = -lead_in to duration, faded in from rest by a cosine over the first half of
        the lead-in.

    Raises
    ------
    ScenarioError
        If the profile cannot be made or read, or the drive leaves the stroke (naming the
        corner, the time and the margin).
    """
    from scenarios.core.config import ScenarioError

    v = scenario.speed_mps
    total_s = scenario.lead_in_s + scenario.duration_s
    # Extra length: the rear axle starts a wheelbase behind, plus margins for the
    # high-pass's edge effects at both ends.
    margin = max(2.0 * scenario.road.cuton_wavelength_m, 20.0)
    length = wheelbase_m + START_MARGIN_M + v * total_s + 2 * margin
    try:
        profile = _road_profile(scenario, length)
        profile = envelope(profile, scenario.road.envelope_length_m)
        profile = highpass(profile, scenario.road.cuton_wavelength_m)
        start = float(profile.x_m[0]) + margin + wheelbase_m + START_MARGIN_M
        wd = sample_wheels(profile, v, wheelbase_m, 1.0 / dt_s, total_s, start_m=start)
    except ScenarioError:
        raise
    except ValueError as exc:  # ProfileError included
        raise ScenarioError(f"road: {exc}") from None
    t = wd.t_s - scenario.lead_in_s
    t_fade = 0.5 * scenario.lead_in_s
    tau = np.clip((t + scenario.lead_in_s) / t_fade, 0.0, 1.0)
    w = 0.5 - 0.5 * np.cos(np.pi * tau)
    dw = np.where((tau > 0) & (tau < 1), 0.5 * np.pi / t_fade * np.sin(np.pi * tau), 0.0)
    drive = Drive(t, wd.z_m * w[:, None], wd.v_mps * w[:, None] + wd.z_m * dw[:, None])
    try:
        drive.check_stroke(half_stroke_m)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    return drive


def identification_drive(duration_s: float, dt_s: float, seed: int = IDENT_SEED, *,
                         rms_m: float = IDENT_RMS_M, corner_hz: float = IDENT_CORNER_HZ,
                         band_hz: tuple[float, float] = IDENT_BAND_HZ,
                         fade_s: float = IDENT_FADE_S) -> Drive:
    """Four independent Gaussian random drives with a road-like spectrum, from t = 0.

    The displacement PSD is flat up to ``corner_hz`` and falls as ``1/f^2`` above it (a road's
    white velocity spectrum), band-limited to ``band_hz``; random phases, scaled to ``rms_m``;
    a cosine fade-in over ``fade_s`` starts it from rest.

    Parameters
    ----------
    duration_s : float, s
    dt_s : float, s
        Sample interval (the model's time step).
    seed : int
        ``numpy.random.default_rng`` seed.
    rms_m : float, m
        RMS displacement of each drive (after the fade-in).
    corner_hz : float, Hz
    band_hz : (float, float), Hz
    fade_s : float, s

    Returns
    -------
    Drive
        N = round(duration / dt) + 1 samples; velocity by centred differences.
    """
    n = int(round(duration_s / dt_s)) + 1
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, dt_s)
    amp = np.where(f < corner_hz, 1.0, (corner_hz / np.maximum(f, 1e-12)) ** 2) ** 0.5
    amp[(f < band_hz[0]) | (f > band_hz[1])] = 0.0
    spec = amp[:, None] * np.exp(2j * np.pi * rng.random((f.size, len(CORNERS))))
    z = np.fft.irfft(spec, n=n, axis=0)
    z *= rms_m / z.std(axis=0)
    tau = np.clip(np.arange(n) * dt_s / fade_s, 0.0, 1.0)
    z = z * (0.5 - 0.5 * np.cos(np.pi * tau))[:, None]
    return Drive.from_positions(np.arange(n) * dt_s, z)


def step_drive(duration_s: float, dt_s: float, size_m: float, at_s: float) -> Drive:
    """A step of ``size_m`` (m) at ``at_s`` (s) on every corner, from t = 0 to ``duration_s`` (s).

    The velocity is zero (the step is an instant change of the reference)."""
    n = int(round(duration_s / dt_s)) + 1
    z = np.zeros((n, len(CORNERS)))
    z[int(round(at_s / dt_s)):] = size_m
    return Drive(np.arange(n) * dt_s, z, np.zeros_like(z))
