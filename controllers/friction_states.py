"""The controller model's friction states stepped along a motion: one sampled step, symbolic.

A dynamic friction model (LuGre and its family, effects with states such as
``dwell-time``) predicts the force from states that follow the motion -- the
bristle deflection ``z``, the film ``h``. Two compensators step them:

* the LuGre observer (:mod:`controllers.lugre_observer`) along the *measured*
  velocity, with a correction added to ``dz/dt``;
* the feedforward (:mod:`controllers.feedforward`) along the *reference*
  motion, uncorrected: the friction the model predicts if the piston follows
  the reference, pre-sliding at starts and reversals included.

:func:`friction_step` is that step: ``(x, sig, c, dt) -> (x_next, F)`` with
``sig`` the signals ``[v, a, x, p1, p2, s]`` held over the sample
(:class:`fcomp.models.base.Signals`) and ``c`` (m/s) added to the rate of
the corrected state. Discretisation: the exponential Rosenbrock-Euler step
of :mod:`fcomp.models.stepping` (exact for the bristle equation, linear in
``z`` at the held velocity, and unconditionally stable however stiff). The
equations are the model's own (:meth:`fcomp.models.base.FrictionModel.rhs`
and ``force``).
"""

from __future__ import annotations

import casadi as ca

from fcomp.backend import CASADI
from fcomp.models.base import FrictionModel, Signals
from fcomp.models.stepping import exponential_euler


def friction_step(model: FrictionModel, corrected: str | None = None) -> ca.Function:
    """``(x, sig, c, dt) -> (x_next, F)``: one step of the model's friction states (module
    docstring).

    ``c`` (m/s) is added to the rate of the state ``corrected`` (``None``: no state, ``c``
    unused); ``F`` is the friction force at ``x`` with ``sigma1*c`` added when the corrected
    state is the bristle ``z`` (its damping acts on the corrected ``dz/dt``). A model
    without states gives ``x_next`` of size 0 and its static force.

    Raises
    ------
    NotSymbolicError
        For a model without a symbolic form.
    """
    model.require_symbolic()
    nx = model.n_states
    x = ca.SX.sym("x", nx)
    sig, sigv = Signals.symbolic()
    c = ca.SX.sym("c")
    dt = ca.SX.sym("dt")
    P = model.param_values(CASADI)
    xl = [x[i] for i in range(nx)]
    F = model.force(CASADI, xl, sig, P)
    if nx:
        f = ca.vertcat(*model.rhs(CASADI, xl, sig, P))
        if corrected is not None:
            i = model.state_names.index(corrected)
            f[i] = f[i] + c
        x_next = exponential_euler(f, x, dt)
    else:
        x_next = ca.SX(0, 1)
    if corrected == "z":
        F = F + float(model.flat_params().get("sigma1", 0.0)) * c
    return ca.Function("friction_step", [x, sigv, c, dt], [x_next, F],
                       ["x", "sig", "c", "dt"], ["x_next", "F"])


__all__ = ["friction_step"]
