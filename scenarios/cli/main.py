"""The ``rigsim`` command line.

Exit codes: 0 success; 2 bad input or a run that cannot go on (one sentence on stderr,
nothing written); 1 a recording process that failed for another reason (``rigsim run --rrd``,
one sentence, nothing written); 130 interrupted, 143 terminated (nothing written: every command that writes a
folder builds it beside the target and renames it at the end, :mod:`scenarios.core.outputs`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys

__all__ = ["main"]


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """Help with each option's default shown (unless its help already states it) and the
    description and example lines kept as written."""

    def _get_help_string(self, action):
        text = action.help or ""
        if ("default" not in text and action.default not in (None, False, argparse.SUPPRESS)
                and action.option_strings and action.nargs != 0):
            text += " (default: %(default)s)"
        return text


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message):  # argparse's own errors: exit 2 with one sentence, like ours
        self.print_usage(sys.stderr)
        self.exit(2, f"rigsim: error: {message}\n")


#: One example line per subcommand, shown at the end of its --help.
EXAMPLES = {
    "run": "rigsim run scenarios/data/paper/high_72kmh_3640kg.toml --mode rig --out out/run --duration-s 10",
    "paper": "rigsim paper --out out/paper",
    "validate": "rigsim validate --out out/validate --duration-s 20",
    "identify": "rigsim identify scenarios/data/paper/high_72kmh_3640kg.toml --out out/ident",
    "correct": "rigsim correct measured.csv --actuators out/ident/actuators.toml -o corrected.csv",
    "sweep": "rigsim sweep scenarios/data/sweeps/example.toml --out out/sweep --jobs 2",
    "iterate": "rigsim iterate scenarios/data/paper/high_72kmh_3640kg.toml --target displacement --out out/iterate",
    "model": "rigsim model --payload-kg 6360",
}


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rigsim")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree not installed
        return "unknown (not installed)"


@contextlib.contextmanager
def _progress_bar(label: str, quiet: bool):
    """A tqdm bar on stderr (only on a terminal) fed by the runner's progress callback."""
    if quiet:
        yield None
        return
    from tqdm import tqdm

    bar = tqdm(total=100, desc=label, unit="%", leave=False, disable=None, file=sys.stderr,
               bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}")
    try:
        def update(done_s: float, total_s: float) -> None:
            bar.n = min(100.0, 100.0 * done_s / total_s)
            bar.refresh()

        yield update
    finally:
        bar.close()


def _cmd_run(args) -> int:
    import os

    from scenarios.core.config import ScenarioError, load_scenario
    from scenarios.core.memory import return_freed_arrays
    from scenarios.core.outputs import check_output_file, claimed_output_file
    from scenarios.core.results import check_timeseries_format

    return_freed_arrays()  # freed arrays leave the process: a long run peaks at its record plus one temporary
    check_timeseries_format(args.format)
    scenario = load_scenario(args.scenario)
    if args.duration_s is not None:
        import dataclasses
        import math

        if not (math.isfinite(args.duration_s) and 0 < args.duration_s <= 3600):
            raise ScenarioError(f"--duration-s must lie in (0, 3600] s, got {args.duration_s:g}")
        scenario = dataclasses.replace(scenario, duration_s=float(args.duration_s))
    rate = scenario.output_rate_hz
    if scenario.duration_s * rate < 1.0 - 1e-9:  # the DLC, the table's first column, needs two samples
        raise ScenarioError(f"duration_s (--duration-s) = {scenario.duration_s:g} s is shorter than one output "
                            f"sample at output_rate_hz = {rate:g} Hz; a DLC needs two, so give at least "
                            f"{1.0 / rate:g} s")
    if args.view and args.rrd is None:
        raise ScenarioError("--view opens the recording that --rrd FILE.rrd writes; give --rrd too")
    from scenarios.core.cost import check_disk, run_cost

    cost = run_cost(args.mode, scenario.lead_in_s + scenario.duration_s,
                    int(scenario.duration_s * rate) + 1, args.format)
    check_disk(cost, args.out)
    with contextlib.ExitStack() as claims:
        if args.rrd is not None:  # checked with --out before the run: both are written, or neither
            check_output_file(args.rrd, "--rrd", force=args.force, folder=args.out)
            if os.path.exists(args.rrd) and os.path.samefile(args.rrd, args.scenario):
                raise ScenarioError(f"--rrd {args.rrd} is the scenario file; name another file for the recording")
            if os.path.relpath(os.path.abspath(args.rrd), os.path.abspath(args.out)).startswith(os.pardir):
                # outside --out (inside, it is written into the staging folder): one command writes it
                claims.enter_context(claimed_output_file(
                    args.rrd, "--rrd", force=args.force,
                    check=lambda: check_output_file(args.rrd, "--rrd", force=args.force, folder=args.out)))
        return _run_and_write(args, scenario, cost)


def _run_and_write(args, scenario, cost) -> int:
    """``rigsim run`` once its arguments are checked (and ``--rrd`` claimed): the run, its folder and recording."""
    from scenarios.core.outputs import staged_output
    from scenarios.core.results import write_run
    from scenarios.review.recording_process import RecordingError, RecordingProcess

    # --rrd: a child process imports rerun and writes the recording (scenarios.review.recording_process);
    # it starts before the simulation's imports, so that its own overlap them and the run
    recording = RecordingProcess() if args.rrd is not None else contextlib.nullcontext()
    if cost.long and not args.quiet:
        print(f"rigsim: {cost.sentence(f'a {scenario.duration_s:g} s {args.mode} run')}", file=sys.stderr,
              flush=True)
    try:
        with staged_output(args.out, force=args.force, inputs=scenario.input_files) as stage, recording as recorder:
            from scenarios.core.poses import DEFAULT_POSE_RATE_HZ
            from scenarios.core.run import run

            with _progress_bar(f"{scenario.name} [{args.mode}]", args.quiet) as progress:
                result = run(scenario, args.mode, progress=progress,
                             pose_rate_hz=None if recorder is None else DEFAULT_POSE_RATE_HZ)
            table = result.table()
            if recorder is not None:  # the child writes the .rrd while this process writes the rest
                recorder.submit(stage.place(args.rrd), [result], dlc_table=table)
            paths = {k: stage.final(p) for k, p in write_run(result, stage.path, fmt=args.format).items()}
            if recorder is not None:
                recorder.commit()
    except RecordingError as exc:  # not bad input nor an unwritable file: exit 1, nothing written
        print(f"rigsim: error: {exc}", file=sys.stderr)
        return 1
    if args.rrd is not None:
        print(f"wrote recording {args.rrd}" + (" and opened the viewer" if args.view else ""))
        if args.view:
            from scenarios.review.recording import open_viewer

            open_viewer(args.rrd)
    print(table)
    if result.events:
        print("events: " + json.dumps(result.events))
    print(f"wrote {paths['result']} and {paths['timeseries']}")
    return 0


def _cmd_model(args) -> int:
    import dataclasses

    import mujoco

    from mjcf.build import build_model
    from mjcf.description import suspension_of
    from mjcf.variant import TruckVariant
    from mjcf.names import CORNERS
    from mjcf.physics import modal_analysis, static_equilibrium, tire_forces
    from mjcf.standing import truck_layout
    from scenarios.core.config import ScenarioError, load_scenario

    base = TruckVariant() if args.scenario is None else load_scenario(args.scenario).vehicle
    payload = args.payload_kg if args.payload_kg is not None else \
        (base.payload_kg if base.payload_kg is not None else 3640.0)
    cab_hz = args.cab_mount_hz if args.cab_mount_hz is not None else base.cab_mount_hz
    try:
        variant = dataclasses.replace(base, payload_kg=payload, cab_mount_hz=cab_hz)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    model = build_model(variant, pans="fixed")
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    forces = tire_forces(model, data)
    layout = truck_layout(model, data)
    cab = "rigid cab" if cab_hz is None else f"cab on {cab_hz:g} Hz mounts"
    print(f"truck on rigid pans, payload {payload:g} kg, {cab}")
    print(f"wheelbase {layout['wheelbase_m']:.3f} m, track front {layout['track_front_m']:.3f} m, rear "
          f"{layout['track_rear_m']:.3f} m ({base.rear_tires or 'dual'} rear tires); suspension front "
          f"{suspension_of(base, True)}, rear {suspension_of(base, False)}")
    print("springs at rest: " + ", ".join(f"{c} {k / 1e3:.0f} kN/m gap {g * 1e3:.0f} mm"
                                          for c, k, g in zip(CORNERS, layout["spring_rate_N_per_m"],
                                                             layout["spring_gap_m"])))
    print("static wheel loads: " + ", ".join(f"{c} {f:.0f} N" for c, f in zip(CORNERS, forces))
          + f"; total {forces.sum():.0f} N")
    print("modes (leaf friction off):")
    modes = modal_analysis(model, data)
    width = max(len(m.name) for m in modes)
    for m in modes:
        print(f"  {m.name:{width}s} {m.frequency_hz:6.2f} Hz  damping ratio {m.damping_ratio:.3f}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="rigsim", description="Four-post road simulator (DYNTRAC) with a heavy truck, in MuJoCo.",
                epilog="example: " + EXAMPLES["paper"])
    p.add_argument("--version", action="version", version=f"rigsim {_version()}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    r = sub.add_parser("run", help="run one scenario file in road or rig mode")
    r.add_argument("scenario", help="scenario TOML file")
    r.add_argument("--mode", choices=("road", "rig"), default="road",
                   help="road: pans follow the profile exactly; rig: hydraulic actuators drive the pans")
    r.add_argument("--out", "-o", required=True, help="output folder (result.json, timeseries.csv or --format's)")
    r.add_argument("--duration-s", type=float, default=None, help="override the scenario's duration, s")
    r.add_argument("--format", default="csv", choices=("csv", "mf4", "tdms", "rsp"),
                   help="time series file: csv (default), mf4 (ASAM MDF4, float64), tdms (NI) or rsp (MTS RPC III, "
                        "int16); mf4 and tdms need pip install -e \".[lab]\"")
    r.add_argument("--rrd", default=None, help="also write a rerun recording (.rrd) of the run")
    r.add_argument("--view", action="store_true", help="with --rrd: open the recording in the rerun viewer")
    r.add_argument("--force", action="store_true", help="replace a previous result in --out (and the --rrd file)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=_cmd_run)

    from scenarios.cli import correct as correct_cmd
    from scenarios.studies.identify import command as identify_cmd
    from scenarios.studies.iterate import command as iterate_cmd
    from scenarios.studies.paper import command as paper
    from scenarios.studies.sweep import command as sweep
    from scenarios.studies.validate import command as validate

    paper.add_parser(sub)
    validate.add_parser(sub)
    correct_cmd.add_parser(sub)
    sweep.add_parser(sub)
    iterate_cmd.add_parser(sub)
    identify_cmd.add_parser(sub)

    m = sub.add_parser("model", help="print the truck's static wheel loads and natural frequencies")
    m.add_argument("scenario", nargs="?", default=None,
                   help="scenario TOML file whose [vehicle] describes the truck (default: the catalogue truck)")
    m.add_argument("--payload-kg", type=float, default=None,
                   help="payload mass in kg (default: the scenario's, else 3640 kg)")
    m.add_argument("--cab-mount-hz", type=float, default=None, metavar="HZ",
                   help="the cab on its own mounts bouncing at HZ (vehicle.cab_mount_hz; default: a rigid cab)")
    m.set_defaults(func=_cmd_model)
    for name, parser in sub.choices.items():
        parser.epilog = f"example: {EXAMPLES[name]}"
    return p


class _SigtermAsInterrupt:
    """While installed, SIGTERM raises KeyboardInterrupt in the main thread, so a terminated run
    stops as after Ctrl-C (pool workers terminated, a sweep's finished cases kept); ``received``
    tells the two apart. Outside the main thread nothing is installed.

    A handler's exception can be lost: Python runs signal handlers between bytecodes, also inside
    a ctypes callback, which hands the exception to ``sys.unraisablehook`` ("Exception ignored")
    and goes on (numba loading its cached callbacks through llvmlite's object-cache callback: a
    command terminated then runs its whole 600 s run and exits 0, measured without the re-send 2
    times in 30 with SIGTERM 0.05-1.5 s after the start). While installed, this also takes that hook: a lost
    interrupt of its own is sent again, as SIGTERM after :data:`RESEND_S`, until one arrives in
    code that lets it through (:meth:`acknowledge` or :meth:`restore` stop it; late copies are
    ignored). An interrupt that was not lost is never repeated, so cleanup runs undisturbed."""

    #: s before a lost interrupt's SIGTERM is sent again.
    RESEND_S = 0.05
    #: The KeyboardInterrupt's message: how the unraisable hook knows its own interrupt.
    MESSAGE = "terminated (SIGTERM)"

    def __init__(self) -> None:
        import signal
        import threading

        self.received, self._signal, self._previous = False, signal, None
        self._caught, self._hook = threading.Event(), None
        try:
            self._previous = (signal.signal(signal.SIGTERM, self._handle),)
        except ValueError:  # not the main thread
            return
        self._hook = sys.unraisablehook
        sys.unraisablehook = self._unraisable

    def _handle(self, signum, frame) -> None:
        if self._caught.is_set():  # a late copy: the interrupt is being handled already
            return
        self.received = True
        raise KeyboardInterrupt(self.MESSAGE)

    def _unraisable(self, unraisable) -> None:
        """``sys.unraisablehook``: our interrupt, lost where exceptions cannot propagate: send it again."""
        exc = unraisable.exc_value
        if not (self.received and isinstance(exc, KeyboardInterrupt) and exc.args == (self.MESSAGE,)):
            (self._hook or sys.__unraisablehook__)(unraisable)
            return
        import os
        import threading

        def resend() -> None:
            if not self._caught.wait(self.RESEND_S):
                os.kill(os.getpid(), self._signal.SIGTERM)

        threading.Thread(target=resend, name="rigsim-sigterm-resend", daemon=True).start()

    def acknowledge(self) -> None:
        """The interrupt was caught: late copies are ignored and none is sent again."""
        self._caught.set()

    def restore(self) -> None:
        self.acknowledge()
        if self._previous is not None:
            self._signal.signal(self._signal.SIGTERM, self._previous[0] or self._signal.SIG_DFL)
            self._previous = None
        if self._hook is not None:
            sys.unraisablehook, self._hook = self._hook, None


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``rigsim`` console command; returns the exit code (SIGTERM: the run
    stops as for Ctrl-C, "rigsim: terminated" on stderr, 143)."""
    args = build_parser().parse_args(argv)  # --help and bad options end here, before the imports below
    # The commands draw nothing with MuJoCo (recordings are rerun's): its import then skips loading
    # OpenGL (glfw), ~0.06 s of every process's start (benchmarks/startup.py); a value set is kept.
    os.environ.setdefault("MUJOCO_GL", "disable")
    from scenarios.core.config import ScenarioError
    from scenarios.core.watch import SimulationError

    sigterm = _SigtermAsInterrupt()
    try:
        return args.func(args)
    except (ScenarioError, SimulationError) as exc:
        print(f"rigsim: error: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:  # parameter validation of the model layers
        print(f"rigsim: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"rigsim: error: cannot write output: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        sigterm.acknowledge()
        if sigterm.received:
            print("rigsim: terminated", file=sys.stderr)
            return 143
        print("rigsim: interrupted", file=sys.stderr)
        return 130
    finally:
        sigterm.restore()


#: Exit codes of an interrupted command (Ctrl-C, SIGTERM), whose cleanup :func:`main` has done.
INTERRUPTED = (130, 143)


def exit_main(code: int) -> None:
    """End ``python -m scenarios.cli.main`` with ``code``. After an interrupt (:data:`INTERRUPTED`)
    the process ends at once (its outputs are removed and its workers stopped; the standard
    streams are flushed): CPython ends a ``-m`` run by SIGINT, whatever the code, once a
    KeyboardInterrupt has passed through a nested ``PyRun_String`` (MuJoCo's callback module runs
    one while the hydraulics are installed), so without ``os._exit`` SIGTERM can end the command as
    killed by SIGINT after it has printed "rigsim: terminated" (measured: 3 times in 30 with SIGTERM
    0.05-1.5 s after the start). The ``rigsim`` script exits by the code as it is."""
    if code in INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    exit_main(main())
