"""Servo-hydraulic DYNTRAC wheelpan actuators: parameters, nonlinear equations, linearization.

Plain numerics (numpy/numba/scipy); only :mod:`rigsim.hydraulics.bridge` imports mujoco, so import it
explicitly (``from rigsim.hydraulics.bridge import add_hydraulic_actuators, hydraulic_callbacks``).
The package re-exports the names of its modules (python-control style); each is defined once,
in the module named in its docstring.
"""

from __future__ import annotations

from .equilibrium import equilibrium_activation
from .events import event_summary, events
from .linearization import ValveLinearization, eq4_parameters, linearization
from .loop import LoopReport, assert_stable, check_design_station, check_stable, loop_matrices, loop_report
from .model import actuator_derivatives, actuator_force
from .packing import pack, unpack
from .params import INPUT_NAMES, STATE_NAMES, ActuatorParams

__all__ = ["ActuatorParams", "STATE_NAMES", "INPUT_NAMES", "pack", "unpack",
           "actuator_derivatives", "actuator_force", "equilibrium_activation", "events",
           "event_summary", "linearization", "ValveLinearization", "eq4_parameters",
           "LoopReport", "loop_matrices", "loop_report", "check_stable", "assert_stable", "check_design_station"]
