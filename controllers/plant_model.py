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
* the sensors (:class:`Sensors`), the valve limits and the control rate of
  its plant file (a built-in plant's: ``plants/data/hydraulic.toml``,
  ``pneumatic.toml``; :func:`plant_settings`);
* its tuning (:attr:`ControlModel.tuning`), derived from the linearised
  plant and its sensors by :mod:`controllers.tuning`, explicit values winning.

Plant settings (assumed; the seeds give no controller): the built-in plant
files give a 1000 Hz control rate, the valve limits (hydraulic +-10 mA at
10 A/s; pneumatic +-1 at 200 1/s), an encoder of 1 um resolution and
0.5 um noise, 12-bit pressure sensors (0-10 MPa, 5 kPa noise; 0-1 MPa,
1 kPa noise). The PID and force-loop bandwidths and the observer gain are
no longer a per-name table: :mod:`controllers.tuning`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from controllers.pid import PIDGains
from controllers.prediction import ContinuousModel
from controllers.safety import FAULT_LATCH, FAULT_RECOVER, safe_command
from controllers.tuning import Margins, Tuning, check_gains, derive_tuning, force_noise, pid_gains
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
    """A plant's controller settings: rate, valve limits, sensors; explicit tuning values; the
    fail-safe layer's settings.

    The tuning fields are None unless given explicitly (a plant file's ``[control]``
    table, or an override): the tuning is otherwise derived from the plant
    (:mod:`controllers.tuning`). The fail-safe fields (``safe_output``, ``fault_latch``,
    ``fault_recover``, ``position_margin``, ``pressure_max``) are the rules' numbers of
    :mod:`controllers.safety`, with its defaults.
    """

    control_rate: float
    u_max: float
    du_max: float
    sensors: Sensors
    pid_bandwidth: float | None = None
    force_bandwidth: float | None = None
    observer_gain: float | None = None
    safe_output: str | float = "centre"
    fault_latch: int = FAULT_LATCH
    fault_recover: int = FAULT_RECOVER
    position_margin: float | None = None
    pressure_max: float | None = None

    def __post_init__(self) -> None:
        """The fail-safe layer's settings (:mod:`controllers.safety`), one line each."""
        safe_command(self.safe_output, self.u_max)
        for k in ("fault_latch", "fault_recover"):
            v = getattr(self, k)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise FcompError(f"{k} must be a whole number of samples >= 1, got {v!r}")
        for k in ("position_margin", "pressure_max"):
            v = getattr(self, k)
            if v is not None and not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise FcompError(f"{k} must be a positive number, got {v!r}")

    def given_tuning(self) -> dict[str, float]:
        """The tuning values given explicitly, by name."""
        return {k: float(v) for k in TUNING_FIELDS if (v := getattr(self, k)) is not None}


#: The settings that are tuning (derived unless given).
TUNING_FIELDS = ("pid_bandwidth", "force_bandwidth", "observer_gain")


def plant_settings(plant: str | PlantFile) -> PlantSettings:
    """The controller settings of a plant: those of its plant file (a built-in plant's
    name: the file shipped for it, :func:`plants.planfile.builtin_plant_file`) -- its
    sensors, valve limits, control rate and the tuning values it gives explicitly."""
    from plants.planfile import KINDS, PlantFile, builtin_plant_file

    if not isinstance(plant, PlantFile):
        if plant not in KINDS:
            raise FcompError(f"closed-loop control is set up for plants "
                             f"{', '.join(sorted(KINDS))}, not {plant!r}")
        plant = builtin_plant_file(plant)
    return PlantSettings(sensors=Sensors(**plant.sensors), **plant.control)


#: Derived tunings by plant, friction and settings (a derivation costs about a second).
_TUNINGS: dict[tuple[Any, ...], Tuning] = {}

def sliding_damping(friction: FrictionModel) -> float:
    """Slope of a friction model's steady-state map at 0.1-0.2 m/s (N s/m, >= 0): the
    damping the seal adds to a sliding piston."""
    F = friction.steady_state(np.array([0.1, 0.2]))
    return max(float(F[1] - F[0]) / 0.1, 0.0)


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
    damping : float, optional
        The viscous damping (N s/m) the tuning's nominal loop assumes
        (:meth:`loop_damping`); default the sliding slope of ``friction``
        (:func:`sliding_damping`). A closed loop on a simulated plant gives the plant's
        own (:func:`controllers.harness.control_model`): every friction model the
        controllers are built with then gets the same PID, so that comparing models
        compares their compensation, not their tuning.
    settings
        Overrides of the plant's settings (:func:`plant_settings`) by field name.
    """

    def __init__(self, plant: str | PlantFile, friction: FrictionModel,
                 params: str | None = None, damping: float | None = None,
                 **settings: Any) -> None:
        from plants import OdePlant, make_plant
        from plants.check import frictionless
        from plants.planfile import PlantFile

        base = plant_settings(plant)
        bad = sorted(set(settings) - set(base.__dataclass_fields__))
        if bad:
            raise FcompError(f"unknown plant setting(s) {', '.join(bad)}")
        self.settings = replace(base, **settings)
        self.friction = friction
        self._damping = sliding_damping(friction) if damping is None else float(damping)
        if not (math.isfinite(self._damping) and self._damping >= 0):
            raise FcompError(f"loop damping must be a finite number >= 0 (N s/m), got {damping}")
        if isinstance(plant, PlantFile):
            if params is not None:
                raise FcompError(f"plant file {plant.label} gives the plant's parameters: "
                                 f"no parameter set {params!r} with it")
            self.plant_name = plant.kind
            own: Any = plant.make_plant(friction)
            self._bare: Any = lambda: plant.make_plant(frictionless())
        else:
            self.plant_name = plant
            own = make_plant(plant, friction, params)
            self._bare = lambda: make_plant(plant, frictionless(), params)
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
        self._tuning: Tuning | None = None

    # ------------------------------------------------------------ settings
    control_rate = property(lambda self: self.settings.control_rate, doc="Hz")
    u_max = property(lambda self: self.settings.u_max, doc="valve command limit")
    du_max = property(lambda self: self.settings.du_max, doc="valve rate limit, 1/s")
    sensors = property(lambda self: self.settings.sensors, doc=":class:`Sensors`")

    @property
    def tuning(self) -> Tuning:
        """The default tuning (:func:`controllers.tuning.derive_tuning`; explicit settings win).

        Raises
        ------
        FcompError
            An explicit tuning without margins (one line).
        """
        if self._tuning is None:
            key = self._tuning_key()
            if key not in _TUNINGS:
                _TUNINGS[key] = derive_tuning(self, given=self.settings.given_tuning())
            self._tuning = _TUNINGS[key]
        return self._tuning

    def placed_gains(self, bandwidth: float, dt: float) -> PIDGains:
        """PID gains placed at ``bandwidth`` (rad/s) with the derivative filter of rule 3 of
        :mod:`controllers.tuning` (:func:`controllers.tuning.pid_gains`)."""
        return pid_gains(self.mass, bandwidth, self.sensors, force_noise(self), dt)

    def checked_margins(self, gains: PIDGains, force_bandwidth: float, dt: float,
                        what: str) -> Margins:
        """Margins of explicit PID gains on the nominal loop, refused (one line, naming
        ``what``) without them (:func:`controllers.tuning.check_gains`)."""
        return check_gains(gains, self, force_bandwidth, dt, what)

    def use_tuning(self, tuning: Tuning) -> None:
        """Replace the derived tuning by ``tuning`` (e.g. :func:`controllers.tuning.fixed_tuning`,
        for comparisons); controllers built afterwards take it as their default."""
        self._tuning = tuning

    def plant_key(self) -> tuple[Any, ...]:
        """What the tuning's feedback part depends on (rules 1-3 of
        :mod:`controllers.tuning`): the plant, its settings and the loop damping -- not the
        friction model's levels."""
        levels = self.friction.flat_params()  # the controller's friction: not in rules 1-3
        return (self.plant_name, tuple(sorted((k, v) for k, v in self.params.items()
                                              if k not in levels)), self.settings,
                self._damping)

    def _tuning_key(self) -> tuple[Any, ...]:
        fp = self.friction.flat_params()
        return (*self.plant_key(), self.friction.describe(), tuple(sorted(fp.items())))

    pid_bandwidth = property(lambda self: self.tuning.pid_bandwidth, doc="rad/s")
    force_bandwidth = property(lambda self: self.tuning.force_bandwidth, doc="rad/s")
    observer_gain = property(lambda self: self.tuning.observer_gain, doc="1/s")
    derivative_cutoff = property(lambda self: self.tuning.derivative_cutoff, doc="Hz")

    @property
    def column_frequency(self) -> float:
        """Natural frequency ``w_h`` (rad/s) of the oil (air) column at mid stroke, no friction.

        :func:`plants.check.column_mode` (python-control's linearisation of the plant).
        """
        from plants.check import column_mode

        return column_mode(self._bare(), 0.5 * self.stroke).frequency

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
        """The viscous damping (N s/m) of the nominal position loop: the tuning's, its
        margins' and the PID's stability check's (the ``damping`` given, or the friction
        model's sliding slope, :func:`sliding_damping`)."""
        return self._damping

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
        """Measurement noise standard deviations of ``[x, p1, p2]`` for the EKF (rule 5 of
        :mod:`controllers.tuning`: the sensors' noise and quantisation)."""
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
