"""Progress of many independent jobs on stderr: a tqdm bar on a terminal, else one line per job.

:class:`Progress` counts finished, failed and remaining jobs and gives an ETA; ``rigsim sweep``
(cases) and ``rigsim programme`` (records) report through it. :func:`format_eta` writes a
duration as ``HH:MM:SS``. Imports tqdm only when a bar is drawn.
"""

from __future__ import annotations

import sys
import time

__all__ = ["Progress", "format_eta"]


def format_eta(seconds: float) -> str:
    """A duration (s) as ``HH:MM:SS``, with days in front from 24 h on (``3d 04:05:06``)."""
    if not seconds >= 0 or seconds == float("inf"):
        return "--:--:--"
    s = int(round(seconds))
    days, s = divmod(s, 86400)
    clock = f"{s // 3600:02d}:{s % 3600 // 60:02d}:{s % 60:02d}"
    return f"{days}d {clock}" if days else clock


class Progress:
    """Finished / failed / remaining counts and an ETA: a tqdm bar on a terminal, else one line
    per finished job on stderr.

    Parameters
    ----------
    total : int
        Jobs in all.
    skipped : int
        Jobs finished by an earlier run (counted as done from the start).
    enabled : bool
        False: nothing is shown (``--quiet``).
    stream : file, optional
        Where to show it (default: stderr).
    unit : str
        What a job is, for the bar (``"case"``, ``"record"``).
    """

    def __init__(self, total: int, skipped: int, enabled: bool, stream=None, unit: str = "case"):
        self.total, self.done, self.failed = total, skipped, 0
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.t0 = time.perf_counter()
        self.started = 0
        self.bar = None
        if enabled and getattr(self.stream, "isatty", lambda: False)():
            from tqdm import tqdm

            self.bar = tqdm(total=total, initial=skipped, unit=unit, file=self.stream, dynamic_ncols=True,
                            bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining}] {postfix}")
            self._postfix()

    def _postfix(self) -> None:
        self.bar.set_postfix_str(f"failed {self.failed}, remaining {self.total - self.done}")

    def update(self, name: str, ok: bool, error: str | None = None, wall_time_s: float | None = None) -> None:
        """One job finished: ``name``, whether it succeeded, its error (one sentence) and wall time (s)."""
        self.done += 1
        self.started += 1
        self.failed += 0 if ok else 1
        if not self.enabled:
            return
        note = f"{name}: {'ok' if ok else 'FAILED: ' + str(error)} ({wall_time_s or 0:.1f} s)"
        if self.bar is not None:
            self.bar.update(1)
            self._postfix()
            if not ok:
                self.bar.write(note, file=self.stream)
            return
        elapsed = time.perf_counter() - self.t0
        left = self.total - self.done
        eta = elapsed / self.started * left
        print(f"[{self.done}/{self.total} finished, {self.failed} failed, {left} remaining, ETA "
              f"{format_eta(eta)}] {note}", file=self.stream, flush=True)

    def close(self) -> None:
        """Close the bar (if one is drawn)."""
        if self.bar is not None:
            self.bar.close()
