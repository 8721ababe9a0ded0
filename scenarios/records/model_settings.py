"""The model correction's own options checked: its channel pairs and workers, its drift cut, the
truck's scenario file and a saved calibration (:func:`~rigsim.scenarios.records.settings.correction_settings`
calls them before any record is read). Every refusal is one
:class:`~rigsim.scenarios.core.config.ScenarioError` sentence naming the parameter as ``naming``
says. Imports nothing heavy at module level.
"""

from __future__ import annotations

import os

from rigsim.scenarios.records.arguments import checked_pairs, count, file_path, finite, is_path, refusal, shown
from rigsim.scenarios.records.naming import Naming
from rigsim.scenarios.records.output import GIVEN

__all__ = ["WORKERS_PER_CORE", "DRIFT_CUT_MAX_HZ", "model_pairs_workers", "checked_drift_hz", "truck_scenario",
           "saved_calibration"]


def model_pairs_workers(naming: Naming, identify, actuator, actuators, pairs, workers):
    """(pairs in corner order, workers); the model's options only."""
    from rigsim.mjcf.names import CORNERS
    from rigsim.scenarios.core.pool import worker_count
    from rigsim.scenarios.records.recorded import pairs_of

    n = naming
    if identify is not None:
        raise refusal(f"{n('identify')} fits one T_a for the linear correction; with {n('model')} the fallback "
                     f"identifies each corner from {n('pairs')}: drop {n('identify')}")
    if actuator is not None and actuators is not None:
        raise refusal(f"give at most one of {n('actuator')} and {n('actuators')} (the T_a of {n('model')}'s linear "
                     "fallback)")
    if pairs is not None:
        checked_pairs(pairs, n)
    if not pairs:
        raise refusal(f"{n('model')} needs {n.setting('pairs', 'fl=DRIVE:LVDT,fr=...,rl=...,rr=...')} naming each "
                     "corner's drive and LVDT channels")
    pairs = pairs_of(pairs, n)
    for corner in pairs:
        if corner not in CORNERS:
            raise refusal(f"{n('pairs')} names corner {corner!r}; the truck's corners are {', '.join(CORNERS)}")
    missing = [c for c in CORNERS if c not in pairs]
    if missing:
        raise refusal(f"{n('pairs')} has no corner {missing[0]!r}; give CORNER=DRIVE:LVDT for each of "
                     f"{', '.join(CORNERS)}")
    cores = os.cpu_count() or 1
    workers = worker_count(count(n, "workers", workers, (WORKERS_PER_CORE * cores,
                                                        f"{WORKERS_PER_CORE} per core; this machine has {cores}")))
    return {c: pairs[c] for c in CORNERS}, workers


#: Most worker processes of the model correction per core, 1: the truck model's runs are CPU-bound,
#: so more processes than cores add only memory (each holds a MuJoCo model); a few per core leave
#: room for a machine whose cores are counted low (a container's quota).
WORKERS_PER_CORE = 4

#: Largest drift-cut corner, Hz: the truck's body bounce and pitch (and a cab on soft mounts) are at
#: 1.5-3 Hz, where the measured force must pass; the cut's gain at 1.5 Hz is 0.5 with a 1.5 Hz corner.
DRIFT_CUT_MAX_HZ = 1.5


def checked_drift_hz(naming: Naming, drift_cut_hz) -> float | None:
    """The model correction's drift-cut corner (Hz) or None (no cut) from the option (None: the default)."""
    from rigsim.correction.output.denoise import DRIFT_HZ

    if drift_cut_hz is None:
        return DRIFT_HZ
    hz = finite(drift_cut_hz)
    if hz is None or not 0 <= hz <= DRIFT_CUT_MAX_HZ:
        raise refusal(f"{naming('drift_cut_hz')} must be 0 (no drift cut, for load cells that do not drift) or a "
                     f"corner in Hz up to {DRIFT_CUT_MAX_HZ:g} (below the truck's body modes), got "
                     f"{shown(drift_cut_hz)}")
    return hz or None


def truck_scenario(naming: Naming, model) -> tuple:
    """(the truck's scenario, its file or :data:`~rigsim.scenarios.records.output.GIVEN`) from ``model``."""
    from rigsim.scenarios.core.config import Scenario, ScenarioError, load_scenario

    if isinstance(model, Scenario):
        return model, GIVEN
    if not is_path(model):
        raise refusal(f"{naming('truck')} must be a scenario file (TRUCK.toml) or a Scenario, got {shown(model)}")
    path = file_path(model, naming("truck"))
    try:
        return load_scenario(path), path
    except ScenarioError as exc:
        raise refusal(f"{naming('truck')}: {exc}") from None


def saved_calibration(naming: Naming, calibration, scenario) -> tuple:
    """(the saved calibration or None, its file or :data:`~rigsim.scenarios.records.output.GIVEN`) from
    ``calibration``, refused where it was made for a truck described otherwise than ``scenario``'s."""
    if calibration is None:
        return None, None
    from rigsim.scenarios.core.config import ScenarioError
    from rigsim.scenarios.records.model.saved import SavedCalibration, read_calibration, spec_of, truck_differs

    opt = naming("calibration")
    if isinstance(calibration, SavedCalibration):
        saved, source = calibration, GIVEN
    elif is_path(calibration):
        source = file_path(calibration, opt)
        try:
            saved = read_calibration(source)
        except ScenarioError as exc:
            raise refusal(f"{opt}: {exc}") from None
    else:
        raise refusal(f"{opt} must be a calibration file (rigsim correct --model writes one) or a SavedCalibration, "
                     f"got {shown(calibration)}")
    differs = truck_differs(saved, spec_of(scenario))
    if differs:
        raise refusal(f"{opt} {str(source)!r}: {differs}")
    return saved, source
