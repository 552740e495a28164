"""``pid-ff``: PID plus static friction feedforward from the steady-state map.

The friction the controller's model predicts at constant velocity (its
steady-state map, for the LuGre family ``F_ss(v) = sign(v)*g(v, h_ss(v)) +
sigma2*v``, seed 002 Eq. 12) is evaluated at the *reference* velocity and
added to the PID force demand of :mod:`controllers.pid`::

    F_hat = F_ss(dr/dt) * min(|dr/dt| / v_band, 1)

Using the reference rather than the measured velocity keeps sensor noise
out of the feedforward (and cannot chatter at rest); the factor
``min(|dr|/v_band, 1)`` fades the map in over a small velocity band
(``ff_band``, default 0.5 mm/s) so the demand has no jump of ``2*Fs`` where
the reference reverses. At rest (``dr = 0``) no friction is fed forward:
the static map cannot say which way the friction acts there.

The map is the controller model's own steady state
(:meth:`fcomp.models.base.FrictionModel.steady_state_states` and ``force``,
evaluated symbolically once and called as a CasADi function), with the
measured pressures for pressure-dependent models.
"""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from controllers.base import Reference
from controllers.pid import PIDController
from fcomp.backend import CASADI
from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel, Signals


def steady_state_function(model: FrictionModel) -> ca.Function:
    """``(v, x, p1, p2) -> F_ss`` (N): the steady-state map, symbolic (gauge pressures)."""
    model.require_symbolic()
    v, x, p1, p2 = (ca.SX.sym(n) for n in ("v", "x", "p1", "p2"))
    s = ca.if_else(v >= 0, 1.0, -1.0)
    sig = Signals(v=v, a=0.0, x=x, p1=p1, p2=p2, s=s)
    P = model.param_values(CASADI)
    xs = model.steady_state_states(CASADI, sig, P)
    F = model.force(CASADI, xs, sig, P)
    return ca.Function("steady_state_map", [v, x, p1, p2], [F], ["v", "x", "p1", "p2"], ["F"])


class PIDFeedforwardController(PIDController):
    """PID plus the static map at the reference velocity (see the module docstring).

    Parameters
    ----------
    ff_band
        Velocity band (m/s) over which the feedforward fades in.
    **options
        Those of :class:`~controllers.pid.PIDController`.
    """

    name: ClassVar[str] = "pid-ff"
    options: ClassVar[tuple[str, ...]] = (*PIDController.options, "ff_band")

    def __init__(self, model: Any, **options: Any) -> None:
        super().__init__(model, **options)
        self.band = float(self.opts.get("ff_band", 5e-4))
        if not self.band > 0:
            raise FcompError(f"pid-ff: ff_band must be positive (m/s), got {self.band}")
        self._map = steady_state_function(model.friction)

    def compensation(self, t: float, y: np.ndarray, ref: Reference, v: float) -> float:
        if ref.dr == 0.0:
            return 0.0
        p1g, p2g = self.model.gauge(y)
        F = float(self._map(ref.dr, float(y[0]), p1g, p2g))
        return F * min(abs(ref.dr) / self.band, 1.0)
