"""rigsim: a servo-hydraulic four-post road simulator in MuJoCo, and the correction of the wheel
forces measured on such rigs.

A lab's script needs nothing but ``import rigsim``::

    import rigsim
    record = rigsim.read_record("messung.csv")
    result = rigsim.correct_record(record, rigsim.LinearOptions(actuators="actuators.toml"))
    result.write("korrigiert.csv")

The names here are the lab's API: reading a record (:func:`read_record`), identifying T_a from
its drive and LVDT channels (:func:`identify_record`, :class:`RecordedIdentification`),
correcting it linearly or by a truck model calibrated on it (:func:`correct_record`, with
:class:`LinearOptions` or :class:`ModelOptions`,
:class:`CorrectionResult`, :class:`ChannelLoads`, the truck model's :class:`Calibration`, kept
for the next record of the truck as a :class:`SavedCalibration` file, :func:`read_calibration`), and the
one error class (:class:`RigsimError`). The sub-packages are the simulator's layers:
:mod:`rigsim.mjcf` (the truck and rig as MJCF), :mod:`rigsim.hydraulics` (the actuators'
equations), :mod:`rigsim.correction` (transfer functions, filters, identification, metrics and the
readers of measured data; no simulator) and :mod:`rigsim.scenarios` (everything that runs
scenarios, and the ``rigsim`` command).

The names load on first use (PEP 562): ``import rigsim`` itself imports nothing, so every layer
can raise :class:`RigsimError` without an import circle.
"""

from __future__ import annotations

import importlib

from rigsim.errors import RigsimError

__all__ = ["read_record", "identify_record", "correct_record", "LinearOptions", "ModelOptions", "CorrectionResult",
           "ChannelLoads", "SavedCalibration", "read_calibration",
           "RecordedIdentification", "Calibration", "RigsimError", "__version__"]

#: The distribution's version (pyproject.toml's).
__version__ = "0.1.0"

#: Each public name and the module it lives in.
_HOMES = {
    "read_record": "rigsim.scenarios.records.api",
    "identify_record": "rigsim.scenarios.records.api",
    "correct_record": "rigsim.scenarios.records.api",
    "LinearOptions": "rigsim.scenarios.records.options",
    "ModelOptions": "rigsim.scenarios.records.options",
    "CorrectionResult": "rigsim.scenarios.records.api",
    "ChannelLoads": "rigsim.scenarios.records.api",
    "RecordedIdentification": "rigsim.scenarios.records.recorded",
    "Calibration": "rigsim.scenarios.records.model.result",
    "SavedCalibration": "rigsim.scenarios.records.model.saved",
    "read_calibration": "rigsim.scenarios.records.model.saved",
}


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'rigsim' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
