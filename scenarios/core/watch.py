"""Watching a run: MuJoCo warnings as errors with their simulated time, progress, schedules.

dm_control's rule: a MuJoCo warning during a run is a :class:`SimulationError`, not a line in
a log file. :class:`Watch` reads MuJoCo's warning counters every 10 ms of simulated time and
names the window of the first warning; :func:`mujoco_warnings_captured` keeps MuJoCo from
printing them or writing ``MUJOCO_LOG.TXT``.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable

import mujoco
import numpy as np

from rigsim.errors import RigsimError

__all__ = ["SimulationError", "ProgressFn", "SayFn", "Watch", "mujoco_warnings_captured", "output_schedule",
           "CHECK_EVERY_S"]

#: MuJoCo warnings are checked this often and reported with this resolution, s.
CHECK_EVERY_S = 0.01

ProgressFn = Callable[[float, float], None]
"""progress(simulated_s, total_s), in s, called a few hundred times per run."""

SayFn = Callable[[str], None]
"""say(line): one line of progress text of a study (which step it is at), for the terminal."""


class SimulationError(RigsimError, RuntimeError):
    """A run that went wrong while simulating (MuJoCo warning, divergence); names the time."""


def _check_warnings(data: mujoco.MjData, t0: float, t1: float) -> None:
    # One read of the counters as an array (0.2 us); iterating the structs costs ~70 us a check.
    number = data.warning.number
    if number.any():
        kind = int(np.flatnonzero(number)[0])
        text = mujoco.mju_warningText(kind, int(data.warning.lastinfo[kind]))
        raise SimulationError(f"MuJoCo warning between t = {t0:.4f} s and t = {t1:.4f} s of simulated time: {text}")


@contextlib.contextmanager
def mujoco_warnings_captured():
    """Route MuJoCo's warning messages into a list for the duration of a run.

    By default MuJoCo prints each warning and appends it to ``MUJOCO_LOG.TXT`` in the current
    folder; a run must leave no such file behind. The warnings still stop the run: the
    :class:`Watch` reads MuJoCo's warning counters. The previous handler is restored on exit.
    """
    previous = mujoco.get_mju_user_warning()
    messages: list[str] = []
    mujoco.set_mju_user_warning(messages.append)
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


def output_schedule(drive, dt_s: float, rate_hz: float) -> tuple[int, int, int]:
    """(k0, decim, n_out): the first step at t >= 0, the steps per output sample, the samples.

    Parameters
    ----------
    drive : Drive or RoadDrive
        Its ``n_steps`` and ``first_step(t)`` (a lead-in has t < 0).
    dt_s : float, s
        Time step.
    rate_hz : float, Hz
        Output rate; must divide ``1 / dt_s``.
    """
    decim = int(round(1.0 / (rate_hz * dt_s)))
    k0 = drive.first_step(-0.5 * dt_s)
    return k0, decim, (drive.n_steps - 1 - k0) // decim + 1


class Watch:
    """Checks MuJoCo's warnings every 10 ms of simulated time and reports progress.

    Call :meth:`tick` after every step ``k``; it raises :class:`SimulationError` naming the
    simulated-time window of the first warning, and :meth:`finish` after the last step.

    Parameters
    ----------
    drive : Drive or RoadDrive
        The drive being run (its ``n_steps`` and ``time_at(k)``, s).
    dt_s : float, s
    progress : ProgressFn, optional
    extra : callable, optional
        ``extra(data, t_s)`` runs at every check and raises on a bad state.
    """

    def __init__(self, drive, dt_s: float, progress: ProgressFn | None = None, extra=None):
        self.time_at = drive.time_at
        self.n = drive.n_steps
        self.dt = dt_s
        self.progress = progress
        self.extra = extra
        self.check = max(1, int(round(CHECK_EVERY_S / dt_s)))
        self.report = max(self.check, self.n // 200)
        self.t0 = self.time_at(0)
        self.total = self.time_at(self.n - 1) - self.t0

    def tick(self, data: mujoco.MjData, k: int) -> None:
        """After step ``k`` of a step-by-step loop: checks every :data:`CHECK_EVERY_S`."""
        if k % self.check == self.check - 1:
            self.checked(data, k - self.check + 1, k)

    def checked(self, data: mujoco.MjData, k_first: int, k_last: int) -> None:
        """After steps ``k_first`` .. ``k_last`` (one window, e.g. a rollout): raise
        :class:`SimulationError` naming the window's simulated time if MuJoCo warned in it or the
        ``extra`` check fails; report progress when a report step was passed."""
        t_last = self.time_at(k_last)
        _check_warnings(data, self.time_at(k_first), t_last + self.dt)
        if self.extra is not None:
            self.extra(data, t_last)
        if self.progress is not None and k_last // self.report > (k_first - 1) // self.report:
            self.progress(t_last - self.t0, self.total)

    @staticmethod
    def warned(data: mujoco.MjData) -> bool:
        """Whether MuJoCo counted a warning in ``data`` since its counters were last cleared."""
        return bool(data.warning.number.any())

    def finish(self, data: mujoco.MjData) -> None:
        t = self.time_at(self.n - 1)
        _check_warnings(data, t - self.check * self.dt, t + self.dt)
        if self.extra is not None:
            self.extra(data, t)
