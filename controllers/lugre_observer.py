"""``lugre-observer``: observer-based LuGre friction compensation (Canudas de Wit et al. 1995).

Canudas de Wit, Olsson, Astrom & Lischinsky, "A new model for control of
systems with friction", IEEE TAC 40(3), 1995, section V: the bristle state
``z`` is not measurable, so it is estimated by a copy of the model driven by
the measured velocity and corrected by the tracking error ``e = x - r``::

    dz_hat/dt = v - sigma0*|v|*z_hat/g(v) - k*e
    F_hat     = sigma0*z_hat + sigma1*dz_hat/dt + sigma2*v

and ``F_hat`` is fed forward (added to the PID force demand of
:mod:`controllers.pid`). With the PID error dynamics strictly positive
real, the estimation error is dissipative and the loop is stable for every
``k > 0`` (their Theorem/passivity argument). A sampled loop through a valve is
not strictly positive real: at rest the correction is an integral action of gain
``sigma0*k``, and ``k`` is derived (and an explicit one checked) on the loop that
contains it (rule 4 of :mod:`controllers.tuning`).

Extension to the film state: where the controller's model has the lubricant
film ``h`` (modified LuGre, NMLGM; seed 002 Eqs. 7-9), ``h_hat`` is
propagated with the model's own film equation from the same velocity, so
``g(v, h_hat)`` follows the frictional lag; the NMLGM lead term
``sigma2*T*dv/dt`` uses the reference acceleration (noise free). Any other
states the model has (effects such as ``dwell-time``) are propagated the
same way, open loop. The equations are the controller model's own
(:meth:`fcomp.models.base.FrictionModel.rhs` / ``force``), only the ``-k*e``
correction of ``dz/dt`` is added here.

Discretisation: the exponential Rosenbrock-Euler step of
:mod:`fcomp.models.stepping` (exact for the bristle equation, linear in ``z`` at
the held velocity, and unconditionally stable however stiff), with the
correction held over the sample.

The velocity is the PID's filtered derivative of the measured position
(the paper assumes a measured velocity).
"""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from controllers.base import Reference
from controllers.pid import PIDController
from controllers.tuning import check_observer
from fcomp.backend import CASADI
from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel, Signals
from fcomp.models.stepping import exponential_euler


def observer_step(model: FrictionModel) -> ca.Function:
    """``(x_hat, sig, c, dt) -> (x_hat_next, F_hat)``: one corrected observer step.

    ``c`` (m/s) is added to ``dz/dt``; ``F_hat`` is the friction force at
    ``x_hat`` including ``sigma1*c`` (the damping acts on the corrected
    ``dz_hat/dt``).
    """
    model.require_symbolic()
    if "z" not in model.state_names:
        raise FcompError(
            f"lugre-observer needs a friction model with a bristle state z; "
            f"{model.describe()!r} has {model.state_names or 'no states'}"
        )
    nx = model.n_states
    iz = model.state_names.index("z")
    x = ca.SX.sym("x", nx)
    sig, sigv = Signals.symbolic()
    c = ca.SX.sym("c")
    dt = ca.SX.sym("dt")
    P = model.param_values(CASADI)
    xl = [x[i] for i in range(nx)]
    f = ca.vertcat(*model.rhs(CASADI, xl, sig, P))
    f[iz] = f[iz] + c
    x_next = exponential_euler(f, x, dt)
    sigma1 = float(model.flat_params().get("sigma1", 0.0))
    F = model.force(CASADI, xl, sig, P) + sigma1 * c
    return ca.Function("lugre_observer_step", [x, sigv, c, dt], [x_next, F],
                       ["x", "sig", "c", "dt"], ["x_next", "F"])


class LuGreObserverController(PIDController):
    """PID plus the LuGre observer's friction estimate (see the module docstring).

    Parameters
    ----------
    observer_gain
        ``k`` (1/s) of the correction ``-k*e``; default the plant's
        :attr:`~controllers.plant_model.ControlModel.observer_gain`.
    **options
        Those of :class:`~controllers.pid.PIDController`.
    """

    name: ClassVar[str] = "lugre-observer"
    options: ClassVar[tuple[str, ...]] = (*PIDController.options, "observer_gain")
    tuning_options: ClassVar[tuple[str, ...]] = (*PIDController.tuning_options, "observer_gain")

    def __init__(self, model: Any, **options: Any) -> None:
        super().__init__(model, **options)
        self.k = float(self.opts.get("observer_gain", model.observer_gain))
        if not self.k > 0:
            raise FcompError(f"lugre-observer: observer_gain must be positive (1/s), got {self.k}")
        explicit = sorted(set(self.opts) & set(self.tuning_options))
        #: Margins of the loop with the observer's path at rest (rule 4 of
        #: :mod:`controllers.tuning`): explicit values are checked, the derived ones are the
        #: tuning's.
        self.observer_margins = (check_observer(self.gains, model, self.k, self.valve.bandwidth,
                                                self.dt, f"{self.name} tuning "
                                                f"({', '.join(explicit)} given)")
                                 if explicit else model.tuning.observer_margins)
        self._step = observer_step(model.friction)
        self._side = 1.0
        self.x_hat = model.friction.initial_state()

    def healthy(self) -> bool:
        return (super().healthy() and bool(np.all(np.isfinite(self.x_hat)))
                and bool(np.isfinite(self._side)))

    def reset_compensation(self, y0: np.ndarray, ref: Reference) -> None:
        self.x_hat = self.model.friction.initial_state()
        self._side = 1.0

    def compensation(self, t: float, y: np.ndarray, ref: Reference, v: float) -> float:
        if v != 0.0:
            self._side = 1.0 if v > 0 else -1.0
        p1g, p2g = self.model.gauge(y)
        sig = [v, ref.ddr, float(y[0]), p1g, p2g, self._side]
        c = -self.k * (float(y[0]) - ref.r)
        x_next, F = self._step(self.x_hat, sig, c, self.dt)
        self.x_hat = np.asarray(x_next, dtype=float).ravel()
        return float(F)
