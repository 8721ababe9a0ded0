"""Several records of one truck as one calibration's data: windows drawn from each.

A programme's records are road sections and speeds of one truck; a calibration fitted on windows of
several of them sees more of the truck (other roads excite other modes) than one record's windows.
:func:`join` lays the records end to end on one uniform time axis (each keeps its samples; the model
runs never cross a join: every calibration window, its lead-in included, lies inside one record,
:meth:`Joined.windows`), and whatever is filtered over a record (the pans' band-limited
acceleration, the load cells' white noise) is computed per record (:meth:`Joined.each`). The
record being corrected is record 0; its windows come first. Imports numpy alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rigsim.scenarios.core.config import ScenarioError

__all__ = ["Joined", "join"]


@dataclass(frozen=True)
class Joined:
    """Records of one truck end to end.

    Attributes
    ----------
    t_s : numpy.ndarray, s, (n,)
        A uniform time axis over all records (record 0's start and step).
    x_a_m, force_N : numpy.ndarray, (n, 4)
        Pan displacement (m) and wheel force (N), corners fl, fr, rl, rr.
    x_ref_m : numpy.ndarray, m, (n, 4), or None
        The drives, where given.
    starts : tuple of int
        Each record's first sample in the joined arrays; the last entry is n.
    times : tuple of numpy.ndarray, s
        Each record's own time axis (for the windows' times on its clock).
    """

    t_s: np.ndarray
    x_a_m: np.ndarray
    force_N: np.ndarray
    x_ref_m: np.ndarray | None
    starts: tuple
    times: tuple

    def windows(self, n: int, scored_s: float, lead_s: float, fit_windows) -> tuple[list, tuple]:
        """``n`` windows spread over each record (``fit_windows(t, n, scored_s, lead_s)`` on its own
        time axis), offset into the joined arrays: (the windows, each one's record index)."""
        wins, owners = [], []
        for i, t in enumerate(self.times):
            try:
                own = fit_windows(t, n, scored_s, lead_s)
            except ScenarioError as exc:
                if len(self.times) == 1:
                    raise
                raise ScenarioError(f"calibration record {i} ({_what(i)}): {exc}") from None
            wins += [(a + self.starts[i], s + self.starts[i], e + self.starts[i]) for a, s, e in own]
            owners += [i] * len(own)
        return wins, tuple(owners)

    def each(self, fn, x) -> np.ndarray:
        """``fn(part)`` of each record's part of ``x`` (joined along axis 0), joined again."""
        return np.concatenate([fn(x[a:b]) for a, b in zip(self.starts[:-1], self.starts[1:])])

    def window_times(self, wins, owners, fs: float) -> tuple:
        """Each window's scored span on its own record's clock (sampled at ``fs``, Hz), s."""
        out = []
        for (_, s, e), i in zip(wins, owners):
            t, a = self.times[i], self.starts[i]
            out.append((float(t[s - a]), float(t[e - 1 - a] + 1.0 / fs)))
        return tuple(out)


def _what(i: int) -> str:
    return "the record corrected" if i == 0 else f"the {_ordinal(i + 1)} record given"


def _ordinal(k: int) -> str:
    return {2: "second", 3: "third", 4: "fourth", 5: "fifth"}.get(k, f"{k}th")


def join(first, more, check) -> Joined:
    """The records end to end.

    Parameters
    ----------
    first : (t_s, x_a_m, force_N, x_ref_m or None)
        The record being corrected: time (s), pan displacement (m, (n, 4)), wheel force (N, (n, 4)),
        drive (m, (n, 4)) or None.
    more : sequence of the same
        Other records of the same truck, at the same rate; given a drive each where ``first`` has one.
    check : callable
        ``check(t_s, signals) -> (t_s, fs)``, refusing a bad record in one sentence
        (:func:`rigsim.scenarios.records.model.model_runs.check_record`).

    Raises
    ------
    ScenarioError
        A record at another rate, or with a drive missing (one sentence naming the record).
    """
    records = [first, *more]
    parts, rates = [], []
    for i, (t, x_a, force, x_ref) in enumerate(records):
        if (x_ref is None) != (first[3] is None):
            raise ScenarioError(f"{_what(i)} has {'no' if x_ref is None else 'a'} drive where the record corrected "
                                f"has {'one' if x_ref is None else 'none'}; give each record's drive x_ref_m or none")
        signals = {"x_a_m": x_a, "force_N": force} | ({} if x_ref is None else {"x_ref_m": x_ref})
        try:
            t, fs = check(t, signals)
        except ScenarioError as exc:
            if not more:
                raise
            raise ScenarioError(f"{_what(i)}: {exc}") from None
        rates.append(fs)
        parts.append((np.asarray(t, float), *(None if a is None else np.asarray(a, float) for a in (x_a, force, x_ref))))
    for i, fs in enumerate(rates[1:], 1):
        if not np.isclose(fs, rates[0], rtol=1e-6):
            raise ScenarioError(f"{_what(i)} is sampled at {fs:.6g} Hz, the record corrected at {rates[0]:.6g} Hz; "
                                "calibrate on records of one rate (resample the others)")
    sizes = [p[0].size for p in parts]
    starts = tuple(int(v) for v in np.concatenate([[0], np.cumsum(sizes)]))
    if not more:  # one record: its own arrays, to the bit
        t, x_a, force, x_ref = parts[0]
        return Joined(t, x_a, force, x_ref, starts, (t,))
    t0, dt = parts[0][0][0], parts[0][0][1] - parts[0][0][0]
    x_ref = None if first[3] is None else np.concatenate([p[3] for p in parts])
    return Joined(t0 + dt * np.arange(starts[-1]), np.concatenate([p[1] for p in parts]),
                  np.concatenate([p[2] for p in parts]), x_ref, starts, tuple(p[0] for p in parts))
