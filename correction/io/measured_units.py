"""Units of measured channels: names decorated with units, and their conversion to SI.

A small explicit table, not pint: pint (0.25.3 installs here) reads several units of
test-lab files wrongly without a word: ``g`` is a gram (an accelerometer's ``g`` is
9.80665 m/s^2), ``Nm`` and ``kNm`` parse to 1e3 and 1e6 m/kg instead of a torque, a lowercase
``kn`` is a knot, ``-`` raises an AssertionError; its base units are kg m/s^2 rather than N, and
its import with a registry takes 0.7 s. The units of rig channels are few; a table that names
each one is exact, fast and reviewable.

Conventions (the readers of :mod:`rigsim.correction.io.measured` rely on them):

* values in SI: ``si = value * factor + offset`` (the offset only for degC -> K);
* a unit is looked up as written (``mm``/``Mm``, ``kN``) and, failing that, case-insensitively
  when that is unambiguous in the table (``KN`` -> kN, ``MM`` -> mm); ``µ``/``μ`` read as ``u``,
  ``²``/``³`` as ``^2``/``^3``;
* dimensionless: ``-``, ``1`` and ``%`` give SI unit ``"1"``; ``%`` is converted to a fraction
  (50 % -> 0.5), the ``%`` is kept in ``source_units``;
* ``g`` is standard gravity (acceleration), never a gram; ``°C``/``degC`` become K;
* no unit (``""``, ``NONE``) means the value is taken as SI as it stands; the SI unit is then the
  one a name suffix gives (``force_N``, ``disp_m``, ``p_Pa``, ``time_s``) or ``""`` when there is
  none.
"""

from __future__ import annotations

import math
import re

__all__ = ["UNITS", "SUFFIX_UNITS", "lookup_unit", "split_name_unit", "suffix_unit"]

_G = 9.80665
_LBF = 4.4482216152605
_PSI = 6894.757293168361

#: unit as written -> (SI unit, factor, offset): si = value * factor + offset.
UNITS: dict[str, tuple[str, float, float]] = {
    # time
    "s": ("s", 1.0, 0.0), "sec": ("s", 1.0, 0.0), "ms": ("s", 1e-3, 0.0), "us": ("s", 1e-6, 0.0),
    "ns": ("s", 1e-9, 0.0), "min": ("s", 60.0, 0.0), "h": ("s", 3600.0, 0.0),
    # force
    "N": ("N", 1.0, 0.0), "mN": ("N", 1e-3, 0.0), "kN": ("N", 1e3, 0.0), "daN": ("N", 10.0, 0.0),
    "MN": ("N", 1e6, 0.0), "lbf": ("N", _LBF, 0.0), "klbf": ("N", 1e3 * _LBF, 0.0),
    "kip": ("N", 1e3 * _LBF, 0.0), "kgf": ("N", _G, 0.0),
    # length
    "m": ("m", 1.0, 0.0), "cm": ("m", 1e-2, 0.0), "mm": ("m", 1e-3, 0.0), "um": ("m", 1e-6, 0.0),
    "in": ("m", 0.0254, 0.0), "inch": ("m", 0.0254, 0.0), "ft": ("m", 0.3048, 0.0),
    # pressure
    "Pa": ("Pa", 1.0, 0.0), "hPa": ("Pa", 1e2, 0.0), "kPa": ("Pa", 1e3, 0.0), "MPa": ("Pa", 1e6, 0.0),
    "bar": ("Pa", 1e5, 0.0), "mbar": ("Pa", 1e2, 0.0), "psi": ("Pa", _PSI, 0.0), "ksi": ("Pa", 1e3 * _PSI, 0.0),
    # velocity, acceleration
    "m/s": ("m/s", 1.0, 0.0), "mm/s": ("m/s", 1e-3, 0.0), "cm/s": ("m/s", 1e-2, 0.0),
    "in/s": ("m/s", 0.0254, 0.0), "km/h": ("m/s", 1 / 3.6, 0.0),
    "m/s^2": ("m/s^2", 1.0, 0.0), "m/s2": ("m/s^2", 1.0, 0.0), "mm/s^2": ("m/s^2", 1e-3, 0.0),
    "g": ("m/s^2", _G, 0.0),
    # frequency, angle, temperature
    "Hz": ("Hz", 1.0, 0.0), "kHz": ("Hz", 1e3, 0.0),
    "rad": ("rad", 1.0, 0.0), "mrad": ("rad", 1e-3, 0.0), "deg": ("rad", math.pi / 180, 0.0),
    "°": ("rad", math.pi / 180, 0.0),
    "K": ("K", 1.0, 0.0), "degC": ("K", 1.0, 273.15), "°C": ("K", 1.0, 273.15),
    # electrical (servo-valve commands, conditioning outputs)
    "V": ("V", 1.0, 0.0), "mV": ("V", 1e-3, 0.0), "A": ("A", 1.0, 0.0), "mA": ("A", 1e-3, 0.0),
    # moment, stiffness, flow
    "N*m": ("N*m", 1.0, 0.0), "Nm": ("N*m", 1.0, 0.0), "N.m": ("N*m", 1.0, 0.0),
    "kN*m": ("N*m", 1e3, 0.0), "kNm": ("N*m", 1e3, 0.0), "kN.m": ("N*m", 1e3, 0.0),
    "N/m": ("N/m", 1.0, 0.0), "N/mm": ("N/m", 1e3, 0.0), "kN/mm": ("N/m", 1e6, 0.0),
    "m^3/s": ("m^3/s", 1.0, 0.0), "l/min": ("m^3/s", 1e-3 / 60, 0.0), "L/min": ("m^3/s", 1e-3 / 60, 0.0),
    "lpm": ("m^3/s", 1e-3 / 60, 0.0),
    # mass (a lone "g" is gravity, see above)
    "kg": ("kg", 1.0, 0.0),
    # dimensionless
    "-": ("1", 1.0, 0.0), "1": ("1", 1.0, 0.0), "%": ("1", 1e-2, 0.0),
}

#: Units a bare name suffix may carry (``time_ms``, ``force_N``): only those that read as no
#: ordinary word ending (no ``_in``, ``_g``, ``_A``, ``_V``, ``_K``), matched case-sensitively.
SUFFIX_UNITS = frozenset({"s", "ms", "us", "N", "kN", "daN", "m", "cm", "mm", "um", "Pa", "kPa", "MPa",
                          "bar", "Hz", "rad", "deg", "degC"})

_NO_UNIT = frozenset({"", "none", "NONE", "None"})


def _lower_table() -> dict[str, str]:
    seen: dict[str, list[str]] = {}
    for key in UNITS:
        seen.setdefault(key.lower(), []).append(key)
    return {low: keys[0] for low, keys in seen.items() if len(keys) == 1}


_LOWER = _lower_table()


def _normal(unit: str) -> str:
    u = unit.strip().replace("µ", "u").replace("μ", "u").replace("²", "^2").replace("³", "^3")
    u = u.replace("**", "^").replace("·", "*").replace(" ", "")
    return u


def lookup_unit(unit: str) -> tuple[str, float, float] | None:
    """``(SI unit, factor, offset)`` of a unit as written, ``("", 1, 0)`` for none, None if unknown.

    Parameters
    ----------
    unit : str
        As written in the file (``"kN"``, ``"[mm]"`` without the brackets, ``"µm"``, ``"NONE"``).
    """
    u = _normal(unit)
    if u in _NO_UNIT:
        return ("", 1.0, 0.0)
    if u in UNITS:
        return UNITS[u]
    key = _LOWER.get(u.lower())
    return UNITS[key] if key is not None else None


def suffix_unit(name: str) -> str:
    """The unit a name's suffix gives (``"time_ms"`` -> ``"ms"``, ``"Fz_FL"`` -> ``""``)."""
    base, sep, suffix = name.rpartition("_")
    return suffix if sep and base and suffix in SUFFIX_UNITS else ""


_BRACKETS = re.compile(r"^(?P<name>.*?)\s*\[(?P<unit>[^\[\]]*)\]\s*$")
_PARENS = re.compile(r"^(?P<name>.*?)\s*\((?P<unit>[^()]*)\)\s*$")
_SLASH = re.compile(r"^(?P<name>[^/]*?)\s*/\s*(?P<unit>[^/\s]+)\s*$")
_IN = re.compile(r"^(?P<name>.*?\S)\s+in\s+(?P<unit>\S+)$")


def split_name_unit(header: str) -> tuple[str, str | None]:
    """Split a header field into the channel name and the unit written with it.

    ``"Fz_FL [kN]"``, ``"Fz_FL[kN]"`` -> ``("Fz_FL", "kN")`` (brackets always hold a unit, known or
    not); ``"Time (s)"`` -> ``("Time", "s")`` and ``"Zeit/s"``, ``"Kraft in kN"`` -> the same way,
    but only when the part in parentheses, after the slash or after "in" is a known unit
    (``"Force (front)"`` stays a name); ``"[]"`` is no unit. Otherwise ``(header, None)``: no unit
    was written (a name suffix may still give one, see :func:`suffix_unit`).
    """
    text = header.strip()
    m = _BRACKETS.match(text)
    if m and m.group("name"):
        return m.group("name").strip(), m.group("unit").strip()
    for pattern in (_PARENS, _SLASH, _IN):
        m = pattern.match(text)
        if m and m.group("name").strip() and m.group("unit").strip() \
                and lookup_unit(m.group("unit")) not in (None, ("", 1.0, 0.0)):
            return m.group("name").strip(), m.group("unit").strip()
    return text, None


def strip_unit_field(field: str) -> str:
    """A units-row field without its brackets: ``"[kN]"``, ``"(kN)"``, ``"kN"`` -> ``"kN"``."""
    f = field.strip()
    if len(f) >= 2 and f[0] + f[-1] in ("[]", "()", "{}", "<>"):
        f = f[1:-1].strip()
    return f
