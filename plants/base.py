"""The plant base classes.

Implementer's contract
======================
A plant is a subclass of :class:`Plant` registered by ``name`` in
:data:`plants.PLANTS`, constructed as ``Plant(friction, params=None)`` with a
friction model of :mod:`fcomp.models` (any effects) and a parameter set
(name or :class:`~fcomp.paramsets.ParameterSet`; each plant documents its
default). It declares ``input_names`` (with units in ``input_units``) and
implements :meth:`Plant.simulate`, which returns a
:class:`~fcomp.measurement.Measurement` sampled at ``rate`` over
``[0, duration]`` in the data format.

Plants given by differential equations (all but ``motion``) derive from
:class:`OdePlant` and follow python-control's ``(t, x, u, params)``
convention: named states ``x``, inputs ``u`` and outputs ``y``,

    dx/dt = f(x, u; p),      y = g(x, u; p),

with ``p`` the flat parameters, the plant's own (:attr:`OdePlant.Params`)
followed by the friction model's (:meth:`~fcomp.models.base.FrictionModel.flat_params`),
in the order of :meth:`OdePlant.flat_params`. States are the plant's own
(:attr:`OdePlant.plant_states`) followed by the friction model's
(``friction.state_names``).

A subclass implements, *once*, against the backend ``be``
(:mod:`fcomp.backend`, numpy or CasADi):

:meth:`OdePlant.equations` ``(be, x, u, P) -> (dx, y)``
    ``x`` and ``u`` are dicts of state and input values by name, ``P`` the
    :class:`~fcomp.parameters.ParamValues` of all parameters; returns the
    dicts of derivatives (every state) and outputs (every name of
    ``output_names``, plus any extra signal worth writing);

and the data around it: ``Params`` (a frozen parameter dataclass, plant
parameters only, names disjoint from every friction parameter),
:meth:`OdePlant.params_from_set` (the plant parameters of a
:class:`~fcomp.paramsets.ParameterSet`), :meth:`OdePlant.default_state`,
:meth:`OdePlant.state_scales` (nominal magnitudes for the error control),
:meth:`OdePlant.check_params` (impossible geometry, ...), and
:meth:`OdePlant.rig_meta` (the sidecar ``[rig]`` table).

What the base class derives from it (the API later work builds on)
------------------------------------------------------------------
Numeric and symbolic forms of the same equations:

* ``plant.rhs(be, x, u, P)`` / ``plant.outputs(be, x, u, P)`` -- lists in
  state / output order (``x``, ``u`` lists; numpy arrays evaluate many
  samples at once);
* ``plant.casadi_functions(symbolic_params=False)`` -- CasADi functions
  ``rhs(x, u[, p]) -> dx``, ``outputs(x, u[, p]) -> y`` and
  ``jacobians(x, u[, p]) -> (A, B, C, D)`` (exact, for the EKF);
* ``plant.discrete_step(dt, substeps=1, scheme=...)`` -- CasADi ``step(x, u,
  p) -> x_next`` over one sample with the input held, differentiable: fixed
  RODAS4 steps (``scheme="rodas4"``, default) or the linearly implicit Euler
  (``"linearly-implicit-euler"``, with ``sensitivities=True`` also its step
  Jacobians), the prediction model of the EKF and the MPC
  (:class:`controllers.plant_model.ControlModel` takes it from here);
* ``plant.ode_model()`` -- the :class:`~fcomp.simulation.OdeModel` the engine runs;
* ``plant.param_vector(**changes)`` -- the numeric ``p``;
* ``plant.initial_state(overrides)`` -- the documented default initial state.

Running it:

* ``plant.simulate(u, duration, rate, x0=..., method=..., rtol=..., atol=...,
  hold=...)`` -- open loop, a :class:`~fcomp.measurement.Measurement`;
* ``plant.stepper(dt, x0=...)`` -- a :class:`~fcomp.simulation.Stepper` for
  sampled-data closed loops (``reset()``, ``step(u) -> x`` with ``u`` held);
* ``plant.to_iosys()`` -- a python-control ``NonlinearIOSystem`` (its
  ``linearize``, ``input_output_response``, ``find_eqpt`` work on it).

Friction with discrete memory (``nmlgm-hysteresis``, the ``nonlocal-memory``
effect) has no symbolic form: ``simulate``, ``stepper`` and
``evaluate_outputs`` then run through :mod:`plants.discrete_memory` (the
memory coupled to the engine in short intervals, ``coupling=`` s), while
``casadi_functions``, ``discrete_step``, ``ode_model`` and ``to_iosys``
refuse with a one-line :class:`~fcomp.models.base.NotSymbolicError`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from functools import cached_property
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from fcomp.backend import CASADI, NUMPY, Backend
from fcomp.errors import FcompError, term
from fcomp.measurement import Measurement
from fcomp.models.base import FrictionModel, Signals
from fcomp.parameters import ParamSet, ParamValues
from fcomp.paramsets import ParameterSet
from fcomp.paramsets import get as get_paramset
from fcomp.simulation import (
    DEFAULT_TOLERANCES,
    OdeModel,
    Stepper,
    Tolerances,
    Trajectory,
    integrate,
)
from fcomp.version import __version__
from plants.discrete_memory import COUPLING, MemoryCoupling, MemoryStepper

InputFn = Callable[[np.ndarray], np.ndarray]


def output_times(duration: float, rate: float) -> np.ndarray:
    """Sample times ``0, 1/rate, ..., duration`` (s); validates both."""
    d_, r_ = term("duration"), term("rate")
    if not (np.isfinite(duration) and duration > 0):
        raise FcompError(f"{d_} must be a positive number of seconds, got {duration}")
    if not (np.isfinite(rate) and rate > 0):
        raise FcompError(f"{r_} must be a positive number of hertz, got {rate}")
    n = int(round(duration * rate))
    if n < 1:
        raise FcompError(f"{d_} {duration} s at {r_} {rate} Hz gives no samples")
    if n > 50_000_000:
        raise FcompError(f"{n} samples requested; lower {r_} or {d_}")
    return np.arange(n + 1) / rate


class Plant(ABC):
    """Base class of plants (see the module docstring for the contract)."""

    name: ClassVar[str] = ""
    default_params: ClassVar[str | None] = None
    input_names: ClassVar[tuple[str, ...]] = ("u",)
    input_units: ClassVar[tuple[str, ...]] = ("-",)

    def __init__(self, friction: FrictionModel, params: str | ParameterSet | None = None) -> None:
        if not isinstance(friction, FrictionModel):
            raise ValueError(f"plant {self.name}: friction must be a FrictionModel")
        self.friction = friction
        if params is None and self.default_params is not None:
            params = self.default_params
        self.paramset: ParameterSet | None = (
            get_paramset(params) if isinstance(params, str) else params
        )

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the states (for ``motion``: the friction states)."""
        return self.friction.state_names

    def initial_state(self, overrides: Mapping[str, float] | None = None) -> np.ndarray:
        """The default initial state, with ``overrides`` (state name -> value) applied."""
        x0 = dict(zip(self.state_names, self._default_state_vector(), strict=True))
        for k, v in (overrides or {}).items():
            if k not in x0:
                raise FcompError(
                    f"plant {self.name}: unknown state {k!r} in the initial state; "
                    f"states: {', '.join(self.state_names) or '(none)'}"
                )
            if not (isinstance(v, int | float) and math.isfinite(v)):
                raise FcompError(f"plant {self.name}: initial {k} must be a finite number")
            x0[k] = float(v)
        return np.array(list(x0.values()), dtype=float)

    def _default_state_vector(self) -> np.ndarray:
        return self.friction.initial_state()

    @abstractmethod
    def simulate(
        self, u: InputFn, duration: float, rate: float, *, x0: Any = None, **options: Any
    ) -> Measurement:
        """Simulate over ``[0, duration]`` s and return the run sampled at ``rate`` Hz."""

    def describe(self) -> str:
        ps = self.paramset.name if self.paramset else "defaults"
        return f"{self.name} ({ps}) with {self.friction.describe()}"


def _friction_structure(model: FrictionModel) -> tuple:
    key = getattr(model, "structure_key", None)
    if callable(key):
        return key()
    return (
        type(model),
        tuple((type(e), tuple(sorted(e.config.items()))) for e in model.effects),
        tuple(model.flat_params()),
    )


class OdePlant(Plant):
    """A plant given by ODEs ``dx/dt = f(x, u; p)``, ``y = g(x, u; p)`` (module docstring).

    Parameters
    ----------
    friction
        A friction model with a symbolic form (any effects).
    params
        Parameter-set name or :class:`~fcomp.paramsets.ParameterSet`
        (default :attr:`default_params`).
    overrides
        Plant parameters changed by name (SI units), e.g. ``{"mass": 20.0}``.
    """

    Params: ClassVar[type[ParamSet]]
    #: the plant's own states (friction states follow)
    plant_states: ClassVar[tuple[str, ...]] = ()
    #: unit of each plant state
    state_units: ClassVar[dict[str, str]] = {}
    #: outputs (python-control ``y``) and their units
    output_names: ClassVar[tuple[str, ...]] = ()
    output_units: ClassVar[dict[str, str]] = {}
    #: ``kind`` written to the sidecar
    kind: ClassVar[str] = "friction-rig"

    def __init__(
        self,
        friction: FrictionModel,
        params: str | ParameterSet | None = None,
        *,
        overrides: Mapping[str, float] | None = None,
    ) -> None:
        super().__init__(friction, params)
        given = self.paramset.plant if self.paramset is not None else {}
        values = dict(given) if given else self.params_from_set(self.paramset)
        known = set(self.Params.names())
        for k, v in (overrides or {}).items():
            if k not in known:
                raise FcompError(f"plant {self.name}: unknown plant parameter {k!r}; known: "
                                 f"{', '.join(self.Params.names())}")
            values[k] = v
        try:
            self.plant_params: ParamSet = self.Params(**values)
        except ValueError as exc:  # names the plant and the parameter already
            raise FcompError(str(exc)) from None
        clash = set(self.plant_params.flat()) & set(friction.flat_params())
        if clash:
            raise FcompError(
                f"plant {self.name}: friction parameter(s) {', '.join(sorted(clash))} clash "
                "with plant parameters of the same name"
            )
        clash = set(self.plant_states) & set(friction.state_names)
        if clash:
            raise FcompError(f"plant {self.name}: friction state(s) {', '.join(sorted(clash))} "
                             "clash with plant states")
        self.check_params()

    # ----------------------------------------------------------- contract
    @classmethod
    @abstractmethod
    def params_from_set(cls, pset: ParameterSet | None) -> dict[str, Any]:
        """Plant parameter values (flat names, SI) from a parameter set."""

    @abstractmethod
    def equations(
        self, be: Backend, x: dict[str, Any], u: dict[str, Any], P: ParamValues
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Derivatives of every state and the outputs, by name (see module docstring)."""

    @abstractmethod
    def default_state(self) -> dict[str, float]:
        """Documented default initial values of the plant's own states."""

    @abstractmethod
    def state_scales(self) -> dict[str, float]:
        """Nominal magnitude of every plant state (units of the state), for error control."""

    def check_params(self) -> None:
        """Raise :class:`FcompError` on impossible parameter values (beyond their bounds)."""

    def rig_meta(self) -> dict[str, Any]:
        """The sidecar ``[rig]`` table."""
        return {}

    def scalar_input(self, u: np.ndarray) -> np.ndarray:
        """Map one input signal to all inputs ``(n, nu)`` (plants with several inputs)."""
        raise FcompError(
            f"plant {self.name} has inputs {', '.join(self.input_names)}: give one column each"
        )

    # ------------------------------------------------------------ names
    @property
    def state_names(self) -> tuple[str, ...]:
        return (*self.plant_states, *self.friction.state_names)

    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def nu(self) -> int:
        return len(self.input_names)

    def flat_params(self) -> dict[str, float]:
        """All parameters by flat name: the plant's, then the friction model's."""
        return {**self.plant_params.flat(), **self.friction.flat_params()}

    def param_vector(self, **changes: float) -> np.ndarray:
        """The numeric parameter vector ``p`` (order of :meth:`flat_params`), with ``changes``."""
        flat = self.flat_params()
        for k, v in changes.items():
            if k not in flat:
                raise FcompError(f"plant {self.name}: unknown parameter {k!r}")
            flat[k] = float(v)
        return np.array(list(flat.values()), dtype=float)

    def param_values(self, be: Backend, values: Mapping[str, Any] | None = None) -> ParamValues:
        return ParamValues(values if values is not None else self.flat_params(), be)

    def with_params(self, **flat: float) -> OdePlant:
        """A copy with plant and/or friction parameters changed by flat name."""
        own = {k: v for k, v in flat.items() if k in self.plant_params.flat()}
        rest = {k: v for k, v in flat.items() if k not in own}
        friction = self.friction.with_params(**rest) if rest else self.friction
        return type(self)(friction, self.paramset, overrides={**self.plant_params.flat(), **own})

    # ------------------------------------------------------- evaluation
    def _evaluate(self, be: Backend, x: list[Any], u: list[Any],
                  P: ParamValues) -> tuple[dict[str, Any], dict[str, Any]]:
        xs = dict(zip(self.state_names, x, strict=True))
        us = dict(zip(self.input_names, u, strict=True))
        return self.equations(be, xs, us, P)

    def rhs(self, be: Backend, x: list[Any], u: list[Any], P: ParamValues) -> list[Any]:
        """``dx/dt`` in state order."""
        dx, _ = self._evaluate(be, x, u, P)
        return [dx[n] for n in self.state_names]

    def outputs(self, be: Backend, x: list[Any], u: list[Any], P: ParamValues) -> list[Any]:
        """Outputs ``y`` in :attr:`output_names` order."""
        _, y = self._evaluate(be, x, u, P)
        return [y[n] for n in self.output_names]

    def casadi_functions(self, *, symbolic_params: bool = False) -> dict[str, ca.Function]:
        """CasADi functions of the plant (with its friction), from the same equations.

        Returns
        -------
        dict
            ``"rhs"``: ``(x, u[, p]) -> dx``; ``"outputs"``: ``(x, u[, p]) -> y``;
            ``"jacobians"``: ``(x, u[, p]) -> (A, B, C, D)`` with ``A = df/dx``,
            ``B = df/du``, ``C = dg/dx``, ``D = dg/du``. ``p`` (only with
            ``symbolic_params``) is the vector of :meth:`flat_params`.
        """
        self.friction.require_symbolic()
        x = ca.SX.sym("x", self.nx)
        u = ca.SX.sym("u", self.nu)
        names = list(self.flat_params())
        if symbolic_params:
            p, P = ParamValues.symbolic(names)
            args, argn = [x, u, p], ["x", "u", "p"]
        else:
            P = self.param_values(CASADI)
            args, argn = [x, u], ["x", "u"]
        xl = [x[i] for i in range(self.nx)]
        ul = [u[i] for i in range(self.nu)]
        dx, y = self._evaluate(CASADI, xl, ul, P)
        f = ca.vertcat(*[dx[n] for n in self.state_names])
        g = ca.vertcat(*[y[n] for n in self.output_names])
        jac = [ca.jacobian(f, x), ca.jacobian(f, u), ca.jacobian(g, x), ca.jacobian(g, u)]
        return {
            "rhs": ca.Function("rhs", args, [f], argn, ["dx"]),
            "outputs": ca.Function("outputs", args, [g], argn, ["y"]),
            "jacobians": ca.Function("jacobians", args, jac, argn, ["A", "B", "C", "D"]),
        }

    def structure_key(self) -> tuple:
        """Identity of the equations' structure (equal keys share compiled code)."""
        return (type(self), _friction_structure(self.friction), tuple(self.plant_params.flat()))

    @cached_property
    def _ode(self) -> OdeModel:
        rhs = self.casadi_functions(symbolic_params=True)["rhs"]
        label = f"{self.name} with {self.friction.describe()}"
        return OdeModel(label, rhs, self.state_names, self.input_names,
                        self._scale_vector(), key=self.structure_key())

    def ode_model(self) -> OdeModel:
        """The :class:`~fcomp.simulation.OdeModel` of this plant (``p`` symbolic)."""
        return self._ode

    def discrete_step(self, dt: float, substeps: int = 1, *, scheme: str = "rodas4",
                      sensitivities: bool = False, scale_input: bool = False) -> ca.Function:
        """CasADi ``step(x, u, p) -> x_next``: one sample of ``dt`` s with the input held
        (:meth:`fcomp.simulation.OdeModel.discrete_step`: ``scheme`` ``"rodas4"`` or
        ``"linearly-implicit-euler"``, the controllers' prediction model; ``scale_input``:
        the state scales are a fourth input)."""
        return self.ode_model().discrete_step(dt, substeps, scheme=scheme,
                                              sensitivities=sensitivities,
                                              scale_input=scale_input)

    def _scale_vector(self) -> np.ndarray:
        own = self.state_scales()
        fr = friction_state_scales(self.friction)
        return np.array([own[n] for n in self.plant_states] + list(fr), dtype=float)

    def _default_state_vector(self) -> np.ndarray:
        own = self.default_state()
        return np.concatenate([[own[n] for n in self.plant_states],
                               self.friction.initial_state()]).astype(float)

    # -------------------------------------------------------------- runs
    def input_samples(self, u: Any, t: np.ndarray) -> np.ndarray:
        """Input values ``(len(t), nu)`` from a function of time, an array or a constant."""
        vals = np.asarray(u(t) if callable(u) else u, dtype=float)
        n = t.size
        if vals.ndim == 0:
            vals = np.full((n, self.nu), float(vals))
        elif vals.ndim == 1 and vals.size == n:
            vals = vals.reshape(n, 1) if self.nu == 1 else self.scalar_input(vals)
        elif vals.ndim == 1 and vals.size == self.nu:
            vals = np.broadcast_to(vals, (n, self.nu))
        if vals.shape != (n, self.nu):
            raise FcompError(f"plant {self.name}: the input must give {self.nu} value(s) "
                             f"({', '.join(self.input_names)}) at each of {n} samples")
        if not np.all(np.isfinite(vals)):
            raise FcompError(f"plant {self.name}: the input has non-finite values")
        return np.ascontiguousarray(vals, dtype=float)

    def _x0(self, x0: Any) -> np.ndarray:
        if x0 is None or isinstance(x0, Mapping):
            return self.initial_state(x0)
        arr = np.asarray(x0, dtype=float).ravel()
        if arr.size != self.nx or not np.all(np.isfinite(arr)):
            raise FcompError(f"plant {self.name}: initial state must be {self.nx} finite values "
                             f"({', '.join(self.state_names)})")
        return arr

    def simulate(
        self,
        u: Any,
        duration: float,
        rate: float,
        *,
        x0: Any = None,
        method: str = "rodas4",
        rtol: float = DEFAULT_TOLERANCES.rtol,
        atol: float = DEFAULT_TOLERANCES.atol,
        hold: str = "linear",
        max_steps: int = DEFAULT_TOLERANCES.max_steps,
        coupling: float | None = None,
        **options: Any,
    ) -> Measurement:
        """Simulate over ``[0, duration]`` s, output at ``rate`` Hz (:mod:`fcomp.simulation`).

        Parameters
        ----------
        u
            Input: a function of time (``fcomp.inputs.parse_input``), an array
            ``(n,)``/``(n, nu)`` on the output grid, or a constant.
        duration, rate
            Simulated time (s) and output sample rate (Hz).
        x0
            Initial state: ``None`` (the documented default), a mapping of
            state names to values overriding the default, or a full vector.
        method, rtol, atol, hold, max_steps
            Engine options (:class:`~fcomp.simulation.Tolerances`, ``METHODS``).
        coupling
            Longest coupling interval (s) for friction with discrete memory
            (:mod:`plants.discrete_memory`, default 1e-4 s); not allowed otherwise.
        """
        if options:
            raise FcompError(f"plant {self.name}: unknown option(s) {', '.join(options)}")
        t = output_times(duration, rate)
        U = self.input_samples(u, t)
        tol = Tolerances(rtol=rtol, atol=atol, max_steps=max_steps)
        start = self._x0(x0)
        if self.friction.discrete_memory() is None:
            if coupling is not None:
                raise FcompError(f"plant {self.name}: {term('coupling')} applies to friction "
                                 "with discrete memory (nmlgm-hysteresis) only")
            traj = integrate(self.ode_model(), start, t, U, self.param_vector(), hold=hold,
                             method=method, tolerances=tol)
            return self.to_measurement(traj)
        mem = self._memory(coupling)
        traj, y = mem.integrate(start, t, U, hold=hold, method=method, tolerances=tol)
        out = self.to_measurement(traj, y)
        out.meta["simulation"]["coupling"] = mem.coupling
        return out

    def _memory(self, coupling: float | None) -> Any:
        return MemoryCoupling(self, COUPLING if coupling is None else coupling)

    def stepper(self, dt: float, *, x0: Any = None, method: str = "rodas4",
                rtol: float = DEFAULT_TOLERANCES.rtol,
                atol: float = DEFAULT_TOLERANCES.atol, coupling: float | None = None) -> Any:
        """A :class:`~fcomp.simulation.Stepper` advancing the plant ``dt`` s per ``step(u)``
        (:class:`plants.discrete_memory.MemoryStepper` for friction with discrete memory)."""
        tol = Tolerances(rtol=rtol, atol=atol)
        if self.friction.discrete_memory() is None:
            return Stepper(self.ode_model(), dt, self.param_vector(), self._x0(x0),
                           method=method, tolerances=tol)
        return MemoryStepper(self._memory(coupling), dt, self._x0(x0), method=method,
                             tolerances=tol)

    def evaluate_outputs(self, X: np.ndarray, U: np.ndarray,
                         values: Mapping[str, Any] | None = None) -> dict[str, np.ndarray]:
        """Every output at the samples ``X (n, nx)``, ``U (n, nu)`` (numpy; ``values``:
        flat parameters, scalars or one value per sample)."""
        if self.friction.discrete_memory() is not None:
            return self._memory(None).outputs(X, U)
        P = self.param_values(NUMPY, values)
        _, y = self._evaluate(NUMPY, [X[:, i] for i in range(self.nx)],
                              [U[:, j] for j in range(self.nu)], P)
        n = X.shape[0]
        return {k: np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy() for k, v in y.items()}

    def to_measurement(self, traj: Trajectory,
                       y: Mapping[str, np.ndarray] | None = None) -> Measurement:
        """A simulated run as a :class:`~fcomp.measurement.Measurement` (data-format.md);
        ``y``: the outputs if already evaluated."""
        if y is None:
            y = self.evaluate_outputs(traj.X, traj.U)
        cols: dict[str, np.ndarray] = {"t": traj.t}
        for name in self.output_names:
            cols[name] = y[name]
        for j, name in enumerate(self.input_names):
            cols.setdefault(name, traj.U[:, j])
        for i, name in enumerate(self.friction.state_names):
            col = name if name not in cols else f"friction_{name}"
            cols[col] = traj.X[:, len(self.plant_states) + i]
        tol = traj.tolerances
        meta: dict[str, Any] = {
            "name": f"{self.name}-{self.friction.name}",
            "kind": self.kind,
            "pressure": "gauge",
            "p_atm": float(self.plant_params.flat().get("p_atm", 101325.0)),
            "rig": self.rig_meta(),
            "signals": {"u_unit": self.input_units[0]} if self.input_units[0] in ("A", "V")
            else {},
            "simulation": {
                "plant": self.name,
                "friction": self.friction.describe(),
                "params": self.paramset.name if self.paramset else "defaults",
                "inputs": {n: u for n, u in zip(self.input_names, self.input_units, strict=True)},
                "method": traj.method,
                "hold": traj.hold,
                "rtol": tol.rtol,
                "atol": tol.atol,
                "duration": float(traj.t[-1] - traj.t[0]),
                "rate": float((traj.t.size - 1) / (traj.t[-1] - traj.t[0])),
                **traj.stats.as_dict(),
                "x0": {n: float(v) for n, v in zip(self.state_names, traj.X[0], strict=True)},
                "plant_params": self.plant_params.flat(),
                "friction_params": self.friction.flat_params(),
                "fcomp_version": __version__,
            },
        }
        if not meta["signals"]:
            del meta["signals"]
        return Measurement(cols, meta)

    def to_iosys(self, name: str | None = None) -> Any:
        """The plant as a python-control ``NonlinearIOSystem``.

        ``updfcn(t, x, u, params)`` and ``outfcn`` evaluate the CasADi
        functions of :meth:`casadi_functions`; ``params`` (python-control's
        dict) may change any parameter of :meth:`flat_params` by name.
        """
        fns = self.casadi_functions(symbolic_params=True)  # first: refuse non-symbolic models


        f, g = fns["rhs"], fns["outputs"]
        base = self.flat_params()
        names = list(base)
        p0 = np.array(list(base.values()), dtype=float)

        def pvec(params: Mapping[str, Any] | None) -> np.ndarray:
            if not params:
                return p0
            p = p0.copy()
            for k, v in params.items():
                if k in base:
                    p[names.index(k)] = float(v)
            return p

        def updfcn(t: float, x: Any, u: Any, params: Any = None) -> np.ndarray:
            return np.asarray(f(x, u, pvec(params)), dtype=float).ravel()

        def outfcn(t: float, x: Any, u: Any, params: Any = None) -> np.ndarray:
            return np.asarray(g(x, u, pvec(params)), dtype=float).ravel()

        return _named_iosys()(
            updfcn, outfcn, states=list(self.state_names), inputs=list(self.input_names),
            outputs=list(self.output_names), name=name or self.name.replace("-", "_"),
            params=dict(base),
        )


_IOSYS: list[type] = []


def _named_iosys() -> type:
    """python-control's ``NonlinearIOSystem`` whose ``linearize`` keeps the signal names.

    The linear system of ``plant.to_iosys().linearize(x0, u0)`` has the plant's
    state, input and output names (``x``, ``v``, ``p1``, ...; python-control's
    default would number them ``x[0]``, ``u[0]``, ``y[0]``), so it can be
    connected and indexed by name; pass ``copy_names=False`` for the numbered ones.
    """
    if not _IOSYS:
        import control as ct

        class PlantIOSystem(ct.NonlinearIOSystem):
            __doc__ = _named_iosys.__doc__

            def linearize(self, x0: Any, u0: Any = None, t: float = 0, params: Any = None,
                          eps: float = 1e-6, copy_names: bool = True, **kwargs: Any) -> Any:
                return super().linearize(x0, u0, t=t, params=params, eps=eps,
                                         copy_names=copy_names, **kwargs)

        _IOSYS.append(PlantIOSystem)
    return _IOSYS[0]


def friction_state_scales(model: FrictionModel) -> np.ndarray:
    """Nominal magnitude of each friction state: its largest steady-state value.

    Evaluated at ``|v|`` = 1e-3 .. 1 m/s in both directions (e.g. ``z ~ g/sigma0``,
    film ``h ~ 1 - Fc/Fs``); a state that stays 0 there gets 1.
    """
    if model.n_states == 0:
        return np.zeros(0)
    v = np.array([-1.0, -0.1, -0.01, -1e-3, 1e-3, 0.01, 0.1, 1.0])
    P = model.param_values(NUMPY)
    sig = Signals(v=v, a=0.0, x=0.0, p1=0.0, p2=0.0, s=np.where(v >= 0, 1.0, -1.0))
    ss = model.steady_state_states(NUMPY, sig, P)
    out = []
    for s in ss:
        m = float(np.max(np.abs(np.broadcast_to(np.asarray(s, dtype=float), v.shape))))
        out.append(m if m > 0 and math.isfinite(m) else 1.0)
    return np.array(out)
