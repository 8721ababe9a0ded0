"""A programme's report: per record how it was corrected and its loads, as JSON, Markdown and a figure.

The results are frozen dataclasses (:class:`WheelReport`, :class:`RecordReport`,
:class:`TruckReport`, :class:`ProgrammeReport`); :func:`write_report` writes them to
``programme.json`` (:func:`rigsim.scenarios.core.files.write_json`), ``programme.md`` (from the same
objects) and ``programme.png`` (DLC before and after, per record and wheel). Nothing in them
depends on when or where a record was corrected (wall times go to ``timings.csv``), so a programme
run twice writes the same bytes. Imports matplotlib only in :func:`plot_dlc`.
"""

from __future__ import annotations

import io
import math
import pathlib
from dataclasses import dataclass, fields

__all__ = ["WheelReport", "RecordReport", "TruckReport", "ProgrammeReport", "record_report", "failed_report",
           "record_from_dict", "write_report", "JSON_FILE", "MARKDOWN_FILE", "FIGURE_FILE"]

JSON_FILE, MARKDOWN_FILE, FIGURE_FILE = "programme.json", "programme.md", "programme.png"

#: How a record's truck model came to be (:attr:`RecordReport.calibration`).
MADE, HELD, REFITTED, NONE = "made", "held", "refitted", "none"


@dataclass(frozen=True)
class WheelReport:
    """One wheel of a corrected record.

    Attributes
    ----------
    corner : str
        fl, fr, rl or rr.
    channel : str
        Its force channel in the record.
    model_error : float or None, 1
        The truck model's error on this record (dynamic fit NRMSE in the correction's band beyond
        the load cells' noise); None without a calibration.
    dlc_before, dlc_after : float or None, 1
        Dynamic Load Coefficient of the measured and the corrected force (settled samples).
    sf4_before, sf4_after : float or None, 1
        Stress factor ``E[(F / F_static)^4]``.
    del5_before_N, del5_after_N : float or None, N
        Damage-equivalent load, exponent 5, at 1 Hz.
    """

    corner: str
    channel: str
    model_error: float | None
    dlc_before: float | None
    dlc_after: float | None
    sf4_before: float | None
    sf4_after: float | None
    del5_before_N: float | None
    del5_after_N: float | None


@dataclass(frozen=True)
class RecordReport:
    """One record of the programme, corrected or failed.

    Attributes
    ----------
    name : str
        The record's name (its file name without extension).
    record : str
        The record file.
    truck : str
        Its truck configuration.
    output : str
        The corrected file's name in ``--out`` ("" when failed).
    status : {"corrected", "failed"}
    method : str
        ``"model"`` or ``"linear"`` (the correction used; "" when failed).
    why : str
        Why: the wheels the model corrected, or the reason the linear correction was used.
    calibration : {"made", "held", "refitted", "none"}
        The truck model calibrated on this record, the saved calibration held on it, it did not
        hold and was refitted from its values, or no calibration (linear).
    calibration_note : str
        The refit's reason, or the calibration file used.
    wheels : tuple of WheelReport
    error : str
        Why the record failed (one sentence); "" otherwise.
    settings : dict
        What made the output (record, truck configuration, format): a later run redoes the record
        where they differ.
    """

    name: str
    record: str
    truck: str
    output: str
    status: str
    method: str = ""
    why: str = ""
    calibration: str = NONE
    calibration_note: str = ""
    wheels: tuple = ()
    error: str = ""
    settings: dict | None = None


@dataclass(frozen=True)
class TruckReport:
    """One truck configuration: its TRUCK.toml, its calibration file and the record it was calibrated on
    (with the other records whose windows the calibration fitted, ``run1 (and run2, run3)``)."""

    name: str
    model: str
    calibration_file: str
    calibrated_on: str


@dataclass(frozen=True)
class ProgrammeReport:
    """The programme: its trucks, its records (in the order given), how many were corrected and failed."""

    trucks: tuple
    records: tuple
    corrected: int
    failed: int
    rigsim_version: str


def _num(x):
    return None if x is None or not math.isfinite(float(x)) else float(x)


def record_report(entry, settings: dict, result, role: str) -> RecordReport:
    """The :class:`RecordReport` of ``entry`` (a :class:`~rigsim.scenarios.studies.programme.settings.RecordEntry`)
    corrected into ``result`` (a :class:`~rigsim.scenarios.records.corrected.CorrectionResult`);
    ``role``: ``"calibrate"`` (the truck was calibrated on this record) or ``"reuse"``."""
    from rigsim.mjcf.names import CORNERS

    cal = result.calibration
    errors = dict(zip(CORNERS, cal.excess_nrmse)) if cal is not None else {}
    corners = result.corners or (None,) * len(result.channels)
    loads = {row.channel: row for row in result.loads}
    wheels = []
    for corner, channel in zip(corners, result.channels):
        row = loads.get(channel)
        pick = (lambda k: _num(getattr(row, k))) if row is not None else (lambda k: None)
        wheels.append(WheelReport(corner or "", channel, _num(errors.get(corner)), pick("dlc_before"),
                                  pick("dlc_after"), pick("stress_factor_before"), pick("stress_factor_after"),
                                  pick("del5_before_N"), pick("del5_after_N")))
    meta = result.metadata
    if result.method == "model":
        why = f"the truck model on {meta.get('model_wheels', '')}" + (f"; {result.reason}" if result.reason else "")
    else:
        why = result.reason or result.description
    if cal is None:
        state, note = NONE, ""
    elif role == "calibrate":
        state, note = MADE, ""
    elif cal.second_start:
        state, note = REFITTED, cal.second_start
    else:
        state, note = HELD, meta.get("cal_source", "")
    return RecordReport(entry.name, entry.path, entry.truck, entry.output, "corrected", result.method, why, state,
                        note, tuple(wheels), "", settings)


def failed_report(entry, settings: dict, error: str) -> RecordReport:
    """The :class:`RecordReport` of a record that could not be corrected, ``error`` one sentence."""
    return RecordReport(entry.name, entry.path, entry.truck, "", "failed", error=error, settings=settings)


def record_from_dict(doc: dict) -> RecordReport:
    """A :class:`RecordReport` read back from its JSON (``records/NAME.json``).

    Raises
    ------
    KeyError, TypeError
        The document is not one (the caller redoes the record).
    """
    names = {f.name for f in fields(RecordReport)}
    if set(doc) != names:
        raise KeyError("not a record report")
    wheels = tuple(WheelReport(**w) for w in doc["wheels"])
    return RecordReport(**{**doc, "wheels": wheels})


def _f(x, spec: str = ".4f") -> str:
    return "-" if x is None else format(x, spec)


def _change(before, after) -> str:
    return "-" if before in (None, 0) or after is None else f"{100.0 * (after / before - 1.0):+.1f} %"


def markdown(report: ProgrammeReport) -> str:
    """``programme.md``: the trucks, then per record the method and calibration, per wheel the figures."""
    from rigsim.scenarios.studies.results_page import markdown_table

    trucks = markdown_table(["truck", "TRUCK.toml", "calibration", "calibrated on"],
                            [[t.name, t.model, t.calibration_file or "-", t.calibrated_on or "-"] for t in report.trucks])
    rows = []
    for r in report.records:
        if r.status != "corrected":
            rows.append([r.name, r.truck, "FAILED", "-", r.error])
        else:
            cal = r.calibration + (f": {r.calibration_note}" if r.calibration == REFITTED else "")
            rows.append([r.name, r.truck, r.method, cal, r.why])
    records = markdown_table(["record", "truck", "method", "calibration", "why"], rows)
    rows = []
    for r in report.records:
        for w in r.wheels:
            kn = [None if v is None else v / 1e3 for v in (w.del5_before_N, w.del5_after_N)]
            rows.append([r.name, w.corner or w.channel, _f(w.model_error, ".3f"), _f(w.dlc_before), _f(w.dlc_after),
                         _change(w.dlc_before, w.dlc_after), _f(w.sf4_before), _f(w.sf4_after), _f(kn[0], ".2f"),
                         _f(kn[1], ".2f")])
    loads = markdown_table(["record", "wheel", "model error", "DLC before", "DLC after", "change", "SF4 before",
                            "SF4 after", "DEL before, kN", "DEL after, kN"], rows)
    lines = ["# Programme", "",
             f"{report.corrected} of {len(report.records)} records corrected, {report.failed} failed "
             f"(rigsim {report.rigsim_version}).", "", "## Trucks", "", trucks.rstrip("\n"), "", "## Records", "",
             records.rstrip("\n"), "", "## Loads per wheel", "",
             "Model error, then DLC, stress factor (SF4) and damage-equivalent load (DEL, m = 5, 1 Hz) of the "
             "measured and the corrected force, on the settled samples.", "", loads.rstrip("\n")]
    failed = [r for r in report.records if r.status != "corrected"]
    if failed:
        lines += ["", "## Failed", ""] + [f"- {r.name} ({r.record}): {r.error}" for r in failed]
    lines += ["", f"![DLC before and after per record and wheel]({FIGURE_FILE})", ""]
    return "\n".join(lines)


def plot_dlc(report: ProgrammeReport, path) -> pathlib.Path:
    """``programme.png``: per corrected record and wheel the DLC measured (light) and corrected (dark)."""
    from matplotlib.figure import Figure

    from rigsim.scenarios.core.files import atomic_write_bytes

    done = [r for r in report.records if r.status == "corrected"]
    corners = sorted({w.corner or w.channel for r in done for w in r.wheels})
    fig = Figure(figsize=(max(5.0, 0.9 * len(done) * max(1, len(corners)) ** 0.5 + 2.0), 3.6), layout="constrained")
    ax = fig.add_subplot()
    width = 0.8 / max(1, len(corners))
    for j, corner in enumerate(corners):
        dlc = [[next((getattr(w, k) for w in r.wheels if (w.corner or w.channel) == corner), None) or math.nan
                for r in done] for k in ("dlc_before", "dlc_after")]
        x = [i + (j - (len(corners) - 1) / 2) * width for i in range(len(done))]
        color = f"C{j}"
        ax.bar(x, dlc[0], width, color=color, alpha=0.35, label=f"{corner} measured")
        ax.bar(x, dlc[1], width * 0.5, color=color, label=f"{corner} corrected")
    ax.set_xticks(range(len(done)), [r.name for r in done], rotation=30, ha="right", fontsize=8)
    ax.set_ylabel("DLC")
    ax.set_title(f"DLC before and after, {len(done)} records" + (f" ({report.failed} failed)" if report.failed else ""))
    ax.legend(fontsize=7, ncols=max(1, len(corners)))
    ax.grid(True, axis="y", alpha=0.3)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, metadata={"Software": None})
    path = pathlib.Path(path)
    atomic_write_bytes(path, buf.getvalue())
    return path


def write_report(report: ProgrammeReport, out) -> list[pathlib.Path]:
    """Write ``programme.json``, ``programme.md`` and ``programme.png`` into ``out``; returns them."""
    from rigsim.scenarios.core.files import atomic_write_text, write_json

    out = pathlib.Path(out)
    written = [write_json(out / JSON_FILE, report)]
    atomic_write_text(out / MARKDOWN_FILE, markdown(report))
    written.append(out / MARKDOWN_FILE)
    if any(r.status == "corrected" for r in report.records):
        written.append(plot_dlc(report, out / FIGURE_FILE))
    return written
