"""Actuator files: the transfer function ``T_a(s) = X_a / X_p`` of a rig's actuator, in TOML.

Either coefficients (descending powers of s, s in rad/s)::

    [transfer_function]
    num = [73.3, 73.3]
    den = [4.82e-6, 2.14e-3, 1.03, 77.5, 73.3]

or the physical parameters of the paper's eq. 4 (SI units; see
:data:`correction.eq4.EQ4_PARAMETERS`)::

    [parameters]
    ksv = 1.0
    kq_m3_s = 0.0109
    kc_m3_s_Pa = 1.26e-11
    kp_per_m = 50.0
    kdp_per_Pa = 2.0e-8
    piston_area_m2 = 7.43e-3
    fluid_volume_m3 = 2.13e-3
    bulk_modulus_Pa = 1.0e9
    mass_kg = 500.0
    damping_N_s_m = 5.0e3
    tire_N_per_m = 1.0e6
    # ti_s = 1.0   (optional: PI integral time; 1 s gives the printed b0 = b1 = a0)

Exactly one of the two tables; every key is checked (an unknown key names the closest valid
one). Errors are :class:`ActuatorFileError` (a ``ValueError``), one sentence naming the key.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .eq4 import EQ4_PARAMETERS, eq4_coefficients_from
from .tomlfile import check_keys, number, read_toml

__all__ = ["ActuatorFileError", "parse_actuator", "read_actuator_file"]

_TABLES = ("transfer_function", "parameters")
_OPTIONAL = ("ti_s",)


class ActuatorFileError(ValueError):
    """An actuator file that cannot be used as written; the message is one sentence naming the key."""


def _coefficients(where: str, value) -> np.ndarray:
    if not isinstance(value, list) or not value:
        raise ActuatorFileError(f"{where} must be a non-empty list of numbers (descending powers of s), "
                                f"got {value!r}")
    return np.array([number(f"{where}[{i}]", v, error=ActuatorFileError) for i, v in enumerate(value)])


def parse_actuator(data: Mapping) -> tuple[np.ndarray, np.ndarray]:
    """``T_a``'s ``(num, den)`` (descending powers of s) from a parsed actuator file.

    Parameters
    ----------
    data : Mapping
        The TOML document as a mapping: one table ``transfer_function`` (keys ``num``, ``den``)
        or ``parameters`` (the keys of :data:`correction.eq4.EQ4_PARAMETERS`, SI units).

    Returns
    -------
    num, den : numpy.ndarray
        Coefficients in descending powers of s (s in rad/s).

    Raises
    ------
    ActuatorFileError
        Unknown, missing or mistyped keys, neither or both tables, or parameters out of range.
    """
    check_keys(data, _TABLES, "", ActuatorFileError)
    present = [t for t in _TABLES if t in data]
    if len(present) != 1:
        raise ActuatorFileError("an actuator file needs exactly one of the tables [transfer_function] "
                                f"(num, den) and [parameters] (eq. 4), got {len(present)}")
    table = data[present[0]]
    if not isinstance(table, Mapping):
        raise ActuatorFileError(f"{present[0]} must be a table, got {table!r}")
    if present[0] == "transfer_function":
        valid = ("num", "den")
        check_keys(table, valid, "transfer_function.", ActuatorFileError)
        for key in valid:
            if key not in table:
                raise ActuatorFileError(f"transfer_function.{key} is missing (coefficients in descending powers of s)")
        return (_coefficients("transfer_function.num", table["num"]),
                _coefficients("transfer_function.den", table["den"]))
    check_keys(table, EQ4_PARAMETERS, "parameters.", ActuatorFileError)
    missing = [k for k in EQ4_PARAMETERS if k not in table and k not in _OPTIONAL]
    if missing:
        raise ActuatorFileError(f"parameters.{missing[0]} is missing ({EQ4_PARAMETERS[missing[0]]})")
    values = {k: number(f"parameters.{k}", v, error=ActuatorFileError) for k, v in table.items()}
    try:
        return eq4_coefficients_from(**values)
    except ValueError as exc:
        raise ActuatorFileError(str(exc).replace("eq. 4 parameter ", "parameters.")) from None


def read_actuator_file(path) -> tuple[np.ndarray, np.ndarray]:
    """Read an actuator file (TOML) and return ``T_a``'s ``(num, den)``, descending powers of s.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file (see the module notes for its two forms).

    Returns
    -------
    num, den : numpy.ndarray

    Raises
    ------
    ActuatorFileError
        A missing, unreadable or malformed file (:func:`correction.tomlfile.read_toml`), or any
        error of :func:`parse_actuator`.
    """
    return parse_actuator(read_toml(path, "actuator file", ActuatorFileError))
