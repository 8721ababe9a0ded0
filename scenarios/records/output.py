"""The output side of a record's correction: checks before any work, the linear correction, the metadata.

Shared by the linear correction and the model correction (which falls back to the linear one) of
:mod:`rigsim.scenarios.records.api`: an output file refused before any work (:func:`check_out_file`,
:func:`probe_output`) and claimed for the command's run (:func:`claimed_out_file`), the one linear
correction with its options (:func:`linear_correction`, :func:`lowpass_filter`), and the metadata
that says how a corrected file was made (:func:`linear_metadata`), fitted to what the output's
format can hold (:func:`fit_metadata`). Imports nothing heavy at module level.
"""

from __future__ import annotations

import pathlib
import textwrap

from rigsim.scenarios.records.naming import KEYWORDS, Naming

__all__ = ["SENTENCE_KEYS", "GIVEN", "check_out_file", "claimed_out_file", "header_value", "fit_metadata",
           "rigsim_version", "lowpass_filter", "linear_metadata", "output_units", "probe_output", "linear_correction"]

#: Metadata keys whose value is a sentence: an RPC III header (96-byte values) holds it split over
#: ``key``, ``key_2``, ``key_3``...
SENTENCE_KEYS = ("fallback_reason", "cal_cab", "cal_frame", "cal_engine", "cal_damper", "cal_second_start")
#: The metadata's ``ta_source`` (or ``scenario_file``) of a T_a (or truck) given as a Python object.
GIVEN = "given in the call"


def _error(message: str):
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


def check_out_file(out, inputs, force: bool) -> None:
    """Refuse an empty output path, one that names an input file, an existing file without
    ``--force``, a folder, an unwritable folder or an extension no writer knows (before any work)."""
    from rigsim.correction.io.measured import WRITE_FORMATS, MeasuredDataError, format_of
    from rigsim.correction.io.measured_core import check_output
    from rigsim.scenarios.core.outputs import check_output_file

    check_output_file(out, "-o", force=True)  # empty, a folder, no permission; an existing file: below
    try:
        check_output(out, overwrite=force, inputs=inputs)
        format_of(out, WRITE_FORMATS)
    except MeasuredDataError as exc:
        raise _error(str(exc).replace(" (overwrite=True)", "")) from None


def claimed_out_file(out, inputs, force: bool):
    """A context manager: :func:`check_out_file` of ``-o`` ``out``, then ``out`` claimed for the
    block (:func:`rigsim.scenarios.core.outputs.claimed_output_file`): a second command writing it is
    refused in one sentence, and a file that appears there meanwhile is not replaced without ``force``."""
    from rigsim.scenarios.core.outputs import claimed_output_file

    return claimed_output_file(out, "-o", force=force, check=lambda: check_out_file(out, inputs, force))


def header_value(text: str) -> str:
    """A metadata value an RPC III header can hold (latin-1, one line, 96 bytes): a longer value
    keeps its end (a path's file name), after '...'."""
    text = " ".join(str(text).split()).encode("latin-1", errors="replace").decode("latin-1")
    return text if len(text) <= 96 else "..." + text[-93:]


def fit_metadata(out, meta) -> dict[str, str]:
    """``meta`` as ``out``'s format can hold it: in RPC III each :data:`SENTENCE_KEYS` value split
    over numbered keys at word boundaries, and :func:`header_value` of every value."""
    from rigsim.correction.io.measured import format_of

    if format_of(out) != "rpc3":
        return {k: str(v) for k, v in meta.items()}
    fitted = {}
    for key, value in meta.items():
        parts = textwrap.wrap(str(value), 96) if key in SENTENCE_KEYS else [value]
        fitted.update({key + (f"_{i + 1}" if i else ""): header_value(v) for i, v in enumerate(parts)})
    return fitted


def rigsim_version() -> str:
    """rigsim's version (:data:`rigsim.__version__`, pyproject.toml's)."""
    import rigsim

    return rigsim.__version__


def lowpass_filter(lowpass: str, lowpass_hz: float | None = None):
    """The low-pass T_F: ``"paper"`` (eq. 5) or ``"regularized"``, the Butterworth of order
    :data:`~rigsim.correction.output.lowpass.BAND_ORDER` at ``lowpass_hz`` (Hz; default
    :data:`~rigsim.correction.output.lowpass.BAND_HZ`). Returns a :class:`~rigsim.correction.output.lowpass.LowPass`."""
    from rigsim.correction.output.lowpass import as_lowpass, regularized_lowpass

    if lowpass == "regularized" and lowpass_hz is not None:
        return regularized_lowpass(corner_hz=lowpass_hz)
    return as_lowpass(lowpass)


def linear_metadata(*, lowpass: str, lowpass_hz: float | None, mode: str, transient: str,
                    normalize_dc: bool) -> dict[str, str]:
    """How the linear correction was made: its formula, low-pass (``lowpass`` with its corner
    ``lowpass_hz``, Hz), mode, tolerance, transients, static-gain scaling."""
    from rigsim.correction.output.pipeline import SETTLING_TOLERANCE

    return {"correction": "F_corrected = T_a^-1 T_F F_measured", "force_unit": "N",
            "lowpass": f"{lowpass}: {lowpass_filter(lowpass, lowpass_hz).description}", "mode": mode,
            "settling_tolerance": f"{SETTLING_TOLERANCE:g}", "transient": transient,
            "normalize_dc": "yes" if normalize_dc else "no"}


def output_units(cols, transient: str) -> dict[str, str]:
    """The output's channels and units: ``<channel>_corrected`` in N (and ``settled`` with ``mark``)."""
    units = {f"{c}_corrected": "N" for c in cols}
    if transient == "mark":
        units["settled"] = "1"
    return units


def probe_output(out, units, meta, option: str = "-o") -> None:
    """Write two samples of the output's channels and metadata to a scratch file of the same
    format: whatever the writer would refuse (a name, a metadata value, a missing extra) is
    refused now, before the correction; the sentence names ``out`` as ``option``."""
    import tempfile
    from types import SimpleNamespace

    from rigsim.correction.io.measured import MeasuredDataError, write_channels

    probe = SimpleNamespace(time_s=[0.0, 1.0], data={n: [0.0, 1.0] for n in units}, units=units)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            write_channels(pathlib.Path(tmp) / f"probe{pathlib.Path(out).suffix}", probe, metadata=meta)
        except MeasuredDataError as exc:
            raise _error(f"{option} {str(out)!r} cannot be written: {exc}") from None


def linear_correction(forces, tas, fs: float, cols, corners, *, lowpass, mode: str, normalize_dc: bool,
                      transient: str, lowpass_hz: float | None = None, naming: Naming = KEYWORDS):
    """The linear correction :func:`rigsim.correction.output.pipeline.correct_forces` of ``forces`` (N, (n, k))
    with ``tas`` (one T_a or one per column), the low-pass ``lowpass`` (a
    :class:`~rigsim.correction.output.lowpass.LowPass`, whose corner the caller set as ``lowpass_hz``, Hz),
    ``mode`` and ``normalize_dc``; a refused T_a, or (``transient="drop"``) a record no longer
    than the filters' transients, as one sentence naming the corner and channel. Returns the
    :class:`~rigsim.correction.output.pipeline.CorrectedForces`."""
    import numpy as np

    from rigsim.correction.output.pipeline import SETTLING_TOLERANCE, CorrectionError, correct_forces

    try:
        res = correct_forces(forces, tas, fs, lowpass=lowpass, mode=mode, normalize_dc=normalize_dc,
                             settling_tolerance=SETTLING_TOLERANCE)
    except ValueError as exc:  # a CorrectionError names its column; the low-pass alone (T_a = 1) none
        msg = str(exc).replace("pass normalize_dc=True", f"pass {naming.setting('normalize_dc')}")
        if lowpass_hz is not None and msg.startswith("sampling rate"):  # the corner is the user's to lower
            msg = msg.replace("; fix: ", f"; fix: lower {naming('lowpass_hz')} ({lowpass_hz:g} Hz), or ", 1)
        column = exc.column if isinstance(exc, CorrectionError) else None
        if column is not None and corners is not None:
            msg = f"corner {corners[column]!r} (column {cols[column]!r}): {msg}"
        raise _error(msg) from None
    if transient == "drop" and np.count_nonzero(res.settled) < 2:
        head = max(f.transient_samples(mode)[0] for f in res.filters)
        tail = max(f.transient_samples(mode)[1] for f in res.filters)
        raise _error(f"the record ({forces.shape[0] / fs:.3g} s) is not longer than the correction's transients "
                     f"({head / fs:.3g} s at the start, {tail / fs:.3g} s at the end); fix: give a longer record "
                     f"or pass {naming.setting('transient', 'keep')}")
    return res
