"""Closed-loop tasks where friction matters, selected by name.

Every task is a position reference ``r(t)`` (m) with its analytic velocity
``dr/dt`` (m/s) and acceleration ``d2r/dt2`` (m/s^2), given as an *offset*
from the starting position (the harness starts the piston at rest at
``x0 = stroke/2``, mid-stroke), and the windows the metrics need
(:mod:`controllers.metrics`):

``settle``
    where a good controller should sit at a constant error: the last 40 %
    of every hold of ``steps``, the second half of the constant-velocity
    part of ``low-velocity-ramp``, the last period of the sine tasks. The
    steady-state error and the hunting amplitude are measured there.
``reversals``
    the times where ``dr/dt`` changes sign; the reversal error is measured
    in a window of ``reversal_window`` seconds around each.

==================== ==========================================================
name                 reference (SI)
==================== ==========================================================
``slow-sine``        ``A*(1 - cos(2*pi*f*t))``, ``A = 10 mm``, ``f = 0.25 Hz``
                     (peak 15.7 mm/s, inside the Stribeck region); velocity
                     reversals every 2 s
``steps``            a staircase of 2 mm steps (+2, +4, +2, 0 mm), each a
                     quintic blend of 150 ms then a 1.5 s hold: integral action
                     plus static friction gives *hunting* (a limit cycle
                     about the set point)
``low-velocity-ramp`` quintic start to 2 mm/s, then a constant 2 mm/s ramp,
                     far below the Stribeck velocity: the classical
                     *stick-slip* test
``seed002-sine``     the closed-loop version of seed 002's sinusoidal case
                     (Fig. 5: valve current 4.5 mA at 1 Hz, piston velocity
                     +-0.14 m/s): ``dr/dt = 0.14*sin(2*pi*t)`` m/s, i.e.
                     ``r = (0.14/(2*pi))*(1 - cos(2*pi*t))`` (22 mm amplitude)
==================== ==========================================================

Starting from rest (``dr/dt = 0`` at ``t = 0``) keeps every reference
consistent with a piston initially at rest. ``fast`` versions are shorter
(for CI and the study's ``--fast`` mode) and keep at least one reversal or
hold of each kind.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fcomp.errors import FcompError
from fcomp.registry import Registry

RefFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Task:
    """A closed-loop task (see the module docstring).

    Attributes
    ----------
    name, description
        Public name and one line on what it exercises.
    duration, fast_duration
        Length of the run (s), full and fast.
    reference
        ``reference(t) -> (r, dr, ddr)``: offset from the start (m), m/s, m/s^2.
    settle
        ``(t0, t1)`` windows (s) for steady-state error and hunting.
    reversals
        Times (s) where the reference velocity changes sign.
    reversal_window
        Full width (s) of the window around each reversal.
    fast_settle
        Settle windows of the fast run, where those of the full run do not fit.
    kind
        ``"periodic"`` (sines), ``"regulation"`` (set points) or ``"ramp"``.
    start
        Absolute position (m) the piston starts from, at rest, and the reference is an
        offset from; ``None``: mid-stroke (every registered task).
    """

    name: str
    description: str
    duration: float
    fast_duration: float
    reference: RefFn
    settle: tuple[tuple[float, float], ...]
    reversals: tuple[float, ...] = ()
    reversal_window: float = 0.2
    fast_settle: tuple[tuple[float, float], ...] = ()
    kind: str = "periodic"
    start: float | None = None

    def start_position(self, stroke: float) -> float:
        """Where the run starts (m): :attr:`start`, else mid-stroke of ``stroke``."""
        return 0.5 * stroke if self.start is None else self.start

    def run_duration(self, fast: bool = False) -> float:
        """Run length (s) in full or fast mode."""
        return self.fast_duration if fast else self.duration

    def windows(self, fast: bool = False) -> tuple[tuple[float, float], ...]:
        """Settle windows that lie inside the run (``fast_settle`` in fast mode, if given)."""
        T = self.run_duration(fast)
        if fast and self.fast_settle:
            return self.fast_settle
        return tuple((a, min(b, T)) for a, b in self.settle if a < T and min(b, T) - a > 0.05)

    def reversal_times(self, fast: bool = False) -> tuple[float, ...]:
        """Reversals inside the run (with their whole window)."""
        T = self.run_duration(fast)
        return tuple(t for t in self.reversals if t + self.reversal_window / 2 <= T)

    def sample(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(r, dr, ddr)`` at times ``t`` (arrays of the shape of ``t``)."""
        tt = np.asarray(t, dtype=float)
        r, dr, ddr = self.reference(tt)
        return (np.broadcast_to(r, tt.shape).astype(float),
                np.broadcast_to(dr, tt.shape).astype(float),
                np.broadcast_to(ddr, tt.shape).astype(float))


def quintic_blend(t: np.ndarray, t0: float, T: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smooth 0 -> 1 transition over ``[t0, t0 + T]`` and its first two derivatives.

    ``s = 10 q^3 - 15 q^4 + 6 q^5`` with ``q = (t - t0)/T`` clipped to [0, 1]
    (zero velocity and acceleration at both ends).
    """
    q = np.clip((t - t0) / T, 0.0, 1.0)
    inside = (t > t0) & (t < t0 + T)
    s = q**3 * (10 - 15 * q + 6 * q**2)
    ds = np.where(inside, 30 * q**2 * (1 - q) ** 2 / T, 0.0)
    dds = np.where(inside, 60 * q * (1 - q) * (1 - 2 * q) / T**2, 0.0)
    return s, ds, dds


def cosine_reference(amplitude: float, frequency: float) -> RefFn:
    """``A*(1 - cos(w t))`` from rest, with derivatives."""
    w = 2 * math.pi * frequency

    def ref(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (amplitude * (1 - np.cos(w * t)), amplitude * w * np.sin(w * t),
                amplitude * w**2 * np.cos(w * t))

    return ref


def staircase_reference(levels: tuple[float, ...], hold: float, blend: float) -> RefFn:
    """Blend from one level to the next (quintic, ``blend`` s), then hold ``hold`` s."""
    period = blend + hold

    def ref(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r = np.zeros_like(t)
        dr = np.zeros_like(t)
        ddr = np.zeros_like(t)
        prev = 0.0
        for i, level in enumerate(levels):
            s, ds, dds = quintic_blend(t, i * period, blend)
            r += (level - prev) * s
            dr += (level - prev) * ds
            ddr += (level - prev) * dds
            prev = level
        return r, dr, ddr

    return ref


def ramp_reference(velocity: float, accel_time: float) -> RefFn:
    """Quintic speed-up to ``velocity`` over ``accel_time`` s, then a constant-velocity ramp."""

    def ref(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s, ds, dds = quintic_blend(t, 0.0, accel_time)
        # integral of the quintic blend: T*(q^4*(5/2 - 3q + q^2)) on [0, T], then t - T/2
        q = np.clip(t / accel_time, 0.0, 1.0)
        integral = np.where(t < accel_time,
                            accel_time * q**4 * (2.5 - 3 * q + q**2),
                            t - 0.5 * accel_time)
        return velocity * integral, velocity * s, velocity * ds

    return ref


TASKS: Registry[Task] = Registry("task")

_HOLD, _BLEND = 1.5, 0.15
_STEPS = (0.002, 0.004, 0.002, 0.0)
_P = _HOLD + _BLEND

TASKS.register("slow-sine", Task(
    "slow-sine", "slow sine, 10 mm at 0.25 Hz: velocity reversals in the Stribeck region",
    duration=8.0, fast_duration=2.3,
    reference=cosine_reference(0.010, 0.25),
    settle=((4.0, 8.0),), reversals=(2.0, 4.0, 6.0), reversal_window=0.4,
    fast_settle=((1.3, 2.3),), kind="periodic",
))
TASKS.register("steps", Task(
    "steps", "2 mm position steps held 1.5 s: hunting (integral action + static friction)",
    duration=len(_STEPS) * _P, fast_duration=_P,
    reference=staircase_reference(_STEPS, _HOLD, _BLEND),
    settle=tuple((i * _P + _BLEND + 0.6 * _HOLD, (i + 1) * _P) for i in range(len(_STEPS))),
    kind="regulation",
))
TASKS.register("low-velocity-ramp", Task(
    "low-velocity-ramp", "constant 2 mm/s ramp, far below the Stribeck velocity: stick-slip",
    duration=5.0, fast_duration=1.5,
    reference=ramp_reference(0.002, 0.3),
    settle=((1.0, 5.0),), fast_settle=((0.8, 1.5),), kind="ramp",
))
TASKS.register("seed002-sine", Task(
    "seed002-sine", "seed 002's sinusoidal case in closed loop: +-0.14 m/s at 1 Hz",
    duration=3.0, fast_duration=1.2,
    reference=cosine_reference(0.14 / (2 * math.pi), 1.0),
    settle=((2.0, 3.0),), reversals=(0.5, 1.0, 1.5, 2.0, 2.5), reversal_window=0.1,
    fast_settle=((0.2, 1.2),), kind="periodic",
))


class SampledReference:
    """A reference given by samples ``(t, x)``: linear interpolation, as an offset from
    ``x[0]``, with its velocity and acceleration by finite differences (picklable, so a
    task built on it runs in worker processes and on a Dask cluster).

    Parameters
    ----------
    t
        Increasing sample times from 0 (s).
    x
        Absolute positions (m).
    """

    def __init__(self, t: np.ndarray, x: np.ndarray) -> None:
        self.t = np.asarray(t, dtype=float)
        self.x = np.asarray(x, dtype=float)
        self.v = np.gradient(self.x, self.t)
        self.a = np.gradient(self.v, self.t)

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (np.interp(t, self.t, self.x) - self.x[0], np.interp(t, self.t, self.v),
                np.interp(t, self.t, self.a))


#: Shortest still reference (s) that counts as a hold of a sampled reference.
MIN_HOLD = 0.2


def reference_task(t: np.ndarray, x: np.ndarray, name: str = "reference") -> Task:
    """A :class:`Task` following a user's reference ``x(t)`` (absolute positions, m).

    The run starts at rest at ``x[0]`` and lasts ``t[-1] - t[0]`` s (``fast``
    changes nothing). Settle windows: the last 40 % of every hold (the
    reference still for at least :data:`MIN_HOLD` s; the task is then a
    ``regulation`` task with a hunting amplitude), else the last quarter of the
    run (steady-state error as an RMS, as for the periodic tasks). Reversals:
    where the reference velocity changes sign (speeds below 0.1 % of the
    largest ignored).
    """
    t = np.asarray(t, dtype=float) - float(t[0])
    x = np.asarray(x, dtype=float)
    ref = SampledReference(t, x)
    speed = np.abs(ref.v)
    top = float(speed.max())
    moving = speed > 1e-3 * top if top > 0 else np.zeros(t.size, dtype=bool)
    holds: list[tuple[float, float]] = []
    i = 0
    while i < t.size:
        if moving[i]:
            i += 1
            continue
        j = i
        while j + 1 < t.size and not moving[j + 1]:
            j += 1
        if t[j] - t[i] >= MIN_HOLD:
            holds.append((float(t[i] + 0.6 * (t[j] - t[i])), float(t[j])))
        i = j + 1
    sign = np.sign(ref.v) * moving
    idx = np.flatnonzero(sign)
    reversals = tuple(float(0.5 * (t[a] + t[b])) for a, b in zip(idx[:-1], idx[1:], strict=True)
                      if sign[a] != sign[b])
    T = float(t[-1])
    settle = tuple(holds) or ((0.75 * T, T),)
    return Task(name, f"the reference of {name} ({t.size} samples over {T:g} s)",
                duration=T, fast_duration=T, reference=ref, settle=settle,
                reversals=reversals, kind="regulation" if holds else "periodic",
                start=float(x[0]))


def get_task(name: str) -> Task:
    """The task called ``name`` (:class:`~fcomp.errors.UnknownNameError` otherwise)."""
    return TASKS.get(name)


def check_fits_stroke(task: Task, x0: float, stroke: float, fast: bool = False) -> None:
    """Refuse a task whose reference leaves the stroke (with a 5 mm margin)."""
    t = np.linspace(0.0, task.run_duration(fast), 2001)
    r = x0 + task.sample(t)[0]
    if r.min() < 0.005 or r.max() > stroke - 0.005:
        raise FcompError(
            f"task {task.name}: reference spans {r.min():.4f}..{r.max():.4f} m, outside the "
            f"stroke 0..{stroke} m less 5 mm margins"
        )


__all__ = ["MIN_HOLD", "TASKS", "SampledReference", "Task", "check_fits_stroke", "get_task",
           "quintic_blend", "reference_task"]
