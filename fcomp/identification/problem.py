"""The fitted parameter vector and the bounded least-squares solve shared by every fit stage.

A fit adjusts a vector ``theta`` of *flat* parameters (model names such as
``Fc``, ``sigma0``, ``Fs_pos``, plus the extras ``mass`` and ``offset``) to
minimise ``sum(r_k^2)`` with ``r = y - F_hat(theta)``. The models require
``Fc <= Fs`` (models.md 1.3). The solve first runs on ``theta`` itself (the
constraint is rarely active, and the plain coordinates converge in about half
the iterations); if the result violates the constraint it runs again on an
*internal* vector ``q`` with ``theta = T q``, ``T`` the identity except that a
static level is written ``Fs = Fc + Fs_excess`` with ``Fs_excess >= 0``,
which keeps every iterate feasible with simple bounds. The Jacobian
transforms linearly (``J_q = J_theta T``).

Bounds come from each parameter's :class:`~fcomp.parameters.ParamSpec`; an
open lower bound (``sigma0 > 0``) becomes ``1e-9`` times the parameter's scale.
The solve is :func:`scipy.optimize.least_squares` (trust-region reflective,
``x_scale`` = the parameter scales) with the analytic Jacobian of the stage.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from fcomp.errors import FcompError
from fcomp.parallel import one_blas_thread
from fcomp.parameters import ParamSpec

#: ``fun(theta, need_jacobian) -> (r, dF_hat/dtheta or None)`` of a stage (external theta).
ResidualFn = Callable[[np.ndarray, bool], tuple[np.ndarray, np.ndarray | None]]


def base_name(flat: str) -> str:
    """``Fc_pos`` -> ``Fc``; other names unchanged."""
    return flat[:-4] if flat.endswith(("_pos", "_neg")) else flat


def side_suffix(flat: str) -> str:
    """``"_pos"``, ``"_neg"`` or ``""``."""
    return flat[-4:] if flat.endswith(("_pos", "_neg")) else ""


@dataclass(frozen=True)
class ParameterVector:
    """Names, start values, bounds and scales of the fitted parameters (external form).

    Attributes
    ----------
    names
        Flat parameter names, in the order of ``theta``.
    start
        Initial values.
    lower, upper
        Bounds of the external values (``Fs`` bounds apply through the excess).
    scale
        Typical magnitudes (``x_scale`` of the solver), all positive.
    units
        Unit of each parameter (SI).
    """

    names: tuple[str, ...]
    start: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    scale: np.ndarray
    units: tuple[str, ...]

    @classmethod
    def build(
        cls,
        names: Sequence[str],
        start: Mapping[str, float],
        specs: Mapping[str, ParamSpec],
        scales: Mapping[str, float] | None = None,
    ) -> ParameterVector:
        """From flat names, start values and the specs (``mass``/``offset`` included in specs)."""
        names = tuple(names)
        x0 = np.array([float(start[n]) for n in names])
        sc = np.array([
            float((scales or {}).get(n, 0.0)) or max(abs(float(start[n])), 1e-12) for n in names
        ])
        lo = np.empty(len(names))
        hi = np.empty(len(names))
        for i, n in enumerate(names):
            s = specs[n]
            lo[i] = s.lower + (1e-9 * sc[i] if s.lower_open else 0.0)
            hi[i] = s.upper
        x0 = np.clip(x0, lo, hi)
        return cls(names, x0, lo, hi, sc, tuple(specs[n].unit for n in names))

    def index(self, name: str) -> int:
        return self.names.index(name)

    # -------------------------------------------------- Fs = Fc + excess
    def transform(self) -> np.ndarray:
        """The matrix ``T`` with ``theta = T q`` (identity but ``Fs = Fc + excess``)."""
        n = len(self.names)
        T = np.eye(n)
        for i, j in self.level_pairs():
            T[i, j] = 1.0
        return T

    def level_pairs(self) -> list[tuple[int, int]]:
        """Index pairs ``(Fs, Fc)`` (same side, or a scalar ``Fc``) among the fitted names."""
        out = []
        for i, name in enumerate(self.names):
            if base_name(name) == "Fs":
                partner = "Fc" + side_suffix(name)
                if partner not in self.names and side_suffix(name):
                    partner = "Fc"
                if partner in self.names:
                    out.append((i, self.names.index(partner)))
        return out

    def internal(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(q0, lower_q, upper_q, scale_q)`` of the internal vector."""
        T = self.transform()
        q0 = np.linalg.solve(T, self.start)
        lo, hi, sc = self.lower.copy(), self.upper.copy(), self.scale.copy()
        for i in range(len(self.names)):
            if T[i].sum() > 1.0:  # an Fs row: the excess is >= 0
                lo[i], hi[i] = 0.0, math.inf
                q0[i] = max(q0[i], 0.0)
                sc[i] = max(abs(q0[i]), 0.05 * self.scale[i])
        return q0, lo, hi, sc


def compressed(J: np.ndarray, r: np.ndarray, block: int = 512) -> tuple[np.ndarray, np.ndarray]:
    """``(r~, J~)`` with ``|r~ + J~ d| = |r + J d|`` for every step ``d``; ``p + 1`` rows.

    ``[J~, r~]`` is the triangular factor ``R`` of ``[J, r] = Q R``. It is
    computed from the Cholesky factor of the column-equilibrated Gram matrix
    (one matrix product: fast); where that is ill-conditioned (smallest
    pivot below ``1e-6`` of the largest, or not positive definite) from a
    blockwise QR (TSQR: QR of row blocks, then of the stacked factors), which
    is exact to rounding at any conditioning.
    """
    A = np.column_stack([J, r])
    p1 = A.shape[1]
    gram = A.T @ A
    D = np.sqrt(np.diag(gram))
    D = np.where(D > 0, D, 1.0)
    R: np.ndarray | None = None
    try:
        Rs = np.linalg.cholesky(gram / np.outer(D, D)).T
        piv = np.abs(np.diag(Rs))
        if piv.min() >= 1e-6 * piv.max():
            R = Rs * D[None, :]
    except np.linalg.LinAlgError:
        R = None
    if R is None:
        Rb = [np.asarray(np.linalg.qr(A[i : i + block], mode="r"))
              for i in range(0, A.shape[0], block)]
        Rq = np.asarray(np.linalg.qr(np.vstack(Rb), mode="r")) if len(Rb) > 1 else Rb[0]
        if Rq.shape[0] < p1:  # fewer rows than columns: pad with zero rows
            Rq = np.vstack([Rq, np.zeros((p1 - Rq.shape[0], p1))])
        R = Rq
    return R[:, -1].copy(), R[:, :-1].copy()


@dataclass
class Solution:
    """Result of :func:`solve` (external parameters)."""

    theta: np.ndarray
    residuals: np.ndarray
    jacobian: np.ndarray  # d F_hat / d theta at the solution (N, p)
    converged: bool
    message: str
    nfev: int
    at_bound: tuple[bool, ...]


def solve(
    pv: ParameterVector,
    fun: ResidualFn,
    *,
    max_nfev: int = 200,
    what: str = "fit",
    compress: bool = True,
) -> Solution:
    """Minimise ``sum(r(theta)^2)`` over the box of ``pv``; ``fun`` returns ``(r, dF_hat/dtheta)``.

    ``r = y - F_hat`` so the residual Jacobian is ``-dF_hat/dtheta``.
    Non-finite residuals at the start raise :class:`~fcomp.errors.FcompError`.

    With ``compress`` (for stages whose Jacobian comes with the residual at no
    extra cost) every evaluation is reduced by :func:`compressed` to ``p + 1``
    residuals: the same sum of squares, gradient and Gauss-Newton model, so
    the trust-region iterations are unchanged while the solver's
    per-iteration SVD works on a ``(p+1) x p`` matrix instead of ``N x p``.
    """
    with one_blas_thread():  # tall, thin algebra: threads only wait (fcomp.parallel)
        r0 = fun(pv.start, False)[0]
        if not np.all(np.isfinite(r0)):
            raise FcompError(f"{what}: the model gives non-finite forces at the initial guess")
        sol = _solve(pv, fun, max_nfev, compress, constrained=False)
        pairs = pv.level_pairs()
        if any(sol.theta[i] < sol.theta[j] for i, j in pairs):
            sol = _solve(pv, fun, max_nfev, compress, constrained=True)
    return sol


def _solve(pv: ParameterVector, fun: ResidualFn, max_nfev: int, compress: bool,
           constrained: bool) -> Solution:
    if constrained:
        T = pv.transform()
        q0, lo, hi, sc = pv.internal()
    else:
        T = np.eye(len(pv.names))
        q0, lo, hi, sc = pv.start.copy(), pv.lower, pv.upper, pv.scale
    links = [(i, j) for i, j in zip(*np.nonzero(T), strict=True) if i != j]
    cache: dict[bytes, tuple[np.ndarray, np.ndarray | None]] = {}

    def evaluate(q: np.ndarray, need_jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        key = q.tobytes()
        if key not in cache or (need_jac and cache[key][1] is None):
            cache.clear()
            with np.errstate(all="ignore"):
                r, G = fun(T @ q, need_jac or compress)
            if not np.all(np.isfinite(r)):  # invalid parameters: a huge cost, no slope
                r = np.full(r.shape, 1e10)
                G = None if G is None else np.zeros_like(G)
            if G is not None:
                J = -G if np.isfinite(G).all() else -np.nan_to_num(G, posinf=0.0, neginf=0.0)
                for i, j in links:  # J_q = J_theta T: column j gains column i (Fs = Fc + ..)
                    J[:, j] += J[:, i]
                if compress:
                    r, J = compressed(J, r)
                G = J
            cache[key] = (r, G)
        return cache[key]

    def res(q: np.ndarray) -> np.ndarray:
        return evaluate(q, False)[0]

    def jac(q: np.ndarray) -> np.ndarray:
        J = evaluate(q, True)[1]
        if J is None:
            raise RuntimeError("the residual function returned no Jacobian")
        return J

    # The solver's trial steps may leave floating-point range (an overflowing
    # bristle state, a 0/0 in its own step-size algebra); it rejects them itself, and
    # the solution it returns is checked for finite forces below. Those excursions are
    # the search's business, not warnings for the user.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        out = least_squares(res, q0, jac=jac, bounds=(lo, hi), x_scale=sc, method="trf",
                            max_nfev=max_nfev, ftol=1e-8, xtol=1e-8, gtol=1e-8)
    theta = T @ out.x
    r, G = fun(theta, True)
    if G is None:
        raise RuntimeError("the residual function returned no Jacobian")
    finite = bool(np.all(np.isfinite(r)))
    converged = bool(out.status > 0) and finite
    msg = out.message if finite else "the model force became non-finite"
    active = tuple(bool(a != 0) for a in out.active_mask)
    return Solution(theta, r, G, converged, msg, int(out.nfev), active)
