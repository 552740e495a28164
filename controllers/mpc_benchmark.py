"""MPC step time: fcomp's real-time iteration beside do-mpc on the same problem; EKF step time.

The problem (:func:`compare`): the hydraulic servo of seed 002 with NMLGM
friction in the prediction model (8 states: piston, chambers, servo valve,
``z``, ``h``), horizon ``N`` steps of ``dt`` (default 20 x 2 ms), the
least-squares cost of :mod:`controllers.mpc` (position and velocity
tracking, command increments) and the valve limits. The closed loop runs
on the plant simulated by the engine (the same model, no mismatch, state
fed back exactly: only the optimiser is timed), tracking the
``seed002-sine`` reference from rest.

* **fcomp** -- :class:`controllers.mpc.RTISolver`: condensed Gauss-Newton
  real-time iteration, one QP (DAQP) per sample, compiled linearisation;
  valve rate limits as constraints.
* **do-mpc** (Lucia et al., J. Process Control 2017; Fiedler et al.,
  Processes 2023) -- its standard set-up: orthogonal collocation on finite
  elements (Radau, degree 2) and IPOPT, warm-started from the previous
  solution, states scaled by the plant's scales and the input by ``u_max``
  (its ``rterm`` then acts on the scaled input); the cost's ``lterm`` on
  ``x_0..x_{N-1}`` plus the same term as ``mterm`` on ``x_N``, the command
  increments as do-mpc's ``rterm``; the valve limits as bounds. do-mpc has
  no rate constraint on the input; the rate limit is not active on this
  reference for either solver.

Only the optimiser call is timed (:func:`time.perf_counter`): ``iterate``
for fcomp, ``make_step`` for do-mpc.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import time
from typing import Any

import numpy as np

from controllers.mpc import DEFAULTS, MPCProblem, RTISolver
from controllers.plant_model import ControlModel, equilibrium
from controllers.tasks import get_task
from fcomp.models import make_model


def do_mpc_available() -> bool:
    """Whether do-mpc can be imported (``pip install 'fcomp[bench]'``)."""
    return importlib.util.find_spec("do_mpc") is not None


def _setup(horizon: int, dt: float) -> tuple[ControlModel, MPCProblem, np.ndarray, float]:
    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))
    problem = MPCProblem(horizon=horizon, dt=dt, substeps=int(DEFAULTS["substeps"]),
                         position_tol=DEFAULTS["position_tol"],
                         velocity_tol=DEFAULTS["velocity_tol"], du_tol=DEFAULTS["du_tol"],
                         u_max=model.u_max, du_max=model.du_max)
    x0, u0 = equilibrium(model.plant, 0.5 * model.stroke)
    return model, problem, x0, u0


def _reference(k: int, horizon: int, dt: float, x_mid: float) -> tuple[np.ndarray, np.ndarray]:
    t = (k + 1 + np.arange(horizon)) * dt
    r, dr, _ = get_task("seed002-sine").sample(t)
    return x_mid + r, dr


def benchmark_rti(steps: int = 300, horizon: int = 20, dt: float = 2e-3) -> dict[str, Any]:
    """Closed loop with :class:`~controllers.mpc.RTISolver`; solve times and tracking error."""
    model, problem, x0, u0 = _setup(horizon, dt)
    solver = RTISolver(model.prediction, problem)
    solver.reset(u0)
    stepper = model.plant.stepper(dt, x0=x0)
    x = stepper.reset()
    x_mid = 0.5 * model.stroke
    R, V = _reference(-1, horizon, dt, x_mid)
    for _ in range(5):
        solver.iterate(x, u0, R, V)
    times, errors, u_prev, failed = [], [], u0, 0
    for k in range(steps):
        R, V = _reference(k, horizon, dt, x_mid)
        solver.shift()
        start = time.perf_counter()
        ok = solver.iterate(x, u_prev, R, V)
        times.append(time.perf_counter() - start)
        failed += not ok
        u_prev = float(solver.U[0])
        x = stepper.step(u_prev)
        errors.append(R[0] - x[0])
    return _stats(times, errors, failed)


def benchmark_do_mpc(steps: int = 300, horizon: int = 20, dt: float = 2e-3) -> dict[str, Any]:
    """The same closed loop with do-mpc (collocation + IPOPT); solve times and tracking error."""
    import warnings

    import casadi as ca

    with warnings.catch_warnings():  # do-mpc announces its optional features on import
        warnings.simplefilter("ignore", UserWarning)
        import do_mpc

    with contextlib.suppress(AttributeError):  # do-mpc calls numpy on casadi values: keep the
        ca.GlobalOptions.setNumpyMode(-1)       # legacy behaviour, without the notice

    model, problem, x0, u0 = _setup(horizon, dt)
    pm = model.prediction
    nx = pm.nx
    m = do_mpc.model.Model("continuous", "SX")
    xs = m.set_variable("_x", "x", shape=(nx, 1))
    us = m.set_variable("_u", "u")
    m.set_variable("_tvp", "r")
    m.set_variable("_tvp", "vr")
    m.set_rhs("x", pm.f(xs, us, ca.DM(pm.p)))
    m.setup()
    ix, iv = pm.index("x"), pm.index("v")
    xm, r, vr = m.x["x"], m.tvp["r"], m.tvp["vr"]
    cost = ((xm[ix] - r) / problem.position_tol) ** 2 + ((xm[iv] - vr) / problem.velocity_tol) ** 2
    mpc = do_mpc.controller.MPC(m)
    mpc.settings.n_horizon = horizon
    mpc.settings.t_step = dt
    mpc.settings.state_discretization = "collocation"
    mpc.settings.collocation_type = "radau"
    mpc.settings.collocation_deg = 2
    mpc.settings.collocation_ni = 1
    mpc.settings.store_full_solution = False
    mpc.settings.nlpsol_opts = {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": 0}
    mpc.set_objective(lterm=cost, mterm=cost)
    # do-mpc's rterm acts on the scaled input u/u_max (scaling below)
    mpc.set_rterm(u=(1.0 / problem.du_tol) ** 2)
    mpc.bounds["lower", "_u", "u"] = -problem.u_max
    mpc.bounds["upper", "_u", "u"] = problem.u_max
    mpc.scaling["_x", "x"] = np.asarray(pm.scales)
    mpc.scaling["_u", "u"] = problem.u_max
    tvp = mpc.get_tvp_template()
    x_mid = 0.5 * model.stroke
    state = {"k": -1}

    def tvp_fun(t_now: float) -> Any:
        R, V = _reference(state["k"], horizon + 1, dt, x_mid)  # r at t_k + j*dt
        for j in range(horizon + 1):
            tvp["_tvp", j, "r"] = R[j]
            tvp["_tvp", j, "vr"] = V[j]
        return tvp

    mpc.set_tvp_fun(tvp_fun)
    with contextlib.redirect_stdout(io.StringIO()):
        mpc.setup()
        mpc.x0 = x0
        mpc.u0 = u0
        mpc.set_initial_guess()
    stepper = model.plant.stepper(dt, x0=x0)
    x = stepper.reset()
    times, errors, failed = [], [], 0
    for k in range(steps):
        state["k"] = k - 1
        start = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            u = float(np.asarray(mpc.make_step(x.reshape(-1, 1))).ravel()[0])
        times.append(time.perf_counter() - start)
        failed += not bool(mpc.solver_stats.get("success", True))
        x = stepper.step(u)
        R, _ = _reference(k, 1, dt, x_mid)
        errors.append(R[0] - x[0])
    return _stats(times, errors, failed)


def benchmark_ekf(steps: int = 2000, rate: float = 1000.0) -> dict[str, Any]:
    """The EKF step (predict + update, :class:`~controllers.ekf.FrictionEKF`) on the hydraulic
    servo with NMLGM, along a simulated open-loop valve sine; solve times and estimate error."""
    from controllers.ekf import make_ekf

    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))
    dt = 1.0 / rate
    x0, u0 = equilibrium(model.plant, 0.5 * model.stroke)
    ekf = make_ekf(model, dt, {}, substeps=1)
    y_idx = list(model.prediction.measured)
    ekf.reset(*model.estimator_initial(x0[y_idx]))
    stepper = model.plant.stepper(dt, x0=x0)
    x = stepper.reset()
    rng = np.random.default_rng(0)
    std = model.sensor_std()
    times, errors, u_prev = [], [], u0
    iz = model.prediction.index("z")
    for k in range(steps):
        y = x[y_idx] + std * rng.standard_normal(3)
        start = time.perf_counter()
        xh = ekf.step(y, u_prev)
        times.append(time.perf_counter() - start)
        errors.append(xh[iz] - x[iz])
        u_prev = u0 + 2e-3 * np.sin(2 * np.pi * k * dt)
        x = stepper.step(u_prev)
    return _stats(times, errors, 0)


def _stats(times: list[float], errors: list[float], failed: int) -> dict[str, Any]:
    t = np.asarray(times)
    e = np.asarray(errors)
    return {"median": float(np.median(t)), "max": float(np.max(t)), "mean": float(np.mean(t)),
            "p99": float(np.quantile(t, 0.99)), "steps": int(t.size), "failed": int(failed),
            "rms_error": float(np.sqrt(np.mean(e**2)))}


def compare(steps: int = 300, horizon: int = 20, dt: float = 2e-3) -> dict[str, Any]:
    """Both solvers on the same closed loop, in one run; medians, maxima and speed-ups."""
    solvers = {"fcomp RTI (CasADi + DAQP)": benchmark_rti(steps, horizon, dt)}
    if do_mpc_available():
        solvers["do-mpc (collocation + IPOPT)"] = benchmark_do_mpc(steps, horizon, dt)
    out: dict[str, Any] = {"solvers": solvers, "horizon": horizon, "dt": dt,
                           "note": "plant = prediction model, exact state feedback, "
                                   "reference seed002-sine"}
    if len(solvers) == 2:
        a, b = solvers.values()
        out["speedup_median"] = b["median"] / a["median"]
        out["speedup_max"] = b["max"] / a["max"]
    return out


__all__ = ["benchmark_do_mpc", "benchmark_ekf", "benchmark_rti", "compare", "do_mpc_available"]
