"""Steady-state friction characteristic and its weighted least-squares fit (seed 002's procedure).

Seed 002 identified the static parameters ``Fs, Fc, vs, vb, n, sigma2`` "from
the measured steady-state friction characteristics using the least-squares
method". Here, from any record:

1. **Steady samples.** A sample is steady when it moves (``|v| >= v_min``)
   and its velocity changes by less than ``rel_change`` (default 10 %) over
   ``min_duration``: ``|a|*min_duration <= rel_change*|v|``; only runs of
   such samples lasting at least ``min_duration`` are kept (the friction
   states have settled).
2. **Force-velocity points.** Steady samples are binned per direction on
   logarithmically spaced speeds (resolving the low-speed Stribeck hump);
   each bin gives a point: mean ``v``, mean force, sample count ``n_b`` (and
   mean ``x``, ``p1``, ``p2`` for effects that read them).
3. **Weighted least squares** of the model's steady-state map
   ``F_ss(v) = sign(v)*g(v, h_ss) + sigma2*v`` (models.md 1.1-1.5; whatever
   :meth:`~fcomp.models.base.FrictionModel.steady_state` gives for the model
   and its effects) plus an optional constant offset, with weights ``n_b``.
   The map and its exact parameter Jacobian are one CasADi function built
   from the model's equations.

The bins are treated as independent points: the standard errors are the
Gauss-Newton ones with the scatter of the points about the curve
(``s^2 = sum n_b r_b^2/(B - p)``), i.e. lack of fit counts as noise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from fcomp.backend import CASADI
from fcomp.identification.problem import ParameterVector, Solution, solve
from fcomp.identification.uncertainty import Uncertainty, estimate
from fcomp.models.base import FrictionModel, Signals
from fcomp.parameters import ParamValues


@dataclass(frozen=True)
class SteadyStatePoints:
    """Binned steady-state force-velocity points (SI): one entry per bin."""

    v: np.ndarray
    F: np.ndarray
    count: np.ndarray
    x: np.ndarray
    p1: np.ndarray
    p2: np.ndarray

    def __len__(self) -> int:
        return int(self.v.size)


def steady_mask(t: np.ndarray, v: np.ndarray, a: np.ndarray, *, v_min: float,
                min_duration: float, rel_change: float = 0.1) -> np.ndarray:
    """Samples in steady motion (step 1 of the module docstring)."""
    ok = (np.abs(v) >= v_min) & (np.abs(a) * min_duration <= rel_change * np.abs(v))
    ok &= np.concatenate([[True], np.sign(v[1:]) == np.sign(v[:-1])])
    out = np.zeros_like(ok)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        if t[stop - 1] - t[start] >= min_duration:
            out[start:stop] = True
    return out


def steady_state_points(
    t: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    F: np.ndarray,
    *,
    v_min: float,
    min_duration: float = 0.05,
    rel_change: float = 0.1,
    bins: int = 20,
    x: np.ndarray | None = None,
    p1: np.ndarray | None = None,
    p2: np.ndarray | None = None,
) -> SteadyStatePoints:
    """Force-velocity points of the steady parts of a record (steps 1-2 of the module docstring).

    ``bins`` is the number of speed bins per direction; empty bins are dropped.
    """
    n = t.size
    x = np.zeros(n) if x is None else x
    p1 = np.zeros(n) if p1 is None else p1
    p2 = np.zeros(n) if p2 is None else p2
    m = steady_mask(t, v, a, v_min=v_min, min_duration=min_duration, rel_change=rel_change)
    rows = []
    for side in (1.0, -1.0):
        sel = m & (np.sign(v) == side)
        if sel.sum() == 0:
            continue
        speed = np.abs(v[sel])
        lo, hi = speed.min(), speed.max()
        edges = np.geomspace(lo, hi * (1 + 1e-9), bins + 1) if hi > lo else np.array([lo, hi + 1])
        idx = np.clip(np.digitize(speed, edges) - 1, 0, edges.size - 2)
        cols = [v[sel], F[sel], x[sel], p1[sel], p2[sel]]
        for b in range(edges.size - 1):
            k = idx == b
            if k.sum():
                rows.append([float(np.mean(c[k])) for c in cols] + [int(k.sum())])
    if not rows:
        e = np.zeros(0)
        return SteadyStatePoints(e, e, e, e, e, e)
    arr = np.array(rows)
    order = np.argsort(arr[:, 0])
    arr = arr[order]
    return SteadyStatePoints(v=arr[:, 0], F=arr[:, 1], count=arr[:, 5], x=arr[:, 2],
                             p1=arr[:, 3], p2=arr[:, 4])


class SteadyStateMap:
    """``F_ss(v, x, p1, p2; p)`` of a model and its exact Jacobian in the ``free`` parameters."""

    def __init__(self, model: FrictionModel, free: Sequence[str]) -> None:
        model.require_symbolic()
        self.model = model
        self.names = list(model.flat_params())
        self.free = tuple(free)
        fi = [self.names.index(n) for n in self.free]
        p, P = ParamValues.symbolic(self.names)
        v, x, p1, p2 = (ca.SX.sym(k) for k in ("v", "x", "p1", "p2"))
        s = ca.if_else(v >= 0, 1.0, -1.0)
        sig = Signals(v=v, a=0.0, x=x, p1=p1, p2=p2, s=s)
        xs = model.steady_state_states(CASADI, sig, P)
        F = model.force(CASADI, xs, sig, P)
        F = ca.SX(F) if not isinstance(F, ca.SX) else F
        w = ca.vertcat(v, x, p1, p2)
        self._fn = ca.Function("fcomp_steady_map", [w, p], [F, ca.jacobian(F, p)[:, fi]])
        self._maps: dict[int, ca.Function] = {}

    def __call__(self, pts: SteadyStatePoints,
                 values: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        flat = dict(self.model.flat_params())
        flat.update(values)
        pvec = np.array([flat[n] for n in self.names], dtype=float)
        W = np.vstack([pts.v, pts.x, pts.p1, pts.p2])
        if W.shape[1] not in self._maps:
            self._maps[W.shape[1]] = self._fn.map(W.shape[1])
        fmap = self._maps[W.shape[1]]
        F, G = fmap(W, np.repeat(pvec[:, None], W.shape[1], axis=1))
        # the map stacks the (1 x nf) row Jacobians side by side: (1, nf*N)
        F = np.asarray(F, dtype=float).ravel()
        G = np.asarray(G, dtype=float).reshape(W.shape[1], len(self.free))
        return F, G


@dataclass
class SteadyStateFit:
    """Result of :func:`fit_steady_state`."""

    values: dict[str, float]
    solution: Solution
    uncertainty: Uncertainty
    rms: float  # count-weighted RMS of the point residuals, N


def fit_steady_state(
    model: FrictionModel,
    points: SteadyStatePoints,
    pv: ParameterVector,
    *,
    max_nfev: int = 200,
    level: float = 0.95,
) -> SteadyStateFit:
    """Weighted least squares of the steady-state map to ``points`` (step 3).

    ``pv`` names model parameters and, optionally, ``offset`` (a constant
    force added to the map); other names are not allowed here.
    """
    model_free = [n for n in pv.names if n != "offset"]
    has_offset = "offset" in pv.names
    fmap = SteadyStateMap(model, model_free)
    w = points.count / points.count.mean()
    sw = np.sqrt(w)

    def fun(theta: np.ndarray, need_jac: bool) -> tuple[np.ndarray, np.ndarray]:
        vals = dict(zip(pv.names, theta, strict=True))
        off = vals.pop("offset", 0.0)
        F, G = fmap(points, vals)
        cols = [G]
        if has_offset:
            cols.append(np.ones((F.size, 1)))
        Gall = np.hstack(cols)
        if has_offset:  # keep the column order of pv.names
            order = [model_free.index(n) if n != "offset" else len(model_free) for n in pv.names]
            Gall = Gall[:, order]
        return sw * (points.F - F - off), sw[:, None] * Gall

    sol = solve(pv, fun, max_nfev=max_nfev, what=f"steady-state fit of {model.describe()}",
                compress=False)
    unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=level, autocorrelated=False)
    rms = math.sqrt(float(np.mean(sol.residuals**2)))
    return SteadyStateFit(dict(zip(pv.names, map(float, sol.theta), strict=True)), sol, unc, rms)
