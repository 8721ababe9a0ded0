"""How a message of the records API names a parameter: by its keyword, or by a command's flag.

Every refusal of :mod:`rigsim.scenarios.records.api` is one sentence naming the parameter at fault and
the fix. Called from Python, the sentence names the keyword (``corner_map``) and writes a fix as
a call would (``corner_map='fl=COLUMN'``); called by a command, it names the command's flag
(``--map``) and writes the fix as a command line would (``--map fl=COLUMN``): the command passes
its :class:`Naming`. Imports nothing heavy.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

__all__ = ["Naming", "KEYWORDS", "FLAGS", "CLI_NAMING"]


@dataclass(frozen=True)
class Naming:
    """Keyword -> flag; a keyword without a flag keeps its own name.

    Attributes
    ----------
    flags : Mapping[str, str]
        The command's flag of each keyword it names differently (``{"corner_map": "--map"}``);
        empty: every message names keywords.
    """

    flags: Mapping = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "flags", MappingProxyType(dict(self.flags)))

    @property
    def cli(self) -> bool:
        """True when the messages are a command's (they name flags)."""
        return bool(self.flags)

    def __call__(self, key: str) -> str:
        """The name of parameter ``key`` in a message: its flag, or the keyword itself."""
        return self.flags.get(key, key)

    def setting(self, key: str, value: str | None = None) -> str:
        """How to pass ``key``: ``--map fl=COLUMN`` / ``corner_map='fl=COLUMN'``, in the text form the
        parameter takes; without ``value`` a switch, ``--normalize-dc`` / ``normalize_dc=True``."""
        if value is None:
            return self(key) if self.cli else f"{key}=True"
        return f"{self(key)} {value}" if self.cli else f"{key}={value!r}"


#: Messages for a call from Python: every parameter named by its keyword.
KEYWORDS = Naming()

#: Each flag of ``rigsim correct`` that sets a correction's field: (flag, argparse dest, where, field),
#: where is ``"linear"`` (a :class:`~rigsim.scenarios.records.options.LinearOptions` field),
#: ``"model"`` (a :class:`~rigsim.scenarios.records.options.ModelOptions` field) or ``"call"`` (a
#: keyword of :func:`~rigsim.scenarios.records.api.correct_record`). The option objects
#: (:func:`rigsim.scenarios.cli.correct.options_from_args`) and the messages' names of the fields (:data:`CLI_NAMING`) both come
#: from this table; ``--force-filter`` and ``--lvdt-filter`` take ``--force-delay`` and
#: ``--lvdt-delay`` with them.
FLAGS = (
    ("--actuator", "actuator", "linear", "actuator"),
    ("--actuators", "actuators", "linear", "actuators"),
    ("--identify", "identify", "linear", "identify"),
    ("--lowpass", "lowpass", "linear", "lowpass"),
    ("--lowpass-hz", "lowpass_hz", "linear", "lowpass_hz"),
    ("--mode", "mode", "linear", "mode"),
    ("--normalize-dc", "normalize_dc", "linear", "normalize_dc"),
    ("--model", "model", "model", "truck"),
    ("--pairs", "pairs", "model", "pairs"),
    ("--jobs", "jobs", "model", "workers"),
    ("--max-evaluations", "max_evaluations", "model", "max_evaluations"),
    ("--calibration-windows", "calibration_windows", "model", "calibration_windows"),
    ("--cab", "cab", "model", "cab"),
    ("--drift-cut-hz", "drift_cut_hz", "model", "drift_cut_hz"),
    ("--calibration", "calibration", "model", "calibration"),
    ("--calibrate-also", "calibrate_also", "model", "calibration_records"),
    ("--columns", "columns", "call", "columns"),
    ("--map", "map", "call", "corner_map"),
    ("--transient", "transient", "call", "transient"),
    ("--force-filter", "force_filter", "call", "force_filter"),
    ("--lvdt-filter", "lvdt_filter", "call", "lvdt_filter"),
)

#: The correction's fields as ``rigsim correct`` names them in its messages (from :data:`FLAGS`; the
#: model correction as a whole is ``--model``, the output ``-o``).
CLI_NAMING = Naming({field: flag for flag, _, _, field in FLAGS} | {"model": "--model", "path": "-o"})
