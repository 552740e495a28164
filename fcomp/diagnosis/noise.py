"""The noise floor, estimated from the data, and the effective sample size of residuals.

The noise floor is the RMS force error a *perfect* model would still leave:
the sensor noise. It is estimated from stretches where the friction force is
known to be smooth, so that what varies there is noise:

1. ``rest`` -- runs at rest (``|v| <= v_rest``) of at least 10 samples,
   trimmed by ``max(3 samples, 20 ms)`` at both ends; a straight line in
   time is removed from each run (slow relaxation, pressure drift) and the
   pooled variance of what remains, with ``n - 2`` degrees of freedom per
   run, is the noise variance. Used when there are at least 50 such samples.
2. ``sliding`` -- otherwise, runs of steady sliding (regime ``sliding``,
   ``|a|`` below a tenth of the acceleration scale) of at least 20 samples,
   each with a quadratic in time removed.
3. ``repeats`` -- for steady-state points, the pooled standard deviation of
   points repeated at the same ``(v, x, p1, p2)`` (e.g. the ten experiments
   of seed 001 at each position).
4. ``difference`` -- otherwise ``std(diff(y))/sqrt(2)`` over the whole record
   (exact for white noise, a lower bound for coloured noise).

Removing a trend from a run of ``n`` samples of noise with correlation time
``tau`` lowers its variance by roughly ``2*tau/T``: on slow records whose
steady runs last a few correlation times, most of it. The pooled variance is
therefore divided by the degrees of freedom expected for AR(1) noise with the
correlation the detrended runs show (:func:`correlated_dof`), not by
``n - degree - 1`` per run (white noise, to which it reduces).

**Noise with a long memory.** A 1/f ("pink", flicker) noise has as much power in every
decade of frequency, down to the length of the record: a run of rest or steady sliding
sees only the decades above its own length, and no AR(1) correction restores the rest
(a pink load-cell noise came out 13-26 % low from rests of 0.05-0.5 s). Its signature is
a variance that keeps growing with the length of the pieces it is measured on, by the
same amount for every doubling, where white or AR(1) noise levels off after a few
correlation times. :func:`long_memory` measures the corrected variance on pieces of
16, 32, 64, ... samples of the same runs; when it grows log-linearly with the piece
length (:data:`GROWTH_MIN` per doubling or more, steadily) the floor is that line carried
to the length of the records' sessions (the residual of the right model keeps the
noise's slow wander), at most :data:`GROWTH_CAP` times the variance of the longest pieces.
Only rests are read this way: in steady sliding the friction's own structure along the
stroke (a ripple, a worn zone) also grows with the piece length, and carried to the
record's length it inflated the floors of the shipped real records by 15-65 %.

The *effective sample size* of a residual series is ``n/tau_int`` with
``tau_int = 1 + 2*sum(rho_l)`` its integrated autocorrelation time
(:func:`fcomp.identification.uncertainty.integrated_autocorrelation`); the
information criterion and the significance tests of :mod:`.loop` use it
because residuals of friction fits are far from independent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter
from scipy.special import ndtr

from fcomp.diagnosis.data import DiagnosisData, sessions
from fcomp.diagnosis.regimes import SLIDING, Segmentation
from fcomp.identification.uncertainty import integrated_autocorrelation

MIN_REST_RUN = 10
MIN_REST_TOTAL = 50
MIN_SLIDE_RUN = 20
#: A run is dropped from the floor when more than this share of its samples ...
OUTLIER_SHARE = 0.01
#: ... lie beyond this many robust standard deviations of the pooled residuals.
OUTLIER_SPREAD = 5.0


@dataclass(frozen=True)
class NoiseFloor:
    """The noise floor of a record.

    Attributes
    ----------
    value : N
        Standard deviation of the force noise.
    method : str
        ``"rest"``, ``"sliding"``, ``"repeats"`` or ``"difference"`` (module docstring).
    n_samples : int
        Samples the estimate rests on.
    runs : int
        Number of runs pooled.
    tau : s
        Integrated autocorrelation time of the noise.
    """

    value: float
    method: str
    n_samples: int
    runs: int
    tau: float
    long_memory: LongMemory | None = None


#: Fewest pieces a length of :func:`long_memory` must have ...
PIECES_MIN = 8
#: ... and fewest lengths measured.
LENGTHS_MIN = 4
#: Shortest piece (samples) of :func:`long_memory`.
PIECE_MIN = 16
#: Growth of the variance per doubling of the piece length, as a share of the variance of
#: the longest pieces, from which the noise counts as having a long memory (AR(1) noise,
#: after its correction, grows by less than 1 % per doubling on the matrix's records; pink
#: noise by 8-10 %).
GROWTH_MIN = 0.03
#: The carried variance is at most this many times that of the longest pieces.
GROWTH_CAP = 4.0
#: The shortest pieces' variance is at least this share of the longest pieces' (broadband) ...
BROADBAND = 0.25
#: ... and the growth over the longer half of the lengths at least this share of that over
#: the shorter half (steady, not levelling off).
STEADY = 0.5


@dataclass(frozen=True)
class LongMemory:
    """A variance growing with the piece length (:func:`long_memory`): its growth per
    doubling (N^2), the variance of the longest pieces measured, their length and the
    length carried to (samples)."""

    growth: float
    longest: float
    measured: int
    carried_to: int

    @property
    def factor(self) -> float:
        """The carried variance over the longest pieces' (>= 1)."""
        doublings = math.log2(self.carried_to / self.measured)
        return min(1.0 + self.growth * doublings / self.longest, GROWTH_CAP)


def long_memory(y: np.ndarray, runs: list[tuple[int, int]], degree: int, target: int
                ) -> LongMemory | None:
    """Whether the noise in ``runs`` of ``y`` has a long memory, and how much (module
    docstring): the variance about a polynomial of ``degree``, corrected by
    :func:`correlated_dof`, on pieces of 16, 32, 64, ... samples cut from the runs (at
    least :data:`PIECES_MIN` pieces, :data:`LENGTHS_MIN` lengths); a weighted line in
    ``log2(length)`` (weights the square roots of the piece counts) whose slope is at least
    :data:`GROWTH_MIN` of the longest pieces' variance, with the variance rising at every
    doubling but one, the shortest pieces holding :data:`BROADBAND` of it and the growth
    not levelling off (:data:`STEADY`). ``target`` is the length (samples) the floor must
    hold for."""
    longest = max((b - a for a, b in runs), default=0)
    levels: list[tuple[int, int, float]] = []
    n = PIECE_MIN
    while n <= longest:
        tt = np.linspace(-1.0, 1.0, n)
        basis = np.vander(tt, degree + 1)
        pieces = [y[a + k * n:a + (k + 1) * n] for a, b in runs for k in range((b - a) // n)]
        if len(pieces) < PIECES_MIN:
            break
        stack = np.array(pieces).T
        coef, *_ = np.linalg.lstsq(basis, stack, rcond=None)
        res = stack - basis @ coef
        dof = correlated_dof(list(res.T), degree)
        if dof > 0:
            levels.append((n, len(pieces), float(np.sum(res * res)) / dof))
        n *= 2
    if len(levels) < LENGTHS_MIN or target <= levels[-1][0]:
        return None
    x = np.log2([lv[0] for lv in levels])
    v = np.array([lv[2] for lv in levels])
    w = np.sqrt([lv[1] for lv in levels])
    slope, _ = np.polyfit(x, v, 1, w=w)
    half = len(levels) // 2
    low = np.polyfit(x[:half + 1], v[:half + 1], 1)[0]
    high = np.polyfit(x[half:], v[half:], 1)[0]
    rises = int(np.sum(np.diff(v) > 0))
    # 1/f noise: broadband (the shortest pieces hold much of it), growing by about the same
    # amount at every doubling; a line (a pump) or a smooth structure at rest grows from
    # almost nothing and levels off once the pieces span it (a 32 Hz line: 0.06 of the
    # longest pieces' variance on pieces of 16 samples)
    if not (slope >= GROWTH_MIN * v[-1] and rises >= len(levels) - 2
            and v[0] >= BROADBAND * v[-1] and high >= STEADY * low):
        return None
    return LongMemory(float(slope), float(v[-1]), int(levels[-1][0]), int(target))


def effective_sample_size(r: np.ndarray) -> float:
    """``n/tau_int`` of a residual series (see the module docstring)."""
    r = np.asarray(r, dtype=float)
    if r.size < 4:
        return float(r.size)
    return float(r.size / integrated_autocorrelation(r, max_lag=max(1, r.size // 10)))


def _runs(mask: np.ndarray, min_len: int) -> list[tuple[int, int]]:
    idx = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    return [(a, b) for a, b in zip(idx[::2], idx[1::2], strict=True) if b - a >= min_len]


def _pooled(t: np.ndarray, y: np.ndarray, runs: list[tuple[int, int]], degree: int
            ) -> tuple[float, int, np.ndarray, list[tuple[int, int]]]:
    """Pooled variance of ``y`` about a polynomial in time per run, robust to outlying runs.

    Each run gets a least-squares polynomial of ``degree``; from the pooled
    residuals a robust spread ``s = 1.4826*MAD`` is taken, and runs with more
    than :data:`OUTLIER_SHARE` of their samples beyond :data:`OUTLIER_SPREAD`
    ``s`` are dropped (a rest read off a coarse encoder may hold a creep, and a
    static friction law jumps there). The variance of the kept runs, with
    ``n - degree - 1`` degrees of freedom per run, is returned with the
    samples counted, their residuals and the runs kept.
    """
    fits = []
    for a, b in runs:
        tt = t[a:b] - t[a]
        coef = np.polyfit(tt, y[a:b], degree)
        fits.append((a, b, y[a:b] - np.polyval(coef, tt)))
    allr = np.concatenate([r for _, _, r in fits]) if fits else np.zeros(0)
    spread = 1.4826 * float(np.median(np.abs(allr - np.median(allr)))) if allr.size else 0.0
    if spread > 0:
        fits = [f for f in fits
                if np.mean(np.abs(f[2]) > OUTLIER_SPREAD * spread) <= OUTLIER_SHARE]
    ss = sum(float(r @ r) for _, _, r in fits)
    kept = [(a, b) for a, b, _ in fits]
    res = np.concatenate([r for _, _, r in fits]) if fits else np.zeros(0)
    dof = correlated_dof([r for _, _, r in fits], degree)
    return (ss / dof if dof > 0 else math.nan), int(res.size), res, kept


def _exp_smooth(q: np.ndarray, rho: float) -> np.ndarray:
    """``C q`` for the AR(1) correlation matrix ``C[t, s] = rho^|t - s|`` (columns of ``q``),
    by a forward and a backward exponential filter: O(n)."""
    q = np.asarray(q, dtype=float)
    f = lfilter([1.0], [1.0, -rho], q, axis=0)
    b = lfilter([1.0], [1.0, -rho], q[::-1], axis=0)[::-1]
    return f + b - q


def _ar1_moments(n: int, degree: int, rho: float) -> tuple[float, float]:
    """For AR(1) noise of unit variance and lag-one correlation ``rho`` on ``n`` samples with a
    polynomial of ``degree`` removed by least squares (``r = A e``, ``A = I - Q Q'``):
    ``E[r'r] = n - tr(Q'CQ)`` and ``E[sum_t r_t r_(t+1)]``."""
    t = np.linspace(-1.0, 1.0, n)
    Q, _ = np.linalg.qr(np.vander(t, degree + 1))
    CQ = _exp_smooth(Q, rho)
    G = Q.T @ CQ
    diag = n - float(np.trace(G))
    # sum_t (A C A)[t, t+1], A C A = C - Q Q'C - C Q Q' + Q G Q'
    lag = ((n - 1) * rho - float(np.sum(Q[:-1] * CQ[1:])) - float(np.sum(CQ[:-1] * Q[1:]))
           + float(np.sum((Q[:-1] @ G) * Q[1:])))
    return diag, lag


def correlated_dof(runs: list[np.ndarray], degree: int) -> float:
    """The expected ``sum r'r / sigma^2`` of detrended runs of correlated noise.

    Removing a polynomial of ``degree`` from a run of ``n`` samples of white noise
    leaves ``n - degree - 1`` degrees of freedom. Correlated noise loses more: over a
    run no longer than a few correlation times the polynomial takes much of the noise
    with it, and the pooled variance, divided by ``n - degree - 1``, comes out low
    (on 100 Hz records with noise correlated over 30 samples and 0.3 s steady runs,
    by a factor of several). The noise is modelled as AR(1) with lag-one correlation
    ``rho``, chosen so that the lag-one autocorrelation it predicts for the
    *detrended* runs equals the observed one (bisection); the expected sum of squares
    is then ``sigma^2 * sum_i (n_i - tr(Q_i' C Q_i))``. White noise (``rho = 0``)
    gives back ``sum_i (n_i - degree - 1)``. ``rho`` is capped so that no run counts
    for fewer than two effective samples. Checked against a Monte Carlo
    (``tests/test_diagnosis_parts.py``): where runs are shorter than about two
    correlation times the inverted ``rho`` errs high and the variance comes out up to
    about 20 % high, against 60-70 % low without the correction.
    """
    runs = [r for r in runs if r.size > degree + 2]
    if not runs:
        return 0.0
    white = float(sum(r.size - (degree + 1) for r in runs))
    num = sum(float(r[:-1] @ r[1:]) for r in runs)
    den = sum(float(r @ r) for r in runs)
    if den <= 0 or num <= 0:
        return white
    observed = num / den
    lengths = np.array([r.size for r in runs])
    # one moment computation per distinct length (runs share lengths at a fixed trim)
    uniq, counts = np.unique(lengths, return_counts=True)

    def moments(rho: float) -> tuple[float, float]:
        d = lag = 0.0
        for n, c in zip(uniq, counts, strict=True):
            dn, ln = _ar1_moments(int(n), degree, rho)
            d += c * dn
            lag += c * ln
        return d, lag

    def predicted(rho: float) -> float:
        d, lag = moments(rho)
        return lag / d if d > 0 else 1.0

    lo, hi = 0.0, 1.0 - 1.0 / max(float(np.median(lengths)), 4.0)
    if predicted(hi) <= observed:
        rho = hi
    else:
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            if predicted(mid) < observed:
                lo = mid
            else:
                hi = mid
        rho = 0.5 * (lo + hi)
    dof = moments(rho)[0]
    return float(max(dof, 2.0 * len(runs))) if dof < white else white


def noise_floor(data: DiagnosisData, seg: Segmentation) -> NoiseFloor:
    """The :class:`NoiseFloor` of ``data`` (see the module docstring)."""
    t, v, a, y = data.signal("t"), data.signal("v"), data.signal("a"), data.y
    dt = data.scales.dt
    boundaries = np.zeros(data.n, dtype=bool)
    for e in data.experiments:
        boundaries[e.start] = True
    if not data.steady_state:
        trim = max(3, int(math.ceil(0.02 / dt)))
        rest = (np.abs(v) <= seg.v_rest) & seg.valid
        runs = [(s + trim, e - trim) for s, e in _runs(rest, MIN_REST_RUN + 2 * trim)]
        runs = [(s, e) for s, e in runs if not boundaries[s + 1:e].any()]
        if sum(e - s for s, e in runs) >= MIN_REST_TOTAL:
            var, n, res, kept = _pooled(t, y, runs, 1)
            if n >= MIN_REST_TOTAL:
                return _floor(var, "rest", n, kept, _tau(res, kept, dt), y, 1, data)
        steady = (seg.regime == SLIDING) & (np.abs(a) < 0.1 * data.scales.accel) & seg.valid
        runs = [r for r in _runs(steady, MIN_SLIDE_RUN) if not boundaries[r[0] + 1:r[1]].any()]
        if sum(e - s for s, e in runs) >= MIN_REST_TOTAL:
            var, n, res, kept = _pooled(t, y, runs, 2)
            if n >= MIN_REST_TOTAL:
                return NoiseFloor(math.sqrt(var), "sliding", n, len(kept), _tau(res, kept, dt))
    else:
        groups = _repeat_groups(data)
        if groups:
            ss = sum(float(np.sum((y[g] - y[g].mean()) ** 2)) for g in groups)
            dof = sum(g.size - 1 for g in groups)
            return NoiseFloor(math.sqrt(ss / dof), "repeats", int(sum(g.size for g in groups)),
                              len(groups), 0.0)
    d = np.diff(y)
    d = d[~boundaries[1:]]
    return NoiseFloor(float(np.std(d) / math.sqrt(2.0)), "difference", int(d.size), 1, dt)


def _floor(var: float, method: str, n: int, runs: list[tuple[int, int]], tau: float,
           y: np.ndarray, degree: int, data: DiagnosisData) -> NoiseFloor:
    """The floor of rests pooled to ``var``, carried to the sessions' length where the noise
    has a long memory (:func:`long_memory`; the sessions of :func:`.data.sessions`)."""
    target = int(np.median([sum(data.experiments[i].n for i in g) for g in sessions(data)]))
    memory = long_memory(y, runs, degree, target)
    if memory is not None:
        var *= memory.factor
    return NoiseFloor(math.sqrt(var), method, n, len(runs), tau, memory)


def tolerant_noise_share(width: np.ndarray, sigma: float) -> float:
    """Mean share of the noise variance the tolerant residual keeps across a band (-).

    The tolerant residual (:func:`fcomp.diagnosis.scoring.tolerant_residual`) is
    the distance of the measurement from the band ``width`` the model could be
    expected to predict, so where the band is wide even pure noise leaves less
    than ``sigma``. For a measurement ``c + e``, ``e ~ N(0, sigma^2)``, ``c`` at the
    centre of a band of half-width ``h = k*sigma``:

    ``E[r^2]/sigma^2 = 2*((1 + k^2)*Q(k) - k*phi(k))``

    (``Q`` the upper normal tail, ``phi`` the normal density; 1 at ``k = 0``).
    The floor a tolerant residual is compared with is ``sigma`` times the square
    root of this share's mean over its samples.
    """
    if width.size == 0 or not sigma > 0:
        return 1.0
    k = 0.5 * np.maximum(width, 0.0) / sigma
    phi = np.exp(-0.5 * k**2) / math.sqrt(2.0 * math.pi)
    share = 2.0 * ((1.0 + k**2) * ndtr(-k) - k * phi)
    return float(np.clip(np.mean(share), 0.0, 1.0))


def _repeat_groups(data: DiagnosisData) -> list[np.ndarray]:
    """Steady-state points measured repeatedly at the same ``(v, x, p1, p2)``."""
    keys = np.column_stack([data.signal(k) for k in ("v", "x", "p1", "p2")])
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return [np.flatnonzero(inverse.ravel() == g) for g in np.flatnonzero(counts > 1)]


def _tau(res: np.ndarray, runs: list[tuple[int, int]], dt: float) -> float:
    """Correlation time (s) of the pooled run residuals (longest run, for simplicity)."""
    lengths = [b - a for a, b in runs]
    k = int(np.argmax(lengths))
    start = sum(lengths[:k])
    r = res[start:start + lengths[k]]
    return float(integrated_autocorrelation(r, max_lag=max(1, r.size // 4)) * dt)
