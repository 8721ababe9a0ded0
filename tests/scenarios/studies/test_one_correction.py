"""One correction for users and studies: ``rigsim identify`` + ``rigsim correct`` on a study's case
give the numbers the studies score (scenarios/studies/scoring.py, correction/output/pipeline.py).

Reference: the study's own corrected forces (score_pair, the paper study's "best" method); the
user's path goes through files only (the run's timeseries.csv, the actuators file written by
``rigsim identify``, the corrected CSV written by ``rigsim correct``), so agreement to the CSV's
printed precision shows that both use the same identification, the same filters and the same
settled samples.
"""

from __future__ import annotations

import csv
import tomllib

import numpy as np
import pytest

from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.cli.main import main
from rigsim.scenarios.core.config import load_scenario
from rigsim.scenarios.core.results import write_run
from rigsim.scenarios.core.rig import Rig
from rigsim.scenarios.core.run import run
from rigsim.scenarios.studies.identify.compute import identify_rig
from rigsim.scenarios.studies.scoring import BEST, score_pair

SCENARIO = """
name = "one-correction"
speed_kmh = 60.0
duration_s = 12.0
seed = 41
[road]
roughness = "C"
tracks = "coherent"
[vehicle]
payload_kg = 5000.0
"""


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    d = tmp_path_factory.mktemp("one")
    path = d / "case.toml"
    path.write_text(SCENARIO)
    s = load_scenario(path)
    road, rig = run(s, "road"), run(s, "rig")
    write_run(rig, d / "rig")
    return d, path, s, road, rig


def _read(path):
    """Header names (without their ' [unit]') and values of the command's CSV, '#' metadata skipped."""
    with open(path, newline="") as fh:
        rows = [r for r in csv.reader(fh) if not r[0].startswith("#")]
    return [h.split(" [")[0] for h in rows[0]], np.array(rows[1:], dtype=float)


def test_identify_then_correct_gives_the_studys_corrected_forces(case, capsys):
    d, path, s, road, rig = case
    assert main(["identify", str(path), "--out", str(d / "ident"), "--quiet"]) == 0
    files = tomllib.loads((d / "ident" / "actuators.toml").read_text())
    ident = identify_rig(s)  # what the studies identify (deterministic: same drive, same seed)
    for c, (num, den) in zip(CORNERS, ident.actuators()):
        np.testing.assert_allclose(files[c]["num"], num, rtol=1e-12)
        np.testing.assert_allclose(files[c]["den"], den, rtol=1e-12)

    cols = ",".join(f"tire_force_{c}_N" for c in CORNERS)
    out = d / "corrected.csv"
    assert main(["correct", str(d / "rig" / "timeseries.csv"), "--actuators", str(d / "ident" / "actuators.toml"),
                 "--columns", cols, "-o", str(out), "--lowpass", "regularized", "--mode", "zerophase",
                 "--transient", "mark"]) == 0
    header, data = _read(out)
    assert header == ["time"] + [f"tire_force_{c}_N_corrected" for c in CORNERS] + ["settled"]

    study = score_pair(road, rig, Rig(s), methods=(BEST,), identified=ident.actuators(), noise_N=0.0, seed=s.seed)
    best = study.methods["best"]
    # The same samples are settled, the same forces come out (the CSV prints 10 significant digits).
    assert np.array_equal(data[:, -1].astype(bool), best.settled)
    np.testing.assert_allclose(data[:, 1:5], best.corrected_N, rtol=2e-9, atol=1e-6)
    # The command's DLC table is the study's corrected DLC.
    printed = capsys.readouterr().out
    for c, v in zip(CORNERS, best.figures["dlc_corrected"]):
        assert f"{v:.4f}" in printed.split(f"tire_force_{c}_N")[1].splitlines()[0]


def test_paper_method_through_the_command_matches_the_study(case, tmp_path):
    """eq. 4 with the paper's low-pass, causal: the study's T_a written as an actuators file and
    applied by ``rigsim correct`` give the study's corrected forces."""
    from rigsim.correction.io.actuator_file import write_actuators_file
    from rigsim.scenarios.studies.scoring import PAPER

    d, _, s, road, rig = case
    study = score_pair(road, rig, Rig(s), methods=(PAPER,), noise_N=0.0, seed=s.seed)
    paper = study.methods["paper"]
    write_actuators_file(tmp_path / "eq4.toml", dict(zip(CORNERS, paper.actuators)))
    out = tmp_path / "corrected.csv"
    cols = ",".join(f"tire_force_{c}_N" for c in CORNERS)
    assert main(["correct", str(d / "rig" / "timeseries.csv"), "--actuators", str(tmp_path / "eq4.toml"),
                 "--columns", cols, "-o", str(out), "--lowpass", "paper", "--mode", "causal",
                 "--transient", "keep"]) == 0
    _, data = _read(out)
    np.testing.assert_allclose(data[:, 1:5], paper.corrected_N, rtol=2e-9, atol=1e-6)
