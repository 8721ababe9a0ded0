"""How the cases of a sweep are corrected and scored: the evaluation keys of a grid's ``[sweep]``.

::

    [sweep]
    actuator = "identified"          # T_a: "identified" (default, from each rig run) or "eq4"
    lowpass = "regularized"          # T_F: "regularized" (default) or "paper"
    correction_mode = "zerophase"    # "zerophase" (default, offline) or "causal"
    noise_N = 100.0                  # rms of the load cell's noise, N (default: the paper study's)
    settling_tolerance = 0.001       # samples inside the filters' transients are not scored

The defaults are :data:`rigsim.scenarios.studies.scoring.BEST` with
:data:`rigsim.scenarios.studies.scoring.NOISE_N` and :data:`rigsim.scenarios.studies.scoring.SETTLING_TOLERANCE`,
the method, noise and scored samples of ``rigsim paper``: a case of a sweep and the same
scenario in the paper study give the same corrected DLC. The identified T_a is fitted to each
rig run's own record: short records (seen: some seeds at 4-6 s) can give a fit whose inverse
cannot be discretized, and the case fails with that error; use longer records or ``eq4``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rigsim.correction.io.tomlfile import number
from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.studies.scoring import NOISE_N, SETTLING_TOLERANCE, Method, method_named

__all__ = ["EvalSettings", "SETTING_KEYS", "parse_settings"]

_CHOICES = {
    "actuator": ("identified", "eq4"),
    "lowpass": ("regularized", "paper"),
    "correction_mode": ("zerophase", "causal"),
}

#: The evaluation keys of ``[sweep]``.
SETTING_KEYS = (*_CHOICES, "noise_N", "settling_tolerance")


@dataclass(frozen=True)
class EvalSettings:
    """How each case is corrected and scored (:func:`rigsim.scenarios.studies.scoring.score_pair`).

    Parameters
    ----------
    actuator : {"identified", "eq4"}
        Where T_a comes from: identified per wheel from the rig run's drive and pan
        displacement, or eq. 4 from the actuator parameters.
    lowpass : {"regularized", "paper"}
        The correction's low-pass T_F.
    correction_mode : {"zerophase", "causal"}
        Offline zero-phase correction or the causal (real-time) filter.
    noise_N : float, N
        rms of the white measurement noise added to the rig's wheel forces (0: none).
    settling_tolerance : float, 1
        Tolerance of the correction's transients (default: the paper study's); samples inside
        them are left out of the band-limited DLCs and the NRMSE.
    """

    actuator: str = "identified"
    lowpass: str = "regularized"
    correction_mode: str = "zerophase"
    noise_N: float = NOISE_N
    settling_tolerance: float = SETTLING_TOLERANCE

    @property
    def method(self) -> Method:
        """The :class:`~rigsim.scenarios.studies.scoring.Method` of these settings (``best`` by default)."""
        return method_named(self.actuator, self.lowpass, self.correction_mode)

    def as_dict(self) -> dict:
        """The settings as a plain dict (JSON, fingerprints, worker arguments)."""
        return dataclasses.asdict(self)


def parse_settings(table: Mapping, where: str = "") -> EvalSettings:
    """The evaluation settings from a grid's ``[sweep]`` table (other keys are ignored here).

    Parameters
    ----------
    table : Mapping
        The ``[sweep]`` table.
    where : str
        Prefix of the messages (the grid file's name and ": ").

    Raises
    ------
    ScenarioError
        A value out of its choices or range, in one sentence naming the key.
    """
    kw: dict[str, Any] = {}
    for key, allowed in _CHOICES.items():
        if key in table:
            if table[key] not in allowed:
                raise ScenarioError(f"{where}sweep.{key} must be {' or '.join(repr(a) for a in allowed)}, "
                                    f"got {table[key]!r}")
            kw[key] = table[key]
    if "noise_N" in table:
        kw["noise_N"] = number(f"{where}sweep.noise_N", table["noise_N"], lo=0.0, error=ScenarioError)
    if "settling_tolerance" in table:
        tol = number(f"{where}sweep.settling_tolerance", table["settling_tolerance"], lo=0.0, hi=1.0,
                     lo_open=True, error=ScenarioError)
        if tol == 1.0:
            raise ScenarioError(f"{where}sweep.settling_tolerance must be < 1, got {table['settling_tolerance']!r}")
        kw["settling_tolerance"] = tol
    return EvalSettings(**kw)
