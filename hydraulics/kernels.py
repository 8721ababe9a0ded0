"""numba-compiled twin of :mod:`hydraulics.model`, over raw float64 arrays and raw pointers.

The scalar kernels of :mod:`hydraulics.model` are ``register_jitable``: the functions here
compile that very source, so the compiled and the plain-Python reference paths share one set
of equations (tests check they agree). Nothing here imports mujoco: the MuJoCo callbacks are
built by :func:`make_raw_callbacks` from integer byte offsets that :mod:`hydraulics.bridge`
finds and verifies at runtime.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
from numba import cfunc, njit, types
from numba.extending import intrinsic

from .model import derivatives_core, force_core
from .packing import LAYOUT_TAG, NPACK, NSTATE, P_NPACK, P_NSTATE, P_TAG

__all__ = ["derivatives_array", "force_array", "step_euler", "RawOffsets", "make_raw_callbacks",
           "CALLBACK_SIGNATURE"]


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


@functools.lru_cache(maxsize=None)
def make_raw_callbacks(off: RawOffsets):
    """Compile the (dyn, gain, bias) ``cfunc`` callbacks for the given struct offsets.

    Each callback checks that actuator ``id`` carries a packed row of this package (layout tag,
    5 activation states) and otherwise does nothing (returns 0), so a callback meeting a foreign
    model (callbacks are process-global, and compiling a model calls them) stays harmless.
    Results are cached per offsets (compilation takes seconds; the callbacks hold no state).
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

    return (cfunc(CALLBACK_SIGNATURE)(dyn), cfunc(CALLBACK_SIGNATURE)(gain),
            cfunc(CALLBACK_SIGNATURE)(bias))
