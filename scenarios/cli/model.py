"""``rigsim model``: the truck's static wheel loads and natural frequencies, printed."""

from __future__ import annotations

from rigsim.scenarios.core.flags import add_command

__all__ = ["add_parser", "cmd_model"]


def add_parser(subparsers) -> None:
    """Register ``rigsim model`` (``func=cmd_model``)."""
    m = add_command(subparsers, "model", "print the truck's static wheel loads and natural frequencies",
                    "The truck on rigid pans at static equilibrium: its layout, springs, wheel loads and modes "
                    "(leaf friction off).")
    m.add_argument("scenario", nargs="?", default=None,
                   help="scenario TOML file whose [vehicle] describes the truck (default: the catalogue truck)")
    m.add_argument("--payload-kg", type=float, default=None, metavar="KG",
                   help="payload mass in kg (default: the scenario's, else 3640 kg)")
    m.add_argument("--cab-mount-hz", type=float, default=None, metavar="HZ",
                   help="the cab on its own mounts bouncing at HZ (vehicle.cab_mount_hz; default: a rigid cab)")
    m.set_defaults(func=cmd_model)


def cmd_model(args) -> int:
    """Run ``rigsim model``: print the truck's layout, static wheel loads (N) and modes (Hz); returns 0."""
    import dataclasses

    import mujoco

    from rigsim.mjcf.build import build_model
    from rigsim.mjcf.description import suspension_of
    from rigsim.mjcf.variant import TruckVariant
    from rigsim.mjcf.names import CORNERS
    from rigsim.mjcf.physics import static_equilibrium, tire_forces
    from rigsim.mjcf.modes import modal_analysis
    from rigsim.mjcf.standing import truck_layout
    from rigsim.scenarios.core.config import ScenarioError, load_scenario

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
