"""The ``mpc`` controller with a fixed-iteration QP: the form :mod:`controllers.export` writes as C.

:class:`controllers.mpc.MPCController` solves the QP of every real-time
iteration with DAQP, an active-set solver whose number of iterations
depends on the data; CasADi's code generator cannot express it. This
variant keeps everything else of ``mpc`` -- the EKF, the condensed
Gauss-Newton linearisation (the same compiled CasADi function), the
warm start, the limits, the fallback law -- and solves the same QP ::

    min 1/2 dU' H dU + g' dU   s.t.  l <= [I; D] dU <= u

(box on the commands, band of the rate limits; ``H`` regularised as in
``mpc``) by a **fixed number of ADMM iterations** (the OSQP splitting,
Stellato et al., "OSQP: an operator splitting solver for quadratic
programs", Math. Prog. Comp. 12, 2020, without relaxation and with a
fixed step)::

    K   = H + sigma I + rho A'A           (inverted once per sample)
    x   = K^-1 (sigma x - g + A'(rho z - lam))
    z   = clip(A x + lam/rho, l, u)
    lam = lam + rho (A x - z)

with ``rho = rho_rel * trace(H)/N`` (the penalty on the QP's own scale),
``sigma = 1e-6 rho``, ``x`` from 0, ``z = clip(0, l, u)`` and the
multipliers ``lam`` warm-started from the previous sample (as DAQP's
``dual_start``). After the iterations the new input sequence is clipped to
the valve range. A fixed number of iterations is not an exact QP solution:
the commands differ from DAQP's by what the iterations leave; the closed-loop
tracking of both is compared in ``docs/compensators.md``.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from controllers.mpc import MPCController, MPCProblem, RTISolver
from controllers.prediction import ContinuousModel
from fcomp.errors import FcompError

#: Defaults of the fixed-iteration QP.
QP_DEFAULTS: dict[str, float] = {"qp_iterations": 30, "rho_rel": 0.03}


class FixedIterationRTI(RTISolver):
    """:class:`~controllers.mpc.RTISolver` with the QP solved by fixed-count ADMM (module
    docstring)."""

    def __init__(self, model: ContinuousModel, problem: MPCProblem, iterations: int,
                 rho_rel: float) -> None:
        super().__init__(model, problem)
        if not (isinstance(iterations, int) and iterations >= 1):
            raise FcompError(f"mpc qp_iterations must be an integer >= 1, got {iterations!r}")
        if not (np.isfinite(rho_rel) and rho_rel > 0):
            raise FcompError(f"mpc rho_rel must be a positive number, got {rho_rel!r}")
        N = problem.horizon
        self.A = np.vstack([np.eye(N), self.D])
        self.qp_iterations = iterations
        self.rho_rel = float(rho_rel)

    def bounds(self, u_prev: float) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)`` of ``[I; D] dU`` at the current warm start."""
        p = self.problem
        N = p.horizon
        du = p.du_max * p.dt
        diff = self.D @ self.U - np.concatenate([[u_prev], np.zeros(N - 1)])
        upper = np.concatenate([p.u_max - self.U, du - diff])
        lower = np.concatenate([-p.u_max - self.U, -du - diff])
        return lower, upper

    def admm(self, H: np.ndarray, g: np.ndarray, lower: np.ndarray, upper: np.ndarray,
             lam0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(dU, lam)`` after :attr:`qp_iterations` ADMM iterations (module docstring)."""
        N = self.problem.horizon
        A = self.A
        rho = self.rho_rel * float(np.trace(H)) / N
        sigma = 1e-6 * rho
        Kinv = np.linalg.inv(H + sigma * np.eye(N) + rho * (A.T @ A))
        x = np.zeros(N)
        z = np.clip(np.zeros(2 * N), lower, upper)
        lam = lam0.copy()
        for _ in range(self.qp_iterations):
            x = Kinv @ (sigma * x - g + A.T @ (rho * z - lam))
            Ax = A @ x
            z = np.clip(Ax + lam / rho, lower, upper)
            lam = lam + rho * (Ax - z)
        return x, lam

    def iterate(self, x0: np.ndarray, u_prev: float, R: np.ndarray, V: np.ndarray) -> bool:
        p = self.problem
        N = p.horizon
        H, g, cost, _X = self._lin(x0, self.U, u_prev, R, V, self.p, self.scales)
        if not (np.all(np.isfinite(H)) and np.all(np.isfinite(g))):
            self._lam = None
            return False
        H = H + (self.reg * max(float(np.trace(H)) / N, 1.0)) * np.eye(N)
        lower, upper = self.bounds(u_prev)
        lam0 = self._lam if self._lam is not None else np.zeros(2 * N)
        dU, lam = self.admm(H, g, lower, upper, lam0)
        if not (np.all(np.isfinite(dU)) and np.all(np.isfinite(lam))):
            self._lam = None
            return False
        self._lam = lam
        self.U = np.clip(self.U + dU, -p.u_max, p.u_max)
        self.cost = float(cost[0])
        self.iterations += 1
        return True


class FixedIterationMPC(MPCController):
    """``mpc`` with the fixed-iteration QP (module docstring).

    Parameters
    ----------
    qp_iterations
        ADMM iterations per sample (default 30).
    rho_rel
        ADMM penalty relative to the mean diagonal of ``H`` (default 0.03).
    **options
        Those of :class:`~controllers.mpc.MPCController`.
    """

    name: ClassVar[str] = "mpc"
    options: ClassVar[tuple[str, ...]] = (*MPCController.options, "qp_iterations", "rho_rel")

    def __init__(self, model: Any, **options: Any) -> None:
        iterations = options.pop("qp_iterations", int(QP_DEFAULTS["qp_iterations"]))
        rho_rel = float(options.pop("rho_rel", QP_DEFAULTS["rho_rel"]))
        super().__init__(model, **options)
        self.opts.update(qp_iterations=iterations, rho_rel=rho_rel)
        self.solver = FixedIterationRTI(model.prediction, self.problem, iterations, rho_rel)
