"""Position signals: resolution, noise, the derivation band and rest read off the position
(the overview: :mod:`fcomp.conditioning`)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from fcomp.reconstruction import differentiate

#: Width of the position band (in position-noise standard deviations) within which
#: the piston counts as at rest (6: one step of an encoder, ``q/sqrt(12)`` each).
REST_NOISE_BAND = 6.0
#: Half window (s) over which the position must stay within that band.
REST_HALF_WINDOW = 0.004
#: Candidate cutoffs of the derivation filter, as fractions of the sample rate.
CUTOFF_FRACTIONS = (1 / 4, 1 / 5, 1 / 6, 1 / 8, 1 / 10, 1 / 15, 1 / 20, 1 / 30, 1 / 50, 1 / 100)
#: Fewest rest samples for a bias estimate.
MIN_REST = 50


def resolution(x: np.ndarray) -> float:
    """Position resolution (m): the 1st percentile of the clearly non-zero steps of ``x``."""
    steps = np.abs(np.diff(x))
    steps = steps[steps > 1e-12 * max(float(np.max(np.abs(x))), 1e-12)] if x.size else steps
    if steps.size == 0:
        return 1e-6
    return float(np.percentile(steps, 1.0))


def position_noise(x: np.ndarray) -> float:
    """Standard deviation (m) of the position noise: quantisation or sensor noise.

    The larger of the quantisation noise ``q/sqrt(12)`` (``q`` from
    :func:`resolution`) and ``1.4826*median|d3x|/sqrt(20)``, the robust spread
    of third differences (for white noise ``var(d3x) = 20*sigma^2``; smooth
    motion contributes only ``jerk*dt^3``).
    """
    q = resolution(x)
    d3 = np.diff(x, 3)
    white = 1.4826 * float(np.median(np.abs(d3))) / math.sqrt(20.0) if d3.size else 0.0
    return max(q / math.sqrt(12.0), white)


def analog_noise(sigma_x: float, q: float) -> float:
    """The white (analog) part of a position noise ``sigma_x`` of resolution ``q`` (m).

    ``sqrt(sigma_x^2 - q^2/12)`` when it is above a fifth of ``q`` (a potentiometer,
    an LVDT, an eddy-current sensor: noise beyond the quantisation), else 0 (an
    encoder, whose position is its count).
    """
    white = math.sqrt(max(sigma_x**2 - q * q / 12.0, 0.0))
    return white if white > 0.2 * q else 0.0


def derived_velocity_noise(sigma_x: float, fc: float, fs: float) -> float:
    """Noise (m/s, std) of ``dx/dt`` from white position noise through an ideal low-pass at ``fc``.

    ``sigma_v = 2*pi*sigma_x*sqrt(2*fc^3/(3*fs))``: the position noise density
    ``2*sigma_x^2/fs`` times ``(2*pi*f)^2`` integrated over ``[0, fc]``.
    """
    return 2.0 * math.pi * sigma_x * math.sqrt(2.0 * fc**3 / (3.0 * fs))


def derived_acceleration_noise(sigma_x: float, fc: float, fs: float) -> float:
    """Noise (m/s^2, std) of the second derivative: ``(2*pi)^2*sigma_x*sqrt(2*fc^5/(5*fs))``."""
    return (2.0 * math.pi) ** 2 * sigma_x * math.sqrt(2.0 * fc**5 / (5.0 * fs))


def sample_rate(t: np.ndarray) -> float:
    """Mean sample rate (Hz)."""
    return (t.size - 1) / float(t[-1] - t[0])


def speed_scale(t: np.ndarray, x: np.ndarray) -> float:
    """95th percentile of ``|dx/dt|`` at a tenth of the sample rate (m/s)."""
    _, v0, _ = differentiate(t, x, cutoff_hz=0.1 * sample_rate(t), label="x")
    return float(np.percentile(np.abs(v0), 95.0))


def band(fs: float, speed: float, noise: Callable[[float], float]) -> float:
    """The highest of :data:`CUTOFF_FRACTIONS` of ``fs`` whose velocity ``noise(fc)`` is at most
    0.2 % of the speed scale (the lowest fraction if none)."""
    for frac in CUTOFF_FRACTIONS:
        if noise(frac * fs) <= 2e-3 * speed:
            return float(frac * fs)
    return float(CUTOFF_FRACTIONS[-1] * fs)


def default_cutoff(t: np.ndarray, x: np.ndarray) -> float:
    """Cutoff (Hz) of the zero-phase filter that derives ``v``, ``a`` from ``x``.

    :func:`band` with the velocity noise the position noise leaves
    (:func:`position_noise`, :func:`derived_velocity_noise`) and the speed scale
    of :func:`speed_scale`. A clean encoder gets ``fs/4``, so presliding
    transients of a few milliseconds keep their timing; a noisy sensor gets a
    lower cutoff.
    """
    fs = sample_rate(t)
    sx = position_noise(x)
    return band(fs, speed_scale(t, x), lambda fc: derived_velocity_noise(sx, fc, fs))


def bristle_stiffness(x: np.ndarray, v: np.ndarray, f: np.ndarray, g: float) -> float | None:
    """``sigma0`` (N/m) a record shows: from the displacement to the force zero crossing
    after its reversals, ``ln(2)*g/dx`` (the LuGre bristle's exponential approach to the new
    level ``g``, N, reaches the crossing after ``dx = ln(2)*g/sigma0``), median over reversals.

    A reversal counts when the force sat on the other side by at least ``g/2`` before it
    (a full swing). Returns ``None`` when the data hold no such reversal. The diagnosis
    reads the presliding length off it, the identification the start of ``sigma0``.
    """
    s = np.sign(v)
    rev = np.nonzero((s[1:] != 0) & (s[:-1] != 0) & (s[1:] != s[:-1]))[0] + 1
    estimates = []
    for k in map(int, rev):
        new = float(s[k])
        if new * f[k - 1] > -0.5 * g:  # the force did not sit on the other side: no full swing
            continue
        j = k
        stop = min(int(f.size), k + 10_000)
        while j < stop and s[j] == new and new * f[j] < 0.0:
            j += 1
        if j >= stop or s[j] != new:
            continue
        # interpolate the zero crossing between j-1 and j
        f0, f1 = f[j - 1], f[j]
        w = f0 / (f0 - f1) if f1 != f0 else 1.0
        xc = x[j - 1] + w * (x[j] - x[j - 1])
        dx = abs(xc - x[k - 1])
        if dx > 0:
            estimates.append(math.log(2.0) * g / dx)
    if not estimates:
        return None
    return float(np.median(estimates))


def quiet_runs(x: np.ndarray, tol: float, min_len: int, edge_tol: float
               ) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """Rest and slow creep read off a position: ``(rest mask, creep runs)``.

    Runs where ``x`` stays within a band ``tol`` (one encoder step and its
    flicker) for ``min_len`` samples or more are grown greedily from the left.
    A run whose second half sits ``edge_tol`` or more from its first half
    (means) is a slow *creep* across an encoder step, not a rest: it is
    returned as ``(start, stop)`` so its displacement is kept. A *rest* run's
    ends are trimmed to the first and last sample within ``edge_tol`` of its
    median, so a stop is placed at the last change of the position and a start
    at its first change (an encoder count), not ``tol`` later or earlier.
    """
    n = x.size
    out = np.zeros(n, dtype=bool)
    creeps: list[tuple[int, int]] = []
    i = 0
    while i < n:
        lo = hi = float(x[i])
        j = i + 1
        while j < n:
            xj = float(x[j])
            lo, hi = min(lo, xj), max(hi, xj)
            if hi - lo > tol:
                break
            j += 1
        if j - i < min_len:
            i += 1
            continue
        run = x[i:j]
        half = run.size // 2
        if abs(float(np.mean(run[half:])) - float(np.mean(run[:half]))) >= edge_tol:
            creeps.append((i, j))
            # go on from where the position first left its starting value
            moved = np.flatnonzero(np.abs(run - run[0]) > 0.0)
            i += int(moved[0]) if moved.size else j - i
            continue
        near = np.flatnonzero(np.abs(run - np.median(run)) <= edge_tol)
        if near.size:
            out[i + near[0]:i + near[-1] + 1] = True
        i = j
    return out, creeps


def position_rest(t: np.ndarray, x: np.ndarray, sigma_x: float
                  ) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """Rest and creep runs of a position (:func:`quiet_runs`).

    Band :data:`REST_NOISE_BAND` position-noise standard deviations (one
    encoder step) held for at least ``2*REST_HALF_WINDOW`` (and 3 samples);
    ends trimmed to within two standard deviations of the resting value (the
    resting count of an encoder).
    """
    fs = sample_rate(t)
    return quiet_runs(x, REST_NOISE_BAND * sigma_x,
                      max(3, int(round(2 * REST_HALF_WINDOW * fs))), 2.0 * sigma_x)

