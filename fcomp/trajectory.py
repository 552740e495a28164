"""Friction along a prescribed motion: the engine behind the ``motion`` plant and fitting.

Given sampled ``t`` and velocity ``v`` (and optionally ``a``, ``x``, ``p1``,
``p2``), the friction states are integrated sample to sample and the force
is evaluated at every sample.

Scheme
------
Between samples the signals are held at their interval means (midpoint
rule: second order in the sample interval) and the states advance by the
exponential Rosenbrock-Euler step of :mod:`fcomp.models.stepping`,
``x_{k+1} = x_k + dt*phi1(dt*J)*f(x_k)`` with ``J = diag(df/dx)`` exact,
``substeps`` times per interval: exact for the LuGre family at piecewise-
constant velocity and unconditionally stable however stiff. The step is one
CasADi function of ``(x, signals, dt, params)`` compiled to native code
(:mod:`fcomp.compiled`); parameters are inputs, so one compiled function
serves a whole identification.

For models with states, everything per sample -- the side ``s``, the
position when not given, the interval means, the step and the force -- runs
in one native loop (:func:`~fcomp.models.stepping.motion_kernel`), with the
same results as the numpy path it replaces (which still runs with
``compiled=False``, without a C compiler, and to name what is wrong with
invalid signals). Static maps are one vectorised numpy evaluation.

A model whose memory is discrete says so (its
:meth:`~fcomp.models.base.FrictionModel.discrete_memory`), and that memory
integrates the motion its own way (``integrate_motion``: the turning-point
stack of ``nmlgm-hysteresis``, advanced exactly on each interval).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.backend import NUMPY
from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel, Signals, side_of
from fcomp.models.stepping import friction_step, midpoint_signals, motion_kernel, step_loop
from fcomp.parameters import ParamValues

__all__ = ["FrictionRun", "friction_along_motion", "friction_step", "midpoint_signals",
           "prepare_signals"]


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

    def __repr__(self) -> str:  # a summary, never the arrays
        span = f", t {self.t[0]:.4g}..{self.t[-1]:.4g} s" if self.t.size else ""
        peak = f", |F| up to {np.max(np.abs(self.F)):.4g} N" if self.F.size else ""
        states = ", ".join(self.state_names) or "none"
        return f"<FrictionRun {self.t.size} samples{span}, states {states}{peak}>"


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
    flat = dict(model.flat_params())
    if values:
        flat.update(values)
    x0 = model.initial_state() if state0 is None else np.asarray(state0, dtype=float)
    if x0.shape != (model.n_states,):
        raise ValueError(f"state0 must have {model.n_states} entries {model.state_names}")
    memory = model.discrete_memory()
    if compiled and memory is None and model.n_states:
        run = _native_run(model, t, v, a, x, p1, p2, x0, flat, substeps)
        if run is not None:
            return run
    sig = prepare_signals(t, v, a, x, p1, p2)
    n = sig["t"].size
    if model.n_states == 0:
        X = np.zeros((n, 0))
    elif memory is not None:
        X = memory.integrate_motion(sig, x0, flat, substeps)
    else:
        M, dt = midpoint_signals(sig)
        pvec = np.array([flat[k] for k in model.flat_params()], dtype=float)
        X = step_loop(model, substeps, compiled)(x0, M.T, dt, pvec)
    P = ParamValues(flat, NUMPY)
    sigs = Signals(v=sig["v"], a=sig["a"], x=sig["x"], p1=sig["p1"], p2=sig["p2"], s=sig["s"])
    F = np.asarray(model.force(NUMPY, [X[:, i] for i in range(X.shape[1])], sigs, P), float)
    F = np.broadcast_to(F, (n,)).copy()
    return FrictionRun(t=sig["t"], v=sig["v"], a=sig["a"], x=sig["x"], p1=sig["p1"],
                       p2=sig["p2"], s=sig["s"], states=X, state_names=model.state_names, F=F)


def _samples(value: Any, n: int, *, single: bool) -> np.ndarray | None:
    """A signal as the native kernel reads it: contiguous float64 of ``n`` samples, or
    (``single``) one value held; ``None`` when it does not broadcast to ``n`` samples."""
    arr = np.asarray(value, dtype=float)
    if arr.shape == (n,):
        return np.ascontiguousarray(arr)
    if arr.size == 1 and arr.ndim <= 1:
        return arr.reshape(1).copy() if single else np.full(n, arr.reshape(-1)[0])
    return None


def _native_run(model: FrictionModel, t: Any, v: Any, a: Any, x: Any, p1: Any, p2: Any,
                x0: np.ndarray, flat: Mapping[str, float], substeps: int) -> FrictionRun | None:
    """:func:`friction_along_motion` in one native pass
    (:func:`~fcomp.models.stepping.motion_kernel`): the same scheme, signals and force. ``None`` where the kernel does not apply (no
    compiler, signals that do not broadcast, invalid signals: the general path then runs,
    or says what is wrong)."""
    t = np.ascontiguousarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        return None
    n = t.size
    vs = _samples(v, n, single=False)
    if vs is None:
        return None
    if a is None:
        with np.errstate(all="ignore"):  # invalid time is reported by the general path
            a = np.gradient(vs, t)
    acc = _samples(a, n, single=False)
    pos = None if x is None else _samples(x, n, single=True)
    q1, q2 = _samples(p1, n, single=True), _samples(p2, n, single=True)
    if acc is None or q1 is None or q2 is None or (x is not None and pos is None):
        return None
    kernel = motion_kernel(model, substeps)
    if kernel is None:
        return None
    pvec = np.array([flat[k] for k in model.flat_params()], dtype=float)
    out = kernel(t, vs, acc, pos, q1, q2, np.ascontiguousarray(x0, dtype=float), pvec)
    if out is None:
        return None
    X, F, S = out
    return FrictionRun(t=t, v=S[0], a=S[1], x=S[2], p1=S[3], p2=S[4], s=S[5], states=X,
                       state_names=model.state_names, F=F)
