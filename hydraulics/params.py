"""SI parameters of one DYNTRAC servo-hydraulic actuator (servovalve, chambers, pan, controller).

The defaults describe the FHWA DYNTRAC rig of the paper ("Correction of dynamic wheel forces
measured on road simulators"): four 156 kN actuators at 21 MPa supply, 380 lpm three-stage
servovalves, 15.2 cm stroke, LVDT position feedback plus differential-pressure feedback.
Values the paper does not give are typical figures from Merritt, *Hydraulic Control Systems*
(Wiley 1967), and servovalve data sheets; each default carries its source or reasoning.

Conventions
-----------
* All interfaces are SI (m, s, kg, N, Pa, m^3/s). Pressures are gauge (relative to atmosphere).
* Chamber 1 pushes the pan up, chamber 2 pulls it down; the piston is double-ended (equal areas,
  the structure the paper's eq. 4 assumes), so the force is ``A (P1 - P2) - b v``.
* The spool position is normalised: 1 is the rated opening (rated flow at rated valve drop);
  the command ``u`` is normalised too (1 = rated current), spool = ``ksv * sat(u)`` at rest.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

__all__ = ["ActuatorParams", "STATE_NAMES", "INPUT_NAMES", "GRAVITY_M_S2"]

#: Labelled activation states of one actuator (python-control style), in this order.
#: spool: normalised spool position (1 = rated opening); spool_rate: 1/s;
#: p1_MPa, p2_MPa: chamber pressures in MPa (scaled so mjd_transitionFD's single eps suits them);
#: integral_m_s: time integral of the position error x_ref - x_a, m s.
STATE_NAMES = ("spool", "spool_rate", "p1_MPa", "p2_MPa", "integral_m_s")

#: Inputs of the actuator dynamics: drive signal x_ref (m), pan position x_a (m, 0 = mid-stroke,
#: + up), pan velocity v_a (m/s).
INPUT_NAMES = ("x_ref_m", "x_a_m", "v_a_m_s")

#: Standard gravity (m/s^2), the value the project's MuJoCo models use.
GRAVITY_M_S2 = 9.81

@dataclass(frozen=True)
class ActuatorParams:
    """Parameters of one servo-hydraulic wheelpan actuator and its analog controller.

    Parameters
    ----------
    supply_pressure_Pa : float, Pa
        Supply pressure (gauge).
    return_pressure_Pa : float, Pa
        Return-line back pressure (gauge).
    rated_flow_m3_s : float, m^3/s
        Servovalve rated flow at ``rated_valve_drop_Pa`` and full (rated) opening.
    rated_valve_drop_Pa : float, Pa
        Total valve pressure drop of the rating (both metering lands; each land drops half).
    spool_hz : float, Hz
        Natural frequency of the second-order spool dynamics; ``math.inf`` makes the valve static
        (spool = ``ksv * sat(u)`` instantly; the spool states then only monitor it with a 1 ms lag).
    spool_damping : float, 1
        Damping ratio of the spool dynamics.
    ksv : float, 1
        Static servovalve gain: normalised spool opening per unit normalised command (paper's Ksv).
    command_limit : float, 1
        Saturation of the normalised valve command (1 = rated current); the command is clipped
        smoothly (linear up to 80 % of the limit, then an exponential approach to it).
    null_opening : float, 1
        Width of the smoothed null region of the metering edges, as a fraction of the rated
        opening: each edge opens ``(xv + sqrt(xv^2 + null_opening^2)) / 2``; this is the valve's
        null leakage (an ideal critically-lapped valve is ``0``).
    laminar_drop_Pa : float, Pa
        Below this drop across a metering land the square-root orifice law is replaced by a
        cubic laminar core matched in value and slope (keeps explicit Euler stable near zero drop).
    piston_area_m2 : float, m^2
        Effective piston area of each chamber (double-ended actuator).
    stroke_m : float, m
        Total stroke; qpos 0 is mid-stroke so the pan travels +- stroke/2.
    dead_volume_m3 : float, m^3
        Oil volume of each chamber at its end of stroke: valve ports, manifold, hoses, end
        clearance. A chamber holds ``dead_volume_m3 + piston_area_m2 * (stroke_m/2 +- x)``.
    bulk_modulus_Pa : float, Pa
        Effective bulk modulus of the oil column (oil, entrained air, hose and cylinder compliance).
    leakage_m3_s_Pa : float, m^3/(s Pa)
        Cross-piston (internal) leakage coefficient, flow = leakage * (P1 - P2) (Merritt's Ctp).
    cavitation_pressure_Pa : float, Pa
        Gauge pressure at which the oil column loses its stiffness (gas release, cavitation).
    cavitation_band_Pa : float, Pa
        Width of the band above ``cavitation_pressure_Pa`` over which the effective bulk modulus
        falls smoothly (smoothstep) from its nominal value to ``cavitation_min_fraction`` of it;
        below the cavitation pressure it falls linearly to zero over 1 % of the band, so the
        pressure cannot pass ``cavitation_pressure_Pa - 0.01 * cavitation_band_Pa`` (hard floor).
    cavitation_min_fraction : float, 1
        Fraction of the bulk modulus left at the cavitation pressure; a chamber whose net inflow
        is positive uses at least this fraction even below the cavitation pressure, so a
        chamber pulled down to the hard floor refills and recovers.
    relief_pressure_Pa : float, Pa
        Cracking pressure of the chamber relief (upper physical bound of the chamber pressure).
    relief_conductance_m3_s_Pa : float, m^3/(s Pa)
        Relief flow per Pa above the cracking pressure.
    pan_mass_kg : float, kg
        Moving mass of wheelpan plus piston/rod (the MuJoCo model's pan body mass).
    friction_N_s_m : float, N s/m
        Viscous friction of piston seals and pan guides.
    kp_per_m : float, 1/m
        Position-loop gain Kp: normalised valve command per metre of position error.
    ti_s : float, s
        Integral time Ti of the PI position controller ``Kp (1 + 1/(Ti s))``; ``math.inf`` = P only.
    kdp_per_Pa : float, 1/Pa
        Differential-pressure feedback gain Kdp: normalised command per Pa of ``P1 - P2``.
    design_tire_N_per_m : float, N/m
        Tire stiffness of the reference wheel station the defaults were tuned for (checked by
        :func:`rigsim.hydraulics.loop.check_design_station` when a rig is built).
    design_load_mass_kg : float, kg
        Unsprung mass of that reference wheel station (``math.inf`` = tire to ground).

    Notes
    -----
    Construction only validates each value (type, sign, finiteness, pressure ordering); it
    never checks the closed loop. Stability is a property of the parameters *and* a load:
    use :func:`rigsim.hydraulics.loop.check_stable` / :func:`rigsim.hydraulics.loop.assert_stable` with a
    tire and unsprung mass, or :func:`rigsim.hydraulics.loop.check_design_station`.
    """

    # --- supply and servovalve ------------------------------------------------------------
    supply_pressure_Pa: float = 21.0e6  # DYNTRAC: 156 kN actuators at 21 MPa supply (paper, brief)
    return_pressure_Pa: float = 0.3e6  # typical return-line back pressure (filter, cooler): 0.2-0.5 MPa
    rated_flow_m3_s: float = 380.0e-3 / 60.0  # paper: 380 lpm three-stage servovalves
    rated_valve_drop_Pa: float = 7.0e6  # servovalve rating convention: 1000 psi total valve drop
    spool_hz: float = 150.0  # 3-stage valves of this size: -90 deg at ~100-200 Hz small-signal; it must
    # stay above the ~110 Hz oil-column mode, a slower valve defeats the pressure feedback
    spool_damping: float = 0.7  # typical fitted spool damping ratio of servovalve data sheets
    ksv: float = 1.0  # normalisation: rated command -> rated opening (Merritt's Ksv = 1 here)
    command_limit: float = 1.0  # controller output clipped at 100 % rated current
    null_opening: float = 0.01  # ~1 % null flow (~6 lpm internal leakage at null, 3-stage valves)
    laminar_drop_Pa: float = 2.0e6  # keeps a wide-open valve Euler-stable at dt 1e-4 s even at the end
    # of stroke (dead volume only): dt*beta/V*1.25*kv/sqrt(dl) = 0.6 < 2 (notes: smooth the sqrt law)
    # --- chambers ---------------------------------------------------------------------------
    piston_area_m2: float = 156.0e3 / 21.0e6  # 156 kN at 21 MPa (paper) -> 7.43e-3 m^2 (97 mm bore eq.)
    stroke_m: float = 0.152  # paper: 15.2 cm stroke (contract: joint range +-0.076 m)
    dead_volume_m3: float = 5.0e-4  # valve manifold, ports, ~0.5 m of 32 mm hose (4e-4), end clearance
    bulk_modulus_Pa: float = 1.0e9  # oil with entrained air and hoses: 0.7-1.4 GPa (Merritt ch. 2)
    leakage_m3_s_Pa: float = 1.0e-11  # cross-piston leakage (notes: keeps the Euler-stepped mode stable)
    cavitation_pressure_Pa: float = -0.08e6  # ~20 kPa absolute: dissolved-air release (gauge); the
    # hard floor 0.02 MPa lower is ~1 kPa absolute, the oil's vapour pressure
    cavitation_band_Pa: float = 2.0e6  # entrained air softens the oil below ~2 MPa (Merritt ch. 2);
    # wide enough that one Euler step at 1 m/s pan speed cannot jump the floor
    cavitation_min_fraction: float = 0.01  # lets a cavitated chamber recover; Euler at 1e-4 s stays
    # stable on the floor's tail up to ~2.5 m/s pan speed (dt*beta*f*A*v/(V*tail) < 2)
    relief_pressure_Pa: float = 25.0e6  # cross-port relief ~20 % above supply (usual setting)
    relief_conductance_m3_s_Pa: float = 2.0e-9  # 120 lpm per MPa override; dt*beta/V_dead*C = 0.4
    # --- mechanics --------------------------------------------------------------------------
    pan_mass_kg: float = 500.0  # steel wheelpan for truck duals (~1 m x 0.6 m plate, ribs) ~430 kg
    # + piston and rod ~70 kg; with the oil column it sets the ~110 Hz hydraulic mode
    friction_N_s_m: float = 5.0e3  # seal/guide viscous friction, 1-10 kN s/m for 150 kN actuators
    # --- controller (analog PI position loop + differential-pressure feedback) --------------
    kp_per_m: float = 50.0  # velocity constant Ksv*Kq*Kp/A = 73 1/s: 15.5 Hz bandwidth on a 1 MN/m tire
    # to ground, 6 dB gain margin (tuned with rigsim.hydraulics.loop over tires 0.9-1.8 MN/m, 300-600 kg)
    ti_s: float = 1.0  # Ti = 1 s: the structure under which the paper's eq. 4 is exact
    kdp_per_Pa: float = 2.0e-8  # damps the oil-column mode to zeta ~ 0.18 (Euler at 1e-4 s removes
    # omega^2 dt/2 = 24 1/s of its 126 1/s decay rate; tuned with rigsim.hydraulics.loop)
    # --- reference wheel station for rigsim.hydraulics.loop.check_design_station -------------------
    design_tire_N_per_m: float = 1.0e6  # truck tire 0.9-1.8 MN/m (brief); the soft end
    design_load_mass_kg: float = 450.0  # unsprung mass per wheel station 300-600 kg (brief)

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"actuator.{f.name} must be a real number, got {value!r}")
            if math.isnan(value):
                raise ValueError(f"actuator.{f.name} must be a number, got nan")
        positive = ("supply_pressure_Pa", "rated_flow_m3_s", "rated_valve_drop_Pa", "spool_hz",
                    "spool_damping", "ksv", "command_limit", "piston_area_m2", "stroke_m",
                    "dead_volume_m3", "bulk_modulus_Pa", "cavitation_band_Pa", "pan_mass_kg",
                    "ti_s", "design_tire_N_per_m", "design_load_mass_kg")
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"actuator.{name} must be > 0, got {getattr(self, name)!r}")
        non_negative = ("null_opening", "laminar_drop_Pa", "leakage_m3_s_Pa",
                        "relief_conductance_m3_s_Pa", "friction_N_s_m", "kp_per_m", "kdp_per_Pa")
        for name in non_negative:
            if not getattr(self, name) >= 0:
                raise ValueError(f"actuator.{name} must be >= 0, got {getattr(self, name)!r}")
        finite = [f.name for f in dataclasses.fields(self)
                  if f.name not in ("spool_hz", "ti_s", "design_load_mass_kg")]
        for name in finite:
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"actuator.{name} must be finite, got {getattr(self, name)!r}")
        if not 0.0 <= self.cavitation_min_fraction <= 1.0:
            raise ValueError("actuator.cavitation_min_fraction must lie in [0, 1], got "
                             f"{self.cavitation_min_fraction!r}")
        if not self.return_pressure_Pa < self.supply_pressure_Pa:
            raise ValueError(f"actuator.return_pressure_Pa must be below supply_pressure_Pa "
                             f"({self.supply_pressure_Pa} Pa), got {self.return_pressure_Pa}")
        if not self.cavitation_pressure_Pa - 0.01 * self.cavitation_band_Pa >= -101325.0:
            raise ValueError("actuator.cavitation_pressure_Pa - 0.01 * cavitation_band_Pa (the hard "
                             "pressure floor) must not lie below absolute vacuum (-101325 Pa gauge), got "
                             f"{self.cavitation_pressure_Pa - 0.01 * self.cavitation_band_Pa:.6g} Pa")
        if not self.cavitation_pressure_Pa < self.return_pressure_Pa:
            raise ValueError(f"actuator.cavitation_pressure_Pa must be below return_pressure_Pa "
                             f"({self.return_pressure_Pa} Pa), got {self.cavitation_pressure_Pa}")
        if not self.relief_pressure_Pa > self.supply_pressure_Pa:
            raise ValueError(f"actuator.relief_pressure_Pa must exceed supply_pressure_Pa "
                             f"({self.supply_pressure_Pa} Pa), got {self.relief_pressure_Pa}")

    # ----------------------------------------------------------------------------------------
    @property
    def half_stroke_m(self) -> float:
        """float, m: travel from mid-stroke (qpos 0) to either end."""
        return 0.5 * self.stroke_m

    @property
    def stall_force_N(self) -> float:
        """float, N: ``(supply - return) * area``, the force of the blocked, wide-open actuator."""
        return (self.supply_pressure_Pa - self.return_pressure_Pa) * self.piston_area_m2

    @property
    def mid_volume_m3(self) -> float:
        """float, m^3: oil volume of each chamber at mid-stroke (half of the paper's Vf)."""
        return self.dead_volume_m3 + self.piston_area_m2 * self.half_stroke_m

    def replace(self, **changes) -> "ActuatorParams":
        """Return a copy with ``changes`` applied (validated again)."""
        return dataclasses.replace(self, **changes)
