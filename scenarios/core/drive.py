"""Drives: the four wheel-pan drive signals x_ref, for identification, or a step.

* :class:`Drive` holds a drive at every time step; a run reads any drive through the same few
  methods (``n_steps``, ``dt_s``, ``times``, ``time_at``, ``first_step``, ``chunk``, ``held``),
  which :class:`rigsim.scenarios.core.road_drive.RoadDrive` (a scenario's road, made on demand) also has;
* :func:`identification_drive` gives four independent road-like random drives (for
  identifying the rig's transfer functions), :func:`step_drive` a step on every corner;
* :func:`check_stroke` refuses a drive that leaves the actuator's stroke.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.core.profiles import check_positive, readonly_copy

__all__ = ["Drive", "check_stroke", "identification_drive", "step_drive", "IDENT_RMS_M", "IDENT_CORNER_HZ",
           "IDENT_BAND_HZ", "IDENT_SEED", "IDENT_FADE_S", "IDENT_SKIP_S", "IDENT_MIN_S", "CHUNK_STEPS"]

#: Identification drive: RMS displacement (the high-roughness 72 km/h drive has 9.5 mm RMS),
#: corner frequency above which the displacement PSD falls as 1/f^2 (a road's white
#: velocity spectrum), band edges, seed, fade-in.
IDENT_RMS_M = 9.5e-3
IDENT_CORNER_HZ = 1.0
IDENT_BAND_HZ = (0.05, 60.0)
IDENT_SEED = 20240604
IDENT_FADE_S = 1.0
#: The start of an identification record left out of its analysis, s: the fade-in
#: (:data:`IDENT_FADE_S`) and the rig's loop settling after it.
IDENT_SKIP_S = 3.0
#: Shortest analysed identification record, s (14 half-overlapping Welch segments of 4 s, 0.25 Hz
#: resolution).
IDENT_MIN_S = 30.0


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
        Column names, :data:`rigsim.mjcf.names.CORNERS`.
    held_m : array_like, m, optional
        The value each step holds in the rig test, shape (N, 4): the drive at mid-step,
        t_k + dt / 2 (see :meth:`held`). Given by the drives that know their signal between the
        samples (a step, a band-limited random drive); otherwise cubic Hermite interpolation of
        ``z_m`` and ``v_mps`` at mid-step.

    The drive of a scenario starts with a lead-in (t < 0, faded in from rest); t = 0 starts
    the analysed record. Arrays are read-only copies.
    """

    t_s: np.ndarray
    z_m: np.ndarray
    v_mps: np.ndarray
    corners: tuple = field(default=CORNERS)
    held_m: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("t_s", "z_m", "v_mps") + (("held_m",) if self.held_m is not None else ()):
            object.__setattr__(self, name, readonly_copy(getattr(self, name)))
        n = self.t_s.shape[0] if self.t_s.ndim == 1 else -1
        if n < 1:
            raise ValueError(f"drive.t_s must be 1-D and non-empty, got shape {self.t_s.shape}.")
        for name in ("z_m", "v_mps") + (("held_m",) if self.held_m is not None else ()):
            if getattr(self, name).shape != (n, len(self.corners)):
                raise ValueError(f"drive.{name} has shape {getattr(self, name).shape}, "
                                 f"expected {(n, len(self.corners))}.")
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError(f"drive.{name} contains NaN or inf; check the source profile.")

    def check_stroke(self, half_stroke_m: float) -> None:
        """Raise ValueError if a drive leaves +-``half_stroke_m`` (m); see :func:`check_stroke`."""
        check_stroke(self, half_stroke_m)

    # -- what a run reads of any drive (RoadDrive has the same) --
    @property
    def n_steps(self) -> int:
        """int: the number of time steps."""
        return int(self.t_s.shape[0])

    def times(self, k0: int, k1: int) -> np.ndarray:
        """Times of steps ``k0`` .. ``k1 - 1``, s."""
        return self.t_s[k0:k1]

    def time_at(self, k: int) -> float:
        """Time of step ``k``, s."""
        return float(self.t_s[k])

    def first_step(self, t_s: float) -> int:
        """The first step at or after ``t_s`` (s); ``n_steps`` if none."""
        return int(np.searchsorted(self.t_s, t_s))

    def chunk(self, k0: int, k1: int) -> tuple[np.ndarray, np.ndarray]:
        """Elevation (m) and velocity (m/s) of steps ``k0`` .. ``k1 - 1``, each (k1 - k0, 4)."""
        return self.z_m[k0:k1], self.v_mps[k0:k1]

    def held(self, k0: int, k1: int) -> np.ndarray:
        """The value (m) each of steps ``k0`` .. ``k1 - 1`` holds, (k1 - k0, 4): the drive at
        mid-step, t_k + dt / 2.

        MuJoCo holds ``ctrl`` constant over a step, so a drive sampled at t_k would lag the
        continuous one by dt / 2 (5.4 degrees at 30 Hz at the rig test's 1e-3 s step); the value
        at mid-step removes that lag to second order (``benchmarks/integrator_study.py``).
        ``held_m`` if given, else the cubic Hermite interpolant of (z, v) at mid-step,
        (z_k + z_k+1) / 2 + dt (v_k - v_k+1) / 8; the last step extrapolates z + v dt / 2.
        """
        if self.held_m is not None:
            return self.held_m[k0:k1]
        k1 = min(k1, self.n_steps)
        z, v = self.z_m[k0:k1 + 1], self.v_mps[k0:k1 + 1]
        h = self.dt_s if self.n_steps > 1 else 0.0
        out = np.empty((k1 - k0, z.shape[1]))
        m = z.shape[0] - 1  # steps with a next sample
        out[:m] = 0.5 * (z[:m] + z[1:m + 1]) + h * (v[:m] - v[1:m + 1]) / 8.0
        if m < k1 - k0:
            out[m:] = z[m:] + 0.5 * h * v[m:]
        return out

    def refined(self, factor: int) -> "Drive":
        """This drive on steps ``factor`` (int >= 1) times finer, for a linear model that runs on
        a finer step than the runs: z and v by the cubic Hermite interpolant of (z, v) between
        samples (its value and derivative; exact for a cubic), from the first sample to the last."""
        r = _factor(factor)
        h = self.dt_s if self.n_steps > 1 else 0.0
        s = np.arange(r) / r  # positions inside a step, 0 <= s < 1
        s2, s3 = s * s, s * s * s
        w = np.stack([2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2])  # h00 h10 h01 h11
        dw = np.stack([6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s])
        z0, z1, v0, v1 = self.z_m[:-1, None], self.z_m[1:, None], self.v_mps[:-1, None], self.v_mps[1:, None]

        def mix(c):
            return (c[0][None, :, None] * z0 + c[1][None, :, None] * h * v0 + c[2][None, :, None] * z1
                    + c[3][None, :, None] * h * v1)

        z = np.concatenate([mix(w).reshape(-1, z0.shape[2]), self.z_m[-1:]])
        v = np.concatenate([(mix(dw) / h if h else mix(dw)).reshape(-1, z0.shape[2]), self.v_mps[-1:]])
        t = np.concatenate([(self.t_s[:-1, None] + s[None, :] * h).reshape(-1), self.t_s[-1:]])  # t_s[::r] exact
        return Drive(t, z, v, self.corners)

    def every(self, factor: int) -> "Drive":
        """Every ``factor``-th step of this drive (``factor`` even), each step holding the sample
        at its middle: the inverse of :meth:`refined` for a signal made on the fine steps (the
        values a coarse step holds are then exact, not interpolated)."""
        r = _factor(factor)
        if r % 2:
            raise ValueError(f"factor must be even (a sample at each coarse step's middle), got {factor}")
        z, v, t = self.z_m[::r], self.v_mps[::r], self.t_s[::r]
        mid = self.z_m[r // 2::r]
        held = np.concatenate([mid, z[mid.shape[0]:] + 0.5 * r * self.dt_s * v[mid.shape[0]:]])
        return Drive(t, z, v, self.corners, held)

    def scaled(self, gain) -> "Drive":
        """This drive with each corner multiplied by ``gain`` (1, shape (4,) or scalar)."""
        g = np.broadcast_to(np.asarray(gain, dtype=float), (len(self.corners),))[None, :]
        return Drive(self.t_s, self.z_m * g, self.v_mps * g, self.corners,
                     None if self.held_m is None else self.held_m * g)

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



def _factor(factor) -> int:
    r = int(factor)
    if r != factor or r < 1:
        raise ValueError(f"factor must be a positive integer, got {factor!r}")
    return r


#: Steps a drive is read in at a time by :func:`check_stroke` and the runs, 1 (0.1 s at 1e-4 s).
CHUNK_STEPS = 1000


def check_stroke(drive, half_stroke_m: float) -> None:
    """Raise if any of ``drive``'s four signals leaves the actuator stroke.

    Parameters
    ----------
    drive : Drive or rigsim.scenarios.core.road_drive.RoadDrive
        Read :data:`CHUNK_STEPS` steps at a time.
    half_stroke_m : float, m
        Allowed |z| about mid-stroke (DYNTRAC: 0.076 m).

    Raises
    ------
    ValueError
        Naming the corner, the time and the excess of the worst sample (the first of equals).
    """
    check_positive("half_stroke_m", half_stroke_m)
    worst = (-1.0, 0, 0, 0.0)  # |z|, step, corner, z
    for k in range(0, drive.n_steps, CHUNK_STEPS):
        z, _ = drive.chunk(k, min(k + CHUNK_STEPS, drive.n_steps))
        mag = np.abs(z)
        i, c = np.unravel_index(int(np.argmax(mag)), mag.shape)
        if mag[i, c] > worst[0]:
            worst = (float(mag[i, c]), k + int(i), int(c), float(z[i, c]))
    mag, k, c, z = worst
    if mag > half_stroke_m:
        raise ValueError(
            f"drive {drive.corners[c]} reaches {1e3 * z:.1f} mm at t = "
            f"{drive.time_at(k):.3f} s, {1e3 * (mag - half_stroke_m):.1f} mm beyond the "
            f"+-{1e3 * half_stroke_m:.1f} mm stroke; raise the high-pass cut-on frequency "
            "(shorter cut-on wavelength) or lower the roughness.")


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
        N = round(duration / dt) + 1 samples; velocity by centred differences; the values held
        over each step (:meth:`Drive.held`) are the same signal at mid-step, exactly (the
        spectrum delayed by -dt / 2).
    """
    n = int(round(duration_s / dt_s)) + 1
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, dt_s)
    amp = np.where(f < corner_hz, 1.0, (corner_hz / np.maximum(f, 1e-12)) ** 2) ** 0.5
    amp[(f < band_hz[0]) | (f > band_hz[1])] = 0.0
    spec = amp[:, None] * np.exp(2j * np.pi * rng.random((f.size, len(CORNERS))))
    z = np.fft.irfft(spec, n=n, axis=0)
    scale = rms_m / z.std(axis=0)
    z *= scale
    mid = np.fft.irfft(spec * np.exp(1j * np.pi * f * dt_s)[:, None], n=n, axis=0) * scale

    def fade(t):
        return (0.5 - 0.5 * np.cos(np.pi * np.clip(t / fade_s, 0.0, 1.0)))[:, None]

    t = np.arange(n) * dt_s
    drive = Drive.from_positions(t, z * fade(t))
    return Drive(drive.t_s, drive.z_m, drive.v_mps, held_m=mid * fade(t + 0.5 * dt_s))


def step_drive(duration_s: float, dt_s: float, size_m: float, at_s: float) -> Drive:
    """A step of ``size_m`` (m) at ``at_s`` (s) on every corner, from t = 0 to ``duration_s`` (s).

    The velocity is zero (the step is an instant change of the reference); each step holds
    the value at its mid-step (:meth:`Drive.held`), so the step starts at ``at_s`` rounded to
    the time grid."""
    n = int(round(duration_s / dt_s)) + 1
    z = np.zeros((n, len(CORNERS)))
    z[int(round(at_s / dt_s)):] = size_m
    return Drive(np.arange(n) * dt_s, z, np.zeros_like(z), held_m=z)
