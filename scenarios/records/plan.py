"""A record's correction planned and checked before any work, then run: :class:`CorrectionPlan`.

:func:`make_plan` matches the settings (:class:`~rigsim.scenarios.records.settings.CorrectionSettings`)
to a record: which force channels are corrected and at which corner
(:func:`rigsim.scenarios.records.channels.plan_channels`; the model's in
:func:`rigsim.scenarios.records.model_record.plan_model`), the low-pass's and the channel filters'
corners held against the record's Nyquist frequency, and the metadata the corrected file will
carry. A plan can check an output file before the work (:meth:`CorrectionPlan.check_output`: whatever the writer would
refuse) and runs the correction (:meth:`CorrectionPlan.run`): the linear one by
:func:`rigsim.scenarios.records.linear.run_linear`, the model one by
:func:`rigsim.scenarios.records.model_record.run_model`. Imports nothing heavy at module level.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from rigsim.scenarios.records.channels import plan_channels, resolver
from rigsim.scenarios.records.corrected import CorrectionResult
from rigsim.scenarios.records.linear import run_linear
from rigsim.scenarios.records.output import fit_metadata, linear_metadata, output_units, probe_output, rigsim_version
from rigsim.scenarios.records.timing import aligned_record, check_rates, lvdt_columns, timing_metadata

__all__ = ["CorrectionPlan", "make_plan"]


def _error(message: str):
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


@dataclass(frozen=True, eq=False)
class CorrectionPlan:
    """The correction of one record, checked: what :meth:`run` corrects and what the file will carry.

    Attributes
    ----------
    settings : rigsim.scenarios.records.settings.CorrectionSettings
    record : rigsim.correction.io.measured.MeasuredChannels
    channels : tuple of str
        The force channels corrected, as named in the record (the model's in corner order).
    corners : tuple of str or None
        The corner of each channel; None: one T_a for all.
    id_cols : tuple of str
        The (drive, displacement) channels T_a is identified from, as named in the record; empty when not.
    pairs : Mapping[str, tuple[str, str]] or None
        The model's (drive, LVDT) channels per corner, as named in the record.
    metadata : Mapping[str, str]
        The corrected file's metadata (the linear correction's), or every key the model's may carry
        (to check an output before the work).
    more : tuple of CorrectionPlan
        The model's other records of the same truck, planned with the same settings, whose windows
        its calibration fits too.
    """

    settings: object
    record: object
    channels: tuple
    corners: tuple | None
    id_cols: tuple = ()
    pairs: Mapping | None = None
    metadata: Mapping = field(default_factory=dict)
    more: tuple = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "metadata", MappingProxyType(dict(self.metadata)))

    @property
    def inputs(self) -> tuple:
        """The files the correction reads: the record's, the settings' and the other records'."""
        return (str(self.record.path), *self.settings.inputs, *(str(p.record.path) for p in self.more))

    def check_output(self, path) -> None:
        """Refuse, before the work, an output ``path`` whose writer would refuse these channels or this
        metadata (a name, a value, an extension, a missing extra): a scratch file of the same format is
        written with two samples."""
        from rigsim.correction.io.measured import MeasuredDataError

        try:
            meta = fit_metadata(path, self.metadata)
        except MeasuredDataError as exc:
            raise _error(str(exc)) from None
        probe_output(path, output_units(self.channels, self.settings.transient), meta,
                     option=self.settings.naming("path"))

    def run(self, progress=None) -> CorrectionResult:
        """Correct the record. ``progress``: called with each progress line or note of a long run
        (the model's calibration), None: silent. The force and LVDT channels' timing, where the
        settings give it, is undone first (:func:`rigsim.scenarios.records.timing.aligned_record`). The
        result keeps where the record's time axis started (its ``time_start_s``), so its file is on the
        record's clock. The linear algebra runs on one thread (threadpoolctl): a least-squares fit's
        last digits depend on how many threads share its BLAS, and a correction is the same wherever it
        runs (the command, a lab's script, a pool's or a Dask cluster's worker)."""
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1):  # the same digits on any machine, pool or Dask worker
            return self._run(progress)

    def aligned(self) -> CorrectionPlan:
        """This plan with the force and LVDT channels' timing undone where the settings give it
        (:func:`rigsim.scenarios.records.timing.aligned_record`)."""
        s = self.settings
        record = aligned_record(self.record, self.record.fs_hz,
                                [(self.channels, s.force_filter), (lvdt_columns(self.pairs, self.id_cols), s.lvdt_filter)])
        return self if record is self.record else dataclasses.replace(self, record=record)

    def _run(self, progress) -> CorrectionResult:
        from rigsim.correction.io.measured_core import TIME_START_KEY

        s = self.settings
        plan = self.aligned()
        if self.more:
            plan = dataclasses.replace(plan, more=tuple(p.aligned() for p in self.more))
        if s.method == "model":
            from rigsim.scenarios.records.model_record import run_model

            result = run_model(plan, progress)
        else:
            result = run_linear(plan)
        start = float(self.record.metadata.get(TIME_START_KEY, 0.0))
        return dataclasses.replace(result, time_start_s=start) if start else result


def _check_band(settings, record) -> None:
    """The low-pass's corner below the record's Nyquist frequency."""
    hz, fs = settings.lowpass_hz, record.fs_hz
    if hz is not None and not hz < fs / 2:
        raise _error(f"{settings.naming('lowpass_hz')} {hz:g} Hz is not below the Nyquist frequency of "
                     f"{str(record.path)!r} ({fs / 2:g} Hz at {fs:g} Hz); give a lower corner")


def make_plan(settings, record, as_read: Mapping | None = None) -> CorrectionPlan:
    """Plan the correction of ``record`` with ``settings``; ``as_read``: channel name as given -> as read."""
    if settings.method == "model":
        from rigsim.scenarios.records.model_record import plan_model

        channels, corners, pairs, meta = plan_model(settings, record, as_read)
        _check_band(settings, record)
        check_rates(settings, record.fs_hz)
        return CorrectionPlan(settings, record, tuple(channels), tuple(corners), pairs=pairs, metadata=meta)
    n, name = settings.naming, resolver(record, as_read)
    asked = None if settings.columns is None else [name(c) for c in settings.columns]
    items = None if settings.corner_map is None else [(k, name(c)) for k, c in settings.corner_map]
    cols, id_cols, corners = plan_channels(record, asked, items, [name(c) for c in settings.identify],
                                           list(settings.ta) if settings.per_corner else None, naming=n)
    if not cols:
        raise _error(f"{str(record.path)!r} has no force channel to correct (unit N, kN... or none); name them with "
                     f"{n('columns')}")
    _check_band(settings, record)
    source = f"identified from {','.join(id_cols)}" if id_cols else settings.ta_source
    meta = {"made_by": "rigsim correct", "rigsim_version": rigsim_version(), "input": str(record.path),
            "ta_source": source}
    if corners is not None:
        meta["corners"] = ",".join(f"{k}={c}" for k, c in zip(corners, cols))
    meta.update(linear_metadata(lowpass=settings.lowpass, lowpass_hz=settings.lowpass_hz, mode=settings.mode,
                                transient=settings.transient, normalize_dc=settings.normalize_dc))
    meta.update(timing_metadata(settings.force_filter, settings.lvdt_filter))
    check_rates(settings, record.fs_hz)
    return CorrectionPlan(settings, record, tuple(cols), None if corners is None else tuple(corners),
                          id_cols=tuple(id_cols), metadata=meta)
