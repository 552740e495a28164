"""The plant base class.

Implementer's contract
======================
A plant is a subclass of :class:`Plant` registered by ``name`` in
:data:`plants.PLANTS`, constructed as ``Plant(friction, params=None)`` with a
friction model of :mod:`fcomp.models` (any effects) and a parameter set
(name or :class:`~fcomp.paramsets.ParameterSet`; each plant documents its
default). It declares ``input_names`` (with units in ``input_units``) and
implements :meth:`simulate`, which returns a :class:`~fcomp.measurement.Measurement`
sampled at ``rate`` over ``[0, duration]`` in the data format.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.models.base import FrictionModel
from fcomp.paramsets import ParameterSet
from fcomp.paramsets import get as get_paramset

InputFn = Callable[[np.ndarray], np.ndarray]


def output_times(duration: float, rate: float) -> np.ndarray:
    """Sample times ``0, 1/rate, ..., duration`` (s); validates both."""
    if not (np.isfinite(duration) and duration > 0):
        raise FcompError(f"--duration must be a positive number of seconds, got {duration}")
    if not (np.isfinite(rate) and rate > 0):
        raise FcompError(f"--rate must be a positive number of hertz, got {rate}")
    n = int(round(duration * rate))
    if n < 1:
        raise FcompError(f"--duration {duration} s at --rate {rate} Hz gives no samples")
    if n > 50_000_000:
        raise FcompError(f"{n} samples requested; lower --rate or --duration")
    return np.arange(n + 1) / rate


class Plant(ABC):
    """Base class of plants (see the module docstring for the contract)."""

    name: ClassVar[str] = ""
    default_params: ClassVar[str | None] = None
    input_names: ClassVar[tuple[str, ...]] = ("u",)
    input_units: ClassVar[tuple[str, ...]] = ("-",)

    def __init__(self, friction: FrictionModel, params: str | ParameterSet | None = None) -> None:
        if not isinstance(friction, FrictionModel):
            raise ValueError(f"plant {self.name}: friction must be a FrictionModel")
        self.friction = friction
        if params is None and self.default_params is not None:
            params = self.default_params
        self.paramset: ParameterSet | None = (
            get_paramset(params) if isinstance(params, str) else params
        )

    @abstractmethod
    def simulate(
        self, u: InputFn, duration: float, rate: float, *, x0: Any = None, **options: Any
    ) -> Measurement:
        """Simulate over ``[0, duration]`` s and return the run sampled at ``rate`` Hz."""

    def describe(self) -> str:
        ps = self.paramset.name if self.paramset else "defaults"
        return f"{self.name} ({ps}) with {self.friction.describe()}"
