"""The LuGre observer's path at rest, in closed form (the tuning's route for rule 4).

``lugre-observer`` is the PID family's law (:mod:`controllers.loop_analysis.pid_family`)
with a friction estimate added to the force demand: the observer's own CasADi step
(:func:`controllers.lugre_observer.observer_step`: the controller model's friction
equations, the correction ``c = -k*(x - r)`` added to ``dz/dt``, one exponential
Rosenbrock-Euler step), driven by the PID's filtered velocity ``v_f``, the measured
position and gauge pressures::

    xh[k+1] = Phi(xh[k], v_f[k], x[k], p[k], c[k]),     F_hat[k] = F(xh[k], v_f[k], x[k], p[k], c[k])

At rest (``v_f = 0``, the side of motion held, ``c = 0``) its fixed point ``xh*`` (the
bristle where it was, the film relaxed: Newton on ``Phi(xh) = xh``, least squares, the
bristle's integrator free) and the Jacobians of ``Phi`` and ``F`` there (CasADi,
exact) give the observer's linear path; with the PID's states
``[I, v_f, x_prev]`` and ``c = -k x`` the controller's state space is::

    v_f' = a v_f + b (x - x_prev),  I' = I - T x,  x_prev' = x
    xh'  = Phi_xh xh + Phi_v v_f' + Phi_y y - k Phi_c x
    F_hat = F_xh xh + F_v v_f' + F_y y - k F_c x
    u     = s w_F (-kp x + ki I' - kd v_f' + F_hat - A1 p1 + A2 p2) + J_y y + lambda J_v v_f'

(deviations; ``y = [x, p1, p2]``). It is the Jacobian of the exported step written out
(the tests check the two agree), cheap enough for the tuning's search over the grid.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from controllers.loop_analysis.pid_family import PIDFamilyGains


class ObserverPath:
    """The observer's step with its Jacobians (module docstring).

    Parameters
    ----------
    model : controllers.plant_model.ControlModel
        The controller's model (its friction model is the observer's).
    dt : float
        Sample period (s).
    stiffness : float
        The observer's bristle stiffness (N/m,
        :func:`controllers.lugre_observer.observer_friction`).
    """

    def __init__(self, model: Any, dt: float, stiffness: float) -> None:
        from controllers.lugre_observer import observer_friction, observer_step

        step = observer_step(observer_friction(model, stiffness))
        nx = model.friction.n_states
        xh = ca.SX.sym("xh", nx)
        sig = ca.SX.sym("sig", 6)
        c = ca.SX.sym("c")
        xn, F = step(xh, sig, c, dt)
        inputs = ca.vertcat(xh, sig, c)
        self._f = ca.Function("observer_lin", [xh, sig, c],
                              [xn, F, ca.jacobian(ca.vertcat(xn, F), inputs)])
        self.nx = nx
        self.rest = np.asarray(model.friction.initial_state(), dtype=float)
        self.p_atm = model.p_atm

    def at(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """At rest on the measurement ``y``: the Jacobians ``(d xh'/d[xh, v, x, p1, p2, c],
        d F_hat/d[...])`` at the observer's fixed point (module docstring)."""
        sig = np.array([0.0, 0.0, y[0], y[1] - self.p_atm, y[2] - self.p_atm, 1.0])
        xh = self.rest.copy()
        n = self.nx
        for _ in range(30):  # Newton on Phi(xh) = xh, least squares
            xn, _F, J = (np.asarray(v, dtype=float) for v in self._f(xh, sig, 0.0))
            res = xn.ravel() - xh
            if np.max(np.abs(res)) <= 1e-14 * max(1.0, float(np.max(np.abs(xh)))):
                break
            M = J[:n, :n] - np.eye(n)
            xh = xh + np.linalg.lstsq(M, -res, rcond=1e-12)[0]
        _xn, _F, J = (np.asarray(v, dtype=float) for v in self._f(xh, sig, 0.0))
        cols = [*range(n), n, n + 2, n + 3, n + 4, n + 6]  # xh, v, x, p1, p2, c
        return J[:n, cols], J[n, cols]


def observer_ss(g: PIDFamilyGains, k: float, s: np.ndarray, J_y: np.ndarray, J_v: np.ndarray,
                phi: np.ndarray, fh: np.ndarray, A1: float, A2: float, dt: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of the module docstring for the points ``(P,)`` whose inversion
    slopes are ``s``, ``J_y``, ``J_v`` and whose observer Jacobians are ``phi`` ``(P, nx,
    nx + 5)``, ``fh`` ``(P, nx + 5)`` (columns ``xh, v, x, p1, p2, c``); states
    ``[I, v_f, x_prev, xh]``, input ``y``."""
    s, J_v = np.asarray(s, dtype=float), np.asarray(J_v, dtype=float)
    P, n = phi.shape[0], phi.shape[1]
    Tf = 1.0 / (2 * math.pi * g.derivative_cutoff)
    a, b = Tf / (Tf + dt), 1.0 / (Tf + dt)
    wF = g.force_bandwidth
    N = 3 + n
    A = np.zeros((P, N, N))
    B = np.zeros((P, N, 3))
    C = np.zeros((P, 1, N))
    D = np.zeros((P, 1, 3))
    # v_f' = a v_f - b x_prev + b x (row of v_f' in [I, v_f, x_prev, xh] and y)
    vf_s = np.zeros(N)
    vf_s[1], vf_s[2] = a, -b
    vf_y = np.array([b, 0.0, 0.0])
    A[:, 0, 0] = 1.0
    B[:, 0, 0] = -dt
    A[:, 1, :] = vf_s
    B[:, 1, :] = vf_y
    B[:, 2, 0] = 1.0
    Phi_x, Phi_v, Phi_y, Phi_c = phi[:, :, :n], phi[:, :, n], phi[:, :, n + 1:n + 4], \
        phi[:, :, n + 4]
    A[:, 3:, 3:] = Phi_x
    A[:, 3:, :] += Phi_v[:, :, None] * vf_s[None, None, :]
    B[:, 3:, :] = Phi_v[:, :, None] * vf_y[None, None, :] + Phi_y
    B[:, 3:, 0] += -k * Phi_c
    F_x, F_v, F_y, F_c = fh[:, :n], fh[:, n], fh[:, n + 1:n + 4], fh[:, n + 4]
    # F_hat as a row over [states; y]
    Fs = np.zeros((P, N))
    Fs[:, 3:] = F_x
    Fs += F_v[:, None] * vf_s[None, :]
    Fy = F_v[:, None] * vf_y[None, :] + F_y
    Fy[:, 0] += -k * F_c
    gv = g.velocity_compensation * J_v - s * wF * g.kd  # on v_f'
    sw = s * wF
    C[:, 0, 0] = sw * g.ki
    C[:, 0, :] += gv[:, None] * vf_s[None, :] + sw[:, None] * Fs
    D[:, 0, :] = (gv[:, None] * vf_y[None, :] + sw[:, None] * Fy + J_y
                  + sw[:, None] * np.array([-(g.kp + dt * g.ki), -A1, A2]))
    return A, B, C, D


__all__ = ["ObserverPath", "observer_ss"]
