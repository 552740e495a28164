"""The nonlinear loop's own gain margin: scale the command until a small disturbance grows.

The linear analysis predicts the gain margin broken at the valve command. The
nonlinear sampled loop -- the plant integrated between samples by the
simulation engine (:meth:`plants.base.OdePlant.stepper`, adaptive RODAS4), the
controller's Python ``step``, the computation delay -- is run at rest holding
its load at a position, with the command's deviation from the holding command
scaled by a factor ``k`` (``u = u_0 + k*(u_c - u_0)``, ``u_c`` the controller's
command: the loop gain at the valve times ``k``), after a small position step of
the reference (``kick``, inside the linear range). :func:`growth` is the growth
rate of the ringing that follows (:func:`ringing_rate`: the RMS of the error, its
slow part removed, late against early); :func:`critical_gain` bisects on ``k`` for
the factor where
it turns from decaying to growing -- the nonlinear loop's gain margin, to hold
against the prediction (``benchmarks/bench_gain_margin.py``).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from controllers.base import Reference


@dataclass(frozen=True)
class Ringing:
    """One run of :func:`growth`: the factor, the growth rate (1/s) and the error (m)."""

    gain: float
    rate: float
    error: np.ndarray


def growth(plant: Any, ctrl: Any, position: float, gain: float, *, delay: int = 1,
           duration: float = 1.2, kick: float = 1e-8, rtol: float = 1e-10) -> Ringing:
    """The growth rate (1/s) of the ringing of the nonlinear loop with its valve command's
    deviation scaled by ``gain`` (module docstring).

    Parameters
    ----------
    plant : plants.base.OdePlant
        The simulated plant (its own friction).
    ctrl : controllers.base.Controller
        A built controller of the PID family or any other (reset here).
    position : float
        Where the piston rests (m).
    gain : float
        The factor on the command's deviation.
    delay : int
        Computation delay (samples).
    duration : float
        Simulated time (s).
    kick : float
        Size of the reference step (m) that starts the ringing.
    """
    from plants.equilibrium import equilibrium

    dt = ctrl.dt
    x0, u0 = equilibrium(plant, position)
    stepper = plant.stepper(dt, x0=x0, rtol=rtol, atol=rtol)
    names = plant.state_names
    meas = [names.index(k) for k in ("x", "p1", "p2")]
    state = stepper.reset()
    ref0 = Reference(position, 0.0, 0.0)
    ctrl.reset(0.0, state[meas], ref0)
    n = int(round(duration / dt))
    pending = deque([u0] * delay)
    err = np.empty(n)
    ref = Reference(position + kick, 0.0, 0.0)
    for k in range(n):
        y = state[meas]
        err[k] = y[0] - ref.r
        u = ctrl.step(k * dt, y, ref)
        if not math.isfinite(u):
            err[k:] = math.inf
            break
        pending.append(u0 + gain * (u - u0))
        state = stepper.step(pending.popleft())
        if not np.all(np.isfinite(state)):
            err[k + 1:] = math.inf
            break
    rate = ringing_rate(err, dt)
    if np.isfinite(err).all() and np.sqrt(np.mean(err[-err.size // 6:] ** 2)) > 10 * kick:
        rate = math.inf  # grown far beyond the kick: a limit cycle the valve's range bounds
    return Ringing(gain, rate, err)


def ringing_rate(err: np.ndarray, dt: float) -> float:
    """Growth rate (1/s) of a signal's ringing: the RMS of its fast part (each window's
    quadratic trend removed) in the last sixth against the second sixth (after the kick's
    own first response). A ringing that saturates (a limit cycle: the valve's range, the
    lap of its edges) still counts as grown."""
    n = err.size
    if not np.all(np.isfinite(err)):
        return math.inf
    a, b, c = n // 6, 2 * n // 6, 5 * n // 6

    def fast_rms(seg: np.ndarray) -> float:
        t = np.arange(seg.size)
        coef = np.polyfit(t, seg, 2)
        return float(np.sqrt(np.mean((seg - np.polyval(coef, t)) ** 2)))

    r1, r2 = fast_rms(err[a:b]), fast_rms(err[c:])
    if r1 <= 0 or r2 <= 0:
        return -math.inf
    return math.log(r2 / r1) / ((c - a) * dt)


def critical_gain(plant: Any, make: Any, position: float, low: float, high: float, *,
                  delay: int = 1, steps: int = 8, duration: float = 1.2,
                  kick: float = 1e-8) -> tuple[float, list]:
    """The factor on the valve command at which the ringing turns from decaying to growing,
    bisected between ``low`` (decays) and ``high`` (grows) in ``steps`` halvings (of the
    logarithm); ``make()`` builds a fresh controller. Returns the factor and the runs."""
    runs = []
    for _ in range(steps):
        mid = math.sqrt(low * high)
        r = growth(plant, make(), position, mid, delay=delay, duration=duration, kick=kick)
        runs.append(r)
        if r.rate > 0:
            high = mid
        else:
            low = mid
    return math.sqrt(low * high), runs


__all__ = ["Ringing", "critical_gain", "growth", "ringing_rate"]
