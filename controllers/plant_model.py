"""What a controller knows about its plant: its *own* plant model, sensors and limits.

A :class:`ControlModel` is built from names -- plant name, parameter set
and the controller's friction model (usually differing from the simulated
plant's: :mod:`controllers.harness` makes the mismatch) -- and constructs a
*new* plant object (:func:`plants.make_plant`) with that friction model. The
simulated plant's object is never handed to a controller. From its plant
model the controller reads

* rigid-body data: moving mass ``m`` (kg), piston areas ``A1``, ``A2``
  (m^2), the weight ``F_g = m*g*orient`` (N) and the actuator force range
  ``[F_min, F_max]`` (N) the supply and return pressures allow;
* the symbolic plant + friction equations (:attr:`ControlModel.prediction`)
  for the EKF and the MPC, and the chamber equations for
  :mod:`controllers.force_to_valve`;
* the sensors (:class:`Sensors`) and the valve limits and default tuning
  of :data:`PLANT_SETTINGS`.

Plant settings (assumed; the seeds give no controller)
------------------------------------------------------
=================== ======================= =======================================
setting              hydraulic (seed 002)    pneumatic (seed000-servo)
=================== ======================= =======================================
control rate         1000 Hz                 1000 Hz (pneumatic servo boards run
                                             0.5-2 kHz; the valve lag is 5 ms)
valve command        +-10 mA (rated current; +-1 (normalised spool command)
                     seed 002 drives 4.5 mA
                     for +-0.14 m/s)
valve rate limit     10 A/s (full range in   200 1/s (full range in 10 ms)
                     2 ms, amplifier slew)
position sensor      1 um resolution,        1 um resolution, 0.5 um noise
                     0.5 um noise (encoder)
pressure sensors     12-bit over 0-10 MPa    12-bit over 0-1 MPa (244 Pa),
                     (2.44 kPa), 5 kPa noise  1 kPa noise
PID bandwidth        40 rad/s                30 rad/s
force-loop bandwidth 150 rad/s               120 rad/s (the 5 ms spool lag and
                                             the air's compliance: 150/40 is
                                             unstable, the nominal check says so)
observer gain k      see the table of        controllers.lugre_observer
=================== ======================= =======================================
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from controllers.prediction import ContinuousModel
from fcomp.errors import FcompError
from fcomp.measurement import G
from fcomp.models.base import FrictionModel
from fcomp.piston import piston_areas
from plants.equilibrium import equilibrium  # noqa: F401 (the closed loops take it from here)

if TYPE_CHECKING:
    from plants.planfile import PlantFile


@dataclass(frozen=True)
class Sensors:
    """Sensor noise (standard deviation) and quantisation step, SI units (m, Pa)."""

    x_noise: float
    x_quantum: float
    p_noise: float
    p_quantum: float

    def __post_init__(self) -> None:
        for k in ("x_noise", "x_quantum", "p_noise", "p_quantum"):
            v = getattr(self, k)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise FcompError(f"sensors: {k} must be a finite number >= 0, got {v!r}")

    def scaled(self, noise_factor: float) -> Sensors:
        """The same sensors with every noise level multiplied by ``noise_factor``."""
        if not (math.isfinite(noise_factor) and noise_factor >= 0):
            raise FcompError(f"noise factor must be >= 0, got {noise_factor}")
        return replace(self, x_noise=self.x_noise * noise_factor,
                       p_noise=self.p_noise * noise_factor)

    def std(self) -> np.ndarray:
        """Effective standard deviations of ``[x, p1, p2]``: noise and quantisation (``q/sqrt(12)``)."""
        sx = math.hypot(self.x_noise, self.x_quantum / math.sqrt(12))
        sp = math.hypot(self.p_noise, self.p_quantum / math.sqrt(12))
        return np.array([max(sx, 1e-9), max(sp, 1.0), max(sp, 1.0)])


@dataclass(frozen=True)
class PlantSettings:
    """Per-plant controller settings (see the module docstring table)."""

    control_rate: float
    u_max: float
    du_max: float
    sensors: Sensors
    pid_bandwidth: float
    force_bandwidth: float
    observer_gain: float


PLANT_SETTINGS: dict[str, PlantSettings] = {
    "hydraulic": PlantSettings(
        control_rate=1000.0, u_max=0.010, du_max=10.0,
        sensors=Sensors(x_noise=0.5e-6, x_quantum=1e-6, p_noise=5e3, p_quantum=1e7 / 4096),
        pid_bandwidth=40.0, force_bandwidth=150.0, observer_gain=20.0,
    ),
    "pneumatic": PlantSettings(
        control_rate=1000.0, u_max=1.0, du_max=200.0,
        sensors=Sensors(x_noise=0.5e-6, x_quantum=1e-6, p_noise=1e3, p_quantum=1e6 / 4096),
        pid_bandwidth=30.0, force_bandwidth=120.0, observer_gain=20.0,
    ),
}

def plant_settings(plant: str | PlantFile) -> PlantSettings:
    """The controller settings of a plant: :data:`PLANT_SETTINGS` of a built-in plant's
    name, or those a plant file gives (its sensors, valve limits, control rate and the
    tuning it gives; the tuning it leaves out is the built-in plant's of its kind)."""
    from plants.planfile import PlantFile

    if not isinstance(plant, PlantFile):
        if plant not in PLANT_SETTINGS:
            raise FcompError(f"closed-loop control is set up for plants "
                             f"{', '.join(sorted(PLANT_SETTINGS))}, not {plant!r}")
        return PLANT_SETTINGS[plant]
    return replace(PLANT_SETTINGS[plant.kind], sensors=Sensors(**plant.sensors),
                   **plant.control)


#: Plant states the controller measures, in the order of ``y``.
MEASURED = ("x", "p1", "p2")


class ControlModel:
    """The controller's own model of a plant (see the module docstring).

    Parameters
    ----------
    plant : str or PlantFile
        Plant name (``hydraulic``, ``pneumatic``), or a plant file
        (:class:`plants.planfile.PlantFile`: its parameters and settings).
    friction : FrictionModel
        The controller's friction model (symbolic).
    params : str, optional
        Parameter-set name (default: the plant's; not with a plant file).
    settings
        Overrides of the plant's settings (:func:`plant_settings`) by field name.
    """

    def __init__(self, plant: str | PlantFile, friction: FrictionModel,
                 params: str | None = None, **settings: Any) -> None:
        from plants import OdePlant, make_plant
        from plants.planfile import PlantFile

        base = plant_settings(plant)
        bad = sorted(set(settings) - set(base.__dataclass_fields__))
        if bad:
            raise FcompError(f"unknown plant setting(s) {', '.join(bad)}")
        self.settings = replace(base, **settings)
        self.friction = friction
        if isinstance(plant, PlantFile):
            if params is not None:
                raise FcompError(f"plant file {plant.label} gives the plant's parameters: "
                                 f"no parameter set {params!r} with it")
            self.plant_name = plant.kind
            own: Any = plant.make_plant(friction)
        else:
            self.plant_name = plant
            own = make_plant(plant, friction, params)
        if not isinstance(own, OdePlant):
            raise FcompError(f"plant {plant} is not given by differential equations")
        self.plant: OdePlant = own
        flat = self.plant.flat_params()
        self.params = flat
        self.mass = float(flat["mass"])
        self.A1, self.A2 = piston_areas(float(flat["bore"]), float(flat["rod"]))
        self.p_atm = float(flat["p_atm"])
        self.weight = self.mass * G * float(flat["orient"])
        ps = float(flat["ps"])
        p_low = float(flat.get("pt", self.p_atm))
        self.force_max = (ps - self.p_atm) * self.A1 - (p_low - self.p_atm) * self.A2
        self.force_min = (p_low - self.p_atm) * self.A1 - (ps - self.p_atm) * self.A2
        self.stroke = float(flat["stroke"])
        self.prediction = self._prediction()

    # ------------------------------------------------------------ settings
    control_rate = property(lambda self: self.settings.control_rate, doc="Hz")
    u_max = property(lambda self: self.settings.u_max, doc="valve command limit")
    du_max = property(lambda self: self.settings.du_max, doc="valve rate limit, 1/s")
    pid_bandwidth = property(lambda self: self.settings.pid_bandwidth, doc="rad/s")
    force_bandwidth = property(lambda self: self.settings.force_bandwidth, doc="rad/s")
    observer_gain = property(lambda self: self.settings.observer_gain, doc="1/s")
    sensors = property(lambda self: self.settings.sensors, doc=":class:`Sensors`")

    def describe(self) -> str:
        return self.plant.describe()

    # ------------------------------------------------------------- signals
    def gauge(self, y: np.ndarray) -> tuple[float, float]:
        """Gauge chamber pressures (Pa) from a measurement ``[x, p1, p2]`` (absolute)."""
        return float(y[1]) - self.p_atm, float(y[2]) - self.p_atm

    def actuator_force(self, y: np.ndarray) -> float:
        """``F_a = (p1 - p_atm)*A1 - (p2 - p_atm)*A2`` (N) from a measurement."""
        p1g, p2g = self.gauge(y)
        return p1g * self.A1 - p2g * self.A2

    # ------------------------------------------------------------ symbolic
    def _prediction(self) -> ContinuousModel:
        fns = self.plant.casadi_functions(symbolic_params=True)
        names = self.plant.state_names
        out_names = self.plant.output_names
        x = ca.SX.sym("x", len(names))
        u = ca.SX.sym("u")
        p = ca.SX.sym("p", fns["rhs"].size1_in(2))
        F = fns["outputs"](x, u, p)[out_names.index("F")]
        return ContinuousModel(
            f=fns["rhs"],
            friction=ca.Function("friction", [x, u, p], [F], ["x", "u", "p"], ["F"]),
            p=np.asarray(self.plant.param_vector(), dtype=float),
            state_names=tuple(names),
            measured=tuple(names.index(n) for n in MEASURED),
            scales=np.asarray(self.plant.ode_model().scales, dtype=float),
            discrete=self.plant.discrete_step,
        )

    def valve_states(self) -> tuple[str, ...]:
        """The plant states that are neither mechanics, pressures nor friction (valve)."""
        skip = {"x", "v", "p1", "p2", *self.friction.state_names}
        return tuple(n for n in self.plant.state_names if n not in skip)

    def steady_valve(self) -> ca.Function:
        """``(u, p) -> valve states`` at rest under a constant command ``u``.

        One Newton step from zero on the valve equations, exact for the
        linear valve models of the plants (second-order servo valve,
        first-order spool lag).
        """
        names = self.plant.state_names
        iv = [names.index(n) for n in self.valve_states()]
        x = ca.SX.sym("x", len(names))
        u = ca.SX.sym("u")
        p = ca.SX.sym("p", self.prediction.p.size)
        f = self.prediction.f(x, u, p)
        fv = ca.vertcat(*[f[i] for i in iv])
        xv = ca.vertcat(*[x[i] for i in iv])
        zero = {names[i]: 0.0 for i in range(len(names))}
        x0 = ca.DM([zero[n] for n in names])
        J = ca.substitute(ca.jacobian(fv, xv), x, x0)
        r = ca.substitute(fv, x, x0)
        return ca.Function("steady_valve", [u, p], [-ca.solve(J, r)])

    def valve_transfer(self) -> Any:
        """The valve's linear dynamics from command to opening, unit DC gain (python-control).

        From the Jacobian of the controller model's valve equations at rest
        (exact for the linear valves of the plants); the opening is the first
        valve state (``xv``, ``xs``).
        """
        import control as ct

        names = self.plant.state_names
        iv = [names.index(n) for n in self.valve_states()]
        x = ca.SX.sym("x", len(names))
        u = ca.SX.sym("u")
        f = self.prediction.f(x, u, self.prediction.p)
        fv = ca.vertcat(*[f[i] for i in iv])
        xv = ca.vertcat(*[x[i] for i in iv])
        jac = ca.Function("valve_jac", [x, u], [ca.jacobian(fv, xv), ca.jacobian(fv, u)])
        A, B = (np.asarray(m, dtype=float) for m in jac(np.zeros(len(names)), 0.0))
        C = np.zeros((1, len(iv)))
        C[0, 0] = 1.0
        sys = ct.ss(A, B, C, 0.0)
        return ct.tf(sys) / float(np.asarray(ct.dcgain(sys)).ravel()[0])

    def viscous_damping(self) -> float:
        """Slope of the controller's steady-state friction map at 0.1-0.2 m/s (N s/m, >= 0)."""
        F = self.friction.steady_state(np.array([0.1, 0.2]))
        return max(float(F[1] - F[0]) / 0.1, 0.0)

    # ---------------------------------------------------------- estimation
    def initial_state(self, y0: np.ndarray) -> np.ndarray:
        """Model state at rest consistent with a measurement: measured states set, rest default."""
        x0 = self.plant.initial_state()
        for i, val in zip(self.prediction.measured, y0, strict=True):
            x0[i] = float(val)
        return x0

    def process_noise(self) -> np.ndarray:
        """Default EKF process-noise intensities per state (state unit/sqrt(s)).

        ``1e-3`` of each state's scale on the plant states (5 mm/s/sqrt(s) on the
        velocity), ``0.5*z_scale`` on the bristle state ``z`` (it must absorb the
        friction mismatch: about 1.5 % of the break-away force per millisecond),
        0.5 on the film ``h``.
        """
        sc = self.prediction.scales
        q = 1e-3 * sc
        names = self.prediction.state_names
        if "v" in names:
            q[names.index("v")] = 0.005
        if "z" in names:
            q[names.index("z")] = 0.5 * sc[names.index("z")]
        if "h" in names:
            q[names.index("h")] = 0.5
        return q

    def sensor_std(self) -> np.ndarray:
        """Measurement noise standard deviations of ``[x, p1, p2]`` for the EKF."""
        return self.sensors.std()

    def estimator_initial(self, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Initial estimate and covariance (states at rest, pressures measured)."""
        x0 = self.initial_state(y0)
        sc = self.prediction.scales
        P0 = np.diag((1e-3 * sc) ** 2)
        for i, s in zip(self.prediction.measured, self.sensor_std(), strict=True):
            P0[i, i] = s * s
        names = self.prediction.state_names
        if "z" in names:
            iz = names.index("z")
            P0[iz, iz] = sc[iz] ** 2
        return x0, P0


def friction_with_mismatch(model: FrictionModel, factors: Mapping[str, float]) -> FrictionModel:
    """A copy of ``model`` with parameters multiplied by ``factors`` (flat or base names).

    A base name (``Fc``) scales both sides of a directional parameter
    (``Fc_pos``, ``Fc_neg``); names the model lacks are ignored, so one
    mismatch specification serves every model.
    """
    flat = model.flat_params()
    new: dict[str, float] = {}
    for name, fac in factors.items():
        if not (isinstance(fac, int | float) and math.isfinite(fac) and fac > 0):
            raise FcompError(f"mismatch factor of {name} must be a positive number, got {fac!r}")
        for k in (name, f"{name}_pos", f"{name}_neg"):
            if k in flat and math.isfinite(flat[k]):
                new[k] = flat[k] * fac
    return model.with_params(**new) if new else model
