"""Actuator files: the transfer function ``T_a(s) = X_a / X_p`` of a rig's actuator, in TOML.

Either coefficients (descending powers of s, s in rad/s)::

    [transfer_function]
    num = [73.3, 73.3]
    den = [4.82e-6, 2.14e-3, 1.03, 77.5, 73.3]

or the physical parameters of the paper's eq. 4 (SI units; see
:data:`rigsim.correction.output.eq4.EQ4_PARAMETERS`)::

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

A rig with several actuators has one ``T_a`` per corner: the per-corner form has one table per
corner (any name but ``meta``, ``transfer_function`` and ``parameters``), each with ``num`` and
``den`` (descending powers of s, s in rad/s), optionally a ``[<corner>.fit]`` table of the fit's
diagnostics (written by :func:`write_actuators_file`, ignored by the reader), plus an optional
``[meta]`` table (source, date, drive rms, record length ...; ignored by the reader)::

    [meta]
    source = "rig run 2024-05-02, identification drive"

    [fl]
    num = [1.29e-3, 1.0]
    den = [2.1e-10, 1.3e-7, 4.5e-5, 1.2e-2, 1.24, 1.0]

    [fl.fit]
    orders = [2, 6]
    held_out_error = 0.03

    [fr]
    ...

:func:`write_actuators_file` writes it (atomically), :func:`read_actuators_file` reads it.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from rigsim.correction.identification.actuator_result import ActuatorFit
from rigsim.correction.output.eq4 import EQ4_PARAMETERS, eq4_coefficients_from
from rigsim.correction.io.tomlfile import check_keys, number, read_toml, write_toml
from rigsim.errors import RigsimError

__all__ = ["ActuatorFileError", "parse_actuator", "read_actuator_file", "parse_actuators",
           "read_actuators_file", "write_actuators_file"]

_TABLES = ("transfer_function", "parameters")
_OPTIONAL = ("ti_s",)


class ActuatorFileError(RigsimError, ValueError):
    """An actuator file that cannot be used as written; the message is one sentence naming the key.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from rigsim.correction.io.actuator_file import ActuatorFileError, read_actuators_file
    >>> acts = pathlib.Path(tempfile.mkdtemp()) / "actuators.toml"
    >>> _ = acts.write_text("[fl]\\nnum = [1.0]\\n")
    >>> try:
    ...     read_actuators_file(acts)
    ... except ActuatorFileError as exc:
    ...     print(exc)
    fl.den is missing (coefficients in descending powers of s)
    """


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
        or ``parameters`` (the keys of :data:`rigsim.correction.output.eq4.EQ4_PARAMETERS`, SI units).

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
        A missing, unreadable or malformed file (:func:`rigsim.correction.io.tomlfile.read_toml`), or any
        error of :func:`parse_actuator`.
    """
    return parse_actuator(read_toml(path, "actuator file", ActuatorFileError))


#: Top-level names that are not corners in a per-corner actuator file.
_NOT_CORNERS = ("meta",) + _TABLES


def parse_actuators(data: Mapping) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each corner's ``T_a`` ``(num, den)`` (descending powers of s) from a parsed per-corner file.

    Parameters
    ----------
    data : Mapping
        The TOML document: one table per corner (keys ``num``, ``den``, optional table ``fit``),
        optional table ``meta``.

    Returns
    -------
    dict of str to (numpy.ndarray, numpy.ndarray)
        Corner name (as written) to ``(num, den)``, in the file's order.

    Raises
    ------
    ActuatorFileError
        A single-actuator file, no corner table, a corner that is not a table, an unknown,
        missing or mistyped key (one sentence naming the table and key).
    """
    single = [t for t in _TABLES if t in data]
    if single:
        raise ActuatorFileError(f"this is a single-actuator file ([{single[0]}]); a per-corner actuator file "
                                "has one table per corner ([fl], [fr], ...) with num and den")
    if "meta" in data and not isinstance(data["meta"], Mapping):
        raise ActuatorFileError(f"meta must be a table ([meta]), got {data['meta']!r}")
    out = {}
    for corner, table in data.items():
        if corner in _NOT_CORNERS:
            continue
        if not isinstance(table, Mapping):
            raise ActuatorFileError(f"{corner} must be a table [{corner}] with num and den (descending powers "
                                    f"of s), got {table!r}")
        check_keys(table, ("num", "den", "fit"), f"{corner}.", ActuatorFileError)
        for key in ("num", "den"):
            if key not in table:
                raise ActuatorFileError(f"{corner}.{key} is missing (coefficients in descending powers of s)")
        if "fit" in table and not isinstance(table["fit"], Mapping):
            raise ActuatorFileError(f"{corner}.fit must be a table of diagnostics, got {table['fit']!r}")
        num, den = _coefficients(f"{corner}.num", table["num"]), _coefficients(f"{corner}.den", table["den"])
        if not np.any(den != 0):
            raise ActuatorFileError(f"{corner}.den is zero; give the denominator in descending powers of s")
        out[corner] = (num, den)
    if not out:
        raise ActuatorFileError("a per-corner actuator file needs at least one corner table ([fl], [fr], ...) "
                                "with num and den")
    return out


def read_actuators_file(path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Read a per-corner actuator file (TOML): corner name to ``T_a``'s ``(num, den)``.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    dict of str to (numpy.ndarray, numpy.ndarray)
        Descending powers of s (s in rad/s), in the file's order.

    Raises
    ------
    ActuatorFileError
        A missing, unreadable or malformed file, or any error of :func:`parse_actuators`.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from rigsim.correction.io.actuator_file import read_actuators_file
    >>> acts = pathlib.Path(tempfile.mkdtemp()) / "actuators.toml"
    >>> _ = acts.write_text("[fl]\\nnum = [1.0]\\nden = [1.1e-4, 0.0106, 1.0]\\n"
    ...                     "[fr]\\nnum = [1.0]\\nden = [1.2e-4, 0.0110, 1.0]\\n")
    >>> for corner, (num, den) in read_actuators_file(acts).items():
    ...     print(corner, num, den)
    fl [1.] [1.10e-04 1.06e-02 1.00e+00]
    fr [1.] [1.2e-04 1.1e-02 1.0e+00]
    """
    return parse_actuators(read_toml(path, "actuator file", ActuatorFileError))


def write_actuators_file(path, actuators: Mapping, meta: Mapping | None = None) -> None:
    """Write a per-corner actuator file, atomically (temporary file in the same folder, then a rename).

    Parameters
    ----------
    path : str or os.PathLike
        The TOML file (created or replaced; not overwriting an input is the caller's business).
    actuators : Mapping of str to ActuatorFit or (num, den)
        Corner name to ``T_a`` (descending powers of s, s in rad/s); an
        :class:`~rigsim.correction.identification.actuator_result.ActuatorFit` also writes ``[<corner>.fit]`` with its
        diagnostics (orders, band, held-out error, per-band errors, bandwidth, poles, zeros).
    meta : Mapping, optional
        The ``[meta]`` table: strings, numbers, booleans or lists of them (e.g. source, date,
        drive rms in m, record length in s).

    Raises
    ------
    ActuatorFileError
        No corner, a corner name that is reserved or empty, coefficients that are not finite, a
        zero denominator (nothing is written).

    Examples
    --------
    Two corners' T_a as ``(num, den)``, s in rad/s (an identified
    :class:`~rigsim.correction.identification.actuator_result.ActuatorFit` also writes its diagnostics):

    >>> import pathlib, tempfile
    >>> from rigsim.correction.io.actuator_file import read_actuators_file, write_actuators_file
    >>> acts = pathlib.Path(tempfile.mkdtemp()) / "actuators.toml"
    >>> write_actuators_file(acts, {"fl": ([1.0], [1.1e-4, 0.0106, 1.0]),
    ...                             "fr": ([1.0], [1.2e-4, 0.0110, 1.0])},
    ...                      meta={"source": "sine sweep, 2 mm rms"})
    >>> print(acts.read_text())
    [meta]
    source = "sine sweep, 2 mm rms"
    <BLANKLINE>
    [fl]
    num = [1.0]
    den = [0.00011, 0.0106, 1.0]
    <BLANKLINE>
    [fr]
    num = [1.0]
    den = [0.00012, 0.011, 1.0]
    <BLANKLINE>
    >>> sorted(read_actuators_file(acts))
    ['fl', 'fr']
    """
    if not isinstance(actuators, Mapping) or not actuators:
        raise ActuatorFileError("actuators must map at least one corner name to its T_a")
    doc: dict = {}
    if meta:
        doc["meta"] = dict(meta)
    for corner, ta in actuators.items():
        if not isinstance(corner, str) or not corner or corner in _NOT_CORNERS:
            raise ActuatorFileError(f"corner name {corner!r} cannot be a table of an actuator file; use a name "
                                    f"other than {', '.join(_NOT_CORNERS)}")
        num, den = ta.as_tf() if isinstance(ta, ActuatorFit) else ta
        num, den = np.atleast_1d(np.asarray(num, float)), np.atleast_1d(np.asarray(den, float))
        if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den)) and num.size and den.size):
            raise ActuatorFileError(f"{corner}'s T_a must have finite coefficients (descending powers of s)")
        if not np.any(den != 0):  # what parse_actuators refuses is never written
            raise ActuatorFileError(f"{corner}'s T_a has a zero denominator; give it in descending powers of s")
        doc[corner] = {"num": num.tolist(), "den": den.tolist()}
        if isinstance(ta, ActuatorFit):
            fit = ta.to_dict()
            doc[corner]["fit"] = {k: v for k, v in fit.items() if k not in ("num", "den")}
    write_toml(path, doc)
