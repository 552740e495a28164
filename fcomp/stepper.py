"""The stepper contract: a state advanced one interval at a time, the input held.

A *stepper* advances a state ``x`` over an interval ``dt`` with the input ``u``
held constant over it (zero-order hold, the sampled-data picture)::

    x(t + dt) = Phi(x(t), u, dt)

for a caller that decides the next input only after seeing the state: a
controller in a closed loop, a plant engine driving a friction model. Three
implement it, each with its own numerics:

* :class:`fcomp.simulation.Stepper` -- a plant's ODE, one controller sample
  (the adaptive RODAS4 engine, the step size carried from sample to sample);
* :class:`plants.discrete_memory.MemoryStepper` -- a plant whose friction
  has discrete memory (the engine in coupling intervals with the memory);
* :class:`fcomp.models.hysteresis.HysteresisStepper` -- the hysteresis
  friction model alone (its exponential step and turning-point memory).

Like scipy's :class:`~scipy.integrate.OdeSolver`, the base class
:class:`SampledStepper` does the bookkeeping and the checks common to all
(time, state, the validity of ``x0``, ``u`` and ``dt``) and a subclass only
its numerics.

Using a stepper
---------------
``reset(x0=None) -> x``
    Start again at ``t = 0`` from ``x0`` (default :meth:`~SampledStepper.initial_state`).
``advance(u, dt) -> x``
    Hold ``u`` (one value per name of ``input_names``) for ``dt`` seconds;
    the state at the end (a copy).
``t``, ``x``
    The time since the last reset (s) and the current state (read them, do
    not assign them).
``state_names``, ``input_names``
    What the entries of ``x`` and ``u`` are.

A stepper may add a shorter form of ``advance`` for its use (a fixed sample
time: ``step(u)``; named signals: ``step(dt, v, ...)``) and readings of the
current state (a force); it calls ``advance``.

Implementing one (the implementer's contract)
---------------------------------------------
A subclass provides

``name``, ``state_names``, ``input_names``
    What is stepped (for messages) and tuples of names (attributes or properties).
``initial_state() -> x0``
    The default initial state.
``_start(x) -> None``
    Called by ``reset`` with the checked initial state (already in ``x``, ``t = 0``):
    set up whatever else the numerics carry (a memory, a step size, counters).
``_advance(u, dt) -> x_new``
    The state ``dt`` seconds after ``(t, x)`` with ``u`` held (``u`` a finite
    float array of ``len(input_names)``, ``dt > 0`` finite, both checked). It
    may update what ``_start`` set up, must not assign ``x`` or ``t`` (the
    base does, after it returns) and returns a new array. On failure it
    raises :class:`~fcomp.errors.FcompError` (e.g.
    :class:`~fcomp.errors.ConvergenceError` naming the time); ``t`` and ``x``
    then stay those of the interval's start, what else the numerics carry
    may not (a caller resets before going on).

and calls ``self.reset()`` at the end of its ``__init__`` if it is to be
usable at once.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from fcomp.errors import FcompError


class SampledStepper(ABC):
    """Base class of the steppers (the contract in the module docstring).

    Attributes
    ----------
    name
        What is stepped (for messages).
    t
        Time since the last :meth:`reset` (s).
    x
        Current state, in :attr:`state_names` order.
    """

    t: float
    x: np.ndarray

    @property
    @abstractmethod
    def name(self) -> str:
        """What is stepped (for messages)."""

    @property
    @abstractmethod
    def state_names(self) -> tuple[str, ...]:
        """The names of the entries of :attr:`x`."""

    @property
    @abstractmethod
    def input_names(self) -> tuple[str, ...]:
        """The names of the entries of the input ``u``."""

    @abstractmethod
    def initial_state(self) -> np.ndarray:
        """The default initial state of :meth:`reset`."""

    @abstractmethod
    def _start(self, x: np.ndarray) -> None:
        """Set up the numerics at :meth:`reset` (module docstring)."""

    @abstractmethod
    def _advance(self, u: np.ndarray, dt: float) -> np.ndarray:
        """The state ``dt`` s after ``(t, x)`` with ``u`` held (module docstring)."""

    def reset(self, x0: Any = None) -> np.ndarray:
        """Start again at ``t = 0`` from ``x0`` (default :meth:`initial_state`); the state."""
        x = np.asarray(self.initial_state() if x0 is None else x0, dtype=float).ravel()
        if x.size != len(self.state_names) or not np.all(np.isfinite(x)):
            raise FcompError(f"initial state of {self.name} must be {len(self.state_names)} "
                             f"finite values ({', '.join(self.state_names)}), got {x0!r}")
        self.x = x.copy()
        self.t = 0.0
        self._start(self.x)
        return self.x.copy()

    def advance(self, u: Any, dt: float) -> np.ndarray:
        """Hold ``u`` for ``dt`` s; the state at the end of the interval."""
        if not (math.isfinite(dt) and dt > 0):
            raise FcompError(f"step of {self.name}: the interval must be a positive number "
                             f"of seconds, got {dt}")
        uu = np.asarray(u, dtype=float).ravel()
        if uu.size != len(self.input_names):
            raise FcompError(f"input of {self.name} must be {len(self.input_names)} values "
                             f"({', '.join(self.input_names)}), got {u!r}")
        if not all(map(math.isfinite, uu.tolist())):  # a few values: faster than np.isfinite
            raise FcompError(f"input of {self.name} ({', '.join(self.input_names)}) at "
                             f"t = {self.t:.6g} s is not finite: {uu}")
        self.x = self._advance(uu, dt)
        self.t += dt
        return self.x.copy()
