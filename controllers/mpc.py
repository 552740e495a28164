"""``mpc``: nonlinear model predictive control by real-time iteration (CasADi + DAQP), fed by the EKF.

Prediction model
----------------
The controller's plant model with its friction model (``nmlgm`` by
default): the symbolic right-hand side of :mod:`plants` (valve, chambers,
piston, friction states ``z`` and ``h``), discretised at the MPC sample
time ``dt`` by the linearly implicit Euler step the plant gives
(:meth:`plants.base.OdePlant.discrete_step`, :mod:`controllers.prediction`;
L-stable: the stiff bristle and oil dynamics are stable at ``dt = 2`` ms). The initial state is the EKF's
estimate (:mod:`controllers.ekf`), so the friction states the prediction
starts from are estimated, not assumed.

Optimal control problem (horizon ``N`` steps, input ``u_0..u_{N-1}`` held
over each step)::

    min  sum_k ((x_k - r_k)/e_x)^2 + ((v_k - dr_k)/e_v)^2 + ((u_k - u_{k-1})/(e_du*u_max))^2
    s.t. x_{k+1} = Phi(x_k, u_k)                       (plant + friction model)
         -u_max <= u_k <= u_max                         (valve limits)
         |u_k - u_{k-1}| <= du_max*dt                   (valve rate limits; u_{-1} applied)

with ``r_k`` the reference positions over the horizon (the harness's
preview) and ``dr_k`` their finite differences.

Real-time iteration (Diehl, Bock et al., "Real-time optimization and
nonlinear model predictive control of processes governed by
differential-algebraic equations", J. Process Control 12, 2002): one
Gauss-Newton SQP step per sample, warm-started from the previous solution
shifted by one sample. The states are eliminated (condensing): the
predicted trajectory and its sensitivity to the inputs are computed by one
CasADi function, compiled to C, that chains the model step and its step
Jacobians ``A_k = (I - h J_k)^{-1}``, ``B_k = h A_k df/du`` (the
linearly-implicit step's own sensitivities, the change of ``J_k`` along
the step neglected -- an inexact-Jacobian SQP; the same step, with
``sensitivities=True``); it returns the
Gauss-Newton Hessian ``H = J'J`` and gradient ``g = J'r`` of the
least-squares cost. The resulting dense QP in the ``N`` input increments
(box constraints for the valve limits, a banded set for the rate limits)
is solved by DAQP (Arnstrom, Bemporad & Axehill, "A dual active-set solver
for embedded quadratic programming using recursive LDL' updates", IEEE TAC
67(8), 2022), warm-started from the previous active set.

Safety
------
* **Infeasible set-up** (refused in one line at construction/reset):
  a horizon below 2, non-positive tolerances, limits, rate limits or
  rates, a valve range that cannot hold the load at the start (the
  controller model's equilibrium command outside ``+-u_max``), or a QP
  that cannot be solved at the start.
* **Run-time failure** (QP not solved, non-finite prediction): the step
  falls back to the stated fallback law -- the ``ekf`` controller's force
  law *without integral action* (PD on the position error, rigid-body and
  weight feedforward, the EKF friction estimate, through
  :mod:`controllers.force_to_valve`), rate-limited to the valve rate --
  and the warm start is reset to that command. Every such step is counted
  (``fallbacks``, reported in the metrics).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import casadi as ca
import daqp
import numpy as np

from controllers.base import Controller, Reference
from controllers.ekf import make_ekf
from controllers.force_to_valve import ForceToValve
from controllers.native import native
from controllers.plant_model import equilibrium
from controllers.prediction import ContinuousModel
from fcomp.errors import FcompError

#: Defaults of the MPC's options. The controller derives its horizon and velocity
#: tolerance from the plant (:mod:`controllers.tuning`, rule 6: ``T_N = pi/w_h``,
#: ``e_v = e_x*w_F/2``); ``horizon`` and ``velocity_tol`` here are the fixed problem of
#: :mod:`controllers.mpc_benchmark`.
DEFAULTS: dict[str, float] = {
    "rate": 500.0,          # Hz
    "horizon": 20,          # steps
    "substeps": 2,          # integration steps per MPC step
    "position_tol": 5e-5,   # m, e_x
    "velocity_tol": 5e-3,   # m/s, e_v
    "du_tol": 0.005,        # e_du, fraction of u_max per step
}


@dataclass(frozen=True)
class MPCProblem:
    """Sizes, weights and limits of the optimal control problem (SI; module docstring)."""

    horizon: int
    dt: float
    substeps: int
    position_tol: float
    velocity_tol: float
    du_tol: float
    u_max: float
    du_max: float

    def __post_init__(self) -> None:
        if not (isinstance(self.horizon, int) and self.horizon >= 2):
            raise FcompError(f"infeasible MPC set-up: horizon must be an integer >= 2 steps, "
                             f"got {self.horizon!r}")
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise FcompError(f"infeasible MPC set-up: substeps must be an integer >= 1, "
                             f"got {self.substeps!r}")
        for name in ("dt", "position_tol", "velocity_tol", "du_tol", "u_max", "du_max"):
            val = getattr(self, name)
            if not (isinstance(val, int | float) and math.isfinite(val) and val > 0):
                raise FcompError(f"infeasible MPC set-up: {name} must be a positive number, "
                                 f"got {val!r}")


class RTISolver:
    """Condensed Gauss-Newton real-time iteration (see the module docstring)."""

    def __init__(self, model: ContinuousModel, problem: MPCProblem) -> None:
        self.model = model
        self.problem = problem
        N, nx = problem.horizon, model.nx
        ix, iv = model.index("x"), model.index("v")
        step = model.step(problem.dt, problem.substeps, sensitivities=True, scale_input=True)
        x0 = ca.MX.sym("x0", nx)
        U = ca.MX.sym("U", N)
        u_prev = ca.MX.sym("u_prev")
        R = ca.MX.sym("R", N)
        V = ca.MX.sym("V", N)
        P = ca.MX.sym("p", model.p.size)
        Sc = ca.MX.sym("s", nx)  # state scales: an input, as the parameters
        wx, wv = 1.0 / problem.position_tol, 1.0 / problem.velocity_tol
        wdu = 1.0 / (problem.du_tol * problem.u_max)
        xk = x0
        Sk = ca.MX.zeros(nx, N)
        res, jac, xs = [], [], []
        E = np.eye(N)
        for k in range(N):
            xk, A, B = step(xk, U[k], P, Sc)
            Sk = ca.mtimes(A, Sk) + ca.mtimes(B, ca.DM(E[k:k + 1, :]))
            res += [wx * (xk[ix] - R[k]), wv * (xk[iv] - V[k])]
            jac += [wx * Sk[ix, :], wv * Sk[iv, :]]
            xs.append(xk[ix])
        D = np.eye(N) - np.eye(N, k=-1)
        res_du = wdu * (ca.mtimes(ca.DM(D), U) - ca.vertcat(u_prev, ca.MX.zeros(N - 1)))
        r = ca.vertcat(*res, res_du)
        Jm = ca.vertcat(*jac, ca.DM(wdu * D))
        H = ca.mtimes(Jm.T, Jm)
        g = ca.mtimes(Jm.T, r)
        cost = 0.5 * ca.dot(r, r)
        fn = ca.Function(f"mpc_rti_N{N}", [x0, U, u_prev, R, V, P, Sc],
                         [H, g, cost, ca.vertcat(*xs)],
                         ["x0", "U", "u_prev", "R", "V", "p", "s"], ["H", "g", "cost", "X"])
        self.p = np.asarray(model.p, dtype=float)
        self.scales = np.asarray(model.scales, dtype=float)
        self._lin = native(fn)
        self.D = D
        self.reg = 1e-10
        self.U = np.zeros(N)
        self.cost = math.nan
        self.iterations = 0
        self._lam: np.ndarray | None = None

    def reset(self, u0: float) -> None:
        self.U = np.full(self.problem.horizon, float(u0))
        self._lam = None

    def shift(self) -> None:
        """Warm start: the previous solution one sample on."""
        self.U = np.concatenate([self.U[1:], self.U[-1:]])

    def iterate(self, x0: np.ndarray, u_prev: float, R: np.ndarray, V: np.ndarray) -> bool:
        """One Gauss-Newton step of the QP from the current ``U``; ``False`` if it failed."""
        p = self.problem
        H, g, cost, _X = self._lin(x0, self.U, u_prev, R, V, self.p, self.scales)
        if not (np.all(np.isfinite(H)) and np.all(np.isfinite(g))):
            return False
        N = p.horizon
        H = H + (self.reg * max(float(np.trace(H)) / N, 1.0)) * np.eye(N)
        du = p.du_max * p.dt
        diff = self.D @ self.U - np.concatenate([[u_prev], np.zeros(N - 1)])
        upper = np.concatenate([p.u_max - self.U, du - diff])
        lower = np.concatenate([-p.u_max - self.U, -du - diff])
        kwargs: dict[str, Any] = {}
        if self._lam is not None:
            kwargs["dual_start"] = self._lam
        dU, _f, flag, info = daqp.solve(H, g, self.D, upper, lower, **kwargs)
        if flag < 1 or not np.all(np.isfinite(dU)):
            self._lam = None
            return False
        self._lam = np.asarray(info["lam"], dtype=float)
        self.U = self.U + np.asarray(dU, dtype=float)
        self.cost = float(cost[0])
        self.iterations += 1
        return True


class MPCController(Controller):
    """Nonlinear MPC by real-time iteration on the EKF's estimate (see the module docstring).

    Parameters
    ----------
    rate
        MPC sample rate (Hz), default 500.
    horizon
        Prediction horizon (steps), default half a period of the oil (air) column
        (:mod:`controllers.tuning`, ``ceil(pi/w_h*rate)``).
    substeps
        Integration steps per MPC step (prediction model and EKF), default 2.
    position_tol, velocity_tol
        Error scales ``e_x`` (m) and ``e_v`` (m/s) of the cost; ``e_v`` defaults to
        ``e_x*w_F/2``, ``w_F`` the derived force-loop bandwidth (:mod:`controllers.tuning`).
    du_tol
        Command-increment scale ``e_du`` (fraction of ``u_max`` per step).
    u_max, du_max
        Valve limit (command unit) and rate limit (unit/s); default the plant's.
    q_scale, q_friction
        EKF options (:class:`~controllers.ekf.EKFController`).
    """

    name: ClassVar[str] = "mpc"
    options: ClassVar[tuple[str, ...]] = (
        "rate", "horizon", "substeps", "position_tol", "velocity_tol", "du_tol", "u_max", "du_max",
        "q_scale", "q_friction",
    )

    def __init__(self, model: Any, **options: Any) -> None:
        options.setdefault("rate", DEFAULTS["rate"])
        super().__init__(model, **options)
        o = self.opts
        tu = model.tuning
        position_tol = float(o.get("position_tol", DEFAULTS["position_tol"]))
        self.problem = MPCProblem(
            horizon=o.get("horizon", tu.mpc_horizon(1.0 / self.dt)),
            dt=self.dt,
            substeps=o.get("substeps", int(DEFAULTS["substeps"])),
            position_tol=position_tol,
            velocity_tol=float(o.get("velocity_tol", position_tol * tu.mpc_velocity_ratio)),
            du_tol=float(o.get("du_tol", DEFAULTS["du_tol"])),
            u_max=float(o.get("u_max", model.u_max)),
            du_max=float(o.get("du_max", model.du_max)),
        )
        if self.problem.u_max > model.u_max:
            raise FcompError(f"infeasible MPC set-up: u_max {self.problem.u_max:g} exceeds the "
                             f"valve range {model.u_max:g}")
        _, u_eq = equilibrium(model.plant, 0.5 * model.stroke)
        if abs(u_eq) >= self.problem.u_max:
            raise FcompError(
                f"infeasible MPC set-up: holding the load needs a valve command of {u_eq:.4g}, "
                f"outside the limits +-{self.problem.u_max:g}"
            )
        self.preview = self.problem.horizon
        self.ekf = make_ekf(model, self.dt, o, substeps=self.problem.substeps)
        self.solver = RTISolver(model.prediction, self.problem)
        # fallback law: PD (placed gains without the integral) through the force loop
        self.fallback_gains = model.tuning.pid_gains
        self.valve = ForceToValve(model, model.force_bandwidth)
        self.iv = model.prediction.index("v")
        self._u_prev = 0.0
        self._ref_prev = 0.0

    def reset(self, t0: float, y0: np.ndarray, ref: Reference) -> None:
        m = self.model
        x0, P0 = m.estimator_initial(y0)
        self.ekf.reset(x0, P0)
        self.fallbacks = 0
        self.fallback_active = False
        _, u_eq = equilibrium(m.plant, float(y0[0]))
        self._u_prev = u_eq
        self.solver.reset(u_eq)
        N = self.problem.horizon
        R = np.full(N, ref.r)
        ok = True
        for _ in range(5):  # converge the warm start before the first sample
            ok = self.solver.iterate(x0, u_eq, R, np.zeros(N)) and ok
        if not ok:
            raise FcompError("infeasible MPC set-up: the QP at the initial state could not be "
                             "solved (check the limits and tolerances)")
        self.friction_estimate = 0.0

    def reenter(self, t: float, y: np.ndarray, ref: Reference, u: float) -> None:
        """Resume after the fail-safe layer held the valve at ``u``: the EKF started from the
        measurement ``y`` (as :meth:`reset`), the warm start at ``u`` (no equilibrium solve:
        the exported step does the same)."""
        x0, P0 = self.model.estimator_initial(y)
        self.ekf.reset(x0, P0)
        self._u_prev = float(u)
        self.solver.reset(u)
        self.fallback_active = False

    def applied(self, u: float) -> None:
        """The EKF and the rate limits take the command the valve was given."""
        self._u_prev = u

    def healthy(self) -> bool:
        kf, sol = self.ekf.kf, self.solver
        parts = [kf.x, kf.P, sol.U, [self._u_prev]] + ([] if sol._lam is None else [sol._lam])
        return all(bool(np.all(np.isfinite(p))) for p in parts)

    def _horizon_reference(self, ref: Reference) -> tuple[np.ndarray, np.ndarray]:
        N = self.problem.horizon
        fut = np.asarray(ref.future, dtype=float)
        if fut.size < N:
            fut = np.concatenate([fut, np.full(N - fut.size, fut[-1] if fut.size else ref.r)])
        R = fut[:N]
        V = np.diff(np.concatenate([[ref.r], R])) / self.dt
        return R, V

    def _fallback(self, x_hat: np.ndarray, y: np.ndarray, ref: Reference, F_hat: float) -> float:
        g = self.fallback_gains
        m = self.model
        v = float(x_hat[self.iv])
        demand = (m.mass * ref.ddr + m.weight + g.kp * (ref.r - float(y[0]))
                  + g.kd * (ref.dr - v) + F_hat)
        demand = min(max(demand, m.force_min), m.force_max)
        u, _ = self.valve.command(demand, y, v)
        du = self.problem.du_max * self.dt
        return min(max(u, self._u_prev - du), self._u_prev + du)

    def step(self, t: float, y: np.ndarray, ref: Reference) -> float:
        x_hat = self.ekf.step(y, self._u_prev)
        F_hat = self.ekf.friction(self._u_prev)
        self.friction_estimate = F_hat
        R, V = self._horizon_reference(ref)
        self.solver.shift()
        ok = self.solver.iterate(x_hat, self._u_prev, R, V)
        if ok:
            u = float(self.solver.U[0])
            self.fallback_active = False
        else:
            u = self._fallback(x_hat, y, ref, F_hat)
            self.solver.reset(u)
            self.fallback_active = True
            self.fallbacks += 1
        self._u_prev = u
        return u
