"""A measured velocity column: its calibration against ``dx/dt`` and rest read off a velocity
(the overview: :mod:`fcomp.conditioning`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fcomp.conditioning.position import MIN_REST, sample_rate
from fcomp.reconstruction import smooth

#: Largest relative gain error of a ``v`` column that is still used.
GAIN_TOL = 0.25
#: Smallest share of ``dx/dt``'s variance (moving) a usable ``v`` column explains.
MIN_R2 = 0.9
#: Shortest quiet stretch (s) read as rest from a velocity alone.
MIN_QUIET = 0.02
#: Largest lag (s) searched between a ``v`` column and ``dx/dt``.
MAX_LAG = 0.02
#: Margin (s), beyond the largest lag, left out at both ends of a rest for the bias.
REST_EDGE = 0.02
VELOCITY_SOURCES = ("x", "v", "fused")


@dataclass(frozen=True)
class VelocityCalibration:
    """How a measured ``v`` column relates to the true velocity (SI).

    The column is modelled as ``v_col(t) = gain*v(t - lag) + bias + noise``.

    Attributes
    ----------
    bias : m/s
        Its median at rest.
    gain : -
        Slope of the lag-corrected column against ``dx/dt`` while moving (1 without a position).
    lag : s
        Delay of the column behind ``dx/dt`` (0 without a position).
    noise : m/s
        Robust standard deviation at rest, over the full band.
    r2 : -
        Share of ``dx/dt``'s variance (moving) the calibrated column explains (nan
        without a position).
    n_rest : int
        Rest samples the bias and noise rest on.
    """

    bias: float
    gain: float
    lag: float
    noise: float
    r2: float
    n_rest: int

    def apply(self, t: np.ndarray, v_col: np.ndarray) -> np.ndarray:
        """The calibrated column: bias removed, lag and gain undone."""
        v = (v_col - self.bias) / self.gain
        if self.lag != 0.0:
            v = np.interp(t + self.lag, t, v)  # v_col(t + lag) ~ gain*v(t)
        return v


def robust_std(r: np.ndarray) -> float:
    """Robust standard deviation: 1.4826 times the median absolute deviation (nan if empty)."""
    return 1.4826 * float(np.median(np.abs(r - np.median(r)))) if r.size else math.nan


def calibrate_velocity(ts: Sequence[np.ndarray], v_cols: Sequence[np.ndarray],
                       v_xs: Sequence[np.ndarray], rests: Sequence[np.ndarray],
                       fc: float) -> VelocityCalibration:
    """Bias, noise, lag and gain of a ``v`` column against ``dx/dt`` (see :class:`VelocityCalibration`).

    Pooled over the pieces (experiments) of one file: ``ts``, ``v_cols``,
    ``v_xs`` (the derived velocity, band ``fc``) and ``rests`` (rest read off the
    position) per piece. The bias and noise are the median and robust spread
    over the inner part of each rest (``MAX_LAG + REST_EDGE`` from its ends:
    a lagging column still moves after a stop, and the piston creeps within
    an encoder step before a start); the noise is at least the white-noise
    equivalent of the column's content above the band while moving (a
    differentiated encoder is exact at rest and noisy in motion). The column
    is then passed through the same low-pass as ``dx/dt`` and the lag and
    gain are fitted by least squares over the moving samples (integer lags up
    to :data:`MAX_LAG`, refined by a parabola).
    """
    fs = sample_rate(ts[0])
    max_k = max(2, int(round(MAX_LAG * fs)))
    # the inner part of each rest: a lagging column still moves after a stop and the
    # piston creeps within an encoder step before a start
    inner = [_inner(r, max_k + int(math.ceil(REST_EDGE * fs))) for r in rests]
    at_rest = np.concatenate([v[r] for v, r in zip(v_cols, inner, strict=True)])
    n_rest = int(at_rest.size)
    bias = float(np.median(at_rest)) if n_rest >= MIN_REST else 0.0
    noise = robust_std(at_rest) if n_rest >= MIN_REST else math.nan
    pieces = []
    for t, vc, vx, rest in zip(ts, v_cols, v_xs, rests, strict=True):
        if t.size <= 2 * max_k + 20:
            continue
        vf = smooth(t, vc - bias, cutoff_hz=fc, label="v")
        scale = float(np.percentile(np.abs(vx), 95.0)) or 1.0
        moving = ~rest & (np.abs(vx) > 0.02 * scale)
        if moving.sum() > 20:  # noise above the band while moving (quantisation shows there)
            hf = (vc - bias - vf)[moving]
            white = robust_std(hf) / math.sqrt(max(1.0 - 2.0 * fc / fs, 0.05))
            noise = white if not math.isfinite(noise) else max(noise, white)
        idx = np.flatnonzero(moving)
        idx = idx[(idx >= max_k) & (idx < t.size - max_k)]
        if idx.size:
            pieces.append((t, vf, vx, idx))
    if sum(p[3].size for p in pieces) < 20:
        return VelocityCalibration(bias, 1.0, 0.0, noise, math.nan, n_rest)

    def fit(shift: float) -> tuple[float, float, float]:
        """(cost, gain, r2) of the column advanced by ``shift`` samples."""
        num = den = 0.0
        cols = []
        for t, vf, vx, idx in pieces:
            vc = np.interp(t[idx] + shift / fs, t, vf)
            num += float(vc @ vx[idx])
            den += float(vx[idx] @ vx[idx])
            cols.append((vc, vx[idx]))
        g = num / den if den > 0 else 1.0
        cost = sum(float(np.sum((vc - g * vx) ** 2)) for vc, vx in cols)
        vx_all = np.concatenate([vx for _, vx in cols])
        sst = max(float(np.sum((vx_all - vx_all.mean()) ** 2)), 1e-300)
        return cost, g, 1.0 - cost / (g * g * sst) if g else -math.inf

    c = np.array([fit(float(k))[0] for k in range(-max_k, max_k + 1)])
    j = int(np.argmin(c))
    shift = float(j - max_k)
    if 0 < j < c.size - 1:
        den = c[j - 1] - 2 * c[j] + c[j + 1]
        if den > 0:
            shift += 0.5 * (c[j - 1] - c[j + 1]) / den
    _, gain, r2 = fit(shift)
    if not gain > 0:
        gain, r2 = 1.0, -math.inf
    return VelocityCalibration(bias, gain, float(shift / fs), noise, float(r2), n_rest)


def velocity_rest(t: np.ndarray, v: np.ndarray, fc: float) -> tuple[np.ndarray, float, float]:
    """Rest read off a velocity alone: ``(rest mask, bias, noise)`` (m/s).

    Quiet samples are those of the low-passed velocity within four robust
    standard deviations of its value at rest; the rest value and spread are
    estimated from the slowest tenth of the samples and refined once on the
    quiet ones. Rest is a quiet stretch of at least :data:`MIN_QUIET` s (and
    10 samples); without any, the bias is taken as zero.
    """
    fs = sample_rate(t)
    vf = smooth(t, v, cutoff_hz=min(fc, 0.45 * fs), label="v")
    slow = np.abs(vf) <= np.percentile(np.abs(vf), 10.0)
    bias, spread = float(np.median(vf[slow])), robust_std(vf[slow])
    rest = np.zeros(v.size, dtype=bool)
    for _ in range(2):
        quiet = np.abs(vf - bias) <= 4.0 * max(spread, 1e-12)
        rest = long_runs(quiet, max(10, int(math.ceil(MIN_QUIET * fs))))
        if rest.sum() < MIN_REST:
            return np.zeros(v.size, dtype=bool), 0.0, robust_std(v[slow])
        bias, spread = float(np.median(vf[rest])), robust_std(vf[rest])
    return rest, bias, robust_std(v[rest] - bias)


def _inner(mask: np.ndarray, margin: int) -> np.ndarray:
    """``mask`` without ``margin`` samples at both ends of each of its runs."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    out = np.zeros(mask.size, dtype=bool)
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a > 2 * margin:
            out[a + margin:b - margin] = True
    return out


def long_runs(mask: np.ndarray, min_len: int) -> np.ndarray:
    """``mask`` kept only in its runs of ``min_len`` samples or more."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    out = np.zeros(mask.size, dtype=bool)
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a >= min_len:
            out[a:b] = True
    return out

