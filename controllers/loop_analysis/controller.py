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
#: Samples stepped on the constant measurement, at most, to reach the fixed point.
MAX_STEPS = 20000


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

    def fixed_point(self, y: np.ndarray, u: float, tol: float = 1e-11) -> np.ndarray:
        """The controller's state at rest on the measurement ``y`` commanding ``u``."""
        ref = self.reference(y)
        if self._last is not None:
            s = self._last.copy()
            s[0] = 1.0
            for i, name in enumerate(self.names):  # the position the state remembers
                if name == "x_prev":
                    s[i] = y[0]
        else:
            s = np.asarray(self._eval(self.step.state0, y, ref)[1]).ravel()  # the reset
        du = 0.0
        if self.integral:
            i = self.integral[0]
            du = float(np.asarray(self._jac(s, y, ref)[2])[0, i])
            if du == 0.0:
                raise FcompError("the controller's command does not depend on its integral")
        scale = np.abs(s)
        for k in range(MAX_STEPS):
            uu, s_new = (np.asarray(v, dtype=float).ravel() for v in self._eval(s, y, ref))
            if self.integral:  # the integral whose command is u (linear in it)
                s_new[self.integral[0]] += (u - float(uu[0])) / du
            change = np.abs(s_new - s)
            s = s_new
            scale = np.maximum(scale, np.abs(s))
            if k > 2 and np.all(change <= tol * scale + 1e-15) \
                    and abs(float(uu[0]) - u) <= tol * max(abs(u), 1e-9):
                break
        else:
            raise ConvergenceError(f"controller {getattr(self.ctrl, 'name', '?')}: no fixed "
                                   f"point at rest within {MAX_STEPS} samples")
        self._last = s
        return s

    def at(self, y: np.ndarray, u: float) -> LinearController:
        """The controller linearised at rest on the measurement ``y`` commanding ``u``."""
        y = np.asarray(y, dtype=float)
        s = self.fixed_point(y, u)
        ref = self.reference(y)
        uu, _sn, J = self._jac(s, y, ref)
        J = np.asarray(J)
        n = len(self.names)
        k = self.keep
        A = J[1:, :n][np.ix_(k, k)]
        B = J[1:, n:][k, :]
        C = J[:1, :n][:, k]
        D = J[:1, n:]
        return LinearController(A=A, B=B, C=C, D=D, states=tuple(self.names[i] for i in k),
                                dt=self.dt, state=s, measurement=y, command=float(uu))


def linearise_controller(ctrl: Any, y: np.ndarray, u: float) -> LinearController:
    """``ctrl`` (built, not reset) linearised at rest on the measurement ``y`` commanding ``u``
    (:class:`StepLinearisation`, once)."""
    return StepLinearisation(ctrl).at(y, u)


__all__ = ["LOGICAL_BLOCKS", "LinearController", "StepLinearisation", "linearise_controller"]
