"""The load cells' mass as the lab's, not the truck's: a study of the fleet suite's scores.

Every calibration fits the load cells' uncompensated mass with the truck
(:mod:`rigsim.scenarios.records.model.cell_mass`), and a model error in phase with the pans'
acceleration passes for mass: one truck's fitted mass may be several kilograms off the cells' own,
and its corrected DLC moves by 0.1-0.2 % per kilogram, the more the lighter the truck. But the
mass is the rig's: every truck a lab tests on it has the same. This module scores the hybrid
correction as it would be with one mass for the lab, read from the lab's own calibrations (their
median), and with the chain's own mass (what an empty-pan run would read), from each truck's
:attr:`~rigsim.scenarios.studies.model_suite.mismatch_score.PlantScore.mass_scan`. It is a study:
``rigsim correct`` fits each record's mass on its own.
"""

from __future__ import annotations

import numpy as np

from rigsim.scenarios.studies.model_suite.goals import DLC_GOOD, FLOOR_RATIO, good_on_linear

__all__ = ["hybrid_at_mass", "lab_mass_kg", "share_at_mass", "mass_text"]


def hybrid_at_mass(score, mass_kg: float) -> tuple[np.ndarray, np.ndarray]:
    """One truck's hybrid correction scored with the load cells' mass ``mass_kg`` (kg): (DLC error,
    NRMSE) per wheel (1, (4,)). The corrected force is linear in the mass, so its variance and its
    mean square error against the road are quadratic in it: ``(1 + DLC error)^2`` and ``NRMSE^2``
    are interpolated through the score's three masses (exact but for the noise gain W, designed
    again on each mass's residual, and the mean's share of the mass's term, both small)."""
    scan = score.mass_scan
    m = np.asarray(scan["mass_kg"], dtype=float)
    ratio2 = (1.0 + np.asarray(scan["dlc_error"], dtype=float)) ** 2
    nrmse2 = np.asarray(scan["nrmse"], dtype=float) ** 2
    at = np.array([float(mass_kg) ** 2, float(mass_kg), 1.0])
    fit = lambda y: at @ np.polyfit(m, y, 2)  # noqa: E731  (one quadratic per wheel: y is (3, 4))
    return np.sqrt(np.maximum(fit(ratio2), 0.0)) - 1.0, np.sqrt(np.maximum(fit(nrmse2), 0.0))


def lab_mass_kg(scores) -> float:
    """The lab's load cells' mass read from its calibrations (kg): the median of the fitted masses
    of the trucks ``scores`` (those calibrated)."""
    return float(np.median([s.cell_mass_kg for s in scores if s.cell_mass_kg is not None]))


def share_at_mass(scores, mass_kg: float) -> float:
    """The share of wheels within :data:`~.goals.DLC_GOOD` of the road DLC at NRMSE at most
    :data:`~.goals.FLOOR_RATIO` times the linear correction's (the issue's terms), each truck whose
    correction the model delivered scored with the hybrid at ``mass_kg`` (kg), the others as delivered."""
    good = []
    for s in scores:
        d, n = s.dlc_error["delivered"], s.nrmse["delivered"]
        if s.method == "model" and s.mass_scan is not None and np.allclose(n, s.nrmse["hybrid"]):
            d, n = hybrid_at_mass(s, mass_kg)
        good.append(good_on_linear(s, d, n))
    return float(np.mean(np.concatenate(good)))


def mass_text(scores, chain_kg: float) -> str:
    """The study's line for a draw's page: the share on the issue's terms with the lab's mass read
    from its calibrations and with the chain's own ``chain_kg`` (kg); "" where a score has no scan."""
    if not scores or any(s.mass_scan is None for s in scores if s.method == "model"):
        return ""
    masses = [s.cell_mass_kg for s in scores if s.cell_mass_kg is not None]
    lab = float(np.median(masses))  # lab_mass_kg's
    return (f"- the load cells' mass as the lab's (a study, not what `rigsim correct` does): the trucks' fitted masses "
            f"{min(masses):+.1f} to {max(masses):+.1f} kg, their median {lab:+.1f} kg, the chain's own {chain_kg:+.1f} kg; "
            f"with the median for every truck {100 * share_at_mass(scores, lab):.1f} % of the wheels within "
            f"{100 * DLC_GOOD:g} % of the road DLC at NRMSE <= {FLOOR_RATIO:g} x the linear correction's, with the "
            f"chain's own {100 * share_at_mass(scores, chain_kg):.1f} %")
