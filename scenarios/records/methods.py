"""The correction methods the studies compare, and the load cells' noise they are scored with.

A :class:`Method` names where T_a comes from, the low-pass T_F and how the filter is applied;
:data:`PAPER` is the paper's method, :data:`BEST` this project's (the one ``rigsim correct``
applies by default), and :data:`NOISE_N` the rms of the white noise a simulated load cell adds.
"""

from __future__ import annotations

from dataclasses import dataclass

from rigsim.scenarios.core.config import ScenarioError

__all__ = ["NOISE_N", "Method", "PAPER", "BEST", "METHODS", "method_named"]

#: Default rms of the white measurement noise added to the rig's wheel forces, N. A strain-gauge
#: load cell rated for the 156 kN actuator force resolves ~0.05 % of its range (~80 N);
#: 100 N rms at 1 kHz is that, rounded up.
NOISE_N = 100.0


@dataclass(frozen=True)
class Method:
    """How a correction is made.

    Attributes
    ----------
    name : str
    actuator : {"eq4", "identified"}
        Where T_a comes from: eq. 4 from the actuator parameters, or identified per wheel from
        the rig run's drive and pan displacement.
    lowpass : {"paper", "regularized"}
        The low-pass T_F (:mod:`rigsim.correction.output.lowpass`).
    mode : {"causal", "zerophase"}
        How the filter is applied (:func:`rigsim.correction.output.apply.correct`).
    description : str
    """

    name: str
    actuator: str
    lowpass: str
    mode: str
    description: str = ""

    def __post_init__(self) -> None:
        for field, value, allowed in (("actuator", self.actuator, ("eq4", "identified")),
                                      ("lowpass", self.lowpass, ("paper", "regularized")),
                                      ("mode", self.mode, ("causal", "zerophase"))):
            if value not in allowed:
                raise ScenarioError(f"correction {field} must be one of {', '.join(allowed)}, got {value!r}")


PAPER = Method("paper", "eq4", "paper", "causal",
               "eq. 4 from the actuator parameters at each wheel's static load, paper's low-pass (16/24 Hz), causal")
BEST = Method("best", "identified", "regularized", "zerophase",
              "T_a identified per corner from independent random drives at the test drive's rms (rigsim identify), "
              "30 Hz 6th-order Butterworth, zero-phase")
METHODS = (PAPER, BEST)


def method_named(actuator: str, lowpass: str, mode: str) -> Method:
    """The :class:`Method` with these settings: ``paper`` or ``best`` when it is one of them."""
    for m in METHODS:
        if (m.actuator, m.lowpass, m.mode) == (actuator, lowpass, mode):
            return m
    return Method("custom", actuator, lowpass, mode, f"T_a {actuator}, low-pass {lowpass}, {mode}")
