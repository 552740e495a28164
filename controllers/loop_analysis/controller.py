"""A controller *as coded*, linearised at its fixed point: Jacobians of its symbolic step.

Every controller of the package has its one sample as a CasADi function,
``controllers.export.step_function(ctrl)``: ``(state, y, ref) -> (u, state_next)``,
the same function the exported C code computes, checked sample by sample against
the Python controller. At an operating point -- the plant at rest holding its
load at a position, measured ``y = [x, p1, p2]``, the reference ``r = x`` at rest
(``dr = ddr = 0``), the command ``u`` that holds the load -- the controller has a
fixed point ``s*``: ``s* = f(s*, y, r)`` with ``g(s*, y, r) = u``. It is found by
stepping the controller on the constant measurement (its filters, observer and
estimator converge; the EKF's covariance to its Riccati fixed point), with its
integral set, after each step, to the value whose command is ``u`` (an integral
action holds any load; Newton on the integral with the exact derivative).
There, the Jacobians (exact, CasADi's algorithmic differentiation)::

    s[k+1] - s* = A (s[k] - s*) + B (y[k] - y),    u[k] - u = C (s[k] - s*) + D (y[k] - y)

are the controller's discrete-time state space: its PID law with the derivative
filter and the backward-Euler integral, the force-to-valve inversion at the
measured pressures and position, the friction compensation where it is
differentiable at rest (the LuGre observer's correction, the EKF's prediction
and update), exactly as they run. Blocks that carry no linear dynamics are left
out: the ``started`` flag, the side of motion (a sign, constant at rest), and
the EKF's covariance (at the fixed point the innovation is zero, so the state
estimate does not depend on it to first order: its block is unobservable from
``u``, and the transfer function is unchanged without it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from fcomp.errors import ConvergenceError, FcompError

#: State blocks of the exported step that carry no linear dynamics (module docstring).
LOGICAL_BLOCKS = ("started", "side", "ekf_P")
#: Samples stepped on the constant measurement before Newton's method (the fixed point).
PLAIN_STEPS = 4
#: The same for a controller with an estimator's covariance (its Riccati recursion first).
PLAIN_STEPS_ESTIMATOR = 600
#: Newton steps, at most, to the fixed point.
NEWTON_STEPS = 60
#: Step of the symmetric differences at a kink, relative to each state's (measurement's) scale.
KINK_STEP = 1e-6
#: The smallest scale of a state or measurement (SI units: a state at rest at zero, such as a
#: filtered velocity, is stepped by KINK_STEP*KINK_FLOOR).
KINK_FLOOR = 1e-6
#: A column of the exact Jacobian is replaced where it differs from the symmetric difference
#: by more than this, relative (scaled by the state's and the output's scales).
KINK_TOL = 1e-4


@dataclass(frozen=True)
class LinearController:
    """A controller linearised at its fixed point (module docstring).

    Attributes
    ----------
    A, B, C, D : numpy.ndarray
        ``(nc, nc)``, ``(nc, 3)``, ``(1, nc)``, ``(1, 3)``: input ``y = [x, p1, p2]``
        (deviations, m and Pa), output the valve command's deviation.
    states : tuple of str
        The states kept (block name and index).
    dt : float
        Sample period (s).
    state : numpy.ndarray
        The full fixed point ``s*`` of the exported step.
    measurement : numpy.ndarray
        ``y`` at the operating point.
    command : float
        ``u`` at the operating point.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    dt: float
    state: np.ndarray
    measurement: np.ndarray
    command: float


class StepLinearisation:
    """The exported step of one controller with its Jacobians, for many operating points.

    Parameters
    ----------
    ctrl : controllers.base.Controller
        A built controller (not yet reset).
    """

    def __init__(self, ctrl: Any) -> None:
        from controllers.export import step_function

        step = step_function(ctrl)
        self.ctrl = ctrl
        self.step = step
        self.dt = float(ctrl.dt)
        n = step.n_state
        s = ca.MX.sym("s", n)
        y = ca.MX.sym("y", 3)
        r = ca.MX.sym("r", step.n_ref)
        u, sn = step.fn(s, y, r)
        out = ca.vertcat(u, sn)
        self._eval = ca.Function("step_eval", [s, y, r], [u, sn])
        self._jac = ca.Function("step_jac", [s, y, r],
                                [u, sn, ca.jacobian(out, ca.vertcat(s, y))])
        names: list[str] = []
        for block, size in step.layout:
            names += [f"{block}[{i}]" if size > 1 else block for i in range(size)]
        self.names = names
        blocks = [b for b, k in step.layout for _ in range(k)]
        self.keep = [i for i, b in enumerate(blocks) if b not in LOGICAL_BLOCKS]
        self.integral = [i for i, b in enumerate(blocks) if b == "integral"]
        self._last: np.ndarray | None = None

    def reference(self, y: np.ndarray) -> np.ndarray:
        """The reference at rest at the measured position (the MPC's preview held)."""
        ref = np.zeros(self.step.n_ref)
        ref[0] = y[0]
        if self.step.n_ref > 3:
            ref[3:] = y[0]
        return ref

    def fixed_point(self, y: np.ndarray, u: float, tol: float = 1e-5) -> np.ndarray:
        """The controller's state at rest on the measurement ``y`` commanding ``u``.

        From its reset (or the last point's fixed point), :data:`PLAIN_STEPS` steps on the
        constant measurement with the integral set after each to the value whose command
        is ``u``; then Newton's method on ``s - f(s) = 0``, ``g(s) = u`` with the exact
        Jacobians, least squares (the integral and an observer's bristle can both hold the
        load: any of them is a fixed point, the minimum-norm correction is taken). Slow
        states (a lubricant film relaxing over seconds) are solved, not waited for. The
        tolerance ``tol`` is relative to each block's largest entry: an EKF's covariance of
        a state it cannot observe at rest (the film) grows without bound, its gain drifts
        by parts per million, and its estimate with it.
        """
        ref = self.reference(y)
        estimator = any(b == "ekf_P" for b, _k in self.step.layout)
        if self._last is not None and not estimator:
            s = self._last.copy()
            for i, name in enumerate(self.names):  # the position the state remembers
                if name == "x_prev":
                    s[i] = y[0]
        else:
            s = np.asarray(self._eval(self.step.state0, y, ref)[1]).ravel()  # the reset
        n = s.size
        du = 0.0
        if self.integral:
            du = float(np.asarray(self._jac(s, y, ref)[2])[0, self.integral[0]])
            if du == 0.0:
                raise FcompError("the controller's command does not depend on its integral")
        for _ in range(PLAIN_STEPS_ESTIMATOR if estimator else PLAIN_STEPS):
            uu, s_new = (np.asarray(v, dtype=float).ravel() for v in self._eval(s, y, ref))
            if self.integral:  # the integral whose command is u (linear in it)
                s_new[self.integral[0]] += (u - float(uu[0])) / du
            s = s_new
        scale = np.empty(n)  # per block of the layout: its largest entry
        i = 0
        for block, size in self.step.layout:
            scale[i:i + size] = max(float(np.abs(s[i:i + size]).max()), self._floor(block))
            i += size
        u_scale = max(abs(u), 1e-9)
        k = self.keep  # the logical blocks held (the covariance: its observable part has
        sk = scale[k]  # converged in the plain steps; it does not move the estimate)
        for _ in range(NEWTON_STEPS):
            uu, s_next, J = self._jac(s, y, ref)
            J = np.asarray(J)[:, :n]
            res = np.concatenate([(np.asarray(s_next).ravel()[k] - s[k]) / sk,
                                  [(float(uu) - u) / u_scale]])
            if np.all(np.abs(res) <= tol):
                break
            M = np.vstack([(J[1:][np.ix_(k, k)] - np.eye(len(k))) / sk[:, None],
                           J[:1, k] / u_scale])
            step = np.linalg.lstsq(M * sk[None, :], -res, rcond=1e-12)[0] * sk
            s[k] = s[k] + step
        else:
            raise ConvergenceError(f"controller {getattr(self.ctrl, 'name', '?')}: no fixed "
                                   f"point at rest (residual {np.abs(res).max():.2e})")
        self._last = s
        return s

    def _floor(self, block: str) -> float:
        """The smallest scale of a block for the fixed point's tolerance: a force carried
        from the last sample (the friction estimate's lead, ``F_prev``) is nil at rest, and
        its rounding (1e-12 N) must not count as a relative change; its floor is a
        billionth of the actuator's force range (N). Other blocks: 1e-12 in their units."""
        if block == "F_prev":
            m = self.ctrl.model
            return 1e-9 * float(m.force_max - m.force_min)
        return 1e-12

    def at(self, y: np.ndarray, u: float) -> LinearController:
        """The controller linearised at rest on the measurement ``y`` commanding ``u``
        (the exact Jacobian; an estimator's where its model has a kink at rest, the symmetric
        difference over a millionth of each state's scale: :meth:`kinks_repaired`. The PID
        family's one kink at rest, the valve inversion's flow reversal, keeps the exact
        one-sided slope of its closed form, :mod:`~controllers.loop_analysis.pid_family`,
        which the nonlinear sampled loop's poles confirm)."""
        y = np.asarray(y, dtype=float)
        s = self.fixed_point(y, u)
        ref = self.reference(y)
        uu, _sn, J = self._jac(s, y, ref)
        J = np.asarray(J)
        if any(b == "ekf_P" for b, _k in self.step.layout):  # an estimator's model at rest
            J = self.kinks_repaired(J, s, y, ref)
        n = len(self.names)
        k = self.keep
        A = J[1:, :n][np.ix_(k, k)]
        B = J[1:, n:][k, :]
        C = J[:1, :n][:, k]
        D = J[:1, n:]
        return LinearController(A=A, B=B, C=C, D=D, states=tuple(self.names[i] for i in k),
                                dt=self.dt, state=s, measurement=y, command=float(uu))


    def kinks_repaired(self, J: np.ndarray, s: np.ndarray, y: np.ndarray, ref: np.ndarray
                       ) -> np.ndarray:
        """The Jacobian ``J`` (``d[u, s']/d[s, y]``) with the columns of the kept states and
        of ``y`` where the step is not differentiable at rest replaced by symmetric
        differences over :data:`KINK_STEP` of each state's block scale (of each measured
        value).

        An estimator's model has terms in ``|v|`` and smoothed signs (``tanh(v/v_eps)``,
        ``v_eps`` = 1e-5 m/s): at rest their algorithmic derivative is that of the smoothing
        below the sensors' resolution -- a lubricant film whose state responds to the
        pressure with a slope of 1e3 and a curvature of 1e18, an eigenvalue of 3.8 on its
        own (the EKF on the built-in hydraulic plant). The loop as it runs moves its states
        by far more than that; its small-signal slope is the symmetric difference over a
        small but finite step, which for a smooth step equals the exact derivative to the
        step's square (the columns where the two agree to :data:`KINK_TOL` keep the exact
        one). The tests hold the result against the finite-difference Jacobian of the
        nonlinear sampled loop with the Python controller.
        """
        n = len(self.names)
        scale = np.empty(n)
        i = 0
        for _block, size in self.step.layout:
            scale[i:i + size] = max(float(np.abs(s[i:i + size]).max()), KINK_FLOOR)
            i += size
        y_scale = np.maximum(np.abs(y), KINK_FLOOR)
        rows = [0, *(1 + np.asarray(self.keep))]
        u0 = float(np.asarray(self._eval(s, y, ref)[0]).ravel()[0])
        row_scale = np.concatenate([[max(abs(u0), 1e-9)], scale])  # u, each state's scale
        out = J.copy()
        cols = [*self.keep, *range(n, n + y.size)]
        for c in cols:
            h = KINK_STEP * (scale[c] if c < n else y_scale[c - n])
            sp, yp, sm, ym = s.copy(), y.copy(), s.copy(), y.copy()
            if c < n:
                sp[c] += h
                sm[c] -= h
            else:
                yp[c - n] += h
                ym[c - n] -= h
            fp = np.concatenate([np.asarray(v, dtype=float).ravel()
                                 for v in self._eval(sp, yp, ref)])
            fm = np.concatenate([np.asarray(v, dtype=float).ravel()
                                 for v in self._eval(sm, ym, ref)])
            fd = (fp - fm) / (2 * h)
            diff = np.abs(fd[rows] - J[rows, c]) * (h / KINK_STEP) / row_scale[rows]
            if np.max(diff) > KINK_TOL:
                out[:, c] = fd
        return out

    def at_many(self, Y: np.ndarray, U: np.ndarray, tol: float = 1e-5) -> list[LinearController]:
        """:meth:`at` at many operating points at once (CasADi's ``map``: one call evaluates
        every point; Newton's method batched). ``Y`` ``(P, 3)``, ``U`` ``(P,)``."""
        Y = np.asarray(Y, dtype=float)
        U = np.asarray(U, dtype=float)
        P = Y.shape[0]
        ev, jac = self._eval.map(P), self._jac.map(P)
        R = np.stack([self.reference(y) for y in Y], axis=1)
        Yt = Y.T
        if any(b == "ekf_P" for b, _k in self.step.layout):
            # an estimator: its Riccati recursion and its kinked bristle equation want the
            # plain steps of each point's own reset (:meth:`at`)
            return [self.at(y, float(u)) for y, u in zip(Y, U, strict=True)]
        S = np.asarray(ev(np.repeat(self.step.state0[:, None], P, axis=1), Yt, R)[1])
        plain = PLAIN_STEPS
        n = S.shape[0]
        if self.integral:
            i = self.integral[0]
            J = np.asarray(jac(S, Yt, R)[2])  # (1 + n, (n + 3) * P)
            du = J[0].reshape(P, n + 3)[:, i] if J.shape[1] == (n + 3) * P else None
            du = np.asarray(J[0, [p * (n + 3) + i for p in range(P)]]) if du is None else du
            if np.any(du == 0.0):
                raise FcompError("the controller's command does not depend on its integral")
        for _ in range(plain):
            uu, S_new = (np.asarray(v, dtype=float) for v in ev(S, Yt, R))
            if self.integral:
                S_new[self.integral[0]] += (U - uu[0]) / du
            S = S_new
        scale = np.empty((n, P))
        i0 = 0
        for block, size in self.step.layout:
            scale[i0:i0 + size] = np.maximum(np.abs(S[i0:i0 + size]).max(axis=0),
                                             self._floor(block))
            i0 += size
        u_scale = np.maximum(np.abs(U), 1e-9)
        k = self.keep
        eye = np.eye(len(k))
        for _ in range(NEWTON_STEPS):
            uu, S_next, J = (np.asarray(v, dtype=float) for v in jac(S, Yt, R))
            Jb = J.reshape(1 + n, P, n + 3).transpose(1, 0, 2)[:, :, :n]  # (P, 1+n, n)
            sk = scale[k].T  # (P, nk)
            res = np.concatenate([((S_next - S)[k].T / sk), ((uu[0] - U) / u_scale)[:, None]],
                                 axis=1)
            if np.all(np.abs(res) <= tol):
                break
            Ak = Jb[:, 1:, :][:, k][:, :, k]
            M = np.concatenate([(Ak - eye) / sk[:, :, None], Jb[:, :1, k] / u_scale[:, None, None]],
                               axis=1) * sk[:, None, :]
            step = np.einsum("pij,pj->pi", np.linalg.pinv(M, rcond=1e-12), -res) * sk
            S[k] = S[k] + step.T
        else:
            raise ConvergenceError(f"controller {getattr(self.ctrl, 'name', '?')}: no fixed "
                                   f"point at rest (residual {np.abs(res).max():.2e})")
        uu, _S, J = (np.asarray(v, dtype=float) for v in jac(S, Yt, R))
        Jb = J.reshape(1 + n, P, n + 3).transpose(1, 0, 2)
        out = []
        for p in range(P):
            Jp = Jb[p]
            out.append(LinearController(
                A=Jp[1:, :n][np.ix_(k, k)], B=Jp[1:, n:][k, :], C=Jp[:1, :n][:, k],
                D=Jp[:1, n:], states=tuple(self.names[i] for i in k), dt=self.dt,
                state=S[:, p].copy(), measurement=Y[p], command=float(uu[0, p])))
        return out


def linearise_controller(ctrl: Any, y: np.ndarray, u: float) -> LinearController:
    """``ctrl`` (built, not reset) linearised at rest on the measurement ``y`` commanding ``u``
    (:class:`StepLinearisation`, once)."""
    return StepLinearisation(ctrl).at(y, u)


__all__ = ["LOGICAL_BLOCKS", "LinearController", "StepLinearisation", "linearise_controller"]
