"""Which channels of a record are corrected, and the corner of each.

Shared by the linear correction and the model correction (:mod:`rigsim.scenarios.records.api`):
``columns``, ``corner_map`` and ``identify`` read in their text form (``"A,B"``,
``"fl=Fz_FL,..."``, ``"DRIVE,DISP"``) or as Python sequences (:func:`parse_columns`,
:func:`parse_corner_map`, :func:`parse_identify`), the channels they name so that a file is read
with only those (:func:`wanted_channels`), each name as given matched to the name as read
(:func:`resolver`), and the force channels chosen and checked (:func:`plan_channels`): a corner
corrects the force channel whose name holds the corner as a token (``tire_force_fl_N``,
``Fz_FL``, case-insensitive, :func:`names_corner`) or the one ``corner_map`` gives. Every refusal
is a :class:`rigsim.scenarios.core.config.ScenarioError` of one sentence naming the channel and the fix,
the parameter named as the caller's :class:`~rigsim.scenarios.records.naming.Naming` says. Imports
nothing heavy at module level (the parser's start-up stays light).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

from rigsim.scenarios.records.naming import KEYWORDS, Naming

__all__ = ["FORCE_UNITS", "LENGTH_UNITS", "split_columns", "names_corner", "map_items", "check_map", "auto_map",
           "parse_columns", "parse_corner_map", "parse_identify", "wanted_channels", "read_record", "resolver",
           "unit_text", "plan_channels"]

#: SI units of forces, lengths as the reader returns them ("": none given, taken as SI).
FORCE_UNITS, LENGTH_UNITS = ("N", ""), ("m", "")

#: Whose corners ``corner_map`` and the name tokens are matched against, in the linear correction's messages.
ACTUATOR_FILE = "the actuator file"


def _error(message: str):
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


def split_columns(text: str, option: str) -> list[str]:
    """``"A,B"`` -> ``["A", "B"]``; an empty name is refused naming ``option``."""
    cols = [c.strip() for c in text.split(",")]
    if not all(cols):
        raise _error(f"{option} {text!r} has an empty channel name; give names separated by commas")
    return cols


def _tokens(name: str) -> list[str]:
    return [t for t in re.split(r"[^0-9a-z]+", name.lower()) if t]


def names_corner(column: str, corner: str) -> bool:
    """True when ``corner``'s tokens appear consecutively among ``column``'s (case-insensitive)."""
    col, cor = _tokens(column), _tokens(corner)
    return bool(cor) and any(col[i:i + len(cor)] == cor for i in range(len(col) - len(cor) + 1))


def map_items(text: str, naming: Naming = KEYWORDS) -> list[tuple[str, str]]:
    """``"fl=Fz_FL,fr=Fz_FR"`` as (corner, channel) pairs; syntax only."""
    items = []
    for item in split_columns(text, naming("corner_map")):
        corner, sep, col = (x.strip() for x in item.partition("="))
        if not sep or not corner or not col:
            raise _error(f"{naming('corner_map')} item {item!r} must be CORNER=COLUMN, e.g. fl=Fz_FL")
        items.append((corner, col))
    return items


def check_map(items, corners, names, owner: str = ACTUATOR_FILE, naming: Naming = KEYWORDS) -> dict[str, str]:
    """``corner_map`` items checked against the ``corners`` of ``owner`` and the input's channel ``names``."""
    out, opt = {}, naming("corner_map")
    for corner, col in items:
        if corner not in corners:
            raise _error(f"{opt} names corner {corner!r}, which is not in {owner} (its corners are "
                         f"{', '.join(corners)})")
        if col not in names:
            raise _error(f"{opt} names column {col!r}, which is not in the input (its columns are {', '.join(names)})")
        if corner in out:
            raise _error(f"{opt} gives corner {corner!r} twice; give each corner one column")
        out[corner] = col
    return out


def auto_map(corners, pool, restricted: bool, owner: str = ACTUATOR_FILE, naming: Naming = KEYWORDS) -> dict[str, str]:
    """Corner -> column by name tokens; one sentence naming the corner (or column) and the fix."""
    out = {}
    if restricted:  # every asked column needs exactly one corner
        for col in pool:
            hits = [c for c in corners if names_corner(col, c)]
            if len(hits) != 1:
                what = "no corner" if not hits else f"several corners ({', '.join(hits)})"
                raise _error(f"column {col!r} names {what} of {owner} (corners {', '.join(corners)}); "
                             f"fix: {naming.setting('corner_map', f'CORNER={col}')}")
            if hits[0] in out:
                raise _error(f"columns {out[hits[0]]!r} and {col!r} both name corner {hits[0]!r}; fix: "
                             f"{naming.setting('corner_map', f'{hits[0]}=COLUMN')}")
            out[hits[0]] = col
        return out
    for corner in corners:
        hits = [col for col in pool if names_corner(col, corner)]
        if len(hits) != 1:
            what = "no column" if not hits else f"several columns ({', '.join(hits)})"
            raise _error(f"corner {corner!r} of {owner} matches {what} of the input; fix: "
                         f"{naming.setting('corner_map', f'{corner}=COLUMN')} (or {naming('columns')} naming the "
                         "force columns)")
        out[corner] = hits[0]
    return out


def _names(value, key: str, naming: Naming) -> list[str]:
    """A text ``"A,B"`` or a sequence of channel names as a list; an empty name refused."""
    if isinstance(value, str):
        return split_columns(value, naming(key))
    names = [str(c).strip() for c in value]
    if not all(names):
        raise _error(f"{naming(key)} {value!r} has an empty channel name; give names separated by commas")
    return names


def parse_identify(value, naming: Naming = KEYWORDS) -> list[str]:
    """``identify`` (``"DRIVE,DISP"`` or two names) as [drive, displacement]; [] when None; one
    channel given twice refused."""
    if value is None:
        return []
    cols = _names(value, "identify", naming)
    if len(cols) != 2:
        raise _error(f"{naming('identify')} needs two columns DRIVE_COL,DISP_COL, got {value!r}")
    if cols[0].lower() == cols[1].lower():
        raise _error(f"{naming('identify')} names channel {cols[0]!r} twice (the same channel as drive and "
                     "displacement); give DRIVE_COL,DISP_COL, the drive and the pan displacement (LVDT)")
    return cols


def parse_columns(value, naming: Naming = KEYWORDS) -> list[str] | None:
    """``columns`` (``"A,B"`` or names) as a list, None when not given; a name twice refused."""
    if value is None:
        return None
    asked = _names(value, "columns", naming)
    if len(set(asked)) != len(asked):
        raise _error(f"{naming('columns')} {value!r} names a column twice; name each column once")
    return asked


def parse_corner_map(value, naming: Naming = KEYWORDS) -> list[tuple[str, str]] | None:
    """``corner_map`` (``"fl=Fz_FL,..."``, a mapping or (corner, channel) pairs) as pairs; None when not given."""
    if value is None:
        return None
    if isinstance(value, str):
        return map_items(value, naming)
    pairs = value.items() if isinstance(value, Mapping) else value
    items = []
    for item in pairs:
        if isinstance(item, str) or len(item) != 2 or not all(str(x).strip() for x in item):
            raise _error(f"{naming('corner_map')} item {item!r} must be CORNER=COLUMN, e.g. fl=Fz_FL")
        items.append((str(item[0]).strip(), str(item[1]).strip()))
    return items


def wanted_channels(asked, items, id_cols) -> list[str] | None:
    """The channels to read: those named by ``asked`` (columns), ``items`` (corner map) and ``id_cols``
    (never corrected), in that order; None (every numeric channel) when neither columns nor map is given."""
    if asked is None and items is None:
        return None
    return list(dict.fromkeys((asked or []) + [c for _, c in items or []] + list(id_cols)))


def read_record(path, *, time_col: str | None = None, channels=None, decimal: str | None = None,
                thousands: str | None = None):
    """Read a rig's record: its channels in SI on its uniform time axis.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        .csv/.txt/.dat in any dialect, .rsp/.drv/.tim/.rpc (RPC III), .mf4/.mdf (MDF4), .tdms.
    time_col : str, optional
        The time column (default: the one with a time name: ``time``, ``t``, ``zeit``...).
    channels : sequence of str, optional
        Only these channels, in this order (a name may be a header as written, or differ by case);
        default: every numeric channel.
    decimal : {".", ","}, optional
        A text file's decimal mark (default: decided by its numbers).
    thousands : {"none", ",", ".", "'", "space"}, optional
        A text file's thousands separator (default: detected).

    Returns
    -------
    rigsim.correction.io.measured.MeasuredChannels
        ``time_s`` (s), ``data`` in SI (a force in kN is read in N, a length in mm in m), ``units``,
        ``source_units``, ``fs_hz`` (Hz), ``metadata``, ``path``.

    Raises
    ------
    ScenarioError
        One sentence naming the file and the column, line, unit or option at fault
        (:func:`rigsim.correction.io.measured.read_channels`).

    Examples
    --------
    A semicolon-separated file with decimal commas, a force in kN and a displacement in mm, read
    in SI:

    >>> import pathlib, tempfile
    >>> from rigsim import read_record
    >>> rig = pathlib.Path(tempfile.mkdtemp()) / "rig.csv"
    >>> rows = [f"{i / 500:.3f};{40 + i % 3:.1f};{1.5 + i % 2:.1f}".replace(".", ",") for i in range(6)]
    >>> _ = rig.write_text("\\n".join(["time;Fz_FL [kN];Weg_FL [mm]", *rows]) + "\\n")
    >>> record = read_record(rig)
    >>> record.fs_hz, dict(record.units), dict(record.source_units)
    (500.0, {'Fz_FL': 'N', 'Weg_FL': 'm'}, {'Fz_FL': 'kN', 'Weg_FL': 'mm'})
    >>> print(record.data["Fz_FL"][:3], record.data["Weg_FL"][:2])
    [40000. 41000. 42000.] [0.0015 0.0025]
    """
    from rigsim.correction.io.measured import MeasuredDataError, read_channels
    from rigsim.correction.io.tomlfile import path_text
    from rigsim.scenarios.core.config import ScenarioError

    from rigsim.scenarios.records.arguments import shown

    path = path_text(path, "path", ScenarioError)
    if channels is not None and (isinstance(channels, (str, bytes)) or not isinstance(channels, Sequence)
                                 or not channels or not all(isinstance(c, str) for c in channels)):
        raise ScenarioError(f"channels must be a sequence of channel names (str), e.g. ['Fz_FL', 'Weg_FL'], "
                            f"got {shown(channels)}")
    for key, value in (("time_col", time_col), ("decimal", decimal), ("thousands", thousands)):
        if value is not None and not isinstance(value, str):
            raise ScenarioError(f"{key} must be a text (a column's name or a mark) or None, got {shown(value)}")
    try:
        return read_channels(path, time_col=time_col, channels=list(channels) if channels is not None else None,
                             decimal=decimal, thousands=thousands)
    except MeasuredDataError as exc:
        raise _error(str(exc)) from None


def resolver(mc, as_read: Mapping | None = None):
    """name -> the channel of ``mc`` it names: itself, the name ``as_read`` gives it (the reader matched
    it to a header as written, or by case), or the one channel equal to it but for case; else itself."""
    names, as_read = list(mc.names), dict(as_read or {})
    low = [n.lower() for n in names]

    def name(given: str) -> str:
        if given in names:
            return given
        if given in as_read:
            return as_read[given]
        return names[low.index(given.lower())] if low.count(given.lower()) == 1 else given

    return name


def unit_text(mc, name: str) -> str:
    """The unit of channel ``name`` as the file wrote it, for messages."""
    return mc.source_units.get(name) or mc.units.get(name) or "no unit"


def plan_channels(mc, asked, items, id_cols, corners, owner: str = ACTUATOR_FILE, naming: Naming = KEYWORDS):
    """(channels to correct, ``id_cols``, corner of each channel or None); checks only.

    ``mc``: the record (:class:`rigsim.correction.io.measured.MeasuredChannels`); ``asked``, ``items``: the
    columns and corner-map pairs (names as read), None when not given; ``id_cols``: the drive and
    displacement channels (``identify``, ``pairs``), never corrected; ``corners``: the corner
    names of ``owner`` (the per-corner actuator file, the truck model), None: no corners.
    """
    names, time_name = list(mc.names), mc.time_name
    for col in id_cols + (asked or []):
        if col == time_name:
            raise _error(f"column {col!r} is the time column and cannot be corrected or used to identify")
        if col not in names:
            raise _error(f"column {col!r} is not in {str(mc.path)!r}; its columns are {', '.join(names)}")
    for col in id_cols:
        if mc.units[col] not in LENGTH_UNITS:
            raise _error(f"{naming('identify')} channel {col!r} is in {unit_text(mc, col)}, not a length; give the drive and "
                         "the pan displacement (m, mm...)")
    pool = asked if asked is not None else [n for n in names if n not in id_cols and mc.units[n] in FORCE_UNITS]
    if corners is None:
        cols, mapped = pool, None
    else:
        if items is not None:
            mapping = check_map(items, corners, names, owner, naming)
            if asked is not None:
                missing = [c for c in asked if c not in mapping.values()]
                if missing:
                    raise _error(f"column {missing[0]!r} is not mapped to a corner; fix: add CORNER={missing[0]} to "
                                 f"{naming('corner_map')}")
                mapping = {k: v for k, v in mapping.items() if v in asked}
        else:
            mapping = auto_map(corners, pool, asked is not None, owner, naming)
        cols, mapped = list(mapping.values()), list(mapping)
        dup = sorted({c for c in cols if cols.count(c) > 1})
        if dup:
            raise _error(f"column {dup[0]!r} is mapped to several corners; fix: {naming('corner_map')} each corner to "
                         "its own column")
    for col in cols:
        if col == time_name:
            raise _error(f"column {time_name!r} is the time column and cannot be corrected; fix: {naming('corner_map')}")
        if mc.units[col] not in FORCE_UNITS:
            raise _error(f"channel {col!r} is in {unit_text(mc, col)}, not a force; name the force channels (N, "
                         f"kN...) with {naming('columns')} or {naming('corner_map')}")
    return cols, id_cols, mapped
