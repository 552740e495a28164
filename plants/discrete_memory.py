"""Plants with discrete-memory friction (``nmlgm-hysteresis``, ``nonlocal-memory``).

Seed 000's hysteresis function ``F(z)`` (:mod:`fcomp.models.hysteresis`) keeps a
turning-point memory, so plant plus friction is no ODE the engine (or CasADi)
can take whole. The engine takes it in short *coupling intervals* ``D``
(default at most 1e-4 s and never longer than the output interval):

1. At the start of an interval the memory gives ``F_k = F(z_k)`` and the
   local slope ``K_k = dF/dz`` of the current curve in the direction of the
   motion (probed on a copy of the memory, 1 nm ahead; kept within
   ``[0, 10*max(sigma0, c_i*k_i)]``, since a regime change just ahead --
   entering sliding, closing a loop -- is a jump of ``F``, not a slope).
2. The engine (:mod:`fcomp.simulation`) integrates the plant with a *twin*
   friction model, :class:`LocalBristle`: the LuGre-family model the
   hysteresis model is built on (same ``g(v, h)``, film state, effects,
   ``sigma1``, ``sigma2``, ``T`` -- so ``T*dv/dt`` is still solved exactly),
   whose bristle force is the tangent ``F_k + K_k*(z - z_k)`` instead of
   ``F(z)``. Exact on the sliding line and on straight pieces of the
   curves, second order in ``D`` on the curved ones.
3. The memory is then driven along the deflection the engine computed,
   ``F_{k+1} = F(z_{k+1})`` (:meth:`~fcomp.models.hysteresis.HysteresisFunction.move_to`,
   the rate-independent operator with the sliding threshold ``Fs/sigma0``),
   so every memory rule (reversals, wiping-out, return points, sliding
   latch) is applied exactly to the deflection path; ``z`` stays the
   engine's.

With the no-op parameters of the ``nonlocal-memory`` effect (zero widths and
amplitudes) ``F(z) = sigma0*z``, the tangent is exact and the coupled run is
the NMLGM plant itself (tested). A reversal inside an interval is met with
the old curve's slope for the rest of that interval: refine with
``coupling`` (s) where pre-sliding detail matters. The price is a Python loop
per interval (~0.1 ms): seconds for seconds of simulated time.

Pressures read by the friction (effects) are the plant states ``p1``, ``p2``
(absolute) where a plant has them, else atmospheric.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from fcomp.backend import NUMPY, Backend
from fcomp.errors import FcompError, term
from fcomp.models.base import FrictionModel, Signals
from fcomp.parameters import ParamValues
from fcomp.progress import report
from fcomp.simulation import (
    DEFAULT_TOLERANCES,
    Stats,
    Stepper,
    Tolerances,
    Trajectory,
    input_rates,
    make_integrator,
    step_budget,
)

if TYPE_CHECKING:
    from plants.base import OdePlant

#: Names of the tangent's parameters in the twin model (force N, slope N/m, deflection m).
TANGENT = ("hyst_F0", "hyst_K", "hyst_z0")
#: Default longest coupling interval (s).
COUPLING = 1e-4
#: Probe distance for the local slope of F(z) (m).
_PROBE = 1e-9


class LocalBristle(FrictionModel):
    """The carrier of a hysteresis model with the tangent bristle law (module docstring).

    ``dz/dt = v - Fb*|v|/g(v, h)``, ``F = Fb + sigma1*dz/dt + sigma2*(v + T*a)``
    with ``Fb = hyst_F0 + hyst_K*(z - hyst_z0)``: the carrier's equations
    evaluated at the deflection ``Fb/sigma0``. Symbolic; parameters are the
    carrier's plus :data:`TANGENT`.
    """

    name = "local-bristle"
    static_map = False

    def __init__(self, carrier: FrictionModel) -> None:  # no super().__init__: a view
        self.carrier = carrier
        self.params = carrier.params
        self.effects = carrier.effects

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.carrier.state_names

    def structure_key(self) -> tuple:
        return (type(self), type(self.carrier), tuple(type(e) for e in self.effects),
                tuple(self.flat_params()))

    def flat_params(self) -> dict[str, float]:
        s0 = self.carrier.flat_params()["sigma0"]
        return {**self.carrier.flat_params(), TANGENT[0]: 0.0, TANGENT[1]: s0, TANGENT[2]: 0.0}

    def initial_state(self) -> np.ndarray:
        return self.carrier.initial_state()

    def describe(self) -> str:
        return f"{self.carrier.describe()} (tangent bristle)"

    def base_force(self, be: Backend, x: list[Any], dx: list[Any], sig: Signals,
                   P: ParamValues, L: dict) -> tuple[Any, Any]:  # pragma: no cover - unused
        """Not part of this view: its force comes from the carrier's equations (class docstring)."""
        raise TypeError(f"{self.name}: evaluated through its carrier "
                        f"{self.carrier.describe()!r}; base_force is never called on the view")

    def _states(self, x: Sequence[Any], P: ParamValues) -> list[Any]:
        x = list(x)
        Fb = P(TANGENT[0]) + P(TANGENT[1]) * (x[0] - P(TANGENT[2]))
        return [Fb / P("sigma0"), *x[1:]]

    def rhs(self, be: Backend, x: Sequence[Any], sig: Signals, P: ParamValues) -> list:
        return self.carrier.rhs(be, self._states(x, P), sig, P)

    def force_parts(self, be: Backend, x: Sequence[Any], sig: Signals,
                    P: ParamValues) -> tuple[Any, Any]:
        return self.carrier.force_parts(be, self._states(x, P), sig, P)

    def steady_state_states(self, be: Backend, sig: Signals, P: ParamValues) -> list:
        return self.carrier.steady_state_states(be, sig, self.carrier.param_values(be))


class MemoryCoupling:
    """Runs a plant whose friction has discrete memory (module docstring).

    Parameters
    ----------
    plant
        The plant with the hysteresis friction model.
    coupling
        Longest coupling interval (s).
    """

    def __init__(self, plant: OdePlant, coupling: float = COUPLING) -> None:
        if not (math.isfinite(coupling) and coupling > 0):
            raise FcompError(f"{term('coupling')} interval must be a positive number of "
                             f"seconds, got {coupling}")
        self.plant = plant
        memory = plant.friction.discrete_memory()
        if memory is None:
            raise FcompError(f"plant {plant.name}: friction {plant.friction.describe()!r} has "
                             "no discrete memory to couple")
        self.model = memory
        self.coupling = float(coupling)
        self.local = LocalBristle(memory.carrier())
        self.twin = type(plant)(self.local, plant.paramset,
                                overrides=plant.plant_params.flat())
        names = list(self.twin.flat_params())
        self.i_tan = [names.index(n) for n in TANGENT]
        self.p_twin = self.twin.param_vector()
        self.n_plant = len(plant.plant_states)
        self.i_F = plant.friction.state_names.index(memory.memory_state)  # "Fz"
        self.P = plant.friction.param_values(NUMPY)
        self.p_atm = plant.plant_params.flat().get("p_atm", 101325.0)
        states = plant.plant_states
        self._ip = [states.index(n) if n in states else None for n in ("p1", "p2")]
        # without effects the levels are the parameters: zs = Fs/sigma0 of the side
        flat = plant.friction.flat_params()
        steep = [abs(flat.get(f"c{i}", 0.0) * flat.get(f"k{i}", 0.0)) for i in (1, 2, 3, 8)]
        self.k_max = 10.0 * max(flat["sigma0"], *steep)
        if not plant.friction.effects:
            zs = [self.P("Fs" if self.P.has("Fs") else "Fc", s) / flat["sigma0"]
                  for s in (1.0, -1.0)]
            self._zs: tuple[float, float] | None = (abs(float(zs[0])), abs(float(zs[1])))
        else:
            self._zs = None

    # ----------------------------------------------------------- states
    def to_twin(self, x: np.ndarray) -> np.ndarray:
        return np.delete(np.asarray(x, dtype=float), self.n_plant + self.i_F)

    def from_twin(self, xt: np.ndarray, F: Any) -> np.ndarray:
        return np.insert(np.asarray(xt, dtype=float), self.n_plant + self.i_F, F, axis=-1)

    def threshold(self, xt: np.ndarray, F: float) -> float:
        """Sliding threshold ``zs = Fs/sigma0`` (effects included) at twin state ``xt``."""
        if self._zs is not None:
            return self._zs[1] if xt[1] < 0 else self._zs[0]
        full = self.from_twin(xt, F)
        pg = [0.0 if i is None else xt[i] - self.p_atm for i in self._ip]
        v = float(xt[1])
        sig = Signals(v=v, a=0.0, x=float(xt[0]), p1=pg[0], p2=pg[1], s=-1.0 if v < 0 else 1.0)
        _, zs = self.model.bristle_inputs(list(full[self.n_plant:]), sig, self.P)
        return float(zs)

    def slope(self, hf: Any, v: float, zs: float) -> float:
        """``dF/dz`` of the memory's current curve in the direction of ``v``, within
        ``[0, K_max]``: a regime change one probe ahead (entering sliding, closing a loop)
        is a jump of ``F``, not a slope."""
        d = 1.0 if v > 0 else -1.0 if v < 0 else float(hf.direction or 1)
        snap = hf.snapshot()
        F1 = hf.move_to(hf.z + d * _PROBE, zs)
        hf.restore(snap)
        K = (F1 - hf.F) / (d * _PROBE)
        return min(max(K, 0.0), self.k_max) if math.isfinite(K) else self.k_max

    # --------------------------------------------------------------- run
    def start(self, x0: np.ndarray) -> Any:
        """A fresh memory (virgin) at the friction state of ``x0``."""
        hf = self.model.hysteresis_function()
        x0 = np.asarray(x0, dtype=float)
        hf.reset(x0[self.n_plant], x0[self.n_plant + self.i_F])
        return hf

    def intervals(self, T: float) -> int:
        """Number of coupling intervals in a sample interval of ``T`` s."""
        return max(1, math.ceil(T / self.coupling - 1e-9))

    def advance(self, integ: Any, hf: Any, xt: np.ndarray, u0: np.ndarray, du: np.ndarray,
                T: float, tol: Tolerances, h: float, stats: Stats,
                t0: float = 0.0, budget: Tolerances | None = None) -> tuple[np.ndarray, float]:
        """Advance the twin state ``xt`` and the memory ``hf`` over ``T`` s, input ``u0 + du*t``
        (``t0``: time at the start, for messages). With ``budget``, its ``max_steps`` bounds
        the steps counted in ``stats`` (the whole run), else ``tol`` bounds each interval."""
        n = self.intervals(T)
        dt = np.array([T / n])
        p = self.p_twin.copy()
        iz = self.n_plant
        for j in range(n):
            zs = self.threshold(xt, hf.F)
            p[self.i_tan] = hf.F, self.slope(hf, float(xt[1]), zs), hf.z
            if budget is not None:
                tol = step_budget(budget, stats, t0 + j * dt[0], self.plant.name)
            X, st, h = integ.run(xt, (u0 + du * j * dt[0])[None, :], du[None, :], dt, p, tol, h,
                                 t0 + j * dt[0])
            xt = X[-1]
            hf.move_to(float(xt[iz]), zs)
            xt[iz] = hf.z
            stats.add(st)
        return xt, h

    def integrate(self, x0: np.ndarray, t: np.ndarray, U: np.ndarray, *, hold: str = "linear",
                  method: str = "rodas4",
                  tolerances: Tolerances = DEFAULT_TOLERANCES) -> tuple[Trajectory, dict]:
        """The run over the sample instants ``t``: trajectory (plant states with the memory's
        ``Fz``) and the outputs at every sample."""
        dU = input_rates(t, U, hold)
        dts = np.diff(t)
        needed = int(np.sum(np.maximum(1, np.ceil(dts / self.coupling - 1e-9))))
        if needed > tolerances.max_steps:
            raise FcompError(
                f"plant {self.plant.name}: a coupling interval of {self.coupling:g} s over "
                f"{float(t[-1] - t[0]):g} s needs {needed:.3g} coupling intervals of at least "
                f"one step each, more than {term('max_steps')} = {tolerances.max_steps}; raise "
                f"{term('coupling')} (default {COUPLING:g} s) or {term('max_steps')}")
        integ = make_integrator(self.twin.ode_model(), method)
        hf = self.start(x0)
        xt = self.to_twin(x0)
        Xt = np.empty((t.size, xt.size))
        Fz = np.empty(t.size)
        Xt[0], Fz[0] = xt, hf.F
        stats = Stats()
        h = tolerances.h0
        for k in range(t.size - 1):
            xt, h = self.advance(integ, hf, xt, U[k], dU[k], t[k + 1] - t[k], tolerances, h,
                                 stats, t[k], budget=tolerances)
            Xt[k + 1], Fz[k + 1] = xt, hf.F
            report(float(t[k + 1] - t[0]), float(t[-1] - t[0]))
        X = self.from_twin(Xt, Fz)
        traj = Trajectory(t=t, X=X, U=U, stats=stats, method=method, tolerances=tolerances,
                          hold=hold)
        return traj, self.outputs(X, U)

    def outputs(self, X: np.ndarray, U: np.ndarray) -> dict[str, np.ndarray]:
        """The plant's outputs at samples ``X`` (plant states with ``Fz``), ``U``: the twin's
        with the tangent through each sample's ``(z, Fz)``."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        Xt = np.delete(X, self.n_plant + self.i_F, axis=1)
        values: dict[str, Any] = dict(self.twin.flat_params())
        values.update({TANGENT[0]: X[:, self.n_plant + self.i_F],
                       TANGENT[2]: X[:, self.n_plant]})
        return self.twin.evaluate_outputs(Xt, U, values=values)


class MemoryStepper(Stepper):
    """Closed-loop stepping of a plant with discrete-memory friction (input held per sample).

    The stepper contract of :mod:`fcomp.stepper` (``reset``, ``advance``, ``t``, ``x``)
    with :class:`fcomp.simulation.Stepper`'s ``step(u)`` and ``stats``; ``x`` holds the
    plant states with the memory's ``Fz``. ``advance(u, dt)`` runs
    :meth:`MemoryCoupling.advance`: the engine on the twin plant in coupling intervals,
    the memory driven along the deflection after each.
    """

    def __init__(self, coupling: MemoryCoupling, dt: float, x0: np.ndarray, *,
                 method: str = "rodas4", tolerances: Tolerances = DEFAULT_TOLERANCES) -> None:
        self.coupling = coupling
        super().__init__(coupling.twin.ode_model(), dt, coupling.p_twin, x0, method=method,
                         tolerances=tolerances)

    @property
    def name(self) -> str:
        return self.coupling.plant.name

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.coupling.plant.state_names

    def _start(self, x: np.ndarray) -> None:
        super()._start(x)
        self.memory = self.coupling.start(x)
        self._xt = self.coupling.to_twin(x)

    def _advance(self, u: np.ndarray, dt: float) -> np.ndarray:
        self._xt, self.h = self.coupling.advance(self.integrator, self.memory, self._xt, u,
                                                 self._dU[0], dt, self.tolerances, self.h,
                                                 self.stats, self.t)
        return self.coupling.from_twin(self._xt, self.memory.F)
