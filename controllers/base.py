"""The controller contract and the controller's own model of the plant.

Implementer's contract
======================
A controller is a subclass of :class:`Controller` registered by ``name`` in
:data:`controllers.CONTROLLERS`, constructed as ``Cls(model, **options)``
with a :class:`ControlModel` (the controller's *own* model of the plant,
never the simulated plant's object) and named options (each class lists
them in ``options``; an unknown one is refused in one line). It implements

:meth:`Controller.reset` ``(t0, y0, ref)``
    forget everything and start at time ``t0`` (s) from the measurement
    ``y0`` and reference ``ref``;
:meth:`Controller.step` ``(t, y, ref) -> u``
    one sample: the measurement ``y = [x, p1, p2]`` (position m, chamber
    pressures Pa *absolute*, as the sensors give them, with their noise and
    quantisation) and the reference ``ref`` (:class:`Reference`) at time
    ``t``; returns the valve command ``u`` (A for the hydraulic servo valve,
    normalised -1..1 for the pneumatic valve), held until the next sample.

and may refine (the defaults serve most controllers):

:meth:`Controller.reenter` ``(t, y, ref, u)``
    resume after the fail-safe layer (:mod:`controllers.safety`) held the valve at
    ``u``: re-seed the states from the measurement ``y`` without a bump (default:
    :meth:`reset`, then :meth:`applied`);
:meth:`Controller.healthy` ``()``
    whether its states are all finite (default True; the layer re-seeds it otherwise);
:meth:`Controller.applied` ``(u)``
    the command the valve was actually given after this step (the layer's range and
    rate limits; default: nothing to do -- a controller whose estimator predicts
    with its last command takes it from here).

:func:`controllers.make_controller` returns every controller behind the fail-safe
layer (:class:`controllers.safety.FailSafe`: input validation, latched safe output,
recovery, range and rate limit); a controller's own ``step`` may assume valid,
finite inputs.

and keeps up to date, after every step:

``friction_estimate``
    the friction force (N) it fed forward (0 for ``pid``);
``fallback_active`` / ``fallbacks``
    whether this step used the controller's stated fallback law (an MPC
    solve that failed) and how many steps did so far -- counted in the
    metrics, never hidden.

The sampled-data loop that calls them is :mod:`controllers.harness`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np

from fcomp.errors import FcompError


class Reference(NamedTuple):
    """Reference at one sample: position ``r`` (m), velocity ``dr`` (m/s), acceleration ``ddr``
    (m/s^2); ``future`` holds the positions at the next samples where a predictive controller
    asks for them (else empty)."""

    r: float
    dr: float
    ddr: float
    future: tuple[float, ...] = ()


class Controller(ABC):
    """Base class of controllers (see the module docstring for the contract)."""

    name: ClassVar[str] = ""
    #: option names accepted by the constructor
    options: ClassVar[tuple[str, ...]] = ("rate",)
    #: how many future reference samples :meth:`step` wants in ``Reference.future``
    preview: int = 0

    def __init__(self, model: Any, **options: Any) -> None:
        check_options(f"controller {self.name}", options, self.options)
        for k, v in options.items():
            if isinstance(v, int | float) and not isinstance(v, bool) and not math.isfinite(v):
                raise FcompError(f"controller {self.name}: option {k} must be finite, got {v}")
        self.model = model
        self.opts: dict[str, Any] = dict(options)
        rate = float(options.get("rate", model.control_rate))
        if not (math.isfinite(rate) and rate > 0):
            raise FcompError(f"controller {self.name}: rate must be a positive number of Hz")
        self.rate = rate
        self.dt = 1.0 / rate
        self.friction_estimate = 0.0
        self.fallback_active = False
        self.fallbacks = 0

    @abstractmethod
    def reset(self, t0: float, y0: np.ndarray, ref: Reference) -> None:
        """Forget all state; start at ``t0`` (s) from measurement ``y0`` and reference ``ref``."""

    @abstractmethod
    def step(self, t: float, y: np.ndarray, ref: Reference) -> float:
        """One sample: measurement ``y = [x, p1, p2]`` (m, Pa abs) -> valve command ``u``."""

    def reenter(self, t: float, y: np.ndarray, ref: Reference, u: float) -> None:
        """Resume at ``t`` from measurement ``y`` after the valve was held at command ``u``
        (the fail-safe layer's recovery, :mod:`controllers.safety`): by default a
        :meth:`reset` from ``y``, told the held command."""
        self.reset(t, y, ref)
        self.applied(u)

    def healthy(self) -> bool:
        """Whether the controller's states are all finite (the fail-safe layer re-seeds it
        otherwise); True by default (no states to check)."""
        return True

    def applied(self, u: float) -> None:
        """The command ``u`` the valve was given after the last step (after the fail-safe
        layer's limits); nothing to do by default."""
        return None

    def describe(self) -> str:
        return f"{self.name} at {self.rate:g} Hz on {self.model.describe()}"


def check_options(name: str, given: Mapping[str, Any], known: tuple[str, ...]) -> None:
    """Refuse unknown option names in one line."""
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise FcompError(
            f"{name}: unknown option(s) {', '.join(unknown)}; known: {', '.join(known)}"
        )
