"""The linear correction of a planned record, ``T_a^-1 T_F``, as a :class:`CorrectionResult`.

:func:`run_linear` corrects a :class:`~rigsim.scenarios.records.plan.CorrectionPlan`'s channels each with
its T_a: one for all, one per corner, or identified from the record's own drive and displacement
channels (:func:`rigsim.correction.identification.actuator_fit.fit_actuator`);
:func:`linear_result` is that correction with any T_a, also the model correction's fallback.
The one correction is :func:`rigsim.scenarios.records.output.linear_correction`. Imports nothing heavy at
module level.
"""

from __future__ import annotations

from collections.abc import Mapping

from rigsim.scenarios.records.corrected import CorrectionResult, channel_loads
from rigsim.scenarios.records.output import GIVEN, linear_correction, lowpass_filter

__all__ = ["run_linear", "linear_result", "ta_text"]


def _error(message: str):
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


def _identified(plan):
    """(T_a fitted on the plan's drive and displacement channels, its one-line source)."""
    import numpy as np

    from rigsim.correction.identification import actuator_fit

    rec, (d, x), n = plan.record, plan.id_cols, plan.settings.naming
    drive, disp = rec.data[d], rec.data[x]
    if np.std(drive) == 0 or np.std(disp) == 0:
        raise _error(f"{n('identify')} columns {d!r} and {x!r} must vary to identify T_a")
    try:
        fit = actuator_fit.fit_actuator(drive, disp, rec.fs_hz)
    except ValueError as exc:
        raise _error(f"{n('identify')} {d},{x}: cannot identify T_a from these channels: {exc}") from None
    return fit, (f"identified (orders {fit.orders[0]}/{fit.orders[1]}, held-out error {fit.held_out_error:.1%}, "
                 f"bandwidth {fit.bandwidth_hz:.3g} Hz)")


def ta_text(source: str) -> str:
    """How a T_a's source reads in a result's description: ``from 'acts.toml'``, or the source itself."""
    return source if source == GIVEN else f"from {source!r}"


def linear_result(plan, tas, source: str, *, corners, method: str = "linear", reason: str = "",
                  metadata: Mapping | None = None, calibration=None) -> CorrectionResult:
    """The linear correction of the plan's channels with ``tas`` (one T_a or one per channel; ``source``:
    one line on where they come from) as a :class:`CorrectionResult`."""
    s, rec = plan.settings, plan.record
    forces = rec.array(plan.channels)
    res = linear_correction(forces, tas, rec.fs_hz, list(plan.channels), corners,
                            lowpass=lowpass_filter(s.lowpass, s.lowpass_hz), mode=s.mode,
                            normalize_dc=s.normalize_dc, transient=s.transient, lowpass_hz=s.lowpass_hz,
                            naming=s.naming)
    settled = res.settled
    loads = channel_loads(plan.channels, forces[settled], res.corrected_N[settled], rec.fs_hz) if settled.any() else ()
    return CorrectionResult(
        channels=plan.channels, corners=None if corners is None else tuple(corners), time_s=rec.time_s,
        measured_N=forces, corrected_N=res.corrected_N, settled=settled, fs_hz=float(rec.fs_hz), method=method,
        reason=reason, description=f"T_a {source}, low-pass {res.filters[0].lowpass.description}, {s.mode}",
        transient=s.transient, metadata=plan.metadata if metadata is None else metadata, loads=loads,
        calibration=calibration, actuators=tuple(tas) if isinstance(tas, list) else (tas,) * len(plan.channels),
        filters=res.filters, inputs=plan.inputs)


def run_linear(plan) -> CorrectionResult:
    """The linear correction of a plan: each channel with its T_a (one, one per corner, or identified
    from the record's own drive and displacement channels)."""
    s = plan.settings
    if plan.id_cols:
        tas, source = _identified(plan)
    else:
        tas = s.ta if plan.corners is None else [s.ta[c] for c in plan.corners]
        source = ta_text(s.ta_source)
    return linear_result(plan, tas, source, corners=plan.corners)
