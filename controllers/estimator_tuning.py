"""Estimator tuning from the model's own uncertainty: the EKF's process noise.

An extended Kalman filter (:mod:`controllers.ekf`, and the MPC's state
estimate) weighs its model against the measurements: its process noise ``Q``
says how far the model's prediction may drift per unit time. Fixed noise
levels (a thousandth of each state's scale, half the bristle's scale per
``sqrt(s)``) make the filter trust an exact model exactly as little as a crude
one: the estimate of the exact model then follows the measurement noise as
freely as that of a wrong model, and what a better model should buy is given
away. Here the friction's share of ``Q`` follows from what the model's
identification says of its own accuracy.

Rules (SI units)
----------------
1. **The friction's uncertainty** ``sigma_F`` (N) of the controller's model:

   * from the standard errors of its values (a fit's or a model file's ``stderr``,
     :attr:`fcomp.models.base.FrictionModel.stderr`), propagated to first order
     through the steady-state map over the speeds a servo tracks
     (:data:`SPEEDS`, both directions), at mid stroke with the chamber pressures
     that hold the load there (:func:`operating_point`)::

         sigma_F^2 = mean_v sum_i (dF_ss/dtheta_i (v) * sigma_i)^2

     the derivatives by central differences (the parameters a draw may vary:
     :func:`controllers.truths.varied_names`); the parameters' correlations are not
     in the model files, so the terms add as if independent;
   * without standard errors (a parameter set from a paper, a model by name):
     :data:`DEFAULT_RELATIVE` (10 %) of the RMS friction level over those speeds
     -- a model whose values nobody estimated is trusted to a tenth.

2. **Its correlation time** ``tau`` (s): the position loop's time constant
   ``1/w_P`` (:mod:`controllers.tuning`, rule 2) -- a friction error the estimate
   must follow within the time the loop reacts to it.

3. **Process noise of the friction state that carries the force**: the state ``s``
   through which the model's force moves most directly -- the largest
   ``|dF/ds|*scale_s``, the force one state scale is worth, at the model's steady
   state at :data:`SENSITIVITY_SPEED`: the bristle ``z`` of the LuGre family,
   ``|dF/dz| = sigma0`` -- gets the rate-noise intensity
   ``q_s = sigma_F/(|dF/ds| sqrt(tau))``: over ``tau`` its random walk moves the
   force by ``sigma_F``. The
   model's other friction states (the film ``h``, an effect's) follow their own
   equations with the plant states' share (rule 4): a film free to wander would
   take the force error the bristle should (``h`` moves the force only through
   the bristle's equilibrium, ``|dF/dh|`` held ``z`` is small, so its noise
   would be large) and let the estimate of an exact NMLGM follow the noise (the
   hydraulic servo's slow sine: 2.65 times the error with plain LuGre). A static
   map has no state to carry its error: the estimator trusts it, and what it
   misses is a bias the PID's integral takes. Putting its uncertainty on the
   velocity instead (``q_v = sigma_F sqrt(tau)/m``, a force error acting for
   ``tau`` on the mass) makes the velocity estimate follow the position noise, and
   the map's force at it -- a sign function at rest -- chatter: the EKF on the
   *exact* Coulomb-viscous friction of the hydraulic servo then tracked worse than
   on a Coulomb level 30 % off (ramp 44 against 40 um; with the velocity at its
   plant share 17 against 90 um).

4. **The plant's states** (position, velocity, chamber pressures, valve): a
   thousandth of their scales. Their models are the plant file's (moving mass, valve flow gain, bulk
   modulus), which carries no standard errors. The velocity must not carry the
   friction's uncertainty: beside the bristle's it lets the estimate of an exact
   LuGre follow the position noise too (the hydraulic servo's steps: 35 um against
   14 um with the velocity at its plant share), and gives away what the better
   model buys.

The measurement noise is the sensors' (:meth:`controllers.plant_model.ControlModel.
sensor_std`, rule 5 of :mod:`controllers.tuning`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from fcomp.models import FrictionModel

if TYPE_CHECKING:
    from controllers.plant_model import ControlModel

#: Relative accuracy of a model whose values nobody estimated (no standard errors).
DEFAULT_RELATIVE = 0.1
#: Speeds (m/s) the friction's uncertainty is averaged over: a servo's tracking speeds.
SPEEDS = np.geomspace(1e-4, 0.3, 25)
#: Speed (m/s) of the steady state where the force's sensitivity to its states is taken.
SENSITIVITY_SPEED = 0.01
#: Process noise of the plant's own states, per unit of their scale and sqrt(s).
PLANT_STATE_NOISE = 1e-3


@dataclass(frozen=True)
class FrictionUncertainty:
    """The friction force's uncertainty of a model (rule 1).

    Attributes
    ----------
    sigma_F
        Standard uncertainty of the friction force (N).
    level
        RMS friction level over :data:`SPEEDS` (N).
    source
        ``"standard errors"`` or ``"default"`` (:data:`DEFAULT_RELATIVE` of the level).
    """

    sigma_F: float
    level: float
    source: str


@dataclass(frozen=True)
class Operating:
    """Where the map is evaluated besides the speeds: the position ``x`` (m) and the
    chambers' gauge pressures ``p1``, ``p2`` (Pa) -- a pressure-dependent level is nil at
    zero gauge pressure, which would make the uncertainty of its model nil too."""

    x: float = 0.0
    p1: float = 0.0
    p2: float = 0.0


def _map(model: FrictionModel, at: Operating) -> np.ndarray:
    v = np.concatenate([SPEEDS, -SPEEDS])
    return np.asarray(model.steady_state(v, x=at.x, p1=at.p1, p2=at.p2), dtype=float)


def operating_point(model: ControlModel) -> Operating:
    """Mid stroke, with the chambers' gauge pressures holding the load there (the plant's
    equilibrium, :func:`plants.equilibrium.equilibrium`)."""
    from plants.equilibrium import equilibrium

    x = 0.5 * model.stroke
    try:
        x0, _ = equilibrium(model.plant, x)
    except Exception:  # noqa: BLE001 -- no equilibrium: the run itself will say why
        return Operating(x=x)
    names = model.plant.state_names
    return Operating(x=x, p1=float(x0[names.index("p1")]) - model.p_atm,
                     p2=float(x0[names.index("p2")]) - model.p_atm)


def friction_uncertainty(model: FrictionModel, at: Operating | None = None
                         ) -> FrictionUncertainty:
    """``sigma_F`` of ``model`` (rule 1) at the operating point ``at`` (default position and
    pressures zero): from its standard errors, else the default share of its level."""
    from controllers.truths import varied_names

    at = at or Operating()
    base = _map(model, at)
    level = float(np.sqrt(np.mean(base**2)))
    se = model.stderr
    names = [k for k in varied_names(model) if se.get(k, 0.0) > 0 and math.isfinite(se[k])]
    if not names:
        return FrictionUncertainty(DEFAULT_RELATIVE * level, level, "default")
    flat = model.flat_params()
    specs = model.param_specs()
    var = np.zeros_like(base)
    for k in names:
        h = 1e-4 * max(abs(flat[k]), se[k])
        lo, hi = max(flat[k] - h, specs[k].lower), min(flat[k] + h, specs[k].upper)
        try:
            d = (_map(model.with_params(**{k: hi}), at)
                 - _map(model.with_params(**{k: lo}), at))
        except ValueError:  # a step across a constraint (Fc at Fs): one side only
            try:
                d = _map(model.with_params(**{k: lo}), at) - base
                hi = flat[k]
            except ValueError:
                continue
        if hi > lo:
            var += (d / (hi - lo) * se[k]) ** 2
    return FrictionUncertainty(float(np.sqrt(np.mean(var))), level, "standard errors")


def state_sensitivities(model: ControlModel, at: Operating | None = None) -> dict[str, float]:
    """``|dF/ds|`` (N per state unit) of the friction force to each friction state at the
    model's steady state at :data:`SENSITIVITY_SPEED` (rule 3); states without effect left
    out."""
    import casadi as ca

    from fcomp.backend import CASADI, NUMPY
    from fcomp.models.base import Signals

    friction = model.friction
    if not friction.n_states:
        return {}
    v = SENSITIVITY_SPEED
    at = at or Operating(x=0.5 * model.stroke)
    sig = Signals(v=v, a=0.0, x=at.x, p1=at.p1, p2=at.p2, s=1.0)
    xs = [float(np.asarray(c)) for c in
          friction.steady_state_states(NUMPY, sig, friction.param_values(NUMPY))]
    x = ca.SX.sym("x", friction.n_states)
    ssig, sigv = Signals.symbolic()
    F = friction.force(CASADI, [x[i] for i in range(friction.n_states)], ssig,
                       friction.param_values(CASADI))
    J = ca.Function("dF_dx", [x, sigv], [ca.jacobian(F, x)])(xs, [v, 0.0, at.x, at.p1,
                                                                  at.p2, 1.0])
    grads = np.abs(np.asarray(J, dtype=float).ravel())
    return {n: float(g) for n, g in zip(friction.state_names, grads, strict=True) if g > 0}


def process_noise(model: ControlModel) -> np.ndarray:
    """The EKF's process-noise intensities per state of ``model.prediction`` (state unit per
    sqrt(s); module docstring, rules 1-4)."""
    sc = np.asarray(model.prediction.scales, dtype=float)
    names = model.prediction.state_names
    q = PLANT_STATE_NOISE * sc
    at = operating_point(model)
    u = friction_uncertainty(model.friction, at)
    tau = 1.0 / model.tuning.pid_bandwidth
    sens = {n: s for n, s in state_sensitivities(model, at).items() if n in names}
    if sens:
        n = max(sens, key=lambda k: sens[k] * sc[names.index(k)])
        i = names.index(n)
        q[i] = u.sigma_F / (sens[n] * math.sqrt(tau))
    return q


__all__ = ["DEFAULT_RELATIVE", "PLANT_STATE_NOISE", "SENSITIVITY_SPEED", "SPEEDS",
           "FrictionUncertainty", "Operating", "friction_uncertainty", "operating_point",
           "process_noise", "state_sensitivities"]
