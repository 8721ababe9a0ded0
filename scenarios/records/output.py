"""The output of ``rigsim correct``: checks before any work, the linear correction, the file and the table.

Shared by the linear correction (:mod:`scenarios.cli.correct`) and the model correction
(:mod:`scenarios.cli.correct_model`, which falls back to the linear one): ``-o`` refused before
any work (:func:`check_out_file`, :func:`probe_output`), the one linear correction with the
command's options (:func:`linear_correction`), and the corrected forces written by
:func:`correction.io.measured.write_channels` with the settled samples handled as ``--transient``
asks and the DLC table printed (:func:`write_corrected`). Imports nothing heavy at module level.
"""

from __future__ import annotations

import math
import pathlib

__all__ = ["check_out_file", "header_value", "fit_metadata", "rigsim_version",
           "linear_metadata", "output_units", "probe_output", "dlc_table", "linear_correction", "write_corrected"]


def _error(message: str):
    from scenarios.core.config import ScenarioError

    return ScenarioError(message)


def check_out_file(out, inputs, force: bool) -> None:
    """Refuse an empty output path, one that names an input file, an existing file without
    ``--force``, a folder, an unwritable folder or an extension no writer knows (before any work)."""
    from correction.io.measured import WRITE_FORMATS, MeasuredDataError, format_of
    from correction.io.measured_core import check_output
    from scenarios.core.outputs import check_output_file

    check_output_file(out, "-o", force=True)  # empty, a folder, no permission; an existing file: below
    try:
        check_output(out, overwrite=force, inputs=inputs)
        format_of(out, WRITE_FORMATS)
    except MeasuredDataError as exc:
        raise _error(str(exc).replace(" (overwrite=True)", "")) from None


def header_value(text: str) -> str:
    """A metadata value an RPC III header can hold (latin-1, one line, 96 bytes): a longer value
    keeps its end (a path's file name), after '...'."""
    text = " ".join(str(text).split()).encode("latin-1", errors="replace").decode("latin-1")
    return text if len(text) <= 96 else "..." + text[-93:]


def fit_metadata(out, meta: dict) -> dict[str, str]:
    """``meta`` as ``out``'s format can hold it (RPC III: :func:`header_value` of each value)."""
    from correction.io.measured import format_of

    if format_of(out) == "rpc3":
        return {k: header_value(v) for k, v in meta.items()}
    return {k: str(v) for k, v in meta.items()}


def rigsim_version() -> str:
    """The installed rigsim's version."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rigsim")
    except PackageNotFoundError:  # pragma: no cover - a source tree that is not installed
        return "unknown (not installed)"


def linear_metadata(args) -> dict[str, str]:
    """How the linear correction was made: its formula, low-pass, mode, tolerance, transients."""
    from correction.output.pipeline import SETTLING_TOLERANCE
    from correction.output.lowpass import as_lowpass

    return {"correction": "F_corrected = T_a^-1 T_F F_measured", "force_unit": "N",
            "lowpass": f"{args.lowpass}: {as_lowpass(args.lowpass).description}", "mode": args.mode,
            "settling_tolerance": f"{SETTLING_TOLERANCE:g}", "transient": args.transient,
            "normalize_dc": "yes" if args.normalize_dc else "no"}


def output_units(cols, transient: str) -> dict[str, str]:
    """The output's channels and units: ``<channel>_corrected`` in N (and ``settled`` with ``mark``)."""
    units = {f"{c}_corrected": "N" for c in cols}
    if transient == "mark":
        units["settled"] = "1"
    return units


def probe_output(out, units, meta) -> None:
    """Write two samples of the output's channels and metadata to a scratch file of the same
    format: whatever the writer would refuse (a name, a metadata value, a missing extra) is
    refused now, before the correction."""
    import tempfile
    from types import SimpleNamespace

    from correction.io.measured import MeasuredDataError, write_channels

    probe = SimpleNamespace(time_s=[0.0, 1.0], data={n: [0.0, 1.0] for n in units}, units=units)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            write_channels(pathlib.Path(tmp) / f"probe{pathlib.Path(out).suffix}", probe, metadata=meta)
        except MeasuredDataError as exc:
            raise _error(f"-o {str(out)!r} cannot be written: {exc}") from None


def dlc_table(cols, before_N, after_N, fs: float) -> str:
    """Per column, before and after correction (the settled rows): DLC (1) with its change in %,
    the stress factor E[(F/F_static)^4] (1) and the damage-equivalent load for m = 5 at 1 Hz (kN)."""
    from correction.metrics.damage import damage_equivalent_load, stress_factor
    from correction.metrics.dlc import dlc

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


def linear_correction(args, forces, tas, fs: float, cols, corners):
    """The linear correction :func:`correction.output.pipeline.correct_forces` of ``forces`` (N, (n, k))
    with ``tas`` (one T_a or one per column) and the command's ``--lowpass``, ``--mode`` and
    ``--normalize-dc``; a refused T_a, or (``--transient drop``) a record no longer than the
    filters' transients, as one sentence naming the corner and channel. Returns the
    :class:`~correction.output.pipeline.CorrectedForces`."""
    import numpy as np

    from correction.output.pipeline import SETTLING_TOLERANCE, CorrectionError, correct_forces

    try:
        res = correct_forces(forces, tas, fs, lowpass=args.lowpass, mode=args.mode, normalize_dc=args.normalize_dc,
                             settling_tolerance=SETTLING_TOLERANCE)
    except CorrectionError as exc:
        msg = str(exc).replace("pass normalize_dc=True", "pass --normalize-dc")
        if exc.column is not None and corners is not None:
            msg = f"corner {corners[exc.column]!r} (column {cols[exc.column]!r}): {msg}"
        raise _error(msg) from None
    if args.transient == "drop" and np.count_nonzero(res.settled) < 2:
        head = max(f.transient_samples(args.mode)[0] for f in res.filters)
        tail = max(f.transient_samples(args.mode)[1] for f in res.filters)
        raise _error(f"the record ({forces.shape[0] / fs:.3g} s) is not longer than the correction's transients "
                     f"({head / fs:.3g} s at the start, {tail / fs:.3g} s at the end); fix: give a longer record "
                     "or pass --transient keep")
    return res


def write_corrected(args, mc, cols, forces, corrected, settled, meta, inputs) -> None:
    """Write ``<channel>_corrected`` (N) of ``cols`` to ``args.out`` with ``meta``: the ``settled``
    rows (``--transient drop``), or all with a ``settled`` 0/1 channel (``mark``) or without
    (``keep``); then print the DLC table of the settled rows, before (``forces``, N) and after."""
    from types import SimpleNamespace

    import numpy as np

    from correction.io.measured import MeasuredDataError, write_channels

    rows = np.flatnonzero(settled) if args.transient == "drop" else np.arange(forces.shape[0])
    data = {f"{c}_corrected": corrected[rows, j] for j, c in enumerate(cols)}
    if args.transient == "mark":
        data["settled"] = settled[rows].astype(float)
    try:
        write_channels(args.out, SimpleNamespace(time_s=mc.time_s[rows], data=data,
                                                 units=output_units(cols, args.transient)),
                       metadata=meta, overwrite=args.force, inputs=inputs)
    except MeasuredDataError as exc:
        raise _error(str(exc)) from None
    if settled.any():
        print(dlc_table(cols, forces[settled], corrected[settled], mc.fs_hz))
