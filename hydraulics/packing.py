"""Flat float64 parameter vector of one actuator (for ``actuator_user`` and compiled kernels).

Layout: ``[LAYOUT_TAG, NSTATE, NPACK, <every ActuatorParams field in declaration order>]``.
The three header slots let a callback recognise a row that really holds these parameters
(MuJoCo callbacks are process-global and may meet other models). The ``P_*`` indices are
plain module constants so numba treats them as compile-time constants.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .params import STATE_NAMES, ActuatorParams

__all__ = ["pack", "unpack", "LAYOUT_TAG", "NSTATE", "NPACK", "FIELD_NAMES"]

#: Arbitrary tag in slot 0 marking a row packed by this module's layout (a row of another layout
#: carries another tag). Change it whenever the layout changes.
LAYOUT_TAG = 7311.125
#: Number of activation states per actuator (``len(STATE_NAMES)``).
NSTATE = 5

FIELD_NAMES = tuple(f.name for f in dataclasses.fields(ActuatorParams))

# Header slots.
P_TAG = 0
P_NSTATE = 1
P_NPACK = 2
# Parameter slots (declaration order of ActuatorParams, offset by the 3 header slots).
P_SUPPLY = 3
P_RETURN = 4
P_QRATED = 5
P_DPRATED = 6
P_SPOOL_HZ = 7
P_SPOOL_ZETA = 8
P_KSV = 9
P_CMD_LIMIT = 10
P_NULL = 11
P_LAMINAR = 12
P_AREA = 13
P_STROKE = 14
P_VDEAD = 15
P_BETA = 16
P_LEAK = 17
P_PCAV = 18
P_CAVBAND = 19
P_CAVMIN = 20
P_PRELIEF = 21
P_CRELIEF = 22
P_MASS = 23
P_FRICTION = 24
P_KP = 25
P_TI = 26
P_KDP = 27
P_DESIGN_KT = 28
P_DESIGN_MASS = 29
#: Length of a packed vector.
NPACK = 30

_EXPECTED = ("supply_pressure_Pa", "return_pressure_Pa", "rated_flow_m3_s", "rated_valve_drop_Pa",
             "spool_hz", "spool_damping", "ksv", "command_limit", "null_opening", "laminar_drop_Pa",
             "piston_area_m2", "stroke_m", "dead_volume_m3", "bulk_modulus_Pa", "leakage_m3_s_Pa",
             "cavitation_pressure_Pa", "cavitation_band_Pa", "cavitation_min_fraction",
             "relief_pressure_Pa", "relief_conductance_m3_s_Pa", "pan_mass_kg", "friction_N_s_m",
             "kp_per_m", "ti_s", "kdp_per_Pa", "design_tire_N_per_m", "design_load_mass_kg")
if FIELD_NAMES != _EXPECTED or NPACK != 3 + len(FIELD_NAMES) or NSTATE != len(STATE_NAMES):
    raise ImportError("rigsim.hydraulics.packing is out of date with ActuatorParams: update the P_* slots")


def pack(params: ActuatorParams) -> np.ndarray:
    """Pack ``params`` into a flat float64 vector of length ``NPACK``."""
    if not isinstance(params, ActuatorParams):
        raise TypeError(f"pack() needs an ActuatorParams, got {type(params).__name__}")
    values = [float(getattr(params, name)) for name in FIELD_NAMES]
    return np.array([LAYOUT_TAG, float(NSTATE), float(NPACK), *values], dtype=np.float64)


def unpack(vector) -> ActuatorParams:
    """Rebuild the validated ``ActuatorParams`` from a packed vector.

    Parameters
    ----------
    vector : array_like of float, shape (NPACK,) or longer (extra slots are ignored)
    """
    v = np.asarray(vector, dtype=np.float64).ravel()
    if v.size < NPACK or v[P_TAG] != LAYOUT_TAG or v[P_NSTATE] != NSTATE or v[P_NPACK] != NPACK:
        raise ValueError("vector is not a packed ActuatorParams (wrong length or layout tag); "
                         "pack it with rigsim.hydraulics.packing.pack")
    kwargs = {name: float(v[3 + i]) for i, name in enumerate(FIELD_NAMES)}
    return ActuatorParams(**kwargs)
