"""The force band: the cut-off of the parallel filtering of a reconstructed force, and the
noise at rest (the overview: :mod:`fcomp.conditioning`)."""

from __future__ import annotations

import math

import numpy as np

from fcomp.conditioning.position import CUTOFF_FRACTIONS, MIN_REST, derived_acceleration_noise
from fcomp.conditioning.velocity import long_runs

#: Largest share of the force noise the inertia noise ``m*sigma_a`` may add (force band).
INERTIA_NOISE_SHARE = 0.3


def force_cutoff(fs: float, fc_motion: float, sigma_x: float | None, mass: float,
                 force_noise: float) -> float:
    """Cut-off (Hz) of the parallel filtering of a reconstructed force.

    The highest of :data:`CUTOFF_FRACTIONS` of ``fs`` (not above ``fc_motion``)
    at which the inertia noise ``mass*sigma_a(fc)``
    (:func:`derived_acceleration_noise`) is at most :data:`INERTIA_NOISE_SHARE`
    of the force noise in that band, ``force_noise*sqrt(2*fc/fs)`` (white).
    Without a position (velocity measured), ``fc_motion``.
    """
    if sigma_x is None or mass <= 0:
        return fc_motion
    for frac in CUTOFF_FRACTIONS:
        fc = frac * fs
        if fc > fc_motion * (1 + 1e-9):
            continue
        inertia = mass * derived_acceleration_noise(sigma_x, fc, fs)
        if inertia <= INERTIA_NOISE_SHARE * force_noise * math.sqrt(2.0 * fc / fs):
            return float(fc)
    return float(min(CUTOFF_FRACTIONS[-1] * fs, fc_motion))


def rest_noise(t: np.ndarray, y: np.ndarray, rest: np.ndarray) -> float:
    """Robust noise (std) of ``y`` over rest runs of at least 20 samples (first differences).

    ``1.4826*median|dy|/sqrt(2)`` over the rest runs: white-noise exact, slow
    drifts do not count. ``nan`` without enough rest.
    """
    keep = long_runs(rest, 20)
    d = np.diff(y)[keep[1:] & keep[:-1]]
    if d.size < MIN_REST:
        return math.nan
    return 1.4826 * float(np.median(np.abs(d))) / math.sqrt(2.0)
