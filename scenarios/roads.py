"""ISO 8608 road profiles for two wheel tracks and their sampling as rig drives.

A road is described by the ISO 8608 displacement PSD Gd(n) = Gd(n0) (n/n0)^-w
(n in cycle/m, Gd in m^3, n0 = 0.1 cycle/m). Profiles are synthesised by the
deterministic-amplitude random-phase method, optionally high-passed in the
distance domain, and sampled in time as the four wheel-pan drives fl fr rl rr
(left track -> fl, rl; right track -> fr, rr; rear = front delayed by
wheelbase / speed). Only numpy and scipy are used.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np
from scipy import fft as sp_fft
from scipy import signal

N0_CYC_PER_M = 0.1  # ISO 8608 reference spatial frequency n0, cycle/m

ISO_CLASSES = MappingProxyType({  # geometric-mean Gd(n0) per class, m^3 (ISO 8608:2016)
    "A": 16e-6, "B": 64e-6, "C": 256e-6, "D": 1024e-6,
    "E": 4096e-6, "F": 16384e-6, "G": 65536e-6, "H": 262144e-6,
})

# Paper words -> ISO class. Two lines of evidence, which disagree by one class:
# - Roughness: the paper's roads are in-service US highways tested by FHWA at
#   48-72 km/h. Golden-car IRI of a w = 2 profile of the class geometric mean (band
#   0.01-10 cycle/m, computed with this module): A 2.2 m/km, B 4.4 m/km, C 8.9 m/km.
#   FHWA calls IRI <= 2.7 m/km acceptable, so by IRI alone "medium" ~ A, "high" ~ B.
# - Dynamic load: the paper's road-test DLCs (0.0985 medium at 72 km/h with 6360 kg;
#   0.1912 / 0.2105 high at 48 / 72 km/h with 3640 kg). This project's MuJoCo truck
#   (mjcf/) gives, over 60 s road tests of the shipped paper scenarios, DLC 0.051 (A) /
#   0.101 (B) on the medium case, and 0.104 / 0.127 (B) or 0.214 / 0.267 (C) on the high
#   cases at 48 / 72 km/h (DLC scales with sqrt(Gd), i.e. x2 per class).
# The project reproduces the paper's tables, so the words map by dynamic load: medium B,
# high C. The truck the paper measured was evidently more excitable than an IRI-class
# guess suggests (its suspension and payload are not published). Calibrate here, only here.
ROUGHNESS_WORDS = MappingProxyType({"medium": "B", "high": "C"})

TRACK_MODES = ("identical", "independent", "coherent")
CORNERS = ("fl", "fr", "rl", "rr")
START_MARGIN_M = 1.0  # default distance, m, of the rear axle past the profile start at t = 0

_UNIFORM_RTOL = 1e-6


class ProfileError(ValueError):
    """A road profile file cannot be read; the message names file, row and fix."""


def _check_positive(name: str, value: float) -> None:
    try:
        ok = bool(np.isfinite(value) and value > 0)
    except TypeError:
        ok = False
    if not ok:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}.")


def iso8608_psd(n_cyc_per_m, gd_n0_m3: float, waviness: float = 2.0) -> np.ndarray:
    """ISO 8608 displacement PSD Gd(n) = Gd(n0) (n / n0)^-w, m^3.

    Parameters
    ----------
    n_cyc_per_m : array_like, cycle/m
        Spatial frequencies, > 0.
    gd_n0_m3 : float, m^3
        Gd(n0) at n0 = 0.1 cycle/m.
    waviness : float, dimensionless
        Exponent w.
    """
    n = np.asarray(n_cyc_per_m, dtype=float)
    return gd_n0_m3 * (n / N0_CYC_PER_M) ** (-waviness)


@dataclass(frozen=True)
class RoadSpec:
    """Statistical description of a two-track road.

    Parameters
    ----------
    gd_n0_m3 : float, m^3
        Displacement PSD Gd(n0) at n0 = 0.1 cycle/m (see ``ISO_CLASSES``).
    waviness : float, dimensionless
        ISO 8608 exponent w, Gd ~ n^-w.
    n_min_cyc_per_m, n_max_cyc_per_m : float, cycle/m
        Spatial band of synthesis; no content outside it.
    tracks : str
        "identical" (right = left), "independent" (zero coherence) or
        "coherent": exponential coherence model, magnitude-squared coherence
        gamma^2(n) = exp(-a n B), one of the analytical models reviewed by
        Kropac & Mucka, "Model of coherence function of road unevenness in
        parallel tracks for vehicle simulation".
    track_width_m : float, m
        Distance B between the wheel-track centre lines.
    coherence_decay : float, dimensionless
        Decay constant a of the coherent model. The default 6.0 approximates the
        isotropic-surface hypothesis of Dodds & Robson (1973), which for w = 2
        gives gamma = u K1(u), u = 2 pi n B: within 0.09 in gamma^2 for
        n B <= 0.4 (gamma^2 = 0.36 at n B = 0.16 for both).
    """

    gd_n0_m3: float
    waviness: float = 2.0
    n_min_cyc_per_m: float = 0.01
    n_max_cyc_per_m: float = 10.0
    tracks: str = "independent"
    track_width_m: float = 2.0
    coherence_decay: float = 6.0

    def __post_init__(self) -> None:
        for name in ("gd_n0_m3", "waviness", "n_min_cyc_per_m", "n_max_cyc_per_m",
                     "track_width_m", "coherence_decay"):
            _check_positive(f"road.{name}", getattr(self, name))
        if self.n_max_cyc_per_m <= self.n_min_cyc_per_m:
            raise ValueError(
                f"road.n_max_cyc_per_m ({self.n_max_cyc_per_m}) must exceed "
                f"road.n_min_cyc_per_m ({self.n_min_cyc_per_m}); widen the band.")
        if self.tracks not in TRACK_MODES:
            raise ValueError(f"road.tracks must be one of {TRACK_MODES}, got {self.tracks!r}.")

    @classmethod
    def from_class(cls, letter_or_word: str, **kw) -> RoadSpec:
        """Spec of an ISO class geometric mean.

        Parameters
        ----------
        letter_or_word : str
            ISO 8608 class letter "A".."H" or a ``ROUGHNESS_WORDS`` key, any case.
        **kw
            Other ``RoadSpec`` fields (units as in the class docstring).
        """
        key = str(letter_or_word).strip()
        letter = ROUGHNESS_WORDS.get(key.lower(), key.upper())
        if letter not in ISO_CLASSES:
            raise ValueError(
                f"road class {letter_or_word!r} is unknown; use one of "
                f"{sorted(ISO_CLASSES)} or {sorted(ROUGHNESS_WORDS)}.")
        return cls(gd_n0_m3=ISO_CLASSES[letter], **kw)

    def coherence(self, n_cyc_per_m) -> np.ndarray:
        """Model magnitude-squared left/right coherence, dimensionless.

        Parameters
        ----------
        n_cyc_per_m : array_like, cycle/m
            Spatial frequencies.
        """
        n = np.asarray(n_cyc_per_m, dtype=float)
        if self.tracks == "identical":
            return np.ones_like(n)
        if self.tracks == "independent":
            return np.zeros_like(n)
        return np.exp(-self.coherence_decay * n * self.track_width_m)


def _readonly(a) -> np.ndarray:
    out = np.array(a, dtype=float)  # always a private copy
    out.flags.writeable = False
    return out


def _grid_problem(x: np.ndarray) -> tuple[int, str] | None:
    """(index, description with fix) of the first bad distance step of ``x``, else None."""
    d = np.diff(x)
    bad = np.flatnonzero(~(d > 0))
    if bad.size:
        i = int(bad[0]) + 1
        return i, (f"{x[i]:.9g} m does not increase from {x[i - 1]:.9g} m; "
                   "sort the samples and remove duplicates")
    dx = float(np.median(d))  # robust reference: the odd step is the one reported
    bad = np.flatnonzero(np.abs(d - dx) > _UNIFORM_RTOL * dx)
    if bad.size:
        i = int(bad[0]) + 1
        return i, (f"step {d[i - 1]:.9g} m differs from the median step {dx:.9g} m by more than "
                   "1e-6 relative; resample the profile to uniform spacing")
    return None


@dataclass(frozen=True, eq=False)
class Profile:
    """Two-track road elevation profile on a uniform distance grid.

    Parameters
    ----------
    x_m : array_like, m
        Distance along the road, 1-D, uniform spacing (1e-6 relative), increasing.
    left_m, right_m : array_like, m
        Elevation of the left and right wheel tracks, same shape as ``x_m``.
    n_max_cyc_per_m : float or None, cycle/m
        Known upper band limit of the content (set by ``generate_profile``);
        None means content may reach the spatial Nyquist frequency 1 / (2 dx).
    """

    x_m: np.ndarray
    left_m: np.ndarray
    right_m: np.ndarray
    n_max_cyc_per_m: float | None = None

    def __post_init__(self) -> None:
        for name in ("x_m", "left_m", "right_m"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))
        x = self.x_m
        if x.ndim != 1 or x.size < 2:
            raise ValueError(f"profile.x_m must be 1-D with >= 2 samples, got shape {x.shape}.")
        for name in ("left_m", "right_m"):
            if getattr(self, name).shape != x.shape:
                raise ValueError(f"profile.{name} has shape {getattr(self, name).shape}, "
                                 f"expected {x.shape} like profile.x_m.")
        for name in ("x_m", "left_m", "right_m"):
            bad = np.flatnonzero(~np.isfinite(getattr(self, name)))
            if bad.size:
                i = int(bad[0])
                where = f"index {i}" if name == "x_m" else f"x = {x[i]:.6g} m (index {i})"
                raise ValueError(f"profile.{name} is not finite at {where}; "
                                 "remove or repair the bad samples.")
        problem = _grid_problem(x)
        if problem:
            raise ValueError(f"profile.x_m at index {problem[0]}: {problem[1]}.")
        nmax = self.n_max_cyc_per_m
        if nmax is not None:
            _check_positive("profile.n_max_cyc_per_m", nmax)
            if nmax > 0.5 / self.dx_m * (1 + 1e-9):
                raise ValueError(f"profile.n_max_cyc_per_m = {nmax} exceeds the spatial Nyquist "
                                 f"{0.5 / self.dx_m:.6g} cycle/m; lower it or refine x_m.")

    @property
    def dx_m(self) -> float:
        """Sample spacing, m."""
        return float((self.x_m[-1] - self.x_m[0]) / (self.x_m.size - 1))

    @property
    def length_m(self) -> float:
        """Covered distance x[-1] - x[0], m."""
        return float(self.x_m[-1] - self.x_m[0])

    @property
    def band_max_cyc_per_m(self) -> float:
        """Upper band limit of the content, cycle/m (Nyquist 1 / (2 dx) if unknown)."""
        return 0.5 / self.dx_m if self.n_max_cyc_per_m is None else self.n_max_cyc_per_m


def generate_profile(spec: RoadSpec, length_m: float, dx_m: float,
                     rng: np.random.Generator) -> Profile:
    """Synthesise a random two-track profile with the ISO 8608 PSD of ``spec``.

    Deterministic-amplitude random-phase method: each frequency line n_k = k / (M dx)
    in [n_min, n_max] (M >= N the FFT length) gets amplitude sqrt(2 Gd(n_k) dn) and
    a uniform random phase, summed by one inverse real FFT. Coherent tracks keep
    the same amplitudes; the right phase is the left phase plus delta_k drawn
    uniformly in [-D_k, D_k] with sin(D_k) / D_k = gamma(n_k), so that the expected
    cross-spectrum is gamma Gd and the magnitude-squared coherence gamma^2.
    Random draws: left phases first, so the left track does not depend on ``tracks``.

    Parameters
    ----------
    spec : RoadSpec
        Road statistics.
    length_m : float, m
        Profile length; N = round(length / dx) + 1 samples from x = 0. Must be at
        least 1 / n_min so the lowest band frequency is represented.
    dx_m : float, m
        Sample spacing; n_max must not exceed the Nyquist frequency 1 / (2 dx).
    rng : numpy.random.Generator
        Source of randomness; same seed -> bit-identical profile.
    """
    _check_positive("length_m", length_m)
    _check_positive("dx_m", dx_m)
    if not isinstance(rng, np.random.Generator):
        raise ValueError("rng must be a numpy.random.Generator; "
                         "use numpy.random.default_rng(seed).")
    if spec.n_max_cyc_per_m > 0.5 / dx_m * (1 + 1e-9):
        raise ValueError(f"dx_m = {dx_m} m is too coarse for road.n_max_cyc_per_m = "
                         f"{spec.n_max_cyc_per_m}; use dx_m <= {0.5 / spec.n_max_cyc_per_m:.6g} m.")
    if length_m * spec.n_min_cyc_per_m < 1 - 1e-9:
        raise ValueError(f"length_m = {length_m} m is shorter than 1 / road.n_min_cyc_per_m = "
                         f"{1 / spec.n_min_cyc_per_m:.6g} m; lengthen it or raise n_min.")
    n_pts = int(round(length_m / dx_m)) + 1
    m = int(sp_fft.next_fast_len(n_pts, real=True))
    dn = 1.0 / (m * dx_m)
    k = np.arange(m // 2 + 1)
    n = k * dn
    band = (n >= spec.n_min_cyc_per_m * (1 - 1e-12)) & (n <= spec.n_max_cyc_per_m * (1 + 1e-12))
    band[0] = False
    if m % 2 == 0:
        band[-1] = False  # the Nyquist line cannot carry an arbitrary phase
    nb = n[band]
    coef = np.zeros(k.size, dtype=complex)
    amp = 0.5 * m * np.sqrt(2.0 * iso8608_psd(nb, spec.gd_n0_m3, spec.waviness) * dn)
    phi_l = rng.uniform(0.0, 2.0 * np.pi, nb.size)
    coef[band] = amp * np.exp(1j * phi_l)
    left = np.fft.irfft(coef, m)[:n_pts]
    if spec.tracks == "identical":
        right = left
    else:
        if spec.tracks == "independent":
            phi_r = rng.uniform(0.0, 2.0 * np.pi, nb.size)
        else:
            gamma = np.sqrt(spec.coherence(nb))
            grid = np.linspace(0.0, np.pi, 4097)  # sinc(D/pi) = sin(D)/D falls 1 -> 0
            half = np.interp(gamma, np.sinc(grid / np.pi)[::-1], grid[::-1])
            phi_r = phi_l + half * rng.uniform(-1.0, 1.0, nb.size)
        coef[band] = amp * np.exp(1j * phi_r)
        right = np.fft.irfft(coef, m)[:n_pts]
    return Profile(np.arange(n_pts) * dx_m, left, right, n_max_cyc_per_m=spec.n_max_cyc_per_m)


_CSV_HEADERS = (("distance_m", "left_m", "right_m"), ("distance_m", "elevation_m"))


def write_profile_csv(profile: Profile, path) -> None:
    """Write ``profile`` as CSV ``distance_m,left_m,right_m`` at full float precision.

    Parameters
    ----------
    profile : Profile
        Profile to write (distance and elevations in m).
    path : str or os.PathLike
        Output file.
    """
    data = np.column_stack([profile.x_m, profile.left_m, profile.right_m])
    np.savetxt(path, data, fmt="%.17g", delimiter=",", header=",".join(_CSV_HEADERS[0]),
               comments="")


def read_profile_csv(path) -> Profile:
    """Read a road profile CSV.

    The first line is a header, either ``distance_m,left_m,right_m`` or
    ``distance_m,elevation_m`` (identical tracks). All values in m. Distance must
    increase with uniform spacing (1e-6 relative tolerance); no resampling is
    done, resample the file beforehand. Blank lines are ignored.

    Parameters
    ----------
    path : str or os.PathLike
        CSV file.

    Raises
    ------
    ProfileError
        On any bad input, naming the file, the line and column, and the fix.
    """
    p = Path(path)
    if not p.is_file():
        raise ProfileError(f"road profile file '{p}' does not exist; check the path.")
    try:
        with p.open(newline="") as fh:
            rows = [(i, r) for i, r in enumerate(csv.reader(fh), 1) if any(c.strip() for c in r)]
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ProfileError(f"'{p}' is not a readable text CSV ({exc}); "
                           "export it as UTF-8 CSV.") from None
    head = tuple(c.strip().lower() for c in rows[0][1]) if rows else ()
    if head not in _CSV_HEADERS:
        raise ProfileError(f"'{p}' line 1: header {','.join(head)!r} is not 'distance_m,left_m,"
                           "right_m' or 'distance_m,elevation_m'; fix the header.")
    data = np.empty((len(rows) - 1, len(head)))
    for j, (line, r) in enumerate(rows[1:]):
        if len(r) != len(head):
            raise ProfileError(f"'{p}' line {line} has {len(r)} cells, expected {len(head)} "
                               f"({','.join(head)}); fix the row.")
        for c, (name, cell) in enumerate(zip(head, r)):
            try:
                data[j, c] = float(cell)
            except ValueError:
                raise ProfileError(f"'{p}' line {line}, column {name}: {cell.strip()!r} is not a "
                                   "number; fix or remove the row.") from None
            if not np.isfinite(data[j, c]):
                raise ProfileError(f"'{p}' line {line}, column {name}: {cell.strip()!r} is not "
                                   "finite; repair or remove the row.")
    if data.shape[0] < 2:
        raise ProfileError(f"'{p}' has {data.shape[0]} data rows, need at least 2; add data.")
    problem = _grid_problem(data[:, 0])
    if problem:
        line = rows[1 + problem[0]][0]
        raise ProfileError(f"'{p}' line {line}, column distance_m: {problem[1]}.")
    return Profile(data[:, 0], data[:, 1], data[:, -1])


def envelope(profile: Profile, length_m: float) -> Profile:
    """Tire enveloping: a moving average of the profile over the tire's contact length.

    A tire does not follow the road at a point: its contact patch bridges short bumps and
    dips. The standard model of this, used by the International Roughness Index (Sayers,
    "On the calculation of IRI from longitudinal road profile", TRR 1501, 1995), is a moving
    average over 250 mm. It attenuates a wave of length lambda by sinc(length / lambda)
    (first null at lambda = length). Apply it to the profile once, for road and rig alike:
    on the rig the tire stands on a flat pan, so the drive must already be the enveloped
    (effective) profile.

    Parameters
    ----------
    profile : Profile
        Road profile (m).
    length_m : float, m
        Averaging length (0 returns the profile unchanged). Truck tires: ~0.2-0.3 m contact
        length.

    Returns
    -------
    Profile
        The averaged profile on the same distance axis (ends padded with the edge value).
    """
    if length_m == 0:
        return profile
    _check_positive("envelope_length_m", length_m)
    width = int(round(length_m / profile.dx_m))
    if width < 2:
        return profile
    if width > profile.x_m.size // 2:
        raise ValueError(f"envelope_length_m = {length_m} m is longer than half the profile "
                         f"({profile.length_m:.6g} m); use a shorter averaging length.")
    kernel = np.full(width, 1.0 / width)

    def smooth(z):
        lo = width // 2
        padded = np.concatenate([np.full(lo, z[0]), z, np.full(width - 1 - lo, z[-1])])
        return np.convolve(padded, kernel, mode="valid")

    return Profile(profile.x_m, smooth(profile.left_m), smooth(profile.right_m),
                   n_max_cyc_per_m=profile.n_max_cyc_per_m)


def highpass(profile: Profile, cuton_wavelength_m: float, order: int = 2) -> Profile:
    """Zero-phase Butterworth high-pass of both tracks in the distance domain.

    The DYNTRAC stroke is 15.2 cm (+-76 mm), yet an ISO road has most of its
    elevation variance in long waves the truck rides over without response;
    they must go before the profile becomes a rig drive. Filtering in distance
    (not time) makes the result independent of speed, and the zero-phase
    forward-backward filter (``sosfiltfilt``; gain |H|^2 of a Butterworth of
    ``order``) shifts no wave, so road-mode and rig-mode simulations receive
    identical drives.

    Parameters
    ----------
    profile : Profile
        Input profile (m).
    cuton_wavelength_m : float, m
        Wavelength of the -3 dB point of one pass (-6 dB overall); must be longer
        than 2 dx (Nyquist) and no longer than the profile length.
    order : int
        Butterworth order of one pass (rolloff doubled by forward-backward).
    """
    _check_positive("cuton_wavelength_m", cuton_wavelength_m)
    if not (isinstance(order, (int, np.integer)) and order >= 1):
        raise ValueError(f"order must be an integer >= 1, got {order!r}.")
    dx = profile.dx_m
    if cuton_wavelength_m <= 2 * dx:
        raise ValueError(f"cuton_wavelength_m = {cuton_wavelength_m} m is not above the Nyquist "
                         f"wavelength 2 dx = {2 * dx:.6g} m; use a longer cut-on wavelength.")
    if cuton_wavelength_m > profile.length_m:
        raise ValueError(f"cuton_wavelength_m = {cuton_wavelength_m} m exceeds the profile length "
                         f"{profile.length_m:.6g} m; use a shorter cut-on or a longer profile.")
    sos = signal.butter(order, 1.0 / cuton_wavelength_m, btype="highpass", output="sos",
                        fs=1.0 / dx)
    left, right = (signal.sosfiltfilt(sos, z) for z in (profile.left_m, profile.right_m))
    return Profile(profile.x_m, left, right, n_max_cyc_per_m=profile.n_max_cyc_per_m)


@dataclass(frozen=True, eq=False)
class WheelDrive:
    """Wheel-pan drive signals of the four corners.

    Parameters
    ----------
    t_s : array_like, s
        Sample times, shape (N,).
    z_m : array_like, m
        Elevation per corner, shape (N, 4), columns in ``corners`` order.
    v_mps : array_like, m/s
        Vertical velocity per corner, shape (N, 4).
    corners : tuple of str
        Column names, ("fl", "fr", "rl", "rr").
    """

    t_s: np.ndarray
    z_m: np.ndarray
    v_mps: np.ndarray
    corners: tuple = field(default=CORNERS)

    def __post_init__(self) -> None:
        for name in ("t_s", "z_m", "v_mps"):
            object.__setattr__(self, name, _readonly(getattr(self, name)))
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
        _check_positive("half_stroke_m", half_stroke_m)
        mag = np.abs(self.z_m)
        i, c = np.unravel_index(int(np.argmax(mag)), mag.shape)
        if mag[i, c] > half_stroke_m:
            raise ValueError(
                f"drive {self.corners[c]} reaches {1e3 * self.z_m[i, c]:.1f} mm at t = "
                f"{self.t_s[i]:.3f} s, {1e3 * (mag[i, c] - half_stroke_m):.1f} mm beyond the "
                f"+-{1e3 * half_stroke_m:.1f} mm stroke; raise the high-pass cut-on frequency "
                "(shorter cut-on wavelength) or lower the roughness.")


def sample_wheels(profile: Profile, speed_mps: float, wheelbase_m: float, fs_hz: float,
                  duration_s: float, start_m: float | None = None) -> WheelDrive:
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
        _check_positive(name, val)
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
    return WheelDrive(t, z, vz)


def welch_psd_spatial(z, dx_m: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD of a profile in the distance domain.

    Parameters
    ----------
    z : array_like, m
        Elevation samples on a uniform grid.
    dx_m : float, m
        Sample spacing.
    nperseg : int
        Segment length, samples (Hann window, 50 % overlap).

    Returns
    -------
    (n_cyc_per_m, gd_m3) : tuple of numpy.ndarray, (cycle/m, m^3)
        Spatial frequencies and displacement PSD (m^2 per cycle/m).
    """
    z = np.asarray(z, dtype=float)
    _check_positive("dx_m", dx_m)
    if not (1 < nperseg <= z.size):
        raise ValueError(f"nperseg must be in 2..{z.size} (len(z)), got {nperseg}.")
    return signal.welch(z, fs=1.0 / dx_m, nperseg=nperseg)
