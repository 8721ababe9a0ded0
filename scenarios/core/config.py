"""Scenario files: strict TOML into frozen, validated dataclasses.

A scenario file names a road, a speed, a payload and a duration, and may override any
parameter of the truck (``[vehicle]``, the fields of :class:`rigsim.mjcf.variant.TruckVariant`) or
of the hydraulic actuators (``[actuator]``, the fields of
:class:`rigsim.hydraulics.params.ActuatorParams`). Every key is checked: an unknown key is an error
that names it and the closest valid key; a wrong type or a value out of range names the
field. Errors are :class:`ScenarioError`, one sentence each.

Example::

    name = "paper-high-72kmh-3640kg"
    speed_kmh = 72.0
    duration_s = 60.0
    seed = 1

    [road]
    roughness = "high"           # ISO 8608 class letter A-H, or the paper's word
    cuton_wavelength_m = 40.0    # high-pass of the drive (stroke 15.2 cm)

    [vehicle]
    payload_kg = 3640.0
"""

from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from rigsim.correction.io.tomlfile import check_keys, number, read_toml
from rigsim.mjcf.variant import TruckVariant
from rigsim.scenarios.core.lab import LabChain
from rigsim.errors import RigsimError

__all__ = ["ScenarioError", "RoadConfig", "Scenario", "load_scenario", "parse_scenario", "paper_scenarios",
           "PAPER_CONFIGURATIONS"]


class ScenarioError(RigsimError, ValueError):
    """A scenario that cannot be run as written; the message is one sentence naming the field.

    Examples
    --------
    Every refusal of :func:`~rigsim.scenarios.records.read_record`,
    :func:`~rigsim.scenarios.records.correct_record` and :func:`~rigsim.scenarios.records.identify_record`,
    before any work:

    >>> import numpy as np
    >>> from rigsim.correction.io.measured import MeasuredChannels
    >>> from rigsim.scenarios.core.config import ScenarioError
    >>> from rigsim import LinearOptions, correct_record
    >>> t = np.arange(1000) / 1000.0
    >>> record = MeasuredChannels(time_s=t, data={"Fz_FL": 40e3 + 0 * t}, units={"Fz_FL": "N"},
    ...                           source_units={"Fz_FL": "N"}, fs_hz=1000.0, metadata={},
    ...                           path="", format="csv")
    >>> try:
    ...     correct_record(record, LinearOptions())
    ... except ScenarioError as exc:
    ...     print(exc)
    give exactly one of actuator='ACT.toml', actuators='ACTS.toml' and identify='DRIVE_COL,DISP_COL'
    """


def _number(where: str, value: Any, *, lo: float | None = None, hi: float | None = None, lo_open=False) -> float:
    return number(where, value, lo=lo, hi=hi, lo_open=lo_open, error=ScenarioError)


@dataclass(frozen=True)
class RoadConfig:
    """The road of a scenario.

    Parameters
    ----------
    roughness : str, optional
        ISO 8608 class letter ("A".."H") or the paper's word ("medium", "high"); see
        :data:`rigsim.scenarios.core.roads.ROUGHNESS_WORDS`. Exactly one of ``roughness``,
        ``gd_n0_m3`` and ``profile_csv`` is given.
    gd_n0_m3 : float, m^3, optional
        Displacement PSD at n0 = 0.1 cycle/m (ISO 8608).
    profile_csv : str, optional
        A measured profile (columns distance_m, left_m, right_m), relative to the scenario file.
    waviness : float
        ISO 8608 waviness w (PSD slope), dimensionless.
    tracks : str
        "identical", "independent" or "coherent" left and right tracks.
    cuton_wavelength_m : float, m
        Cut-on wavelength of the zero-phase high-pass applied to the profile in the distance
        domain, identically for road and rig mode (a rig's stroke is 15.2 cm).
    envelope_length_m : float, m
        Tire enveloping: moving average of the profile over this length before anything else
        (0.25 m, the IRI's tire model; 0 turns it off). See :func:`rigsim.scenarios.core.profiles.envelope`.
    n_min_cyc_per_m, n_max_cyc_per_m : float, cycle/m
        Spatial band of a synthesized profile (ISO 8608 roughness or gd_n0_m3).
    """

    roughness: str | None = None
    gd_n0_m3: float | None = None
    profile_csv: str | None = None
    waviness: float = 2.0
    tracks: str = "independent"
    cuton_wavelength_m: float = 40.0
    envelope_length_m: float = 0.25
    n_min_cyc_per_m: float = 0.01
    n_max_cyc_per_m: float = 10.0


@dataclass(frozen=True)
class Scenario:
    """A validated scenario.

    Parameters
    ----------
    name : str
        Identifier used in outputs.
    speed_kmh : float, km/h
        Vehicle speed over the road (the paper's 48 and 72 km/h). :attr:`speed_mps` in m/s.
    duration_s : float, s
        Analysed duration (after the lead-in).
    seed : int
        Seed of the road's random phases (``numpy.random.default_rng``).
    road : RoadConfig
    vehicle : TruckVariant
        Overrides of the truck model.
    actuator : Mapping[str, float]
        Overrides of the hydraulic actuator parameters (used in rig mode).
    lead_in_s : float, s
        Simulated before t = 0 while the drive fades in (cosine taper over its first half),
        so the run starts from rest and the statistics see no start-up transient.
    output_rate_hz : float, Hz
        Rate of the written time series (a divisor of the simulation rate, >= 1 kHz).
    lab : rigsim.scenarios.core.lab.LabChain
        How the lab measures the rig test (``[lab]``, the fields of
        :class:`~rigsim.scenarios.core.lab.LabChain`; default: the ideal load cell and LVDT).
    source : pathlib.Path, optional
        The file the scenario was read from (for relative paths).
    """

    name: str
    speed_kmh: float
    duration_s: float
    seed: int = 0
    road: RoadConfig = field(default_factory=RoadConfig)
    vehicle: TruckVariant = field(default_factory=TruckVariant)
    actuator: Mapping = field(default_factory=lambda: MappingProxyType({}))
    lead_in_s: float = 2.0
    output_rate_hz: float = 1000.0
    lab: LabChain = field(default_factory=LabChain)
    source: pathlib.Path | None = None

    @property
    def speed_mps(self) -> float:
        """Speed in m/s."""
        return self.speed_kmh / 3.6

    @property
    def profile_path(self) -> pathlib.Path | None:
        """The measured road profile file (``road.profile_csv``, relative to :attr:`source`), or None."""
        if self.road.profile_csv is None:
            return None
        base = self.source.parent if self.source is not None else None
        return pathlib.Path(self.road.profile_csv) if base is None else base / self.road.profile_csv

    @property
    def input_files(self) -> tuple[pathlib.Path, ...]:
        """The files this scenario was read from: the scenario file and its road profile, if any."""
        return tuple(p for p in (self.source, self.profile_path) if p is not None)


_TOP_KEYS = {"name", "description", "speed_kmh", "duration_s", "seed", "lead_in_s", "output_rate_hz", "road", "vehicle",
             "actuator", "lab"}
_ROAD_KEYS = {f.name for f in dataclasses.fields(RoadConfig)}
_TRACKS = ("identical", "independent", "coherent")


def _check_keys(table: Mapping, valid, where: str) -> None:
    check_keys(table, valid, f"{where}." if where else "", error=ScenarioError)


def _road(table: Any) -> RoadConfig:
    if not isinstance(table, Mapping):
        raise ScenarioError("[road] must be a table")
    _check_keys(table, _ROAD_KEYS, "road")
    given = [k for k in ("roughness", "gd_n0_m3", "profile_csv") if k in table]
    if len(given) != 1:
        raise ScenarioError(
            "road needs exactly one of roughness, gd_n0_m3 or profile_csv"
            + (f", got {', '.join(given)}" if given else "")
        )
    kw: dict[str, Any] = {}
    if "roughness" in table:
        from rigsim.scenarios.core.roads import ISO_CLASSES, ROUGHNESS_WORDS

        r = table["roughness"]
        valid = list(ISO_CLASSES) + list(ROUGHNESS_WORDS)
        if not isinstance(r, str) or (r.upper() not in ISO_CLASSES and r.lower() not in ROUGHNESS_WORDS):
            raise ScenarioError(f"road.roughness must be one of {', '.join(valid)}, got {r!r}")
        kw["roughness"] = r
    if "gd_n0_m3" in table:
        kw["gd_n0_m3"] = _number("road.gd_n0_m3", table["gd_n0_m3"], lo=0, hi=1e-1, lo_open=True)
    if "profile_csv" in table:
        if not isinstance(table["profile_csv"], str):
            raise ScenarioError("road.profile_csv must be a file path string")
        kw["profile_csv"] = table["profile_csv"]
    if "waviness" in table:
        kw["waviness"] = _number("road.waviness", table["waviness"], lo=0.5, hi=5.0)
    if "tracks" in table:
        if table["tracks"] not in _TRACKS:
            raise ScenarioError(f"road.tracks must be one of {', '.join(_TRACKS)}, got {table['tracks']!r}")
        kw["tracks"] = table["tracks"]
    for key, lo, hi in (("n_min_cyc_per_m", 1e-4, 10.0), ("n_max_cyc_per_m", 0.1, 50.0)):
        if key in table:
            kw[key] = _number(f"road.{key}", table[key], lo=lo, hi=hi, lo_open=True)
    if kw.get("n_min_cyc_per_m", 0.01) >= kw.get("n_max_cyc_per_m", 10.0):
        raise ScenarioError("road.n_min_cyc_per_m must be below road.n_max_cyc_per_m; widen the band")
    if "envelope_length_m" in table:
        kw["envelope_length_m"] = _number("road.envelope_length_m", table["envelope_length_m"], lo=0.0, hi=2.0)
    if "cuton_wavelength_m" in table:
        kw["cuton_wavelength_m"] = _number("road.cuton_wavelength_m", table["cuton_wavelength_m"], lo=1.0, hi=1e4)
    return RoadConfig(**kw)


def _dataclass_overrides(table: Any, cls, where: str):
    if not isinstance(table, Mapping):
        raise ScenarioError(f"[{where}] must be a table")
    names = {f.name for f in dataclasses.fields(cls)}
    _check_keys(table, names, where)
    words = cls.word_fields() if hasattr(cls, "word_fields") else {}
    for key, value in table.items():
        if key in words:
            if value not in words[key]:
                choices = " or ".join(f'"{w}"' for w in words[key])
                raise ScenarioError(f"{where}.{key} must be {choices}, got {value!r}")
            continue
        _number(f"{where}.{key}", value)
    return {k: v if k in words else float(v) for k, v in table.items()}


def _actuator_fields():
    try:
        from rigsim.hydraulics.params import ActuatorParams
    except ImportError:  # pragma: no cover - hydraulics is part of this distribution
        return None
    return ActuatorParams


def parse_scenario(doc: Mapping, *, source: pathlib.Path | None = None) -> Scenario:
    """Validate a parsed TOML document into a :class:`Scenario` (see the module docstring)."""
    _check_keys(doc, _TOP_KEYS, "")
    for key in ("name", "speed_kmh", "duration_s"):
        if key not in doc:
            raise ScenarioError(f"missing required key {key}")
    name = doc["name"]
    if not isinstance(name, str) or not name.strip():
        raise ScenarioError("name must be a non-empty string")
    kw: dict[str, Any] = {
        "name": name,
        "speed_kmh": _number("speed_kmh", doc["speed_kmh"], lo=0, hi=200, lo_open=True),
        "duration_s": _number("duration_s", doc["duration_s"], lo=0, hi=3600, lo_open=True),
        "source": source,
    }
    if "seed" in doc:
        seed = doc["seed"]
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ScenarioError(f"seed must be a non-negative integer, got {seed!r}")
        kw["seed"] = seed
    if "lead_in_s" in doc:
        kw["lead_in_s"] = _number("lead_in_s", doc["lead_in_s"], lo=0.5, hi=60)
    if "output_rate_hz" in doc:
        kw["output_rate_hz"] = _number("output_rate_hz", doc["output_rate_hz"], lo=1000, hi=1e5)
    if "road" not in doc:
        raise ScenarioError("missing [road] table (give roughness, gd_n0_m3 or profile_csv)")
    kw["road"] = _road(doc["road"])
    if "vehicle" in doc:
        try:
            kw["vehicle"] = TruckVariant(**_dataclass_overrides(doc["vehicle"], TruckVariant, "vehicle"))
            from rigsim.mjcf.description import described

            if described(kw["vehicle"]):  # a truck of its own: refused here if it cannot stand on the rig
                from rigsim.mjcf.standing import check_stands

                check_stands(kw["vehicle"])
        except ValueError as exc:
            raise ScenarioError(str(exc)) from None
    if "actuator" in doc:
        params_cls = _actuator_fields()
        overrides = _dataclass_overrides(doc["actuator"], params_cls, "actuator")
        try:
            params_cls(**overrides)  # validate now, before anything runs
        except (TypeError, ValueError) as exc:
            raise ScenarioError(str(exc)) from None
        kw["actuator"] = MappingProxyType(overrides)
    if "lab" in doc:
        try:
            lab = LabChain(**_dataclass_overrides(doc["lab"], LabChain, "lab"))
            lab.check_rate(kw.get("output_rate_hz", 1000.0))
        except ValueError as exc:
            raise ScenarioError(str(exc)) from None
        kw["lab"] = lab
    return Scenario(**kw)


def load_scenario(path) -> Scenario:
    """Read and validate a scenario TOML file.

    Raises
    ------
    ScenarioError
        Missing file, malformed TOML, unknown key, wrong type or value; one sentence.
    """
    p = pathlib.Path(path)
    doc = read_toml(p, "scenario file", error=ScenarioError)
    try:
        return parse_scenario(doc, source=p.resolve())
    except ScenarioError as exc:
        raise ScenarioError(f"{p.name}: {exc}") from None


#: The configurations of the paper's cases: folder of ``scenarios/data`` by name. ``design``: the
#: project's default actuator gains, the ISO class of each roughness word and the XML's leaf
#: friction; ``dyntrac``: the rig's loop gains, the roads and the leaf friction fitted to the
#: paper's Table 2 (``benchmarks/dyntrac_fit.py``).
PAPER_CONFIGURATIONS = MappingProxyType({"design": "paper", "dyntrac": "paper_dyntrac"})


def paper_scenarios(configuration: str = "design") -> list[pathlib.Path]:
    """The shipped scenario files of the paper's three cases (Table 2 order).

    Parameters
    ----------
    configuration : str
        A key of :data:`PAPER_CONFIGURATIONS`: ``"design"`` (default) or ``"dyntrac"``.
    """
    import importlib.resources

    if configuration not in PAPER_CONFIGURATIONS:
        raise ScenarioError(f"the paper's configuration must be one of {sorted(PAPER_CONFIGURATIONS)}, "
                            f"got {configuration!r}")
    base = importlib.resources.files("rigsim.scenarios").joinpath("data", PAPER_CONFIGURATIONS[configuration])
    names = ("medium_72kmh_6360kg.toml", "high_48kmh_3640kg.toml", "high_72kmh_3640kg.toml")
    return [pathlib.Path(str(base.joinpath(n))) for n in names]
