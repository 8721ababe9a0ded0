"""The truck as its spec sheet describes it: wheelbase, tracks, rear tires, and each axle's suspension.

The XML (``truck_rig.xml``) holds the catalogue truck: 5.0 m wheelbase, tracks 2.05 / 1.83 m, dual
rear tires, multi-leaf springs on both axles. A lab's truck is another truck; the fields of
:data:`DESCRIPTION_FIELDS` (``TruckVariant``, a scenario's ``[vehicle]``) describe it, and
:func:`apply_geometry` and :func:`apply_suspension` edit the spec so that the MJCF follows: the axles,
hangers, wheel sites, pans and the chassis' centre of mass move with the geometry; an air
suspension replaces a leaf one. A field left at None keeps the XML's value; with every field None
the spec is the XML's exactly.

An air spring (``suspension_front`` / ``suspension_rear`` = ``"air"``) differs from a leaf spring in
three ways (mjcf/README.md, "A truck of its own"):

* no interleaf friction (``spring_friction_<axle>_N`` defaults to 0; a value given is the bushings');
* dampers of its own (``spring_damping_<axle>_Ns_per_m``, default :data:`AIR_DAMPING_NS_PER_M`);
* its levelling valve holds the ride height at any payload, and its rate rises with the load it
  carries: at the levelled height the gas volume is fixed and the rate follows the gas pressure,
  which carries the load, so k = k_empty F / F_empty, a ride frequency that stays the same at any
  payload. ``spring_rate_<axle>_N_per_m`` of an air axle is its rate at the **empty** truck's static
  spring load F_empty; the free length is set so that the spring rests at the design gap, which with
  k proportional to F is the same free length at any load (F / k = F_empty / k_empty).

The static spring loads come from the lever rule on the described masses (:func:`spring_loads`),
the rest's small pitch left out (0.1 % on the catalogue truck).
"""

from __future__ import annotations

import numpy as np

from rigsim.mjcf import names

__all__ = ["DESCRIPTION_FIELDS", "lever_loads", "CHOICES", "BOUNDS", "AIR_RATE_N_PER_M", "AIR_DAMPING_NS_PER_M",
           "SINGLE_TIRE_STIFFNESS_N_PER_M", "SINGLE_TIRE_DAMPING_NS_PER_M", "DUAL_HALF_SPACING_M",
           "described", "apply_geometry", "apply_suspension", "spring_loads", "suspension_of"]

#: The description's fields (``TruckVariant``), what a truck's spec sheet gives.
DESCRIPTION_FIELDS = ("wheelbase_m", "track_front_m", "track_rear_m", "rear_tires", "suspension_front",
                      "suspension_rear", "spring_rate_front_N_per_m", "spring_rate_rear_N_per_m",
                      "spring_damping_front_Ns_per_m", "spring_damping_rear_Ns_per_m")

#: The word-valued fields and the words each takes (the first: the XML's).
CHOICES: dict[str, tuple[str, ...]] = {"rear_tires": ("dual", "single"), "suspension_front": ("leaf", "air"),
                                       "suspension_rear": ("leaf", "air")}

#: Bounds of the numeric description fields, ``{field: (low, high, unit, why)}``, inclusive, SI.
BOUNDS: dict[str, tuple[float, float, str, str]] = {
    "wheelbase_m": (3.0, 7.0, "m", "two-axle trucks and tractor units have 3.2-6.5 m between their axles; the "
                    "rig's pans reach 3-7 m"),
    "track_front_m": (1.6, 2.3, "m", "a steer axle's track is 1.9-2.1 m; narrower puts the tires inside the frame "
                      "rails' spring seats (0.9 m apart), wider is beyond the 2.55 m legal width"),
    "track_rear_m": (1.5, 2.2, "m", "the centres of a drive axle's dual pairs are 1.8-1.85 m apart and wide-base "
                     "singles 1.9-2.1 m; narrower puts the inner duals on the spring seats, wider is beyond "
                     "the 2.55 m legal width"),
    "spring_rate_front_N_per_m": (2e4, 3e6, "N/m", "a steer axle's leaf spring is 200-400 kN/m and an air spring "
                                  "50-300 kN/m; softer sags through the 0.3 m travel, stiffer is a rigid axle"),
    "spring_rate_rear_N_per_m": (2e4, 3e6, "N/m", "a drive axle's leaf spring is 500-1000 kN/m and an air spring "
                                 "50-300 kN/m; softer sags through the 0.3 m travel, stiffer is a rigid axle"),
    "spring_damping_front_Ns_per_m": (0.0, 1e5, "N s/m", "a truck damper is 5-20 kN s/m; 100 kN s/m is beyond "
                                      "the critical damping of an axle on its springs"),
    "spring_damping_rear_Ns_per_m": (0.0, 1e5, "N s/m", "a truck damper is 5-20 kN s/m; 100 kN s/m is beyond "
                                     "the critical damping of an axle on its springs"),
}

#: N/m, per spring: an air spring's rate at the empty truck's static load when the description gives
#: none, {front, rear}. **Estimate**: air suspensions are tuned to a ride frequency of about 1.3 Hz
#: (1.0-1.5 Hz), k = m (2 pi f)^2 with m the empty catalogue truck's sprung mass per spring by the
#: lever rule (front 1560 kg: 1.04e5 N/m; rear 1040 kg: 6.9e4 N/m), rounded.
AIR_RATE_N_PER_M = {"front": 1.0e5, "rear": 7.0e4}
#: N s/m, per spring: an air axle's damper when the description gives none, {front, rear}.
#: **Estimate**: 30 % of critical at the catalogue's 3640 kg payload (2 zeta sqrt(k m): front
#: 2000 kg on 1.33e5 N/m, 9.8 kN s/m; rear 2420 kg on 1.62e5 N/m, 11.9 kN s/m), rounded; dampers
#: of air suspensions give 20-40 % of critical, as the leaves' friction no longer damps.
AIR_DAMPING_NS_PER_M = {"front": 1.0e4, "rear": 1.2e4}
#: N/m: one wide-base single tire's vertical stiffness when the description gives none.
#: **Estimate**: a wide-base single (445/50R22.5 class) carries a dual pair's load on two sidewalls
#: instead of four; about 0.8 of the pair's 1.8 MN/m, 1.5 times a conventional tire's 0.9 MN/m.
SINGLE_TIRE_STIFFNESS_N_PER_M = 1.44e6
#: N s/m: one wide-base single tire's damping when the description gives none (**estimate**: 0.8 of
#: the dual pair's 3 kN s/m, as its stiffness).
SINGLE_TIRE_DAMPING_NS_PER_M = 2.4e3
#: m: each dual tire's distance from its pair's centre (truck_rig.xml's drawing: 1.08 and 0.75 m
#: either side of the 0.915 m pair centre).
DUAL_HALF_SPACING_M = 0.165
#: m: a wide-base single's half width as drawn (a 445 mm section: 0.22 m).
SINGLE_HALF_WIDTH_M = 0.22


def described(variant) -> bool:
    """Whether ``variant`` gives any field of :data:`DESCRIPTION_FIELDS` (else the XML's geometry)."""
    return any(getattr(variant, k) is not None for k in DESCRIPTION_FIELDS)


def suspension_of(variant, front: bool) -> str:
    """``"leaf"`` or ``"air"``: the kind of suspension of the front (``front``) or rear axle."""
    value = variant.suspension_front if front else variant.suspension_rear
    return "leaf" if value is None else value


def _axle_x(spec) -> tuple[float, float]:
    return (float(spec.body(names.axle_body("fl")).pos[0]), float(spec.body(names.axle_body("rl")).pos[0]))


def apply_geometry(spec, variant) -> None:
    """Move the axles, hangers, wheel sites, pans and drawing to ``variant``'s wheelbase and tracks, and
    fit the rear wheels as duals or wide-base singles; the XML's where a field is None.

    With another wheelbase the chassis' centre of mass keeps its share of the wheelbase (the XML's 2.0 m
    behind the front axle of 5.0 m: 40 %), as do the payload's default x (-1.3 m: 76 % behind the front
    axle) and the cab's place over the steer axle (0.6 m ahead of it); the chassis' pitch inertia keeps
    its radius of gyration's share of the wheelbase (0.44) and scales with its square, unless
    ``chassis_pitch_inertia_kg_m2`` is given. With another track each axle's roll inertia scales with
    the track's square (the wheel ends carry most of it)."""
    v = variant
    x_f, x_r = _axle_x(spec)
    wb0 = x_f - x_r
    if v.wheelbase_m is not None:
        s = float(v.wheelbase_m) / wb0
        half = 0.5 * float(v.wheelbase_m)
        for corner in names.CORNERS:
            x = half if corner in names.FRONT else -half
            spec.body(names.axle_body(corner)).pos = [x, *spec.body(names.axle_body(corner)).pos[1:]]
            spec.site(f"hanger_{corner}").pos = [x, *spec.site(f"hanger_{corner}").pos[1:]]
            pan = spec.body(names.pan_body(corner))
            pan.pos = [x, *pan.pos[1:]]
        chassis = spec.body("chassis")
        chassis.ipos = [float(chassis.ipos[0]) * s, *chassis.ipos[1:]]
        inertia = np.array(chassis.inertia, dtype=float)
        old = inertia.copy()
        inertia[1] *= s ** 2
        inertia[2] = old[2] * (inertia[0] + inertia[1]) / (old[0] + old[1])  # yaw: held by the rig, kept a moment
        chassis.inertia = inertia
        payload = spec.body("payload")
        payload.pos = [float(payload.pos[0]) * s, *payload.pos[1:]]
        cab = spec.geom("cab")
        cab.pos = [float(cab.pos[0]) - x_f + half, *cab.pos[1:]]
        bed = spec.geom("bed")
        bed.pos = [float(bed.pos[0]) * s, *bed.pos[1:]]
        bed.size = [float(bed.size[0]) * s, *bed.size[1:]]
        for rail in ("rail_left", "rail_right"):  # from 1.4 m behind the rear axle to 0.8 m ahead of the front
            g = spec.geom(rail)
            g.size = [float(g.size[0]) - 0.5 * wb0 + half, *g.size[1:]]
    for axle, track in ((names.FRONT, v.track_front_m), (names.REAR, v.track_rear_m)):
        if track is not None:
            _set_track(spec, axle, float(track))
    if v.rear_tires == "single":
        _single_rear(spec)


def _set_track(spec, corners: tuple[str, ...], track: float) -> None:
    """Put ``corners``' wheel sites, wheel geoms and pans at +-track / 2, the axle's roll inertia scaled."""
    y0 = abs(float(spec.site(names.wheel_site(corners[0])).pos[1]))
    for corner in corners:
        y = 0.5 * track * (1.0 if corner.endswith("l") else -1.0)
        site = spec.site(names.wheel_site(corner))
        shift = y - float(site.pos[1])
        site.pos = [site.pos[0], y, site.pos[2]]
        for geom in (f"wheel_{corner}", f"wheel_{corner}_outer", f"wheel_{corner}_inner"):
            g = spec.geom(geom)
            if g is not None:
                g.pos = [g.pos[0], float(g.pos[1]) + shift, g.pos[2]]
        pan = spec.body(names.pan_body(corner))
        pan.pos = [pan.pos[0], y, pan.pos[2]]
    axle = spec.body(names.axle_body(corners[0]))
    scale = (0.5 * track / y0) ** 2
    axle.inertia = np.asarray(axle.inertia, dtype=float) * np.array([scale, 1.0, scale])


def _single_rear(spec) -> None:
    """One wide-base tire per rear station at the pair's centre instead of a dual pair (drawing only:
    the physics is the station's tire element; its default stiffness and damping are set by
    :func:`apply_suspension`'s caller, :data:`SINGLE_TIRE_STIFFNESS_N_PER_M`)."""
    axle = spec.body(names.axle_body("rl"))
    for corner in names.REAR:
        outer = spec.geom(f"wheel_{corner}_outer")
        looks = dict(type=outer.type, rgba=list(outer.rgba), group=outer.group)
        radius = float(outer.size[0])
        spec.delete(outer)
        spec.delete(spec.geom(f"wheel_{corner}_inner"))
        y = float(spec.site(names.wheel_site(corner)).pos[1])
        axle.add_geom(name=f"wheel_{corner}", pos=[0.0, y, 0.0], size=[radius, SINGLE_HALF_WIDTH_M, 0.0],
                      quat=[np.sqrt(0.5), np.sqrt(0.5), 0.0, 0.0],  # the cylinder's axis along y, as the XML's wheels
                      contype=0, conaffinity=0, density=0.0, **looks)


def lever_loads(bodies, x_f: float, x_r: float, y_corners) -> np.ndarray:
    """Each corner's share (fl fr rl rr) of the bodies' weights by the lever rule.

    Each body's weight splits between the axles in proportion to its distance from the other axle
    (``x_f``, ``x_r``: the front and rear axle's x, m); its moment about the centreline splits
    between an axle's two corners, ``y_corners`` (m, + left) apart, each axle taking the share of
    the moment it takes of the weight.

    Parameters
    ----------
    bodies : iterable of (float, array_like)
        Each body's weight (N) and its centre of mass (x, y, ...) (m).
    x_f, x_r : float, m
    y_corners : sequence of float, m
        Each corner's y, in :data:`~rigsim.mjcf.names.CORNERS` order.

    Returns
    -------
    numpy.ndarray, N, (4,)
    """
    out = np.zeros(4)
    for weight, pos in bodies:
        front = (pos[0] - x_r) / (x_f - x_r)
        for i, (corner, y) in enumerate(zip(names.CORNERS, y_corners)):
            share = front if corner in names.FRONT else 1.0 - front
            out[i] += weight * share * (0.5 + pos[1] / (2.0 * abs(y)) * np.sign(y))
    return out


def spring_loads(spec, payload: bool = True) -> np.ndarray:
    """Each spring's static load (N, compression positive, corners fl fr rl rr) by the lever rule
    (:func:`lever_loads`, across each axle's two springs, 0.9 m apart) on the spec's chassis and
    payload (``payload=False``: the empty truck), at the design pose."""
    g = -float(spec.option.gravity[2])
    chassis, body = spec.body("chassis"), spec.body("payload")
    masses = [(float(chassis.mass), np.array(chassis.ipos, dtype=float))]
    if payload:
        masses.append((float(spec.geom("payload_box").mass), np.array(body.pos, dtype=float)))
    springs_y = [float(spec.site(f"hanger_{corner}").pos[1]) for corner in names.CORNERS]  # + left
    return lever_loads([(m * g, pos) for m, pos in masses], *_axle_x(spec), springs_y)


def _design_gap(spec, corner: str) -> float:
    """m: hanger-to-seat distance at the design pose (truck_rig.xml: 0.3 m)."""
    hanger = np.array(spec.site(f"hanger_{corner}").pos, dtype=float)
    seat = np.array(spec.body(names.axle_body(corner)).pos, dtype=float) + np.array(spec.site(f"seat_{corner}").pos,
                                                                                    dtype=float)
    return float(np.linalg.norm(hanger - seat))


def apply_suspension(spec, variant) -> None:
    """Set each axle's springs to ``variant``'s kind, rate and damping; the XML's where None.

    A leaf axle given a rate keeps the XML's design load at the design gap (its free length
    L0 = gap + F_design / k, F_design the XML's (L0 - gap) k), so another rate changes the truck's
    dynamics and not its ride height under the catalogue's load. An air axle: friction 0 unless
    given, its damping, and per spring k = k_empty F / F_empty (:func:`spring_loads`) with the free
    length gap + F_empty / k_empty, so that it rests at the design gap at any payload. Call after the
    payload and the masses are set (the loads read them), before the per-station factors."""
    v = variant
    loads, empty = None, None
    for axle, corners in (("front", names.FRONT), ("rear", names.REAR)):
        kind = suspension_of(v, axle == "front")
        rate = getattr(v, f"spring_rate_{axle}_N_per_m")
        damping = getattr(v, f"spring_damping_{axle}_Ns_per_m")
        if kind == "air":
            if loads is None:
                loads, empty = spring_loads(spec), spring_loads(spec, payload=False)
            rate = AIR_RATE_N_PER_M[axle] if rate is None else float(rate)
            damping = AIR_DAMPING_NS_PER_M[axle] if damping is None else damping
        for corner in corners:
            tendon = spec.tendon(names.spring_tendon(corner))
            stiffness = np.array(tendon.stiffness, dtype=float)
            gap = _design_gap(spec, corner)
            if kind == "air":
                i = names.CORNERS.index(corner)
                stiffness[0] = rate * loads[i] / empty[i]
                tendon.springlength = [gap + empty[i] / rate, gap + empty[i] / rate]
                if getattr(v, f"spring_friction_{axle}_N") is None:
                    tendon.frictionloss = 0.0
            elif rate is not None:
                design_load = (float(tendon.springlength[0]) - gap) * stiffness[0]
                stiffness[0] = float(rate)
                tendon.springlength = [gap + design_load / float(rate)] * 2
            tendon.stiffness = stiffness
            if damping is not None:
                value = np.array(tendon.damping, dtype=float)
                value[0] = float(damping)
                tendon.damping = value
