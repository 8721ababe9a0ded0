"""The one error class a lab's script catches: :class:`RigsimError`.

Every refusal rigsim makes is one sentence naming the field, file, channel or option at fault and
the fix (``str(error)``), raised as a subclass of :class:`RigsimError` before any work is done:
a scenario or command option (``ScenarioError``), a measured file (``MeasuredDataError``), an
actuator file or fit (``ActuatorFileError``, ``ActuatorFitError``, ``WiringError``), a correction
(``CorrectionError``), a road profile (``ProfileError``), a truck that cannot stand
(``EquilibriumError``), an iteration that diverges (``IterationStabilityError``), and a simulation
that MuJoCo warned about (``SimulationError``, naming the simulated time). The classes of bad
input are also ``ValueError``; ``SimulationError`` is also a ``RuntimeError``.

This module imports nothing, so every layer of the package can raise its errors as rigsim's.
"""

from __future__ import annotations

__all__ = ["RigsimError"]


class RigsimError(Exception):
    """Base of every one-sentence error of rigsim: ``str(error)`` names what is at fault and the fix.

    Examples
    --------
    >>> import rigsim
    >>> try:
    ...     rigsim.read_record("no such file.csv")
    ... except rigsim.RigsimError as error:
    ...     print(type(error).__name__, isinstance(error, ValueError))
    ScenarioError True
    """
