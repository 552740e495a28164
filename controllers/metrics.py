"""Closed-loop metrics: tracking, steady state, hunting, reversals, valve activity, compute time.

All errors are computed on the *true* plant position (not the noisy,
quantised measurement the controller saw): ``e = r - x`` (m).

================================ =================================================
metric                            definition
================================ =================================================
``rms_error`` (m)                 ``sqrt(mean(e^2))`` over the whole run
``max_error`` (m)                 ``max |e|`` over the whole run
``steady_state_error`` (m)        mean of ``|mean(e)|`` over the task's settle
                                  windows (the constant part of the error where
                                  the reference holds still or moves steadily);
                                  for the periodic tasks the window is the last
                                  period and the value is the RMS error there
``hunting_amplitude`` (m)         limit-cycle amplitude: the largest half
                                  peak-to-peak of ``e`` over the settle windows
                                  (0 for a loop that settles), ``None`` for the
                                  periodic tasks
``reversal_error`` (m)            RMS of ``e`` in windows centred on the
                                  reference-velocity reversals (``None`` if the
                                  task has none)
``valve_activity`` (1/s)          total variation of the valve command per
                                  second, in units of the valve range:
                                  ``sum|du| / (u_max * duration)``
``solve_time_median``, ``_p99``,  wall-clock time of the controller's
``_max`` (s)                      ``step`` call: median, 99th percentile, maximum
``solve_time_cpu_median``,        CPU time of the controller's thread in the
``_cpu_p99``, ``_cpu_max`` (s)    ``step`` call (what the step costs on a
                                  processor of its own; ``nan`` if not measured)
``solve_time_descheduled`` (-)    steps whose wall-clock time exceeds their CPU
                                  time by more than :data:`DESCHEDULED` (the
                                  processor was given to another process)
``fallbacks`` (-)                 steps where the controller could not apply its
                                  law and used its stated fallback (MPC solve
                                  failure): counted, never hidden
``faults`` (-)                    faulty samples the fail-safe layer counted
                                  (:mod:`controllers.safety`: implausible inputs
                                  held, a controller's non-finite command)
``max_consecutive_faults`` (-)    the longest run of faulty samples
``latched_steps`` (-)             samples the safe output was latched
``latches`` (-)                   how often it latched
``last_fault`` (-)                the last fault's cause (None: none)
================================ =================================================
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from fcomp.errors import FcompError

#: Wall-clock time beyond a step's CPU time (s) that counts it as descheduled: a step that
#: waited for the processor (the scheduler's tick is 1-4 ms), not timer jitter (microseconds).
DESCHEDULED = 0.5e-3


@dataclass(frozen=True)
class Metrics:
    """The metrics of one closed-loop run (see the module docstring; SI units)."""

    rms_error: float
    max_error: float
    steady_state_error: float
    hunting_amplitude: float | None
    reversal_error: float | None
    valve_activity: float
    solve_time_median: float
    solve_time_max: float
    fallbacks: int
    steps: int
    solve_time_p99: float = math.nan
    solve_time_cpu_median: float = math.nan
    solve_time_cpu_p99: float = math.nan
    solve_time_cpu_max: float = math.nan
    solve_time_descheduled: int = 0
    faults: int = 0
    max_consecutive_faults: int = 0
    latched_steps: int = 0
    latches: int = 0
    last_fault: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _mask(t: np.ndarray, a: float, b: float) -> np.ndarray:
    return (t >= a) & (t <= b)


def compute_metrics(
    t: np.ndarray,
    r: np.ndarray,
    x: np.ndarray,
    u: np.ndarray,
    solve_times: np.ndarray,
    *,
    u_max: float,
    settle: Sequence[tuple[float, float]],
    reversals: Sequence[float] = (),
    reversal_window: float = 0.2,
    periodic: bool = False,
    fallbacks: int = 0,
    cpu_times: np.ndarray | None = None,
    faults: int = 0,
    max_consecutive_faults: int = 0,
    latched_steps: int = 0,
    latches: int = 0,
    last_fault: str | None = None,
) -> Metrics:
    """Metrics of a run sampled at ``t`` (s).

    Parameters
    ----------
    t, r, x
        Sample times (s), reference and true position (m).
    u
        Valve command applied over each sample interval.
    solve_times
        Wall-clock duration of each controller step (s).
    u_max
        Half range of the valve command (its unit), for ``valve_activity``.
    settle
        Settle windows ``(t0, t1)`` (s).
    reversals, reversal_window
        Reversal times (s) and full window width (s).
    periodic
        Whether the task is periodic (steady-state error is then an RMS, and
        there is no hunting amplitude).
    fallbacks
        Number of fallback steps the controller reported.
    cpu_times
        CPU time of the controller's thread in each step (s), if measured.
    faults, max_consecutive_faults, latched_steps, latches, last_fault
        The fail-safe layer's record of the run (:mod:`controllers.safety`).
    """
    t = np.asarray(t, dtype=float)
    e = np.asarray(r, dtype=float) - np.asarray(x, dtype=float)
    if t.size < 2 or e.shape != t.shape:
        raise FcompError("metrics need at least two samples of equal length")
    if not np.all(np.isfinite(e)):
        raise FcompError("the closed loop produced non-finite positions (unstable run)")
    if not settle:
        raise FcompError("metrics need at least one settle window inside the run")
    duration = float(t[-1] - t[0])
    sse: list[float] = []
    hunt: list[float] = []
    for a, b in settle:
        m = _mask(t, a, b)
        if not m.any():
            raise FcompError(f"settle window {a}..{b} s holds no sample")
        ew = e[m]
        sse.append(float(np.sqrt(np.mean(ew**2))) if periodic else abs(float(np.mean(ew))))
        hunt.append(0.5 * float(ew.max() - ew.min()))
    rev: float | None = None
    if reversals:
        m = np.zeros_like(t, dtype=bool)
        for tr in reversals:
            m |= _mask(t, tr - reversal_window / 2, tr + reversal_window / 2)
        rev = float(np.sqrt(np.mean(e[m] ** 2)))
    u = np.asarray(u, dtype=float)
    activity = float(np.sum(np.abs(np.diff(u))) / (u_max * duration)) if u.size > 1 else 0.0
    st = np.asarray(solve_times, dtype=float)
    ct = np.asarray(cpu_times if cpu_times is not None else [], dtype=float)
    if ct.size and ct.shape != st.shape:
        raise FcompError("metrics need one CPU time per step")
    return Metrics(
        rms_error=float(np.sqrt(np.mean(e**2))),
        max_error=float(np.max(np.abs(e))),
        steady_state_error=float(np.mean(sse)),
        hunting_amplitude=None if periodic else float(max(hunt)),
        reversal_error=rev,
        valve_activity=activity,
        solve_time_median=float(np.median(st)) if st.size else 0.0,
        solve_time_max=float(np.max(st)) if st.size else 0.0,
        fallbacks=int(fallbacks),
        steps=int(st.size),
        solve_time_p99=_quantile(st, 0.99),
        solve_time_cpu_median=_quantile(ct, 0.5),
        solve_time_cpu_p99=_quantile(ct, 0.99),
        solve_time_cpu_max=_quantile(ct, 1.0),
        solve_time_descheduled=int(np.sum(st - ct > DESCHEDULED)) if ct.size else 0,
        faults=int(faults), max_consecutive_faults=int(max_consecutive_faults),
        latched_steps=int(latched_steps), latches=int(latches), last_fault=last_fault,
    )


def _quantile(values: np.ndarray, q: float) -> float:
    return float(np.quantile(values, q)) if values.size else math.nan


__all__ = ["DESCHEDULED", "Metrics", "compute_metrics"]
