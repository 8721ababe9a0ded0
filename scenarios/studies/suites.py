"""The shipped suites of cases, read from data files: what the studies and benchmarks run.

The cases a study runs are data, not code: each suite is a TOML file under
``scenarios/data/`` (installed with the package) and this module reads it.

* the paper suite: the paper's three scenario files, ``scenarios/data/paper/*.toml``
  (:func:`paper_cases`);
* the generalization suite: 24 scenario documents beyond the paper's cases (ISO 8608 classes
  A-D, 30-100 km/h, payload 0-8000 kg, three kinds of tracks, seeds other than the paper's),
  ``scenarios/data/suites/generalization.toml`` (:func:`generalization_cases`);
* the model-correction study's plant trucks: the catalogue offsets of the truck on the rig
  from the XML's nominal one and the plants (rigid cab, cab on mounts, progressive tire,
  gradually stiffening tire), ``scenarios/data/suites/model_plants.toml`` (:func:`model_plants`);
* the mismatch suite's ranges of real trucks, ``scenarios/data/suites/mismatch_plants.toml``
  (:func:`rigsim.scenarios.studies.model_suite.mismatch.plant_ranges`);
* the fleet suite's spec sheets and plants of other trucks, ``scenarios/data/suites/fleet.toml``
  (:mod:`rigsim.scenarios.studies.model_suite.fleet`).

:func:`pick_cases` picks cases of a suite by parts of their names, as a command line gives them.
"""

from __future__ import annotations

import functools
import importlib.resources
import pathlib
import tomllib
import types
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields

from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.config import paper_scenarios

__all__ = ["SUITES", "SUITE_FILES", "Plant", "ModelPlants", "suite_file", "generalization_cases", "paper_cases",
           "pick_cases", "case_name", "case_scenario", "case_payload_kg", "model_plants"]

#: The suites of cases :func:`pick_cases` knows.
SUITES = ("paper", "generalization")
#: The data files of :mod:`rigsim.scenarios.studies.suites`, under ``scenarios/data/suites/``.
SUITE_FILES = ("generalization.toml", "model_plants.toml", "mismatch_plants.toml", "fleet.toml")


def suite_file(name: str):
    """The installed data file ``name`` (one of :data:`SUITE_FILES`).

    Parameters
    ----------
    name : str
        File name under ``scenarios/data/suites/``.

    Returns
    -------
    importlib.resources.abc.Traversable
        The file as a package resource (``read_text`` reads it).
    """
    if name not in SUITE_FILES:
        raise ValueError(f"no suite file {name!r}; the suite files are {', '.join(SUITE_FILES)}")
    return importlib.resources.files("rigsim.scenarios").joinpath("data", "suites", name)


def _read(name: str) -> dict:
    return tomllib.loads(suite_file(name).read_text(encoding="utf-8"))


def generalization_cases(n: int = 24, duration_s: float | None = None) -> list[dict]:
    """The generalization suite's first ``n`` scenario documents, in the suite's order.

    Parameters
    ----------
    n : int
        How many cases, 1 to 24 (the suite holds 24).
    duration_s : float, s, optional
        Record length of every case, in place of the suite's default (30 s).

    Returns
    -------
    list of dict
        Scenario documents (:func:`rigsim.scenarios.core.config.parse_scenario` reads each): ``name``
        (``gen<i>-<class>-<speed>kmh-<payload>kg-<tracks>``), ``speed_kmh``, ``duration_s``,
        ``seed``, ``road`` (``roughness``, ``tracks``, and for class D ``cuton_wavelength_m``)
        and ``vehicle`` (``payload_kg``). Fresh dicts on every call.

    Raises
    ------
    ValueError
        ``n`` outside 1 to the suite's size.
    """
    docs = _read("generalization.toml")["cases"]
    if not 1 <= n <= len(docs):
        raise ValueError(f"the generalization suite holds {len(docs)} cases: n must be 1 to {len(docs)}, got {n!r}")
    if duration_s is None:
        return docs[:n]
    return [{**d, "duration_s": float(duration_s)} for d in docs[:n]]  # the key keeps its place


def _unique(names: Sequence[str], keys: Sequence[str], suite: str) -> list[int]:
    """Per key, the index of the one name that contains it; ValueError where not exactly one does."""
    out = []
    for key in keys:
        hit = [i for i, name in enumerate(names) if key in name]
        if len(hit) != 1:
            raise ValueError(f"{key!r} matches {len(hit)} of the {suite} suite's cases ({names[0]} ... {names[-1]}); "
                             "give a unique part of one name")
        out.append(hit[0])
    return out


def paper_cases(keys: Sequence[str] | None = None) -> list[pathlib.Path]:
    """The paper's scenario files whose file names contain each of ``keys`` (all three by default).

    Parameters
    ----------
    keys : sequence of str, optional
        Parts of the files' names (e.g. ``"high_72"``), each matching exactly one file.

    Returns
    -------
    list of pathlib.Path
        In the order of ``keys``; without keys, Table 2's order (:func:`rigsim.scenarios.core.config.paper_scenarios`).

    Raises
    ------
    ValueError
        A key that matches no file or more than one.
    """
    paths = paper_scenarios()
    if not keys:
        return paths
    return [paths[i] for i in _unique([p.stem for p in paths], keys, "paper")]


def pick_cases(suite: str, keys: Sequence[str] | None = None, duration_s: float | None = None) -> list:
    """The cases of ``suite`` whose names contain each of ``keys`` (all of the suite by default).

    Parameters
    ----------
    suite : str
        ``"paper"`` or ``"generalization"`` (:data:`SUITES`).
    keys : sequence of str, optional
        Parts of the cases' names, each matching exactly one case.
    duration_s : float, s, optional
        The generalization documents' record length (:func:`generalization_cases`); the paper's
        scenario files keep theirs (a study replaces it when it loads them).

    Returns
    -------
    list
        ``"paper"``: the scenario files' paths (str); ``"generalization"``: scenario documents (dict).

    Raises
    ------
    ValueError
        An unknown suite, or a key that matches no case or more than one.
    """
    if suite not in SUITES:
        raise ValueError(f"suite must be one of {', '.join(SUITES)}, got {suite!r}")
    if suite == "paper":
        return [str(p) for p in paper_cases(keys)]
    docs = generalization_cases(24, duration_s)
    if not keys:
        return docs
    return [docs[i] for i in _unique([d["name"] for d in docs], keys, suite)]


def case_name(case) -> str:
    """A case's name: a scenario document's ``name`` (dict) or a scenario file's stem (path)."""
    return str(case["name"]) if isinstance(case, Mapping) else pathlib.Path(case).stem


def case_scenario(case):
    """A case as a :class:`rigsim.scenarios.core.config.Scenario`: a scenario document parsed (dict), a
    scenario file read (path)."""
    from rigsim.scenarios.core.config import load_scenario, parse_scenario

    return parse_scenario(case) if isinstance(case, Mapping) else load_scenario(case)


def case_payload_kg(scenario) -> float:
    """The payload (kg) a case's scenario carries: its ``[vehicle] payload_kg``, else the XML's."""
    from rigsim.mjcf.build import nominal_values

    given = scenario.vehicle.payload_kg
    return float(given) if given is not None else nominal_values()["payload_kg"]


@dataclass(frozen=True)
class Plant:
    """One plant truck of the model-correction study.

    Attributes
    ----------
    key : str
        Its name in the data (``rigid``, ``cab``, ``tire``, ``smooth``).
    truck : Mapping[str, float]
        The :class:`rigsim.mjcf.variant.TruckVariant` fields it sets beyond the catalogue offsets
        (SI units, as the fields' names say).
    outside_family : tuple of str
        The model's cab modes (:data:`rigsim.scenarios.records.model.cab_choice.CAB_CHOICES`) under which
        the plant lies outside the calibrated model family; inside it under the others.
    """

    key: str
    truck: Mapping[str, float]
    outside_family: tuple[str, ...]


@dataclass(frozen=True)
class ModelPlants:
    """The model-correction study's plant trucks (``scenarios/data/suites/model_plants.toml``).

    Attributes
    ----------
    factors : Mapping[str, float], 1
        Per :class:`rigsim.mjcf.variant.TruckVariant` field, the factor on the XML's nominal value
        (``payload_kg``: on the case's own payload).
    payload_x_shift_m : float, m
        The payload's position against the XML's, forward positive.
    plants : Mapping[str, Plant]
        The plants by key, in their default order.
    """

    factors: Mapping[str, float]
    payload_x_shift_m: float
    plants: Mapping[str, Plant]


@functools.cache
def model_plants() -> ModelPlants:
    """The model-correction study's plant trucks, read from ``scenarios/data/suites/model_plants.toml``.

    Returns
    -------
    ModelPlants
        Read once per process; its mappings are read-only.

    Raises
    ------
    ValueError
        A file that names a field :class:`rigsim.mjcf.variant.TruckVariant` does not have, a cab mode
        that does not exist, or a table or key this reader does not know.
    """
    from rigsim.scenarios.records.model.cab_choice import CAB_CHOICES  # the model correction's imports: only here

    doc = _read("model_plants.toml")
    variant_fields = {f.name for f in fields(TruckVariant)}

    def known(table: Mapping, keys: set, where: str) -> None:
        if set(table) - keys:
            raise ValueError(f"model_plants.toml: unknown {where} {sorted(set(table) - keys)}")

    known(doc, {"catalogue", "plants"}, "table(s)")
    known(doc["catalogue"], {"factors", "payload_x_shift_m"}, "catalogue key(s)")
    known(doc["catalogue"]["factors"], variant_fields, "TruckVariant field(s) among the factors")
    plants = {}
    for key, p in doc["plants"].items():
        known(p, {"truck", "outside_family"}, f"key(s) of plant {key!r}")
        known(p["truck"], variant_fields, f"TruckVariant field(s) of plant {key!r}")
        known(dict.fromkeys(p["outside_family"]), set(CAB_CHOICES), f"cab mode(s) of plant {key!r}")
        plants[key] = Plant(key=key, truck=types.MappingProxyType(dict(p["truck"])),
                            outside_family=tuple(p["outside_family"]))
    return ModelPlants(factors=types.MappingProxyType(dict(doc["catalogue"]["factors"])),
                       payload_x_shift_m=float(doc["catalogue"]["payload_x_shift_m"]),
                       plants=types.MappingProxyType(plants))
