"""``ekf``: extended Kalman filter on the friction states, its friction estimate fed forward.

The filter (filterpy's :class:`~filterpy.kalman.ExtendedKalmanFilter`)
estimates the whole state of the controller's plant model -- piston
position and velocity, chamber pressures, valve states and the friction
states ``z`` (bristle) and ``h`` (lubricant film) -- from the measured
position and chamber pressures ``y = [x, p1, p2]``:

* prediction: the plant + friction model of :mod:`controllers.prediction`
  (``x_{k+1} = Phi(x_k, u_k)``, linearly implicit Euler at the controller
  rate) with its *exact* Jacobian ``A = dPhi/dx`` from CasADi -- the same
  symbolic equations the simulator integrates, differentiated, never a
  hand-derived copy; ``P <- A P A' + Q``;
* update: the measurement is a selection of states (``H`` constant) with the
  sensor noise covariance ``R`` (noise and quantisation of the harness's
  sensors, :mod:`controllers.harness`).

The process noise ``Q = diag(q_i^2 * dt)`` is small on the mechanical and
hydraulic states (model errors of a few percent) and large on ``z``: a
friction level that differs from the model's appears as a bristle
deflection the filter must be free to track -- that is what makes the
estimate useful against a mismatched model. ``h`` gets a moderate value.

The friction estimate ``F_hat = F(x_hat)`` (the model's force at the
estimated state, lead term included) is added to the PID force demand of
:mod:`controllers.pid`, and the estimated velocity replaces the filtered
derivative in the force-to-valve inversion. Step cost is measured by the
harness (median goal 0.2 ms).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar

import casadi as ca
import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from controllers.base import Reference
from controllers.native import native
from controllers.pid import PIDController
from controllers.prediction import ContinuousModel
from fcomp.errors import FcompError


class _ModelEKF(ExtendedKalmanFilter):
    """filterpy's EKF whose state prediction is the nonlinear model step (set before predict)."""

    x_pred: np.ndarray

    def predict_x(self, u: Any = 0) -> None:
        self.x = self.x_pred


class FrictionEKF:
    """EKF of a :class:`~controllers.prediction.ContinuousModel` (see the module docstring).

    Parameters
    ----------
    model
        The controller's symbolic plant model.
    dt
        Sample time (s).
    q
        Process-noise intensities, one per state (state unit / sqrt(s)).
    r
        Measurement-noise standard deviations, one per measured output (SI).
    substeps
        Integration substeps per sample.
    """

    def __init__(self, model: ContinuousModel, dt: float, q: Sequence[float] | np.ndarray,
                 r: Sequence[float] | np.ndarray, substeps: int = 1) -> None:
        nx = model.nx
        if len(q) != nx or len(r) != len(model.measured):
            raise FcompError(f"ekf: need {nx} process-noise and {len(model.measured)} "
                             "measurement-noise values")
        if min(q) < 0 or min(r) <= 0:
            raise FcompError("ekf: noise intensities must be >= 0 (q) and > 0 (r)")
        self.model = model
        self.dt = dt
        # the filter runs on scaled states xi = x/scale and measurements y/r (both O(1))
        sc = np.asarray(model.scales, dtype=float)
        self.scale = sc
        self.r = np.asarray(r, dtype=float)
        # the scales are an input, like the parameters: one kernel for every parameter set
        step = model.step(dt, substeps, scale_input=True)
        xi = ca.SX.sym("xi", nx)
        u = ca.SX.sym("u")
        p = ca.SX.sym("p", model.p.size)
        S = ca.SX.sym("s", nx)
        xn = step(S * xi, u, p, S) / S
        self.p = np.asarray(model.p, dtype=float)
        self._predict = native(ca.Function("ekf_predict", [xi, u, p, S],
                                           [xn, ca.jacobian(xn, xi)]))
        self._friction = native(ca.Function("ekf_friction", [xi, u, p, S],
                                            [model.friction(S * xi, u, p)]))
        self.kf = _ModelEKF(dim_x=nx, dim_z=len(model.measured))
        H = np.zeros((len(model.measured), nx))
        for row, i in enumerate(model.measured):
            H[row, i] = sc[i] / self.r[row]
        self.H = H
        self.Q = np.diag((np.asarray(q, dtype=float) / sc) ** 2 * dt)
        self.R = np.eye(len(model.measured))
        self._HJ = lambda _x: H
        self._Hx = lambda xx: H @ xx

    def reset(self, x0: np.ndarray, P0: np.ndarray) -> None:
        """Start from estimate ``x0`` with covariance ``P0`` (model units).

        One step is run from there and discarded: the first call of the native
        kernels and of the update's linear algebra pays one-time costs (page
        faults, lazy binding; some 0.3-0.5 ms) that belong to the set-up, not
        to the first sample.
        """
        x0 = np.asarray(x0, dtype=float)
        self._start(x0, P0)
        self.step(x0[list(self.model.measured)], 0.0)  # the warm-up step, discarded
        self.friction(0.0)
        self._start(x0, P0)

    def _start(self, x0: np.ndarray, P0: np.ndarray) -> None:
        kf = self.kf
        kf.x = (x0 / self.scale).reshape(-1, 1)
        kf.P = np.array(P0, dtype=float) / np.outer(self.scale, self.scale)
        kf.Q = self.Q
        kf.R = self.R

    def step(self, y: np.ndarray, u_prev: float) -> np.ndarray:
        """Predict with the input held over the last interval, update with ``y``; return ``x_hat``."""
        kf = self.kf
        xn, A = self._predict(kf.x[:, 0], u_prev, self.p, self.scale)
        if not np.all(np.isfinite(xn)):
            raise FloatingPointError("ekf prediction is not finite")
        kf.x_pred = xn.reshape(-1, 1)
        kf.F = A
        kf.predict()
        kf.update((np.asarray(y, dtype=float) / self.r).reshape(-1, 1), self._HJ, self._Hx)
        return self.x_hat

    @property
    def x_hat(self) -> np.ndarray:
        """The state estimate (model units)."""
        return self.kf.x[:, 0] * self.scale

    @property
    def P(self) -> np.ndarray:
        """The estimate's covariance (model units)."""
        return self.kf.P * np.outer(self.scale, self.scale)

    def friction(self, u: float) -> float:
        """Friction force (N) of the model at the current estimate."""
        return float(self._friction(self.kf.x[:, 0], u, self.p, self.scale)[0][0])


class EKFController(PIDController):
    """PID plus the EKF's friction estimate (see the module docstring).

    Parameters
    ----------
    q_scale
        Factor on every process-noise intensity of the plant model's defaults.
    q_friction
        Process-noise intensity of ``z`` (m/sqrt(s)); default the model's.
    **options
        Those of :class:`~controllers.pid.PIDController`.
    """

    name: ClassVar[str] = "ekf"
    options: ClassVar[tuple[str, ...]] = (*PIDController.options, "q_scale", "q_friction")

    def __init__(self, model: Any, **options: Any) -> None:
        super().__init__(model, **options)
        self.ekf = make_ekf(model, self.dt, self.opts,
                            substeps=max(1, round(self.dt * model.control_rate)))
        self.iv = model.prediction.index("v")
        self._u_prev = 0.0

    def reset_compensation(self, y0: np.ndarray, ref: Reference) -> None:
        x0, P0 = self.model.estimator_initial(y0)
        self.ekf.reset(x0, P0)
        self._u_prev = 0.0

    def compensation(self, t: float, y: np.ndarray, ref: Reference, v: float) -> float:
        self.ekf.step(y, self._u_prev)
        return self.ekf.friction(self._u_prev)

    def velocity_estimate(self, v_f: float) -> float:
        return float(self.ekf.x_hat[self.iv])

    def step(self, t: float, y: np.ndarray, ref: Reference) -> float:
        u = super().step(t, y, ref)
        self._u_prev = u
        return u

    def applied(self, u: float) -> None:
        """The EKF predicts with the command the valve was given."""
        self._u_prev = u

    def healthy(self) -> bool:
        kf = self.ekf.kf
        return (super().healthy() and bool(np.all(np.isfinite(kf.x)))
                and bool(np.all(np.isfinite(kf.P))) and np.isfinite(self._u_prev))


def make_ekf(model: Any, dt: float, opts: dict[str, Any], substeps: int = 1) -> FrictionEKF:
    """The EKF of a :class:`~controllers.plant_model.ControlModel` with option overrides."""
    q = np.array(model.process_noise(), dtype=float) * float(opts.get("q_scale", 1.0))
    if "q_friction" in opts:
        q[model.prediction.index("z")] = float(opts["q_friction"])
    return FrictionEKF(model.prediction, dt, q, model.sensor_std(), substeps=substeps)
