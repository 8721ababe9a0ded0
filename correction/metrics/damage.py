"""Pavement-damage and fatigue measures of wheel forces, and one result object for the reports.

The DLC (std / mean, :mod:`rigsim.correction.metrics.dlc`) is the paper's figure, but two forces with the same
DLC can do very different damage. This module adds the measures the users of wheel forces judge
them by:

- pavement engineers: the power-law ("fourth-power law", AASHO Road Test, Highway Research Board
  Special Report 61E, 1962) dynamic load stress factor E[(F / F_static)^n] (:func:`stress_factor`,
  and its Gaussian value 1 + 6 DLC^2 + 3 DLC^4 for n = 4, :func:`stress_factor_gaussian`; Eisenmann,
  "Dynamic wheel load fluctuations - road stress", Strasse und Autobahn 26(4), 1975; Cebon,
  "Handbook of Vehicle-Road Interaction", Swets & Zeitlinger, 1999), impact factors (percentile
  force over the static load, :func:`impact_factors`), and where along the road the large loads
  land (:mod:`rigsim.correction.metrics.spatial_load`: :func:`spatial_profile`, :func:`spatial_correlation` =
  the spatial repeatability index of Cole and Cebon, :func:`top_loads`; re-exported here);
- vehicle and component engineers: rainflow fatigue damage (:mod:`rigsim.correction.metrics.rainflow_damage`:
  :func:`rainflow_cycles`, :func:`pseudo_damage`, :func:`damage_equivalent_load`,
  :func:`level_crossings`, :data:`WOHLER_PRESETS`, re-exported here).

:func:`damage_metrics` gathers them per wheel in a :class:`DamageMetrics`; :func:`compare` gives the
relative errors of one against a reference (corrected vs road, rig vs road).

Forces in N; every function takes a 1-D force or an (n, k) array (one force per column, time along
axis 0) and returns per-column results (a float or shape (k,), as documented).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rigsim.correction.metrics.dlc import column_sum
from rigsim.correction.metrics.dlc import dlc as dynamic_load_coefficient
from rigsim.correction.metrics.rainflow_damage import (
    WOHLER_PRESETS,
    damage_equivalent_load,
    force_columns,
    level_crossings,
    pseudo_damage,
    rainflow_cycles,
)
from rigsim.correction.metrics.spatial_load import spatial_correlation, spatial_profile, top_loads

__all__ = [
    "WOHLER_PRESETS",
    "DamageMetrics",
    "compare",
    "damage_equivalent_load",
    "damage_metrics",
    "impact_factors",
    "level_crossings",
    "pseudo_damage",
    "rainflow_cycles",
    "spatial_correlation",
    "spatial_profile",
    "stress_factor",
    "stress_factor_gaussian",
    "top_loads",
]


def _static(static_N, f: np.ndarray) -> np.ndarray:
    """The static load per column (N): the record's mean if None; refuses a non-positive one."""
    s = f.mean(axis=0) if static_N is None else np.broadcast_to(np.asarray(static_N, dtype=float), (f.shape[1],))
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        what = "the mean force" if static_N is None else "static_N"
        raise ValueError(f"{what} must be positive (a compressive static wheel load in N), got {s}")
    return s


def _out(values: np.ndarray, one: bool):
    """Per-column values: a float for a 1-D record, else the array."""
    return float(values[0]) if one else values


def stress_factor(force_N, static_N=None, n: float = 4.0):
    """Dynamic load stress factor E[(F / F_static)^n] of a wheel-force record.

    The pavement damage of a load F grows as (F / F_standard)^n (n = 4: the "fourth-power law" of
    the AASHO Road Test, 1962); averaged over a dynamic load it is the static load's damage times
    this factor (Cebon 1999, the dynamic load stress factor; Eisenmann 1975). 1 for a constant
    load equal to the static one.

    Parameters
    ----------
    force_N : array_like, N
        Wheel force, shape (n,) or (n, k) (time along axis 0).
    static_N : float or array_like, optional, N
        Static wheel load, scalar or one per column; default the record's mean per column.
    n : float
        Damage exponent (dimensionless, > 0): 4 for the fourth-power law; other values are used
        for particular pavement materials and distress modes (Cebon 1999 reviews them).

    Returns
    -------
    float or numpy.ndarray
        mean((max(F, 0) / F_static)^n) along axis 0, dimensionless; a float for 1-D input.

    Notes
    -----
    Negative forces (the tyre lifted off, or a tensile reading) load no pavement: they are
    clamped at 0 before the power. This also keeps an odd or non-integer n real.
    """
    n = float(n)
    if not (math.isfinite(n) and n > 0):
        raise ValueError(f"the damage exponent n must be a positive number, got {n}")
    f, one = force_columns(force_N)
    s = _static(static_N, f)
    # np.mean((max(f, 0) / s) ** n, axis=0) bit for bit, without three temporaries as large as f
    return _out(column_sum(f, lambda b: (np.maximum(b, 0.0) / s) ** n) / f.shape[0], one)


def stress_factor_gaussian(dlc, n: int = 4):
    """Stress factor E[(1 + c Z)^n] of a Gaussian wheel force with DLC c (Z standard normal).

    E[(1 + c Z)^n] = sum_k C(n, k) c^k E[Z^k] with E[Z^k] = (k - 1)!! for even k and 0 for odd k;
    n = 4 gives 1 + 6 c^2 + 3 c^4, the dynamic load stress factor of Eisenmann (1975) and Cebon
    (1999) for a normally distributed wheel load.

    Parameters
    ----------
    dlc : float or array_like
        Dynamic load coefficient(s) c = std / static load (dimensionless, >= 0).
    n : int
        Damage exponent, a non-negative integer (4.0 is accepted as 4).

    Returns
    -------
    float or numpy.ndarray
        The expectation, dimensionless; a float for scalar input.

    Notes
    -----
    Unlike :func:`stress_factor` the Gaussian has no lift-off clamp: its negative tail (the
    probability Phi(-1/c), 3e-7 at c = 0.2) counts with (1 + c Z)^n. The two agree while lift-off
    is negligible.
    """
    if float(n) != int(n) or int(n) < 0:
        raise ValueError(f"stress_factor_gaussian needs a non-negative integer exponent n, got {n}")
    n = int(n)
    c = np.asarray(dlc, dtype=float)
    if not np.all(np.isfinite(c)) or np.any(c < 0):
        raise ValueError(f"dlc must be finite and non-negative, got {dlc}")
    total = np.zeros_like(c)
    for k in range(0, n + 1, 2):
        double_factorial = math.prod(range(k - 1, 0, -2))  # (k - 1)!!, 1 for k = 0 and 2
        total = total + math.comb(n, k) * double_factorial * c ** k
    return float(total) if total.ndim == 0 else total


def impact_factors(force_N, static_N=None, percentiles=(95.0, 99.9)):
    """Impact factors: percentile forces over the static load.

    The ratio of a high percentile of the dynamic wheel load to the static load (the "impact
    factor" of bridge and pavement loading; Cebon 1999 uses the 95th percentile of the wheel
    load, which a Gaussian force reaches at 1 + 1.645 DLC).

    Parameters
    ----------
    force_N : array_like, N
        Wheel force, shape (n,) or (n, k) (time along axis 0).
    static_N : float or array_like, optional, N
        Static wheel load, scalar or one per column; default the record's mean per column.
    percentiles : sequence of float
        Percentiles in [0, 100] (numpy's linear interpolation between samples).

    Returns
    -------
    numpy.ndarray
        percentile(F, p) / F_static, dimensionless, shape (p,) for 1-D force, (p, k) otherwise.
    """
    q = np.atleast_1d(np.asarray(percentiles, dtype=float))
    if q.ndim != 1 or not np.all((q >= 0) & (q <= 100)):
        raise ValueError(f"percentiles must be numbers in [0, 100], got {percentiles}")
    f, one = force_columns(force_N)
    s = _static(static_N, f)
    out = np.percentile(f, q, axis=0) / s
    return out[:, 0] if one else out


def _key(m: float) -> str:
    """Exponent m as a key part: 3.0 -> "m3", 2.5 -> "m2.5"."""
    return f"m{m:g}"


@dataclasses.dataclass(frozen=True)
class DamageMetrics:
    """Pavement-damage and fatigue figures of one wheel-force record, one value per column (wheel).

    Attributes
    ----------
    fs_hz : float, Hz
        Sample rate of the record.
    duration_s : float, s
        Record length n / fs_hz.
    n_equivalent : float
        Equivalent cycles of the DELs: 1 Hz * duration_s (dimensionless).
    exponents : tuple of float
        Woehler exponents m of ``del_N`` and ``pseudo_damage`` (dimensionless).
    mean_N, static_N : tuple of float, N
        Mean force and the static load the ratios are taken against (the mean unless given).
    dlc : tuple of float
        std / mean (dimensionless).
    stress_factor_4 : tuple of float
        E[(max(F, 0) / F_static)^4] of the record (:func:`stress_factor`).
    stress_factor_4_gaussian : tuple of float
        The same for a Gaussian force with the record's mean and DLC:
        (mean / static)^4 (1 + 6 DLC^2 + 3 DLC^4) (:func:`stress_factor_gaussian`).
    impact_95, impact_999 : tuple of float
        95th and 99.9th percentile force over the static load (:func:`impact_factors`).
    del_N : tuple of tuple of float, N
        Damage-equivalent load range per exponent (outer, as ``exponents``) and column (inner).
    pseudo_damage : tuple of tuple of float, N^m
        sum count * range^m per exponent and column.
    """

    fs_hz: float
    duration_s: float
    n_equivalent: float
    exponents: tuple
    mean_N: tuple
    static_N: tuple
    dlc: tuple
    stress_factor_4: tuple
    stress_factor_4_gaussian: tuple
    impact_95: tuple
    impact_999: tuple
    del_N: tuple
    pseudo_damage: tuple

    def del_m(self, m: float) -> np.ndarray:
        """DEL (N) per column for Woehler exponent m (one of ``exponents``)."""
        return np.array(self.del_N[self._index(m)])

    def pseudo_damage_m(self, m: float) -> np.ndarray:
        """Pseudo-damage (N^m) per column for Woehler exponent m (one of ``exponents``)."""
        return np.array(self.pseudo_damage[self._index(m)])

    def _index(self, m: float) -> int:
        for i, e in enumerate(self.exponents):
            if math.isclose(e, float(m)):
                return i
        raise KeyError(f"no exponent m = {m} in these metrics (computed for {self.exponents})")

    @property
    def del_m3(self) -> np.ndarray:
        """DEL (N) per column, m = 3 (welded steel)."""
        return self.del_m(3)

    @property
    def del_m5(self) -> np.ndarray:
        """DEL (N) per column, m = 5 (steel)."""
        return self.del_m(5)

    @property
    def del_m10(self) -> np.ndarray:
        """DEL (N) per column, m = 10 (composite)."""
        return self.del_m(10)

    @property
    def pseudo_damage_m5(self) -> np.ndarray:
        """Pseudo-damage (N^5) per column, m = 5."""
        return self.pseudo_damage_m(5)

    def figures(self) -> dict[str, list[float]]:
        """Per-column figures by flat name: "del_m3_N" (N), "pseudo_damage_m5" (N^5), "dlc", ..."""
        out = {name: list(getattr(self, name)) for name in (
            "mean_N", "static_N", "dlc", "stress_factor_4", "stress_factor_4_gaussian", "impact_95", "impact_999")}
        for m, d, p in zip(self.exponents, self.del_N, self.pseudo_damage):
            out[f"del_{_key(m)}_N"] = list(d)
            out[f"pseudo_damage_{_key(m)}"] = list(p)
        return out

    def to_dict(self) -> dict:
        """JSON-ready: the scalars and :meth:`figures` (lists per column)."""
        return {"fs_hz": self.fs_hz, "duration_s": self.duration_s, "n_equivalent": self.n_equivalent,
                "exponents": list(self.exponents), **self.figures()}


def damage_metrics(force_N, fs_hz: float, static_N=None, exponents=(3, 5, 10)) -> DamageMetrics:
    """All the damage figures of a wheel-force record, per column.

    Parameters
    ----------
    force_N : array_like, N
        Wheel force, shape (n,) or (n, k) (time along axis 0), compressive (positive mean).
    fs_hz : float, Hz
        Sample rate; the record lasts n / fs_hz and the DELs use 1 equivalent cycle per second.
    static_N : float or array_like, optional, N
        Static load per column for the stress and impact factors; default the mean.
    exponents : sequence of float
        Woehler exponents for the DELs and pseudo-damages (:data:`WOHLER_PRESETS`).

    Returns
    -------
    DamageMetrics
    """
    fs = float(fs_hz)
    if not (math.isfinite(fs) and fs > 0):
        raise ValueError(f"fs_hz must be a positive sample rate in Hz, got {fs_hz}")
    exps = tuple(float(m) for m in exponents)
    if not exps or not all(math.isfinite(m) and m > 0 for m in exps):
        raise ValueError(f"exponents must be positive Woehler exponents, got {exponents}")
    f, _one = force_columns(force_N)
    s = _static(static_N, f)
    mean = f.mean(axis=0)
    c = dynamic_load_coefficient(f, axis=0)
    duration = f.shape[0] / fs
    impact = impact_factors(f, s, (95.0, 99.9))
    cycles = rainflow_cycles(f)  # counted once, summed for every exponent's DEL and pseudo-damage
    cols = lambda v: tuple(float(x) for x in np.atleast_1d(v))  # noqa: E731
    return DamageMetrics(
        fs_hz=fs, duration_s=duration, n_equivalent=duration * 1.0, exponents=exps,
        mean_N=cols(mean), static_N=cols(s), dlc=cols(c),
        stress_factor_4=cols(stress_factor(f, s, 4.0)),
        stress_factor_4_gaussian=cols((mean / s) ** 4 * stress_factor_gaussian(c, 4)),
        impact_95=cols(impact[0]), impact_999=cols(impact[1]),
        del_N=tuple(cols(damage_equivalent_load(f, m, duration_s=duration, cycles=cycles)) for m in exps),
        pseudo_damage=tuple(cols(pseudo_damage(f, m, cycles=cycles)) for m in exps),
    )


#: figures whose excess over 1 (the dynamic increment) is also compared
_INCREMENTS = ("stress_factor_4", "stress_factor_4_gaussian", "impact_95", "impact_999")


def compare(reference: DamageMetrics, other: DamageMetrics) -> dict[str, list[float]]:
    """Relative errors of ``other``'s figures against ``reference``'s, per column.

    (other - reference) / reference for every figure of :meth:`DamageMetrics.figures`
    ("del_m5_N", "stress_factor_4", ...), and for the stress and impact factors also of their
    dynamic increment over 1 under "<name>_increment": ((o - 1) - (r - 1)) / (r - 1), since a
    stress factor of 1.03 against 1.06 is a 3 % error of the factor but a 50 % error of the
    dynamic damage. NaN where the reference is 0 (a constant reference force's DEL).

    Parameters
    ----------
    reference, other : DamageMetrics
        With the same number of columns and the same exponents (e.g. road, and corrected or rig).

    Returns
    -------
    dict of str to list of float
        Relative errors, dimensionless, one per column.
    """
    if reference.exponents != other.exponents or len(reference.mean_N) != len(other.mean_N):
        raise ValueError("compare needs metrics with the same columns and exponents; compute both with damage_metrics "
                         "and the same exponents")
    ref, oth = reference.figures(), other.figures()
    out = {}
    with np.errstate(divide="ignore", invalid="ignore"):
        for name, r in ref.items():
            r, o = np.asarray(r), np.asarray(oth[name])
            out[name] = np.where(r != 0, (o - r) / r, np.nan).tolist()
            if name in _INCREMENTS:
                out[f"{name}_increment"] = np.where(r != 1, (o - r) / (r - 1), np.nan).tolist()
    return out
