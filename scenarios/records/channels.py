"""Which channels of a measured file ``rigsim correct`` corrects, and the corner of each.

Shared by the linear correction (:mod:`scenarios.cli.correct`) and the model correction
(:mod:`scenarios.cli.correct_model`): ``--columns``, ``--map`` and ``--identify`` parsed
(:func:`parse_options`), the file read once with only the channels they name
(:func:`read_input`), and the force channels chosen and checked (:func:`plan_channels`): a corner
corrects the force channel whose name holds the corner as a token (``tire_force_fl_N``,
``Fz_FL``, case-insensitive, :func:`names_corner`) or the one ``--map`` gives. Every refusal is a
:class:`scenarios.core.config.ScenarioError` of one sentence naming the channel and the fix.
Imports nothing heavy at module level (the parser's start-up stays light).
"""

from __future__ import annotations

import re

__all__ = ["FORCE_UNITS", "LENGTH_UNITS", "split_columns",
           "names_corner", "map_items", "check_map", "auto_map", "parse_options", "read_input", "unit_text",
           "plan_channels"]

#: SI units of forces, lengths as the reader returns them ("": none given, taken as SI).
FORCE_UNITS, LENGTH_UNITS = ("N", ""), ("m", "")

#: ``--decimal`` and ``--thousands`` choices: :data:`correction.io.measured_numbers.DECIMALS` and
#: ``THOUSANDS`` (not imported here, to keep the parser light).

#: Whose corners ``--map`` and the name tokens are matched against, in the linear correction's messages.
ACTUATOR_FILE = "the actuator file"


def _error(message: str):
    from scenarios.core.config import ScenarioError

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


def map_items(text: str) -> list[tuple[str, str]]:
    """``--map`` as (corner, channel) pairs; syntax only."""
    items = []
    for item in split_columns(text, "--map"):
        corner, sep, col = (x.strip() for x in item.partition("="))
        if not sep or not corner or not col:
            raise _error(f"--map item {item!r} must be CORNER=COLUMN, e.g. fl=Fz_FL")
        items.append((corner, col))
    return items


def check_map(items, corners, names, owner: str = ACTUATOR_FILE) -> dict[str, str]:
    """``--map`` items checked against the ``corners`` of ``owner`` and the input's channel ``names``."""
    out = {}
    for corner, col in items:
        if corner not in corners:
            raise _error(f"--map names corner {corner!r}, which is not in {owner} (its corners are "
                         f"{', '.join(corners)})")
        if col not in names:
            raise _error(f"--map names column {col!r}, which is not in the input (its columns are {', '.join(names)})")
        if corner in out:
            raise _error(f"--map gives corner {corner!r} twice; give each corner one column")
        out[corner] = col
    return out


def auto_map(corners, pool, restricted: bool, owner: str = ACTUATOR_FILE) -> dict[str, str]:
    """Corner -> column by name tokens; one sentence naming the corner (or column) and the fix."""
    out = {}
    if restricted:  # every asked column needs exactly one corner
        for col in pool:
            hits = [c for c in corners if names_corner(col, c)]
            if len(hits) != 1:
                what = "no corner" if not hits else f"several corners ({', '.join(hits)})"
                raise _error(f"column {col!r} names {what} of {owner} (corners {', '.join(corners)}); "
                             f"fix: --map CORNER={col}")
            if hits[0] in out:
                raise _error(f"columns {out[hits[0]]!r} and {col!r} both name corner {hits[0]!r}; fix: --map "
                             f"{hits[0]}=COLUMN")
            out[hits[0]] = col
        return out
    for corner in corners:
        hits = [col for col in pool if names_corner(col, corner)]
        if len(hits) != 1:
            what = "no column" if not hits else f"several columns ({', '.join(hits)})"
            raise _error(f"corner {corner!r} of {owner} matches {what} of the input; fix: "
                         f"--map {corner}=COLUMN (or --columns naming the force columns)")
        out[corner] = hits[0]
    return out


def parse_options(args):
    """(--columns list or None, --map items or None, --identify channels); syntax only."""
    id_cols = split_columns(args.identify, "--identify") if args.identify is not None else []
    if args.identify is not None and len(id_cols) != 2:
        raise _error(f"--identify needs two columns DRIVE_COL,DISP_COL, got {args.identify!r}")
    asked = split_columns(args.columns, "--columns") if args.columns is not None else None
    if asked is not None and len(set(asked)) != len(asked):
        raise _error(f"--columns {args.columns!r} names a column twice; name each column once")
    items = map_items(args.map) if args.map is not None else None
    return asked, items, id_cols


def read_input(args, asked, items, id_cols):
    """The input's channels (every numeric one, or only those named by --columns, --map and
    ``id_cols``), and each name as given -> the name as read (a CSV header may match by case)."""
    from correction.io.measured import MeasuredDataError, read_channels

    wanted = None
    if asked is not None or items is not None:
        wanted = list(dict.fromkeys((asked or []) + [c for _, c in items or []] + list(id_cols)))
    try:
        mc = read_channels(args.input, time_col=args.time_col, channels=wanted, decimal=args.decimal,
                           thousands=args.thousands)
    except MeasuredDataError as exc:
        raise _error(str(exc)) from None
    alias = dict(zip(wanted, mc.names)) if wanted is not None else {}
    return mc, (lambda name: alias.get(name, name))


def unit_text(mc, name: str) -> str:
    """The unit of channel ``name`` as the file wrote it, for messages."""
    return mc.source_units.get(name) or mc.units.get(name) or "no unit"


def plan_channels(args, mc, asked, items, id_cols, corners, owner: str = ACTUATOR_FILE):
    """(channels to correct, ``id_cols``, corner of each channel or None); checks only.

    ``id_cols``: the drive and displacement channels (``--identify``), never corrected; ``corners``:
    the corner names of ``owner`` (the ``--actuators`` file, the truck model), None: no corners.
    """
    names, time_name = list(mc.names), mc.time_name
    for col in id_cols + (asked or []):
        if col == time_name:
            raise _error(f"column {col!r} is the time column and cannot be corrected or used to identify")
        if col not in names:
            raise _error(f"column {col!r} is not in {str(args.input)!r}; its columns are {', '.join(names)}")
    for col in id_cols:
        if mc.units[col] not in LENGTH_UNITS:
            raise _error(f"--identify channel {col!r} is in {unit_text(mc, col)}, not a length; give the drive and "
                         "the pan displacement (m, mm...)")
    pool = asked if asked is not None else [n for n in names if n not in id_cols and mc.units[n] in FORCE_UNITS]
    if corners is None:
        cols, mapped = pool, None
    else:
        if items is not None:
            mapping = check_map(items, corners, names, owner)
            if asked is not None:
                missing = [c for c in asked if c not in mapping.values()]
                if missing:
                    raise _error(f"column {missing[0]!r} is not mapped to a corner; fix: add CORNER={missing[0]} to "
                                 "--map")
                mapping = {k: v for k, v in mapping.items() if v in asked}
        else:
            mapping = auto_map(corners, pool, asked is not None, owner)
        cols, mapped = list(mapping.values()), list(mapping)
        dup = sorted({c for c in cols if cols.count(c) > 1})
        if dup:
            raise _error(f"column {dup[0]!r} is mapped to several corners; fix: --map each corner to its own column")
    for col in cols:
        if col == time_name:
            raise _error(f"column {time_name!r} is the time column and cannot be corrected; fix: --map")
        if mc.units[col] not in FORCE_UNITS:
            raise _error(f"channel {col!r} is in {unit_text(mc, col)}, not a force; name the force channels (N, "
                         "kN...) with --columns or --map")
    return cols, id_cols, mapped
