"""The bad-input matrix: every subcommand refuses bad input before any work.

One parametrized test over (argv, id) cases across all eight subcommands: bad numbers (negative,
zero, NaN, infinite, huge, not a number), bad paths (empty, a folder for a file, a file for a
folder, under a file, a previous result without --force, the input as output), missing and
malformed files (scenario, grid, actuator, measured files, written into tmp_path), bad choices,
options that do not go together, bad channel names for ``rigsim correct`` and ``--pairs`` for
``rigsim identify``. Each case must: return 2 from :func:`rigsim.scenarios.cli.main.main` (argparse's own
``SystemExit(2)`` counts), print exactly one line on stderr (argparse: its usage lines and one
``error:`` line), no traceback, and leave the folder of inputs and outputs exactly as it was.

"Before any work" is enforced, not hoped for: the simulation (:meth:`Rig.run`), the studies' job
pools and the validation, the sweep's runner, process pools and the actuator fit are replaced by
functions that fail the test if called. ``rigsim correct`` checks T_a (stable, minimum phase,
proper) and the record's length against the filters' transients where it designs the filters,
in memory; those cases are held to writing nothing.
"""

from __future__ import annotations

import hashlib
import pathlib

import numpy as np
import pytest

from rigsim.scenarios.cli.main import main

# --------------------------------------------------------------------------------- input files
GOOD = 'name = "m"\nspeed_kmh = 72.0\nduration_s = 12.0\nseed = 5\n[road]\nroughness = "high"\n'


def _edit(old: str, new: str) -> str:
    assert old in GOOD, old
    return GOOD.replace(old, new)


#: Scenario files, each bad in one way (a key, a type, a range, the TOML itself).
SCENARIOS = {
    "syntax": 'name = "m"\nspeed_kmh = \n',
    "unclosed_string": 'name = "m\nspeed_kmh = 72.0\n',
    "duplicate_key": "speed_kmh = 50.0\n" + GOOD,
    "empty": "",
    "binary": "\x00\x01\x02\xff",
    "unknown_key": GOOD.replace("seed = 5", "seed = 5\nspeedkmh = 72.0"),
    "no_name": _edit('name = "m"\n', ""),
    "no_speed": _edit("speed_kmh = 72.0\n", ""),
    "no_duration": _edit("duration_s = 12.0\n", ""),
    "no_road": GOOD.split("[road]")[0],
    "name_empty": _edit('name = "m"', 'name = " "'),
    "name_number": _edit('name = "m"', "name = 5"),
    "speed_negative": _edit("speed_kmh = 72.0", "speed_kmh = -10.0"),
    "speed_zero": _edit("speed_kmh = 72.0", "speed_kmh = 0.0"),
    "speed_nan": _edit("speed_kmh = 72.0", "speed_kmh = nan"),
    "speed_inf": _edit("speed_kmh = 72.0", "speed_kmh = inf"),
    "speed_huge": _edit("speed_kmh = 72.0", "speed_kmh = 1e9"),
    "speed_text": _edit("speed_kmh = 72.0", 'speed_kmh = "fast"'),
    "speed_list": _edit("speed_kmh = 72.0", "speed_kmh = [72.0]"),
    "duration_negative": _edit("duration_s = 12.0", "duration_s = -1.0"),
    "duration_zero": _edit("duration_s = 12.0", "duration_s = 0"),
    "duration_nan": _edit("duration_s = 12.0", "duration_s = nan"),
    "duration_inf": _edit("duration_s = 12.0", "duration_s = inf"),
    "duration_huge": _edit("duration_s = 12.0", "duration_s = 1e6"),
    "duration_tiny": _edit("duration_s = 12.0", "duration_s = 1e-4"),  # not one output sample at 1 kHz
    "seed_negative": _edit("seed = 5", "seed = -1"),
    "seed_float": _edit("seed = 5", "seed = 1.5"),
    "seed_bool": _edit("seed = 5", "seed = true"),
    "lead_in_short": _edit("seed = 5", "seed = 5\nlead_in_s = 0.1"),
    "lead_in_nan": _edit("seed = 5", "seed = 5\nlead_in_s = nan"),
    "output_rate_low": _edit("seed = 5", "seed = 5\noutput_rate_hz = 10.0"),
    "roughness_unknown": _edit('roughness = "high"', 'roughness = "Z"'),
    "roughness_number": _edit('roughness = "high"', "roughness = 3"),
    "road_two_choices": _edit('roughness = "high"', 'roughness = "high"\ngd_n0_m3 = 1e-5'),
    "road_no_choice": _edit('roughness = "high"', 'tracks = "independent"'),
    "road_unknown_key": _edit('roughness = "high"', 'roughness = "high"\nroughnes = "A"'),
    "road_not_a_table": GOOD.split("[road]")[0] + 'road = "high"\n',
    "gd_negative": _edit('roughness = "high"', "gd_n0_m3 = -1e-5"),
    "waviness_huge": _edit('roughness = "high"', 'roughness = "high"\nwaviness = 100.0'),
    "tracks_unknown": _edit('roughness = "high"', 'roughness = "high"\ntracks = "sideways"'),
    "band_inverted": _edit('roughness = "high"', 'roughness = "high"\nn_min_cyc_per_m = 5.0\nn_max_cyc_per_m = 1.0'),
    "cuton_zero": _edit('roughness = "high"', 'roughness = "high"\ncuton_wavelength_m = 0.0'),
    "profile_missing": _edit('roughness = "high"', 'profile_csv = "no_such_profile.csv"'),
    "payload_huge": GOOD + "[vehicle]\npayload_kg = 1e9\n",
    "payload_negative": GOOD + "[vehicle]\npayload_kg = -5.0\n",
    "payload_nan": GOOD + "[vehicle]\npayload_kg = nan\n",
    "payload_text": GOOD + '[vehicle]\npayload_kg = "heavy"\n',
    "tire_soft": GOOD + "[vehicle]\ntire_stiffness_front_N_per_m = 1.0\n",
    "timestep_tiny": GOOD + "[vehicle]\ntimestep_s = 1e-9\n",
    "timestep_coarse": GOOD + "[vehicle]\ntimestep_s = 0.1\n",
    "pan_mass_huge": GOOD + "[vehicle]\npan_mass_kg = 1e5\n",
    "vehicle_unknown_key": GOOD + "[vehicle]\npayload = 3640.0\n",
    # a truck of its own (mjcf/description.py, mjcf/standing.py): bad words, ranges, pairs, trucks that cannot stand
    "wheelbase_short": GOOD + "[vehicle]\nwheelbase_m = 2.0\n",
    "suspension_word": GOOD + '[vehicle]\nsuspension_rear = "coil"\n',
    "rear_tires_number": GOOD + "[vehicle]\nrear_tires = 2\n",
    "track_wide": GOOD + "[vehicle]\ntrack_front_m = 3.0\n",
    "truck_lifts": GOOD + "[vehicle]\npayload_kg = 9000.0\npayload_x_m = -3.4\nwheelbase_m = 3.6\n",
    "springs_bottom": GOOD + "[vehicle]\npayload_kg = 14000.0\nspring_rate_rear_N_per_m = 1.5e5\nwheelbase_m = 5.0\n",
    "frame_half": GOOD + "[vehicle]\nframe_torsion_hz = 8.0\n",
    "engine_mass_alone": GOOD + "[vehicle]\nengine_mass_kg = 1000.0\n",
    "no_rest": GOOD + "[vehicle]\npayload_kg = 40000.0\npayload_x_m = -3.5\n",
    "memory": _edit("duration_s = 12.0", "duration_s = 3600.0") + "[vehicle]\ntimestep_s = 1e-6\n",
    "actuator_unknown_key": GOOD + "[actuator]\nsupply_pressure = 21e6\n",
    "actuator_negative": GOOD + "[actuator]\nsupply_pressure_Pa = -1.0\n",
    "actuator_nan": GOOD + "[actuator]\nrated_flow_m3_s = nan\n",
}

GRID_HEAD = '[sweep]\nname = "g"\n[base]\nname = "g"\nspeed_kmh = 72.0\nduration_s = 5.0\n[base.road]\nroughness = "high"\n'

#: Sweep grid files, each bad in one way.
GRIDS = {
    "syntax": "[sweep\nname = 1\n",
    "empty": "",
    "unknown_top": GRID_HEAD + "[axis]\nseed = [1, 2]\n",
    "no_base": '[sweep]\nname = "g"\n[axes]\nseed = [1, 2]\n',
    "base_bad_speed": GRID_HEAD.replace("speed_kmh = 72.0", "speed_kmh = -1.0") + "[axes]\nseed = [1, 2]\n",
    "axis_empty": GRID_HEAD + "[axes]\nseed = []\n",
    "axis_unknown_key": GRID_HEAD + "[axes]\nsped_kmh = [50, 60]\n",
    "axis_bad_value": GRID_HEAD + "[axes]\nspeed_kmh = [50, -60]\n",
    "axis_nan": GRID_HEAD + "[axes]\nspeed_kmh = [50, nan]\n",
    "axis_not_a_list": GRID_HEAD + "[axes]\nspeed_kmh = 50\n",
    "huge": GRID_HEAD + "[axes]\nseed = [%s]\nspeed_kmh = [%s]\n" % (
        ", ".join(map(str, range(200))), ", ".join(str(v) for v in range(10, 70))),
    "lowpass_unknown": GRID_HEAD.replace('name = "g"\n[base]', 'name = "g"\nlowpass = "magic"\n[base]', 1)
    + "[axes]\nseed = [1, 2]\n",
    "noise_negative": GRID_HEAD.replace('name = "g"\n[base]', 'name = "g"\nnoise_N = -5.0\n[base]', 1)
    + "[axes]\nseed = [1, 2]\n",
    "actuator_unknown": GRID_HEAD.replace('name = "g"\n[base]', 'name = "g"\nactuator = "guess"\n[base]', 1)
    + "[axes]\nseed = [1, 2]\n",
    "sweep_unknown_key": GRID_HEAD.replace('name = "g"\n[base]', 'name = "g"\nworkers = 4\n[base]', 1)
    + "[axes]\nseed = [1, 2]\n",
    # shorter than the band limit's own transients plus MIN_SCORED_S (scoring.shortest_scorable_s)
    "duration_unscorable": GRID_HEAD.replace("duration_s = 5.0", "duration_s = 0.0001") + "[axes]\nseed = [1, 2]\n",
    "axis_duration_unscorable": GRID_HEAD + "[axes]\nduration_s = [5.0, 0.3]\n",
}

#: Actuator files (``rigsim correct --actuator``), each bad in one way.
ACTUATORS = {
    "syntax": "[transfer_function\nnum = [1.0]\n",
    "empty": "",
    "unknown_table": "[transfer]\nnum = [1.0]\nden = [1.0, 1.0]\n",
    "no_den": "[transfer_function]\nnum = [1.0]\n",
    "den_zero": "[transfer_function]\nnum = [1.0]\nden = [0.0, 0.0]\n",
    "unstable": "[transfer_function]\nnum = [1.0]\nden = [2.5e-4, -0.02, 1.0]\n",
    "nan": "[transfer_function]\nnum = [nan]\nden = [2.5e-4, 0.02, 1.0]\n",
    "text": '[transfer_function]\nnum = ["one"]\nden = [2.5e-4, 0.02, 1.0]\n',
    "non_minimum_phase": "[transfer_function]\nnum = [-0.01, 1.0]\nden = [2.5e-4, 0.02, 1.0]\n",
    "dc_gain_not_one": "[transfer_function]\nnum = [2.0]\nden = [2.5e-4, 0.02, 1.0]\n",
    "eq4_incomplete": "[parameters]\nmass_kg = -1.0\n",
}
GOOD_ACTUATOR = "[transfer_function]\nnum = [1.0]\nden = [2.5e-4, 0.02, 1.0]\n"
GOOD_ACTUATORS = "".join(f"[{c}]\nnum = [1.0]\nden = [2.5e-4, 0.02, 1.0]\n" for c in ("fl", "fr"))


def _measured_csv(path: pathlib.Path, n: int = 4000, fs: float = 1000.0, jitter: bool = False) -> None:
    """time [s], two wheel forces [N], a drive and a pan displacement [m] (4 s at 1 kHz)."""
    rng = np.random.default_rng(1)
    t = np.arange(n) / fs
    if jitter:
        t[n // 2:] += 0.37e-3  # a jump in the time axis: not uniform
    drive = 0.005 * rng.standard_normal(n)
    cols = [t, 30e3 + 1e3 * rng.standard_normal(n), 28e3 + 1e3 * rng.standard_normal(n), drive, 0.9 * drive]
    lines = ["time [s],fl_N [N],fr_N [N],drive_m [m],pan_m [m]"]
    lines += [",".join(f"{v:.9g}" for v in row) for row in zip(*cols)]
    path.write_text("\n".join(lines) + "\n")


def _inputs(d: pathlib.Path) -> None:
    d.mkdir()
    (d / "good.toml").write_text(GOOD)
    (d / "short.toml").write_text(_edit("duration_s = 12.0", "duration_s = 2.0"))
    for name, text in SCENARIOS.items():
        (d / f"s_{name}.toml").write_text(text)
    for name, text in GRIDS.items():
        (d / f"g_{name}.toml").write_text(text)
    for name, text in ACTUATORS.items():
        (d / f"a_{name}.toml").write_text(text)
    (d / "grid.toml").write_text(GRID_HEAD + "[axes]\nseed = [1, 2]\n")
    (d / "act.toml").write_text(GOOD_ACTUATOR)
    (d / "acts.toml").write_text(GOOD_ACTUATORS)
    _measured_csv(d / "rig.csv")
    _measured_csv(d / "jitter.csv", jitter=True)
    _measured_csv(d / "tiny.csv", n=40)  # 40 ms: shorter than the correction's transients
    (d / "empty.csv").write_text("")
    (d / "words.csv").write_text("time,force\nabc,def\nghi,jkl\n")
    (d / "one_row.csv").write_text("time [s],fl_N [N]\n0.0,30000\n")
    (d / "constant.csv").write_text("time [s],fl_N [N],drive_m [m],pan_m [m]\n"
                                    + "".join(f"{i / 1000:.3f},30000,0.0,0.0\n" for i in range(3000)))
    (d / "existing.csv").write_text("time [s],x_N [N]\n0,1\n")
    (d / "file.txt").write_text("not a folder\n")
    (d / "folder").mkdir()
    (d / "prev").mkdir()
    (d / "prev" / "result.json").write_text('{"previous": true}\n')
    (d / "old.rrd").write_bytes(b"an older recording")


# ----------------------------------------------------------------------------------- the cases
CASES: list = []


def _add(cmd: str, kind: str, what: str, *argv: str) -> None:
    CASES.append(pytest.param(cmd, kind, list(argv), id=f"{cmd}-{kind}-{what}"))


S, O = "{d}", "{out}"  # the inputs folder and the output path, filled in per case

# rigsim run: every bad scenario file, then the options
for _name in SCENARIOS:
    _add("run", "scenario file", _name, "run", f"{S}/s_{_name}.toml", "--out", O, "--quiet")
_add("run", "scenario file", "no_rest_rig_mode", "run", f"{S}/s_no_rest.toml", "--mode", "rig", "--out", O, "--quiet")
_add("run", "scenario file", "memory_rig_mode", "run", f"{S}/s_memory.toml", "--mode", "rig", "--out", O, "--quiet")
_add("run", "missing file", "scenario", "run", f"{S}/nothing.toml", "--out", O)
_add("run", "bad path", "scenario_is_folder", "run", f"{S}/folder", "--out", O)
_add("run", "bad path", "scenario_empty", "run", "", "--out", O)
for _v in ("-1", "0", "nan", "inf", "-inf", "1e9", "abc", "1e-400", "1e-4"):
    _add("run", "bad number", f"duration_{_v}", "run", f"{S}/good.toml", "--out", O, "--duration-s", _v)
_add("run", "bad choice", "mode", "run", f"{S}/good.toml", "--mode", "flying", "--out", O)
_add("run", "bad path", "out_empty", "run", f"{S}/good.toml", "--out", "")
_add("run", "bad path", "out_blank", "run", f"{S}/good.toml", "--out", "  ")
_add("run", "bad path", "out_is_file", "run", f"{S}/good.toml", "--out", f"{S}/file.txt")
_add("run", "bad path", "out_under_file", "run", f"{S}/good.toml", "--out", f"{S}/file.txt/out")
_add("run", "bad path", "out_previous_result", "run", f"{S}/good.toml", "--out", f"{S}/prev")
_add("run", "bad path", "out_root", "run", f"{S}/good.toml", "--out", "/")
_add("run", "bad path", "rrd_empty", "run", f"{S}/good.toml", "--out", O, "--rrd", "")
_add("run", "bad path", "rrd_folder", "run", f"{S}/good.toml", "--out", O, "--rrd", f"{S}/folder")
_add("run", "bad path", "rrd_exists", "run", f"{S}/good.toml", "--out", O, "--rrd", f"{S}/old.rrd")
_add("run", "bad path", "rrd_is_out", "run", f"{S}/good.toml", "--out", O, "--rrd", O)
_add("run", "bad path", "rrd_under_file", "run", f"{S}/good.toml", "--out", O, "--rrd", f"{S}/file.txt/r.rrd")
_add("run", "options", "view_without_rrd", "run", f"{S}/good.toml", "--out", O, "--view")
_add("run", "options", "no_out", "run", f"{S}/good.toml")
_add("run", "options", "no_scenario", "run", "--out", O)
_add("run", "options", "unknown_option", "run", f"{S}/good.toml", "--out", O, "--speed", "5")

# rigsim model
for _v in ("-5", "1e12", "nan", "inf", "-inf", "1e9", "abc"):
    _add("model", "bad number", f"payload_{_v}", "model", "--payload-kg", _v)
_add("model", "options", "unknown_option", "model", "--mass", "5")
for _name in ("truck_lifts", "springs_bottom", "suspension_word"):
    _add("model", "scenario file", _name, "model", f"{S}/s_{_name}.toml")
_add("model", "missing file", "scenario", "model", f"{S}/nothing.toml")

# rigsim paper
for _name in ("truck_lifts", "frame_half"):
    _add("paper", "scenario file", f"truck_{_name}", "paper", "--out", O, "--truck", f"{S}/s_{_name}.toml")
_add("paper", "missing file", "truck", "paper", "--out", O, "--truck", f"{S}/nothing.toml")
for _v in ("0", "-1", "nan", "inf", "9.9", "1e6", "abc"):
    _add("paper", "bad number", f"duration_{_v}", "paper", "--out", O, "--duration-s", _v)
for _v in ("0", "-5", "1.5", "x"):
    _add("paper", "bad number", f"jobs_{_v}", "paper", "--out", O, "--jobs", _v)
for _v in ("-1", "nan", "inf"):
    _add("paper", "bad number", f"noise_{_v}", "paper", "--out", O, "--noise-N", _v)
_add("paper", "bad path", "out_empty", "paper", "--out", "")
_add("paper", "bad path", "out_is_file", "paper", "--out", f"{S}/file.txt")
_add("paper", "bad path", "out_previous_result", "paper", "--out", f"{S}/prev")
_add("paper", "bad path", "out_under_file", "paper", "--out", f"{S}/file.txt/p")
_add("paper", "bad path", "rrd_empty", "paper", "--out", O, "--rrd", "")
_add("paper", "bad path", "rrd_folder", "paper", "--out", O, "--rrd", f"{S}/folder")
_add("paper", "bad path", "rrd_exists", "paper", "--out", O, "--rrd", f"{S}/old.rrd")
_add("paper", "bad path", "rrd_under_file", "paper", "--out", O, "--rrd", f"{S}/file.txt/p.rrd")
_add("paper", "options", "view_without_rrd", "paper", "--out", O, "--view")
_add("paper", "bad choice", "rig", "paper", "--out", O, "--rig", "fast")
_add("paper", "bad choice", "series", "paper", "--out", O, "--series", "xlsx")
_add("paper", "options", "no_out", "paper")

# rigsim validate
for _v in ("0", "-5", "nan", "inf", "4000"):
    _add("validate", "bad number", f"duration_{_v}", "validate", "--out", O, "--duration-s", _v)
_add("validate", "bad number", "duration_1e-4", "validate", "--out", O, "--duration-s", "1e-4")
for _v in ("0", "-1", "nan", "1e9", "0.1"):
    _add("validate", "bad number", f"ident_duration_{_v}", "validate", "--out", O, "--ident-duration-s", _v)
for _v in ("0", "-5", "x"):
    _add("validate", "bad number", f"jobs_{_v}", "validate", "--out", O, "--jobs", _v)
_add("validate", "bad path", "out_empty", "validate", "--out", "")
_add("validate", "bad path", "out_is_file", "validate", "--out", f"{S}/file.txt")
_add("validate", "bad path", "out_previous_result", "validate", "--out", f"{S}/prev")
_add("validate", "bad path", "rrd_folder", "validate", "--out", O, "--rrd", f"{S}/folder")
_add("validate", "bad path", "rrd_exists", "validate", "--out", O, "--rrd", f"{S}/old.rrd")
_add("validate", "options", "view_without_rrd", "validate", "--out", O, "--view")

# rigsim identify
_ID = ("identify", f"{S}/good.toml", "--out", O)
_add("identify", "options", "neither_scenario_nor_file", "identify", "--out", O)
_add("identify", "options", "both_scenario_and_file", *_ID, "--from-file", f"{S}/rig.csv", "--pairs", "fl=drive_m:pan_m")
_add("identify", "options", "pairs_without_file", *_ID, "--pairs", "fl=drive_m:pan_m")
_add("identify", "options", "time_col_without_file", *_ID, "--time-col", "time")
_add("identify", "options", "file_without_pairs", "identify", "--from-file", f"{S}/rig.csv", "--out", O)
for _v in ("5", "0", "-10", "nan", "inf", "1e5"):
    _add("identify", "bad number", f"duration_{_v}", *_ID, "--duration-s", _v)
for _v in ("x", "1.5", "-1"):
    _add("identify", "bad number", f"seed_{_v}", *_ID, "--seed", _v)
for _name in ("syntax", "speed_nan", "payload_huge", "duration_negative"):
    _add("identify", "scenario file", _name, "identify", f"{S}/s_{_name}.toml", "--out", O)
_add("identify", "missing file", "scenario", "identify", f"{S}/nothing.toml", "--out", O)
_FF = ("identify", "--out", O, "--from-file")
_add("identify", "missing file", "from_file", *_FF, f"{S}/nothing.csv", "--pairs", "fl=drive_m:pan_m")
_add("identify", "bad path", "from_file_folder", *_FF, f"{S}/folder", "--pairs", "fl=drive_m:pan_m")
_add("identify", "measured file", "from_file_empty", *_FF, f"{S}/empty.csv", "--pairs", "fl=drive_m:pan_m")
_add("identify", "measured file", "from_file_words", *_FF, f"{S}/words.csv", "--pairs", "fl=time:force")
for _what, _pairs in (("no_equals", "fl"), ("no_colon", "fl=drive_m"), ("twice", "fl=drive_m:pan_m,fl=drive_m:pan_m"),
                      ("empty_lvdt", "fl=drive_m:"), ("empty", ",")):
    _add("identify", "channel names", f"pairs_{_what}", *_FF, f"{S}/rig.csv", "--pairs", _pairs)
_add("identify", "channel names", "pairs_missing_column", *_FF, f"{S}/rig.csv", "--pairs", "fl=drive_x:pan_m")
_add("identify", "channel names", "pairs_force_as_lvdt", *_FF, f"{S}/rig.csv", "--pairs", "fl=drive_m:fl_N")
_add("identify", "channel names", "time_col_missing", *_FF, f"{S}/rig.csv", "--pairs", "fl=drive_m:pan_m",
     "--time-col", "zeit")
_add("identify", "bad path", "out_empty", "identify", f"{S}/good.toml", "--out", "")
_add("identify", "bad path", "out_is_file", "identify", f"{S}/good.toml", "--out", f"{S}/file.txt")
_add("identify", "bad path", "out_previous_result", "identify", f"{S}/good.toml", "--out", f"{S}/prev")

# rigsim iterate
_IT = ("iterate", f"{S}/good.toml", "--target", "displacement", "--out", O)
_add("iterate", "bad choice", "target", "iterate", f"{S}/good.toml", "--target", "pressure", "--out", O)
_add("iterate", "options", "no_target", "iterate", f"{S}/good.toml", "--out", O)
for _v in ("0", "-1", "nan", "inf", "5", "2"):
    _add("iterate", "bad number", f"gain_{_v}", *_IT, "--gain", _v)
for _v in ("-1", "51", "1.5"):
    _add("iterate", "bad number", f"max_iterations_{_v}", *_IT, "--max-iterations", _v)
for _v in ("0", "1", "nan", "-0.1"):
    _add("iterate", "bad number", f"tolerance_{_v}", *_IT, "--tolerance", _v)
for _lo, _hi in (("30", "0.3"), ("-1", "10"), ("0", "300"), ("nan", "10"), ("5", "inf")):
    _add("iterate", "bad number", f"band_{_lo}_{_hi}", *_IT, "--band-hz", _lo, _hi)
_add("iterate", "options", "band_one_value", *_IT, "--band-hz", "5")
for _v in ("1", "-0.1", "nan"):
    _add("iterate", "bad number", f"coherence_{_v}", *_IT, "--coherence-min", _v)
for _v in ("5", "0", "nan", "inf"):
    _add("iterate", "bad number", f"duration_{_v}", *_IT, "--duration-s", _v)
for _v in ("-1", "nan"):
    _add("iterate", "bad number", f"noise_{_v}", *_IT, "--noise-N", _v)
_add("iterate", "scenario file", "too_short", "iterate", f"{S}/short.toml", "--target", "force", "--out", O)
for _name in ("syntax", "unknown_key", "timestep_tiny"):
    _add("iterate", "scenario file", _name, "iterate", f"{S}/s_{_name}.toml", "--target", "force", "--out", O)
_add("iterate", "missing file", "scenario", "iterate", f"{S}/nothing.toml", "--target", "force", "--out", O)
_add("iterate", "bad path", "out_empty", "iterate", f"{S}/good.toml", "--target", "force", "--out", "")
_add("iterate", "bad path", "out_is_file", "iterate", f"{S}/good.toml", "--target", "force", "--out", f"{S}/file.txt")
_add("iterate", "bad path", "out_previous_result", "iterate", f"{S}/good.toml", "--target", "force", "--out",
     f"{S}/prev")

# rigsim correct
_CO = ("correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml", "-o", f"{O}.csv")
_add("correct", "missing file", "input", "correct", f"{S}/nothing.csv", "--actuator", f"{S}/act.toml", "-o", f"{O}.csv")
_add("correct", "bad path", "input_folder", "correct", f"{S}/folder", "--actuator", f"{S}/act.toml", "-o", f"{O}.csv")
for _name in ("empty", "words", "one_row", "jitter", "tiny"):
    _add("correct", "measured file", _name, "correct", f"{S}/{_name}.csv", "--actuator", f"{S}/act.toml",
         "-o", f"{O}.csv")
_add("correct", "options", "no_actuator", "correct", f"{S}/rig.csv", "-o", f"{O}.csv")
_add("correct", "options", "two_actuator_sources", *_CO, "--identify", "drive_m,pan_m")
_add("correct", "options", "map_without_actuators", *_CO, "--map", "fl=fl_N")
_add("correct", "missing file", "actuator", "correct", f"{S}/rig.csv", "--actuator", f"{S}/nothing.toml",
     "-o", f"{O}.csv")
for _name in ACTUATORS:
    _add("correct", "actuator file", _name, "correct", f"{S}/rig.csv", "--actuator", f"{S}/a_{_name}.toml",
         "-o", f"{O}.csv")
_add("correct", "actuator file", "per_corner_given_as_one", "correct", f"{S}/rig.csv", "--actuator",
     f"{S}/acts.toml", "-o", f"{O}.csv")
_add("correct", "actuator file", "one_given_as_per_corner", "correct", f"{S}/rig.csv", "--actuators",
     f"{S}/act.toml", "-o", f"{O}.csv")
for _what, _cols in (("missing", "fz_rr"), ("time", "time"), ("empty_name", "fl_N,,fr_N"), ("twice", "fl_N,fl_N"),
                     ("length", "drive_m")):
    _add("correct", "channel names", f"columns_{_what}", *_CO, "--columns", _cols)
for _what, _cols in (("one_column", "drive_m"), ("missing", "drive_m,lvdt"), ("forces", "fl_N,fr_N"),
                     ("three", "drive_m,pan_m,fl_N")):
    _add("correct", "channel names", f"identify_{_what}", "correct", f"{S}/rig.csv", "--identify", _cols,
         "-o", f"{O}.csv")
_add("correct", "channel names", "identify_constant", "correct", f"{S}/constant.csv", "--identify", "drive_m,pan_m",
     "-o", f"{O}.csv")
_ACTS = ("correct", f"{S}/rig.csv", "--actuators", f"{S}/acts.toml", "-o", f"{O}.csv")
for _what, _map in (("syntax", "fl"), ("unknown_corner", "rr=fl_N"), ("unknown_column", "fl=fz"),
                    ("corner_twice", "fl=fl_N,fl=fr_N"), ("one_column_two_corners", "fl=fl_N,fr=fl_N")):
    _add("correct", "channel names", f"map_{_what}", *_ACTS, "--map", _map)
_add("correct", "channel names", "time_col_missing", *_CO, "--time-col", "zeit")
_add("correct", "bad path", "out_is_input", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml",
     "-o", f"{S}/rig.csv", "--force")
_add("correct", "bad path", "out_is_actuator", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml",
     "-o", f"{S}/act.toml", "--force")
_add("correct", "bad path", "out_exists", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml",
     "-o", f"{S}/existing.csv")
_add("correct", "bad path", "out_folder", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml",
     "-o", f"{S}/folder", "--force")
_add("correct", "bad path", "out_empty", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml", "-o", "")
_add("correct", "bad path", "out_unknown_format", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml",
     "-o", f"{O}.xyz")
_add("correct", "bad path", "out_under_file", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml",
     "-o", f"{S}/file.txt/o.csv")
for _opt in ("--lowpass", "--mode", "--transient"):
    _add("correct", "bad choice", _opt.strip("-"), *_CO, _opt, "magic")
_add("correct", "options", "no_out", "correct", f"{S}/rig.csv", "--actuator", f"{S}/act.toml")

# rigsim sweep
for _name in GRIDS:
    _add("sweep", "grid file", _name, "sweep", f"{S}/g_{_name}.toml", "--out", O, "--quiet")
_add("sweep", "missing file", "grid", "sweep", f"{S}/nothing.toml", "--out", O)
_add("sweep", "bad path", "grid_folder", "sweep", f"{S}/folder", "--out", O)
_add("sweep", "grid file", "a_scenario_not_a_grid", "sweep", f"{S}/good.toml", "--out", O)
for _v in ("0", "-1", "x", "2.5"):
    _add("sweep", "bad number", f"jobs_{_v}", "sweep", f"{S}/grid.toml", "--out", O, "--jobs", _v)
_add("sweep", "options", "workers_and_scheduler", "sweep", f"{S}/grid.toml", "--out", O, "--jobs", "2",
     "--scheduler", "tcp://127.0.0.1:1")
_add("sweep", "bad path", "out_empty", "sweep", f"{S}/grid.toml", "--out", "")
_add("sweep", "bad path", "out_is_a_file", "sweep", f"{S}/grid.toml", "--out", f"{S}/file.txt")
_add("sweep", "bad path", "out_under_a_file", "sweep", f"{S}/grid.toml", "--out", f"{S}/file.txt/o")

# top level
_add("rigsim", "options", "no_command")
_add("rigsim", "bad choice", "unknown_command", "simulate")


# -------------------------------------------------------------------------------------- the test
def _listing(root: pathlib.Path) -> dict[str, str]:
    """Every file and folder under ``root`` (hidden ones too) -> sha256 of its bytes (folders: '/')."""
    return {str(p.relative_to(root)): "/" if p.is_dir() else hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*"))}


def _import_everything() -> None:
    """Import every module of the project before anything is patched: a module imported for the
    first time while a function is replaced (``from rigsim.correction.identification.actuator_fit import fit_actuator``)
    would keep the replacement after the test."""
    import importlib
    import pkgutil

    for package in ("rigsim.correction", "rigsim.hydraulics", "rigsim.mjcf", "rigsim.scenarios"):
        pkg = importlib.import_module(package)
        for info in pkgutil.walk_packages(pkg.__path__, f"{package}."):
            try:
                importlib.import_module(info.name)
            except ImportError:  # an optional extra that is not installed
                pass


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    _import_everything()
    root = tmp_path_factory.mktemp("bad_inputs")
    _inputs(root / "in")
    return root


@pytest.fixture(autouse=True)
def no_work(workdir, monkeypatch):
    """Everything that would be work fails the test if it is reached."""
    import rigsim.correction.identification.actuator_fit
    import rigsim.scenarios.core.pool
    import rigsim.scenarios.studies.paper.compute
    import rigsim.scenarios.studies.sweep.run
    import rigsim.scenarios.studies.validate.compute
    from rigsim.scenarios.core.rig import Rig

    def work(what):
        def fail(*a, **k):
            raise AssertionError(f"{what} started: the bad input was not refused before the work")
        return fail

    monkeypatch.setattr(Rig, "run", work("a simulation (Rig.run)"))
    monkeypatch.setattr(rigsim.scenarios.studies.paper.compute, "local_executor", work("the paper's job pool"))
    monkeypatch.setattr(rigsim.scenarios.studies.validate.compute, "validate", work("the validation"))
    monkeypatch.setattr(rigsim.scenarios.core.pool, "local_executor", work("a process pool"))
    monkeypatch.setattr(rigsim.scenarios.studies.sweep.run, "run_sweep", work("the sweep"))
    monkeypatch.setattr(rigsim.correction.identification.actuator_fit, "fit_actuator", work("the actuator fit"))


def _one_error(err: str, from_argparse: bool) -> None:
    assert "Traceback" not in err, err
    lines = err.rstrip("\n").splitlines()
    assert lines and all(line.strip() for line in lines[-1:]), err
    errors = [line for line in lines if "error:" in line]
    assert len(errors) == 1 and errors[0] == lines[-1], err
    if from_argparse:  # argparse: usage lines, then one error line
        assert lines[0].startswith("usage:") and all(ln.startswith((" ", "usage:")) for ln in lines[:-1]), err
    else:
        assert len(lines) == 1 and lines[0].startswith("rigsim: error: "), err


@pytest.mark.parametrize("command, kind, argv", CASES)
def test_bad_input_is_refused_before_any_work(command, kind, argv, workdir, capsys, monkeypatch):
    monkeypatch.chdir(workdir / "in")  # a relative path the case may hit stays inside tmp
    out = workdir / "out"
    argv = [a.replace("{d}", str(workdir / "in")).replace("{out}", str(out)) for a in argv]
    before = _listing(workdir)
    try:
        code, from_argparse = main(argv), False
    except SystemExit as exc:
        code, from_argparse = exc.code, True
    captured = capsys.readouterr()
    assert code == 2, (code, captured.err)
    _one_error(captured.err, from_argparse)
    assert _listing(workdir) == before  # nothing written, nothing left behind, the inputs unchanged


def test_the_matrix_is_large_and_covers_every_subcommand():
    commands = {p.values[0] for p in CASES}
    assert {"run", "model", "paper", "validate", "identify", "correct", "sweep", "iterate"} <= commands
    assert len(CASES) >= 150
    assert len({p.id for p in CASES}) == len(CASES)
