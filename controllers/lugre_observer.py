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
:mod:`controllers.friction_states` (exact for the bristle equation, linear in ``z``
at the held velocity, and unconditionally stable however stiff), with the
correction held over the sample.

The velocity is the PID's filtered derivative of the measured position
(the paper assumes a measured velocity).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from controllers.base import Reference
from controllers.friction_states import friction_step
from controllers.pid import PIDController
from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel


def observer_friction(model: Any, stiffness: float | None = None) -> FrictionModel:
    """The observer's friction model: the controller model's with the bristle stiffness
    ``stiffness`` (N/m; default the tuning's, rule 4 of :mod:`controllers.tuning`).

    At rest the observer's bristle integrates the measured velocity, ``z_hat - z0 = x - x0``
    (filtered, one sample late), and ``sigma0_obs*(x - x0)`` is fed forward against the
    seal's own pre-sliding spring ``sigma0_seal*(x - x0)``. Where the seal is softer than
    the observer's model the difference is a negative stiffness the PID must hold (with
    ``sigma0`` = 2e6 N/m, ``kp`` = 3e5 N/m and a seal half as stiff, the resting loop rings
    at 4.5 Hz and grows to a 0.25 mm limit cycle, on the nonlinear loop as in its
    linearisation); and even an exact cancellation leaves ``sigma0 (1 - e^{-sT})``, the
    spring against its own late copy, a path of up to twice the seal's stiffness at high
    frequency. So the observer's stiffness is at most the low end of the seal's range
    (:attr:`plants.uncertainty.Uncertainty.presliding` times the seal's ``sigma0``,
    :attr:`~controllers.plant_model.ControlModel.bristle`) and is lowered from there until
    the loop at rest meets the requirement (rule 4). Every ``sigma0`` parameter of a
    direction-dependent model is scaled alike. Sliding, the estimate is unchanged -- the
    bristle's steady state ``z = g(v)/sigma0`` gives the force ``g(v)`` whatever
    ``sigma0``; only the pre-sliding displacement the observer assumes grows.
    """
    fr = model.friction
    p = fr.flat_params()
    if "sigma0" not in p or "z" not in fr.state_names:
        return fr
    s0 = float(model.tuning.observer_stiffness if stiffness is None else stiffness)
    if not (math.isfinite(s0) and s0 > 0) or s0 == float(p["sigma0"]):
        return fr
    factor = s0 / float(p["sigma0"])
    return fr.with_params(**{k: v * factor for k, v in p.items()
                             if k == "sigma0" or k.startswith("sigma0_")})


def stiffness_ceiling(model: Any) -> float:
    """The highest bristle stiffness the observer may have (N/m): the low end of the seal's
    range, ``(1 + lo) sigma0_seal``, and no more than its model's ``sigma0``
    (:func:`observer_friction`)."""
    s0 = float(model.friction.flat_params()["sigma0"])
    seal = model.bristle
    if seal is None:
        return s0
    return min(s0, (1.0 + float(model.uncertainty.presliding[0])) * float(seal[0]))


def observer_step(model: FrictionModel) -> ca.Function:
    """``(x_hat, sig, c, dt) -> (x_hat_next, F_hat)``: one corrected observer step
    (:func:`controllers.friction_states.friction_step` with the correction on ``z``).

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
    return friction_step(model, "z")


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
    uses_friction: ClassVar[bool] = True
    options: ClassVar[tuple[str, ...]] = (*PIDController.options, "observer_gain")
    tuning_options: ClassVar[tuple[str, ...]] = (*PIDController.tuning_options, "observer_gain")

    @classmethod
    def refuses(cls, friction: FrictionModel) -> str | None:
        """A model without the bristle state ``z`` (a static map) or without a symbolic
        form cannot be observed."""
        if "z" not in friction.state_names:
            return (f"lugre-observer needs a friction model with a bristle state z; "
                    f"{friction.describe()!r} has {friction.state_names or 'no states'}")
        return super().refuses(friction)

    def __init__(self, model: Any, **options: Any) -> None:
        super().__init__(model, **options)
        self.k = float(self.opts.get("observer_gain", model.observer_gain))
        if not self.k > 0:
            raise FcompError(f"lugre-observer: observer_gain must be positive (1/s), got {self.k}")
        explicit = sorted(set(self.opts) & set(self.tuning_options))
        #: Margins of the loop with the observer's path at rest (rule 4 of
        #: :mod:`controllers.tuning`): explicit values are checked, the derived ones are the
        #: tuning's.
        #: The observer's friction model (:func:`observer_friction`).
        self.observer_model = observer_friction(model)
        #: Its bristle stiffness (N/m).
        self.observer_stiffness = float(self.observer_model.flat_params()["sigma0"]) \
            if "sigma0" in self.observer_model.flat_params() else math.nan
        self._step = observer_step(self.observer_model)
        self.observer_margins = (model.checked_observer(self, f"{self.name} tuning "
                                                         f"({', '.join(explicit)} given)")
                                 if explicit else model.tuning.observer_margins)
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
