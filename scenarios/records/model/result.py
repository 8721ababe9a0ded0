"""Result objects of the model correction: a calibration and a correction (or its fallback).

Both are frozen dataclasses whose fields are plain numbers, strings, tuples, mappings and numpy
arrays, so :func:`rigsim.scenarios.core.files.to_json` / ``write_json`` write them as they are
(:meth:`ModelCorrection.to_dict` leaves the time series out of the JSON).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rigsim.mjcf.names import CORNERS
from rigsim.mjcf.variant import TruckVariant

__all__ = ["Calibration", "ModelCorrection", "MODEL", "LINEAR", "model_error", "fitted_text"]

#: The two answers of :func:`rigsim.scenarios.records.model.differential.correct_with_model`.
MODEL, LINEAR = "model", "linear"


def model_error(fit_nrmse, noise_nrmse) -> tuple:
    """Per wheel: the fit NRMSE beyond the noise, sqrt(fit^2 - noise^2) (0 where the noise estimate
    exceeds the fit), 1: independent errors add in power."""
    return tuple(float(np.sqrt(max(f * f - n * n, 0.0))) for f, n in zip(fit_nrmse, noise_nrmse))


@dataclass(frozen=True)
class Calibration:
    """The truck model fitted to a rig record (:func:`rigsim.scenarios.records.model.calibrate.calibrate`).

    Attributes
    ----------
    names : tuple of str
        The fitted :class:`rigsim.mjcf.variant.TruckVariant` fields.
    units : tuple of str
        Their SI units ("kg", "m", "N/m", "N s/m", "N", "Hz").
    initial : tuple of float
        The first guess, SI (payload and its position from the measured static loads, a tire's
        onset at its axle's static load (:mod:`rigsim.scenarios.records.model.onset_load`), the
        rest catalogue values: :func:`rigsim.scenarios.records.model.first_guess.catalogue`).
    fitted : tuple of float
        The fitted values, SI.
    sigma : tuple of float
        1-sigma uncertainty of each fitted value, SI: the diagonal of (J^T J)^-1 s^2 at the optimum
        (J the Jacobian of the residuals, s^2 their variance with m - n degrees of freedom), carried
        to the values through their derivatives (an onset, load / kt, through its kt too). It
        treats the residual as white: a lower bound where a model mismatch leaves a coloured one.
    sigma_robust : tuple of float
        1-sigma from the block-robust sandwich estimate (blocks of
        :data:`~rigsim.scenarios.records.model.calibrate.BLOCK_S`), which allows a residual
        correlated in time; neither includes the bias a structural model error leaves.
    fixed : Mapping[str, float or None]
        Fields held at catalogue values (not identifiable from the record, or not asked for), SI;
        None: the XML's (``cab_mount_hz`` None: the rigid cab; ``tire_progressive_ratio`` None:
        the linear tire).
    fit_nrmse : tuple of float
        Per wheel (fl, fr, rl, rr): NRMSE (1, :func:`rigsim.correction.metrics.dlc.nrmse`) of the fitted model's
        force, pans following the measured x_a, against the measured rig force, on the windows'
        scored samples (the load cells' noise included).
    initial_nrmse : tuple of float
        The same where the search started (the first guess, or the ``start`` given).
    windows_s : tuple of (float, float)
        Scored span of each window, s on the record's time axis (each run starts its lead-in
        before it).
    weighted : bool
        The residual was weighted towards where the correction uses the model
        (:mod:`rigsim.scenarios.records.model.weighting`); :attr:`fit_nrmse` is unweighted.
    evaluations : int
        Truck variants run (each on every window), the Jacobians' perturbed ones included, by every
        calibration behind this one (with the cab's choice both families'; with a wheel left out,
        the first calibration's too), as :attr:`wall_time_s` counts their time.
    converged : bool
        The least squares met a tolerance (not its evaluation limit).
    message : str
        The optimizer's word on how it stopped, and any stiffening ratio set to 0 because its
        onset lies beyond every measured load (:data:`~rigsim.scenarios.records.model.onset_load.TOP`).
    wall_time_s : float, s
    bounds : tuple of (float, float)
        Each fitted field's search range, SI (its first guess times
        :data:`~rigsim.scenarios.records.model.family.RANGES`, clipped to
        :data:`rigsim.mjcf.variant.BOUNDS`; a tire's onset: the loads measured on its axle over the fitted
        kt): a value at its edge was stopped there, not fitted.
    noise_nrmse : tuple of float
        Per wheel: the measured force's white noise (:func:`rigsim.correction.identification.noise.noise_rms`, read above
        the truck's band) over the same std as :attr:`fit_nrmse`, 1: the part of the fit NRMSE no
        model can remove; () when not estimated.
    band_nrmse : tuple of float
        Per wheel: the fit's dynamic residual inside the correction's band, over the band-limited
        measured force's std (:func:`rigsim.scenarios.records.model.band_error.band_errors`), 1; () when not
        measured.
    band_noise_nrmse : tuple of float
        Per wheel: the white noise's share of :attr:`band_nrmse`, 1.
    wheels : tuple of str
        The corners whose measured forces were fitted (all four unless one was left out).
    cell_mass_kg : float, kg
        The mass the load cells weigh with their pans' acceleration beyond the lab's compensation,
        fitted with the truck (:mod:`rigsim.scenarios.records.model.cell_mass`; negative: the lab
        compensates too much); 0 where not fitted.
    cell_mass_sigma_kg : float, kg
        Its block-robust 1-sigma given the truck's fitted values.
    cab_choice : str
        Where the calibration chose whether to fit the cab's mount
        (:func:`rigsim.scenarios.records.model.cab_choice.calibrate_cab`): one sentence on which
        and why; "" otherwise.
    frame_choice : str
        On a described truck, whether the frame's modes were fitted and why
        (:func:`rigsim.scenarios.records.model.frame_choice.calibrate_truck`); "" otherwise.
    engine_choice : str
        On a described truck, whether the engine on its mounts was fitted and why (the same
        function, after the frame); "" otherwise.
    damper_choice : str
        On a described truck, whether the spring dampers were fitted digressive and why (the same
        function, after the engine); "" otherwise.
    window_records : tuple of int
        Where the calibration fitted windows of other records too (``calibrate(more=...)``): the
        record of each window of :attr:`windows_s` (0: the record calibrated, 1, 2...: the others in
        the order given), each window's times on its own record's clock; empty: every window is
        the record's.
    second_start : str
        Where the first fit was refused for its model error and searched again, from the leaf
        springs sliding and with each axle's stations held alike
        (:func:`rigsim.scenarios.records.model.restart.calibrate_again`): one sentence on the fits and
        which is kept; "" otherwise.

    Examples
    --------
    What ``CorrectionResult.calibration`` holds after a correction by the truck model; one built
    by hand here, two fields fitted on two windows:

    >>> from rigsim.scenarios.records.model.result import Calibration
    >>> cal = Calibration(names=("payload_kg", "payload_x_m"), units=("kg", "m"),
    ...                   initial=(6000.0, -1.0), fitted=(6352.4, -1.32), sigma=(8.1, 0.004),
    ...                   sigma_robust=(21.0, 0.011), fixed={"cab_mount_hz": None},
    ...                   fit_nrmse=(0.041, 0.043, 0.052, 0.049),
    ...                   initial_nrmse=(0.31, 0.30, 0.42, 0.40),
    ...                   windows_s=((5.0, 10.0), (15.0, 20.0)), weighted=True, evaluations=42,
    ...                   converged=True, message="ftol reached", wall_time_s=95.0)
    >>> print(cal.table())
    | parameter | unit | first guess | fitted +- 1 sigma (robust) |
    | --- | --- | --- | --- |
    | payload_kg | kg | 6000 | 6352.4 +- 8.1 (21) |
    | payload_x_m | m | -1 | -1.32 +- 0.004 (0.011) |
    >>> cal.values()["payload_kg"], cal.worst_fit_nrmse, cal.fitted_cab_hz
    (6352.4, 0.052, None)
    """

    names: tuple
    units: tuple
    initial: tuple
    fitted: tuple
    sigma: tuple
    sigma_robust: tuple
    fixed: Mapping
    fit_nrmse: tuple
    initial_nrmse: tuple
    windows_s: tuple
    weighted: bool
    evaluations: int
    converged: bool
    message: str
    wall_time_s: float
    bounds: tuple = ()
    cab_choice: str = ""
    frame_choice: str = ""
    engine_choice: str = ""
    damper_choice: str = ""
    window_records: tuple = ()
    second_start: str = ""
    noise_nrmse: tuple = ()
    band_nrmse: tuple = ()
    band_noise_nrmse: tuple = ()
    wheels: tuple = CORNERS
    cell_mass_kg: float = 0.0
    cell_mass_sigma_kg: float = 0.0

    @property
    def choices(self) -> tuple[str, ...]:
        """The sentences of the choices the calibration made (the cab's, the frame's, the engine's, the
        dampers'), in that order, those it did not make left out."""
        return tuple(s for s in (self.cab_choice, self.frame_choice, self.engine_choice, self.damper_choice) if s)

    def values(self) -> dict[str, float]:
        """The whole model truck: fitted and fixed fields, SI."""
        out = dict(self.fixed)
        out.update(zip(self.names, self.fitted))
        return out

    def variant(self) -> TruckVariant:
        """The fitted truck as a :class:`rigsim.mjcf.variant.TruckVariant`."""
        return TruckVariant(**self.values())

    def at_edge(self, name: str, fraction: float = 0.02) -> bool:
        """Whether fitted field ``name`` ended within ``fraction`` (1) of an end of its search range
        (:attr:`bounds`), relative to that end's magnitude (to the range's width for an end at 0);
        False without bounds."""
        if not self.bounds:
            return False
        i = self.names.index(name)
        lo, hi = self.bounds[i]
        v = self.fitted[i]

        def tol(end: float) -> float:
            return fraction * (abs(end) if end != 0 else hi - lo)

        return bool(v - lo <= tol(lo) or hi - v <= tol(hi))

    def error_figures(self) -> tuple[str, tuple, tuple]:
        """What :attr:`excess_nrmse` is read from: where (" in the correction's band", or "" for the
        whole band), the NRMSE per wheel and the noise's share of it (() where not estimated)."""
        if self.band_nrmse:
            return " in the correction's band", self.band_nrmse, self.band_noise_nrmse
        return "", self.fit_nrmse, self.noise_nrmse

    @property
    def excess_nrmse(self) -> tuple:
        """Per wheel: the model's own error on the record, 1: the fit's residual in the correction's
        band beyond the load cells' noise there (:attr:`band_nrmse`, :attr:`band_noise_nrmse`,
        :func:`model_error`); where those were not measured, the fit NRMSE beyond the noise (or the
        fit NRMSE itself where the noise was not estimated)."""
        _, fit, noise = self.error_figures()
        return model_error(fit, noise) if noise else tuple(fit)

    @property
    def fitted_cab_hz(self) -> float | None:
        """float, Hz: the cab's fitted mount frequency, or None where the cab was held (not fitted)."""
        return self.fitted[self.names.index("cab_mount_hz")] if "cab_mount_hz" in self.names else None

    @property
    def worst_fit_nrmse(self) -> float:
        """float, 1: the largest per-wheel :attr:`fit_nrmse`."""
        return float(max(self.fit_nrmse))

    def table(self, truth: Mapping | None = None) -> str:
        """Markdown table of the fit: guess, fitted +- 1 sigma, and (given) the true values."""
        head = "| parameter | unit | first guess | fitted +- 1 sigma (robust) |" + (" plant (truth) | error |" if truth else "")
        lines = [head, "|" + " --- |" * (6 if truth else 4)]
        for name, unit, g, v, s, sr in zip(self.names, self.units, self.initial, self.fitted, self.sigma,
                                           self.sigma_robust):
            row = f"| {name} | {unit} | {g:.5g} | {fitted_text(v, s)} +- {s:.2g} ({sr:.2g}) |"
            if truth:
                tv = truth.get(name)
                if tv is None:
                    row += " - | - |"
                elif name in ("payload_x_m", "payload_z_m"):
                    row += f" {tv:.5g} | {v - tv:+.3f} m |"
                else:
                    row += f" {tv:.5g} | {(v / tv - 1) if tv else float('nan'):+.1%} |"
            lines.append(row)
        return "\n".join(lines)


def fitted_text(value: float, sigma: float) -> str:
    """A fitted value written to the digits its 1-sigma supports.

    Parameters
    ----------
    value : float
        The fitted value.
    sigma : float
        Its 1-sigma uncertainty, same unit.

    Returns
    -------
    str
        ``value`` to the decimal of ``sigma``'s second significant digit, at most 5 significant
        digits (``format(value, ".5g")`` where ``value`` or ``sigma`` is zero or not finite):
        0.0039416 +- 0.063 reads "0.004", 3657.65 +- 0.44 "3657.7".
    """
    if not (np.isfinite(value) and np.isfinite(sigma) and value != 0 and sigma > 0):
        return f"{value:.5g}"
    digits = int(np.floor(np.log10(abs(value)))) - int(np.floor(np.log10(sigma))) + 2
    return f"{value:.{min(max(digits, 1), 5)}g}"


@dataclass(frozen=True)
class ModelCorrection:
    """The outcome of correcting a rig record by the calibrated truck model, or why not.

    Attributes
    ----------
    method : {"model", "linear"}
        "model": :attr:`corrected_N` holds the model correction (:attr:`formula`); "linear": the
        model cannot be trusted on this record and the linear correction is to be used.
    reason : str
        With "linear": one sentence saying why; "" otherwise.
    calibration : Calibration or None
        None when the calibration could not even start (e.g. the static loads imply no truck).
    corrected_N : numpy.ndarray or None, N, (n, 4)
        The corrected wheel forces on the record's time axis (unfiltered; method "model" only).
    settled : numpy.ndarray of bool or None, (n,)
        Samples after the model runs' start-up transient (:data:`~rigsim.scenarios.records.model.differential.START_S`).
    wall_time_s : float, s
        Calibration plus correction.
    timings : Mapping[str, float]
        Wall time of each stage, s.
    wheels : tuple of str
        The wheels the model corrects (method "model"); the others are corrected linearly and
        :attr:`reason` says why.
    formula : str
        How :attr:`corrected_N` was made, e.g. ``F_model(x_ref) + L(W(F_rig - F_model(x_a)))``.
    model_N : tuple of numpy.ndarray or None, N, (n, 4) each
        ``(F_model(x_ref), F_model(x_a))``, the calibrated model's two runs the correction used
        (method "model" only).
    residual_noise_N : Mapping[str, float or None] or None, N
        Per wheel the model corrects (by corner), the white noise W took out of the model's
        residual (its rms over the whole band), None for a wheel whose residual was not white above
        the truck's band (W passed it); None without W (the differential form, or method "linear").
    outlook : HybridOutlook or None
        The derived fallback's figures per wheel (:mod:`~rigsim.scenarios.records.model.fallback`), where
        the hybrid was weighed against the linear correction; None otherwise.
    record_error : tuple of float or None, 1, (4,)
        Per wheel, the model error over the whole run the correction uses
        (:func:`~rigsim.scenarios.records.model.band_error.record_errors`), where the model ran on the
        record; None otherwise.
    """

    method: str
    reason: str
    calibration: Calibration | None
    corrected_N: np.ndarray | None = None
    settled: np.ndarray | None = None
    wall_time_s: float = 0.0
    timings: Mapping = field(default_factory=dict)
    wheels: tuple = ()
    formula: str = ""
    model_N: tuple | None = None
    residual_noise_N: Mapping | None = None
    outlook: object | None = None
    record_error: tuple | None = None

    @property
    def use_linear(self) -> bool:
        """True: fall back to the linear correction (:attr:`reason` says why)."""
        return self.method == LINEAR

    def to_dict(self) -> dict:
        """Everything but the time series (for JSON)."""
        settled_s = None
        if self.settled is not None:
            settled_s = int(np.count_nonzero(self.settled))
        return {"method": self.method, "reason": self.reason, "calibration": self.calibration,
                "settled_samples": settled_s, "wall_time_s": self.wall_time_s, "timings": dict(self.timings),
                "wheels": list(self.wheels), "formula": self.formula,
                "residual_noise_N": None if self.residual_noise_N is None else dict(self.residual_noise_N),
                "record_error": None if self.record_error is None else list(self.record_error)}
