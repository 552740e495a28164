"""The controller's prediction model: plant + friction equations, symbolic, discretised.

The EKF and the MPC do not carry their own copy of any equation or scheme:
they take the continuous-time right-hand side ``dx/dt = f(x, u)`` that the
plant builds symbolically from its equations and the controller's own
friction model (:mod:`plants`, one source of truth), and its discrete-time
step from the plant's documented route,
:meth:`plants.base.OdePlant.discrete_step` with the scheme
:data:`PREDICTION_SCHEME`.

Discretisation: the *linearly implicit (Rosenbrock) Euler* step with the
exact CasADi Jacobian ``J = df/dx`` (:func:`fcomp.rosenbrock.linearly_implicit_euler`)::

    x_{k+1} = x_k + h * (I - h*J(x_k, u))^{-1} * f(x_k, u)

applied ``substeps`` times per sample with the input held (Hairer & Wanner,
*Solving ODEs II*, sec. IV.7). It is L-stable, so the stiff parts of the
model -- the bristle state ``dz/dt = v - sigma0*|v|*z/g`` with
``sigma0*|v|/g`` up to 1e4 1/s, the servo valve at 440 rad/s, the oil
compliance -- neither blow up nor ring at a 1-2 ms step, and it is smooth
in ``x`` and ``u``, as the EKF Jacobian and the MPC's Gauss-Newton
linearisation need. It is first-order accurate; the tests measure its error
against an accurate integration (``scipy.integrate.solve_ivp``, Radau) of
the same equations.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

#: The scheme of the prediction model (:meth:`plants.base.OdePlant.discrete_step`).
PREDICTION_SCHEME = "linearly-implicit-euler"


@dataclass(frozen=True)
class ContinuousModel:
    """A symbolic continuous-time model ``dx/dt = f(x, u)`` and what a controller reads from it.

    Attributes
    ----------
    f
        ``(x, u, p) -> dx/dt`` (CasADi function; ``u`` scalar valve command,
        ``p`` the model parameters, inputs so that one compiled function
        serves every parameter value).
    friction
        ``(x, u, p) -> F`` the friction force (N) at state ``x``.
    p
        The parameter values (the order of ``f``'s ``p``).
    state_names
        Names of the states (``x``, ``v``, ``p1``, ``p2``, valve states,
        friction states ``z``, ``h``, ...).
    measured
        Indices of the measured states, in the order of the measurement
        vector ``y = [x, p1, p2]``.
    scales
        Nominal magnitude of every state (its unit): the discretisation
        works in the scaled states ``x_i/scale_i``.
    discrete
        The plant's :meth:`~plants.base.OdePlant.discrete_step`.
    """

    f: ca.Function
    friction: ca.Function
    p: np.ndarray
    state_names: tuple[str, ...]
    measured: tuple[int, ...]
    scales: np.ndarray
    discrete: Callable[..., ca.Function]

    @property
    def nx(self) -> int:
        return len(self.state_names)

    def index(self, name: str) -> int:
        return self.state_names.index(name)

    def step(self, dt: float, substeps: int = 1, *, sensitivities: bool = False,
             scale_input: bool = False) -> ca.Function:
        """The prediction step ``(x, u, p) -> x_next`` over ``dt`` (s) (module docstring);
        with ``sensitivities`` ``-> (x_next, A, B)``, its step Jacobians; with
        ``scale_input`` ``(x, u, p, s)``, the state scales (:attr:`scales`) an input.

        The controllers compile their steps with the scales as an input: the
        scale of a friction state follows the friction parameters (``z ~
        g/sigma0``), so baked in as constants every parameter draw of a Monte
        Carlo sweep would compile a kernel of its own.
        """
        return self.discrete(dt, substeps, scheme=PREDICTION_SCHEME, sensitivities=sensitivities,
                             scale_input=scale_input)
