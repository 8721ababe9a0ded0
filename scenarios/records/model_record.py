"""A record corrected by a truck model calibrated on it: the plan, the run, the linear fallback, the metadata.

The truck model (the truck the scenario's ``[vehicle]`` describes, the catalogue truck of
``truck_rig.xml`` where it describes none) is calibrated on the record alone: per
corner the drive x_ref and the LVDT x_a (``pairs``; lengths in m) and the wheel force F_rig (the
force channel whose name holds the corner as a token, or ``corner_map``'s; in N); then
F_corrected = F_model(x_ref) + L(W(F_rig - F_model(x_a))) per wheel, W the residual's white noise
taken out (:mod:`rigsim.correction.output.denoise`), L the linear correction
``T_a^-1 T_F`` with the given T_a, else T_a identified per corner from the ``pairs`` channels
(:func:`rigsim.scenarios.records.model.differential.correct_with_model`). The scenario's rig (actuator
stroke) is used, and its ``[vehicle]`` tire and leaf-friction values, where given, are the
calibration's first guesses (:func:`first_guess`); the payload and its position always start
from the record's static loads.

Where the model cannot be trusted on this record (its calibration did not converge or could not
run, or it does not reproduce F_rig on any wheel) the linear correction L is used instead
(:func:`rigsim.scenarios.records.linear.linear_result`); where it does not reproduce F_rig on some wheels,
those are corrected by L alone; the reason goes into the result and the file's metadata (:func:`model_metadata`: the method
and why, the calibration's fitted values with units and 1-sigma, the fit NRMSE per wheel).
Imports nothing heavy at module level.
"""

from __future__ import annotations

from rigsim.scenarios.records.channels import LENGTH_UNITS, plan_channels, resolver, unit_text
from rigsim.scenarios.records.corrected import CorrectionResult, channel_loads
from rigsim.scenarios.records.linear import linear_result, ta_text
from rigsim.scenarios.records.output import linear_correction, linear_metadata, lowpass_filter, rigsim_version
from rigsim.scenarios.records.timing import timing_metadata

__all__ = ["FROM_STATIC_LOADS", "MODEL_TEXT", "first_guess", "description_note", "cal_key", "calibration_meta", "model_metadata",
           "plan_model", "run_model"]

#: The fields the payload's first guess comes from the record for (a [vehicle] value is not used).
FROM_STATIC_LOADS = ("payload_kg", "payload_x_m", "payload_y_m")
#: How the model correction corrects, in a result's description.
MODEL_TEXT = "the truck model calibrated on the record (F_model(drive) + L(W(F_rig - F_model(LVDT))))"


def _error(message: str):
    from rigsim.scenarios.core.config import ScenarioError

    return ScenarioError(message)


def _windows(settings) -> tuple[int, int]:
    """(calibration windows, most fit evaluations) of the settings, the calibration's defaults where not given."""
    from rigsim.scenarios.records.model.calibrate import MAX_NFEV, WINDOWS

    return (WINDOWS if settings.calibration_windows is None else int(settings.calibration_windows),
            MAX_NFEV if settings.max_evaluations is None else int(settings.max_evaluations))


def _check_pairs(record, pairs, naming) -> None:
    """Each pair: two channels, each in the record, not the time, a length, varying."""
    import numpy as np

    from rigsim.scenarios.records.recorded import check_pair_channels

    names, opt = list(record.names), naming("pairs")
    for corner, cols in pairs.items():
        check_pair_channels(corner, *cols, naming)
        for col in cols:
            if col == record.time_name or col not in names:
                what = "is the time column" if col == record.time_name else f"is not in {str(record.path)!r}"
                raise _error(f"{opt} {corner}: channel {col!r} {what}; its channels are {', '.join(names)}")
            if record.units[col] not in LENGTH_UNITS:
                raise _error(f"{opt} {corner}: channel {col!r} is in {unit_text(record, col)}, not a length; give "
                             "the drive and the LVDT (pan displacement) channels, in m or mm")
        if any(np.std(record.data[c]) == 0 for c in cols):
            raise _error(f"{opt} {corner}: channels {cols[0]!r} and {cols[1]!r} must vary (a drive and the pan's "
                         "motion)")


def plan_model(settings, record, as_read=None):
    """(force channels in corner order, corners, pairs as read, the probe's metadata); every check
    before any work, one ScenarioError sentence otherwise."""
    import numpy as np

    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.records.model.calibrate import WINDOW_LEAD_S, WINDOW_S, fit_windows

    n, name = settings.naming, resolver(record, as_read)
    pairs = {corner: (name(d), name(x)) for corner, (d, x) in settings.pairs.items()}
    _check_pairs(record, pairs, n)
    asked = None if settings.columns is None else [name(c) for c in settings.columns]
    items = None if settings.corner_map is None else [(k, name(c)) for k, c in settings.corner_map]
    cols, _, corners = plan_channels(record, asked, items, [c for cs in pairs.values() for c in cs], CORNERS,
                                     owner="the truck model", naming=n)  # the pairs' channels are never corrected
    mapping = dict(zip(corners, cols))
    missing = [c for c in CORNERS if c not in mapping]
    if missing:
        raise _error(f"corner {missing[0]!r} has no force channel; fix: "
                     f"{n.setting('corner_map', f'{missing[0]}=CHANNEL')} ({n('model')} corrects the four wheels "
                     f"{', '.join(CORNERS)} together)")
    force_cols = [mapping[c] for c in CORNERS]
    for col in force_cols:
        if not np.all(np.isfinite(record.data[col])):
            raise _error(f"channel {col!r} has NaN or infinite values; clean or cut the record first")
    try:
        fit_windows(record.time_s, _windows(settings)[0], WINDOW_S, WINDOW_LEAD_S)
    except ScenarioError as exc:
        raise _error(f"{str(record.path)!r}: {exc}") from None
    return force_cols, CORNERS, pairs, model_metadata(settings, record, pairs, force_cols, None, None)


def first_guess(scenario) -> tuple[dict, list[str]]:
    """(fitted fields' first guesses from the scenario's [vehicle], its other given fields: not used)."""
    from rigsim.mjcf.tires import REAR_FIELDS
    from rigsim.scenarios.records.model.family import FITTED
    from rigsim.scenarios.records.model.first_guess import SPEC_FIELDS

    given = {k: getattr(scenario.vehicle, k) for k in type(scenario.vehicle).field_names()
             if getattr(scenario.vehicle, k) is not None and k not in SPEC_FIELDS}  # the description: the model's own
    guess = {k: float(v) for k, v in given.items() if k in FITTED and k not in FROM_STATIC_LOADS}
    for every, rear in REAR_FIELDS.items():
        if every in guess and rear not in guess:  # an all-wheel value is the rear tires' too
            guess[rear] = guess[every]
    return guess, [k for k in given if k not in guess]


def cal_key(name: str) -> str:
    """The metadata key of the fitted field ``name``: ``cal_`` and the name, "progressive" shortened
    to "prog", "spring_damping" to "spring_damp" and "digressive" to "digr" so that every key fits
    RPC III's 32 bytes (``cal_spring_damp_front_Ns_per_m``: 30)."""
    return "cal_" + name.replace("progressive", "prog").replace("spring_damping", "spring_damp").replace("digressive",
                                                                                                          "digr")


def calibration_meta(cal) -> dict[str, str]:
    """The calibration in metadata: one key per fitted value (unit, 1-sigma, first guess), fit NRMSE per wheel."""
    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT

    meta = {cal_key(n): f"{v:.6g} {u} +- {s:.2g} (robust {sr:.2g}; first guess {g:.6g})"
            for n, u, g, v, s, sr in zip(cal.names, cal.units, cal.initial, cal.fitted, cal.sigma, cal.sigma_robust)}
    meta["cal_fit_nrmse"] = ", ".join(f"{c} {v:.3f}" for c, v in zip(CORNERS, cal.fit_nrmse))
    meta["cal_model_error"] = (", ".join(f"{c} {v:.3f}" for c, v in zip(CORNERS, cal.excess_nrmse))
                               + f" (limit {HYBRID_LIMIT:g})")
    meta["cal_windows_s"] = ", ".join(f"{a:.3f}-{b:.3f}" for a, b in cal.windows_s)
    meta["cal_runs"] = f"{cal.evaluations} truck variants, {'converged' if cal.converged else 'not converged'}"
    meta["cal_cell_mass"] = (f"{cal.cell_mass_kg:.3g} kg +- {cal.cell_mass_sigma_kg:.2g}: the load cells' mass beyond "
                             "the lab's compensation, fitted with the truck and taken out of the force")
    return meta


def residual_noise_text(noise_N) -> str:
    """What W took out of the model's residual: ``noise_N``, per wheel the model corrects (corner:
    value) the white noise's rms (N) or None where the residual was not white above the truck's band
    (W passed it)."""
    read = [f"{c} {v:.4g} N" if v is not None else f"{c} none (its residual is not white above the truck's band)"
            for c, v in noise_N.items()]
    return "white noise taken out of the model's residual (rms): " + ", ".join(read)


def _shown_path(record) -> str:
    """A record as given: its file, or a read record's path."""
    import os

    path = getattr(record, "path", record)
    return os.fsdecode(path) if isinstance(path, (str, bytes, os.PathLike)) else str(path)


def model_metadata(settings, record, pairs, force_cols, model_result, fallback_source: str | None) -> dict[str, str]:
    """How the output was made; ``model_result`` the ModelCorrection (None: every key the file may
    carry, with the longest sentences, to check an output before the work)."""
    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.records.model.differential import HYBRID_FORMULA, START_S

    method = "probe" if model_result is None else model_result.method
    meta = {"made_by": "rigsim correct --model", "rigsim_version": rigsim_version(), "input": str(record.path),
            "scenario_file": str(settings.scenario_file), "method": method}
    if settings.saved is not None:  # the calibration came from another record, checked on this one
        meta["cal_source"] = (f"{str(settings.saved_file)} (calibrated on {settings.saved.record!r})"
                              if model_result is not None else "x " * 200)
    if settings.calibration_records:  # the calibration fitted windows of these records too
        meta["cal_also"] = ",".join(_shown_path(r) for r in settings.calibration_records)
    reason = "x " * 300 if model_result is None else model_result.reason
    if reason:
        meta["fallback_reason"] = reason
    meta.update({"corners": ",".join(f"{k}={c}" for k, c in zip(pairs, force_cols)),
                 "pairs": ",".join(f"{k}={d}:{x}" for k, (d, x) in pairs.items())})
    meta.update(timing_metadata(settings.force_filter, settings.lvdt_filter))
    if method in ("model", "probe"):
        meta.update({"correction": f"F_corrected = {HYBRID_FORMULA}, L = T_a^-1 T_F", "force_unit": "N",
                     "start_up_s": f"{START_S:g} (model runs' start-up: not settled)",
                     "transient": settings.transient,
                     "model_wheels": ",".join(CORNERS if model_result is None else model_result.wheels) or "none",
                     "drift_cut": "none" if settings.drift_hz is None else f"{settings.drift_hz:g} Hz"})
        noise = dict.fromkeys(CORNERS) if model_result is None else model_result.residual_noise_N  # probe: the longest
        if noise is not None:
            meta["residual_noise"] = residual_noise_text(noise)
    outlook = "x " * 200 if model_result is None else (model_result.outlook and model_result.outlook.text())
    if outlook:  # the derived fallback's figures, where the hybrid was weighed
        meta["hybrid_outlook"] = outlook
    if method in ("linear", "model", "probe"):
        meta.update({"ta_source": fallback_source or "x",
                     **linear_metadata(lowpass=settings.lowpass, lowpass_hz=settings.lowpass_hz, mode=settings.mode,
                                       transient=settings.transient, normalize_dc=settings.normalize_dc)})
    cal = None if model_result is None else model_result.calibration
    if model_result is None:
        from rigsim.scenarios.records.model.family import FITTED, UNITS

        meta.update({cal_key(n): f"0 {UNITS[n]}" for n in FITTED})
        meta.update({k: "x" for k in ("cal_fit_nrmse", "cal_model_error", "cal_windows_s", "cal_runs")})
        meta["cal_cell_mass"] = "x " * 60
        meta["cal_cab"] = "x " * 150
        meta["cal_frame"] = "x " * 150
        meta["cal_engine"] = "x " * 250  # room for two sentences
        meta["cal_damper"] = "x " * 150
        meta["cal_second_start"] = "x " * 180
    elif cal is not None:
        meta.update(calibration_meta(cal))
        if cal.cab_choice:
            meta["cal_cab"] = cal.cab_choice
        if cal.frame_choice:
            meta["cal_frame"] = cal.frame_choice
        if cal.engine_choice:
            meta["cal_engine"] = cal.engine_choice
        if cal.damper_choice:
            meta["cal_damper"] = cal.damper_choice
        if cal.second_start:
            meta["cal_second_start"] = cal.second_start
    return meta


def description_note(cal, scenario_file) -> str:
    """One sentence pointing at the truck's description where the calibrated model does not reproduce a
    wheel beyond the fallback's limit (a wheelbase 10 % off or leaves declared where the truck rides on
    air give model errors of 0.2-0.8, the described truck 0.02-0.05: tests/scenarios/records/
    test_described_truck.py), else ""."""
    if cal is None:
        return ""
    import numpy as np

    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.records.model.fallback import HYBRID_LIMIT

    excess = np.asarray(cal.excess_nrmse, dtype=float)
    worst = int(np.argmax(excess))
    if excess[worst] <= HYBRID_LIMIT:
        return ""
    return (f"note: a model error of {excess[worst]:.2f} on {CORNERS[worst]} (limit {HYBRID_LIMIT:g}) is what a truck "
            f"described wrongly gives: check {str(scenario_file)!r} [vehicle] wheelbase_m, track_front_m, "
            "track_rear_m, rear_tires, suspension_front and suspension_rear against the truck on the rig")


def run_model(plan, progress=None) -> CorrectionResult:
    """Calibrate the truck model on the planned record and correct it, or correct it linearly and say why.

    ``plan``: a :class:`~rigsim.scenarios.records.plan.CorrectionPlan` of the model correction;
    ``progress``: called with each progress line and note (None: silent)."""
    from rigsim.scenarios.records.model.calibrate import WINDOW_LEAD_S, WINDOW_S
    import dataclasses

    from rigsim.scenarios.records.model.differential import correct_with_model
    from rigsim.scenarios.records.model.saved import SavedCalibration, spec_of

    s, record, pairs = plan.settings, plan.record, plan.pairs
    say = progress or (lambda line: None)
    windows, max_nfev = _windows(s)
    guess, unused = first_guess(s.scenario)

    def arrays(p):  # time, drives, LVDTs, forces of a planned record, corners in order
        r = p.record
        return r.time_s, r.array([d for d, _ in p.pairs.values()]), r.array([x for _, x in p.pairs.values()]), \
            r.array(p.channels)

    t, x_ref, x_a, forces = arrays(plan)
    fs = record.fs_hz
    if unused:
        say(f"note: {str(s.scenario_file)!r} [vehicle] {', '.join(unused)} not used: the model is the truck its "
            "description gives, its payload and position start from the record's static loads")
    if s.ta is not None:
        tas, source = s.ta, ta_text(s.ta_source)
    else:  # identified first: a drive and LVDT wired wrongly is refused before minutes of calibration
        from rigsim.scenarios.records.recorded import identify_pairs

        say("identifying T_a per corner from the drive and LVDT channels for the linear correction L")
        fits = identify_pairs(record, pairs=pairs, naming=s.naming).fits
        tas, source = [fits[c] for c in pairs], "identified per corner from the drive and LVDT channels"
    if s.saved is None:
        say(f"model correction of {str(record.path)!r} ({forces.shape[0] / fs:.4g} s at {fs:.6g} Hz): calibrating "
            f"the truck model on {windows} window(s) of {WINDOW_LEAD_S + WINDOW_S:g} s, at most {max_nfev} fit "
            f"evaluations, {s.workers} worker process(es); this takes minutes")
    else:
        say(f"model correction of {str(record.path)!r} ({forces.shape[0] / fs:.4g} s at {fs:.6g} Hz) with the "
            f"calibration {str(s.saved_file)!r}: checking its model error on this record")

    def linear(f):
        res = linear_correction(f, tas, fs, list(plan.channels), list(pairs), lowpass=lowpass_filter(s.lowpass, s.lowpass_hz),
                                mode=s.mode, normalize_dc=s.normalize_dc, transient=s.transient,
                                lowpass_hz=s.lowpass_hz, naming=s.naming)
        return res.corrected_N, res.settled

    more = [(t_o, x_a_o, f_o, x_ref_o) for t_o, x_ref_o, x_a_o, f_o in map(arrays, plan.more)]  # calibrate's order
    if more:
        say(f"the calibration fits {windows} window(s) of each of {len(more)} other record(s) too: "
            + ", ".join(repr(str(p.record.path)) for p in plan.more))
    res = correct_with_model(t, x_ref, x_a, forces, base_scenario=s.scenario,
                             workers=s.workers, windows=windows, max_nfev=max_nfev, fitted_guess=guess, cab=s.cab,
                             linear=linear, drift_hz=s.drift_hz, saved=None if s.saved is None else s.saved.calibration,
                             **({"more": more} if more else {}))
    cal = res.calibration
    saved = None if cal is None else SavedCalibration(cal, spec_of(s.scenario), str(s.scenario_file), str(record.path),
                                                      forces.shape[0] / fs, float(fs), rigsim_version(),
                                                      tuple(str(p.record.path) for p in plan.more))
    from rigsim.scenarios.records.model.refine import refined_names
    from rigsim.scenarios.records.model.skew import skew_note

    for hint in (description_note(cal, s.scenario_file), skew_note(cal)):
        if hint:
            say(hint)
    if cal is not None and s.saved is not None and not cal.second_start:
        say(f"calibration {str(s.saved_file)!r} (calibrated on {s.saved.record!r}) holds on this record: model error "
            + ", ".join(f"{c} {v:.3f}" for c, v in zip(pairs, cal.excess_nrmse))
            + (", the tire's progressive stiffening refitted on its loads" if refined_names(cal) else "")
            + f", checked in {cal.wall_time_s:.0f} s")
    elif cal is not None:
        say(f"calibrated in {cal.wall_time_s:.0f} s ({cal.evaluations} truck variants run, "
            f"{'converged' if cal.converged else 'not converged'}, worst fit NRMSE {cal.worst_fit_nrmse:.3f})"
            + (f"; corrected in {res.timings['correction_s']:.1f} s" if not res.use_linear else ""))
    if not res.use_linear:
        settled = res.settled
        loads = channel_loads(plan.channels, forces[settled], res.corrected_N[settled], fs) if settled.any() else ()
        return CorrectionResult(
            channels=plan.channels, corners=plan.corners, time_s=record.time_s, measured_N=forces,
            corrected_N=res.corrected_N, settled=settled, fs_hz=float(fs), method="model", reason=res.reason,
            description=f"{MODEL_TEXT}, L with T_a {source}", transient=s.transient,
            metadata=model_metadata(s, record, pairs, plan.channels, res, source), loads=loads, calibration=cal,
            inputs=plan.inputs, saved_calibration=saved)
    return dataclasses.replace(
        linear_result(plan, tas, source, corners=list(pairs), reason=res.reason, calibration=cal,
                      metadata=model_metadata(s, record, pairs, plan.channels, res, source)), saved_calibration=saved)
