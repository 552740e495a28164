"""Friction compensation in closed loop: controllers by name, the harness, metrics and tasks.

==================== ============================================================
name                 controller
==================== ============================================================
``pid``              PID with derivative filter and anti-windup (:mod:`.pid`)
``pid-ff``           PID + static friction feedforward (:mod:`.feedforward`)
``lugre-observer``   PID + observer-based LuGre compensation, Canudas de Wit et
                     al. 1995, extended to the film state (:mod:`.lugre_observer`)
``ekf``              PID + extended Kalman filter on the friction states
                     (:mod:`.ekf`, filterpy)
``mpc``              nonlinear MPC, CasADi, real-time iteration, fed by the EKF
                     (:mod:`.mpc`)
==================== ============================================================

Every controller :func:`make_controller` builds runs behind the fail-safe layer of
:mod:`.safety` (input validation, latched safe output, recovery without re-init, the
valve's range and rate limit).

>>> from controllers import make_controller
>>> from controllers.plant_model import ControlModel
>>> model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))  # doctest: +SKIP
>>> ctrl = make_controller("lugre-observer", model)                                 # doctest: +SKIP

The closed loop is :func:`controllers.harness.run_closed_loop`; tasks are
:data:`controllers.tasks.TASKS`.
"""

from __future__ import annotations

from typing import Any

from controllers.base import Controller, Reference
from controllers.ekf import EKFController
from controllers.feedforward import PIDFeedforwardController
from controllers.lugre_observer import LuGreObserverController
from controllers.mpc import MPCController
from controllers.pid import PIDController
from controllers.safety import FailSafe
from fcomp import registry
from fcomp.registry import Registry

#: fcomp's registry of controllers (:mod:`fcomp.registry`, entry point ``fcomp.controllers``),
#: filled here.
CONTROLLERS: Registry[type[Controller]] = registry.CONTROLLERS
for _cls in (PIDController, PIDFeedforwardController, LuGreObserverController, EKFController,
             MPCController):
    CONTROLLERS.register(_cls.name, _cls)


def make_controller(name: str, model: Any, **options: Any) -> Controller:
    """The controller ``name`` on the controller model ``model`` with named ``options``,
    behind the fail-safe layer (:class:`controllers.safety.FailSafe`: its inputs validated,
    a safe output latched after repeated faults, recovery, the valve's range and rate limit;
    :func:`controllers.safety.unwrap` gives the law alone)."""
    return FailSafe(CONTROLLERS.get(name)(model, **options))


__all__ = ["CONTROLLERS", "Controller", "Reference", "make_controller"]
