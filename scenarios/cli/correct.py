"""``rigsim correct``: output correction of wheel forces measured on a real rig.

::

    rigsim correct IN (--actuator ACT.toml | --actuators ACTS.toml [--map fl=CH,...]
                   | --identify DRIVE_CH,DISP_CH) -o OUT [--force] [--time-col NAME]
                   [--lowpass paper|regularized] [--mode causal|zerophase] [--columns A,B]
                   [--transient drop|mark|keep]

``IN`` is read by :func:`correction.measured.read_channels` (any CSV dialect, RPC III, MDF4, TDMS),
its channels named as the reader returns them (``Fz_FL`` for a header ``Fz_FL [kN]``) and in SI,
so a force in kN is corrected in N. Without ``--columns``/``--map`` every numeric channel is read
and the force channels (unit N, kN... or none) are the candidates; with them only the named
channels are read. A chosen channel that is not a force is refused. ``T_a`` comes from
``--actuator`` (one actuator file, :mod:`correction.actuator_file`, for every channel),
``--actuators`` (one ``T_a`` per corner; a corner corrects the channel whose name holds the
corner as a token, ``tire_force_fl_N`` or ``Fz_FL``, case-insensitive, or the one ``--map``
gives) or ``--identify`` (the drive and pan displacement channels of the same file, fitted by
:func:`correction.actuator_fit.fit_actuator`). The one correction is
:func:`correction.pipeline.correct_forces`.

``OUT`` is written by :func:`correction.measured.write_channels` in its extension's format: the
time (s) and ``<channel>_corrected`` in N (and ``settled``, 0/1, with ``--transient mark``;
``drop``, the default, leaves out the correction's transients, ``keep`` keeps them), with
metadata on how it was made (input, T_a source, low-pass, mode, settling tolerance, rigsim
version). The per-channel DLC, stress factor and damage-equivalent load before and after
correction are printed. Bad input raises :class:`scenarios.core.config.ScenarioError` (one
sentence naming the channel or line and the fix) and nothing is written; ``-o`` naming an input,
or an existing file without ``--force``, is refused before any work.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import re

__all__ = ["add_parser", "cmd_correct", "SETTLING_TOLERANCE"]

#: Tolerance (1) of the correction filters' start-up and run-out transients: the samples kept.
SETTLING_TOLERANCE = 1e-3

_FORCE_UNITS, _LENGTH_UNITS = ("N", ""), ("m", "")  # SI units of forces, lengths ("": none given, taken as SI)


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register ``correct`` on an ``argparse`` sub-parsers object; sets ``func=cmd_correct``."""
    c = subparsers.add_parser(
        "correct", help="correct wheel forces measured on a rig (CSV, RPC III, MDF4, TDMS) for the actuator dynamics",
        description="Filter measured wheel forces by the inverse actuator transfer function times a "
                    "low-pass (the paper's output correction) and write them, in N, to a new file.")
    c.add_argument("input", metavar="IN", help="measured file (.csv/.txt/.dat in any dialect, RPC III .rsp/.drv/.tim, "
                   ".mf4, .tdms) on a uniform time axis; units converted to SI (kN -> N, mm -> m)")
    c.add_argument("--time-col", metavar="NAME", help="the time column (default: the one named time, t, zeit...)")
    c.add_argument("--actuator", metavar="ACT.toml",
                   help="actuator file for every channel: [transfer_function] num, den (descending powers of s) "
                        "or [parameters] (eq. 4)")
    c.add_argument("--actuators", metavar="ACTS.toml",
                   help="per-corner actuator file: one table per corner ([fl], [fr], ...) with num, den; each "
                        "corner corrects the force channel whose name holds the corner as a token (or see --map)")
    c.add_argument("--map", metavar="CORNER=CH[,...]",
                   help="with --actuators: the channel (name without [unit]) of each corner, e.g. fl=Fz_FL,fr=Fz_FR")
    c.add_argument("-o", "--out", required=True, metavar="OUT",
                   help="output file (.csv, .rsp RPC III, .mf4, .tdms) with <channel>_corrected in N")
    c.add_argument("--force", action="store_true", help="replace OUT if it exists (never an input file)")
    c.add_argument("--lowpass", choices=("paper", "regularized"), default="regularized",
                   help="paper: eq. 5 (2 x 2nd order, 16/24 Hz, zeta 1; already -3 dB near 8 Hz); "
                        "regularized: 6th-order Butterworth at 30 Hz, inverse ~exact to 20 Hz (default)")
    c.add_argument("--mode", choices=("causal", "zerophase"), default="zerophase",
                   help="zerophase: |T_a^-1 T_F| with T_a^-1's phase, offline (default); causal: as a "
                        "real-time filter (adds T_F's phase lag)")
    c.add_argument("--identify", metavar="DRIVE_CH,DISP_CH",
                   help="identify T_a from these two channels (drive and pan displacement) instead of --actuator")
    c.add_argument("--columns", metavar="CH[,CH...]",
                   help="force channels to correct (default: every force channel but the --identify ones; with "
                        "--actuators, those of the file's corners)")
    c.add_argument("--transient", choices=("drop", "mark", "keep"), default="drop",
                   help="samples inside the filters' transients: drop (default), mark ('settled' channel) or keep")
    c.add_argument("--normalize-dc", action="store_true", help="scale T_a to T_a(0) = 1 instead of refusing it")
    c.set_defaults(func=cmd_correct)
    return c


def _error(message: str):
    from scenarios.core.config import ScenarioError

    return ScenarioError(message)


def _split_columns(text: str, option: str) -> list[str]:
    cols = [c.strip() for c in text.split(",")]
    if not all(cols):
        raise _error(f"{option} {text!r} has an empty channel name; give names separated by commas")
    return cols


def _check_output(out, inputs, force: bool) -> None:
    """Refuse an empty output path, one that names an input file, an existing file without
    ``--force``, a folder, an unwritable folder or an extension no writer knows (before any work)."""
    from correction.measured import WRITE_FORMATS, MeasuredDataError, format_of
    from correction.measured_core import check_output
    from scenarios.core.outputs import check_output_file

    check_output_file(out, "-o", force=True)  # empty, a folder, no permission; an existing file: below
    try:
        check_output(out, overwrite=force, inputs=inputs)
        format_of(out, WRITE_FORMATS)
    except MeasuredDataError as exc:
        raise _error(str(exc).replace(" (overwrite=True)", "")) from None


def _tokens(name: str) -> list[str]:
    return [t for t in re.split(r"[^0-9a-z]+", name.lower()) if t]


def _names_corner(column: str, corner: str) -> bool:
    """True when ``corner``'s tokens appear consecutively among ``column``'s (case-insensitive)."""
    col, cor = _tokens(column), _tokens(corner)
    return bool(cor) and any(col[i:i + len(cor)] == cor for i in range(len(col) - len(cor) + 1))


def _map_items(text: str) -> list[tuple[str, str]]:
    """``--map`` as (corner, channel) pairs; syntax only."""
    items = []
    for item in _split_columns(text, "--map"):
        corner, sep, col = (x.strip() for x in item.partition("="))
        if not sep or not corner or not col:
            raise _error(f"--map item {item!r} must be CORNER=COLUMN, e.g. fl=Fz_FL")
        items.append((corner, col))
    return items


def _check_map(items, corners, names) -> dict[str, str]:
    out = {}
    for corner, col in items:
        if corner not in corners:
            raise _error(f"--map names corner {corner!r}, which is not in the actuator file (its corners are "
                         f"{', '.join(corners)})")
        if col not in names:
            raise _error(f"--map names column {col!r}, which is not in the input (its columns are {', '.join(names)})")
        if corner in out:
            raise _error(f"--map gives corner {corner!r} twice; give each corner one column")
        out[corner] = col
    return out


def _auto_map(corners, pool, restricted: bool) -> dict[str, str]:
    """Corner -> column by name tokens; one sentence naming the corner (or column) and the fix."""
    out = {}
    if restricted:  # every asked column needs exactly one corner
        for col in pool:
            hits = [c for c in corners if _names_corner(col, c)]
            if len(hits) != 1:
                what = "no corner" if not hits else f"several corners ({', '.join(hits)})"
                raise _error(f"column {col!r} names {what} of the actuator file (corners {', '.join(corners)}); "
                             f"fix: --map CORNER={col}")
            if hits[0] in out:
                raise _error(f"columns {out[hits[0]]!r} and {col!r} both name corner {hits[0]!r}; fix: --map "
                             f"{hits[0]}=COLUMN")
            out[hits[0]] = col
        return out
    for corner in corners:
        hits = [col for col in pool if _names_corner(col, corner)]
        if len(hits) != 1:
            what = "no column" if not hits else f"several columns ({', '.join(hits)})"
            raise _error(f"corner {corner!r} of the actuator file matches {what} of the input; fix: "
                         f"--map {corner}=COLUMN (or --columns naming the force columns)")
        out[corner] = hits[0]
    return out


def _options(args):
    """(--columns list or None, --map items or None, --identify channels); syntax only."""
    id_cols = _split_columns(args.identify, "--identify") if args.identify is not None else []
    if args.identify is not None and len(id_cols) != 2:
        raise _error(f"--identify needs two columns DRIVE_COL,DISP_COL, got {args.identify!r}")
    asked = _split_columns(args.columns, "--columns") if args.columns is not None else None
    if asked is not None and len(set(asked)) != len(asked):
        raise _error(f"--columns {args.columns!r} names a column twice; name each column once")
    items = _map_items(args.map) if args.map is not None else None
    return asked, items, id_cols


def _read(args, asked, items, id_cols):
    """The input's channels (every numeric one, or only those named by --columns, --map and
    --identify), and each name as given -> the name as read (a CSV header may match by case)."""
    from correction.measured import MeasuredDataError, read_channels

    wanted = None
    if asked is not None or items is not None:
        wanted = list(dict.fromkeys((asked or []) + [c for _, c in items or []] + id_cols))
    try:
        mc = read_channels(args.input, time_col=args.time_col, channels=wanted)
    except MeasuredDataError as exc:
        raise _error(str(exc)) from None
    alias = dict(zip(wanted, mc.names)) if wanted is not None else {}
    return mc, (lambda name: alias.get(name, name))


def _unit_text(mc, name: str) -> str:
    return mc.source_units.get(name) or mc.units.get(name) or "no unit"


def _plan(args, mc, asked, items, id_cols, corners):
    """(channels to correct, --identify channels, corner of each channel or None); checks only.

    ``corners``: the corner names of the ``--actuators`` file (None without it).
    """
    names, time_name = list(mc.names), mc.time_name
    for col in id_cols + (asked or []):
        if col == time_name:
            raise _error(f"column {col!r} is the time column and cannot be corrected or used to identify")
        if col not in names:
            raise _error(f"column {col!r} is not in {str(args.input)!r}; its columns are {', '.join(names)}")
    for col in id_cols:
        if mc.units[col] not in _LENGTH_UNITS:
            raise _error(f"--identify channel {col!r} is in {_unit_text(mc, col)}, not a length; give the drive and "
                         "the pan displacement (m, mm...)")
    pool = asked if asked is not None else [n for n in names if n not in id_cols and mc.units[n] in _FORCE_UNITS]
    if args.actuators is None:
        cols, mapped = pool, None
    else:
        if items is not None:
            mapping = _check_map(items, corners, names)
            if asked is not None:
                missing = [c for c in asked if c not in mapping.values()]
                if missing:
                    raise _error(f"column {missing[0]!r} is not mapped to a corner; fix: add CORNER={missing[0]} to "
                                 "--map")
                mapping = {k: v for k, v in mapping.items() if v in asked}
        else:
            mapping = _auto_map(corners, pool, asked is not None)
        cols, mapped = list(mapping.values()), list(mapping)
        dup = sorted({c for c in cols if cols.count(c) > 1})
        if dup:
            raise _error(f"column {dup[0]!r} is mapped to several corners; fix: --map each corner to its own column")
    for col in cols:
        if col == time_name:
            raise _error(f"column {time_name!r} is the time column and cannot be corrected; fix: --map")
        if mc.units[col] not in _FORCE_UNITS:
            raise _error(f"channel {col!r} is in {_unit_text(mc, col)}, not a force; name the force channels (N, "
                         "kN...) with --columns or --map")
    return cols, id_cols, mapped


def _read_actuators(args):
    from correction.actuator_file import read_actuator_file, read_actuators_file

    given = [o for o in ("actuator", "actuators", "identify") if getattr(args, o) is not None]
    if len(given) != 1:
        raise _error("give exactly one of --actuator ACT.toml, --actuators ACTS.toml and --identify DRIVE_COL,DISP_COL")
    if args.map is not None and args.actuators is None:
        raise _error("--map maps corners of a per-corner file: use it with --actuators ACTS.toml")
    try:
        if args.actuator is not None:
            return read_actuator_file(args.actuator)
        if args.actuators is not None:
            return read_actuators_file(args.actuators)
    except ValueError as exc:
        raise _error(str(exc)) from None
    return None


def _header_value(text: str) -> str:
    """A metadata value an RPC III header can hold (latin-1, one line, 96 bytes): a longer value
    keeps its end (a path's file name), after '...'."""
    text = " ".join(str(text).split()).encode("latin-1", errors="replace").decode("latin-1")
    return text if len(text) <= 96 else "..." + text[-93:]


def _metadata(args, id_cols, cols, corners) -> dict[str, str]:
    """How the output was made: rigsim version, input, T_a source, low-pass, mode, tolerance."""
    from importlib.metadata import PackageNotFoundError, version

    from correction.lowpass import as_lowpass
    from correction.measured import format_of

    try:
        rigsim = version("rigsim")
    except PackageNotFoundError:  # pragma: no cover - a source tree that is not installed
        rigsim = "unknown (not installed)"
    source = f"identified from {','.join(id_cols)}" if args.identify else str(args.actuator or args.actuators)
    meta = {"made_by": "rigsim correct", "rigsim_version": rigsim, "input": str(args.input), "ta_source": source}
    if corners is not None:
        meta["corners"] = ",".join(f"{k}={c}" for k, c in zip(corners, cols))
    meta.update({"correction": "F_corrected = T_a^-1 T_F F_measured", "force_unit": "N",
                 "lowpass": f"{args.lowpass}: {as_lowpass(args.lowpass).description}", "mode": args.mode,
                 "settling_tolerance": f"{SETTLING_TOLERANCE:g}", "transient": args.transient,
                 "normalize_dc": "yes" if args.normalize_dc else "no"})
    if format_of(args.out) == "rpc3":
        meta = {k: _header_value(v) for k, v in meta.items()}
    return meta


def _probe_output(out, units, meta) -> None:
    """Write two samples of the output's channels and metadata to a scratch file of the same
    format: whatever the writer would refuse (a name, a metadata value, a missing extra) is
    refused now, before the correction."""
    import tempfile
    from types import SimpleNamespace

    from correction.measured import MeasuredDataError, write_channels

    probe = SimpleNamespace(time_s=[0.0, 1.0], data={n: [0.0, 1.0] for n in units}, units=units)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            write_channels(pathlib.Path(tmp) / f"probe{pathlib.Path(out).suffix}", probe, metadata=meta)
        except MeasuredDataError as exc:
            raise _error(f"-o {str(out)!r} cannot be written: {exc}") from None


def _dlc_table(cols, before_N, after_N, fs: float) -> str:
    """Per column, before and after correction (the settled rows): DLC (1) with its change in %,
    the stress factor E[(F/F_static)^4] (1) and the damage-equivalent load for m = 5 at 1 Hz (kN)."""
    from correction.damage import damage_equivalent_load, stress_factor
    from correction.dlc import dlc

    lines = [f"{'column':<24} {'DLC before':>10} {'DLC after':>10} {'change':>8}   "
             f"{'SF4 before':>10} {'SF4 after':>10}   {'DEL5 before':>11} {'DEL5 after':>11}"]
    for j, col in enumerate(cols):
        try:
            b, a = float(dlc(before_N[:, j])), float(dlc(after_N[:, j]))
        except ValueError:  # not a compressive load (mean <= 0): no DLC
            lines.append(f"{col:<24} {'-':>10} {'-':>10} {'-':>8}")
            continue
        sf = [float(stress_factor(x[:, j])) for x in (before_N, after_N)]
        dl = [float(damage_equivalent_load(x[:, j], 5, duration_s=x.shape[0] / fs)) / 1e3 for x in (before_N, after_N)]
        lines.append(f"{col:<24} {b:>10.4f} {a:>10.4f} {100.0 * (a / b - 1.0) if b > 0 else math.nan:>7.1f}%   "
                     f"{sf[0]:>10.4f} {sf[1]:>10.4f}   {dl[0]:>8.2f} kN {dl[1]:>8.2f} kN")
    return "\n".join(lines)


def cmd_correct(args) -> int:
    """Run ``rigsim correct``; returns 0, raises ScenarioError (one sentence) for bad input."""
    from types import SimpleNamespace

    import numpy as np

    from correction.actuator_fit import fit_actuator
    from correction.measured import MeasuredDataError, write_channels
    from correction.pipeline import CorrectionError, correct_forces

    inputs = [args.input, args.actuator, args.actuators]
    _check_output(args.out, inputs, args.force)
    asked, items, id_cols = _options(args)
    ta_file = _read_actuators(args)
    mc, name = _read(args, asked, items, id_cols)
    asked = None if asked is None else [name(c) for c in asked]
    items = None if items is None else [(k, name(c)) for k, c in items]
    force_cols, id_cols, corners = _plan(args, mc, asked, items, [name(c) for c in id_cols],
                                         list(ta_file) if args.actuators is not None else None)
    if not force_cols:
        raise _error(f"{str(args.input)!r} has no force channel to correct (unit N, kN... or none); name them with "
                     "--columns")
    fs = mc.fs_hz
    units = {f"{c}_corrected": "N" for c in force_cols}
    if args.transient == "mark":
        units["settled"] = "1"
    meta = _metadata(args, id_cols, force_cols, corners)
    _probe_output(args.out, units, meta)
    source = f"from {str(args.actuator or args.actuators)!r}"
    if args.identify is not None:
        drive, disp = (mc.data[c] for c in id_cols)
        if np.std(drive) == 0 or np.std(disp) == 0:
            raise _error(f"--identify columns {id_cols[0]!r} and {id_cols[1]!r} must vary to identify T_a")
        try:
            fit = fit_actuator(drive, disp, fs)
        except ValueError as exc:
            raise _error(f"cannot identify T_a from {id_cols[0]!r} and {id_cols[1]!r}: {exc}") from None
        tas = fit
        source = (f"identified (orders {fit.orders[0]}/{fit.orders[1]}, held-out error {fit.held_out_error:.1%}, "
                  f"bandwidth {fit.bandwidth_hz:.3g} Hz)")
    else:
        tas = ta_file if corners is None else [ta_file[c] for c in corners]
    forces = mc.array(force_cols)
    try:
        res = correct_forces(forces, tas, fs, lowpass=args.lowpass, mode=args.mode, normalize_dc=args.normalize_dc,
                             settling_tolerance=SETTLING_TOLERANCE)
    except CorrectionError as exc:
        msg = str(exc).replace("pass normalize_dc=True", "pass --normalize-dc")
        if exc.column is not None and corners is not None:
            msg = f"corner {corners[exc.column]!r} (column {force_cols[exc.column]!r}): {msg}"
        raise _error(msg) from None
    settled = res.settled
    if args.transient == "drop" and np.count_nonzero(settled) < 2:
        head = max(f.transient_samples(args.mode)[0] for f in res.filters)
        tail = max(f.transient_samples(args.mode)[1] for f in res.filters)
        raise _error(f"the record ({forces.shape[0] / fs:.3g} s) is not longer than the correction's transients "
                     f"({head / fs:.3g} s at the start, {tail / fs:.3g} s at the end); fix: give a longer record "
                     "or pass --transient keep")
    rows = np.flatnonzero(settled) if args.transient == "drop" else np.arange(forces.shape[0])
    corrected = res.corrected_N
    data = {f"{c}_corrected": corrected[rows, j] for j, c in enumerate(force_cols)}
    if args.transient == "mark":
        data["settled"] = settled[rows].astype(float)
    try:
        write_channels(args.out, SimpleNamespace(time_s=mc.time_s[rows], data=data, units=units), metadata=meta,
                       overwrite=args.force, inputs=inputs)
    except MeasuredDataError as exc:
        raise _error(str(exc)) from None
    if settled.any():
        print(_dlc_table(force_cols, forces[settled], corrected[settled], fs))
    print(f"corrected {len(force_cols)} channel(s) of {str(args.input)!r} at {fs:.6g} Hz (T_a {source}, low-pass "
          f"{res.filters[0].lowpass.description}, {args.mode}); {forces.shape[0] - int(settled.sum())} transient "
          f"samples {'dropped' if args.transient == 'drop' else 'kept'}; wrote {args.out}")
    return 0
