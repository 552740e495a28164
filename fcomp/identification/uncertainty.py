"""Standard errors and confidence intervals of least-squares estimates.

At the solution ``theta`` of ``min sum r_k^2`` with Jacobian ``J = dr/dtheta``
(N samples, p parameters) the Gauss-Newton covariance is

    cov_GN = s^2 (J^T J)^-1,    s^2 = sum r_k^2 / (N - p),

which assumes independent residuals. Residuals of friction fits along a
measured motion are strongly autocorrelated (model error and sensor noise
filtered by the velocity/acceleration estimation), which makes ``cov_GN``
far too optimistic. The package therefore reports the *batch-means
sandwich* (a heteroscedasticity and autocorrelation consistent, HAC,
estimate; e.g. Flegal & Jones, Ann. Stat. 38 (2010), for batch means):

    cov = (J^T J)^-1  [ sum_b g_b g_b^T ]  (J^T J)^-1 * N/(N - p),
    g_b = sum_{k in batch b} J_k^T r_k,

with contiguous batches of length ``L = ceil(3 * tau_int)``, where the
integrated autocorrelation time of the residuals is
``tau_int = 1 + 2 sum_{l>=1} rho_l`` summed up to the first lag with
``rho_l < 0.05`` (at most ``N/(6 p)`` so there are enough batches). For
white residuals ``tau_int = 1`` and the estimate reduces to the usual
one. The *effective sample size* ``N_eff = N / tau_int`` sets the degrees of
freedom ``N_eff - p`` of the Student-t confidence intervals.

Rank deficiency (a parameter the data do not determine) shows as a tiny
singular value of the column-scaled ``J`` (below ``1e-7`` of the largest):
:func:`determined_mask` then marks the parameter weighing most in that
direction as undetermined, repeatedly; those get an infinite standard error
and the covariance of the others is computed without them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import stdtrit


@dataclass(frozen=True)
class Uncertainty:
    """Covariance of the estimates and what it rests on.

    Attributes
    ----------
    cov
        Covariance matrix (p, p) in the parameters' units.
    stderr
        Standard errors ``sqrt(diag(cov))`` (``inf`` where not identifiable).
    ci_low, ci_high
        Bounds of the two-sided confidence intervals at ``level``.
    level
        Confidence level (e.g. 0.95).
    tau_int
        Integrated autocorrelation time of the residuals (samples).
    n_eff
        Effective number of independent samples ``N / tau_int``.
    batch
        Batch length used by the HAC estimate (samples).
    identifiable
        Per parameter: whether the data determine it (see module docstring).
    """

    cov: np.ndarray
    stderr: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    level: float
    tau_int: float
    n_eff: float
    batch: int
    identifiable: np.ndarray

    def correlation(self) -> np.ndarray:
        """Correlation matrix of the estimates."""
        with np.errstate(invalid="ignore", divide="ignore"):
            d = 1.0 / self.stderr
        return self.cov * np.outer(d, d)


def integrated_autocorrelation(r: np.ndarray, max_lag: int | None = None) -> float:
    """``tau_int = 1 + 2 sum rho_l`` up to the first lag with ``rho_l < 0.05`` (samples)."""
    r = np.asarray(r, dtype=float) - np.mean(r)
    n = r.size
    if n < 4 or not np.any(r):
        return 1.0
    nfft = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(r, nfft)
    acf = np.fft.irfft(f * np.conj(f), nfft)[:n]
    acf /= acf[0]
    limit = n - 1 if max_lag is None else min(max_lag, n - 1)
    below = np.nonzero(acf[1 : limit + 1] < 0.05)[0]
    cut = int(below[0]) + 1 if below.size else limit + 1
    return max(1.0, 1.0 + 2.0 * float(np.sum(acf[1:cut])))


def determined_mask(J: np.ndarray, rcond: float = 1e-7) -> np.ndarray:
    """Which parameters the data determine (``True``) given the Jacobian ``J`` (N, p).

    The columns are scaled to unit norm; while the smallest singular value is
    below ``rcond`` times the largest, the parameter with the largest
    component in its singular vector is declared undetermined and its column
    removed. Zero columns are undetermined from the start. The remaining
    parameters have a well-conditioned (``cond < 1/rcond``) scaled Jacobian.
    """
    from fcomp.identification.problem import compressed

    J = np.asarray(J, dtype=float)
    p = J.shape[1]
    norms = np.linalg.norm(J, axis=0)
    ok = norms > 0
    # the triangular factor R of the scaled J has J's singular values and vectors
    R = compressed(J / np.where(ok, norms, 1.0), np.zeros(J.shape[0]))[1]
    while ok.any():
        idx = np.flatnonzero(ok)
        _, sv, Vt = np.linalg.svd(R[:, idx], full_matrices=False)
        if sv[-1] >= rcond * sv[0]:
            break
        ok[idx[int(np.argmax(np.abs(Vt[-1])))]] = False
    return ok if p else np.zeros(0, dtype=bool)


def estimate(
    J: np.ndarray,
    r: np.ndarray,
    theta: np.ndarray,
    *,
    level: float = 0.95,
    autocorrelated: bool = True,
) -> Uncertainty:
    """Covariance, standard errors and confidence intervals (see the module docstring).

    Parameters
    ----------
    J
        Jacobian of the residuals (or of the model output; the sign does not
        matter) with respect to the parameters, (N, p).
    r
        Residuals at the solution, (N,).
    theta
        Estimates, (p,).
    level
        Confidence level of the intervals.
    autocorrelated
        Use the batch-means HAC estimate (default); ``False`` gives the plain
        Gauss-Newton ``s^2 (J^T J)^-1`` (independent residuals, e.g. binned data).
    """
    J = np.asarray(J, dtype=float)
    r = np.asarray(r, dtype=float)
    n, p = J.shape
    if n <= p:
        raise ValueError(f"{n} residuals cannot determine {p} parameters")
    identifiable = determined_mask(J)
    cov = np.full((p, p), np.nan)
    kept = np.flatnonzero(identifiable)
    Jk = J[:, kept]
    scale = np.linalg.norm(Jk, axis=0)
    Js = Jk / scale
    H_inv_s = np.linalg.inv(Js.T @ Js) if kept.size else np.zeros((0, 0))
    tau = integrated_autocorrelation(r, max_lag=max(1, n // (6 * p))) if autocorrelated else 1.0
    batch = max(1, min(math.ceil(3.0 * tau), max(1, n // (6 * p))))
    if autocorrelated:
        g = Js * r[:, None]
        nb = n // batch
        head = g[: nb * batch].reshape(nb, batch, kept.size).sum(axis=1)
        tail = g[nb * batch :].sum(axis=0, keepdims=True)
        blocks = np.vstack([head, tail]) if n % batch else head
        meat = blocks.T @ blocks
        cov_s = H_inv_s @ meat @ H_inv_s * n / (n - p)
    else:
        s2 = float(r @ r) / (n - p)
        cov_s = s2 * H_inv_s
    with np.errstate(over="ignore"):  # a tiny scale: an error too large to matter (inf)
        cov[np.ix_(kept, kept)] = cov_s / np.outer(scale, scale)
    var = np.full(p, np.inf)
    var[kept] = np.diag(cov)[kept]
    stderr = np.sqrt(np.maximum(var, 0.0))
    n_eff = n / tau
    dof = max(n_eff - p, 1.0)
    q = float(stdtrit(dof, 0.5 + level / 2.0))
    return Uncertainty(cov=cov, stderr=stderr, ci_low=theta - q * stderr,
                       ci_high=theta + q * stderr, level=level, tau_int=float(tau),
                       n_eff=float(n_eff), batch=int(batch), identifiable=identifiable)
