"""Friction along a prescribed motion: the engine behind the ``motion`` plant and fitting.

Given sampled ``t`` and velocity ``v`` (and optionally ``a``, ``x``, ``p1``,
``p2``), the friction states are integrated sample to sample and the force
is evaluated at every sample.

Scheme
------
Between samples ``t_k`` and ``t_{k+1}`` the signals are held at their
interval means (midpoint rule: second order in the sample interval) and
the states advance by the *exponential Rosenbrock-Euler* step with the
diagonal of the exact (CasADi) Jacobian ``J = diag(df/dx)``::

    x_{k+1} = x_k + dt*phi1(dt*J)*f(x_k),   phi1(y) = (exp(y) - 1)/y,

``substeps`` times per interval. For the LuGre family the bristle equation
``dz/dt = v - sigma0*|v|*z/g`` is linear in ``z`` at fixed ``v`` and the film
equation is linear in ``h`` with a time constant that cannot switch within a
step (``h`` approaches ``h_ss`` monotonically), so the step is *exact* for
piecewise-constant velocity and unconditionally stable however stiff
(``sigma0*|v|/g*dt`` may be 1e4). Models with discrete memory
(``nmlgm-hysteresis``) provide their own stepping (``integrate_motion``).
States with hard limits (Maxwell-slip element deflections) are projected back
onto their admissible set after every step (:meth:`FrictionModel.project`).

The step is a CasADi function of ``(x, signals, dt, params)``, rolled over
chunks of samples with ``mapaccum`` and compiled to native code
(:mod:`fcomp.compiled`); parameters are inputs, so one compiled function
serves a whole identification.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from fcomp.backend import CASADI, NUMPY
from fcomp.compiled import Loop, stepping_loop
from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel, Signals, side_of
from fcomp.parameters import ParamValues


@dataclass(frozen=True)
class FrictionRun:
    """Friction along a motion (SI): time, signals, states and force at every sample."""

    t: np.ndarray
    v: np.ndarray
    a: np.ndarray
    x: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    s: np.ndarray
    states: np.ndarray  # (N, n_states)
    state_names: tuple[str, ...]
    F: np.ndarray


def _structure_key(model: FrictionModel) -> tuple:
    return (
        type(model),
        tuple((type(e), tuple(sorted(e.config.items()))) for e in model.effects),
        tuple(model.flat_params()),
    )


def _phi1(y: Any) -> Any:
    return ca.if_else(ca.fabs(y) < 1e-8, 1.0 + 0.5 * y, ca.expm1(y) / y)


_MODEL_BY_KEY: dict[tuple, FrictionModel] = {}


def friction_step(model: FrictionModel, substeps: int = 1) -> ca.Function:
    """The CasADi step ``(x, sig, dt, p) -> x_next`` of the scheme above.

    ``sig`` is the interval-mean signal vector ``[v, a, x, p1, p2, s]``, ``p``
    the flat parameters in the order of :meth:`FrictionModel.flat_params`.
    Identification differentiates this same step for exact sensitivities.
    """
    model.require_symbolic()
    nx = model.n_states
    names = list(model.flat_params())
    x = ca.SX.sym("x", nx)
    sig, sigv = Signals.symbolic()
    dt = ca.SX.sym("dt")
    p, P = ParamValues.symbolic(names)
    h = dt / substeps
    xk = x
    f_x = ca.vertcat(*model.rhs(CASADI, [x[i] for i in range(nx)], sig, P))
    J_x = ca.diag(ca.jacobian(f_x, x))  # differentiate w.r.t. the symbol, then substitute
    proj = ca.vertcat(*model.project(CASADI, [x[i] for i in range(nx)], sig, P))
    for _ in range(substeps):
        f, J = ca.substitute([f_x, J_x], [x], [xk])
        xk = xk + h * _phi1(h * J) * f
        xk = ca.substitute(proj, x, xk)
    return ca.Function("fcomp_friction_step", [x, sigv, dt, p], [xk])


@lru_cache(maxsize=64)
def _stepper(key: tuple, substeps: int, compiled: bool) -> Loop:
    return stepping_loop(friction_step(_MODEL_BY_KEY[key], substeps), compiled=compiled)


def _as_array(name: str, value: Any, n: int) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(arr)):
        raise FcompError(f"signal {name} has non-finite values")
    return arr


def prepare_signals(
    t: np.ndarray,
    v: np.ndarray,
    a: np.ndarray | None = None,
    x: np.ndarray | None = None,
    p1: Any = 0.0,
    p2: Any = 0.0,
    x0: float = 0.0,
) -> dict[str, np.ndarray]:
    """Validated sample signals; ``a`` and ``x`` derived from ``v`` if absent."""
    t = np.asarray(t, dtype=float)
    n = t.size
    if n < 2:
        raise FcompError("a motion needs at least two samples")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise FcompError("time must be finite and strictly increasing")
    v = _as_array("v", v, n)
    a = np.gradient(v, t) if a is None else _as_array("a", a, n)
    if x is None:
        x = x0 + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    x = _as_array("x", x, n)
    return {"t": t, "v": v, "a": a, "x": x, "p1": _as_array("p1", p1, n),
            "p2": _as_array("p2", p2, n), "s": side_of(v)}


def friction_along_motion(
    model: FrictionModel,
    t: np.ndarray,
    v: np.ndarray,
    *,
    a: np.ndarray | None = None,
    x: np.ndarray | None = None,
    p1: Any = 0.0,
    p2: Any = 0.0,
    state0: np.ndarray | None = None,
    values: Mapping[str, float] | None = None,
    substeps: int = 1,
    compiled: bool = True,
) -> FrictionRun:
    """Integrate ``model`` along the sampled motion and return the force at every sample.

    Parameters
    ----------
    model
        Any friction model (with effects).
    t, v
        Sample times (s, strictly increasing) and velocity (m/s).
    a, x, p1, p2
        Acceleration (m/s^2; default ``np.gradient(v, t)``), position (m;
        default the trapezoidal integral of ``v`` from 0), gauge pressures (Pa).
    state0
        Initial friction state (default :meth:`FrictionModel.initial_state`).
    values
        Flat parameter values overriding the model's (used by fitting).
    substeps
        Integration steps per sample interval (see the module docstring).
    compiled
        Run the native-compiled step (default) or CasADi's virtual machine.
    """
    if substeps < 1:
        raise ValueError("substeps must be >= 1")
    sig = prepare_signals(t, v, a, x, p1, p2)
    n = sig["t"].size
    flat = dict(model.flat_params())
    if values:
        flat.update(values)
    x0 = model.initial_state() if state0 is None else np.asarray(state0, dtype=float)
    if x0.shape != (model.n_states,):
        raise ValueError(f"state0 must have {model.n_states} entries {model.state_names}")
    if model.n_states == 0:
        X = np.zeros((n, 0))
    elif not model.symbolic:
        X = model.integrate_motion(sig, x0, flat, substeps)  # type: ignore[attr-defined]
    else:
        X = _integrate(model, sig, x0, flat, substeps, compiled)
    P = ParamValues(flat, NUMPY)
    sigs = Signals(v=sig["v"], a=sig["a"], x=sig["x"], p1=sig["p1"], p2=sig["p2"], s=sig["s"])
    F = np.asarray(model.force(NUMPY, [X[:, i] for i in range(X.shape[1])], sigs, P), float)
    F = np.broadcast_to(F, (n,)).copy()
    return FrictionRun(t=sig["t"], v=sig["v"], a=sig["a"], x=sig["x"], p1=sig["p1"],
                       p2=sig["p2"], s=sig["s"], states=X, state_names=model.state_names, F=F)


def midpoint_signals(sig: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Interval-mean signals ``(6, N-1)`` in :data:`SIGNAL_NAMES` order, and ``dt``."""
    mid = {k: 0.5 * (sig[k][1:] + sig[k][:-1]) for k in ("v", "a", "x", "p1", "p2")}
    s_mid = np.sign(mid["v"])
    s_mid = np.where(s_mid == 0, sig["s"][:-1], s_mid)
    M = np.vstack([mid["v"], mid["a"], mid["x"], mid["p1"], mid["p2"], s_mid])
    return M, np.diff(sig["t"])


def _integrate(
    model: FrictionModel,
    sig: Mapping[str, np.ndarray],
    x0: np.ndarray,
    flat: Mapping[str, float],
    substeps: int,
    compiled: bool,
) -> np.ndarray:
    key = _structure_key(model)
    _MODEL_BY_KEY.setdefault(key, model)
    run = _stepper(key, substeps, compiled)
    M, dt = midpoint_signals(sig)
    pvec = np.array([flat[k] for k in model.flat_params()], dtype=float)
    return run(x0, M.T, dt, pvec)
