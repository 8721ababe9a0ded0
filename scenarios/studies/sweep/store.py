"""The files of a sweep folder: one JSON file per finished case, ``results.csv`` and ``sweep.json``.

* ``cases/<case_id>.json``: one file per finished case, written atomically as soon as it
  finishes: its values, scenario, scores (:meth:`rigsim.scenarios.studies.sweep.case.CaseResult.to_dict`)
  or error, fingerprint and :data:`~rigsim.scenarios.studies.sweep.grid.GRID_FORMAT`. A case file is
  part of a grid only if its format and fingerprint match (same scenario, same settings).
* ``results.csv``: one row per case of the grid that has a case file, sorted by case id,
  collected from the case files (so an interrupted and resumed sweep gives the same file as an
  uninterrupted one).
* ``timings.csv``: each case's wall time (s) in the worker, sorted by case id, kept apart so
  that the case files and ``results.csv`` of two sweeps of the same grid are byte-identical.
* ``sweep.json``: the grid, the settings, counts and the executor of the last run.
"""

from __future__ import annotations

import csv
import io
import json
import pathlib
from collections.abc import Mapping
from typing import Any

from rigsim.scenarios.core.files import atomic_write_text, write_json
from rigsim.scenarios.studies.sweep.case import METRIC_COLUMNS
from rigsim.scenarios.studies.sweep.grid import GRID_FORMAT, Case, SweepGrid, format_value

__all__ = ["CASES_DIR", "RESULTS_FILE", "META_FILE", "TIMINGS_FILE", "case_path", "read_case_files",
           "results_columns", "collect_results", "write_case", "write_meta", "write_timings"]

RESULTS_FILE = "results.csv"
TIMINGS_FILE = "timings.csv"
CASES_DIR = "cases"
META_FILE = "sweep.json"


def case_path(out_dir, case_id: str) -> pathlib.Path:
    """``out_dir/cases/<case_id>.json``."""
    return pathlib.Path(out_dir) / CASES_DIR / f"{case_id}.json"


def read_case_files(grid: SweepGrid, out_dir) -> dict[str, dict]:
    """The case files in ``out_dir`` that belong to ``grid`` (same id, format and fingerprint), by case id."""
    found = {}
    for case in grid.cases:
        try:
            rec = json.loads(case_path(out_dir, case.case_id).read_text(encoding="utf-8"))
        except (FileNotFoundError, json.JSONDecodeError, UnicodeDecodeError):
            continue
        if isinstance(rec, dict) and rec.get("fingerprint") == case.fingerprint and rec.get("format") == GRID_FORMAT:
            found[case.case_id] = rec
    return found


def write_case(out_dir, case: Case, record: Mapping) -> pathlib.Path:
    """Write the case file of ``case`` from a worker's ``record`` (atomically; its wall time is
    left out: it goes to :data:`TIMINGS_FILE`)."""
    doc = {"format": GRID_FORMAT, "case_id": case.case_id, "fingerprint": case.fingerprint,
           "values": dict(case.values),
           **{k: v for k, v in record.items() if k not in ("case_id", "wall_time_s")},
           "scenario": case.doc, "source": case.source}
    return write_json(case_path(out_dir, case.case_id), doc)


def results_columns(grid: SweepGrid) -> list[str]:
    """Header of ``results.csv``: case id, the swept keys, status, the scores, error (no wall time:
    see :data:`TIMINGS_FILE`)."""
    return ["case_id", *grid.keys, "status", *METRIC_COLUMNS, "error"]


def _lookup(doc: Mapping, key: str) -> Any:
    node: Any = doc
    for part in key.split("."):
        if not isinstance(node, Mapping) or part not in node:
            return ""
        node = node[part]
    return node


def _cell(value: Any) -> str:
    if value is None:
        return ""
    return format_value(value) if isinstance(value, (float, int, bool)) else str(value)


def collect_results(grid: SweepGrid, out_dir) -> pathlib.Path:
    """Write ``DIR/results.csv`` from the case files of ``grid``, sorted by case id (atomically).

    A swept key a case does not set (an explicit case without it) shows the base's value.
    Failed cases have empty scores and their error.
    """
    records = read_case_files(grid, out_dir)
    cases = {c.case_id: c for c in grid.cases}
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(results_columns(grid))
    for cid in sorted(records):
        rec = records[cid]
        result = rec.get("result") or {}
        ok = rec["status"] == "ok"
        writer.writerow([cid, *(_cell(_lookup(cases[cid].doc, k)) for k in grid.keys), rec["status"],
                         *(_cell(result.get(k)) if ok else "" for k in METRIC_COLUMNS),
                         rec.get("error") or ""])
    path = pathlib.Path(out_dir) / RESULTS_FILE
    atomic_write_text(path, buf.getvalue())
    return path


def write_timings(grid: SweepGrid, out_dir, timings: Mapping[str, float | None]) -> pathlib.Path:
    """Write ``DIR/timings.csv`` (``case_id,wall_time_s``, s, sorted by case id; atomically): the
    rows already there for cases of ``grid``, updated with ``timings`` (this run's cases)."""
    path = pathlib.Path(out_dir) / TIMINGS_FILE
    ids = {c.case_id for c in grid.cases}
    rows: dict[str, str] = {}
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            for row in csv.DictReader(fh):
                if row.get("case_id") in ids:
                    rows[row["case_id"]] = row.get("wall_time_s") or ""
    except (FileNotFoundError, csv.Error, UnicodeDecodeError):
        pass
    rows.update({cid: _cell(None if t is None else round(float(t), 3)) for cid, t in timings.items() if cid in ids})
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["case_id", "wall_time_s"])
    writer.writerows([cid, rows[cid]] for cid in sorted(rows))
    atomic_write_text(path, buf.getvalue())
    return path


def write_meta(grid: SweepGrid, out_dir, *, ran: int, wall_time_s: float, interrupted: bool,
               executor_label: str) -> dict[str, dict]:
    """Write ``DIR/sweep.json`` (grid, settings, counts, last run; wall time in s); returns the
    grid's case files (:func:`read_case_files`)."""
    records = read_case_files(grid, out_dir)
    meta = {
        "grid": grid.source, "name": grid.name, "format": GRID_FORMAT,
        "axes": {k: list(v) for k, v in grid.axes}, "settings": grid.settings,
        "cases": len(grid.cases), "finished": len(records),
        "failed": sum(r["status"] != "ok" for r in records.values()),
        "complete": len(records) == len(grid.cases), "executor": executor_label,
        "last_run": {"ran": ran, "wall_time_s": round(wall_time_s, 3), "interrupted": interrupted},
    }
    write_json(pathlib.Path(out_dir) / META_FILE, meta)
    return records
