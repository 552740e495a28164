"""``pid-ff``: PID plus friction feedforward: the controller model's friction along the reference.

The friction the controller's model predicts *if the piston follows the
reference* is added to the PID force demand of :mod:`controllers.pid`:

* a **dynamic** model (states: LuGre's bristle ``z``, the film ``h``, an
  effect's states) has its states stepped along the reference motion --
  velocity ``dr/dt``, acceleration ``d2r/dt2``, position ``r``, the measured
  chamber pressures -- by :func:`controllers.friction_states.friction_step`, and
  its force at those states is fed forward: the pre-sliding at starts and
  reversals (the friction reverses over the bristles' deflection, some 0.1 mm,
  not at the instant the reference velocity changes sign), the frictional lag
  and the force held at rest are the model's own;
* a **static** map (Coulomb-viscous, Stribeck) is its steady state
  (:meth:`fcomp.models.base.FrictionModel.steady_state_states` and ``force``,
  for the LuGre family ``F_ss(v) = sign(v)*g(v, h_ss(v)) + sigma2*v``, seed 002
  Eq. 12) at the reference velocity::

      F_hat = F_ss(dr/dt) * min(|dr/dt| / v_band, 1)

  the factor fading the map in over a small velocity band (``ff_band``, default
  0.5 mm/s) so the demand has no jump of ``2*Fs`` where the reference reverses;
  at rest (``dr = 0``) nothing is fed forward: a static map cannot say which way
  the friction acts there.

Driven by the reference, not the measured velocity, the feedforward carries no
sensor noise and cannot chatter at rest. The steady state of the static map
at the reference velocity was the former law for every model; for a dynamic
model it is wrong exactly where the friction matters -- at a reversal it
steps from ``+Fs`` to ``-Fs`` in a fraction of a millisecond while the true
friction takes tens of milliseconds -- so a controller built on the *true*
LuGre friction fed forward worse than one built on a Coulomb level (the
hydraulic servo's fast sine: 55 um against 30 um; now 12 um against 61 um).
Like every friction estimate, it reaches the piston through the force loop
with its lead (:meth:`controllers.pid.PIDController.friction_demand`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import casadi as ca
import numpy as np

from controllers.base import Reference
from controllers.friction_states import friction_step
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
    """PID plus the model's friction along the reference (see the module docstring).

    Parameters
    ----------
    ff_band
        Velocity band (m/s) over which a static map's feedforward fades in.
    **options
        Those of :class:`~controllers.pid.PIDController`.
    """

    name: ClassVar[str] = "pid-ff"
    uses_friction: ClassVar[bool] = True
    options: ClassVar[tuple[str, ...]] = (*PIDController.options, "ff_band")

    def __init__(self, model: Any, **options: Any) -> None:
        super().__init__(model, **options)
        self.band = float(self.opts.get("ff_band", 5e-4))
        if not self.band > 0:
            raise FcompError(f"pid-ff: ff_band must be positive (m/s), got {self.band}")
        friction = model.friction
        #: Whether the model has states (stepped along the reference) or is a static map.
        self.dynamic = friction.n_states > 0
        self._map = steady_state_function(friction)
        self._step = friction_step(friction) if self.dynamic else None
        self.x_ff = np.asarray(friction.initial_state(), dtype=float).ravel()
        self._side = 1.0

    def reset_compensation(self, y0: np.ndarray, ref: Reference) -> None:
        self.x_ff = np.asarray(self.model.friction.initial_state(), dtype=float).ravel()
        self._side = 1.0

    def compensation(self, t: float, y: np.ndarray, ref: Reference, v: float) -> float:
        p1g, p2g = self.model.gauge(y)
        if self._step is not None:
            if ref.dr != 0.0:
                self._side = 1.0 if ref.dr > 0 else -1.0
            sig = [ref.dr, ref.ddr, ref.r, p1g, p2g, self._side]
            x_next, F = self._step(self.x_ff, sig, 0.0, self.dt)
            self.x_ff = np.asarray(x_next, dtype=float).ravel()
            return float(F)
        if ref.dr == 0.0:
            return 0.0
        F = float(self._map(ref.dr, ref.r, p1g, p2g))
        return F * min(abs(ref.dr) / self.band, 1.0)
