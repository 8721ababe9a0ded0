"""Tools for taking a corrected force's error apart by cause: runs and a correction with one cause removed.

The output correction's error against the road has several causes: what the identified T_a gets
wrong, the rig's own nonlinearity and coupling, the leaf springs' dry friction, the band limit,
lift-off and noise. Removing one cause at a time takes the error apart:

* :func:`with_friction`: a scenario without the leaf springs' dry friction;
* :func:`linear_pans_run`: a road-mode run whose pans follow the profile through the linearized
  plant (each wheel's own path, or the whole 4 x 4 plant) instead of the nonlinear rig;
* :class:`ExactLinearCorrection`: the zero-phase correction by the linearized plant's exact
  frequency response, in place of an identified T_a.

``benchmarks/nrmse_decomposition.py`` (the NRMSE on the paper's cases) and
``benchmarks/generalization_blame.py`` (the DLC error of the generalization suite) use them.
Nothing here corrects a measured record: these are diagnostics of the simulation.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rigsim.correction.output.filters import reference_filter
from rigsim.correction.output.lowpass import BAND_LOWPASS, BAND_MODE
from rigsim.scenarios.core.config import Scenario
from rigsim.scenarios.core.drive import Drive
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run

__all__ = ["KERNEL_WINDOW_S", "with_friction", "linear_pans_run", "kernel_tail", "ExactLinearCorrection"]

#: Length of the grid on which the exact linear correction's kernel is evaluated for its margins, s.
KERNEL_WINDOW_S = 64.0


def with_friction(sc: Scenario, friction: bool) -> Scenario:
    """``sc`` with the leaf springs' dry friction as it is (``friction`` True) or at 0 N (False)."""
    if friction:
        return sc
    return dataclasses.replace(sc, vehicle=dataclasses.replace(
        sc.vehicle, spring_friction_front_N=0.0, spring_friction_rear_N=0.0))


def linear_pans_run(sc: Scenario, diagonal: bool):
    """A road-mode run of ``sc`` whose pans follow the profile through the linearized plant.

    Parameters
    ----------
    sc : Scenario
    diagonal : bool
        True: each pan through its own wheel's path T_a of the plant; False: through the whole
        4 x 4 plant (each pan also moved by the other posts' drives, through the truck loading
        the actuators). Friction never enters the linearization.

    Returns
    -------
    rigsim.scenarios.core.results.RunResult
        As :func:`rigsim.scenarios.core.run.run` in road mode, the pans' motion replaced.
    """
    plant = Rig(sc).linearize()

    def through_linear_ta(drive: Drive) -> Drive:
        return plant.pan_drive(drive, diagonal=diagonal)

    return run(sc, "road", pan_drive=through_linear_ta)


def kernel_tail(h: np.ndarray, tol: float) -> int:
    """Samples after which sum |h[k:]| <= ``tol`` (``h``: one side of a kernel, from lag 0 outwards)."""
    tail = np.cumsum(np.abs(h)[::-1])[::-1]
    idx = np.flatnonzero(tail > tol)
    return 0 if idx.size == 0 else int(idx[-1] + 1)


class ExactLinearCorrection:
    """Zero-phase correction of one wheel by the linearized plant's own path: ``|T_F| / T_a(f)``.

    Duck-types what :func:`rigsim.correction.output.apply.correct_zero_phase` needs of a
    :class:`~rigsim.correction.output.correction_filter.CorrectionFilter` (``fs``,
    ``zero_phase_response``, ``transient_samples``); its margins come from its own kernel (on a
    :data:`KERNEL_WINDOW_S` grid) at ``tolerance``. T_F is the project's band limit
    (:data:`rigsim.correction.output.lowpass.BAND_LOWPASS`).

    Parameters
    ----------
    plant : rigsim.scenarios.core.plant.PlantLinearization
    wheel : int
        The wheel (0-3, :data:`rigsim.mjcf.names.CORNERS`' order) whose own path T_a = x_a / x_ref is inverted.
    fs : float, Hz
        Sample rate of the forces it corrects.
    tolerance : float, 1
        Tail of the kernel (sum of |taps|) left outside the margins.
    cache : dict, optional
        Frequency grid -> the plant's (nf, 4, 4) response; pass one dict to the four wheels'
        corrections to compute it once.
    """

    def __init__(self, plant, wheel: int, fs: float, tolerance: float, cache: dict | None = None):
        self.plant, self.wheel, self.fs = plant, int(wheel), float(fs)
        self.cache = {} if cache is None else cache
        self.reference = reference_filter(fs, BAND_LOWPASS, settling_tolerance=tolerance)
        m = int(KERNEL_WINDOW_S * fs)
        kernel = np.fft.irfft(self.zero_phase_response(np.fft.rfftfreq(m, 1.0 / fs)), m)
        self.margins = (kernel_tail(kernel[:m // 2], tolerance), kernel_tail(kernel[m // 2:][::-1], tolerance))

    def zero_phase_response(self, f_hz) -> np.ndarray:
        """|T_F| with T_a^-1's phase at ``f_hz`` (Hz), complex."""
        f = np.atleast_1d(np.asarray(f_hz, dtype=float))
        key = (f.size, float(f[0]), float(f[-1]))
        if key not in self.cache:
            self.cache[key] = self.plant.frequency_response(f)
        ta = self.cache[key][:, self.wheel, self.wheel]
        return self.reference.zero_phase_response(f) / ta

    def transient_samples(self, mode: str = BAND_MODE) -> tuple[int, int]:
        """Samples (start, end) the correction's transients spoil."""
        return self.margins

    def transient_mask(self, n: int) -> np.ndarray:
        """Samples (bool, (n,)) outside the start and end transients."""
        mask = np.zeros(n, dtype=bool)
        mask[self.margins[0]:n - self.margins[1]] = True
        return mask
