"""The time scale of a record's events and the band that keeps them (the overview:
:mod:`fcomp.conditioning`).

The derivation band of :func:`~fcomp.conditioning.position.default_cutoff` is set
by the position noise alone: the highest cut-off whose velocity noise stays below
0.2 % of the speed scale. On a slow record from a noisy sensor (a laser
triangulation at 100 Hz, 14 um of noise, 5-14 mm/s) that is 1-2 Hz, and the
friction's transition after a reversal -- 0.07-0.14 s in the raw force of the
TU Delft seals -- comes out two to four times wider in every filtered signal:
the velocity that drives the model's states, the force it is scored against
(the parallel filtering of a driving force follows the motion's band), and
every verdict and noise floor judged in that band.

So the band is also matched to the events: the 10-90 % transition time of the
force at the record's reversals is read off the *raw* force
(:func:`event_time_scale`; the faster quartile of the reversals, the events the
band must keep), and the cut-off is raised to at least its inverse, which
widens such a transition by about 10 % (a second-order zero-phase Butterworth;
measured: 0.75/T widens a ramp of 10-90 % time T by 15 %, 1/T by 5-10 %), as
long as the velocity noise at that cut-off stays below
:data:`EVENT_NOISE_SHARE` of the speed scale (:func:`event_band`). A clean
encoder at a high rate already has a band far above its events and is
unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from fcomp.conditioning.position import CUTOFF_FRACTIONS

#: Largest velocity noise (share of the speed scale) the events' band may cost.
EVENT_NOISE_SHARE = 0.03
#: A run counts as moving above this share of the speed scale (95th percentile of ``|v|``).
RUN_SHARE = 0.3
#: Fewest samples on each side of a reversal to read its levels off.
MIN_RUN = 20
#: A reversal's force swing must be this many times the force's sample-to-sample noise.
MIN_SWING = 10.0
#: Quantile of the transition times taken as the record's event time scale (the faster
#: events are the ones a band must keep).
EVENT_QUANTILE = 25.0
#: Fewest transitions to trust the time scale.
MIN_EVENTS = 3


def transition_times(t: np.ndarray, v: np.ndarray, force: np.ndarray) -> list[float]:
    """10-90 % transition times (s) of ``force`` at the reversals of the velocity ``v``.

    A reversal is a change of direction between two runs faster than
    :data:`RUN_SHARE` of the speed scale. Its levels are the medians of the raw
    force over 10-30 % of each run away from the reversal; the transition starts
    where the force first passes 10 % of the swing between them (searched from a
    tenth of the run before the reversal) and ends where it first passes 90 %
    after that. Swings within :data:`MIN_SWING` noise levels (robust spread of the
    first differences) are left out.
    """
    top = float(np.percentile(np.abs(v), 95.0)) if v.size else 0.0
    if not top > 0:
        return []
    s = np.where(v > RUN_SHARE * top, 1, np.where(v < -RUN_SHARE * top, -1, 0))
    k = np.flatnonzero(s != 0)
    if k.size < 2 * MIN_RUN:
        return []
    change = np.flatnonzero(np.diff(s[k]) != 0)
    firsts = np.concatenate([[k[0]], k[change + 1]])  # first fast sample of each run
    lasts = np.concatenate([k[change], [k[-1]]])  # last fast sample of each run
    noise = 1.4826 * float(np.median(np.abs(np.diff(force)))) / math.sqrt(2.0)
    out = []
    for r in range(firsts.size - 1):
        end, start = int(lasts[r]), int(firsts[r + 1])
        before, after = end - int(firsts[r]), int(lasts[r + 1]) - start
        if before < MIN_RUN or after < MIN_RUN:
            continue
        lo = float(np.median(force[end - int(0.3 * before):end - int(0.1 * before)]))
        hi = float(np.median(force[start + int(0.1 * after):start + int(0.3 * after)]))
        swing = hi - lo
        if not abs(swing) > MIN_SWING * noise:
            continue
        a, b = end - int(0.1 * before), start + int(0.1 * after)
        f = (force[a:b] - lo) / swing
        i10 = int(np.argmax(f > 0.1))
        i90 = i10 + int(np.argmax(f[i10:] > 0.9))
        if f[i10] > 0.1 and f[i90] > 0.9:
            out.append(float(t[a + i90] - t[a + i10]))
    return out


def event_time_scale(pieces: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]]
                     ) -> float | None:
    """The time scale (s) of a record's events: the lower quartile of the force's
    transition times at its reversals (:func:`transition_times`), pooled over the pieces
    ``(t, v, force)``; None with fewer than :data:`MIN_EVENTS` transitions."""
    times = [w for t, v, f in pieces for w in transition_times(t, v, f) if w > 0]
    if len(times) < MIN_EVENTS:
        return None
    return float(np.percentile(times, EVENT_QUANTILE))


def event_band(fs: float, fc: float, t_event: float | None, speed: float,
               noise: Callable[[float], float]) -> float:
    """The cut-off (Hz) that keeps events of time scale ``t_event``: ``fc`` raised to the
    lowest of :data:`~fcomp.conditioning.position.CUTOFF_FRACTIONS` of ``fs`` at or above
    ``1/t_event``, or to the highest whose velocity ``noise(fc)`` stays within
    :data:`EVENT_NOISE_SHARE` of ``speed`` if that is lower; never below ``fc``."""
    if t_event is None or not t_event > 0:
        return fc
    want = 1.0 / t_event
    if fc >= want:  # the band keeps the events already
        return fc
    fine = [f * fs for f in sorted(CUTOFF_FRACTIONS) if f * fs > fc * (1 + 1e-9)
            and noise(f * fs) <= EVENT_NOISE_SHARE * speed]
    if not fine:
        return fc
    above = [f for f in fine if f >= want * (1 - 1e-9)]
    return float(above[0] if above else fine[-1])


__all__ = ["EVENT_NOISE_SHARE", "EVENT_QUANTILE", "event_band", "event_time_scale",
           "transition_times"]
