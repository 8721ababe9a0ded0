"""The shipped trucks' static loads and modes: the table of mjcf/README.md ("A truck of its own").

::

    python benchmarks/truck_models.py [--readme mjcf/README.md]

For each scenario file of ``scenarios/data/trucks/`` the truck its ``[vehicle]`` describes stands
on rigid pans at its payload (``rigsim model SCENARIO.toml``'s computation:
:func:`rigsim.mjcf.physics.static_equilibrium`, :func:`rigsim.mjcf.modes.modal_analysis`, leaf friction off);
prints the table, and with ``--readme`` writes it between the page's markers.
"""

from __future__ import annotations

import argparse
import pathlib
import sys

from rigsim.scenarios.studies.results_page import configuration_line, markdown_table, script_command, write_block

ROOT = pathlib.Path(__file__).resolve().parents[1]

TRUCKS = ROOT / "scenarios" / "data" / "trucks"
BEGIN = "<!-- trucks: written by benchmarks/truck_models.py --readme mjcf/README.md -->"
END = "<!-- trucks end -->"
HEADER = ("truck", "static wheel loads fl / rl (N)", "body bounce, pitch (Hz)", "axle hop front / rear (Hz)")


def truck_row(path: pathlib.Path) -> list[str]:
    """One shipped truck's row: its file, loads at rest, body and axle-hop modes."""
    import mujoco

    from rigsim.mjcf.build import build_model
    from rigsim.mjcf.physics import static_equilibrium, tire_forces
    from rigsim.mjcf.modes import modal_analysis
    from rigsim.scenarios.core.config import load_scenario

    vehicle = load_scenario(path).vehicle
    model = build_model(vehicle, pans="fixed")
    data = mujoco.MjData(model)
    static_equilibrium(model, data)
    loads = tire_forces(model, data)
    modes = {m.name: m.frequency_hz for m in modal_analysis(model, data)}

    def hz(name: str) -> str:
        found = [f for n, f in modes.items() if n.startswith(name)]
        return f"{found[0]:.2f}" if found else "-"

    return [f"`{path.name}` ({vehicle.payload_kg or 0:g} kg)", f"{loads[0]:.0f} / {loads[2]:.0f}",
            f"{hz('body bounce')}, {hz('body pitch')}", f"{hz('front axle hop')} / {hz('rear axle hop')}"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readme", type=pathlib.Path, default=None, help="the page whose table block to rewrite")
    args = parser.parse_args(argv)
    rows = [truck_row(p) for p in sorted(TRUCKS.glob("*.toml"))]
    block = markdown_table(HEADER, rows).rstrip("\n") + "\n\n" + configuration_line(
        script_command(__file__, argv if argv is not None else sys.argv[1:])) + "\n"
    print(block)
    if args.readme is not None:
        write_block(args.readme, BEGIN, END, block)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
