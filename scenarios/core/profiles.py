"""Two-track road elevation profiles: the profile object, its CSV file, tire enveloping, high-pass.

A :class:`Profile` is elevation against distance on a uniform grid for the left and right
wheel tracks. This module reads and writes it (CSV ``distance_m,left_m,right_m``), applies
the tire's enveloping (a moving average, the IRI's tire model) and the distance-domain
high-pass that keeps a drive inside the actuator stroke. Only numpy and scipy are used.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import signal

from rigsim.correction.io.atomic import open_regular
from rigsim.errors import RigsimError

__all__ = ["ProfileError", "Profile", "write_profile_csv", "read_profile_csv", "envelope", "highpass",
           "check_positive", "readonly_copy"]

_UNIFORM_RTOL = 1e-6


class ProfileError(RigsimError, ValueError):
    """A road profile file cannot be read; the message names file, row and fix."""



def check_positive(name: str, value: float) -> None:
    try:
        ok = bool(np.isfinite(value) and value > 0)
    except TypeError:
        ok = False
    if not ok:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}.")


def readonly_copy(a) -> np.ndarray:
    """A read-only float copy of ``a`` (the arrays of the frozen profile and drive objects)."""
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
            object.__setattr__(self, name, readonly_copy(getattr(self, name)))
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
            check_positive("profile.n_max_cyc_per_m", nmax)
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
    try:
        with io.TextIOWrapper(open_regular(p, "road profile file", error=ProfileError, expected="a CSV file"),
                              newline="") as fh:
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
    check_positive("envelope_length_m", length_m)
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
    check_positive("cuton_wavelength_m", cuton_wavelength_m)
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

