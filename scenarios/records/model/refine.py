"""A saved calibration's load-dependent fields refined on the record it corrects.

A tire stiffens progressively beyond an onset load (:data:`REFINED`: the ratio of its stiffness
beyond the onset and the onset, front and rear). A record shows that stiffening only at the loads it
reaches, and on a plant whose tire is not the model's law the best ratio and onset are those of the
record's own load range: calibrated on records of another road or speed, the same truck's ratio is
0.76-3.1 times the one a record gives alone (the programme benchmark's mismatched truck, 20 records
of 60 s at 48-80 km/h), and a record's DLC follows it (0.2-0.3 % on the wheels whose ratio moved
most), where every other fitted value agrees within 14 %. The peaks that set a record's DLC and
damage are those loads.

So a calibration that holds on a record (:func:`~rigsim.scenarios.records.model.saved.check_saved`)
keeps every value but these, which are fitted again on the record's own windows, started from the
saved values, with everything else held (:func:`refine_on_record`): a handful of model runs per
iteration instead of the whole calibration's.
"""

from __future__ import annotations

import dataclasses

from rigsim.scenarios.records.model.calibrate import calibrate
from rigsim.scenarios.records.model.result import Calibration

__all__ = ["REFINED", "refined_names", "refine_on_record"]

#: The fields a saved calibration refits on each record it corrects: the progressive tire's.
REFINED = ("tire_progressive_ratio", "tire_progressive_onset_m", "tire_progressive_ratio_rear",
           "tire_progressive_onset_rear_m")


def refined_names(cal: Calibration) -> tuple:
    """The fields of ``cal`` that :func:`refine_on_record` refits: :data:`REFINED` that it fitted (a tire
    held linear has none)."""
    return tuple(k for k in REFINED if k in cal.names)


def refine_on_record(cal: Calibration, t_s, x_a_m, force_N, **calibrate_kw) -> Calibration:
    """``cal`` with its :func:`refined_names` fitted again on this record, every other value held.

    Parameters
    ----------
    cal : Calibration
        A calibration from other records that holds on this one (as
        :func:`~rigsim.scenarios.records.model.saved.on_record` shows it).
    t_s, x_a_m, force_N
        This record: time (s), measured pan displacement (m, (n, 4)), measured wheel force (N, (n, 4)).
    **calibrate_kw
        Passed to :func:`~rigsim.scenarios.records.model.calibrate.calibrate` (``base_scenario``
        required; ``x_ref_m``, ``windows``, ``executor``...); ``names``, ``fitted_guess`` and
        ``start`` are this function's.

    Returns
    -------
    Calibration
        ``cal`` with those values, their sigmas, the load cells' mass and the fit figures of the
        refit on this record's windows; its ``evaluations`` and ``wall_time_s`` (s) are the refit's
        added to ``cal``'s. ``cal`` itself where it has no such field.
    """
    names = refined_names(cal)
    if not names:
        return cal
    kw = {k: v for k, v in calibrate_kw.items() if k not in ("names", "fitted_guess", "start", "sigma", "more")}
    values = cal.values()
    fit = calibrate(t_s, x_a_m, force_N, names=names, fitted_guess=values, start={k: values[k] for k in names},
                    wheels=cal.wheels, **kw)
    new = dict(zip(fit.names, fit.fitted))
    sigma, robust = dict(zip(fit.names, fit.sigma)), dict(zip(fit.names, fit.sigma_robust))
    return dataclasses.replace(
        cal, fitted=tuple(float(new.get(k, v)) for k, v in zip(cal.names, cal.fitted)),
        sigma=tuple(float(sigma.get(k, s)) for k, s in zip(cal.names, cal.sigma)),
        sigma_robust=tuple(float(robust.get(k, s)) for k, s in zip(cal.names, cal.sigma_robust)),
        fit_nrmse=fit.fit_nrmse, noise_nrmse=fit.noise_nrmse, band_nrmse=fit.band_nrmse,
        band_noise_nrmse=fit.band_noise_nrmse, windows_s=fit.windows_s, converged=cal.converged and fit.converged,
        cell_mass_kg=fit.cell_mass_kg, cell_mass_sigma_kg=fit.cell_mass_sigma_kg,
        evaluations=cal.evaluations + fit.evaluations,
        wall_time_s=round((cal.wall_time_s or 0.0) + fit.wall_time_s, 3))
