"""Generated inputs at the file boundaries that are not measured data (hypothesis): scenario
documents, sweep grids, actuator files. Valid ones parse (and the actuator tables round-trip
through the writer); invalid ones raise the project's one error type with one sentence, never
another exception. The references: the parsers' own contracts (the error types documented in
their docstrings) and, for the round trip, the written file read back.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from rigsim.correction.io.actuator_file import (ActuatorFileError, parse_actuator, read_actuators_file,  # noqa: E402
                                      write_actuators_file)
from rigsim.mjcf.names import CORNERS  # noqa: E402
from rigsim.scenarios.core.config import ScenarioError, parse_scenario  # noqa: E402
from rigsim.scenarios.studies.sweep.grid import parse_grid  # noqa: E402

SETTINGS = settings(max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

BASE = {"name": "p", "speed_kmh": 72.0, "duration_s": 20.0, "seed": 1, "road": {"roughness": "high"},
        "vehicle": {"payload_kg": 3640.0}}
TOP_KEYS = ["name", "description", "speed_kmh", "duration_s", "seed", "lead_in_s", "output_rate_hz", "speed"]
ROAD_KEYS = ["roughness", "tracks", "cuton_wavelength_m", "envelope_length_m", "waviness", "gd_n0_m3", "profile_csv"]
VEHICLE_KEYS = ["payload_kg", "timestep_s", "tire_stiffness_front_N_per_m", "pan_mass_kg", "spring_friction_rear_N"]
ACTUATOR_KEYS = ["rated_flow_m3_s", "supply_pressure_Pa", "kp_per_m", "spool_hz", "stroke_m", "nonsense"]

#: Any TOML-ish value, including the awkward ones.
ANY = st.one_of(st.none(), st.booleans(), st.integers(-10**12, 10**12),
                st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
                st.lists(st.floats(-1e3, 1e3), max_size=3), st.dictionaries(st.text(max_size=5), st.integers(), max_size=2))


def _one_sentence(exc: BaseException) -> None:
    text = str(exc)
    assert text and "\n" not in text and "Traceback" not in text, text


@st.composite
def scenario_docs(draw):
    doc = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BASE.items()}
    for _ in range(draw(st.integers(1, 4))):
        where = draw(st.sampled_from(["top", "road", "vehicle", "actuator"]))
        if where == "top":
            doc[draw(st.sampled_from(TOP_KEYS))] = draw(ANY)
        else:
            keys = {"road": ROAD_KEYS, "vehicle": VEHICLE_KEYS, "actuator": ACTUATOR_KEYS}[where]
            table = doc.setdefault(where, {})
            if isinstance(table, dict):
                table[draw(st.sampled_from(keys))] = draw(ANY)
    return doc


@SETTINGS
@given(scenario_docs())
def test_a_scenario_document_parses_or_raises_one_sentence(doc):
    try:
        s = parse_scenario(doc)
    except ScenarioError as exc:
        _one_sentence(exc)
        return
    assert s.duration_s > 0 and math.isfinite(s.speed_mps) and s.speed_mps > 0


@SETTINGS
@given(st.dictionaries(st.sampled_from(["speed_kmh", "seed", "duration_s", "payload_kg", "vehicle.payload_kg",
                                        "road.roughness", "bogus"]),
                       st.lists(ANY, min_size=0, max_size=3), max_size=2),
       st.one_of(st.none(), st.sampled_from(["eq4", "identified", "magic"])))
def test_a_sweep_grid_parses_or_raises_one_sentence(axes, actuator):
    doc = {"sweep": {"name": "g", **({} if actuator is None else {"actuator": actuator})},
           "base": {k: (dict(v) if isinstance(v, dict) else v) for k, v in BASE.items()}, "axes": axes}
    try:
        grid = parse_grid(doc)
    except ScenarioError as exc:
        _one_sentence(exc)
        return
    assert len(grid.cases) >= 1


COEFF = st.lists(st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False), min_size=1, max_size=5)


@SETTINGS
@given(st.one_of(
    st.fixed_dictionaries({"transfer_function": st.fixed_dictionaries({"num": COEFF, "den": COEFF})}),
    st.dictionaries(st.sampled_from(["transfer_function", "parameters", "meta", "x"]),
                    st.one_of(ANY, st.dictionaries(st.sampled_from(["num", "den", "valve_gain", "zz"]), ANY,
                                                   max_size=3)), max_size=2)))
def test_an_actuator_table_parses_or_raises_one_sentence(data):
    try:
        num, den = parse_actuator(data)
    except ActuatorFileError as exc:
        _one_sentence(exc)
        return
    assert num.size >= 1 and den.size >= 1 and np.all(np.isfinite(num)) and np.all(np.isfinite(den))


@SETTINGS
@given(st.lists(st.tuples(COEFF, COEFF), min_size=4, max_size=4))
def test_actuators_files_round_trip_or_refuse(tmp_path_factory, pairs):
    """Every corner's (num, den) written and read back equal, or refused by the writer's own
    check (one sentence, nothing written): the writer never writes what the reader refuses (a zero
    denominator, say, which read_actuators_file rejects)."""
    path = tmp_path_factory.mktemp("act") / "actuators.toml"
    actuators = {c: (np.array(n), np.array(d)) for c, (n, d) in zip(CORNERS, pairs)}
    try:
        write_actuators_file(path, actuators)
    except (ActuatorFileError, ValueError) as exc:
        _one_sentence(exc)
        assert not path.exists()
        return
    back = read_actuators_file(path)
    for c in CORNERS:
        for a, b in zip(actuators[c], back[c]):
            np.testing.assert_allclose(np.trim_zeros(a, "f"), np.trim_zeros(b, "f"), rtol=1e-15, atol=0)
