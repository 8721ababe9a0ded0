"""``rigsim paper`` does each piece of work once: each force's rainflow cycles are counted once
(the scoring's DELs and the report's histograms share them), the report's figures are drawn from
small data that can go to any worker, paper.json's rows are worked out once, and a case job is
sent the tire forces only.

References: the rainflow counter against ``rainflow.extract_cycles`` (ASTM E1049-85, the
reference of tests/correction/metrics/test_rainflow_fast.py); the DELs and figures against the
same quantities computed the straightforward way (counting again, drawing from the case).
"""

from __future__ import annotations

import dataclasses
import pathlib
import pickle
from types import SimpleNamespace

import numpy as np
import pytest

from rigsim.correction.metrics import rainflow_damage
from rigsim.correction.metrics.damage import (
    damage_equivalent_load,
    damage_metrics,
    pseudo_damage,
    rainflow_cycles,
)
from rigsim.hydraulics.params import ActuatorParams
from rigsim.scenarios.core.config import paper_scenarios
from rigsim.scenarios.core.results import RunResult
from rigsim.scenarios.studies.paper import compute, report
from rigsim.scenarios.studies.scoring import METHODS, score_pair

FS = 1000.0  # Hz
SECONDS = 12.0


def _forces(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Road and rig wheel forces, N, (n, 4): two tones and broadband load, the rig's lagging."""
    t = np.arange(int(SECONDS * FS)) / FS
    rng = np.random.default_rng(seed)
    phase = np.arange(4)[None, :]
    road = 40e3 + 3e3 * np.sin(2 * np.pi * 1.7 * t[:, None] + phase) + 1.2e3 * np.sin(2 * np.pi * 11.0 * t[:, None])
    road = road + 400.0 * rng.standard_normal(road.shape)
    rig = (40e3 + 2.4e3 * np.sin(2 * np.pi * 1.7 * t[:, None] + phase - 0.2)
           + 0.5e3 * np.sin(2 * np.pi * 11.0 * t[:, None]))
    return t, road, rig + 1e3 * np.arange(4)[None, :]


def _runs(extra_signals: bool = False) -> tuple[RunResult, RunResult]:
    t, road, rig = _forces()
    extra = {"pan_m": np.zeros_like(road), "p1_Pa": np.full_like(road, 1e7)} if extra_signals else {}

    def make(mode, f):
        return RunResult(scenario_name="synthetic", mode=mode, t_s=t, signals={"tire_force_N": f, **extra},
                         vehicle_mass_kg=0.0)

    return make("road", road), make("rig", rig)


def _actuators():
    out = []
    for hz in (12.0, 15.0, 18.0, 21.0):
        wn = 2 * np.pi * hz
        out.append((np.array([wn * wn]), np.array([1.0, 2 * 0.7 * wn, wn * wn])))
    return out


def _rig_model():
    return SimpleNamespace(params=ActuatorParams(), pan_mass_kg=480.0,
                           tire_stiffness_N_per_m=np.array([0.9e6, 1.1e6, 1.4e6, 1.8e6]))


@pytest.fixture(scope="module")
def case():
    road, rig = _runs()
    score = score_pair(road, rig, _rig_model(), identified=_actuators(), noise_N=100.0, seed=3)
    return compute.PaperCase(scenario=SimpleNamespace(name="synthetic", speed_mps=20.0), road=road, rig=rig,
                             identification=None, score=score)


@pytest.fixture()
def count_rainflow(monkeypatch):
    """The number of 1-D rainflow counts so far (every count goes through ``_cycles_1d``)."""
    calls = [0]
    original = rainflow_damage._cycles_1d

    def counting(f):
        calls[0] += 1
        return original(f)

    monkeypatch.setattr(rainflow_damage, "_cycles_1d", counting)
    return lambda: calls[0]


def test_a_case_counts_each_forces_rainflow_once_per_wheel(count_rainflow):
    road, rig = _runs()
    score = score_pair(road, rig, _rig_model(), identified=_actuators(), noise_N=100.0, seed=3)
    # per method: the road, measured rig and corrected force on its settled samples, 4 wheels each
    assert count_rainflow() == len(METHODS) * 3 * 4
    case = compute.PaperCase(scenario=SimpleNamespace(name="synthetic"), road=road, rig=rig, identification=None,
                             score=score)
    report.case_figure_data(case)  # the damage figure's histograms read the scoring's cycles
    assert count_rainflow() == len(METHODS) * 3 * 4


def test_the_shared_cycles_are_the_counters_and_give_the_same_dels(case):
    best = case.score.methods["best"]
    s = best.settled
    forces = {"road": case.score.road_N[s], "rig": case.score.rig_N[s], "corrected": best.corrected_N[s]}
    rainflow = pytest.importorskip("rainflow")
    for name, f in forces.items():
        for i, (ranges, means, counts) in enumerate(best.cycles[name]):
            ref = [(r, m, c) for r, m, c, _i, _j in rainflow.extract_cycles(list(f[:, i])) if r > 0]
            assert np.array_equal(ranges, [r for r, _m, _c in ref])  # exact, in the library's order
            assert np.array_equal(means, [m for _r, m, _c in ref]) and np.array_equal(counts, [c for *_x, c in ref])
        seconds = f.shape[0] / FS
        recounted = damage_equivalent_load(f, 5, duration_s=seconds)
        assert np.array_equal(best.figures[f"del_{name}_N"], recounted), name  # the same floats
        assert np.array_equal(damage_equivalent_load(f, 5, duration_s=seconds, cycles=best.cycles[name]), recounted)


def test_damage_metrics_count_once_for_every_exponent(count_rainflow):
    _t, road, _rig = _forces()
    metrics = damage_metrics(road, FS, exponents=(3, 5, 10))
    assert count_rainflow() == 4
    for m in (3, 5, 10):
        assert np.array_equal(metrics.del_m(m), damage_equivalent_load(road, m, duration_s=SECONDS))
        assert np.array_equal(metrics.pseudo_damage_m(m), pseudo_damage(road, m))


def test_cycles_of_another_force_are_refused():
    _t, road, rig = _forces()
    with pytest.raises(ValueError, match="columns"):
        pseudo_damage(road, 5, cycles=rainflow_cycles(rig[:, :3]))


def test_a_pickled_score_leaves_the_cycles_behind_and_the_figures_count_them(case, count_rainflow):
    copied = pickle.loads(pickle.dumps(case.score))
    assert copied.methods["best"].cycles is None and case.score.methods["best"].cycles is not None
    moved = dataclasses.replace(case, score=copied)
    assert _same_data(report.case_figure_data(moved), report.case_figure_data(case))
    assert count_rainflow() == 3 * 4  # counted again, only there


def _same_data(a, b) -> bool:
    """Equal nested figure data (arrays compared exactly)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same_data(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same_data(x, y) for x, y in zip(a, b))
    return a == b


def _figures_straight(case) -> dict[str, bytes]:
    """The case's two figures drawn from the case directly, as the report drew them before it
    prepared their data apart: the same numpy calls on the score's forces (reference)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator

    ev, best = case.score, case.score.methods["best"]
    t, settled = ev.t_s, np.flatnonzero(ev.settled)
    start = settled[0] + (settled[-1] - settled[0]) // 3
    sl = slice(start, min(start + int(round(3.0 / (t[1] - t[0]))), settled[-1]))
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for ax, i, label in zip(axes, (0, 2), ("front left (fl)", "rear left (rl)")):
        ax.plot(t[sl], ev.road_lowpassed_N["best"][sl, i] * 1e-3, color="k", lw=1.6, label="road (30 Hz low-pass)")
        ax.plot(t[sl], ev.rig_N[sl, i] * 1e-3, color="tab:red", lw=1.0, label="rig, measured")
        ax.plot(t[sl], ev.corrected_N["paper"][sl, i] * 1e-3, color="tab:orange", lw=1.0, ls="--",
                label="corrected, paper's method")
        ax.plot(t[sl], ev.corrected_N["best"][sl, i] * 1e-3, color="tab:blue", lw=1.2,
                label="corrected, this project")
        ax.set_ylabel("tire force, kN")
        ax.set_title(label, loc="left", fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].legend(ncol=2, fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time, s")
    fig.suptitle(f"{case.name}: measured and corrected tire forces (Figure 8 analogue)", fontsize=11)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.08, top=0.92, hspace=0.15)
    out = {f"figure8_{case.name}.png": report._png(fig, tight=False)}
    plt.close(fig)

    s = best.settled
    forces = {"road": ev.road_N[s], "rig, measured": ev.rig_N[s], "corrected": best.corrected_N[s]}
    colors = {"road": "k", "rig, measured": "tab:red", "corrected": "tab:blue"}
    fig, axes = plt.subplots(2, 4, figsize=(13, 6.2))
    for i, corner in enumerate(ev.corners):
        static = float(np.mean(forces["road"][:, i]))
        bins = None
        for label, f in forces.items():
            x = np.sort(f[:, i] / static)[::-1]
            rank = np.unique(np.geomspace(1, x.size, 500).astype(int))
            axes[0, i].semilogy(x[rank - 1], rank / x.size, color=colors[label], lw=1.2, label=label)
            ranges, _, counts = rainflow_cycles(f[:, i])
            if bins is None:
                bins = np.linspace(0.0, float(np.max(ranges)) * 1.05 / 1e3, 30)
            h, _ = np.histogram(np.asarray(ranges) / 1e3, bins=bins, weights=counts)
            axes[1, i].step(bins[:-1], np.maximum(h, 0.5), where="post", color=colors[label], lw=1.1)
        axes[0, i].set_title(corner, loc="left", fontsize=10)
        axes[0, i].set_xlabel("F / F_static")
        axes[1, i].set_yscale("log")
        axes[1, i].set_xlabel("rainflow range, kN")
        for ax in axes[:, i]:
            ax.yaxis.set_minor_locator(LogLocator(subs=(2.0, 5.0)))
            ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel("exceedance probability")
    axes[1, 0].set_ylabel("cycles per bin")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"{case.name}: load exceedance and rainflow cycles (ASTM E1049-85)", fontsize=11)
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.09, top=0.91, wspace=0.28, hspace=0.38)
    out[f"damage_{case.name}.png"] = report._png(fig, tight=False)
    plt.close(fig)
    return out


def test_figures_drawn_from_their_data_in_another_process_are_the_figures_of_the_case(case, tmp_path):
    expected = _figures_straight(case)
    assert report.case_figures(case) == expected  # byte for byte
    jobs = pickle.loads(pickle.dumps(report.case_figure_jobs(case, tmp_path)))  # as a worker receives them
    assert [args[1] for _fn, args in jobs] == [f"damage_{case.name}.png", f"figure8_{case.name}.png"]  # longest first
    assert sum(len(pickle.dumps(args)) for _fn, args in jobs) < 0.1 * len(pickle.dumps(case.score))
    for fn, args in jobs:
        fn(*args)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == expected


def test_paper_rows_are_worked_out_once_and_handed_out_as_copies():
    calls = []

    class Case:
        def row(self):
            calls.append(1)
            return {"case": "c", "wheels": {"fl": {"dlc_road": 0.1}}}

    result = compute.PaperResult(cases=(Case(), Case()), noise_N=100.0)
    first = result.rows()
    first[0]["wheels"]["fl"]["dlc_road"] = -1.0
    assert result.rows() == [{"case": "c", "wheels": {"fl": {"dlc_road": 0.1}}}] * 2
    assert len(calls) == 2
    assert len(dataclasses.replace(result, noise_N=0.0).rows()) == 2 and len(calls) == 4  # a new result: its own rows


# --- run_paper's jobs, the physics stood in (module level: the pool's workers are forked from here)
@dataclasses.dataclass(frozen=True)
class _Identified:
    def actuators(self):
        return _actuators()


def _fake_identify_job(path, duration_s=None, truck=None):
    return _Identified()


def _fake_run_job(path, mode, duration_s=None, pose_rate_hz=None, finish_run=None, truck=None):
    road, rig = _runs(extra_signals=True)
    return dataclasses.replace(road if mode == "road" else rig, scenario_name=pathlib.Path(path).stem)


def _seen_case(case, out):
    """A case_jobs stand-in: records what the scoring worker's case holds, as a further job."""
    signals = sorted(case.road.signals) + sorted(case.rig.signals)
    return [(_write_line, (pathlib.Path(out) / f"{case.road.scenario_name}.txt", ",".join(signals)))]


def _write_line(path, text):
    pathlib.Path(path).write_text(text)


def test_run_paper_sends_a_case_job_the_tire_forces_and_runs_the_jobs_it_asks_for(monkeypatch, tmp_path):
    """The case jobs get the time axis and tire forces, the parent keeps the whole runs; the calls
    ``case_jobs`` returns run in the pool; ``on_scored`` gets the result once every case is scored."""
    import functools

    monkeypatch.setattr(compute, "identify_job", _fake_identify_job)
    monkeypatch.setattr(compute, "run_job", _fake_run_job)
    paths = paper_scenarios()[:2]
    scored = []
    result = compute.run_paper(paths, workers=2, case_jobs=functools.partial(_seen_case, out=tmp_path),
                               on_scored=scored.append)
    assert len(scored) == 1 and scored[0] is result  # once every case is scored, the result returned
    for p, case in zip(paths, result.cases):
        # the follow-up job ran; the case job had the time axis and the tire forces only
        assert (tmp_path / f"{pathlib.Path(p).stem}.txt").read_text() == "tire_force_N,tire_force_N"
        assert set(case.road.signals) == {"tire_force_N", "pan_m", "p1_Pa"}  # the parent keeps the whole runs
        assert case.score.methods["best"].cycles is None  # left in the worker
        road, rig = _runs()
        expected = score_pair(road, rig, compute.Rig(case.scenario), identified=_actuators(), seed=case.scenario.seed)
        assert case.score.mean == expected.mean
