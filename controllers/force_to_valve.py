"""How a force demand -- and so a friction correction -- reaches the valve of a fluid plant.

A cylinder does not take a force command: the valve meters flow, and the
actuator force ``F_a = (p1 - p_atm)*A1 - (p2 - p_atm)*A2`` follows from the
chamber pressures. The force-based controllers (``pid``, ``pid-ff``,
``lugre-observer``, ``ekf``) therefore close a *force (pressure) inner
loop by model-based inversion* of the chamber equations (a backstepping
step, as in sliding-mode/backstepping control of hydraulic and pneumatic
servos):

1. the desired force rate is that of a first-order force loop of
   bandwidth ``w_F`` (rad/s)::

       dF_a/dt |target = w_F * (F_d - F_a)

   with ``F_a`` from the *measured* pressures;
2. the model gives the force rate for a held valve command ``u`` at the
   measured position and pressures and the estimated velocity ``v``::

       dF_a/dt (u) = A1*dp1/dt(x, v, p1, p2, xv_ss(u)) - A2*dp2/dt(...)

   where ``dp1/dt``, ``dp2/dt`` are the *controller's plant model's own*
   chamber equations (hydraulic: orifice flows, oil compressibility,
   models.md 3.2; pneumatic: ISO 6358 mass flows, polytropic chambers,
   models.md 3.3), evaluated with the valve at its steady opening
   ``xv_ss(u)`` for the command (valve dynamics neglected in the
   inversion; their lag is in the loop the bandwidth ``w_F`` is designed
   on: :mod:`controllers.tuning`, rule 1, a 45 deg phase margin through the
   valve's linearised dynamics and the zero-order hold);
3. ``dF_a/dt(u)`` increases monotonically with ``u`` (opening the valve
   fills chamber 1 and drains chamber 2), and at fixed pressures it is
   piecewise linear in the opening; it is evaluated on a grid of commands
   (cubically spaced, dense around the valve centre where the under- or
   overlap is) and inverted by linear interpolation. A target outside the
   reachable range saturates the valve at ``+-u_max`` (reported, for the
   PID's anti-windup).

The term ``A1^2/V1 + A2^2/V2`` of the velocity (the flow the moving piston
displaces) is part of the chamber equations, so the inversion also
compensates the velocity-induced force drop at the velocity it is given. With
the measured velocity the ideal force loop is the first-order ``w_F/(s + w_F)``
and the oil (air) column disappears from it -- but only as well as that
velocity (a filtered derivative of the sampled position, a sample late) is
right at the column's frequency, which it is not near the stroke's ends where
the column is stiff and fast. The PID family therefore gives it a mix
(:class:`controllers.pid.PIDController`, the *velocity compensation*
``lambda``): ``lambda`` of the measured velocity and ``1 - lambda`` of the
reference's, so the rest of the column's stiffness stays in the feedback loop,
damped by the pressure feedback ``w_F*(F_d - F_a)`` from the measured
pressures (load-pressure feedback: Merritt, *Hydraulic Control Systems*, 1967,
sec. 8.4; Jelali & Kroll, *Hydraulic Servo-systems*, 2003, sec. 7.3), while
the flow a tracked motion needs is still fed forward. A friction estimate added
to ``F_d`` becomes the extra pressure difference that cancels it within the
force loop's time constants.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from controllers.native import native
from fcomp.errors import FcompError


def command_grid(u_max: float, n: int = 41) -> np.ndarray:
    """Valve commands ``u_max*s^3``, ``s`` uniform on [-1, 1]: dense near the centre."""
    s = np.linspace(-1.0, 1.0, n)
    return u_max * s**3


class ForceToValve:
    """Model-based force loop: force demand -> valve command (see the module docstring).

    Parameters
    ----------
    model
        The controller's :class:`~controllers.plant_model.ControlModel`.
    bandwidth
        Force-loop bandwidth ``w_F`` (rad/s).
    """

    def __init__(self, model: Any, bandwidth: float) -> None:
        if not (np.isfinite(bandwidth) and bandwidth > 0):
            raise FcompError(f"force_bandwidth must be a positive number (rad/s), got {bandwidth}")
        self.model = model
        self.bandwidth = float(bandwidth)
        self.grid = command_grid(model.u_max)
        names = model.plant.state_names
        meas = ca.SX.sym("meas", 4)  # x, v, p1, p2
        ug = ca.SX.sym("u")
        p = ca.SX.sym("p", model.prediction.p.size)
        vs = model.steady_valve()(ug, p)
        subs = {"x": meas[0], "v": meas[1], "p1": meas[2], "p2": meas[3]}
        for i, n in enumerate(model.valve_states()):
            subs[n] = vs[i]
        state = ca.vertcat(*[subs.get(n, 0.0) for n in names])
        f = model.prediction.f(state, ug, p)
        rate = model.A1 * f[names.index("p1")] - model.A2 * f[names.index("p2")]
        one = ca.Function("force_rate", [meas, ug, p], [rate])
        grid = ca.SX.sym("grid", self.grid.size)
        rates = ca.vertcat(*[one(meas, grid[k], p) for k in range(self.grid.size)])
        self._rates = native(ca.Function("force_rate_grid", [meas, grid, p], [rates]))
        self.p = np.asarray(model.prediction.p, dtype=float)
        self._meas = np.zeros(4)
        self._jacobian: ca.Function | None = None

    def reset(self) -> None:
        """No state (the inversion is static)."""

    def force_rates(self, y: np.ndarray, v: float) -> np.ndarray:
        """``dF_a/dt`` (N/s) on :attr:`grid` at measurement ``y`` and velocity ``v``."""
        m = self._meas
        m[0], m[1], m[2], m[3] = y[0], v, y[1], y[2]
        return self._rates(m, self.grid, self.p)[0]

    def slopes(self, y: np.ndarray, u: float, v: float = 0.0) -> tuple[float, np.ndarray, float]:
        """The inversion's partial derivatives where its command is ``u`` (the loop analysis,
        :mod:`controllers.loop_analysis.pid_family`).

        Where ``u`` lies in the grid segment ``j`` (``grid[j] <= u <= grid[j+1]``, a
        fraction ``theta`` along it), :meth:`command` returns ``u = grid[j] + (target -
        R[j])*s``, ``s = (grid[j+1] - grid[j])/(R[j+1] - R[j])``, ``R`` the running maximum
        of the force rates; so ``du/dtarget = s`` and ``du/dm = -s*((1 - theta)*dR[j]/dm +
        theta*dR[j+1]/dm)`` for each measured quantity ``m``.

        Returns
        -------
        tuple
            ``du/dtarget`` (1/(N/s)), ``du/dy`` (``[x, p1, p2]``, the force ``F_a`` of the
            target excluded) and ``du/dv`` (per m/s of the velocity given).
        """
        if self._jacobian is None:
            f = self._rates.fn
            meas = ca.SX.sym("meas", 4)
            grid = ca.SX.sym("grid", self.grid.size)
            p = ca.SX.sym("p", self.p.size)
            r = f(meas, grid, p)
            self._jacobian = ca.Function("force_rate_jac", [meas, grid, p],
                                         [r, ca.jacobian(r, meas)])
        meas = np.array([y[0], v, y[1], y[2]], dtype=float)
        R, J = (np.asarray(m, dtype=float) for m in self._jacobian(meas, self.grid, self.p))
        R = R.ravel()
        best = np.zeros(R.size, dtype=int)  # which rate the running maximum is
        for k in range(1, R.size):
            best[k] = k if R[k] >= R[best[k - 1]] else best[k - 1]
        Rm, Jm = R[best], J[best]
        g = self.grid
        j = int(np.clip(np.searchsorted(g, u, side="right") - 1, 0, g.size - 2))
        dR = Rm[j + 1] - Rm[j]
        if not dR > 0:
            raise FcompError(f"the force-to-valve inversion is flat at the command {u:g}: "
                             "no force rate to linearise")
        s = (g[j + 1] - g[j]) / dR
        theta = (u - g[j]) / (g[j + 1] - g[j])
        dm = -s * ((1.0 - theta) * Jm[j] + theta * Jm[j + 1])  # x, v, p1, p2
        return float(s), np.array([dm[0], dm[2], dm[3]]), float(dm[1])

    def command(self, F_d: float, y: np.ndarray, v: float) -> tuple[float, int]:
        """Valve command for force demand ``F_d`` (N); and +1/-1 if saturated high/low, else 0."""
        target = self.bandwidth * (F_d - self.model.actuator_force(y))
        rates = np.maximum.accumulate(self.force_rates(y, v))
        if target >= rates[-1]:
            return float(self.grid[-1]), 1
        if target <= rates[0]:
            return float(self.grid[0]), -1
        return float(np.interp(target, rates, self.grid)), 0
