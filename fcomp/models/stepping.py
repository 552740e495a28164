"""The sampled step of a friction model: exponential Rosenbrock-Euler, one source.

Between samples ``t_k`` and ``t_{k+1}`` the signals are held at their interval
means (:func:`midpoint_signals`) and the states advance by the *exponential
Rosenbrock-Euler* step with the diagonal of the exact (CasADi) Jacobian
``J = diag(df/dx)`` (Hochbruck & Ostermann, "Exponential integrators", Acta
Numerica 19, 2010, Sec. 2.4)::

    x_{k+1} = x_k + h*phi1(h*J)*f(x_k),   phi1(y) = (exp(y) - 1)/y,

``substeps`` times per interval (:func:`exponential_euler`). For the LuGre
family it is *exact* for a held velocity: the bristle equation ``dz/dt = v -
sigma0*|v|*z/g`` is linear in ``z`` at fixed ``v``, the film equation linear in
``h``. States with hard limits are projected back onto their admissible set
after every step (:meth:`~fcomp.models.base.FrictionModel.project`).

:func:`friction_step` builds the step as one CasADi function of ``(x,
signals, dt, params)``; :func:`step_loop` rolls it over a record, compiled to
native code (:mod:`fcomp.compiled`) and cached per model structure, so one
compiled loop serves every parameter value. The engine along a motion
(:mod:`fcomp.trajectory`), the exact sensitivities of identification
(:mod:`fcomp.identification.sensitivity`), the carrier of the hysteresis model
(:mod:`fcomp.models.hysteresis`) and the LuGre observer
(:mod:`controllers.lugre_observer`) all take their step from here.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from fcomp.backend import CASADI
from fcomp.compiled import Loop, stepping_loop
from fcomp.models.base import FrictionModel, Signals
from fcomp.parameters import ParamValues


def phi1(y: Any) -> Any:
    """``phi1(y) = (exp(y) - 1)/y`` as a CasADi expression (``1 + y/2`` near 0)."""
    return ca.if_else(ca.fabs(y) < 1e-8, 1.0 + 0.5 * y, ca.expm1(y) / y)


def exponential_euler(f: Any, x: Any, h: Any) -> Any:
    """One exponential Rosenbrock-Euler step ``x + h*phi1(h*J)*f`` of ``dx/dt = f(x)``.

    ``f`` is the right-hand side as a CasADi expression of the symbol ``x``;
    ``J`` the diagonal of its Jacobian. Returns the new state (expression of ``x``).
    """
    J = ca.diag(ca.jacobian(f, x))
    return x + h * phi1(h * J) * f


def structure_key(model: FrictionModel) -> tuple:
    """Identity of a model's equations: models with equal keys share compiled code."""
    return (
        type(model),
        tuple((type(e), tuple(sorted(e.config.items()))) for e in model.effects),
        tuple(model.flat_params()),
    )


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
    xl = [x[i] for i in range(nx)]
    one = exponential_euler(ca.vertcat(*model.rhs(CASADI, xl, sig, P)), x, h)
    proj = ca.vertcat(*model.project(CASADI, xl, sig, P))
    xk = x
    for _ in range(substeps):
        xk = ca.substitute(proj, x, ca.substitute(one, x, xk))
    return ca.Function("fcomp_friction_step", [x, sigv, dt, p], [xk])


_MODEL_BY_KEY: dict[tuple, FrictionModel] = {}


@lru_cache(maxsize=64)
def _loop(key: tuple, substeps: int, compiled: bool) -> Loop:
    return stepping_loop(friction_step(_MODEL_BY_KEY[key], substeps), compiled=compiled)


def step_loop(model: FrictionModel, substeps: int = 1, compiled: bool = True) -> Loop:
    """The compiled loop ``(x0, M, dt, p) -> X`` of :func:`friction_step` (cached by
    :func:`structure_key`): ``M`` the interval-mean signals ``(N-1, 6)``."""
    key = structure_key(model)
    _MODEL_BY_KEY.setdefault(key, model)
    return _loop(key, substeps, compiled)


def midpoint_signals(sig: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Interval-mean signals ``(6, N-1)`` in :data:`~fcomp.models.base.SIGNAL_NAMES` order,
    and ``dt``; the side of an interval at rest is the side at its start."""
    mid = {k: 0.5 * (sig[k][1:] + sig[k][:-1]) for k in ("v", "a", "x", "p1", "p2")}
    s_mid = np.sign(mid["v"])
    s_mid = np.where(s_mid == 0, sig["s"][:-1], s_mid)
    M = np.vstack([mid["v"], mid["a"], mid["x"], mid["p1"], mid["p2"], s_mid])
    return M, np.diff(sig["t"])
