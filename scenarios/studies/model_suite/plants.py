"""The plant trucks of the model-correction study: each case's truck on the rig, its scenario and runs.

The truck on the rig (the "plant") differs from the XML's nominal truck as a real truck differs
from its catalogue: the catalogue offsets of :func:`rigsim.scenarios.studies.suites.model_plants`
(payload -5 % of the case's own and 0.1 m further forward, tire stiffness +10 % front / -10 %
rear, tire damping +20 % / -20 %, leaf friction +30 % / -30 %) on every plant, and each plant's
own cab and tire: ``rigid`` (the XML's rigid cab and linear tires), ``cab`` (the cab on 2 Hz
mounts), ``tire`` (a bilinear progressive tire, +25 % beyond a 2 cm onset), ``smooth`` (a tire
stiffening gradually, +50 % over 2 cm). The model correction calibrates from the rig's records
alone and never sees these values; a plant lies inside or outside the calibrated model family
depending on the model's cab mode (:func:`mismatch`).

A case is a paper scenario's path or a scenario document of a suite
(:func:`rigsim.scenarios.studies.suites.pick_cases`).
"""

from __future__ import annotations

import dataclasses

from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.config import Scenario
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies.identify.compute import identify_rig
from rigsim.scenarios.studies.suites import case_payload_kg, case_scenario, model_plants

__all__ = ["TIRE_PLANT", "plant_keys", "plant_truck", "plant_variant", "plant_name", "mismatch", "plant_scenario",
           "plant_job"]

#: The plant whose progressive tire's ratio a study may set (``tire_ratio`` below).
TIRE_PLANT = "tire"


def plant_keys() -> tuple[str, ...]:
    """The plants' keys in their default order (``rigid``, ``cab``, ``tire``, ``smooth``)."""
    return tuple(model_plants().plants)


def plant_truck(plant: str, tire_ratio: float | None = None) -> dict:
    """The :class:`rigsim.mjcf.variant.TruckVariant` fields plant ``plant`` sets beyond the catalogue offsets.

    Parameters
    ----------
    plant : str
        A key of :func:`plant_keys`.
    tire_ratio : float, 1, optional
        The :data:`TIRE_PLANT`'s extra tire stiffness beyond the onset, in place of the data's
        (0.25); no effect on the other plants.

    Raises
    ------
    ValueError
        An unknown plant.
    """
    plants = model_plants().plants
    if plant not in plants:
        raise ValueError(f"plant must be one of {', '.join(plants)}, got {plant!r}")
    truck = dict(plants[plant].truck)
    if plant == TIRE_PLANT and tire_ratio is not None:
        truck["tire_progressive_ratio"] = float(tire_ratio)
    return truck


def plant_variant(case_payload_kg: float, plant: str = "rigid", tire_ratio: float | None = None) -> TruckVariant:
    """The plant truck of a case: the catalogue offsets on the XML's nominal values, then the plant's own fields.

    Parameters
    ----------
    case_payload_kg : float, kg
        The case's payload (the plant carries the catalogue's factor of it, 0 kg included).
    plant : str
        A key of :func:`plant_keys`.
    tire_ratio : float, 1, optional
        See :func:`plant_truck`.

    Returns
    -------
    rigsim.mjcf.variant.TruckVariant

    Raises
    ------
    ValueError
        An unknown plant, or a field value :class:`~rigsim.mjcf.variant.TruckVariant` refuses.
    """
    from rigsim.scenarios.records.model.first_guess import xml_nominal  # the model correction's imports: only here

    truck = plant_truck(plant, tire_ratio)
    suite, nominal = model_plants(), xml_nominal()
    values = {k: nominal[k] * f for k, f in suite.factors.items()}
    values["payload_kg"] = case_payload_kg * suite.factors["payload_kg"]
    values["payload_x_m"] = nominal["payload_x_m"] + suite.payload_x_shift_m
    return TruckVariant(**(values | truck))


def plant_name(plant: str, tire_ratio: float | None = None) -> str:
    """A plant's readable name, from what it sets: "rigid cab", "cab on 2 Hz mounts", "progressive
    tire +25 %", "tire stiffening +50 % over 2 cm" (``tire_ratio``: see :func:`plant_truck`)."""
    t = plant_truck(plant, tire_ratio)
    if "cab_mount_hz" in t:
        return f"cab on {t['cab_mount_hz']:g} Hz mounts"
    if "tire_progressive_spread_m" in t:
        return f"tire stiffening +{100 * t['tire_progressive_ratio']:g} % over {100 * t['tire_progressive_spread_m']:g} cm"
    if "tire_progressive_ratio" in t:
        return f"progressive tire +{100 * t['tire_progressive_ratio']:g} %"
    return "rigid cab"


def mismatch(plant: str, cab: str) -> str:
    """ "on" where plant ``plant`` lies outside the model family calibrated with cab mode ``cab``
    (:data:`rigsim.scenarios.records.model.cab_choice.CAB_CHOICES`), "off" inside: the gradually
    stiffening tire always, the cab on its mounts only with the cab held rigid (the bilinear
    progressive tire is in the family: each axle's ratio and onset are fitted)."""
    plants = model_plants().plants
    if plant not in plants:
        raise ValueError(f"plant must be one of {', '.join(plants)}, got {plant!r}")
    return "on" if cab in plants[plant].outside_family else "off"


def plant_scenario(case, duration_s: float, plant: str = "rigid", tire_ratio: float | None = None) -> Scenario:
    """The case with its plant truck (:func:`plant_variant` of the case's own payload).

    Parameters
    ----------
    case : str, pathlib.Path or dict
        A paper scenario's path, or a scenario document of a suite.
    duration_s : float, s
        Record length, in place of the case's.
    plant : str
        A key of :func:`plant_keys`.
    tire_ratio : float, 1, optional
        See :func:`plant_truck`.
    """
    sc = case_scenario(case)
    return dataclasses.replace(sc, duration_s=float(duration_s),
                               vehicle=plant_variant(case_payload_kg(sc), plant, tire_ratio))


def plant_job(case, duration_s: float, plant: str, kind: str, tire_ratio: float | None = None):
    """Worker job: one MuJoCo run of a case's plant (:func:`plant_scenario`).

    Parameters
    ----------
    kind : str
        "road" (the reference), "rig" (the rig test) or "identify" (the rig characterized before
        the test, :func:`rigsim.scenarios.studies.identify.compute.identify_rig`).

    Returns
    -------
    rigsim.scenarios.core.results.RunResult or rigsim.scenarios.studies.identify.compute.RigIdentification
    """
    sc = plant_scenario(case, duration_s, plant, tire_ratio)
    return identify_rig(sc) if kind == "identify" else run(sc, kind)
