"""numba-compiled twin of :mod:`rigsim.hydraulics.model`, over raw float64 arrays and raw pointers.

The scalar kernels of :mod:`rigsim.hydraulics.model` are ``register_jitable``: the functions here
compile that very source, so the compiled and the plain-Python reference paths share one set
of equations (tests check they agree). Nothing here imports mujoco: the MuJoCo callbacks are
built by :func:`make_raw_callbacks` from integer byte offsets that :mod:`rigsim.hydraulics.bridge`
finds and verifies at runtime.

Cache of the compiled callbacks
-------------------------------
Compiling the three callbacks takes seconds, so their machine code is kept on disk between
processes. numba's own ``cfunc(cache=True)`` is not used: its key holds the signature, the CPU,
the bytecode of the decorated function, its closure variables and the modification time of
*this* file only, so an edit of :mod:`rigsim.hydraulics.model` (the equations) or of
:mod:`rigsim.hydraulics.packing` (``LAYOUT_TAG`` and the slot indices, frozen into the code as
constants) would reuse stale machine code. This module keeps its own cache instead; an entry
is used only if everything the machine code depends on is unchanged. The key (a JSON
document, stored whole in the entry and compared on load; its SHA-256 names the file) holds:

* the byte offsets (:class:`RawOffsets`) and the packing constants (``LAYOUT_TAG``, ``NSTATE``,
  ``NPACK``, ``P_*``), the C signature and a format number;
* the text of ``kernels.py``, ``model.py``, ``packing.py`` and ``params.py`` as read at import,
  and a fingerprint of what numba compiles from memory: the bytecode, constants and names of
  every function, and every number and string constant, of this module, ``model`` and ``packing``;
* the versions of Python, numba, llvmlite, LLVM, numpy and mujoco, the LLVM target triple,
  CPU name and CPU features (numba's ``magic_tuple``) and every ``NUMBA_*`` environment variable.

An entry (:mod:`rigsim.hydraulics.callback_cache`: ``hydraulics-callbacks-<sha256>.bin``) holds a
header (the key, symbol names, sizes, the SHA-256 of the payload) and numba's object code of
each callback; no pickle. It is written atomically (temporary file, then rename; concurrent
writers are harmless) and verified on load: header, key, payload digest, every external symbol
resolvable, then :mod:`rigsim.hydraulics.bridge` runs the loaded callbacks once against the
plain-Python reference equations. Anything unexpected is a miss: the entry is deleted, the
callbacks are compiled afresh and a new entry written. Each compilation names its callbacks
with a fresh random suffix, so code loaded from an entry never collides with code compiled in
the same process (the helpers they inline or call, e.g. ``derivatives_core``, are weak symbols
named after their source function and flags: a name shared with an in-process compilation
always stands for the same source, since the source is in the key).

Where: ``$RIGSIM_CACHE_DIR``, else ``$XDG_CACHE_HOME/rigsim``, else ``~/.cache/rigsim``;
``RIGSIM_NO_CACHE=1`` compiles in every process and touches no file. The 16 most recently used
entries are kept. :func:`cache_info` tells what this process did (compiled, loaded, rejected).
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib.metadata
import os
import pathlib
import platform
import secrets
import sys
from dataclasses import dataclass, field
from typing import Callable, NamedTuple

import numpy as np
from numba import cfunc, njit, types
from numba.extending import intrinsic

from . import callback_cache as _cache
from . import model as _model
from . import packing as _packing
from . import params as _params
from .model import derivatives_core, force_core
from .packing import LAYOUT_TAG, NPACK, NSTATE, P_NPACK, P_NSTATE, P_TAG

__all__ = ["derivatives_array", "force_array", "step_euler", "RawOffsets", "RawCallbacks",
           "make_raw_callbacks", "CALLBACK_SIGNATURE", "cache_key", "cache_info"]


@njit
def derivatives_array(x, u, prm, out):
    """Compiled ``out[:] = f(x, u)``: x (5,) states, u (3,) inputs (x_ref, x_a, v_a), prm packed."""
    derivatives_core(x[0], x[1], x[2], x[3], x[4], u[0], u[1], u[2], prm, out)


@njit
def force_array(x, v_a, prm):
    """Compiled actuator force (N) from states ``x`` (5,) and pan velocity ``v_a`` (m/s)."""
    return force_core(x[2], x[3], v_a, prm)


@njit
def step_euler(x, x_ref, x_a, v_a, prm, dt, n):
    """Advance the states ``n`` explicit-Euler steps of ``dt`` with constant inputs (in place)."""
    out = np.empty(NSTATE)
    for _ in range(n):
        derivatives_core(x[0], x[1], x[2], x[3], x[4], x_ref, x_a, v_a, prm, out)
        for k in range(NSTATE):
            x[k] += dt * out[k]


# ---------------------------------------------------------------------------------------------
# Raw-pointer access for the MuJoCo callbacks.
def _pointer_intrinsic(elem):
    @intrinsic
    def as_pointer(typingctx, addr):
        sig = types.CPointer(elem)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(types.CPointer(elem)))

        return sig, codegen

    return as_pointer


_f64_at = _pointer_intrinsic(types.float64)
_i32_at = _pointer_intrinsic(types.int32)
_i64_at = _pointer_intrinsic(types.int64)


class RawOffsets(NamedTuple):
    """Byte offsets of the fields the callbacks read, inside mjModel and mjData (ints)."""

    m_nuser_actuator: int  # mjtSize (int64)
    m_actuator_actadr: int  # int*
    m_actuator_actnum: int  # int*
    m_actuator_user: int  # mjtNum*
    d_act: int  # mjtNum*
    d_act_dot: int  # mjtNum*
    d_ctrl: int  # mjtNum*
    d_actuator_length: int  # mjtNum*
    d_actuator_velocity: int  # mjtNum*


#: C signature of MuJoCo's ``mjfAct``: ``mjtNum (*)(const mjModel*, const mjData*, int id)``
#: (the two pointers are taken as 64-bit integers, same registers on the x86-64/AArch64 ABIs).
CALLBACK_SIGNATURE = types.float64(types.int64, types.int64, types.int32)


#: ctypes type of a callback (what ``mujoco.set_mjcb_act_*`` accept).
_CTYPE = ctypes.CFUNCTYPE(ctypes.c_double, ctypes.c_int64, ctypes.c_int64, ctypes.c_int32)
_NAMES = ("dyn", "gain", "bias")


@dataclass(frozen=True, eq=False)
class RawCallbacks:
    """The three compiled callbacks of one set of offsets.

    Attributes
    ----------
    dyn, gain, bias : ctypes function pointers
        ``mjfAct`` callbacks, ready for ``mujoco.set_mjcb_act_dyn`` etc.
    source : str
        ``"compiled"`` (in this process) or ``"cache"`` (machine code loaded from disk).
    key_sha256 : str
        SHA-256 of the cache key (:func:`cache_key`).
    """

    dyn: object
    gain: object
    bias: object
    source: str
    key_sha256: str
    _keep: tuple = field(default=(), repr=False)  # the code libraries: alive as long as this

    def functions(self) -> tuple:
        """``(dyn, gain, bias)``."""
        return self.dyn, self.gain, self.bias


def _compile(off: RawOffsets) -> list:
    """Compile the (dyn, gain, bias) ``cfunc`` callbacks for the given struct offsets.

    Each callback checks that actuator ``id`` carries a packed row of this package (layout tag,
    5 activation states) and otherwise does nothing (returns 0), so a callback meeting a foreign
    model (callbacks are process-global, and compiling a model calls them) stays harmless.
    """
    o_nuser, o_actadr, o_actnum, o_user = (off.m_nuser_actuator, off.m_actuator_actadr,
                                           off.m_actuator_actnum, off.m_actuator_user)
    o_act, o_act_dot, o_ctrl, o_len, o_vel = (off.d_act, off.d_act_dot, off.d_ctrl,
                                              off.d_actuator_length, off.d_actuator_velocity)

    @njit(inline="always")
    def row_address(m, i):
        nuser = _i64_at(m + o_nuser)[0]
        if nuser < NPACK:
            return 0
        if _i32_at(_i64_at(m + o_actnum)[0])[i] != NSTATE:
            return 0
        row = _i64_at(m + o_user)[0] + 8 * nuser * i
        p = _f64_at(row)
        if p[P_TAG] != LAYOUT_TAG or p[P_NSTATE] != NSTATE or p[P_NPACK] != NPACK:
            return 0
        return row

    def dyn(m, d, i):
        row = row_address(m, i)
        if row == 0:
            return 0.0
        prm = _f64_at(row)
        adr = _i32_at(_i64_at(m + o_actadr)[0])[i]
        a = _f64_at(_i64_at(d + o_act)[0] + 8 * adr)
        out = _f64_at(_i64_at(d + o_act_dot)[0] + 8 * adr)
        derivatives_core(a[0], a[1], a[2], a[3], a[4], _f64_at(_i64_at(d + o_ctrl)[0])[i],
                         _f64_at(_i64_at(d + o_len)[0])[i], _f64_at(_i64_at(d + o_vel)[0])[i],
                         prm, out)
        return 0.0

    def gain(m, d, i):
        return 0.0

    def bias(m, d, i):
        row = row_address(m, i)
        if row == 0:
            return 0.0
        adr = _i32_at(_i64_at(m + o_actadr)[0])[i]
        a = _f64_at(_i64_at(d + o_act)[0] + 8 * adr)
        return force_core(a[2], a[3], _f64_at(_i64_at(d + o_vel)[0])[i], _f64_at(row))

    # A fresh suffix per compilation makes the symbols unique in the process (see the docstring).
    tag = secrets.token_hex(8)
    out = []
    for fn in (dyn, gain, bias):
        fn.__qualname__ = f"{fn.__qualname__}_{tag}"
        out.append(cfunc(CALLBACK_SIGNATURE)(fn))
    return out


# ---------------------------------------------------------------------------------------------
# The cache key (see the module docstring) and the callbacks, from the cache or compiled.
_FORMAT = 1
_MEMO: dict = {}


def _read_sources() -> dict:
    out = {}
    for mod in (sys.modules[__name__], _model, _packing, _params):
        try:
            out[mod.__name__] = hashlib.sha256(pathlib.Path(mod.__file__).read_bytes()).hexdigest()
        except (OSError, TypeError):  # no source file (a frozen install): the bytecode fingerprint remains
            out[mod.__name__] = "unavailable"
    return out


_SOURCES = _read_sources()  # at import: the text the modules in memory were loaded from


def _code_fingerprint(code) -> str:
    consts = [_code_fingerprint(c) if hasattr(c, "co_code")
              else repr(sorted(c, key=repr)) if isinstance(c, frozenset) else repr(c)
              for c in code.co_consts]
    return repr((code.co_name, code.co_code.hex(), consts, code.co_names, code.co_varnames,
                 code.co_freevars, code.co_cellvars, code.co_argcount, code.co_kwonlyargcount))


def _compiled_fingerprint() -> str:
    """SHA-256 over what numba compiles from memory: the functions' bytecode and the constants
    (numbers and strings) of this module, :mod:`rigsim.hydraulics.model` and :mod:`rigsim.hydraulics.packing`."""
    h = hashlib.sha256()
    for mod in (sys.modules[__name__], _model, _packing):
        for name in sorted(vars(mod)):
            obj = getattr(getattr(mod, name), "py_func", getattr(mod, name))
            if getattr(obj, "__module__", None) == mod.__name__ and hasattr(obj, "__code__"):
                h.update(f"{mod.__name__}.{name}={_code_fingerprint(obj.__code__)}\n".encode())
            elif isinstance(obj, (bool, int, float, str)) and not name.startswith("__"):
                h.update(f"{mod.__name__}.{name}={obj!r}\n".encode())
    return h.hexdigest()


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "absent"


def cache_key(off: RawOffsets) -> dict:
    """The cache key of the callbacks for ``off``: a JSON-serializable dict of everything their
    machine code depends on (see the module docstring)."""
    import llvmlite
    import llvmlite.binding as ll
    import numba
    from numba.core.registry import cpu_target

    return {
        "format": _FORMAT,
        "offsets": {k: int(v) for k, v in off._asdict().items()},
        "signature": str(CALLBACK_SIGNATURE),
        "layout": {k: v for k, v in sorted(vars(_packing).items())
                   if (k == "LAYOUT_TAG" or k.startswith(("N", "P_"))) and isinstance(v, (int, float))},
        "sources": _SOURCES,
        "compiled": _compiled_fingerprint(),
        "versions": {"python": sys.version, "cache_tag": sys.implementation.cache_tag,
                     "numba": numba.__version__, "llvmlite": llvmlite.__version__,
                     "llvm": ".".join(map(str, ll.llvm_version_info)), "numpy": np.__version__,
                     "mujoco": _version("mujoco")},
        "platform": [platform.system(), platform.machine()],
        "target": list(cpu_target.target_context.codegen().magic_tuple()),
        "numba_env": {k: v for k, v in sorted(os.environ.items()) if k.startswith("NUMBA_")},
    }


def cache_info() -> dict:
    """What this process did: callbacks ``compiled``, ``loaded`` from the cache, entries
    ``rejected`` (corrupt, of another key, or failing a check) and ``saved``; the ``directory``
    (None: cache off)."""
    d = _cache.cache_directory()
    return dict(_cache.STATS, directory=None if d is None else str(d))


def make_raw_callbacks(off: RawOffsets, verify: Callable[[RawCallbacks], bool] | None = None) -> RawCallbacks:
    """The (dyn, gain, bias) callbacks for the given struct offsets: from the cache if it holds
    an entry of the same key, else compiled (seconds) and stored.

    Parameters
    ----------
    off : RawOffsets
    verify : callable, optional
        ``verify(callbacks) -> bool``, run on callbacks loaded from the cache (an entry failing
        it is deleted and the callbacks compiled) and on freshly compiled ones (failing it
        raises RuntimeError).

    Returns
    -------
    RawCallbacks
        The same object for the same offsets for the rest of the process (no state is held).
    """
    if off in _MEMO:
        return _MEMO[off]
    directory = _cache.cache_directory()
    key = cache_key(off) if directory is not None else None
    digest = _cache.key_digest(key) if key is not None else ""
    result = None
    if directory is not None:
        path = _cache.entry_path(directory, digest)
        try:
            code = _cache.load_entry(path, key, digest, _NAMES)
            result = RawCallbacks(*(_CTYPE(address) for _, address in code), source="cache",
                                  key_sha256=digest, _keep=tuple(lib for lib, _ in code))
            if verify is not None and not verify(result):
                raise _cache.RejectedEntry("the loaded callbacks disagree with the reference equations")
            _cache.STATS["loaded"] += 1
        except FileNotFoundError:
            result = None
        except (_cache.RejectedEntry, OSError):
            _cache.STATS["rejected"] += 1
            result = None
            try:
                path.unlink(missing_ok=True)
            except OSError:
                pass
    if result is not None:
        try:
            os.utime(path)  # recently used: kept when the folder is pruned
        except OSError:
            pass
    else:
        compiled = _compile(off)
        _cache.STATS["compiled"] += 1
        result = RawCallbacks(*(cf.ctypes for cf in compiled), source="compiled", key_sha256=digest,
                              _keep=tuple(compiled))
        if verify is not None and not verify(result):
            raise RuntimeError("the compiled hydraulic callbacks disagree with the reference equations; "
                               "use hydraulic_callbacks(model, fast=False)")
        if directory is not None:
            try:
                _cache.save_entry(directory, key, digest, list(zip(_NAMES, compiled)))
            except OSError:
                pass  # a cache that cannot be written only costs time
    _MEMO[off] = result
    return result
