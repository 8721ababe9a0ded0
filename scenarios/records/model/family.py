"""The model family: which fields of the truck model the calibration can fit, their units and search ranges.

What is fitted, and why (:data:`FITTED`): the fields of :class:`rigsim.mjcf.variant.TruckVariant` that a
lab does not know to better than ~10-30 % and that change the wheel forces:

* ``payload_kg``, ``payload_x_m``: the ballast's mass and its position along the truck set the
  static loads and the body's bounce and pitch; the first guess comes from the measured static
  loads (:func:`~rigsim.scenarios.records.model.first_guess.static_guess`), the fit refines them;
  ``payload_y_m``, its centre across the truck, is held where the measured left/right moment puts it
  (:func:`~rigsim.scenarios.records.model.first_guess.static_lateral`): the four static loads pin it;
* ``payload_z_m``, the height of the payload's centre of mass, fitted from the XML's 0.56 m (a
  0.8 m stack on the bed), searched 0.5 m either way within :data:`rigsim.mjcf.variant.BOUNDS`: the
  static loads say nothing of it, but it sets the sprung mass's pitch and roll inertia about its
  centre of mass, and so the body's bounce and pitch modes the front wheels feel; a lab knows a
  stack's height only roughly (a taller stack of lighter goods, or a low one of steel), and a
  model that holds the XML's height puts the difference into the front leaf friction and tire
  values. Where the truck is empty there is no payload to raise or lower (and where it is light,
  under :data:`~rigsim.scenarios.records.model.first_guess.LIGHT_FRACTION` of the empty truck, its
  height barely matters), and the chassis' pitch inertia (``chassis_pitch_inertia_kg_m2``,
  from the XML's 25 200 kg m^2, searched 0.5-2 times it, :data:`EMPTY_STAND_IN`) is fitted in
  its place: a chassis with its tanks, body and equipment is not the catalogue's, and with little
  or no payload nothing else sets the body's pitch mode; on a loaded truck it is held (the payload's height and the chassis' inertia trade against each other);
* ``chassis_roll_inertia_kg_m2``, on a described truck only, beside the body's pitch (from the XML's
  2600 kg m^2, searched 0.75-2 times it, the model's cab needing ~1700 kg m^2 of it,
  :data:`~rigsim.scenarios.records.model.calibrate.DESCRIBED_ROLL`): a spec sheet gives no roll inertia,
  and on soft air springs or worn dampers the body's roll mode sits low (0.3-0.7 Hz), lightly
  damped, where the road's cross-slope excites it;
* ``tire_stiffness_front/rear_N_per_m``, ``tire_damping_front/rear_Ns_per_m``: per axle (left and
  right tires are the same type); they set the wheel-hop modes (~10 Hz) and the force a pan's
  motion puts straight through the tire;
* ``spring_friction_front/rear_N``: the leaf springs' interleaf friction per axle, the truck's
  main nonlinearity (it locks the springs at small amplitude); searched from 0.05 to 8 times the
  catalogue guess, since a worn or dry multi-leaf spring sticks far harder than a new one;
* ``axle_mass_front/rear_kg``: the unsprung masses, which set the wheel-hop frequencies with the
  tire stiffness (the two are told apart by the hop mode's force through the tire against the
  pan's motion); the first guess is the truck's specification (:mod:`~rigsim.scenarios.records.model.first_guess`),
  searched 0.6-1.8 times it within :data:`rigsim.mjcf.variant.BOUNDS` (a heavy drive axle with dual
  wheels and drum brakes weighs far more than a light steer axle);
* ``tire_progressive_ratio``, ``tire_progressive_onset_m`` (front tires) and
  ``tire_progressive_ratio_rear``, ``tire_progressive_onset_rear_m``: each axle's tire stiffening, a
  bilinear tire (``TruckVariant.tire_progressive_ratio``: stiffness kt up to the onset deflection,
  (1 + ratio) kt beyond it); a pneumatic tire stiffens over its working deflection, and a model
  whose tire is linear cannot follow it (docs/model_correction.md). The ratio from a catalogue
  guess of +20 % (:mod:`~rigsim.scenarios.records.model.first_guess`), searched additively
  (:data:`ADDITIVE`: 0-0.7); the onset as the wheel load where the tire stiffens, within the loads
  the windows measure on its axle, from the axle's static load
  (:mod:`~rigsim.scenarios.records.model.onset_load`, which says why: an onset beyond every
  measured load has no gradient, nor has its ratio); a linear-tire truck fits the ratio to ~0,
  where the onset is not identifiable and does not matter;
* ``tire_stiffness_factor_fl``, ``tire_stiffness_factor_rl``, ``tire_damping_factor_fl``,
  ``tire_damping_factor_rl``, ``spring_rate_factor_fl``, ``spring_rate_factor_rl``,
  ``spring_friction_factor_fl``, ``spring_friction_factor_rl`` (:data:`STATION_FITTED`): each axle's
  left tire (its stiffness and its damping), leaf spring and interleaf friction over its right one
  (:mod:`rigsim.mjcf.stations`), from 1; a real truck's left and right differ (a tire at another pressure,
  of another make or warmer, a spring with a broken leaf, leaves that rust and rub harder), and a
  model whose axles are symmetric puts the difference into both wheels' errors, in opposite
  directions. Rates are searched at 0.7-1.3, the tire damping at 0.5-2 (the plant's range,
  :data:`rigsim.mjcf.stations.STATION_FACTORS`), the friction at 0.4-2.5: two springs of one truck whose
  leaves rub 0.7 and 1.4 times the catalogue's differ by a factor of 2. The tire damping sets the
  wheel-hop peak (~10 Hz), which on a rough road carries most of the rear wheels' dynamic force; the
  mismatch suite's plants (``benchmarks/mismatch_suite.py``) draw each tire's damping 0.8-1.25 times
  its axle's, and an empty truck on a class D road among them (gen03) needs each left tire's own to
  bring its rear wheels under half the linear floor;
* ``cab_mount_hz``, on request only (``names=FITTED``; :data:`DEFAULT_NAMES` hold the XML's rigid
  cab): the cab on its own mounts (``TruckVariant.cab_mount_hz``), a mode next to the body's
  bounce and pitch that loads the front wheels. A model without it absorbs a suspended cab's mode
  into the front leaf friction and misses the front wheels' road DLC. Fitted through its
  compliance (:data:`COMPLIANCE`), 1-30 Hz from a 2.5 Hz guess; on the paper's rough roads a rigid
  cab fits to the top, 30 Hz, at no loss, but on a smooth road at low speed the fit can wander to
  the bottom and spoil the front wheels (:data:`DEFAULT_NAMES`), which is why it is not fitted by
  default. The cab's mass is never fitted: it is locally identifiable on a suspended cab but not
  on a rigid one; the price is a larger front-wheel error where the plant's cab mass differs from
  the model's.
* ``frame_torsion_hz``, ``frame_bending_hz`` (:data:`FRAME_FITTED`), on a described truck only, where
  they make the fit clearly better (:mod:`~rigsim.scenarios.records.model.frame_choice`): the ladder frame's first torsion
  and vertical bending modes (``TruckVariant.frame_torsion_hz``, :mod:`rigsim.mjcf.frame`: the
  chassis cut at mid-wheelbase into two halves on a torsion and a bending hinge, damped at
  :data:`rigsim.mjcf.frame.FRAME_DAMPING_RATIO`). A spec sheet gives a frame's rail section and
  length, not its modes with the cab, body, tanks and load bolted on (5-12 Hz, the catalogue guess
  the middle, :data:`~rigsim.scenarios.records.model.first_guess.CATALOGUE_FRAME_HZ`). The modes sit
  among the wheel-hop modes and above the body's, where the rig excites the truck: a rigid-frame
  model puts a flexible frame's twist and bend into the tires, the friction and the masses, and
  misses the wheels the frame loads (fleet suite, development draw, 30 s: a 6 m leaf truck whose
  only structure beyond the family is its frame, bending at 8.37 Hz, fits 8.31 Hz and its model
  error falls from 0.17-0.18 to 0.05-0.08; a torsion mode a coherent road does not excite stays
  near its guess, at no loss). Beside an engine on mounts, a suspended cab and a frame cut elsewhere,
  the fit from the 9 Hz guess may stop in a worse minimum than the rigid frame's (fleet07, 15, 16 of
  that draw: model error up to 1.5 times the rigid frame's, its fit NRMSE worse alike), or a far
  better one (fleet18: rear wheels 0.25 of the linear correction's NRMSE against 0.79). Fitted through their compliance (:data:`COMPLIANCE`),
  3-20 Hz (:data:`rigsim.mjcf.frame.BOUNDS`; at 20 Hz a frame is rigid for the road's input).
  Where the frame is cut and how much it is damped are held (mid-wheelbase, 4 %): a real frame's
  flexibility is spread along it and concentrates behind the cab or at the body's front mount, which
  the fleet suite's plants draw (``TruckVariant.frame_hinge_share``, ``frame_damping_ratio``) and
  the model does not. The catalogue truck keeps the XML's rigid chassis.
* ``engine_mount_hz``, ``engine_mass_kg`` (:data:`ENGINE_FITTED`), on a described truck only, where
  they make the fit clearly better (:mod:`~rigsim.scenarios.records.model.frame_choice`, after the
  frame): the engine and gearbox as their own body on rubber mounts (:mod:`rigsim.mjcf.engine`,
  taken out of the chassis' mass, which keeps the truck's mass and centre of mass). A truck's engine
  bounces on its mounts at 6-12 Hz, among the wheel-hop modes, and with 0.7-1.3 t it is a tenth of
  a laden two-axle truck's sprung mass over the front axle: a model without it puts its mode into
  the front tires and the frame. From 9 Hz and 1 t (:data:`rigsim.mjcf.engine.ENGINE_MASS_KG`),
  searched 5-20 Hz (through its compliance) and 0.3-1.5 t (:data:`rigsim.mjcf.engine.BOUNDS`); the
  mounts' damping and the engine's place are held (:mod:`rigsim.mjcf.engine`'s estimates).
* ``damper_digressive_knee_m_per_s``, ``damper_digressive_ratio``, ``damper_rebound_ratio``
  (:data:`DAMPER_FITTED`), on a described truck only, always, after the engine: the spring dampers
  digressive (:mod:`rigsim.mjcf.dampers`), their slope beyond the knee a fraction of the slope below
  it, and harder in rebound than in bump (:func:`rigsim.mjcf.stations.add_rebound_damping`), all four
  alike. A new vehicle damper's blow-off valves open at 0.1-0.3 m/s and beyond it its force grows at
  a fifth to a half of its low-speed slope; a worn one is linear; a linear damper fitted to a
  digressive one takes a slope between the two and errs at both ends of the speeds a rough road
  drives. Dampers are valved 2-4 times harder in rebound than in bump: a symmetric damper fitted to
  such a one misses the force's asymmetry, which the rig's large strokes at the wheel-hop modes show.
  Held at 0.15 m/s, 0.95 and 2 until fitted (nearly linear, the low end of the rebound's valving:
  :mod:`~rigsim.scenarios.records.model.frame_choice` says why), searched 0.05-0.5 m/s, 0.2-1
  (:data:`rigsim.mjcf.dampers.BOUNDS`; 1 is a linear damper) and 1-5
  (:data:`rigsim.mjcf.variant.BOUNDS`; 1 is symmetric); the slope below the knee in bump is each
  axle's fitted damping.

The truck is the one the scenario's ``[vehicle]`` describes (its wheelbase, tracks, rear tires,
suspensions, spring rates and dampers: :data:`~rigsim.scenarios.records.model.first_guess.SPEC_FIELDS`),
held at the given values: a spec sheet states its geometry. Its springs' rates and dampers per axle
(:data:`AIR_FITTED`, :func:`~rigsim.scenarios.records.model.first_guess.spring_fields`) are fitted beside
the axle's interleaf friction, searched 0.5-2 and 0.3-3 times the catalogue guess: a spec sheet
quotes an air spring's rate at one load and pressure and a leaf spring's to 5-10 %, and dampers wear
to a third of their force. An **air axle** has no interleaf friction, but its bushings and its
dampers' seals rub: its friction is fitted from a small guess
(:data:`~rigsim.scenarios.records.model.first_guess.AIR_FRICTION_GUESS_N`), one value for the axle.

Not fitted: the chassis (5.2 t, its CoM and inertia; the payload's height stands in for a
sprung mass whose pitch inertia is not the XML's, and on an empty truck the pitch inertia itself
is fitted, :data:`EMPTY_STAND_IN`), the cab's mass (the
model's :data:`rigsim.mjcf.cab.CAB_MASS_KG`) and the leaf springs' rate (but for the left/right factors)
and viscous damping are held at their catalogue (XML) values; the tire free radius only moves
the static ride height, and the pan mass does not enter a tire force whose pans follow a given
motion, so neither can be identified from x_a and F_rig. How well each fitted field is pinned
shows in its 1-sigma (:class:`~rigsim.scenarios.records.model.result.Calibration`); the onset of a tire
that does not stiffen (ratio fitted to ~0) changes nothing, and its sigma says so. A tire whose
wheels never leave the stiff branch (the heavy truck's front tires) trades its stiffness against
its ratio; that is why each axle has its own ratio and onset: one ratio shared by both axles
settles at a compromise that bends both axles' tire stiffnesses and leaves one axle's wheels far
from the plant's forces.

The fit itself: :mod:`rigsim.scenarios.records.model.calibrate`.
"""

from __future__ import annotations

__all__ = ["FITTED", "STATION_FITTED", "AIR_FITTED", "FRAME_FITTED", "ENGINE_FITTED", "DAMPER_FITTED", "DEFAULT_NAMES", "EMPTY_STAND_IN", "UNITS", "COMPLIANCE", "ADDITIVE", "RANGES"]

#: Each axle's left tire stiffness, leaf-spring rate and interleaf friction over its right one (the
#: module's description).
STATION_FITTED = ("tire_stiffness_factor_fl", "tire_stiffness_factor_rl", "tire_damping_factor_fl",
                  "tire_damping_factor_rl", "spring_rate_factor_fl", "spring_rate_factor_rl",
                  "spring_friction_factor_fl", "spring_friction_factor_rl")
#: Each axle's spring rate (an air spring's at the empty truck's load) and damper: fitted on a described
#: truck (:func:`~rigsim.scenarios.records.model.first_guess.spring_fields`), where the names fit the axle's friction.
AIR_FITTED = ("spring_rate_front_N_per_m", "spring_damping_front_Ns_per_m", "spring_rate_rear_N_per_m",
              "spring_damping_rear_Ns_per_m")
#: The frame's first torsion and bending modes: fitted on a described truck
#: (:mod:`~rigsim.scenarios.records.model.frame_choice`), both or neither.
FRAME_FITTED = ("frame_torsion_hz", "frame_bending_hz")
#: The engine on its rubber mounts, its bounce frequency and its mass (with its gearbox): fitted on a
#: described truck (:mod:`~rigsim.scenarios.records.model.frame_choice`), both or neither.
ENGINE_FITTED = ("engine_mount_hz", "engine_mass_kg")
#: The spring dampers' digressive knee and their slope beyond it over their slope below (all four
#: dampers alike): fitted on a described truck (:mod:`~rigsim.scenarios.records.model.frame_choice`),
#: both or neither.
DAMPER_FITTED = ("damper_digressive_knee_m_per_s", "damper_digressive_ratio", "damper_rebound_ratio")
#: The fields that can be fitted, in this order (:data:`DEFAULT_NAMES` are fitted by default).
FITTED = ("payload_kg", "payload_x_m", "payload_z_m", "chassis_pitch_inertia_kg_m2", "chassis_roll_inertia_kg_m2",
          "tire_stiffness_front_N_per_m", "tire_stiffness_rear_N_per_m",
          "tire_damping_front_Ns_per_m", "tire_damping_rear_Ns_per_m", "spring_friction_front_N",
          "spring_friction_rear_N", "axle_mass_front_kg", "axle_mass_rear_kg", "tire_progressive_ratio", "tire_progressive_onset_m", "tire_progressive_ratio_rear",
          "tire_progressive_onset_rear_m", "cab_mount_hz") + STATION_FITTED + AIR_FITTED + FRAME_FITTED + ENGINE_FITTED + DAMPER_FITTED
UNITS = {"payload_kg": "kg", "payload_x_m": "m", "payload_z_m": "m", "chassis_pitch_inertia_kg_m2": "kg m^2",
         "chassis_roll_inertia_kg_m2": "kg m^2",
         "tire_stiffness_front_N_per_m": "N/m",
         "tire_stiffness_rear_N_per_m": "N/m", "tire_damping_front_Ns_per_m": "N s/m",
         "tire_damping_rear_Ns_per_m": "N s/m", "spring_friction_front_N": "N", "spring_friction_rear_N": "N",
         "axle_mass_front_kg": "kg", "axle_mass_rear_kg": "kg",
         "tire_progressive_ratio": "1", "tire_progressive_onset_m": "m", "tire_progressive_ratio_rear": "1",
         "tire_progressive_onset_rear_m": "m", "cab_mount_hz": "Hz", **dict.fromkeys(STATION_FITTED, "1"),
         "spring_rate_front_N_per_m": "N/m", "spring_rate_rear_N_per_m": "N/m",
         "spring_damping_front_Ns_per_m": "N s/m", "spring_damping_rear_Ns_per_m": "N s/m",
         **dict.fromkeys(FRAME_FITTED, "Hz"), "engine_mount_hz": "Hz", "engine_mass_kg": "kg",
         "damper_digressive_knee_m_per_s": "m/s", "damper_digressive_ratio": "1", "damper_rebound_ratio": "1"}
#: The fields fitted unless the caller names others: all of :data:`FITTED` but the cab mount, which
#: is held rigid (the XML's cab) unless asked for (``names=FITTED``): on a smooth road at low speed
#: its effect on the wheel forces is too small to pin, and the fit can wander to the range's
#: bottom (generalization case gen00, class A at 30 km/h, rigid-cab plant, 20 s, the cab fitted:
#: 1.0 Hz, front wheels 1.36 of the linear floor against 0.19 with the cab held rigid; the paper's
#: rougher cases fit a rigid cab to the top, 30 Hz, and lose nothing).
DEFAULT_NAMES = tuple(k for k in FITTED if k not in ("cab_mount_hz", "chassis_pitch_inertia_kg_m2",
                                                     "chassis_roll_inertia_kg_m2") + AIR_FITTED + FRAME_FITTED
                                                     + ENGINE_FITTED + DAMPER_FITTED)
#: The payload's height's stand-in on an empty or light truck (fitted in its place where the payload is light):
#: the chassis' pitch inertia (the module's description).
EMPTY_STAND_IN = {"payload_z_m": "chassis_pitch_inertia_kg_m2"}
#: Search range of each fitted field about its first guess: (low, high) factors, or for the fields
#: of :data:`ADDITIVE` the span either side in the field's unit. Clipped to :data:`rigsim.mjcf.variant.BOUNDS`.
#: The onsets have none: their range is the loads measured on their axle (onset_load).
RANGES = {"payload_kg": (0.5, 1.5), "payload_x_m": 1.0, "payload_z_m": 0.5, "chassis_pitch_inertia_kg_m2": (0.5, 2.0),
          # down to 0.75 of the XML's: the model's cab taken off the chassis (cab_mount_hz) needs ~1700 kg m^2 of it
          "chassis_roll_inertia_kg_m2": (0.75, 2.0),
          "tire_stiffness_front_N_per_m": (0.3, 3.0),
          "tire_stiffness_rear_N_per_m": (0.3, 3.0), "tire_damping_front_Ns_per_m": (0.05, 5.0),
          "tire_damping_rear_Ns_per_m": (0.05, 5.0), "spring_friction_front_N": (0.05, 8.0),
          "spring_friction_rear_N": (0.05, 8.0), "axle_mass_front_kg": (0.6, 1.8), "axle_mass_rear_kg": (0.6, 1.8),
          "tire_progressive_ratio": 0.5,
          "tire_progressive_ratio_rear": 0.5, "cab_mount_hz": (0.4, 12.0),
          **dict.fromkeys(STATION_FITTED, (0.7, 1.3)),
          "tire_damping_factor_fl": (0.5, 2.0), "tire_damping_factor_rl": (0.5, 2.0),
          "spring_friction_factor_fl": (0.4, 2.5), "spring_friction_factor_rl": (0.4, 2.5),
          # an air spring's rate is quoted at one load and pressure, its damper's at one speed
          "spring_rate_front_N_per_m": (0.5, 2.0), "spring_rate_rear_N_per_m": (0.5, 2.0),
          "spring_damping_front_Ns_per_m": (0.3, 3.0), "spring_damping_rear_Ns_per_m": (0.3, 3.0),
          # from the 9 Hz guess to rigsim.mjcf.frame.BOUNDS' 3-20 Hz
          **dict.fromkeys(FRAME_FITTED, (1.0 / 3.0, 20.0 / 9.0)),
          # from the 9 Hz and 1 t guesses to rigsim.mjcf.engine.BOUNDS' 5-20 Hz and 0.3-1.5 t
          "engine_mount_hz": (5.0 / 9.0, 20.0 / 9.0), "engine_mass_kg": (0.3, 1.5),
          # from the 0.15 m/s and 0.95 guesses to the whole of rigsim.mjcf.dampers.BOUNDS' 0.05-0.5 m/s and 0.2-1,
          # and from the rebound's 2 to the whole of rigsim.mjcf.variant.BOUNDS' 1-5
          "damper_digressive_knee_m_per_s": (1.0 / 3.0, 10.0 / 3.0), "damper_digressive_ratio": (0.2, 2.0),
          "damper_rebound_ratio": (0.5, 2.5)}
#: Fields searched and scaled additively (their :data:`RANGES` entry: the span either side of the
#: guess, in the field's unit, theta = 1 at the guess and 0 at its low end; clipped to
#: :data:`rigsim.mjcf.variant.BOUNDS`): the payload's x, which may be either sign, and the progressive tire's
#: ratio, whose linear tire is ratio 0; the onsets are searched as loads, N, their range and span
#: the loads measured on their axle (:mod:`~rigsim.scenarios.records.model.onset_load`).
ADDITIVE = ("payload_x_m", "payload_z_m", "tire_progressive_ratio", "tire_progressive_onset_m", "tire_progressive_ratio_rear",
            "tire_progressive_onset_rear_m")
#: Fields fitted through their compliance, theta = (guess / value)^2, not their value: the cab
#: mount's and the frame's frequencies, whose effect on the wheel forces fades as 1 / f^2 towards a
#: rigid cab or frame (a frequency scale would crawl along that flat valley).
COMPLIANCE = ("cab_mount_hz",) + FRAME_FITTED + ("engine_mount_hz",)
