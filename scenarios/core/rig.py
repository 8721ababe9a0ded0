"""The one rig: the truck on the DYNTRAC wheelpans, built from a scenario, at rest, linearized, run.

:class:`Rig` is the only place that builds truck + pans (+ the four hydraulic actuators),
gives the rest state, linearizes the closed-loop plant (``mujoco.mjd_transitionFD``) and
steps it. Every command (``run``, ``paper``, ``validate``, ``iterate``, ``sweep``) and the
benchmarks use it; none keeps its own stepping loop.

Two kinds of rig:

* ``Rig(scenario, hydraulic=True)``, the rig test: the drive is the actuators' reference
  x_ref in ``ctrl``; the actuator states live in MuJoCo's activation vector and are advanced
  by the callbacks of :mod:`rigsim.hydraulics.bridge`, installed for a run only.
* ``Rig(scenario, hydraulic=False)``, the road test: the pans follow the drive exactly
  (mocap bodies whose positions and velocities each step prescribes).

:meth:`Rig.run` hands the stepping to :mod:`rigsim.scenarios.core.stepping` (the loops themselves).
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from rigsim.hydraulics.bridge import add_hydraulic_actuators, hydraulic_callbacks
from rigsim.hydraulics.equilibrium import equilibrium_activation
from rigsim.hydraulics.loop import check_design_station
from rigsim.hydraulics.params import ActuatorParams
from rigsim.mjcf import names
from rigsim.mjcf.build import build_spec
from rigsim.mjcf.physics import RigIndex, friction_disabled, static_equilibrium, tire_forces, tire_stiffness
from rigsim.mjcf.standing import MAX_GROWTH_PER_S
from rigsim.scenarios.core.config import Scenario, ScenarioError
from rigsim.scenarios.core.drive import Drive
from rigsim.scenarios.core.memory import check_memory
from rigsim.scenarios.core.plant import PlantLinearization
from rigsim.scenarios.core.road_drive import RoadDrive, road_source
from rigsim.scenarios.core.stepping import RigRecord, run_hydraulic, run_kinematic
from rigsim.scenarios.core.watch import mujoco_warnings_captured, output_schedule

__all__ = ["actuator_params", "rig_step_s", "Rig", "RIG_INTEGRATOR", "RIG_INTEGRATOR_NAME", "RIG_TIMESTEP_S"]

#: How both tests are integrated, chosen by measurement (``benchmarks/integrator_study.py``,
#: docs/integrator_study.md): MuJoCo's RK4 at 1e-3 s with the drive held at mid-step passes the
#: accuracy goals (rig DLC within 0.1 %, FRF within 0.1 dB / 1 degree to 30 Hz against Euler at
#: 2.5e-5 s; 24/24 generalization cases stable) at 0.37 of explicit Euler at 1e-4 s; the road
#: test (pans prescribed as mocap bodies) passes them too (road DLC within 0.1 %). A scenario's
#: ``vehicle.timestep_s`` overrides the step; an ``output_rate_hz`` above 1 kHz makes it the
#: output period.
RIG_INTEGRATOR = mujoco.mjtIntegrator.mjINT_RK4
RIG_TIMESTEP_S = 1e-3
#: The coarsest step a road test may be given (``Rig(timestep_s=...)``), s: with the drive held
#: over each step, the error on the truck's forces grows as the step's square, 0.0035 of their std
#: at 4e-3 s (``benchmarks/model_step.py``).
MAX_KINEMATIC_STEP_S = 4e-3
#: :data:`RIG_INTEGRATOR` as reports name it ("RK4").
RIG_INTEGRATOR_NAME = RIG_INTEGRATOR.name.removeprefix("mjINT_")


def rig_step_s(output_rate_hz: float) -> float:
    """The rig's integration step for an output at ``output_rate_hz`` (Hz), s: :data:`RIG_TIMESTEP_S`,
    or the output period where that is finer (RK4, finer)."""
    return min(RIG_TIMESTEP_S, 1.0 / float(output_rate_hz))


def actuator_params(scenario: Scenario) -> ActuatorParams:
    """The scenario's actuator parameters (defaults with the ``[actuator]`` overrides)."""
    try:
        return ActuatorParams(**dict(scenario.actuator))
    except (TypeError, ValueError) as exc:
        raise ScenarioError(str(exc)) from None


class Rig:
    """The truck of a scenario on the four-post rig.

    Parameters
    ----------
    scenario : Scenario
        Truck variant, actuator overrides (``[actuator]``), road and output rate.
    hydraulic : bool
        True: the pans are driven by the servo-hydraulic actuators (rig test); False: the pans
        follow their drive exactly (road test).
    check_stability : bool
        With ``hydraulic``: refuse actuator parameters whose loop is unstable under the design
        wheel station (:func:`rigsim.hydraulics.loop.check_design_station`) or whose closed loop under
        this truck is unstable (:meth:`check_stable`). False only to study an unstable rig.
    timestep_s : float, s, optional
        The integration step, instead of :data:`RIG_TIMESTEP_S` (or the output period, or
        ``vehicle.timestep_s``): the model correction's truck runs take their own
        (:data:`rigsim.scenarios.records.model.model_runs.MODEL_STEP_S`). Only without ``hydraulic``
        (the oil columns' modes need the rig's step).

    Raises
    ------
    ScenarioError
        Bad actuator or vehicle parameters, disagreeing pan masses, an unstable loop.
    """

    def __init__(self, scenario: Scenario, *, hydraulic: bool = True, check_stability: bool = True,
                 timestep_s: float | None = None):
        self.scenario = scenario
        self.hydraulic = bool(hydraulic)
        if timestep_s is not None and (hydraulic or not 0.0 < timestep_s <= MAX_KINEMATIC_STEP_S):
            raise ValueError(f"timestep_s = {timestep_s!r} s is for a road test (hydraulic=False) with a step in "
                             f"(0, {MAX_KINEMATIC_STEP_S:g}] s")
        self.params = params = actuator_params(scenario)
        variant = scenario.vehicle
        # The pan mass is one physical quantity with two homes (the MuJoCo pan body and the
        # actuator parameters the linear models use): the actuator's value unless the scenario
        # sets vehicle.pan_mass_kg, and two different values are refused.
        if variant.pan_mass_kg is None:
            variant = dataclasses.replace(variant, pan_mass_kg=params.pan_mass_kg)
        elif "pan_mass_kg" in scenario.actuator and scenario.actuator["pan_mass_kg"] != variant.pan_mass_kg:
            raise ScenarioError(
                f"vehicle.pan_mass_kg ({variant.pan_mass_kg:g} kg) and actuator.pan_mass_kg "
                f"({scenario.actuator['pan_mass_kg']:g} kg) disagree; set only one of them")
        self.pan_mass_kg = float(variant.pan_mass_kg)
        if hydraulic and check_stability:
            try:
                check_design_station(params)
            except ValueError as exc:
                raise ScenarioError(f"actuator: {exc}") from None
        try:
            spec = build_spec(variant, pans="slide" if hydraulic else "mocap")
        except ValueError as exc:
            raise ScenarioError(str(exc)) from None
        if hydraulic:
            # One stroke: the actuator's. The pan joints' limits are set from it.
            for c in names.CORNERS:
                spec.joint(names.pan_joint(c)).range = [-params.half_stroke_m, params.half_stroke_m]
            add_hydraulic_actuators(spec, params, names.CORNERS)
        self.model = model = spec.compile()
        #: float, s: the step of the linear models (the XML's explicit Euler step, or
        #: ``vehicle.timestep_s``), where :meth:`linearize` discretizes the plant.
        self.linear_dt_s = float(model.opt.timestep)
        model.opt.integrator = RIG_INTEGRATOR
        model.opt.timestep = (timestep_s if timestep_s is not None
                              else rig_step_s(scenario.output_rate_hz)
                              if variant.timestep_s is None else variant.timestep_s)
        self.index = RigIndex.of(model)
        obj = mujoco.mjtObj

        def sensor_adr(name_of) -> np.ndarray:
            return np.array([model.sensor_adr[mujoco.mj_name2id(model, obj.mjOBJ_SENSOR, name_of(c))]
                             for c in names.CORNERS])

        self.sensors = sensor_adr(names.tire_sensor)
        if not hydraulic:
            #: Road test: sensordata addresses of the tire tendons' lengths (m) and truck-side rates (m/s).
            self.tire_length_sensors = sensor_adr(names.tire_length_sensor)
            self.tire_rate_sensors = sensor_adr(names.tire_rate_sensor)
        if hydraulic:
            self.actuators = np.array([mujoco.mj_name2id(model, obj.mjOBJ_ACTUATOR, names.hydraulic_actuator(c))
                                       for c in names.CORNERS])
            dim = int(model.actuator_actnum[self.actuators[0]])
            self.act_index = model.actuator_actadr[self.actuators][:, None] + np.arange(dim)[None, :]
        if hydraulic and check_stability:
            self.check_stable()

    # ------------------------------------------------------------------------ properties
    @property
    def dt_s(self) -> float:
        """float, s: the simulation time step."""
        return float(self.model.opt.timestep)

    @property
    def half_stroke_m(self) -> float:
        """float, m: the actuators' travel from mid-stroke (``actuator.stroke_m / 2``)."""
        return self.params.half_stroke_m

    @property
    def tire_stiffness_N_per_m(self) -> np.ndarray:
        """numpy.ndarray, N/m, (4,): each wheel station's tire stiffness, as compiled."""
        return tire_stiffness(self.model, self.index)

    @property
    def wheelbase_m(self) -> float:
        """float, m: front-to-rear axle distance of the compiled truck."""
        data = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, data)
        sid = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, names.wheel_site(c)) for c in ("fl", "rl")]
        return float(data.site_xpos[sid[0], 0] - data.site_xpos[sid[1], 0])

    @property
    def truck_mass_kg(self) -> float:
        """float, kg: chassis, payload, axles and a suspended cab, a frame's rear half and an engine on
        mounts where the truck has them (pans excluded)."""
        ids = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, n)
               for n in (*names.TRUCK_BODIES, names.CAB_BODY, names.FRAME_REAR_BODY, names.ENGINE_BODY)]
        return float(self.model.body_mass[[i for i in ids if i >= 0]].sum())

    @property
    def unsprung_kg(self) -> np.ndarray:
        """numpy.ndarray, kg, (4,): half the mass of the axle over each pan."""
        return np.array([0.5 * self.model.body_mass[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY,
                                                                      names.axle_body(c))] for c in names.CORNERS])

    def road_source(self) -> RoadDrive:
        """The scenario's road as the four pan drives on this rig's time step, stroke-checked,
        made on demand (what a run reads chunk by chunk)."""
        return road_source(self.scenario, dt_s=self.dt_s, wheelbase_m=self.wheelbase_m,
                           half_stroke_m=self.half_stroke_m)

    def road_drive(self) -> Drive:
        """:meth:`road_source` made whole: arrays at every time step."""
        return self.road_source().drive()

    # ------------------------------------------------------------------------ rest, linear
    def rest_state(self, pan_z_m=None) -> mujoco.MjData:
        """MjData at static rest: the truck in equilibrium on the pans (at ``pan_z_m``, m,
        default mid-stroke); with the actuators, each one's pressures carrying its tire load
        plus the pan's weight and the spool at the flow balance."""
        model, data = self.model, mujoco.MjData(self.model)
        static_equilibrium(model, data, pan_z_m=np.zeros(4) if pan_z_m is None else pan_z_m)
        if self.hydraulic:
            loads = self._actuator_loads(data)
            for i, act in enumerate(self.actuators):
                data.act[self.act_index[i]] = equilibrium_activation(self.params, float(loads[i]))
                data.ctrl[act] = 0.0
            mujoco.mj_forward(model, data)
        return data

    def _actuator_loads(self, data: mujoco.MjData) -> np.ndarray:
        g = -self.model.opt.gravity[2]
        pans = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, names.pan_body(c)) for c in names.CORNERS]
        return tire_forces(self.model, data, self.index) + self.model.body_mass[pans] * g

    def static_loads_N(self) -> np.ndarray:
        """numpy.ndarray, N, (4,): each actuator's static load at rest (tire force + pan weight)."""
        return self._actuator_loads(self.rest_state())

    def linearize(self, eps: float = 1e-6) -> PlantLinearization:
        """The closed-loop plant (truck, pans, four actuators) linearized at static rest.

        ``mujoco.mjd_transitionFD`` (centred differences with step ``eps`` in the state's units)
        with the hydraulic callbacks installed and leaf-spring dry friction off (it locks the
        springs at rest and has no derivative), for the linearization only. It refuses RK4, so
        the map is that of explicit Euler at :attr:`linear_dt_s` (the result's ``dt_s``), the
        linear models' time base.
        """
        if not self.hydraulic:
            raise ValueError("linearize() needs the hydraulic rig (Rig(scenario, hydraulic=True))")
        model, data = self.model, self.rest_state()
        n = 2 * model.nv + model.na
        a, b = np.zeros((n, n)), np.zeros((n, model.nu))
        dt = self.linear_dt_s
        with hydraulic_callbacks(model), friction_disabled(model), _euler(model, dt):
            mujoco.mj_forward(model, data)
            mujoco.mjd_transitionFD(model, data, eps, True, a, b, None, None)
        c = np.zeros((8, n))
        c[np.arange(4), self.index.pan_dof] = 1.0  # no quaternions: the qpos tangent is qpos itself
        c[4 + np.arange(4), model.nv + self.index.pan_dof] = 1.0
        return PlantLinearization(a=a, b=b[:, self.actuators].copy(), c=c, dt_s=dt,
                                  kt_N_per_m=np.asarray(self.tire_stiffness_N_per_m, float),
                                  load_N=np.asarray(self._actuator_loads(data), float),
                                  unsprung_kg=self.unsprung_kg)

    def check_stable(self) -> None:
        """Refuse a rig whose linearized closed loop under this truck is unstable.

        Raises
        ------
        ScenarioError
            Naming the unstable pole and the parameters to change.
        """
        lam = self.linearize().poles()
        worst = lam[np.argmax(lam.real)]
        # A growth rate below MAX_GROWTH_PER_S is numerical noise of the finite differences around
        # the neutrally stable integrator states, not an instability over a run of minutes.
        if worst.real > MAX_GROWTH_PER_S:
            raise ScenarioError(
                f"the rig's closed loop under this truck is unstable: pole {worst.real:.3g} "
                f"{'+-' if worst.imag else ''}{abs(worst.imag):.4g}j rad/s ({abs(worst.imag) / (2 * np.pi):.1f} Hz); "
                "raise actuator.kdp_per_Pa, lower actuator.kp_per_m or raise actuator.spool_hz")
        if self.model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4:
            gain = np.abs(rk4_amplification(lam * self.dt_s))
            k = int(np.argmax(gain))
            if gain[k] > 1.0 + 1e-9:
                raise ScenarioError(
                    f"vehicle.timestep_s = {self.dt_s:g} s is too coarse for RK4: the mode at "
                    f"{abs(lam[k].imag) / (2 * np.pi):.1f} Hz ({lam[k].real:.3g} {'+-' if lam[k].imag else ''}"
                    f"{abs(lam[k].imag):.4g}j rad/s) grows by {gain[k]:.4f} per step; lower vehicle.timestep_s")

    # ------------------------------------------------------------------------ running
    def run(self, drive, *, rate_hz: float, progress=None, pose_rate_hz: float | None = None) -> RigRecord:
        """Run ``drive`` from rest and record at ``rate_hz`` from its first step at t >= 0.

        Parameters
        ----------
        drive : Drive or RoadDrive
            One sample per time step of the model (times may start below 0: a lead-in); read
            chunk by chunk (:mod:`rigsim.scenarios.core.stepping`).
        rate_hz : float, Hz
            Output rate; must divide the simulation rate.
        progress : callable, optional
            ``progress(simulated_s, total_s)``.
        pose_rate_hz : float, Hz, optional
            Also sample the bodies' poses at this (video) rate for a recording.

        Raises
        ------
        SimulationError
            A MuJoCo warning or diverging states, naming the simulated time.
        """
        if drive.n_steps > 1 and abs(drive.dt_s - self.dt_s) > 1e-9 * self.dt_s:
            raise ValueError(f"the drive's step {drive.dt_s:g} s is not the model's {self.dt_s:g} s")
        decim = 1.0 / (rate_hz * self.dt_s)
        if abs(decim - round(decim)) > 1e-9:
            raise ScenarioError(f"output_rate_hz = {rate_hz:g} Hz must divide the simulation rate "
                                f"{1.0 / self.dt_s:g} Hz")
        n_out = output_schedule(drive, self.dt_s, rate_hz)[2]
        span = drive.time_at(drive.n_steps - 1) - drive.time_at(0)
        check_memory(0, n_out, f"a drive of {span:g} s recorded at {rate_hz:g} Hz is "
                     f"{n_out:.3g} output samples", "shorten duration_s or lower output_rate_hz")
        with mujoco_warnings_captured():
            if self.hydraulic:
                return run_hydraulic(self, drive, rate_hz, progress, pose_rate_hz)
            return run_kinematic(self, drive, rate_hz, progress, pose_rate_hz)


def rk4_amplification(z):
    """The classical Runge-Kutta method's growth factor per step, R(z) = 1 + z + z^2/2 + z^3/6
    + z^4/24, for ``z`` = lambda dt (complex; Hairer & Wanner, Solving ODEs II, IV.2): a mode
    lambda (rad/s) is stable at step dt (s) if |R(lambda dt)| <= 1."""
    z = np.asarray(z, dtype=complex)
    return 1 + z * (1 + z / 2 * (1 + z / 3 * (1 + z / 4)))


class _euler:
    """Context: ``model`` integrated by explicit Euler at ``dt_s`` (s), its options restored after."""

    def __init__(self, model: mujoco.MjModel, dt_s: float) -> None:
        self.model, self.dt_s = model, dt_s

    def __enter__(self):
        opt = self.model.opt
        self.saved = (opt.integrator, opt.timestep)
        opt.integrator, opt.timestep = mujoco.mjtIntegrator.mjINT_EULER, self.dt_s
        return self.model

    def __exit__(self, *exc) -> None:
        self.model.opt.integrator, self.model.opt.timestep = self.saved
