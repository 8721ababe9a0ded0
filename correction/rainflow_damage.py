"""Fatigue measures of wheel forces: rainflow cycles, pseudo-damage, damage-equivalent load,
level crossings.

Rainflow counting follows ASTM E1049-85 (reapproved 2011), "Standard Practices for Cycle Counting
in Fatigue Analysis", section 5.4.4 (rainflow counting): the first and last points of the record
count as reversals, closed ranges are full cycles (count 1), ranges that contain the starting
point and the residue left at the end are half cycles (count 0.5).

Library: ``rainflow`` (https://github.com/iamlikeme/rainflow, MIT, no dependencies), chosen over
``fatpack`` (ISC) after comparing both (rainflow 3.2.0, fatpack 0.7.8):

- on the standard's example history (-2, 1, -3, 5, -1, 3, -4, 4, -2; E1049-85 fig. 6 and its
  table) ``rainflow.extract_cycles`` reproduces the table exactly (ranges 3: 0.5, 4: 1.5, 6: 0.5,
  8: 1.0, 9: 0.5 cycles, with the cycle means); ``fatpack`` first bins the record into ``k``
  load classes (default 64, so the ranges come out as 4.08, 3.09, ...), finds only the one closed
  cycle (range 4) by its 4-point rule and closes the residue by concatenating it with itself,
  i.e. counts the residue as full cycles, not the standard's half cycles;
- on 200 000 Gaussian samples both find the same 66 794 full cycles (same ranges when fatpack's
  classes are made very fine); they differ only in the residue: pseudo-damage sum n S^m agrees to
  5e-5 (m = 3), 5e-4 (m = 5) and 2e-2 (m = 10), fatpack higher since it counts the residue's
  largest ranges as full cycles;
- rainflow gives exact (unbinned) ranges, means and 0.5/1 counts per the standard, with the
  sample indices; it ran in 0.23 s on those 200 000 samples (fatpack: 0.22 s with 64 classes,
  0.34 s with 4096, 32 s with 2^30 classes, fine enough to stop the binning).

Forces in N throughout. Every function takes a 1-D force (time along axis 0) or an (n, k) array
(one force per column) and returns per-column results.
"""

from __future__ import annotations

import math

import numpy as np
import rainflow

__all__ = [
    "WOHLER_PRESETS",
    "turning_points",
    "damage_equivalent_load",
    "force_columns",
    "level_crossings",
    "pseudo_damage",
    "rainflow_cycles",
]

#: Typical Woehler (S-N curve) slopes m (dimensionless) by material, for :func:`pseudo_damage`
#: and :func:`damage_equivalent_load`:
#:
#: - "welded steel": m = 3, the slope of the fatigue-class S-N curves of welded details under
#:   normal stress in the IIW recommendations (Hobbacher, "Recommendations for Fatigue Design of
#:   Welded Joints and Components", IIW, 2nd ed. 2016) and in Eurocode 3, EN 1993-1-9 (m = 3 up to
#:   10^7 cycles);
#: - "steel": m = 5, the slope used for unwelded (base-material, machined) steel components and
#:   the usual single exponent of vehicle durability load analysis (Johannesson and Speckert,
#:   "Guide to Load Analysis for Durability in Vehicle Engineering", Wiley 2014); EN 1993-1-9 also
#:   uses m = 5 for shear stress ranges and beyond the constant-amplitude fatigue limit;
#: - "composite": m = 10, the slope typical of glass-fibre reinforced plastics (wind-turbine blade
#:   practice, e.g. the Germanischer Lloyd 2010 guideline and DNV-ST-0376, which give m of about
#:   9 to 10 for GFRP laminates).
WOHLER_PRESETS: dict[str, float] = {"welded steel": 3.0, "steel": 5.0, "composite": 10.0}


def force_columns(force_N, name: str = "force_N") -> tuple[np.ndarray, bool]:
    """A force record as an (n, k) float array (N) and whether it was 1-D.

    Raises ValueError (naming ``name``) if it is not 1-D or 2-D, has fewer than two samples
    along axis 0, no column, or a NaN or infinite value.
    """
    f = np.asarray(force_N, dtype=float)
    if f.ndim not in (1, 2):
        raise ValueError(f"{name} must be 1-D (n,) or 2-D (n, k) with time along axis 0, got shape {f.shape}")
    if f.shape[0] < 2:
        raise ValueError(f"{name} needs at least two samples along axis 0, got {f.shape[0]}")
    if f.ndim == 2 and f.shape[1] < 1:
        raise ValueError(f"{name} has no columns; pass an (n, k) array with k >= 1")
    if not np.all(np.isfinite(f)):
        raise ValueError(f"{name} contains NaN or infinite values; remove or fill them first")
    return (f[:, None], True) if f.ndim == 1 else (f, False)


def _exponent(m) -> float:
    m = float(m)
    if not (math.isfinite(m) and m > 0):
        raise ValueError(f"the Woehler exponent m must be a positive number, got {m}")
    return m


def turning_points(f: np.ndarray) -> np.ndarray:
    """The reversals of a 1-D history as ``rainflow.reversals`` finds them, found with numpy.

    The first sample, every sample where the slope changes sign (a run of equal samples counts
    once) and the last sample. ``rainflow`` walks every sample in Python (~1 us each); counting
    the cycles of these points instead gives the same cycles (tested against the library) in a
    fraction of the time: a 60 s record at 1 kHz has ~10 % of its samples as reversals.

    Parameters
    ----------
    f : numpy.ndarray, (n,), n >= 2

    Returns
    -------
    numpy.ndarray
        The reversal values, then the last one repeated (so that ``rainflow`` sees the last
        point as a reversal also when there are only two).
    """
    g = f[np.concatenate(([True], f[1:] != f[:-1]))]  # runs of equal samples once
    if g.size < 2:
        return np.array([f[0], f[0], f[0]])
    d = np.diff(g)
    interior = np.flatnonzero(d[:-1] * d[1:] < 0) + 1
    return np.concatenate((g[:1], g[interior], g[-1:], g[-1:]))


def _cycles_1d(f: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    points = turning_points(f) if f.size >= 2 else f  # 2 samples: one half cycle (the library drops the last point)
    rows = [(r, mean, c) for r, mean, c, _i, _j in rainflow.extract_cycles(points) if r > 0]
    if not rows:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    ranges, means, counts = (np.asarray(v, dtype=float) for v in zip(*rows))
    return ranges, means, counts


def rainflow_cycles(force_N):
    """Rainflow cycles of a force history, ASTM E1049-85 section 5.4.4.

    Parameters
    ----------
    force_N : array_like, N
        Force history, shape (n,), or (n, k) with one history per column (time along axis 0).

    Returns
    -------
    (ranges_N, means_N, counts) or list of them
        For 1-D input one tuple of equal-length arrays: the cycle ranges (N, peak-to-valley),
        the cycle means (N) and the counts (0.5 for a half cycle, 1.0 for a full cycle), in the
        order the cycles close. For (n, k) input a list of k such tuples. Cycles of range 0
        (the library's half cycle between the end points of a constant record) are left out: a
        constant force has no cycles (empty arrays).

    Notes
    -----
    Counted by ``rainflow.extract_cycles`` (see the module docstring for why this library). The
    first and last samples count as reversals, as in the standard; a sampled peak is the largest
    sample, so a range is only as exact as the sampling lets it be.
    """
    f, one = force_columns(force_N)
    out = [_cycles_1d(f[:, j]) for j in range(f.shape[1])]
    return out[0] if one else out


def pseudo_damage(force_N, m):
    """Relative fatigue damage sum n_i S_i^m of a force history (Palmgren-Miner, no S-N intercept).

    With an S-N curve N(S) = C S^-m, Miner's rule gives the damage D = sum n_i / N(S_i)
    = sum n_i S_i^m / C (Miner, J. Appl. Mech. 12, 1945; ASTM E1049-85 for the cycles). Leaving
    out the intercept C, which depends on the component, gives a measure proportional to the
    damage of any component with slope m: only ratios of pseudo-damages (one force against
    another) have meaning.

    Parameters
    ----------
    force_N : array_like, N
        Force history, shape (n,) or (n, k) (time along axis 0).
    m : float
        Woehler exponent (dimensionless, > 0); see :data:`WOHLER_PRESETS`.

    Returns
    -------
    float or numpy.ndarray, N^m
        sum over the rainflow cycles of count * range^m; a float for 1-D input, shape (k,)
        otherwise. 0 for a constant force.
    """
    m = _exponent(m)
    f, one = force_columns(force_N)
    d = np.array([float(np.sum(c * r ** m)) for r, _mean, c in (_cycles_1d(f[:, j]) for j in range(f.shape[1]))])
    return float(d[0]) if one else d


def damage_equivalent_load(force_N, m, n_equivalent=None, duration_s=None, f_equivalent_hz: float = 1.0):
    """Damage-equivalent load range: the constant range that does the record's damage in N_eq cycles.

    DEL = (sum n_i S_i^m / N_eq)^(1/m), from Miner's rule with an S-N curve of slope m: N_eq
    cycles of range DEL do the same damage as the rainflow cycles (n_i, S_i) of the record,
    whatever the intercept (the short-term DEL of wind-turbine load analysis, e.g. NREL's MLife,
    Hayman 2012; the "equivalent load" of Johannesson and Speckert 2014 for vehicles).

    Parameters
    ----------
    force_N : array_like, N
        Force history, shape (n,) or (n, k) (time along axis 0).
    m : float
        Woehler exponent (dimensionless, > 0); see :data:`WOHLER_PRESETS`.
    n_equivalent : float, optional
        Number of equivalent cycles N_eq (dimensionless, > 0). Takes precedence over
        ``duration_s``.
    duration_s : float, optional, s
        Record length; with it N_eq = ``f_equivalent_hz`` * ``duration_s``.
    f_equivalent_hz : float, Hz
        Equivalent cycle rate; 1 Hz (one equivalent cycle per second of record, the "1 Hz DEL")
        is the common convention in wind-turbine and vehicle load practice, and makes DELs of
        records of different lengths comparable.

    Returns
    -------
    float or numpy.ndarray, N
        The DEL (a range, peak to valley); a float for 1-D input, shape (k,) otherwise.
        0 for a constant force.

    Raises
    ------
    ValueError
        If neither ``n_equivalent`` nor ``duration_s`` is given, or one is not positive.
    """
    m = _exponent(m)
    if n_equivalent is not None:
        n_eq = float(n_equivalent)
        what = "n_equivalent"
    elif duration_s is not None:
        n_eq = float(f_equivalent_hz) * float(duration_s)
        what = "f_equivalent_hz * duration_s"
    else:
        raise ValueError("damage_equivalent_load needs n_equivalent or duration_s "
                         "(N_eq = f_equivalent_hz * duration_s)")
    if not (math.isfinite(n_eq) and n_eq > 0):
        raise ValueError(f"{what} must be a positive number of equivalent cycles, got {n_eq}")
    return (pseudo_damage(force_N, m) / n_eq) ** (1.0 / m)


def level_crossings(force_N, levels_N):
    """Number of upward crossings of each level.

    An upward crossing of level L is a step from a sample at or below L to the next sample
    above L (F[i] <= L < F[i+1]), so a force that only touches L does not cross it, and one that
    sits on L and then rises crosses once. The level-crossing spectrum is the classical summary
    of a load history next to rainflow (ASTM E1049-85 section 5.1; Rice, "Mathematical analysis
    of random noise", Bell Syst. Tech. J. 23-24, 1944-45, for its expected value for Gaussian
    loads).

    Parameters
    ----------
    force_N : array_like, N
        Force history, shape (n,) or (n, k) (time along axis 0).
    levels_N : array_like, N
        Levels, shape (p,) (or a scalar).

    Returns
    -------
    numpy.ndarray of int
        Upward crossing counts, shape (p,) for 1-D force, (p, k) otherwise.
    """
    f, one = force_columns(force_N)
    levels = np.atleast_1d(np.asarray(levels_N, dtype=float))
    if levels.ndim != 1 or not np.all(np.isfinite(levels)):
        raise ValueError("levels_N must be a finite scalar or 1-D array of force levels in N")
    counts = np.zeros((levels.size, f.shape[1]), dtype=int)
    for i, level in enumerate(levels):  # one level at a time: memory n * k, not n * p * k
        counts[i] = np.sum((f[:-1] <= level) & (f[1:] > level), axis=0)
    return counts[:, 0] if one else counts
