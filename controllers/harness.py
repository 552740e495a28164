"""The closed-loop harness: sampled-data control of a simulated plant on the one simulation engine.

A run (:func:`run_closed_loop`) wires

* the **plant**: a plant of :mod:`plants` with the *true* friction model
  (by name and parameter set), integrated between samples by the
  simulation engine (:meth:`plants.base.OdePlant.stepper`, adaptive RODAS4,
  input held: zero-order hold);
* the **sensors**: position and chamber pressures with Gaussian noise and
  quantisation (:class:`controllers.plant_model.Sensors`; the noise level
  scaled by ``noise``, the random generator seeded);
* the **controller**: built by name on its *own* plant model
  (:class:`controllers.plant_model.ControlModel`) whose friction model is
  the one named in the configuration with parameters multiplied by the
  ``mismatch`` factors -- the controller never sees the plant's model
  object, and by default its friction is wrong by the amounts of
  :data:`DEFAULT_MISMATCH`;

samples at the controller's rate, applies the command (clipped to the valve
range), advances the plant one sample and records everything.

Every ``step`` call is timed twice: wall clock (:func:`time.perf_counter`)
and the CPU time of the calling thread (:func:`time.thread_time`). The
second is what the step costs on a processor of its own; the wall clock
also holds the time the operating system (or the hypervisor) gave the
processor to another process -- on a shared machine whole scheduler ticks
of 4 ms, the outliers of the wall-clock maximum. Python's cyclic garbage
collector is held off during the loop (as a real-time control thread
would: ``gc.disable``, collected after the run): a full collection in the
middle of a step costs a millisecond the controller did not spend. The true friction
force is the plant's output ``F`` at every sample, beside the controller's
estimate.

Start: the piston at rest at mid-stroke (or where the task starts: a user's
reference, :attr:`controllers.tasks.Task.start`) with the chambers and valve at the
*equilibrium* that holds the load there (solved from the plant's equations:
no flow into either chamber, zero acceleration, friction states zero), so
every run starts from the same physical state, not from a settling load.

Every controller runs behind the fail-safe layer (:mod:`controllers.safety`); its fault
state is recorded at every sample (:attr:`LoopResult.faults`, :attr:`LoopResult.latched`)
and summed up in the metrics. A configuration's ``sensor_faults``
(:class:`SensorFault`: a dropout, a stuck or wild reading over a time window) corrupt
what the controller receives, to test that layer in closed loop.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from controllers.base import Reference
from controllers.metrics import Metrics, compute_metrics
from controllers.plant_model import (
    ControlModel,
    equilibrium,
    friction_with_mismatch,
    sliding_damping,
)
from controllers.safety import FailSafe
from controllers.tasks import Task, check_fits_stroke, get_task
from fcomp.errors import FcompError
from fcomp.models import FrictionModel, make_model

if TYPE_CHECKING:
    from controllers.tuning import Tuning
    from plants.planfile import PlantFile

#: Default friction mismatch of the controller's model (factors on the plant's values): an
#: identification a few tens of percent off, the bristles half as stiff.
DEFAULT_MISMATCH: dict[str, float] = {
    "Fc": 1.2, "Fs": 0.85, "vs": 1.3, "sigma2": 1.15, "sigma0": 0.5, "sigma1": 1.5,
    "tau_hp": 1.5, "tau_hn": 0.7, "T": 0.5,
}


@dataclass(frozen=True)
class SensorFault:
    """What the sensors deliver wrongly over ``[start, start + duration)`` (s): the channels
    (``x``, ``p1``, ``p2``) read ``value`` (NaN by default: a dropout)."""

    start: float
    duration: float
    channels: tuple[str, ...] = ("x", "p1", "p2")
    value: float = math.nan

    def __post_init__(self) -> None:
        bad = sorted(set(self.channels) - {"x", "p1", "p2"})
        if bad or not self.channels:
            raise FcompError(f"sensor fault: channels are x, p1, p2, got {self.channels!r}")
        if not (math.isfinite(self.start) and math.isfinite(self.duration)
                and self.duration > 0):
            raise FcompError(f"sensor fault: start and a positive duration (s), got "
                             f"{self.start!r}, {self.duration!r}")

    def apply(self, t: float, y: np.ndarray) -> None:
        """Corrupt the measurement ``y = [x, p1, p2]`` in place if ``t`` is in the window."""
        if self.start <= t < self.start + self.duration:
            for c in self.channels:
                y[("x", "p1", "p2").index(c)] = self.value


@dataclass(frozen=True)
class LoopConfig:
    """One closed-loop set-up (names, SI units).

    Attributes
    ----------
    plant
        Plant name (``hydraulic``, ``pneumatic``); with ``plant_file``, its kind.
    params
        Parameter set (default: the plant's; not with ``plant_file``).
    friction
        The plant's true friction model: a name (values from the parameter set)
        or a model (e.g. read from a model file, :func:`fcomp.load_model`).
    controller_friction
        The friction model the controller is built with (name or model; a name
        takes its parameters from the same set; times ``mismatch``).
    plant_file
        A plant file (:class:`plants.planfile.PlantFile`) instead of the
        built-in plant ``plant``: its parameters, sensors, limits and rate; a
        friction *name* takes the values of the built-in plant of its kind.
    mismatch
        Factors on the controller model's friction parameters (by name).
    noise
        Factor on the sensor noise levels (0: quantisation only).
    seed
        Seed of the sensor-noise generator.
    fast
        Use the task's fast duration.
    rtol
        Relative (and scaled absolute) tolerance of the plant integration.
    plant_factors
        Factors on parameters of the *simulated* plant only (flat names of the
        plant or of its friction, e.g. ``mass``, ``Fc``): the true plant differs
        from the one the controller is built on (the controller never sees them).
    tuning
        A function of the controller's model giving its tuning instead of the derived
        one (:func:`controllers.tuning.fixed_tuning`; a top-level function, so that the
        configuration pickles); default the derived tuning.
    sensor_faults
        Wrong sensor readings over time windows (:class:`SensorFault`), applied to what
        the controller receives (not to the recorded true states).
    """

    plant: str = "hydraulic"
    params: str | None = None
    friction: str | FrictionModel = "nmlgm"
    controller_friction: str | FrictionModel = "nmlgm"
    mismatch: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_MISMATCH))
    noise: float = 1.0
    seed: int = 0
    fast: bool = False
    rtol: float = 1e-5
    plant_file: PlantFile | None = None
    plant_factors: Mapping[str, float] = field(default_factory=dict)
    tuning: Callable[[ControlModel], Tuning] | None = None
    sensor_faults: tuple[SensorFault, ...] = ()

    def __post_init__(self) -> None:
        if self.plant_file is not None:
            if self.params is not None:
                raise FcompError(f"plant file {self.plant_file.label} gives the plant: no "
                                 f"parameter set {self.params!r} with it")
            object.__setattr__(self, "plant", self.plant_file.kind)


@dataclass
class LoopResult:
    """A closed-loop run: every sample (SI units) and its metrics.

    Attributes
    ----------
    t
        Sample times (s).
    r, x, v
        Reference, true position (m), true velocity (m/s).
    y
        Measurements ``(n, 3)``: position (m), chamber pressures (Pa abs).
    u
        Valve command applied from each sample on.
    F_true, F_hat
        The plant's friction force and the controller's estimate (N).
    solve_times
        Wall-clock duration of every controller step (s).
    solve_cpu
        CPU time of the controller's thread in every step (s).
    fallbacks
        Per-sample flag: the controller used its fallback law.
    metrics
        :class:`~controllers.metrics.Metrics`.
    faults
        Faulty samples the fail-safe layer counted up to each sample.
    latched
        Per-sample flag: the fail-safe layer's safe output was latched.
    """

    controller: str
    task: str
    plant: str
    t: np.ndarray
    r: np.ndarray
    x: np.ndarray
    v: np.ndarray
    y: np.ndarray
    u: np.ndarray
    F_true: np.ndarray
    F_hat: np.ndarray
    solve_times: np.ndarray
    solve_cpu: np.ndarray
    fallbacks: np.ndarray
    metrics: Metrics
    description: str = ""
    faults: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    latched: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


class SensorModel:
    """Noise and quantisation of ``[x, p1, p2]`` (seeded)."""

    def __init__(self, sensors: Any, noise: float, seed: int) -> None:
        s = sensors.scaled(noise)
        self.std = np.array([s.x_noise, s.p_noise, s.p_noise])
        self.q = np.array([s.x_quantum, s.p_quantum, s.p_quantum])
        self.rng = np.random.default_rng(seed)

    def measure(self, x_true: np.ndarray) -> np.ndarray:
        y = x_true + self.std * self.rng.standard_normal(3)
        q = self.q
        return np.where(q > 0, np.round(y / np.where(q > 0, q, 1.0)) * q, y)


def build_loop(controller: str, config: LoopConfig, options: Mapping[str, Any] | None = None
               ) -> tuple[Any, Any, Any]:
    """The true plant, the controller's model and the controller of a configuration."""
    from controllers import make_controller
    from plants import make_plant
    from plants.planfile import KINDS

    if config.plant not in KINDS:
        raise FcompError(f"closed-loop control is set up for plants "
                         f"{', '.join(sorted(KINDS))}, not {config.plant!r}")
    true_friction = _friction(config.friction, config)
    plant: Any
    if config.plant_file is not None:
        plant = config.plant_file.make_plant(true_friction)
    else:
        plant = make_plant(config.plant, true_friction, config.params)
    if config.plant_factors:
        plant = _with_factors(plant, config.plant_factors)
    model = control_model(config)
    ctrl = make_controller(controller, model, **dict(options or {}))
    return plant, model, ctrl


def control_model(config: LoopConfig) -> ControlModel:
    """The controller's own plant model of a configuration (its friction times the mismatch;
    the tuning's loop damping the simulated plant's friction, :func:`sliding_damping`: the
    same PID whatever friction model the controller is built with)."""
    ctrl_friction = friction_with_mismatch(_friction(config.controller_friction, config),
                                           config.mismatch)
    damping = sliding_damping(_friction(config.friction, config))
    model = (ControlModel(config.plant_file, ctrl_friction, damping=damping)
             if config.plant_file is not None
             else ControlModel(config.plant, ctrl_friction, config.params, damping=damping))
    if config.tuning is not None:
        model.use_tuning(config.tuning(model))
    return model


def _with_factors(plant: Any, factors: Mapping[str, float]) -> Any:
    """``plant`` with its parameters (plant or friction, flat names) times ``factors``."""
    flat = plant.flat_params()
    bad = sorted(set(factors) - set(flat))
    if bad:
        raise FcompError(f"plant factors: {', '.join(bad)} not parameters of the plant "
                         f"{plant.describe()}")
    for k, f in factors.items():
        if not (isinstance(f, int | float) and math.isfinite(f) and f > 0):
            raise FcompError(f"plant factor of {k} must be a positive number, got {f!r}")
    return plant.with_params(**{k: float(flat[k]) * f for k, f in factors.items()})


def _friction(friction: str | FrictionModel, config: LoopConfig) -> FrictionModel:
    """A friction model of the configuration: itself, or the model named with the values
    of the configuration's parameter set."""
    if isinstance(friction, FrictionModel):
        return friction
    return make_model(friction, params=config.params or _default_set(config))


def friction_label(friction: str | FrictionModel) -> str:
    """A friction model of a configuration as results name it: its name, or a model's
    description (``lugre + dwell-time``)."""
    return friction.describe() if isinstance(friction, FrictionModel) else friction


def _default_set(config: LoopConfig) -> str:
    from plants import PLANTS

    name = PLANTS.get(config.plant).default_params
    if name is None:
        raise FcompError(f"plant {config.plant} has no default parameter set; give params")
    return name


def run_closed_loop(controller: str, task: str | Task, config: LoopConfig | None = None,
                    options: Mapping[str, Any] | None = None) -> LoopResult:
    """Run ``controller`` on ``task`` (a name, or a :class:`~controllers.tasks.Task` such
    as a user's reference) in the closed loop of ``config`` (see the module docstring).

    Raises
    ------
    FcompError
        Unknown names, bad options, unstable gains, an infeasible MPC set-up.
    ConvergenceError
        The plant integration failed (for instance a loop gone unstable).
    """
    config = config or LoopConfig()
    tk = get_task(task) if isinstance(task, str) else task
    plant, model, ctrl = build_loop(controller, config, options)
    x_start = tk.start_position(model.stroke)
    check_fits_stroke(tk, x_start, model.stroke, config.fast)
    dt = ctrl.dt
    n = int(round(tk.run_duration(config.fast) / dt))
    t = np.arange(n + 1) * dt
    r, dr, ddr = tk.sample(t)
    r = r + x_start
    x0, _u0 = equilibrium(plant, x_start)
    stepper = plant.stepper(dt, x0=x0, rtol=config.rtol, atol=config.rtol)
    sensors = SensorModel(model.sensors, config.noise, config.seed)
    names = plant.state_names
    meas_idx = [names.index(k) for k in ("x", "p1", "p2")]
    preview = ctrl.preview
    r_pad = np.concatenate([r, np.full(preview, r[-1])])
    X = np.empty((n + 1, len(names)))
    Y = np.empty((n + 1, 3))
    U = np.zeros(n + 1)
    F_hat = np.zeros(n + 1)
    times = np.zeros(n + 1)
    cpu = np.zeros(n + 1)
    fb = np.zeros(n + 1, dtype=bool)
    nfault = np.zeros(n + 1, dtype=np.int64)
    run_faults = np.zeros(n + 1, dtype=np.int64)
    latched = np.zeros(n + 1, dtype=bool)
    guarded = isinstance(ctrl, FailSafe)
    state = stepper.reset()
    y0 = _measure(sensors, state[meas_idx], 0.0, config.sensor_faults)
    ctrl.reset(0.0, y0, Reference(float(r[0]), float(dr[0]), float(ddr[0])))
    u_max = model.u_max
    collecting = gc.isenabled()
    gc.disable()  # no collection inside a timed step (module docstring)
    try:
        for k in range(n + 1):
            X[k] = state
            y = y0 if k == 0 else _measure(sensors, state[meas_idx], float(t[k]),
                                           config.sensor_faults)
            Y[k] = y
            fut = tuple(r_pad[k + 1:k + 1 + preview]) if preview else ()
            ref = Reference(float(r[k]), float(dr[k]), float(ddr[k]), fut)
            cpu0 = time.thread_time()
            start = time.perf_counter()
            u = ctrl.step(float(t[k]), y, ref)
            times[k] = time.perf_counter() - start
            cpu[k] = time.thread_time() - cpu0
            if not math.isfinite(u):
                raise FcompError(f"controller {controller} returned a non-finite command at "
                                 f"t = {t[k]:.4f} s")
            u = min(max(u, -u_max), u_max)
            U[k] = u
            F_hat[k] = ctrl.friction_estimate
            fb[k] = ctrl.fallback_active
            if guarded:
                nfault[k] = ctrl.faults
                run_faults[k] = ctrl.consecutive_faults
                latched[k] = ctrl.latched
            if k < n:
                state = stepper.step(u)
    finally:
        if collecting:
            gc.enable()
    outs = plant.evaluate_outputs(X, U.reshape(-1, 1))
    metrics = compute_metrics(
        t, r, X[:, names.index("x")], U, times, cpu_times=cpu, u_max=u_max,
        settle=tk.windows(config.fast), reversals=tk.reversal_times(config.fast),
        reversal_window=tk.reversal_window, periodic=tk.kind == "periodic",
        fallbacks=int(fb.sum()),
        faults=int(nfault[-1]), max_consecutive_faults=int(run_faults.max()),
        latched_steps=int(latched.sum()),
        latches=int(np.sum(latched[1:] & ~latched[:-1]) + latched[0]),
        last_fault=ctrl.last_fault if guarded else None,
    )
    return LoopResult(
        controller=controller, task=tk.name, plant=config.plant, t=t, r=r,
        x=X[:, names.index("x")], v=X[:, names.index("v")], y=Y, u=U, F_true=outs["F"],
        F_hat=F_hat, solve_times=times, solve_cpu=cpu, fallbacks=fb, metrics=metrics,
        description=ctrl.describe(), faults=nfault, latched=latched,
    )


def _measure(sensors: SensorModel, true: np.ndarray, t: float,
             faults: tuple[SensorFault, ...]) -> np.ndarray:
    """The sensors' reading of the true ``[x, p1, p2]`` at ``t``, corrupted by ``faults``."""
    y = sensors.measure(true)
    for f in faults:
        f.apply(t, y)
    return y


__all__ = ["DEFAULT_MISMATCH", "LoopConfig", "LoopResult", "SensorFault", "build_loop",
           "control_model",
           "friction_label",
           "run_closed_loop"]
