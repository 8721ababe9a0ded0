"""The one module of :mod:`hydraulics` that imports mujoco: user actuators and their callbacks.

* :func:`add_hydraulic_actuators` adds, per wheel corner, a user actuator ``hyd_<c>`` on the
  slide joint ``pan_<c>_z`` with five activation states (``STATE_NAMES``) and its parameters
  packed into ``actuator_user``, so every callback is a pure function of (model, data).
  ``ctrl`` carries the drive signal x_ref (m); the force is ``A (P1 - P2) - b v`` (gain
  callback 0, bias callback the force), positive up.
* :func:`hydraulic_callbacks` installs the dyn/gain/bias callbacks for a ``with`` block (after
  compiling) and removes them afterwards, also on error. ``fast=True`` installs numba ``cfunc``
  callbacks reading raw mjModel/mjData pointers (byte offsets found with
  ``mujoco.introspect.structs`` and verified against known arrays of the given model;
  compiled once per process or loaded from the on-disk cache of :mod:`rigsim.hydraulics.kernels`,
  and checked against the reference equations on the model before use);
  ``fast=False`` installs the plain-Python reference callbacks (same equations, ~9x slower
  on the single-pan rig). Do not compile models inside a ``fast=False`` block: compiling calls
  installed callbacks and MuJoCo then fails with "Python exception raised" (the compiled
  callbacks tolerate it: they ignore any actuator without a packed row).

MuJoCo calls the callbacks again inside ``mj_forward``, in RK4 stages and in
``mjd_transitionFD``; they only read states and write ``act_dot``, so all of these are safe.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
from collections.abc import Mapping

import mujoco
import numpy as np
from mujoco.introspect import structs as _structs

from rigsim.mjcf.names import CORNERS, hydraulic_actuator, pan_body, pan_joint

from .kernels import RawCallbacks, RawOffsets, make_raw_callbacks
from .model import MPA, derivatives_core, force_core
from .packing import LAYOUT_TAG, NPACK, NSTATE, P_NPACK, P_NSTATE, P_SUPPLY, P_TAG, pack, unpack
from .params import GRAVITY_M_S2, ActuatorParams

__all__ = ["add_hydraulic_actuators", "single_pan_spec", "hydraulic_callbacks", "actuator_id",
           "activation_slice", "set_activation", "params_from_model", "LayoutError"]

# Every element name (and CORNERS) comes from rigsim.mjcf.names.


class LayoutError(RuntimeError):
    """The mjModel/mjData memory layout does not match what the compiled callbacks assume."""


# ---------------------------------------------------------------------------------------------
def add_hydraulic_actuators(spec: mujoco.MjSpec, params: ActuatorParams | Mapping[str, ActuatorParams],
                            corners=CORNERS) -> None:
    """Add one hydraulic user actuator ``hyd_<c>`` on joint ``pan_<c>_z`` per corner.

    Parameters
    ----------
    spec : mujoco.MjSpec
        Model under construction; must contain the slide joints ``pan_<c>_z``.
    params : ActuatorParams or Mapping[str, ActuatorParams]
        One parameter set for all corners, or one per corner name.
    corners : sequence of str
        Corner names (default ``("fl", "fr", "rl", "rr")``).
    """
    corners = tuple(corners)
    if isinstance(params, ActuatorParams):
        per_corner = {c: params for c in corners}
    elif isinstance(params, Mapping):
        missing = [c for c in corners if c not in params]
        if missing:
            raise ValueError(f"params has no ActuatorParams for corner(s) {missing}; give one per corner")
        per_corner = {c: params[c] for c in corners}
        bad = [c for c, p in per_corner.items() if not isinstance(p, ActuatorParams)]
        if bad:
            raise ValueError(f"params[{bad[0]!r}] must be an ActuatorParams")
    else:
        raise ValueError(f"params must be ActuatorParams or a mapping of them, got {type(params).__name__}")
    for c in corners:
        if spec.joint(pan_joint(c)) is None:
            raise ValueError(f"spec has no joint {pan_joint(c)!r}; build the rig model first")
    nuser = max(int(spec.nuser_actuator), NPACK)
    spec.nuser_actuator = nuser
    for c in corners:
        row = np.zeros(nuser)
        row[:NPACK] = pack(per_corner[c])
        act = spec.add_actuator(name=hydraulic_actuator(c), target=pan_joint(c),
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.dyntype = mujoco.mjtDyn.mjDYN_USER
        act.gaintype = mujoco.mjtGain.mjGAIN_USER
        act.biastype = mujoco.mjtBias.mjBIAS_USER
        act.actdim = NSTATE
        act.gear = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]  # actuator_length = qpos: x_a in m
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        act.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE  # limits live in the dynamics
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE
        act.userdata = row.tolist()


def single_pan_spec(params: ActuatorParams, *, spring_N_per_m: float = 0.0, load_N: float = 0.0,
                    pan_mass_kg: float | None = None, gravity: bool = True,
                    timestep_s: float = 1.0e-4, corner: str = "fl") -> mujoco.MjSpec:
    """A one-wheelpan test rig: body ``pan_<corner>`` on slide joint ``pan_<corner>_z`` with the
    hydraulic actuator, a linear spring to ground standing in for the tire, Euler integration.

    Parameters
    ----------
    params : ActuatorParams
    spring_N_per_m : float, N/m
        Joint stiffness between pan and ground (a tire on a fixed axle, eq. 4's load).
    load_N : float, N
        Downward spring preload at qpos 0 (the wheel load); the spring rest position is set so
        the spring pushes the pan down with ``load_N`` there (needs ``spring_N_per_m > 0``).
        Negative values pull up (e.g. ``-m g`` balances the pan's weight).
    pan_mass_kg : float, kg, optional
        Moving mass (default ``params.pan_mass_kg``).
    gravity : bool
        Gravity -9.81 m/s^2 along z, or none.
    timestep_s : float, s
    corner : str
    """
    if load_N != 0.0 and not spring_N_per_m > 0.0:
        raise ValueError("load_N needs a spring: give spring_N_per_m > 0")
    spec = mujoco.MjSpec()
    spec.modelname = "single_pan"
    spec.option.timestep = timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.gravity = [0.0, 0.0, -GRAVITY_M_S2 if gravity else 0.0]
    body = spec.worldbody.add_body(name=pan_body(corner))
    mass = params.pan_mass_kg if pan_mass_kg is None else float(pan_mass_kg)
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5, 0.3, 0.05], mass=mass,
                  contype=0, conaffinity=0)
    half = params.half_stroke_m
    body.add_joint(name=pan_joint(corner), type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                   range=[-half, half], limited=mujoco.mjtLimited.mjLIMITED_TRUE,
                   stiffness=float(spring_N_per_m),
                   springref=(-load_N / spring_N_per_m) if spring_N_per_m > 0 else 0.0)
    add_hydraulic_actuators(spec, params, corners=(corner,))
    return spec


def actuator_id(model: mujoco.MjModel, corner: str) -> int:
    """Index of actuator ``hyd_<corner>`` (ValueError if absent)."""
    name = hydraulic_actuator(corner)
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
    if i < 0:
        raise ValueError(f"model has no actuator {name!r}; add it with add_hydraulic_actuators")
    return i


def activation_slice(model: mujoco.MjModel, corner: str) -> slice:
    """Slice of ``data.act`` holding the five states of ``hyd_<corner>``."""
    i = actuator_id(model, corner)
    adr = int(model.actuator_actadr[i])
    return slice(adr, adr + NSTATE)


def set_activation(model: mujoco.MjModel, data: mujoco.MjData, corner: str, act) -> None:
    """Write the five activation states of ``hyd_<corner>`` (e.g. ``equilibrium_activation``)."""
    a = np.asarray(act, dtype=np.float64).ravel()
    if a.size != NSTATE:
        raise ValueError(f"act must have {NSTATE} states, got {a.size}")
    data.act[activation_slice(model, corner)] = a


def params_from_model(model: mujoco.MjModel, corner: str) -> ActuatorParams:
    """The ``ActuatorParams`` packed into ``hyd_<corner>``'s ``actuator_user`` row."""
    return unpack(model.actuator_user[actuator_id(model, corner)])


def _is_hydraulic_row(row) -> bool:
    return (row.size >= NPACK and row[P_TAG] == LAYOUT_TAG and row[P_NSTATE] == NSTATE
            and row[P_NPACK] == NPACK)


def _hydraulic_ids(model: mujoco.MjModel) -> list[int]:
    if model.nuser_actuator < NPACK:
        return []
    return [i for i in range(model.nu)
            if model.actuator_actnum[i] == NSTATE and _is_hydraulic_row(model.actuator_user[i])]


# ---------------------------------------------------------------------------------------------
# Reference (plain-Python) callbacks.
def _python_callbacks():
    def dyn(m, d, i):
        row = m.actuator_user[i]
        if m.actuator_actnum[i] != NSTATE or not _is_hydraulic_row(row):
            return 0.0
        adr = int(m.actuator_actadr[i])
        a = d.act[adr:adr + NSTATE].tolist()
        out = [0.0] * NSTATE
        derivatives_core(a[0], a[1], a[2], a[3], a[4], float(d.ctrl[i]), float(d.actuator_length[i]),
                         float(d.actuator_velocity[i]), row.tolist(), out)
        d.act_dot[adr:adr + NSTATE] = out
        return 0.0

    def gain(m, d, i):
        return 0.0

    def bias(m, d, i):
        row = m.actuator_user[i]
        if m.actuator_actnum[i] != NSTATE or not _is_hydraulic_row(row):
            return 0.0
        adr = int(m.actuator_actadr[i])
        return force_core(float(d.act[adr + 2]), float(d.act[adr + 3]),
                          float(d.actuator_velocity[i]), row.tolist())

    return dyn, gain, bias


# ---------------------------------------------------------------------------------------------
# Struct layout for the compiled callbacks.
_PRIMITIVES = {  # (size, alignment) in bytes on the 64-bit platforms MuJoCo wheels exist for
    "mjtNum": (8, 8), "double": (8, 8), "float": (4, 4), "int": (4, 4), "unsigned int": (4, 4),
    "mjtSize": (8, 8), "size_t": (8, 8), "uintptr_t": (8, 8), "uint64_t": (8, 8),
    "int64_t": (8, 8), "mjtBool": (1, 1), "mjtByte": (1, 1), "char": (1, 1),
    "unsigned char": (1, 1),
}


def _size_align(t) -> tuple[int, int]:
    if isinstance(t, _structs.PointerType):
        return 8, 8
    if isinstance(t, _structs.ArrayType):
        size, align = _size_align(t.inner_type)
        return size * int(np.prod(t.extents)), align
    if isinstance(t, _structs.AnonymousStructDecl):
        _, size, align = _layout(t.fields)
        return size, align
    if isinstance(t, _structs.AnonymousUnionDecl):
        parts = [_size_align(f.type) for f in t.fields]
        align = max(a for _, a in parts)
        return -(-max(s for s, _ in parts) // align) * align, align
    if isinstance(t, _structs.ValueType):
        if t.name in _PRIMITIVES:
            return _PRIMITIVES[t.name]
        if t.name in _structs.STRUCTS:
            _, size, align = _layout(_structs.STRUCTS[t.name].fields)
            return size, align
    raise LayoutError(f"unknown field type {t!r} in mujoco.introspect")


def _word(address: int) -> int:
    return ctypes.c_uint64.from_address(address).value


def _layout(fields) -> tuple[dict, int, int]:
    """C layout (natural alignment) of a struct: ({field: byte offset}, size, alignment)."""
    offsets, off, align = {}, 0, 1
    for f in fields:
        size, a = _size_align(f.type)
        off = -(-off // a) * a
        offsets[f.name] = off
        off += size
        align = max(align, a)
    return offsets, -(-off // align) * align, align


def _find_offsets(model: mujoco.MjModel, data: mujoco.MjData) -> RawOffsets:
    """Byte offsets from ``mujoco.introspect.structs``, verified against this model and data."""
    m_off, _, _ = _layout(_structs.STRUCTS["mjModel"].fields)
    d_off, _, _ = _layout(_structs.STRUCTS["mjData"].fields)
    offsets = RawOffsets(m_nuser_actuator=m_off["nuser_actuator"],
                         m_actuator_actadr=m_off["actuator_actadr"],
                         m_actuator_actnum=m_off["actuator_actnum"],
                         m_actuator_user=m_off["actuator_user"],
                         d_act=d_off["act"], d_act_dot=d_off["act_dot"], d_ctrl=d_off["ctrl"],
                         d_actuator_length=d_off["actuator_length"],
                         d_actuator_velocity=d_off["actuator_velocity"])
    _verify_offsets(offsets, m_off, d_off, model, data)
    return offsets


def _verify_offsets(off: RawOffsets, m_off: dict, d_off: dict, model: mujoco.MjModel,
                    data: mujoco.MjData) -> None:
    """Read every field the callbacks use (and a few more) at the computed offsets and compare
    it with the numpy view MuJoCo's bindings give of the same field."""
    if m_off["nuser_actuator"] != off.m_nuser_actuator:
        raise LayoutError("internal: inconsistent offsets")  # pragma: no cover
    checks = []
    for name in ("nq", "nv", "nu", "na", "nbody", "nuser_actuator"):
        checks.append((f"mjModel.{name}", ctypes.c_int64.from_address(model._address + m_off[name]).value,
                       int(getattr(model, name))))
    for obj, offs, names in ((model, m_off, ("qpos0", "body_mass", "jnt_qposadr", "actuator_actadr",
                                             "actuator_actnum", "actuator_user", "actuator_gear")),
                             (data, d_off, ("qpos", "qvel", "act", "act_dot", "ctrl", "actuator_length",
                                            "actuator_velocity", "actuator_force", "qfrc_actuator"))):
        for name in names:
            arr = getattr(obj, name)
            if arr.size:  # empty arrays share the next array's address: nothing to compare
                checks.append((name, _word(obj._address + offs[name]), arr.ctypes.data))
    bad = [f"{n} (read {got}, expected {want})" for n, got, want in checks if got != want]
    if bad:
        raise LayoutError("mjModel/mjData layout check failed for " + ", ".join(bad)
                          + f"; this mujoco {mujoco.__version__} build does not match "
                          "mujoco.introspect, so use hydraulic_callbacks(model, fast=False)")


def _agrees_with_reference(model: mujoco.MjModel, callbacks: RawCallbacks) -> bool:
    """Call the compiled dyn and bias callbacks once per hydraulic actuator of ``model`` on a
    scratch MjData at a state away from rest and compare with the plain-Python equations
    (they agree to ~1e-13 relative; a wrong or stale machine code does not)."""
    data = mujoco.MjData(model)
    dyn, gain, bias = callbacks.functions()
    for i in _hydraulic_ids(model):
        row = model.actuator_user[i].tolist()
        adr = int(model.actuator_actadr[i])
        supply_MPa = row[P_SUPPLY] / MPA
        a = [0.3, 20.0, 0.55 * supply_MPa, 0.35 * supply_MPa, 2e-4]
        data.act[adr:adr + NSTATE] = a
        data.ctrl[i], data.actuator_length[i], data.actuator_velocity[i] = 3e-3, 1e-3, 0.05
        data.act_dot[adr:adr + NSTATE] = np.nan
        ref = [0.0] * NSTATE
        derivatives_core(*a, 3e-3, 1e-3, 0.05, row, ref)
        dyn(model._address, data._address, i)
        got = data.act_dot[adr:adr + NSTATE]
        ref_force = force_core(a[2], a[3], 0.05, row)
        if not (all(map(math.isfinite, ref)) and math.isfinite(ref_force)):
            continue  # parameters odd enough to overflow here: nothing to compare with
        if not (np.allclose(got, ref, rtol=1e-10, atol=1e-12 * max(map(abs, ref)))
                and math.isclose(bias(model._address, data._address, i), ref_force, rel_tol=1e-10)
                and gain(model._address, data._address, i) == 0.0):
            return False
    return True


def _fast_callbacks(model: mujoco.MjModel):
    data = mujoco.MjData(model)
    try:
        offsets = _find_offsets(model, data)
    except LayoutError:
        raise
    except Exception as exc:  # pragma: no cover - defensive: anything odd is a layout problem
        raise LayoutError(f"could not locate mjModel/mjData fields ({exc}); use "
                          "hydraulic_callbacks(model, fast=False)") from exc
    # Compiled once per process (or loaded from the on-disk cache, see rigsim.hydraulics.kernels) and
    # checked against the reference equations on this model before use.
    callbacks = make_raw_callbacks(offsets, verify=lambda cbs: _agrees_with_reference(model, cbs))
    return callbacks.functions()


# ---------------------------------------------------------------------------------------------
_SETTERS = (mujoco.set_mjcb_act_dyn, mujoco.set_mjcb_act_gain, mujoco.set_mjcb_act_bias)
_GETTERS = (mujoco.get_mjcb_act_dyn, mujoco.get_mjcb_act_gain, mujoco.get_mjcb_act_bias)


@contextlib.contextmanager
def hydraulic_callbacks(model: mujoco.MjModel, fast: bool = True):
    """Install the hydraulic actuator callbacks for the duration of a ``with`` block.

    Parameters
    ----------
    model : mujoco.MjModel
        A compiled model with actuators added by :func:`add_hydraulic_actuators` (install the
        callbacks only after compiling: compiling calls installed callbacks).
    fast : bool
        True: numba ``cfunc`` callbacks on raw pointers (raises :class:`LayoutError` if the struct
        layout check fails); False: plain-Python reference callbacks.

    Raises
    ------
    RuntimeError
        If actuator callbacks are already installed (nesting is refused).
    ValueError
        If the model has no hydraulic actuator.
    """
    if any(get() is not None for get in _GETTERS):
        raise RuntimeError("MuJoCo actuator callbacks are already installed (nested "
                           "hydraulic_callbacks or foreign callbacks); leave that block first")
    if not _hydraulic_ids(model):
        raise ValueError("model has no hydraulic actuator (add them with add_hydraulic_actuators)")
    callbacks = _fast_callbacks(model) if fast else _python_callbacks()
    try:
        for setter, cb in zip(_SETTERS, callbacks):
            setter(cb)
        yield callbacks
    finally:
        for setter in _SETTERS:
            setter(None)
