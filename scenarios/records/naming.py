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

__all__ = ["Naming", "KEYWORDS"]


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
