"""On-disk entries of compiled numba ``cfunc`` code, for :func:`rigsim.hydraulics.kernels.make_raw_callbacks`.

The design (what the key holds and why numba's own cache is not used) is in
:mod:`rigsim.hydraulics.kernels`. This module only stores and loads entries, given a key:

* :func:`save_entry` writes ``hydraulics-callbacks-<sha256 of the key>.bin``: a magic line, the
  header length, a JSON header (the key itself, the symbol and library names, the byte counts
  and the SHA-256 of the payload) and the payload (numba's object code and linking bitcode of
  each function). No pickle: loading an entry runs no Python code from the file. Written
  atomically (temporary file in the folder, then rename), so concurrent writers are harmless
  and a reader never sees half an entry; the 16 most recently used entries are kept.
* :func:`load_entry` verifies magic, key (compared whole, not only its hash), payload digest,
  that every external symbol the code needs resolves in this process (LLVM would abort the
  process otherwise), then hands the object code to numba's code generator. Any failure raises
  :class:`RejectedEntry`; the caller deletes the entry and compiles.

Where: ``$RIGSIM_CACHE_DIR``, else ``$XDG_CACHE_HOME/rigsim``, else ``~/.cache/rigsim``;
``RIGSIM_NO_CACHE=1`` turns the cache off (:func:`cache_directory` returns None).
"""

from __future__ import annotations

import hashlib
import json
import os
import pathlib
import re
import tempfile

__all__ = ["cache_directory", "entry_path", "key_digest", "load_entry", "save_entry", "RejectedEntry",
           "STATS", "KEEP_ENTRIES"]

_MAGIC = b"rigsim numba cfunc cache\n"
_PREFIX = "hydraulics-callbacks-"
#: Entries kept in the folder (the most recently used).
KEEP_ENTRIES = 16
#: What this process did: callbacks compiled, loaded from an entry, entries rejected, saved.
STATS = {"compiled": 0, "loaded": 0, "rejected": 0, "saved": 0}
# A use of a runtime environment in the IR (an instruction operand, not the global's definition):
# code needing one cannot be restored from object code alone, so it is never stored.
_ENV_USE = re.compile(r"^[ \t]+.*@_ZN08NumbaEnv", re.MULTILINE)


class RejectedEntry(Exception):
    """An entry that is corrupt, belongs to another key, or cannot be loaded here."""


def cache_directory() -> pathlib.Path | None:
    """Folder of the cache, or None when ``RIGSIM_NO_CACHE`` is set (to anything but 0)."""
    if os.environ.get("RIGSIM_NO_CACHE", "").strip() not in ("", "0"):
        return None
    if os.environ.get("RIGSIM_CACHE_DIR"):
        return pathlib.Path(os.environ["RIGSIM_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache"
    return pathlib.Path(base) / "rigsim"


def key_digest(key: dict) -> str:
    """SHA-256 (hex) of the canonical JSON of ``key``."""
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()


def entry_path(directory: pathlib.Path, digest: str) -> pathlib.Path:
    """The file of the entry with key digest ``digest``."""
    return directory / f"{_PREFIX}{digest}.bin"


def save_entry(directory: pathlib.Path, key: dict, digest: str, functions) -> bool:
    """Store compiled ``cfunc`` objects under ``key``.

    Parameters
    ----------
    directory : pathlib.Path
    key : dict
        JSON-serializable; stored whole.
    digest : str
        ``key_digest(key)``.
    functions : sequence of (str, numba CFunc)
        Names and compiled callbacks, in the order :func:`load_entry` returns them.

    Returns
    -------
    bool
        False if the code needs a runtime environment (then nothing is written).
    """
    parts, chunks = [], []
    for name, cf in functions:
        library = cf._library
        if _ENV_USE.search(str(library._final_module)):
            return False
        lib_name, kind, (obj, bitcode) = library.serialize_using_object_code()
        if kind != "object":  # pragma: no cover - a numba that serializes otherwise
            return False
        parts.append({"name": name, "library": lib_name, "symbol": cf.native_name,
                      "object_bytes": len(obj), "bitcode_bytes": len(bitcode)})
        chunks += [obj, bitcode]
    payload = b"".join(chunks)
    header = json.dumps({"key": key, "key_sha256": digest, "parts": parts,
                         "payload_sha256": hashlib.sha256(payload).hexdigest()}, sort_keys=True).encode()
    directory.mkdir(parents=True, exist_ok=True)
    path = entry_path(directory, digest)
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(_MAGIC + str(len(header)).encode() + b"\n" + header + payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        pathlib.Path(tmp).unlink(missing_ok=True)
        raise
    STATS["saved"] += 1
    _prune(directory)
    return True


def _prune(directory: pathlib.Path) -> None:
    def mtime(p: pathlib.Path) -> float:
        try:
            return p.stat().st_mtime
        except OSError:
            return 0.0

    entries = sorted(directory.glob(f"{_PREFIX}*.bin"), key=mtime, reverse=True)
    for old in entries[KEEP_ENTRIES:]:
        try:
            old.unlink(missing_ok=True)
        except OSError:
            pass


def load_entry(path: pathlib.Path, key: dict, digest: str, names) -> list:
    """The code of an entry: ``[(code library, address of the function), ...]`` in ``names`` order.

    Raises
    ------
    FileNotFoundError
        No entry (a plain miss).
    RejectedEntry
        Anything else wrong with the entry.
    """
    blob = path.read_bytes()
    try:
        return _restore(blob, key, digest, list(names))
    except RejectedEntry:
        raise
    except Exception as exc:  # garbage of any kind in the file
        raise RejectedEntry(f"unreadable entry ({exc!r})") from None


def _restore(blob: bytes, key: dict, digest: str, names: list) -> list:
    import llvmlite.binding as ll
    from numba.core.registry import cpu_target
    from numba.core.runtime import rtsys

    if not blob.startswith(_MAGIC):
        raise RejectedEntry("not an entry of this cache")
    size, _, rest = blob[len(_MAGIC):].partition(b"\n")
    n = int(size)
    header, payload = json.loads(rest[:n]), rest[n:]
    if header["key_sha256"] != digest or header["key"] != key:
        raise RejectedEntry("the entry belongs to another key")
    if hashlib.sha256(payload).hexdigest() != header["payload_sha256"]:
        raise RejectedEntry("the payload does not match its digest")
    parts = header["parts"]
    if [p["name"] for p in parts] != names:
        raise RejectedEntry("the entry holds other functions")
    ctx = cpu_target.target_context
    rtsys.initialize(ctx)  # the numba runtime's symbols (NRT_*), as a compilation would do
    codegen, out, pos = ctx.codegen(), [], 0
    for p in parts:
        n_obj, n_bc = int(p["object_bytes"]), int(p["bitcode_bytes"])
        obj, bitcode = payload[pos:pos + n_obj], payload[pos + n_obj:pos + n_obj + n_bc]
        pos += n_obj + n_bc
        module = ll.parse_bitcode(bitcode)
        needed = [f.name for f in module.functions if f.is_declaration and not f.name.startswith("llvm.")]
        needed += [g.name for g in module.global_variables if g.is_declaration]
        missing = [s for s in needed if not ll.address_of_symbol(s)]
        if missing:  # checked first: LLVM aborts the process on an unresolved symbol
            raise RejectedEntry(f"symbols not available in this process: {missing}")
        library = codegen.unserialize_library((p["library"], "object", (obj, bitcode)))
        address = library.get_pointer_to_function(p["symbol"])
        if not address:
            raise RejectedEntry(f"the entry has no function {p['symbol']}")
        out.append((library, address))
    if pos != len(payload):
        raise RejectedEntry("the payload is longer than its parts")
    return out
