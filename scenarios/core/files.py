"""Writing results: atomic files, and JSON from result objects in one place.

Every file a command writes goes through :func:`atomic_write_bytes`
(:mod:`rigsim.correction.io.atomic`: a temporary file in the same folder, then a rename), so a reader never
sees half a file. Every JSON document
is made by :func:`to_json` from a result object (frozen dataclasses, mappings, sequences,
numpy arrays and scalars), so units and rounding live in the objects, not in the writers.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib
from collections.abc import Mapping

import numpy as np

# The atomic writer's one home is rigsim.correction.io.atomic (correction may not import scenarios); these
# names are re-exported here for the result writers of scenarios.
from rigsim.correction.io.atomic import atomic_write_bytes, atomic_write_text, remove_stale_temp_files  # noqa: E402

__all__ = ["atomic_write_bytes", "atomic_write_text", "remove_stale_temp_files", "to_plain", "to_json", "write_json"]


def to_plain(obj):
    """``obj`` as plain JSON types: dataclasses (their ``to_dict()`` if they define one, else
    their fields), mappings, sequences, numpy arrays and scalars, paths as strings."""
    to_dict = getattr(obj, "to_dict", None)
    if callable(to_dict) and dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return to_plain(to_dict())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, Mapping):
        return {str(k): to_plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_plain(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer, int)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        return float(obj)
    if isinstance(obj, complex):
        return {"re": obj.real, "im": obj.imag}
    if isinstance(obj, pathlib.PurePath):
        return str(obj)
    if obj is None or isinstance(obj, str):
        return obj
    raise TypeError(f"cannot write a {type(obj).__name__} to JSON")


def _finite_or_null(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite_or_null(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite_or_null(v) for v in obj]
    return obj


def to_json(obj) -> str:
    """The JSON text of a result object (indent 2, a trailing newline; NaN and infinities
    written as ``null``, so every JSON reader can read the file)."""
    return json.dumps(_finite_or_null(to_plain(obj)), indent=2, allow_nan=False) + "\n"


def write_json(path, obj) -> pathlib.Path:
    """Write ``to_json(obj)`` to ``path`` atomically; returns the path."""
    path = pathlib.Path(path)
    atomic_write_text(path, to_json(obj))
    return path
