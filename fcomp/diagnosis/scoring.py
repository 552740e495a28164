"""How well a prediction meets the measurement when the motion it runs along is uncertain.

The diagnosis scores every model on the record's held-out samples. A model
runs along a motion reconstructed from sampled, quantised positions, so what
it predicts at a sample is known only within a band (:func:`prediction_band`:
its range along motions as consistent with the position, widened by the time
the piston takes to move one position resolution, :func:`timing_windows`).
Three measures follow from the band:

* the *scored* residual (:func:`scored_residual`), the logarithmic score of
  the band with the noise floor in newtons: what decides;
* the *tolerant* residual (:func:`tolerant_residual`), the distance of the
  measurement from the band: where structure is left;
* the sample weights of the fits (:func:`sample_weights`), which distrust the
  samples where the band is wide;

and :func:`score_noise_share`, what even the right model scores where its
prediction is known only within its timing band.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

import numpy as np
from scipy.integrate import trapezoid
from scipy.special import log_ndtr


def sample_weights(spread: np.ndarray, noise: float) -> np.ndarray:
    """``w = 1/(1 + (spread/(2*noise))^2)``: how much a sample can tell, given the width
    ``spread`` (N) of the band the model's prediction could take there and the noise floor
    (:meth:`~fcomp.diagnosis.refit.Refit.set_weights`)."""
    ratio = np.minimum(np.asarray(spread) / (2.0 * max(noise, 1e-300)), 1e100)
    return 1.0 / (1.0 + ratio**2)


#: Largest timing tolerance (s) of :func:`tolerant_residual`.
MAX_TIMING = 0.02


def timing_windows(v: np.ndarray, dt: float, resolution: float) -> np.ndarray:
    """Timing uncertainty of every sample, in samples: ``w_k = ceil(q/(|v_k|*dt))``, 1 to 20 ms.

    The time the piston needs to move one position resolution ``q`` at its
    speed there: an event placed by the position -- a start, a stop, a
    reversal -- is known only to within that time. At speed it is one sample;
    near a turning point of a slow motion, or at rest, it reaches
    :data:`MAX_TIMING`.
    """
    w_max = max(1, int(round(MAX_TIMING / dt)))
    speed = np.abs(v)
    with np.errstate(divide="ignore"):
        w = np.where(speed > 0, np.ceil(resolution / (np.maximum(speed, 1e-300) * dt)), w_max)
    return np.clip(w, 1, w_max).astype(int)


def prediction_band(lo: np.ndarray, hi: np.ndarray, starts: Sequence[int],
                    windows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The band ``[low, high]`` (N) the model could be expected to predict at each sample.

    The model runs along a motion reconstructed from sampled, quantised
    positions, so what it predicts at a sample is known only within

    * the range ``[lo, hi]`` of its predictions along motions as consistent
      with the measured position as the one used
      (:func:`fcomp.conditioning.motion_ensemble`: a creep within an encoder
      step, the turning point of a slow loop), and
    * the time the piston takes to move one position resolution
      (:func:`timing_windows`, ``w_k`` samples): an event -- a start, a stop, a
      velocity reversal where a friction law jumps by its whole level -- is
      placed only to within that time,

    so the range is widened to the lowest and highest value within ``w_k``
    samples (in the experiment; ``starts`` are its first samples).
    """
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    n = lo.size
    w = np.ones(n, dtype=int) if windows is None else windows
    bounds = [*sorted(set(starts) | {0}), n]
    low = lo.copy()
    high = hi.copy()
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        ws = w[a:b]
        for k in np.unique(ws):
            sel = ws == k
            size = 2 * int(k) + 1
            low[a:b][sel] = minimum_filter1d(lo[a:b], size, mode="nearest")[sel]
            high[a:b][sel] = maximum_filter1d(hi[a:b], size, mode="nearest")[sel]
    return low, high


def tolerant_residual(y: np.ndarray, lo: np.ndarray, hi: np.ndarray, starts: Sequence[int],
                      windows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The distance of ``y`` from the band the model could be expected to predict (N).

    ``y`` minus its projection onto :func:`prediction_band`. Where the motion is
    well measured and the prediction smooth the band is narrower than the noise
    and this is the plain residual. It locates structure a model could place
    (the verdict's features) but it is *not* an error measure to rank models
    by: a wider band lowers it (a mass relabelled as a lead term, whose band
    along the motion ensemble is 27 N wide, scored 0.33 N against a plain
    4.1 N). :func:`scored_residual` is. Returns the residual and the band's width (N).
    """
    low, high = prediction_band(lo, hi, starts, windows)
    return y - np.clip(y, low, high), high - low


#: Log of the peak density of a unit normal, ``ln(1/sqrt(2*pi))``.
_LOG_PEAK = -0.5 * math.log(2.0 * math.pi)


def scored_residual(y: np.ndarray, F_hat: np.ndarray, low: np.ndarray, high: np.ndarray,
                    sigma: float) -> np.ndarray:
    """The logarithmic score of the prediction band, as a residual in newtons.

    The model predicts "somewhere in ``[low, high]``" (:func:`prediction_band`)
    and the measurement adds noise of standard deviation ``sigma`` (the noise
    floor), so its predictive density of ``y`` is the uniform band convolved
    with that noise,

    ``p(y) = [Phi((high - y)/sigma) - Phi((low - y)/sigma)] / (high - low)``

    (the normal density ``phi((y - F_hat)/sigma)/sigma`` for a point band). The
    logarithmic score ``-ln p(y)`` is a *strictly proper* scoring rule
    (Gneiting & Raftery 2007, J. Am. Stat. Assoc. 102:359, sect. 4.1): a
    forecaster cannot improve its expected score by widening or shifting its
    band away from what it believes. Expressed against the best possible score,
    that of a point prediction hitting ``y`` (``p = 1/(sigma*sqrt(2*pi))``),

    ``e^2 = -2*sigma^2*ln(p(y)*sigma*sqrt(2*pi))  >= 0``,

    ``e = sign(y - F_hat)*sqrt(e^2)`` is the plain residual ``y - F_hat`` where
    the band is a point, and a band of width ``W`` around the measurement costs
    ``e^2 ~ 2*sigma^2*ln(W/(sigma*sqrt(2*pi)))``: a static law's 40 N jump placed
    within its timing window costs about three noise floors instead of 40 N,
    while a 27 N band where a point prediction would do costs what it is. The
    RMS of ``e`` is the diagnosis's deciding error; its mean square is twice
    ``sigma^2`` times the mean log-score excess, so comparing two models' RMS
    compares their mean log scores.
    """
    y = np.asarray(y, dtype=float)
    s = max(float(sigma), 1e-300)
    width = high - low
    a = (high - y) / s
    b = (low - y) / s  # a >= b
    # Phi(a) - Phi(b) in the tail where it is accurate: Phi(-b) - Phi(-a) above the centre
    flip = a + b > 0
    upper, lower = np.where(flip, -b, a), np.where(flip, -a, b)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lu, ll = log_ndtr(upper), log_ndtr(lower)
        log_mass = lu + np.log1p(-np.exp(np.minimum(ll - lu, 0.0)))
        e2 = -2.0 * (log_mass - np.log(width / s) - _LOG_PEAK)
    narrow = ~(width > 1e-6 * s) | ~np.isfinite(e2)
    if narrow.any():  # a point band (or a mass lost to rounding): the normal density
        centre = 0.5 * (low + high)
        e2 = np.where(narrow, ((y - np.where(width > 1e-6 * s, np.clip(y, low, high), centre))
                               / s) ** 2, e2)
    sign = np.where(y >= F_hat, 1.0, -1.0)
    return sign * s * np.sqrt(np.maximum(e2, 0.0))


@lru_cache(maxsize=1)
def _score_share_table() -> tuple[np.ndarray, np.ndarray]:
    """``(k, g(k))`` on a log grid: :func:`score_noise_share` of one band, by quadrature."""
    ks = np.concatenate([[0.0], np.geomspace(1e-2, 1e5, 141)])
    gs = np.ones(ks.size)
    for i, k in enumerate(ks[1:], start=1):
        y = np.linspace(-0.5 * k - 12.0, 0.5 * k + 12.0, 20_001)
        lo, hi = np.full(y.size, -0.5 * k), np.full(y.size, 0.5 * k)
        e2 = scored_residual(y, np.zeros(y.size), lo, hi, 1.0) ** 2
        dens = np.exp(-0.5 * e2) / math.sqrt(2.0 * math.pi)  # p(y) itself, from e^2
        gs[i] = float(trapezoid(dens * e2, y) / trapezoid(dens, y))
    return ks, gs


def score_noise_share(width: np.ndarray, sigma: float) -> float:
    """Mean ``E[e^2]/sigma^2`` of the scored residual of a *right* model over bands ``width``.

    Where a model's prediction is known only within a band of width
    ``W = k*sigma`` (an event placed within its timing window), even the right
    model scores more than the noise: for the truth anywhere in the band
    (uniform) and normal noise, ``g(k) = E[e^2]/sigma^2`` is twice the
    differential entropy of the predictive density in units of ``sigma``, less
    ``ln(2*pi)`` (1 at ``k = 0``, ``2*ln(k) - ln(2*pi)`` for a wide band), computed
    once by quadrature on a grid of ``k`` and interpolated in ``ln k``. The verdict
    compares a final error with ``sigma*sqrt`` of this share over the *timing*
    band alone (:attr:`~fcomp.diagnosis.refit.FitResult.timing_spread`), never over the band of the
    motions a model chose to depend on, so a wide band is never excused.
    """
    if width.size == 0 or not sigma > 0:
        return 1.0
    ks, gs = _score_share_table()
    k = np.clip(np.asarray(width, dtype=float) / sigma, 0.0, ks[-1])
    small = k < ks[1]
    g = np.interp(np.log(np.maximum(k, ks[1])), np.log(ks[1:]), gs[1:])
    g = np.where(small, 1.0 + (gs[1] - 1.0) * (k / ks[1]) ** 2, g)
    return float(np.mean(g))
