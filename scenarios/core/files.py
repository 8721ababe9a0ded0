"""Writing results: atomic files, and JSON from result objects in one place.

Every file a command writes goes through :func:`atomic_write_bytes` (a temporary file in
the same folder, then a rename), so a reader never sees half a file. Every JSON document
is made by :func:`to_json` from a result object (frozen dataclasses, mappings, sequences,
numpy arrays and scalars), so units and rounding live in the objects, not in the writers.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import pathlib
import re
import socket
import tempfile
from collections.abc import Mapping

import numpy as np

__all__ = ["atomic_write_bytes", "atomic_write_text", "remove_stale_temp_files", "to_plain", "to_json", "write_json"]


def _host() -> str:
    """This machine's name as it appears in temporary file names (letters, digits, '-'; 16 at most)."""
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname().split(".")[0])[:16] or "host"


def _running(pid: int) -> bool:
    """Whether process ``pid`` of this machine still runs (a process of another user counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temp_files(path) -> list[pathlib.Path]:
    """Remove the temporary files :func:`atomic_write_bytes` left beside ``path`` when their writer
    was killed: ``.{name}.{host}.{pid}.{random}.tmp`` of this host whose pid no longer runs.

    Files of other hosts (a shared folder) and of running processes are kept; POSIX only (elsewhere
    nothing is removed). Returns the files removed.
    """
    path = pathlib.Path(path)
    if os.name != "posix":
        return []
    prefix, host, removed = f".{path.name}.", _host(), []
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return []
    for entry in entries:
        name = entry.name
        if not (name.startswith(prefix) and name.endswith(".tmp")):
            continue
        parts = name[len(prefix):-len(".tmp")].split(".")
        if len(parts) != 3 or parts[0] != host or not parts[1].isdigit():
            continue  # another target's temporary file, another host's, or an older naming
        pid = int(parts[1])
        if pid == os.getpid() or _running(pid):
            continue
        with contextlib.suppress(FileNotFoundError):
            os.unlink(entry.path)
            removed.append(pathlib.Path(entry.path))
    return removed


def atomic_write_bytes(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temporary file in the same folder, then rename).

    The temporary file is ``.{name}.{host}.{pid}.{random}.tmp``; one left by a writer that was
    killed (its pid no longer runs on this host) is removed before writing
    (:func:`remove_stale_temp_files`).
    """
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temp_files(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{_host()}.{os.getpid()}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; results are meant to be shared
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def atomic_write_text(path, text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    atomic_write_bytes(path, text.encode("utf-8"))


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
