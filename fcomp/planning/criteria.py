"""What a motion tells: the rivals' predicted forces along it, their separation, and the
Fisher information of a parameter.

Discrimination (T-optimality, Atkinson & Fedorov 1975, Biometrika 62:57-70 and
62:289-303): for rival models with predicted forces ``F_a``, ``F_b`` along the motion and a
force noise of standard deviation ``sigma`` (the noise floor), the non-centrality

    T = sum_k (F_a(t_k) - F_b(t_k))^2 / sigma^2

is what a record of that motion adds to the evidence for the right one (the expected
log-likelihood ratio is ``T/2``). ``separation = sqrt(mean((F_a - F_b)^2))/sigma`` is the
same in noise floors per sample, the number a re-diagnosis measures
(:func:`achieved_separation`).

Estimation (D/A-optimality; Atkinson, Donev & Tobias, *Optimum Experimental Designs, with
SAS*, 2007; Walter & Pronzato 1997): the information on the parameters ``theta`` is
``I = J^T J / sigma^2`` with ``J = dF/dtheta`` along the motion (central differences of the
model's force; ``dF/dm = -a`` for a fitted moving mass of a force from the pressures). The
predicted standard error after the programme is ``sqrt(diag((I_0 + I)^-1))`` with ``I_0`` the
diagnosis's own (``diag(1/se^2)``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from fcomp.models.base import FrictionModel
from fcomp.trajectory import friction_along_motion


def force(model: FrictionModel, sig: Mapping[str, np.ndarray],
          values: Mapping[str, float] | None = None) -> np.ndarray:
    """The model's force along the motion ``sig`` (``t``, ``v``, ``a``, ``x``, ``p1``, ``p2``)."""
    run = friction_along_motion(model, sig["t"], sig["v"], a=sig["a"], x=sig["x"],
                                p1=sig["p1"], p2=sig["p2"], values=values)
    return np.asarray(run.F, dtype=float)


def t_criterion(fa: np.ndarray, fb: np.ndarray, sigma: float) -> float:
    """``sum((F_a - F_b)^2)/sigma^2``."""
    return float(np.sum((fa - fb) ** 2) / sigma**2)


def separation(fa: np.ndarray, fb: np.ndarray, sigma: float) -> float:
    """RMS of ``F_a - F_b`` in noise floors."""
    return float(np.sqrt(np.mean((fa - fb) ** 2)) / sigma) if fa.size else 0.0


def achieved_separation(y: np.ndarray, fa: np.ndarray, fb: np.ndarray, sigma: float
                        ) -> tuple[float, str]:
    """The separation a record shows, and which rival it favours: with the residuals
    ``r_a = y - F_a`` and ``r_b = y - F_b``, ``sqrt(|mean(r_b^2) - mean(r_a^2)|)/sigma``
    (for the right rival ``a`` this is ``rms(F_a - F_b)/sigma`` plus noise)."""
    ma, mb = float(np.mean((y - fa) ** 2)), float(np.mean((y - fb) ** 2))
    return float(np.sqrt(abs(mb - ma)) / sigma), ("a" if ma <= mb else "b")


def step(value: float, spec: tuple[float, float] | None = None) -> float:
    """A central-difference step for a parameter of ``value`` (relative, floored)."""
    return 1e-3 * max(abs(value), 1e-6 if spec is None else 1e-3 * (spec[1] - spec[0])
                      if np.isfinite(spec[1] - spec[0]) else 1e-6)


def jacobian(model: FrictionModel, sig: Mapping[str, np.ndarray], names: Sequence[str],
             mass_from_pressures: bool) -> np.ndarray:
    """``dF/dtheta`` along ``sig`` for the flat parameters ``names`` (``mass``: ``-a``)."""
    flat = model.flat_params()
    cols = []
    for n in names:
        if n == "mass":
            cols.append(-sig["a"] if mass_from_pressures else np.zeros(sig["t"].size))
            continue
        if n not in flat:
            cols.append(np.zeros(sig["t"].size))
            continue
        value = float(flat[n])
        h = step(value)
        # central where both sides are allowed; one-sided at a bound (a bristle damping
        # fitted to its bound of 0 has no value below it)
        up, dn = _moved(model, sig, n, value + h), _moved(model, sig, n, value - h)
        if up is not None and dn is not None:
            cols.append((up - dn) / (2 * h))
        elif up is not None:
            cols.append((up - force(model, sig)) / h)
        elif dn is not None:
            cols.append((force(model, sig) - dn) / h)
        else:
            cols.append(np.zeros(sig["t"].size))
    return np.column_stack(cols) if cols else np.zeros((sig["t"].size, 0))


def _moved(model: FrictionModel, sig: Mapping[str, np.ndarray], name: str,
           value: float) -> np.ndarray | None:
    """The force along ``sig`` with parameter ``name`` at ``value``; None outside its bounds."""
    try:
        moved = model.with_params(**{name: value})
    except ValueError:
        return None
    return force(moved, sig)


def predicted_stderr(info: np.ndarray, prior_se: Sequence[float | None]) -> np.ndarray:
    """``sqrt(diag((I_0 + I)^-1))`` with ``I_0 = diag(1/se^2)`` of the given ones (a
    parameter without a standard error starts from no information)."""
    prior = np.array([0.0 if s is None or not s > 0 else 1.0 / s**2 for s in prior_se])
    total = info + np.diag(prior)
    try:
        cov = np.linalg.pinv(total, rcond=1e-12)
    except np.linalg.LinAlgError:
        return np.full(len(prior_se), np.inf)
    d = np.diag(cov)
    return np.where(d > 0, np.sqrt(np.abs(d)), np.inf)
