"""Running a programme: each truck calibrated once, every record corrected, side by side, resumably.

Per truck configuration the first record not yet corrected is corrected by the model calibrated on
it (what ``rigsim correct --model`` does), on windows of the truck's next ``calibrate_on`` - 1
records too (:data:`~rigsim.scenarios.studies.programme.settings.CALIBRATE_ON`, 3, by default),
and its calibration written to ``NAME.calibration.json``; every other record of that truck is
then corrected with ``ModelOptions(..., calibration=that file)``: the records API
checks the calibration on the record, refits the tire's progressive stiffening on the record's own
loads where it holds (:mod:`~rigsim.scenarios.records.model.refine`) and the whole truck where it
does not. A record that cannot be
corrected (unreadable, wrong channels, refused) is reported and the others go on; where the record
a truck was to be calibrated on fails, or gives no calibration (the linear correction), the truck's
next record is calibrated instead. The calibrations run first, here, one after the other, each on
all local cores (a calibration runs its model variants side by side; nothing else can start before
it). The other records then run on a ``concurrent.futures`` executor (the local pool or a Dask
cluster's), each with one worker process for its own model runs; the workers read the records and
TRUCK.toml and write into ``--out`` under the same paths (a shared file system on a cluster).

Resume: a record whose corrected file exists and whose ``records/NAME.json`` says it was corrected
with the same settings is not corrected again; a truck whose calibration file exists and whose
calibrating record is such a record is not calibrated again. Outputs are written atomically and
depend on nothing but the inputs (the calibration file holds no wall time; each record's goes to
``timings.csv``), so a run resumed after a kill writes the same bytes as one run through.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import math
import pathlib
import time
from dataclasses import dataclass

from rigsim.scenarios.core.config import ScenarioError
from rigsim.scenarios.core.files import atomic_write_text, write_json
from rigsim.scenarios.core.progress import Progress
from rigsim.scenarios.studies.programme.report import (MADE, ProgrammeReport, RecordReport, TruckReport,
                                                       failed_report, record_from_dict, record_report, write_report)
from rigsim.scenarios.studies.programme.settings import CALIBRATE_ON, Programme, RecordEntry, TruckSettings

__all__ = ["RECORDS_DIR", "TIMINGS_FILE", "Job", "ProgrammeOutcome", "correct_one", "calibration_file",
           "run_programme"]

RECORDS_DIR, TIMINGS_FILE = "records", "timings.csv"


@dataclass(frozen=True)
class Job:
    """One record to correct in a worker.

    Attributes
    ----------
    entry : RecordEntry
    truck : TruckSettings
    output : str
        The corrected file (absolute).
    calibration : str or None
        The saved calibration to reuse; None: calibrate on this record.
    write_calibration : str or None
        Where to write the calibration made on this record (with ``calibration`` None).
    more : tuple of str
        Other records of the truck whose windows the calibration fits too (with ``calibration`` None).
    workers : int or None
        Worker processes of its model runs (None: all cores).
    """

    entry: RecordEntry
    truck: TruckSettings
    output: str
    calibration: str | None
    write_calibration: str | None
    more: tuple = ()
    workers: int | None = 1

    @property
    def settings(self) -> dict:
        """What the output depends on: the record, its truck configuration, the output file."""
        return {"record": self.entry.path, "truck": self.truck.as_dict(), "output": self.entry.output}


def calibration_file(out, truck: TruckSettings) -> pathlib.Path:
    """A truck configuration's calibration in ``out``: ``NAME.calibration.json``."""
    return pathlib.Path(out) / f"{truck.name}.calibration.json"


def correct_one(job: Job) -> tuple[RecordReport, float]:
    """Correct one record in a worker and write its corrected file (and, calibrating, the calibration
    before it); returns its report and wall time (s). Never raises: a failure is the report's error."""
    import os

    os.environ.setdefault("MUJOCO_GL", "disable")
    from rigsim.errors import RigsimError
    from rigsim.scenarios.records.api import plan_correction

    t0 = time.perf_counter()
    try:
        options = job.truck.options(job.calibration, workers=job.workers, more=job.more)
        plan = plan_correction(job.entry.path, options, **job.truck.call())
        result = plan.run(None)
        if job.write_calibration is not None and result.saved_calibration is not None:
            result.write_calibration(job.write_calibration, overwrite=True)
        result.write(job.output, overwrite=True)
        report = record_report(job.entry, job.settings, result, "calibrate" if job.calibration is None else "reuse")
    except (RigsimError, ValueError) as exc:  # a refusal of the records API, one sentence
        report = failed_report(job.entry, job.settings, " ".join(str(exc).split()))
    except Exception as exc:  # noqa: BLE001 - a record the readers choke on must not stop the programme
        report = failed_report(job.entry, job.settings, f"{type(exc).__name__}: {' '.join(str(exc).split())}")
    return report, time.perf_counter() - t0


@dataclass(frozen=True)
class ProgrammeOutcome:
    """What a call of :func:`run_programme` did.

    Attributes
    ----------
    report : ProgrammeReport
    skipped : int
        Records corrected by an earlier run.
    ran : int
        Records corrected or failed now.
    wall_time_s : float, s
    written : tuple of pathlib.Path
        The report's files.
    """

    report: ProgrammeReport
    skipped: int
    ran: int
    wall_time_s: float
    written: tuple

    @property
    def failed(self) -> tuple:
        """The reports of the records that failed."""
        return tuple(r for r in self.report.records if r.status != "corrected")


def _job(out: pathlib.Path, programme: Programme, entry: RecordEntry, calibration: str | None) -> Job:
    """A record's job: with ``calibration`` (a file) reusing it on one worker process, else calibrating
    on all cores on the record and the truck's next ``calibrate_on`` - 1 records."""
    truck = programme.truck(entry.truck)
    if calibration is not None:
        return Job(entry, truck, str(out / entry.output), calibration, None)
    more = tuple(e.path for e in _also(programme, entry))
    return Job(entry, truck, str(out / entry.output), None, str(calibration_file(out, truck)), more, None)


def _also(programme: Programme, entry: RecordEntry) -> list[RecordEntry]:
    """The records whose windows a calibration on ``entry`` fits too: its truck's next
    ``calibrate_on`` - 1 records in the programme's order."""
    truck = programme.truck(entry.truck)
    same = [e for e in programme.records if e.truck == truck.name]
    return same[same.index(entry) + 1:][:(truck.calibrate_on or CALIBRATE_ON) - 1]


def _finished(out: pathlib.Path, job: Job) -> RecordReport | None:
    """The report of a record corrected earlier with the same settings, its file in place; else None."""
    path = out / RECORDS_DIR / f"{job.entry.name}.json"
    try:
        report = record_from_dict(json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if report.status != "corrected" or report.settings != json.loads(json.dumps(job.settings)):
        return None
    return report if (out / job.entry.output).is_file() else None


def run_programme(programme: Programme, out, executor: cf.Executor, *, progress: bool = True,
                  on_record=None) -> ProgrammeOutcome:
    """Correct the records of ``programme`` not finished in ``out`` on ``executor``.

    Parameters
    ----------
    programme : Programme
    out : path
        The output folder (created): the corrected files, ``NAME.calibration.json`` per truck,
        ``records/`` (one report per record), ``programme.json``, ``programme.md``,
        ``programme.png``, ``timings.csv``.
    executor : concurrent.futures.Executor
        :func:`rigsim.scenarios.core.pool.local_executor` or a Dask cluster's
        (:func:`rigsim.scenarios.studies.sweep.executors.dask_executor`).
    progress : bool
        A progress bar (or lines) on stderr.
    on_record : callable, optional
        ``on_record(report)`` after each record's report is written (tests).

    Returns
    -------
    ProgrammeOutcome
        Whatever failed is in its report; the report is written also after Ctrl-C.
    """
    out = pathlib.Path(out).absolute()
    (out / RECORDS_DIR).mkdir(parents=True, exist_ok=True)
    reports: dict[str, RecordReport] = {}
    pending: dict[str, list[RecordEntry]] = {t.name: [] for t in programme.trucks}
    calibrated_on: dict[str, str] = {}
    for entry in programme.records:
        truck = programme.truck(entry.truck)
        done = _finished(out, _job(out, programme, entry, None))
        if done is not None and (done.calibration != MADE or calibration_file(out, truck).is_file()):
            reports[entry.name] = done
            if done.calibration == MADE:
                calibrated_on[truck.name] = entry.name
        else:
            pending[truck.name].append(entry)
    skipped = len(reports)
    bar = Progress(len(programme.records), skipped, progress, unit="record")
    futures: dict[cf.Future, Job] = {}
    timings: list[tuple[str, float]] = []
    t0 = time.perf_counter()

    def finish(job: Job, report: RecordReport, wall: float) -> None:
        reports[job.entry.name] = report
        timings.append((job.entry.name, wall))
        write_json(out / RECORDS_DIR / f"{job.entry.name}.json", report)
        if report.calibration == MADE:
            calibrated_on[job.entry.truck] = job.entry.name
        bar.update(job.entry.name, report.status == "corrected", report.error, wall)
        if on_record is not None:
            on_record(report)

    try:
        for name, queue in pending.items():  # the calibrations, here, each on all cores
            while name not in calibrated_on and queue:
                job = _job(out, programme, queue.pop(0), None)
                finish(job, *correct_one(job))
        for name, queue in pending.items():  # then every other record, side by side
            if name in calibrated_on:
                cal = str(calibration_file(out, programme.truck(name)))
                for entry in queue:
                    job = _job(out, programme, entry, cal)
                    futures[executor.submit(correct_one, job)] = job
                queue.clear()
        while futures:
            finished, _ = cf.wait(futures, return_when=cf.FIRST_COMPLETED)
            for fut in finished:
                job = futures.pop(fut)
                try:
                    report, wall = fut.result()
                except Exception as exc:  # noqa: BLE001 - a lost worker fails its record only
                    report, wall = failed_report(job.entry, job.settings, f"the worker correcting it failed "
                                                 f"({type(exc).__name__}: {' '.join(str(exc).split())})"), math.nan
                finish(job, report, wall)
    finally:
        bar.close()
        report = _report(programme, out, reports, calibrated_on)
        written = tuple(write_report(report, out))
        atomic_write_text(out / TIMINGS_FILE, "record,wall_time_s\n" + "".join(f"{n},{w:.3f}\n" for n, w in timings))
    return ProgrammeOutcome(report, skipped, len(timings), time.perf_counter() - t0, written)


def _report(programme: Programme, out: pathlib.Path, reports: dict, calibrated_on: dict) -> ProgrammeReport:
    from rigsim.scenarios.records.output import rigsim_version

    def on(t) -> str:  # the record calibrated on, and the others whose windows it fitted (as its file says)
        if t.name not in calibrated_on:
            return ""
        from rigsim.scenarios.records.model.saved import read_calibration

        try:
            also = read_calibration(calibration_file(out, t)).also
        except ScenarioError:
            also = ()
        names = [next((e.name for e in programme.records if e.path == a), pathlib.Path(a).stem) for a in also]
        return calibrated_on[t.name] + (f" (and {', '.join(names)})" if names else "")

    trucks = tuple(TruckReport(t.name, t.model, calibration_file(out, t).name if t.name in calibrated_on else "",
                               on(t)) for t in programme.trucks)
    records = tuple(reports[e.name] for e in programme.records if e.name in reports)
    n_ok = sum(r.status == "corrected" for r in records)
    return ProgrammeReport(trucks, records, n_ok, len(records) - n_ok, rigsim_version())
