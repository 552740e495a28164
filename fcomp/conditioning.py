"""Signal conditioning: the velocity that drives the friction states, rest, and the force band.

A friction model is simulated along the *measured* motion, so whatever is
wrong with the motion signals goes straight into its states. Real rigs record
the motion in several ways -- an encoder position ``x`` (quantised), a
tachometer or a drive's differentiated encoder velocity ``v`` (noisy, with a
bias, a gain error and a lag), sometimes no position at all -- and the force
as a load-cell friction ``F``, or as chamber pressures from which the friction
is reconstructed, ``p1*A1 - p2*A2 + F_ext - m*a``. The same physical record
written in any of these styles must drive the model with the same motion.
This module decides, per record and visibly (:class:`Conditioning`, the
``signals`` field of ``fcomp diagnose --json``):

**Which velocity.** ``dx/dt`` is the zero-phase low-pass derivative of the
position at the cut-off :func:`default_cutoff` (set by the position noise).
A ``v`` column is first *calibrated* against it (:func:`calibrate_velocity`):
its bias is its median at rest (rest read off the position, where the true
velocity is zero), its noise the robust spread there, its lag and gain the
shift and slope that best map it onto ``dx/dt`` while moving. Then

* ``"x"`` -- ``dx/dt`` alone, when there is no ``v`` column, when the column
  disagrees with the position (gain off by more than :data:`GAIN_TOL`, or it
  explains less than :data:`MIN_R2` of ``dx/dt``'s variance while moving), or
  when it is noisier than ``dx/dt`` over the whole band used;
* ``"fused"`` -- a complementary filter: ``dx/dt`` below the cross-over
  frequency ``f* = sigma_v/(2*pi*sigma_x)`` where the two noise densities
  are equal (white position noise ``sigma_x`` differentiated rises as ``f``;
  the column's white noise ``sigma_v`` is flat), the calibrated
  column (bias removed, lag and gain corrected) above it;
* ``"v"`` -- the calibrated column, when the record has no position. Its bias
  is then its median over quiet stretches (:func:`velocity_rest`).

A measured velocity is never trusted at rest: a tachometer's noise of
1e-4 m/s drives a bristle state through every dwell (LuGre's held force creeps
by newtons), and a bias drives it to one side. **Rest** is read off the
position where there is one (it stays within six position-noise standard
deviations, one encoder step, for 8 ms or more: :func:`position_rest`), else off the
calibrated velocity (quiet for at least :data:`MIN_QUIET` s); velocity and
acceleration are held at zero there.

**The force band.** A friction reconstructed from pressures subtracts
``m*a``, and ``a`` is a second derivative of a quantised position: its noise
grows as ``fc^2.5``. Where the target is reconstructed (or the mass is fitted
to the driving force) the whole driving force and the model's prediction are
passed through the same zero-phase low-pass ("parallel filtering", Gautier &
Janot), at the highest cut-off at which the inertia noise ``m*sigma_a`` stays
below :data:`INERTIA_NOISE_SHARE` of the force noise in that band
(:func:`force_cutoff`). Target and prediction then have the same bandwidth,
so the residual is the model error in that band and the noise floor,
estimated from the same filtered force at rest, is its noise.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass

import numpy as np

from fcomp.errors import FcompError
from fcomp.reconstruction import differentiate, smooth

#: Width of the position band (in position-noise standard deviations) within which
#: the piston counts as at rest (6: one step of an encoder, ``q/sqrt(12)`` each).
REST_NOISE_BAND = 6.0
#: Half window (s) over which the position must stay within that band.
REST_HALF_WINDOW = 0.004
#: Candidate cutoffs of the derivation filter, as fractions of the sample rate.
CUTOFF_FRACTIONS = (1 / 4, 1 / 5, 1 / 6, 1 / 8, 1 / 10, 1 / 15, 1 / 20, 1 / 30, 1 / 50, 1 / 100)
#: Largest relative gain error of a ``v`` column that is still used.
GAIN_TOL = 0.25
#: Smallest share of ``dx/dt``'s variance (moving) a usable ``v`` column explains.
MIN_R2 = 0.9
#: Fewest rest samples for a bias estimate.
MIN_REST = 50
#: Shortest quiet stretch (s) read as rest from a velocity alone.
MIN_QUIET = 0.02
#: Largest share of the force noise the inertia noise ``m*sigma_a`` may add (force band).
INERTIA_NOISE_SHARE = 0.3
#: Largest lag (s) searched between a ``v`` column and ``dx/dt``.
MAX_LAG = 0.02
#: Margin (s), beyond the largest lag, left out at both ends of a rest for the bias.
REST_EDGE = 0.02
VELOCITY_SOURCES = ("x", "v", "fused")


# ------------------------------------------------------------------ position
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


# ------------------------------------------------------------------ velocity
@dataclass(frozen=True)
class Scales:
    """Magnitudes of a record, the reference of every data-derived threshold (SI).

    Attributes
    ----------
    force : N
        Typical friction magnitude: median ``|y|`` over moving samples.
    speed : m/s
        95th percentile of ``|v|``.
    accel : m/s^2
        95th percentile of ``|a|``.
    x_min, x_max : m
        1st and 99th percentiles of the position.
    resolution : m
        Position resolution: the smallest clearly non-zero step of ``x``.
    p_mid, p_span : Pa
        Mean and range (1st to 99th percentile) of ``p1 + p2``.
    dt : s
        Median sample interval.
    duration : s
        Total duration of all experiments.
    """

    force: float
    speed: float
    accel: float
    x_min: float
    x_max: float
    resolution: float
    p_mid: float
    p_span: float
    dt: float
    duration: float

    @property
    def stroke(self) -> float:
        """Position range covered (m), at least 100 resolutions."""
        return max(self.x_max - self.x_min, 100.0 * self.resolution)


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


def _robust_std(r: np.ndarray) -> float:
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
    noise = _robust_std(at_rest) if n_rest >= MIN_REST else math.nan
    pieces = []
    for t, vc, vx, rest in zip(ts, v_cols, v_xs, rests, strict=True):
        if t.size <= 2 * max_k + 20:
            continue
        vf = smooth(t, vc - bias, cutoff_hz=fc, label="v")
        scale = float(np.percentile(np.abs(vx), 95.0)) or 1.0
        moving = ~rest & (np.abs(vx) > 0.02 * scale)
        if moving.sum() > 20:  # noise above the band while moving (quantisation shows there)
            hf = (vc - bias - vf)[moving]
            white = _robust_std(hf) / math.sqrt(max(1.0 - 2.0 * fc / fs, 0.05))
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
    bias, spread = float(np.median(vf[slow])), _robust_std(vf[slow])
    rest = np.zeros(v.size, dtype=bool)
    for _ in range(2):
        quiet = np.abs(vf - bias) <= 4.0 * max(spread, 1e-12)
        rest = _long_runs(quiet, max(10, int(math.ceil(MIN_QUIET * fs))))
        if rest.sum() < MIN_REST:
            return np.zeros(v.size, dtype=bool), 0.0, _robust_std(v[slow])
        bias, spread = float(np.median(vf[rest])), _robust_std(vf[rest])
    return rest, bias, _robust_std(v[rest] - bias)


def _inner(mask: np.ndarray, margin: int) -> np.ndarray:
    """``mask`` without ``margin`` samples at both ends of each of its runs."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    out = np.zeros(mask.size, dtype=bool)
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a > 2 * margin:
            out[a + margin:b - margin] = True
    return out


def _long_runs(mask: np.ndarray, min_len: int) -> np.ndarray:
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    out = np.zeros(mask.size, dtype=bool)
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a >= min_len:
            out[a:b] = True
    return out


@dataclass(frozen=True)
class Conditioning:
    """What drives the friction states of one record, and why (the JSON ``signals``).

    Attributes
    ----------
    velocity : str
        ``"x"`` (``dx/dt``), ``"v"`` (the calibrated column) or ``"fused"``.
    reason : str
        Why, in one sentence.
    cutoff_hz : Hz
        Band of the derived velocity and acceleration.
    crossover_hz : Hz or None
        Cross-over of the fusion (``"fused"`` only).
    x_resolution, x_noise : m or None
        Position resolution and noise (None without a position).
    vx_noise : m/s or None
        Noise of ``dx/dt`` in its band.
    column : VelocityCalibration or None
        Calibration of the ``v`` column, if there is one.
    rest : str
        ``"position"``, ``"velocity"`` or ``"none"``: what rest was read off.
    rest_share : -
        Share of samples held at rest.
    force : str
        ``"F"``, ``"reconstructed"`` or ``"driving-force"`` (set by the caller).
    force_cutoff_hz : Hz or None
        Band of the parallel filtering of force and prediction (None: unfiltered).
    label : str
        The record's name (set by the caller).
    """

    velocity: str
    reason: str
    cutoff_hz: float
    crossover_hz: float | None
    x_resolution: float | None
    x_noise: float | None
    vx_noise: float | None
    column: VelocityCalibration | None
    rest: str
    rest_share: float
    force: str = ""
    force_cutoff_hz: float | None = None
    label: str = ""

    def to_dict(self) -> dict:
        """Plain JSON-ready values (nan -> None)."""
        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, float) and not math.isfinite(v):
                return None
            return v

        return clean(asdict(self))


@dataclass(frozen=True)
class Motion:
    """The conditioned motion of one piece (experiment) of a record (SI)."""

    v: np.ndarray
    a: np.ndarray
    rest: np.ndarray


def condition_motion(pieces: Sequence[tuple[np.ndarray, np.ndarray | None, np.ndarray | None]],
                     *, cutoff_hz: float | None = None
                     ) -> tuple[list[Motion], Conditioning]:
    """The conditioned motion of every piece of one record, and how it was made.

    Parameters
    ----------
    pieces
        ``(t, x, v_col)`` per experiment of one file (s, m, m/s); ``x`` or
        ``v_col`` may be None (the same for every piece). One calibration of the
        ``v`` column is pooled over the pieces.
    cutoff_hz
        Band of the derivation filter (default :func:`default_cutoff` of the
        longest piece, or a tenth of the sample rate without a position).
    """
    t0, x0, v0 = max(pieces, key=lambda p: p[0].size)
    fs = sample_rate(t0)
    if x0 is None and v0 is None:
        raise FcompError("a motion needs a position 'x' or a velocity 'v' column")
    if x0 is None:
        return _from_velocity(pieces, cutoff_hz if cutoff_hz is not None else 0.1 * fs)
    fc = cutoff_hz if cutoff_hz is not None else default_cutoff(t0, x0)
    sx = max(position_noise(x) for _, x, _ in pieces if x is not None)
    q = min(resolution(x) for _, x, _ in pieces if x is not None)
    derived = []
    for t, x, _ in pieces:
        assert x is not None
        _, v_x, a_x = differentiate(t, x, cutoff_hz=fc, label="x")
        rest, _ = position_rest(t, x, sx)
        derived.append((v_x, a_x, rest))
    vx_noise = derived_velocity_noise(sx, fc, fs)
    velocity, reason, cross, cal = "x", "no velocity column: dx/dt of the position", None, None
    if v0 is not None:
        cols = [p[2] for p in pieces if p[2] is not None]
        cal = calibrate_velocity([p[0] for p in pieces], cols,
                                 [d[0] for d in derived], [d[2] for d in derived], fc)
        velocity, reason, cross, fc = _choose(cal, sx, fc, fs, speed_scale(t0, x0),
                                              cutoff_hz is not None)
    out = []
    for (t, _, v_col), (v, a, rest) in zip(pieces, derived, strict=True):
        if velocity == "fused":
            assert cross is not None and cal is not None and v_col is not None
            vc = cal.apply(t, v_col)
            low = smooth(t, v, cutoff_hz=cross, label="dx/dt")
            high = vc - smooth(t, vc, cutoff_hz=cross, label="v")
            v = smooth(t, low + high, cutoff_hz=fc, label="v")
            a = np.gradient(v, t)
        out.append(Motion(np.where(rest, 0.0, v), np.where(rest, 0.0, a), rest))
    share = float(np.mean(np.concatenate([m.rest for m in out])))
    return out, Conditioning(velocity, reason, fc, cross, q, sx, vx_noise, cal, "position",
                             share)


def _from_velocity(pieces: Sequence[tuple[np.ndarray, np.ndarray | None, np.ndarray | None]],
                   fc: float) -> tuple[list[Motion], Conditioning]:
    """Rest, bias and noise read off the velocity alone (no position)."""
    found = []
    for t, _, v_col in pieces:
        assert v_col is not None
        found.append(velocity_rest(t, v_col, fc))
    at_rest = np.concatenate([p[2][r] for p, (r, _, _) in zip(pieces, found, strict=True)
                              if p[2] is not None])
    bias = float(np.median(at_rest)) if at_rest.size >= MIN_REST else 0.0
    noise = _robust_std(at_rest) if at_rest.size >= MIN_REST else math.nan
    cal = VelocityCalibration(bias, 1.0, 0.0, noise, math.nan, int(at_rest.size))
    out = []
    for (t, _, v_col), (rest, _, _) in zip(pieces, found, strict=True):
        assert v_col is not None
        v = smooth(t, cal.apply(t, v_col), cutoff_hz=fc, label="v")
        a = np.gradient(v, t)
        out.append(Motion(np.where(rest, 0.0, v), np.where(rest, 0.0, a), rest))
    share = float(np.mean(np.concatenate([m.rest for m in out])))
    reason = (f"no position column: the measured velocity, bias {bias:.2g} m/s removed "
              "(rest read off the velocity)" if at_rest.size >= MIN_REST else
              "no position column: the measured velocity (no rest found to estimate a bias)")
    return out, Conditioning("v", reason, fc, None, None, None, None, cal,
                             "velocity" if at_rest.size >= MIN_REST else "none", share)


def _choose(cal: VelocityCalibration, sx: float, fc_x: float, fs: float, speed: float,
            fixed: bool) -> tuple[str, str, float | None, float]:
    """``(velocity, reason, crossover, band)`` for a calibrated column (module docstring).

    The fused velocity's noise in a band ``fc`` is that of ``dx/dt`` up to the
    cross-over ``f*`` plus the column's white noise from ``f*`` to ``fc``; its
    band is chosen by the same rule as ``dx/dt``'s (:func:`band`), unless the
    user fixed it.
    """
    if not (math.isfinite(cal.r2) and cal.r2 >= MIN_R2 and abs(cal.gain - 1.0) <= GAIN_TOL):
        return ("x", f"the v column disagrees with dx/dt (gain {cal.gain:.3g}, explains "
                f"{100 * max(cal.r2, 0.0) if math.isfinite(cal.r2) else 0:.0f} % of it while "
                "moving): dx/dt of the position", None, fc_x)
    if not math.isfinite(cal.noise):
        return "x", "the v column's noise is unknown (no rest in the record): dx/dt", None, fc_x
    # densities (one-sided, white): column noise^2/(fs/2); dx/dt (2*pi*f)^2*sx^2/(fs/2)
    cross = cal.noise / (2.0 * math.pi * max(sx, 1e-300))

    def fused_noise(fc: float) -> float:
        low = derived_velocity_noise(sx, min(fc, cross), fs)
        return math.sqrt(low**2 + cal.noise**2 * max(fc - cross, 0.0) / (0.5 * fs))

    fc = fc_x if fixed else max(fc_x, band(fs, speed, fused_noise))
    if cross >= fc:
        return ("x", f"dx/dt is cleaner than the v column up to the cutoff ({fc:.3g} Hz): "
                f"column noise {cal.noise:.2g} m/s", None, fc)
    cross = max(cross, 0.01 * fc)
    return ("fused", f"dx/dt below {cross:.3g} Hz, the v column (bias {cal.bias:.2g} m/s "
            f"removed, lag {1e3 * cal.lag:.2g} ms, gain {cal.gain:.3g}) above, up to "
            f"{fc:.3g} Hz: their noise densities cross there", cross, fc)


# ------------------------------------------------------------------ ensemble
#: Alternative motions of :func:`motion_ensemble`.
ENSEMBLE = 4


def motion_ensemble(t: np.ndarray, x: np.ndarray, cond: Conditioning, k: int = ENSEMBLE,
                    seed: int = 0) -> list[Motion]:
    """``k`` motions as consistent with the measured position as the one conditioned.

    The smooth position (the zero-phase filtered ``x``) is measured again by an
    encoder whose grid is shifted by ``(j + 1/2)/k`` of a step (``j = 0..k-1``),
    plus, for a sensor noisier than its quantisation, fresh white noise of the
    position noise; each is conditioned as the record was (same band, rest
    read off it). Where the record pins the motion down -- fast sliding, long
    rests -- they agree; where it cannot -- a creep within an encoder step,
    the turning point of a slow loop, a start placed between two counts --
    they differ, by what the measurement leaves open. A model's predictions
    along them bound what it could be expected to predict
    (:func:`fcomp.diagnosis.scoring.tolerant_residual`).
    """
    if cond.x_resolution is None or cond.x_noise is None:
        return []
    rng = np.random.default_rng(seed)
    q = cond.x_resolution
    white = analog_noise(cond.x_noise, q)
    x_s = smooth(t, x, cutoff_hz=cond.cutoff_hz, label="x")
    out = []
    for j in range(k):
        phi = (j + 0.5) / k * q
        xj = np.round((x_s + phi) / q) * q - phi
        if white > 0:
            xj = x_s + rng.normal(0.0, cond.x_noise, x_s.size)
        (mo,), _ = condition_motion([(t, xj, None)], cutoff_hz=cond.cutoff_hz)
        counted = count_timing(t, xj, mo, cond.cutoff_hz) if white == 0 else None
        out.append(mo if counted is None else counted)
    (own,), _ = condition_motion([(t, x, None)], cutoff_hz=cond.cutoff_hz)
    turned = through_turns(t, x, own, REST_NOISE_BAND * cond.x_noise if white > 0 else q)
    if turned is not None:
        out.append(turned)
    if white == 0:
        counted = count_timing(t, x, own, cond.cutoff_hz)
        if counted is not None:
            out.append(counted)
    return out


def count_timing(t: np.ndarray, x: np.ndarray, mo: Motion, fc: float) -> Motion | None:
    """The motion ``mo`` with its slow creeps read off the times the count changes.

    Between two changes of an encoder's count in the same direction, ``t_i`` and
    ``t_j``, a piston slower than one count per ``1/fc`` moved ``x_j - x_i`` in
    ``t_j - t_i`` (the "1/T" velocity of encoder practice). The derivative of
    the staircase through the zero-phase filter (:func:`condition_motion`)
    instead rings between the counts and changes sign (a 0.1 mm/s creep at a
    2 um count read -0.03 mm/s between counts), and a law that jumps with the
    sign of the speed jumps with it. In the motion returned, such stretches
    (not held at rest) move at the count-timing velocity, constant between
    counts; elsewhere ``mo`` is kept. One more of the motions consistent with
    the position (:func:`motion_ensemble`); None if there is no such stretch.
    """
    changes = np.flatnonzero(np.diff(x) != 0.0) + 1
    if changes.size < 2:
        return None
    step = np.sign(x[changes] - x[changes - 1])
    i, j = changes[:-1], changes[1:]
    gap = t[j] - t[i]
    speed = np.abs(x[j] - x[i]) / gap
    q = float(np.min(np.abs(x[changes] - x[changes - 1])))
    slow = (step[:-1] == step[1:]) & (speed < q * fc) & (j - i > 1)
    if not slow.any():
        return None
    v, a = mo.v.copy(), mo.a.copy()
    found = False
    for a_k, b_k, s_k, u_k in zip(i[slow], j[slow], step[1:][slow], speed[slow], strict=True):
        if mo.rest[a_k:b_k].any():  # a stop between the counts: not a creep
            continue
        v[a_k:b_k] = s_k * u_k
        found = True
    if not found:
        return None
    changed = v != mo.v
    a[changed] = np.gradient(v, t)[changed]
    return Motion(v, a, mo.rest & ~changed)


#: A held stretch between opposite directions is a turn the position cannot tell from a
#: stop while the speeds around it, held over its length, stay within this many bands.
TURN_BANDS = 2.0


def through_turns(t: np.ndarray, x: np.ndarray, mo: Motion, band: float) -> Motion | None:
    """The motion ``mo`` with its unresolved turns passed through, not held; None if it has none.

    A slow reversal keeps the position within one encoder step ``band`` for
    ``T = 2*sqrt(2*band/a)`` at a deceleration ``a``, so it is read as a rest
    (:func:`position_rest`) although the piston never stopped. A held stretch of
    length ``T`` between motion in opposite directions is such a turn when the
    mean speeds over ``T`` before and after it, ``v_in`` and ``v_out``, are what
    a turn at constant deceleration gives (``v*T = 8*band``), within a factor
    :data:`TURN_BANDS`: ``v*T <= 8*TURN_BANDS*band``. A piston that arrives fast
    and stays has stopped. In the motion returned, the velocity of a turn
    goes linearly from the speed before it to the speed after it (through
    zero, at the deceleration between them): a model with a state that ages at
    rest (contact age) sees no rest there, and the prediction's range over the
    motions (:func:`motion_ensemble`) holds both readings.
    """
    held = mo.rest
    if not held.any():
        return None
    edges = np.flatnonzero(np.diff(np.concatenate([[0], held.astype(int), [0]])))
    v, a = mo.v.copy(), mo.a.copy()
    n, found = v.size, False
    for i, j in zip(edges[::2], edges[1::2], strict=True):
        lo, hi = i - 1 - (j - i), j + (j - i)  # as long as the hold, before and after it
        if lo < 0 or hi >= n or v[i - 1] * v[j] >= 0.0:
            continue
        before = abs(float(x[i - 1] - x[lo])) / float(t[i - 1] - t[lo])
        after = abs(float(x[hi] - x[j])) / float(t[hi] - t[j])
        if max(before, after) * float(t[j] - t[i - 1]) > 8.0 * TURN_BANDS * band:
            continue
        w = (t[i:j] - t[i - 1]) / (t[j] - t[i - 1])
        v[i:j] = v[i - 1] + w * (v[j] - v[i - 1])
        a[i:j] = (v[j] - v[i - 1]) / (t[j] - t[i - 1])
        found = True
    if not found:
        return None
    return Motion(v, a, held & (v == 0.0))


# ------------------------------------------------------------------ force band
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
    keep = _long_runs(rest, 20)
    d = np.diff(y)[keep[1:] & keep[:-1]]
    if d.size < MIN_REST:
        return math.nan
    return 1.4826 * float(np.median(np.abs(d))) / math.sqrt(2.0)
