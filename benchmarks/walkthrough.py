"""The documentation's walk-throughs, run as the pages show them; their terminal output written as
results files the pages include.

::

    python benchmarks/walkthrough.py [--work DIR] [--results docs/results]

The walk-through of ``docs/getting_started.md`` ("Correcting data from your rig": the measured
file made with the simulator, ``rigsim identify --from-file``, ``rigsim correct``, the same from
Python, the result read back, the road run) and the truck-model correction of
``docs/guide/correct.md`` (``rigsim correct --model``) are run in a fresh folder (a temporary
one unless ``--work`` names one, which must not hold ``out/lab`` yet), the commands taken from the
pages themselves: each step names a text only one code block of its page holds (or one inline
command, for the road run), and a page that no longer holds it stops the script. The folder gets
the two things a repository root has and the commands use: ``scenarios`` (the installed package,
so ``scenarios/data/paper/...`` resolves and ``python -`` imports what ``rigsim`` does) and, in a
virtual environment, ``.venv`` (so ``export PATH="$PWD/.venv/bin:$PATH"`` works); this
interpreter's ``bin`` folder heads ``PATH`` too.

Writes to ``docs/results`` (``--results``: its folder), each with the command lines as a terminal
shows them (a here-document's script shortened to ``...``), what they printed and the line that
says how and where it was measured (:func:`rigsim.scenarios.studies.results_page.write_output_page`):

* ``walkthrough_messung.md``: the measured file's first lines (``head -3``);
* ``walkthrough_identify.md``, ``walkthrough_correct.md``: the identification and the linear
  correction; ``walkthrough_correct_again.md``: the same correction run again (refused: the output
  exists);
* ``walkthrough_read_back.md``: the corrected file read back with its metadata;
* ``walkthrough_road.md``: the road run of the same scenario;
* ``walkthrough_correct_model.md``: ``rigsim correct --model`` (stdout; the progress lines on
  stderr left out, as the page says);
* ``walkthrough_fallback.md``: the same command on the walk-through's file cut to 20 s with
  ``Fz_RR`` replaced by its mean plus 3 kN rms of noise (seeded), which the truck model cannot
  reproduce: rr is left out of a second calibration and corrected linearly, the other wheels by
  the model;
* ``walkthrough_dlc.md`` (a table, :func:`rigsim.scenarios.studies.results_page.write_results_page`):
  the DLC of the measured and corrected forces against the road run's on the samples each
  correction keeps.

It checks, too, that the Python API's file (``out/lab/corrected_api.rsp``) is the command's byte
for byte but for the time of writing in the RPC III header (``DATE``), as the page says; the
script ends with status 1 if it is not. Prints each step's wall and CPU time to stderr, and the
files written. The two model corrections take most of the time (a few CPU-minutes each, on all
cores, as the page's command runs).
"""

from __future__ import annotations

import argparse
import os
import pathlib
import re
import resource
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple

import numpy as np

import rigsim.scenarios
from rigsim.correction.io.measured import read_channels
from rigsim.correction.io.measured_core import TIME_START_KEY
from rigsim.correction.metrics.dlc import dlc
from rigsim.mjcf.names import CORNERS
from rigsim.scenarios.studies.results_page import (
    script_command,
    write_output_page,
    write_results_page,
)

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: Where the results files go by default: docs/results of this repository.
RESULTS = DOCS / "results"
#: The fallback's record: the walk-through's file cut to this many seconds, its rear right force
#: replaced by its mean plus white noise of this rms (kN) from this seed.
FALLBACK_S, FALLBACK_NOISE_KN, FALLBACK_SEED = 20.0, 3.0, 3


class Step(NamedTuple):
    """One command of a page.

    ``page``: the page, relative to docs/; ``key``: a text exactly one code block (bash or python)
    of the page holds, or, with ``inline``, one inline code span; ``name``: the results file (none:
    run only); ``stderr``: show what the command printed to stderr after its stdout; ``status``:
    the exit status it must end with.
    """

    page: str
    key: str
    name: str | None = None
    inline: bool = False
    stderr: bool = False
    status: int = 0


STEPS = (
    Step("getting_started.md", "--mode rig --out out/lab/rig --duration-s 30"),
    Step("getting_started.md", "head -3 out/lab/messung.csv", "walkthrough_messung"),
    Step("getting_started.md", "rigsim identify --from-file out/lab/messung.csv", "walkthrough_identify"),
    Step("getting_started.md", "--actuators out/lab/ident/actuators.toml", "walkthrough_correct"),
    Step("getting_started.md", "--actuators out/lab/ident/actuators.toml", "walkthrough_correct_again",
         stderr=True, status=2),
    Step("getting_started.md", 'result.write("out/lab/corrected_api.rsp")'),
    Step("getting_started.md", 'read_channels("out/lab/corrected.rsp")', "walkthrough_read_back"),
    Step("getting_started.md", "--mode road --out out/lab/road --duration-s 30", "walkthrough_road", inline=True),
    Step("guide/correct.md", "rigsim correct out/lab/messung.csv --model", "walkthrough_correct_model"),
)


def code_blocks(text: str) -> list[tuple[str, str]]:
    """The fenced code blocks of a Markdown page: (language, body), in order."""
    blocks, lang, body = [], None, []
    for line in text.splitlines():
        if lang is None and line.startswith("```"):
            lang, body = line[3:].strip(), []
        elif lang is not None and line.startswith("```"):
            blocks.append((lang, "\n".join(body) + "\n"))
            lang = None
        elif lang is not None:
            body.append(line)
    return blocks


def find_command(text: str, step: Step) -> tuple[str, str]:
    """(language, code) of the one block (or inline span) of ``text`` that holds ``step.key``."""
    if step.inline:
        prose = re.sub(r"^```.*?^```", "", text, flags=re.MULTILINE | re.DOTALL)  # the fenced blocks left out
        found = [("bash", s + "\n") for s in re.findall(r"`([^`\n]+)`", prose) if step.key in s]
    else:
        found = [(lang, body) for lang, body in code_blocks(text) if lang in ("bash", "python") and step.key in body]
    if len(found) != 1:
        raise SystemExit(f"docs/{step.page}: {len(found)} {'inline commands' if step.inline else 'code blocks'} "
                         f"hold {step.key!r}, the walk-through needs exactly one")
    return found[0]


def shown(code: str) -> list[str]:
    """The commands of a bash block as a terminal shows them: a here-document's script as ``...``."""
    out, lines, i = [], code.strip("\n").splitlines(), 0
    while i < len(lines):
        line = lines[i]
        m = re.search(r"<<-?\s*'?\"?(\w+)'?\"?", line)
        if m:
            end = next((j for j in range(i + 1, len(lines)) if lines[j].strip() == m[1]), len(lines) - 1)
            out.append(f"{line}\n...\n{m[1]}")
            i = end + 1
        else:
            out.append(line)
            i += 1
    return out


def prepare(folder: pathlib.Path) -> dict:
    """The folder as a repository root looks to the commands; the environment they run in."""
    (folder / "scenarios").symlink_to(pathlib.Path(rigsim.scenarios.__file__).resolve().parent, target_is_directory=True)
    if sys.prefix != sys.base_prefix:
        (folder / ".venv").symlink_to(pathlib.Path(sys.prefix).resolve(), target_is_directory=True)
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(pathlib.Path(sys.executable).parent), env.get("PATH", "")])
    env.setdefault("MPLBACKEND", "Agg")
    return env


def cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def execute(lang: str, code: str, folder: pathlib.Path, env: dict, status: int = 0) -> tuple[str, str, float, float]:
    """Run a bash or python block in ``folder``; (stdout, stderr, wall s, CPU s)."""
    argv = ["bash", "-e", "-c", code] if lang == "bash" else [sys.executable, "-"]
    t0, c0 = time.perf_counter(), cpu_children()
    done = subprocess.run(argv, input=None if lang == "bash" else code, cwd=folder, env=env,
                          capture_output=True, text=True, check=False)
    wall, cpu = time.perf_counter() - t0, cpu_children() - c0
    if done.returncode != status:
        raise SystemExit(f"exit status {done.returncode} (expected {status}) from:\n{code}\n"
                         f"stdout:\n{done.stdout[-3000:]}\nstderr:\n{done.stderr[-3000:]}")
    return done.stdout, done.stderr, wall, cpu


def rpc_bytes(path: pathlib.Path) -> bytes:
    """An RPC III file's bytes with its ``DATE`` header's value (the time of writing) blanked."""
    data = bytearray(path.read_bytes())
    for i in range(0, min(len(data), 1 << 16), 128):  # the header: 128-byte records, a 32-byte key each
        if data[i:i + 32].rstrip(b"\0 ") == b"DATE":
            data[i + 32:i + 128] = bytes(96)
            break
    return bytes(data)


def fallback_record(folder: pathlib.Path) -> None:
    """``out/lab/messung_rr_noise.csv``: the walk-through's file, its first :data:`FALLBACK_S` s,
    ``Fz_RR`` replaced by its mean plus :data:`FALLBACK_NOISE_KN` kN rms of white noise."""
    lines = (folder / "out/lab/messung.csv").read_text(encoding="utf-8").splitlines()
    preamble, header, rows = lines[0], lines[1], lines[2:]
    names = header.split(";")
    rr = names.index("Fz_RR [kN]")
    cells = [r.split(";") for r in rows]
    cells = [c for c in cells if float(c[0].replace(",", ".")) < FALLBACK_S - 1e-9]
    mean = float(np.mean([float(c[rr].replace(",", ".")) for c in cells]))
    noise = np.random.default_rng(FALLBACK_SEED).normal(0.0, FALLBACK_NOISE_KN, len(cells))
    for c, x in zip(cells, noise):
        c[rr] = f"{mean + x:.6f}".replace(".", ",")
    text = "\n".join([preamble, header] + [";".join(c) for c in cells]) + "\n"
    (folder / "out/lab/messung_rr_noise.csv").write_text(text, encoding="utf-8")


def dlc_rows(folder: pathlib.Path) -> tuple[list[list[str]], str]:
    """The DLC table's rows: road run, measured and corrected forces on the samples each
    correction keeps; and the note under it."""
    road = np.genfromtxt(folder / "out/lab/road/timeseries.csv", delimiter=",", names=True)
    measured = read_channels(folder / "out/lab/messung.csv")
    fs = 1.0 / float(np.median(np.diff(road["time_s"])))

    def index(t) -> np.ndarray:
        i = np.rint((np.asarray(t) - road["time_s"][0]) * fs).astype(int)
        if i.min() < 0 or i.max() >= road.size or np.max(np.abs(road["time_s"][i] - t)) > 0.25 / fs:
            raise SystemExit("the corrected file's samples are not the road run's")
        return i

    def clock(channels) -> np.ndarray:
        """A file's samples on the lab's clock, s (readers count from the first sample)."""
        return channels.time_s + float(channels.metadata.get(TIME_START_KEY, 0.0))

    m_index = index(clock(measured))
    rows = []
    for label, path in (("linear correction (`out/lab/corrected.rsp`)", "out/lab/corrected.rsp"),
                        ("truck-model correction (`out/lab/corrected_model.csv`)", "out/lab/corrected_model.csv")):
        got = read_channels(folder / path)
        t = clock(got)
        i = index(t)
        span = f"{t[0]:.3f}-{t[-1]:.3f} s"
        on = np.isin(m_index, i)
        if on.sum() != i.size:
            raise SystemExit(f"{path}: samples the measured file does not hold")
        r = [dlc(road[f"tire_force_{c}_N"][i]) for c in CORNERS]
        raw = [dlc(measured.data[f"Fz_{c.upper()}"][on]) for c in CORNERS]
        cor = [dlc(got.data[f"Fz_{c.upper()}_corrected"]) for c in CORNERS]
        rows.append(["road run", span] + [f"{x:.4f}" for x in r])
        rows.append(["rig, measured", span] + [f"{x:.4f} ({100 * (x / y - 1):+.2f} %)" for x, y in zip(raw, r)])
        rows.append([label, span] + [f"{x:.4f} ({100 * (x / y - 1):+.2f} %)" for x, y in zip(cor, r)])
    note = ("Each correction's samples: the linear correction drops its filters' transients, the truck-model "
            "correction the model runs' start-up. Road run: `out/lab/road/timeseries.csv`; rig, measured: "
            "`out/lab/messung.csv` (with the load cells' noise); in brackets, the difference from the road run's "
            "DLC on the same samples.")
    return rows, note


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", type=pathlib.Path, default=None,
                    help="run in this folder and keep it (default: a temporary folder, removed)")
    ap.add_argument("--results", type=pathlib.Path, default=RESULTS,
                    help="folder of the results files walkthrough_*.md (default docs/results)")
    args = ap.parse_args(argv)
    me = script_command(__file__, argv)
    pages = {s.page: (DOCS / s.page).read_text(encoding="utf-8") for s in STEPS}
    commands = [find_command(pages[s.page], s) for s in STEPS]  # every page checked before anything runs
    if args.work is None:
        tmp = tempfile.TemporaryDirectory(prefix="rigsim-walkthrough-")
        folder = pathlib.Path(tmp.name)
    else:
        tmp, folder = None, args.work.resolve()
        if (folder / "out" / "lab").exists():
            raise SystemExit(f"--work: {folder / 'out' / 'lab'} exists; the walk-through starts without it")
        folder.mkdir(parents=True, exist_ok=True)
        for name in ("scenarios", ".venv"):
            if (folder / name).is_symlink():
                (folder / name).unlink()
    written, problems, t_all = [], [], time.perf_counter()
    try:
        env = prepare(folder)

        def step(name, lang, code, commands_shown, stderr=False, status=0, note="", title=""):
            out, err, wall, cpu = execute(lang, code, folder, env, status)
            print(f"[{name or 'run'}] {wall:.1f} s wall, {cpu:.1f} s CPU: {commands_shown[-1].splitlines()[0]}",
                  file=sys.stderr, flush=True)
            if name:
                text = out + (err if stderr else "")
                written.append(write_output_page(args.results, name, commands_shown, text, me, note=note,
                                                 title=title))
            return out, err

        for s, (lang, code) in zip(STEPS, commands):
            note = ""
            if s.name == "walkthrough_correct_model":
                note = "What it printed on stdout; the progress lines on stderr left out."
            step(s.name, lang, code, shown(code), stderr=s.stderr, status=s.status, note=note)
            if s.key.startswith("result.write"):
                api, cli = folder / "out/lab/corrected_api.rsp", folder / "out/lab/corrected.rsp"
                same = rpc_bytes(api) == rpc_bytes(cli)
                print(f"corrected_api.rsp {'is' if same else 'is NOT'} corrected.rsp byte for byte (but the DATE "
                      "header)", file=sys.stderr)
                if not same:
                    problems.append("the Python API's file differs from the command's")
        # The fallback: the page's model command on a record whose Fz_RR the model cannot reproduce.
        fallback_record(folder)
        _, model_code = commands[-1]
        code = model_code.replace("out/lab/messung.csv", "out/lab/messung_rr_noise.csv").replace(
            "out/lab/corrected_model.csv", "out/lab/corrected_rr_noise.csv")
        step("walkthrough_fallback", "bash", code, shown(code),
             note=(f"`out/lab/messung_rr_noise.csv`: the walk-through's file, its first {FALLBACK_S:g} s, with "
                   f"`Fz_RR` replaced by its mean plus {FALLBACK_NOISE_KN:g} kN rms of white noise (seed "
                   f"{FALLBACK_SEED}). What it printed on stdout; the progress lines on stderr left out."))
        rows, note = dlc_rows(folder)
        written.append(write_results_page(args.results, "walkthrough_dlc",
                                          "DLC of the walk-through's wheel forces against the road run's, on the "
                                          "samples each correction keeps",
                                          ("force", "samples", *CORNERS), rows, me, note=note))
    finally:
        if tmp is not None:
            tmp.cleanup()
    print(f"walk-through done in {time.perf_counter() - t_all:.0f} s wall, {cpu_children():.0f} s CPU "
          "(the commands')", file=sys.stderr)
    for path in written:
        print(f"wrote {path}")
    for p in problems:
        print(f"problem: {p}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
