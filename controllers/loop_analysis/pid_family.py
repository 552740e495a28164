"""The PID family's law at rest, linearised in closed form (the tuning's fast route).

At rest (``dr = ddr = 0``) ``pid`` and ``pid-ff`` (whose feedforward is zero at
``dr = 0``) run, per sample (:mod:`controllers.pid`, :mod:`controllers.force_to_valve`)::

    v_f[k] = a v_f[k-1] + b (x[k] - x[k-1]),        a = Tf/(Tf + T), b = 1/(Tf + T)
    I[k]   = I[k-1] + T e[k],                        e = r - x  (backward Euler)
    F_d    = kp e + ki I[k] - kd v_f[k]
    u      = inv(w_F (F_d - F_a(p1, p2)); x, p1, p2, lambda v_f[k])

with ``F_a = (p1 - p_atm) A1 - (p2 - p_atm) A2``, ``Tf = 1/(2 pi f_d)`` and the
inversion's partial derivatives at the operating point
(:meth:`controllers.force_to_valve.ForceToValve.slopes`): ``s = du/dtarget``,
``J_y = du/dy`` (its own dependence on the position and the pressures) and
``J_v = du/dv``. Linearised, with the states ``[I, v_f, x_prev]`` and the
input ``y = [x, p1, p2]`` (deviations; ``e = -x``)::

    A = [[1, 0, 0], [0, a, -b], [0, 0, 0]],   B = [[-T, 0, 0], [b, 0, 0], [1, 0, 0]]
    C = [s w_F ki, g a, -g b],                  g = lambda J_v - s w_F kd
    D = s w_F [-(kp + T ki), -A1, A2] + J_y + g b [1, 0, 0]

This is the Jacobian of the exported step (:mod:`controllers.loop_analysis.controller`)
written out, checked equal to it in the tests; the tuning
(:mod:`controllers.loop_analysis.design`) evaluates thousands of gain sets with it
without building a controller for each.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PIDFamilyGains:
    """What the PID family's linear law at rest depends on (SI units).

    Attributes
    ----------
    kp, ki, kd : float
        PID gains (N/m, N/(m s), N s/m).
    derivative_cutoff : float
        ``f_d`` (Hz).
    force_bandwidth : float
        ``w_F`` (rad/s).
    velocity_compensation : float
        ``lambda`` (0..1).
    forward_euler : bool
        The integral before this sample's error (``I[k-1]``, forward Euler): the law as
        it ran before the backward-Euler integral (``benchmarks/bench_margins.py`` analyses
        the former tunings with it).
    """

    kp: float
    ki: float
    kd: float
    derivative_cutoff: float
    force_bandwidth: float
    velocity_compensation: float
    forward_euler: bool = False


def pid_family_ss(g: PIDFamilyGains, s: np.ndarray, J_y: np.ndarray, J_v: np.ndarray,
                  A1: float, A2: float, dt: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C, D)`` of the module docstring for the operating points whose inversion
    slopes are ``s`` ``(P,)``, ``J_y`` ``(P, 3)``, ``J_v`` ``(P,)`` (batched)."""
    s, J_v = np.asarray(s, dtype=float), np.asarray(J_v, dtype=float)
    J_y = np.asarray(J_y, dtype=float)
    P = s.shape
    Tf = 1.0 / (2 * math.pi * g.derivative_cutoff)
    a, b = Tf / (Tf + dt), 1.0 / (Tf + dt)
    wF = g.force_bandwidth
    gv = g.velocity_compensation * J_v - s * wF * g.kd
    A = np.broadcast_to(np.array([[1.0, 0, 0], [0, a, -b], [0, 0, 0]]), (*P, 3, 3)).copy()
    B = np.broadcast_to(np.array([[-dt, 0, 0], [b, 0, 0], [1.0, 0, 0]]), (*P, 3, 3)).copy()
    C = np.stack([s * wF * g.ki, gv * a, -gv * b], axis=-1)[..., None, :]
    D = (s[..., None] * wF * np.array([0.0, -A1, A2]) + J_y)
    D[..., 0] += -s * wF * (g.kp + (0.0 if g.forward_euler else dt) * g.ki) + gv * b
    return A, B, C, D[..., None, :]


def pid_family_response(g: PIDFamilyGains, s: np.ndarray, J_y: np.ndarray, J_v: np.ndarray,
                        A1: float, A2: float, dt: float, z: np.ndarray) -> np.ndarray:
    """``K(z)`` ``(P, F, 3)`` of :func:`pid_family_ss` in closed form::

        K_x = s w_F (-kp - ki T z/(z - 1)) + J_y,x + g b (z - 1)/(z - a)
        K_p1 = -s w_F A1 + J_y,p1,     K_p2 = s w_F A2 + J_y,p2
    """
    Tf = 1.0 / (2 * math.pi * g.derivative_cutoff)
    a, b = Tf / (Tf + dt), 1.0 / (Tf + dt)
    s, J_v = np.asarray(s, dtype=float)[..., None], np.asarray(J_v, dtype=float)[..., None]
    J_y = np.asarray(J_y, dtype=float)
    wF = g.force_bandwidth
    gv = g.velocity_compensation * J_v - s * wF * g.kd
    integ = dt / (z - 1.0) if g.forward_euler else dt * z / (z - 1.0)
    Kx = (s * wF * (-g.kp - g.ki * integ) + J_y[..., 0:1] + gv * b * (z - 1.0) / (z - a))
    Kp1 = np.broadcast_to(-s * wF * A1 + J_y[..., 1:2], Kx.shape)
    Kp2 = np.broadcast_to(s * wF * A2 + J_y[..., 2:3], Kx.shape)
    return np.stack([Kx, Kp1, Kp2], axis=-1)


__all__ = ["PIDFamilyGains", "pid_family_response", "pid_family_ss"]
