"""A record's corrected forces as data: :class:`CorrectionResult`, its load table and its file.

:func:`rigsim.scenarios.records.api.correct_record` returns a :class:`CorrectionResult`: the corrected
forces in N per channel, where they are settled, how they were corrected and why, and per
channel the loads before and after (:class:`ChannelLoads`: DLC, stress factor, damage-equivalent
load; :meth:`CorrectionResult.table` as text). :meth:`CorrectionResult.write` writes the file
``rigsim correct`` writes, through :func:`rigsim.correction.io.measured.write_channels`: the time (s) and
``<channel>_corrected`` in N, the settled samples only (``transient="drop"``) or all of them,
with a ``settled`` 0/1 channel (``"mark"``) or without (``"keep"``), and the metadata. Imports
nothing heavy at module level.
"""

from __future__ import annotations

import math
import pathlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from rigsim.scenarios.records.output import fit_metadata, output_units

__all__ = ["ChannelLoads", "channel_loads", "loads_table", "CorrectionResult", "calibration_path"]


@dataclass(frozen=True)
class ChannelLoads:
    """One channel's loads on the settled samples, before and after the correction.

    Attributes
    ----------
    channel : str
    dlc_before, dlc_after : float or None, 1
        Dynamic Load Coefficient, std / mean; None when the mean is not a compressive load (<= 0).
    change : float or None, 1
        ``dlc_after / dlc_before - 1`` (NaN when ``dlc_before`` is 0).
    stress_factor_before, stress_factor_after : float or None, 1
        ``E[(F / F_static)^4]`` (:func:`rigsim.correction.metrics.damage.stress_factor`).
    del5_before_N, del5_after_N : float or None, N
        Damage-equivalent load for the exponent m = 5 at 1 Hz
        (:func:`rigsim.correction.metrics.damage.damage_equivalent_load`).

    Examples
    --------
    A row of :attr:`CorrectionResult.loads` (as :func:`~rigsim.scenarios.records.correct_record` computes
    them; by hand here):

    >>> from rigsim import ChannelLoads
    >>> row = ChannelLoads("Fz_FL", dlc_before=0.0363, dlc_after=0.0367, change=0.011,
    ...                    stress_factor_before=1.0079, stress_factor_after=1.0081,
    ...                    del5_before_N=5.90e3, del5_after_N=6.11e3)
    >>> print(f"{row.channel}: DLC {row.dlc_before} -> {row.dlc_after} ({row.change:+.1%})")
    Fz_FL: DLC 0.0363 -> 0.0367 (+1.1%)

    A channel whose mean is not a compressive load has no DLC:

    >>> ChannelLoads("Fx_FL").dlc_before is None
    True
    """

    channel: str
    dlc_before: float | None = None
    dlc_after: float | None = None
    change: float | None = None
    stress_factor_before: float | None = None
    stress_factor_after: float | None = None
    del5_before_N: float | None = None
    del5_after_N: float | None = None


def channel_loads(cols, before_N, after_N, fs: float) -> tuple[ChannelLoads, ...]:
    """Per column of ``before_N`` and ``after_N`` (N, (n, k), sampled at ``fs`` Hz) its :class:`ChannelLoads`."""
    from rigsim.correction.metrics.damage import damage_equivalent_load, stress_factor
    from rigsim.correction.metrics.dlc import dlc

    rows = []
    for j, col in enumerate(cols):
        try:
            b, a = float(dlc(before_N[:, j])), float(dlc(after_N[:, j]))
        except ValueError:  # not a compressive load (mean <= 0): no DLC
            rows.append(ChannelLoads(col))
            continue
        sf = [float(stress_factor(x[:, j])) for x in (before_N, after_N)]
        dl = [float(damage_equivalent_load(x[:, j], 5, duration_s=x.shape[0] / fs)) for x in (before_N, after_N)]
        rows.append(ChannelLoads(col, b, a, a / b - 1.0 if b > 0 else math.nan, sf[0], sf[1], dl[0], dl[1]))
    return tuple(rows)


def loads_table(loads) -> str:
    """:class:`ChannelLoads` rows as the text table ``rigsim correct`` prints (DLC and its change in %,
    stress factor, damage-equivalent load in kN)."""
    lines = [f"{'column':<24} {'DLC before':>10} {'DLC after':>10} {'change':>8}   "
             f"{'SF4 before':>10} {'SF4 after':>10}   {'DEL5 before':>11} {'DEL5 after':>11}"]
    for r in loads:
        if r.dlc_before is None:
            lines.append(f"{r.channel:<24} {'-':>10} {'-':>10} {'-':>8}")
            continue
        lines.append(f"{r.channel:<24} {r.dlc_before:>10.4f} {r.dlc_after:>10.4f} {100.0 * r.change:>7.1f}%   "
                     f"{r.stress_factor_before:>10.4f} {r.stress_factor_after:>10.4f}   "
                     f"{r.del5_before_N / 1e3:>8.2f} kN {r.del5_after_N / 1e3:>8.2f} kN")
    return "\n".join(lines)


def _frozen(a) -> np.ndarray:
    a = np.array(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class CorrectionResult:
    """The corrected forces of a record, how they were corrected, and their loads.

    Attributes
    ----------
    channels : tuple of str
        The corrected channels, as named in the record.
    corners : tuple of str or None
        The corner of each channel (per-corner T_a, the truck model); None: one T_a for all.
    time_s : numpy.ndarray, (n,), s
        The record's time axis, every sample.
    measured_N, corrected_N : numpy.ndarray, (n, k), N
        The measured and the corrected force of each channel, every sample.
    settled : numpy.ndarray of bool, (n,)
        The samples outside the correction's transients (the filters', or the model runs' start-up).
    fs_hz : float, Hz
        Sampling rate.
    method : {"linear", "model"}
        The correction used: ``T_a^-1 T_F`` (linear) or ``F_model(x_ref) + L(W(F_rig - F_model(x_a)))``.
    reason : str
        Why the linear correction was used although the model was asked for (one sentence); "" otherwise.
    description : str
        How the forces were corrected, one line (T_a's source, low-pass and mode; or the model).
    transient : {"drop", "mark", "keep"}
        What :meth:`write` does with the samples that are not settled.
    metadata : Mapping[str, str]
        What :meth:`write` puts in the file's metadata (fitted there to the format).
    loads : tuple of ChannelLoads
        Per channel the loads on the settled samples; empty when no sample is settled.
    calibration : rigsim.scenarios.records.model.result.Calibration or None
        The truck model's calibration, when the model was asked for and could be calibrated.
    time_start_s : float, s
        Where the record's time axis started on the lab's clock (its reader's ``time_start_s``;
        :attr:`time_s` runs from 0 as the record was read): the written file's time is on that clock.
    saved_calibration : rigsim.scenarios.records.model.saved.SavedCalibration or None
        The same with the truck description and the record it came from, as
        :meth:`write_calibration` writes it for the next record of this truck.
    actuators : tuple
        The T_a of each channel (linear; ``(num, den)`` or an identified
        :class:`~rigsim.correction.identification.actuator_result.ActuatorFit`); empty for the model.
    filters : tuple of CorrectionFilter
        The linear correction's filter of each channel; empty for the model.
    inputs : tuple of str
        The files the result was made from: :meth:`write` never writes onto one of them.

    Examples
    --------
    Two wheels, each corrected with its corner's T_a; the written file marks the settled samples:

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from rigsim.correction.io.measured import MeasuredChannels
    >>> from rigsim import LinearOptions, correct_record, read_record
    >>> t = np.arange(10_000) / 1000.0
    >>> wave = 2e3 * np.sin(2 * np.pi * 3.0 * t) + 5e2 * np.sin(2 * np.pi * 12.0 * t)
    >>> data = {"Fz_FL": 40e3 + wave, "Fz_FR": 38e3 - wave}
    >>> record = MeasuredChannels(time_s=t, data=data, units=dict.fromkeys(data, "N"),
    ...                           source_units=dict.fromkeys(data, "kN"), fs_hz=1000.0,
    ...                           metadata={}, path="", format="csv")
    >>> w = 2 * np.pi * 15.0
    >>> acts = {"fl": ([w * w], [1.0, 1.4 * w, w * w]), "fr": ([w * w], [1.0, 1.2 * w, w * w])}
    >>> result = correct_record(record, LinearOptions(actuators=acts), transient="mark")
    >>> result.corners, result.method
    (('fl', 'fr'), 'linear')
    >>> print(result.table())  # doctest: +NORMALIZE_WHITESPACE
    column                   DLC before  DLC after   change   SF4 before  SF4 after   DEL5 before  DEL5 after
    Fz_FL                        0.0363     0.0367     1.1%       1.0079     1.0081       5.90 kN     6.11 kN
    Fz_FR                        0.0382     0.0379    -0.8%       1.0088     1.0086       5.90 kN     5.88 kN
    >>> out = result.write(pathlib.Path(tempfile.mkdtemp()) / "corrected.rsp")
    >>> back = read_record(out)
    >>> list(back.data), back.time_s.size, f"{result.transient_samples} not settled"
    (['Fz_FL_corrected', 'Fz_FR_corrected', 'settled'], 10000, '264 not settled')
    """

    channels: tuple
    corners: tuple | None
    time_s: np.ndarray
    measured_N: np.ndarray
    corrected_N: np.ndarray
    settled: np.ndarray
    fs_hz: float
    method: str
    reason: str
    description: str
    transient: str
    metadata: Mapping = field(default_factory=dict)
    loads: tuple = ()
    calibration: object = None
    saved_calibration: object = None
    time_start_s: float = 0.0
    actuators: tuple = ()
    filters: tuple = ()
    inputs: tuple = ()

    def __post_init__(self) -> None:
        for name in ("time_s", "measured_N", "corrected_N", "settled"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        object.__setattr__(self, "metadata", MappingProxyType(dict(self.metadata)))

    @property
    def transient_samples(self) -> int:
        """Samples that are not settled (dropped from the file with ``transient="drop"``)."""
        return int(self.settled.size - np.count_nonzero(self.settled))

    def table(self) -> str:
        """The load table as text: per channel DLC before and after (and its change in %), stress
        factor, damage-equivalent load (kN), on the settled samples."""
        return loads_table(self.loads)

    def write(self, path, *, overwrite: bool = False) -> pathlib.Path:
        """Write the corrected forces to ``path``, in its extension's format.

        Parameters
        ----------
        path : str, bytes or os.PathLike
            .csv/.txt/.dat, .rsp/.drv/.tim/.rpc (RPC III), .mf4/.mdf, .tdms
            (:func:`rigsim.correction.io.measured.write_channels`).
        overwrite : bool
            Replace an existing file; a file the result was made from is never replaced.

        Returns
        -------
        pathlib.Path
            The file written: the time (s), ``<channel>_corrected`` (N) and, with
            ``transient="mark"``, ``settled`` (0/1); with ``transient="drop"`` only the settled samples.

        Raises
        ------
        ScenarioError
            One sentence: a path or ``overwrite`` of the wrong type, an existing file without
            ``overwrite``, an input file, an extension no writer knows, a name or metadata value the
            format cannot hold.
        """
        from types import SimpleNamespace

        from rigsim.correction.io.measured import MeasuredDataError, write_channels
        from rigsim.scenarios.records.arguments import file_path, flag
        from rigsim.scenarios.records.naming import KEYWORDS

        path, overwrite = file_path(path, "path"), flag(KEYWORDS, "overwrite", overwrite)

        rows = np.flatnonzero(self.settled) if self.transient == "drop" else np.arange(self.settled.size)
        data = {f"{c}_corrected": self.corrected_N[rows, j] for j, c in enumerate(self.channels)}
        if self.transient == "mark":
            data["settled"] = self.settled[rows].astype(float)
        out = SimpleNamespace(time_s=self.time_s[rows] + self.time_start_s, data=data,
                              units=output_units(self.channels, self.transient))
        try:
            return write_channels(path, out, metadata=fit_metadata(path, self.metadata), overwrite=overwrite,
                                  inputs=self.inputs)
        except MeasuredDataError as exc:
            from rigsim.scenarios.core.config import ScenarioError

            raise ScenarioError(str(exc)) from None

    def write_calibration(self, path, *, overwrite: bool = False) -> pathlib.Path:
        """Write the truck model's calibration (:attr:`saved_calibration`) to ``path`` (JSON), for
        ``ModelOptions(..., calibration=path)`` on the next record of this truck
        (:func:`rigsim.scenarios.records.model.saved.write_calibration`).

        Raises
        ------
        ScenarioError
            No calibration (a linear correction, or a model that could not be calibrated), a path
            of the wrong type, an existing file without ``overwrite``, an input file (one sentence).
        """
        from rigsim.scenarios.records.arguments import file_path, flag
        from rigsim.scenarios.records.model.saved import write_calibration
        from rigsim.scenarios.records.naming import KEYWORDS

        path, overwrite = file_path(path, "path"), flag(KEYWORDS, "overwrite", overwrite)
        if self.saved_calibration is None:
            from rigsim.scenarios.core.config import ScenarioError

            raise ScenarioError("this result has no calibration to write: it was corrected linearly, or the truck "
                                "model could not be calibrated on the record")
        return write_calibration(path, self.saved_calibration, overwrite=overwrite, inputs=self.inputs)


def calibration_path(out) -> pathlib.Path:
    """The calibration file ``rigsim correct --model -o OUT`` writes beside ``OUT``:
    ``OUT``'s name without its extension, then ``.calibration.json``."""
    out = pathlib.Path(out)
    return out.with_name(out.stem + ".calibration.json")
