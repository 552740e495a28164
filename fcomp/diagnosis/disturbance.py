"""Periodic disturbances: narrow spectral lines in the residual that follow no motion.

A pump's pulsation, a fan, mains hum on an unscreened load cell, a valve's
dither: forces that act on (or in) the force channel at their own frequency,
whatever the piston does. No friction law explains them, so they are not a
missing effect; left in the record they would be folded into the noise floor
(a 0.8 N line at 37 Hz on 0.2 N of sensor noise reads as a 0.61 N floor) and
a record still carrying them would be called explained. They are found, and
taken out, before the search:

1. **Lines.** The residual of the first baseline fit (plain, ``y - F_hat``,
   gated by the square root of the fits' sample weights: where the model cannot
   place its prediction -- a static law's jump at a reversal, within the timing
   uncertainty -- a spike of its whole level is a broadband impulse that buries
   a line; on a pneumatic record whose force comes from the pressures a 0.46 N
   pump line stands 1.3 times over the plain residual's spectrum and 25 times
   over the gated one's)
   of every experiment of at least :data:`MIN_SECONDS` is resampled onto its
   median interval where the stamps are not uniform, and its Welch spectrum
   (Hann windows of about :data:`WINDOW_SECONDS`, half overlap; the spectra of
   experiments on one frequency grid pooled, their windows adding up) is divided by
   its running median over :data:`BACKGROUND_HZ` on either side (the local
   background of a smooth spectrum). A bin is a line when that ratio exceeds
   the level a chi-square spectrum with ``2K`` degrees of freedom (``K``
   windows) passes with probability :data:`FALSE_ALARM` over all the bins
   searched (:data:`MIN_HZ` to :data:`MAX_SHARE` of the Nyquist frequency), and
   it is the largest within two bins.
2. **Not the motion's.** A line is the motion's -- a friction law's error
   repeating with a periodic motion, its harmonics -- when the motion shows a
   line there too: the spectra of ``v``, ``a``, ``sign(v)``, ``|v|``, ``x`` and
   the model's prediction are tested the same way, at half the threshold (at least
   :data:`MOTION_LINE`), within two bins. It is the motion's too when it no
   longer stands out once the part of the residual *coherent* with the motion is
   taken off: at each frequency the residual's spectrum times ``1 - C``, ``C`` the
   largest Welch magnitude-squared coherence of the residual with one of those
   features or with ``sign(v)*p1``, ``sign(v)*p2`` (a pressure-dependent friction
   law's shape), is divided by its own running median and must still pass the
   threshold within a bin. A missing law's misfit concentrated near a frequency
   the motion dwells at, without a line of the motion's own, is coherent with it
   and vanishes (generated records: a lead-lag law's 2.25 Hz "line", coherence 0.9
   with ``v`` and ``a``; a chamber-weighted pressure law's 3.05 Hz "line", 0.5 with
   ``sign(v)*p1``); a source on its own clock is incoherent with the motion and
   stays, even where the friction the motion drives fills the same bin (a pump
   line on a hydraulic record whose residual at 36 Hz is 85 % coherent with ``x``
   stands out *more* without that part: 2.3 -> 4.2). A pump's line enters the force
   through the chamber pressures themselves, unmodulated, so the pressures alone
   are no such feature; modulated by ``sign(v)`` its coherence stays below 0.05.
   A line must also be there at low and at high speed alike
   (:func:`_same_at_all_speeds`: a ripple along the bore is a line in time
   only at one speed), as large within three of its cycles of a start or
   reversal as beyond (a ring the break-away excites is not), and keep its
   phase in time from window to window
   (:func:`_phase_consistency`: a source on its own clock does, a structure met
   at varying positions and speeds does not). Only lines that pass all three are
   disturbances.
3. **Size.** The line's frequency is refined on a grid a tenth of a bin
   fine (the periodogram summed over the experiments, each with its own phase),
   and a sinusoid at that frequency is fitted by least squares in each
   experiment on the actual stamps. It is reported when its RMS is at least
   :data:`MIN_SHARE` of the noise floor left once all lines are removed.

The diagnosis subtracts the fitted sinusoids from the force it matches,
estimates the noise floor again on what is left, reports each line in the
JSON (``disturbances``) and the report, and does not call such a record
``explained`` (:mod:`.loop`). The search is run on the first fit's residual,
and again on the final model's: a line small beside the baseline's misfit (a
5 N pump line under the 33 N misfit of a missing viscous law) stands out only
once the misfit is explained; it is then taken out the same way and the final
model refitted on the cleaned force before the verdict.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats
from scipy.ndimage import median_filter
from scipy.signal import get_window

from fcomp.diagnosis.data import DiagnosisData
from fcomp.reconstruction import sampling_interval

#: Shortest experiment (s) whose spectrum is searched.
MIN_SECONDS = 2.0
#: Length (s) of the spectral windows (frequency resolution about its inverse).
WINDOW_SECONDS = 2.0
#: Fewest windows an experiment's spectrum averages.
MIN_WINDOWS = 3
#: Width (Hz) of the running median on either side of a bin (the local background) ...
BACKGROUND_HZ = 3.0
#: ... and at least this many bins.
BACKGROUND_BINS = 8
#: Chance that a spectrum without a line shows one anywhere in the band searched.
FALSE_ALARM = 1e-3
#: A motion feature has a line of its own where its spectrum is at least this many times its
#: local background (and half the residual's threshold): its spectrum is no chi-square
#: noise, and a pooled threshold near 1 would call its every ripple a line.
MOTION_LINE = 3.0
#: Lowest frequency searched (Hz): below it the residual's slow structure is a law's.
MIN_HZ = 2.0
#: Highest frequency searched, as a share of the Nyquist frequency (the anti-alias filter's
#: roll-off and the spectrum's edge lie above).
MAX_SHARE = 0.8
#: A line is reported when its RMS is at least this share of the noise floor left.
MIN_SHARE = 0.5
#: Fewest samples of a speed group the line is compared in.
MIN_GROUP = 200
#: Least steadiness of the line's phase in time (:func:`_phase_consistency`) ...
PHASE_CONSISTENCY = 0.5
#: ... over windows of this length (s).
PHASE_WINDOW = 1.0
#: Least gain of the line's sinusoid in the slower and in the faster half of the samples.
SPEED_GAIN = 0.5
#: A line must be as large within this many of its cycles after a start or reversal as
#: beyond (:func:`_same_at_all_speeds`: a ring the break-away excites is not).
EVENT_CYCLES = 3.0
#: ... and at most this many times as large there as its fitted size.
EVENT_GAIN = 3.0
#: Most candidate lines tested for being the motion's (strongest first).
MAX_CANDIDATES = 40
#: Most lines reported.
MAX_LINES = 5
#: Lines closer than this (Hz, two bins) are one line.
SAME_HZ = 2.0 / WINDOW_SECONDS


@dataclass(frozen=True)
class Disturbance:
    """A narrow line in the residual that follows no motion feature.

    Attributes
    ----------
    frequency_hz
        Its frequency (Hz).
    amplitude
        Amplitude of the fitted sinusoid (N), the RMS-weighted mean over the
        experiments that show it.
    rms
        Its RMS over the record (N).
    prominence
        Its power over the local background of the spectrum (-).
    experiments
        In how many experiments it was fitted.
    """

    frequency_hz: float
    amplitude: float
    rms: float
    prominence: float
    experiments: int

    def to_dict(self) -> dict[str, Any]:
        return {"frequency_hz": self.frequency_hz, "amplitude": self.amplitude,
                "rms": self.rms, "prominence": self.prominence,
                "experiments": self.experiments, "units": {"frequency_hz": "Hz",
                                                           "amplitude": "N", "rms": "N"}}


def _uniform(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    """``y`` on a uniform grid of the median interval (itself when already uniform)."""
    dt = sampling_interval(t)
    if np.allclose(np.diff(t), dt, rtol=1e-3, atol=0.0):
        return y, dt
    grid = t[0] + dt * np.arange(int(math.floor((t[-1] - t[0]) / dt)) + 1)
    return np.interp(grid, t, y), dt


@dataclass(frozen=True)
class _Frames:
    """A signal's Welch frames: the discrete Fourier transforms of its Hann-windowed,
    linearly detrended windows of ``nper`` samples at half overlap (:func:`_frames`)."""

    X: np.ndarray
    nper: int
    dt: float
    windows: int
    norm: float


def _frames(a: np.ndarray, dt: float) -> _Frames | None:
    """The Welch frames of ``a`` on a uniform grid of ``dt`` (windows of about
    :data:`WINDOW_SECONDS`; None: too short for :data:`MIN_WINDOWS` of them): every window
    at once, so that a signal's frames are computed once for its power spectrum and for
    its cross spectrum with every other (scipy's ``csd`` transformed both signals again on
    every call, and detrended window by window: 5 % of a diagnosis of the O-ring files)."""
    nper = int(round(WINDOW_SECONDS / dt))
    if a.size < nper or nper < 16:
        return None
    k = 1 + (a.size - nper) // (nper // 2)
    if k < MIN_WINDOWS:
        return None
    step = nper - nper // 2
    count = 1 + (a.size - nper) // step
    seg = np.lib.stride_tricks.sliding_window_view(a, nper)[::step][:count]
    tt = np.arange(nper) - 0.5 * (nper - 1)
    seg = (seg - seg.mean(axis=1, keepdims=True)
           - np.outer(seg @ tt / float(tt @ tt), tt))
    win = get_window("hann", nper)
    return _Frames(np.fft.rfft(seg * win, axis=1), nper, dt, k, float(win @ win))


def _cross(fa: _Frames, fb: _Frames) -> tuple[np.ndarray, np.ndarray, int]:
    """``(f, S_ab, K)``: the Welch cross spectral density of two signals' frames (one-sided,
    scipy's ``csd`` with ``scaling="density"``; the power spectrum, real, where ``fb`` is
    ``fa``) and the number of windows."""
    S = np.mean(np.conj(fa.X) * fb.X, axis=0) * (fa.dt / fa.norm)
    S[1:-1 if fa.nper % 2 == 0 else None] *= 2.0
    f = np.fft.rfftfreq(fa.nper, fa.dt)
    return f, (S.real if fb is fa else S), fa.windows


def _prominence(f: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Power over the running median of the neighbouring bins (the local background)."""
    df = float(f[1] - f[0])
    half = max(BACKGROUND_BINS, int(round(BACKGROUND_HZ / df)))
    back = median_filter(P, size=2 * half + 1, mode="nearest")
    return P / np.maximum(back, 1e-300)


def _threshold(k: int, bins: int) -> float:
    """Ratio a line-free chi-square(2K) spectrum passes in one of ``bins`` bins with
    probability :data:`FALSE_ALARM` (over its median: the background is a median)."""
    dof = 2 * k
    alpha = FALSE_ALARM / max(bins, 1)
    return float(stats.chi2.isf(alpha, dof) / stats.chi2.median(dof))


def _lines(f: np.ndarray, ratio: np.ndarray, level: float) -> list[int]:
    """Bins above ``level`` that are the largest of their neighbours, strongest first.

    A local maximum over one bin either side, not two: a line between two bins
    (scalloping spreads it over both) next to a stronger peak of the motion's a bin
    or two away was masked by it, and lost when that peak failed the tests of
    :func:`find`. Two maxima of one line's main lobe refine to one frequency and
    are counted once (:func:`find`).
    """
    out = []
    for i in np.flatnonzero((ratio > level) & (f >= MIN_HZ) & (f <= MAX_SHARE * f[-1])):
        lo, hi = max(i - 1, 0), min(i + 2, ratio.size)
        if ratio[i] >= ratio[lo:hi].max():
            out.append(int(i))
    return sorted(out, key=lambda i: -ratio[i])


def _candidates(f: np.ndarray, ratio: np.ndarray, alone: np.ndarray, level: float,
                local: float) -> list[int]:
    """The strongest :data:`MAX_CANDIDATES` bins that are lines (:func:`_lines`) of the
    residual's spectrum ``ratio``, or of its spectrum without the motion's part ``alone``
    where the residual's own spectrum passes the ``local`` level (one bin's false-alarm
    level) there: a line the motion's part hides still lifts its own bin, while taking a
    noisy coherence estimate off bin by bin leaves peaks the residual does not have."""
    hidden = [i for i in _lines(f, alone, level) if ratio[max(i - 1, 0):i + 2].max() > local]
    both = {i: max(ratio[i], alone[i]) for i in [*_lines(f, ratio, level), *hidden]}
    return sorted(both, key=lambda i: -both[i])[:MAX_CANDIDATES]


def _sinusoid(t: np.ndarray, r: np.ndarray, freq: float, weights: np.ndarray) -> np.ndarray:
    """The weighted least-squares sinusoid (with a mean) at ``freq`` in ``r(t)``, without
    the mean."""
    w = 2.0 * math.pi * freq * (t - t[0])
    X = np.column_stack([np.cos(w), np.sin(w), np.ones_like(t)])
    g = np.sqrt(weights)
    coef, *_ = np.linalg.lstsq(X * g[:, None], r * g, rcond=None)
    return np.asarray(X[:, :2] @ coef[:2])


def _refine(pieces: Sequence[tuple[np.ndarray, np.ndarray]], f0: float, df: float) -> float:
    """The frequency near ``f0`` (within a bin) that maximises the summed periodograms."""
    grid = f0 + df * np.linspace(-1.0, 1.0, 21)
    power = np.zeros(grid.size)
    for t, r in pieces:
        rc = r - r.mean()
        ph = 2.0 * math.pi * np.outer(grid, t - t[0])
        power += (np.cos(ph) @ rc) ** 2 + (np.sin(ph) @ rc) ** 2
    return float(grid[int(np.argmax(power))])


def find(residual: np.ndarray, prediction: np.ndarray, data: DiagnosisData,
         weights: np.ndarray | None = None, since: np.ndarray | None = None
         ) -> list[tuple[float, float, list[np.ndarray]]]:
    """Candidate lines of ``residual``: ``(frequency, prominence, sinusoid per experiment)``.

    See the module docstring (steps 1-3, without the size rule, which needs the
    noise floor once the lines are out). ``weights`` (0 to 1 per sample, the fits'
    :func:`~fcomp.diagnosis.scoring.sample_weights`) gate the residual where the model
    could not place its prediction: the spectra and the tests see ``sqrt(w) * r``, the
    sinusoids are fitted to ``r`` by weighted least squares. ``since`` (seconds since
    the last start or reversal) lets the test of :func:`_same_at_all_speeds` tell a ring
    after events from a line.
    """
    if data.steady_state:
        return []
    w_all = np.ones(residual.size) if weights is None else np.clip(weights, 0.0, 1.0)
    w_all = np.where(data.bridged, 0.0, w_all)  # inserted across a pause: no measurement
    gated = residual * np.sqrt(w_all)
    t_all = data.signal("t")
    feats = {"v": data.signal("v"), "x": data.signal("x"), "model": prediction}
    if data.available.get("a", False):
        feats["a"] = data.signal("a")
    feats["sign(v)"] = np.sign(feats["v"])
    feats["|v|"] = np.abs(feats["v"])
    # what a pressure-dependent law makes of the pressures: coherence only (step 2)
    laws = {f"sign(v)*{k}": feats["sign(v)"] * data.signal(k) for k in ("p1", "p2")
            if data.available.get(k, False)}
    found: dict[float, tuple[float, float, float]] = {}  # bin frequency -> (f, ratio, df)
    pieces = []
    # the spectra of experiments on one frequency grid are pooled (their windows add up):
    # a line every experiment carries stands out of a background one experiment's
    # reversals can raise
    pooled: dict[tuple[int, float], list[Any]] = {}
    for idx, e in enumerate(data.experiments):
        t = t_all[e.start:e.stop]
        if t.size < 16 or t[-1] - t[0] < MIN_SECONDS:
            continue
        r = gated[e.start:e.stop]
        pieces.append((t, r, idx))  # fitted wherever long enough, searched where K windows fit
        ru, dt = _uniform(t, r)
        fr = _frames(ru, dt)
        if fr is None:
            continue
        f, P, k = _cross(fr, fr)
        grid = (f.size, round(float(f[1] - f[0]), 9))
        signals = [*feats.values(), *laws.values()]
        acc = pooled.setdefault(grid, [f, np.zeros_like(P), 0,
                                       [np.zeros_like(P) for _ in signals],
                                       [np.zeros(P.size, dtype=complex) for _ in signals]])
        acc[1] += k * P
        acc[2] += k
        for j, sig in enumerate(signals):  # each resampled once: its spectrum and the cross one
            fs_ = _frames(_uniform(t, sig[e.start:e.stop])[0], dt)
            assert fs_ is not None  # the residual's length and grid
            auto, cross = _cross(fs_, fs_), _cross(fr, fs_)
            acc[3][j] += k * auto[1]
            acc[4][j] += k * cross[1]
    for f, P, k, motion_P, cross_P in pooled.values():
        ratio = _prominence(f, P / k)
        level = _threshold(k, int(np.sum((f >= MIN_HZ) & (f <= MAX_SHARE * f[-1]))))
        motion_ratio = [_prominence(f, m) if np.any(m > 0) else None
                        for m in motion_P[:len(feats)]]
        # the residual's spectrum without, at each frequency, its part coherent with the motion
        # feature that explains most of it: what follows no motion
        share = np.zeros_like(P)
        for m, c in zip(motion_P, cross_P, strict=True):
            ok = (m > 0) & (P > 0)
            share[ok] = np.maximum(share[ok], np.abs(c[ok]) ** 2 / (P[ok] * m[ok]))
        alone = _prominence(f, P * (1.0 - np.clip(share, 0.0, 1.0)))
        # a line stands out of the residual, or of what is left of it without the motion's
        # part (a pump line on a misfit the motion drives in the same band)
        for i in _candidates(f, ratio, alone, level, _threshold(k, 1)):
            lo, hi = max(i - 2, 0), min(i + 3, f.size)
            if any(m is not None and m[lo:hi].max() > max(0.5 * level, MOTION_LINE)
                   for m in motion_ratio):
                continue  # the motion has a line there: the residual repeats with it
            if alone[max(i - 1, 0):i + 2].max() <= level:
                continue  # without what follows the motion, no line is left: a law's misfit
            key = round(float(f[i]), 6)
            if key not in found or ratio[i] > found[key][1]:
                found[key] = (float(f[i]), float(ratio[i]), float(f[1] - f[0]))
    out: list[tuple[float, float, list[np.ndarray]]] = []
    speed = feats["|v|"]
    for f0, prom, df in sorted(found.values(), key=lambda x: -x[1]):
        if len(out) >= MAX_LINES:
            break
        freq = _refine([(t, r) for t, r, _ in pieces], f0, df)
        if any(abs(freq - fl) < df for fl, _, _ in out):
            continue  # a second maximum of a line already taken
        waves = [np.zeros(e.n) for e in data.experiments]
        for t, _, idx in pieces:
            e = data.experiments[idx]
            waves[idx] = _sinusoid(t, residual[e.start:e.stop], freq, w_all[e.start:e.stop])
        if not _same_at_all_speeds(gated, np.concatenate(waves) * np.sqrt(w_all), speed,
                                   since, freq, w_all):
            continue
        if _phase_consistency([(t, r) for t, r, _ in pieces], freq) < PHASE_CONSISTENCY:
            continue
        out.append((freq, prom, waves))
    return out


def _phase_consistency(pieces: Sequence[tuple[np.ndarray, np.ndarray]], freq: float) -> float:
    """How steadily the line keeps its phase in time: ``|sum A_w| / sum |A_w|`` (0 to 1).

    ``A_w = sum r*exp(-2i*pi*f*t)`` over windows of :data:`PHASE_WINDOW` seconds (at
    least ten cycles), on absolute stamps, within each experiment (each its own
    phase; the experiments weighted by their windows' magnitudes). A source that
    runs on its own clock keeps its phase from window to window (1 without noise);
    a structure tied to the motion (a ripple along the bore, met at varying
    positions and speeds) does not.
    """
    num = 0.0
    den = 0.0
    span = max(PHASE_WINDOW, 10.0 / freq)
    for t, r in pieces:
        edges = np.arange(t[0], t[-1] + span, span)
        amps = []
        for lo, hi in zip(edges[:-1], edges[1:], strict=False):
            m = (t >= lo) & (t < hi)
            if m.sum() < 8:
                continue
            rc = r[m] - r[m].mean()
            amps.append(complex(np.sum(rc * np.exp(-2j * math.pi * freq * t[m]))))
        if len(amps) >= 2:
            num += abs(sum(amps))
            den += sum(abs(a) for a in amps)
    return num / den if den > 0 else 0.0


def _same_at_all_speeds(r: np.ndarray, wave: np.ndarray, speed: np.ndarray,
                        since: np.ndarray | None, freq: float, weights: np.ndarray) -> bool:
    """Whether the line is there at low and at high speed alike, and just after the
    motion's events as much as away from them (:data:`SPEED_GAIN`).

    A disturbance keeps its frequency and its size whatever the piston does; a
    structure of the bore (a ripple of wavelength ``L`` along the stroke) is a line
    only at the speed ``f*L``, and absent at rest; a ring after starts and reversals
    (a resonance the break-away excites) is a line in time only because the events
    repeat, and lives within a few of its cycles of them. The residual is projected
    onto the fitted sinusoid at rest, and within the slower and the faster half of
    the moving samples (by ``|v|``): the gain in each group of at least
    :data:`MIN_GROUP` samples (counted by their ``weights``: gated samples say little)
    must be at least :data:`SPEED_GAIN`. With ``since``
    (seconds since the last start or reversal, :meth:`.regimes.Segmentation.events`)
    the gain within :data:`EVENT_CYCLES` cycles of an event and beyond must also lie
    between :data:`SPEED_GAIN` and :data:`EVENT_GAIN` (a generated ring at 30 Hz: 5.0
    within three cycles, 0.7 beyond; pump lines: 1 beyond, and up to 2.2 within, where
    the gated residual still carries a law's misfit at the events).
    """
    used = wave != 0.0
    if used.sum() < 40:
        return False
    moving = used & (speed > 0.0)  # the conditioned velocity is held at 0 at rest
    cut = float(np.median(speed[moving])) if moving.any() else 0.0
    groups = [(used & (speed == 0.0), math.inf), (moving & (speed <= cut), math.inf),
              (moving & (speed > cut), math.inf)]
    if since is not None:
        near = since <= EVENT_CYCLES / freq
        groups += [(used & near, EVENT_GAIN), (used & ~near, EVENT_GAIN)]
    for group, most in groups:
        w = wave[group]
        if float(np.sum(weights[group])) < MIN_GROUP or not float(w @ w) > 0:
            continue  # too few samples here (after the gate): nothing to compare
        gain = float(r[group] @ w) / float(w @ w)
        if not SPEED_GAIN <= gain <= most:
            return False
    return True


def without(data: DiagnosisData, waves: Sequence[Sequence[np.ndarray]]) -> DiagnosisData:
    """``data`` with the sinusoids ``waves`` (per line, per experiment) taken off the force."""
    exps = []
    for i, e in enumerate(data.experiments):
        y = e.data.y - sum((w[i] for w in waves), np.zeros(e.n))
        exps.append(dataclasses.replace(e, data=dataclasses.replace(e.data, y=y)))
    return dataclasses.replace(data, experiments=exps)


def band_gain(band_hz: float | None, freq: float) -> float:
    """Gain at ``freq`` of the parallel filter a band-limited force went through: the
    zero-phase second-order Butterworth (:func:`fcomp.reconstruction.band_limit`),
    ``|H|^2 = 1/(1 + (f/fc)^4)``; 1 for an unfiltered force."""
    if band_hz is None or not band_hz > 0:
        return 1.0
    return 1.0 / (1.0 + (freq / band_hz) ** 4)


def describe(freq: float, prom: float, waves: Sequence[np.ndarray],
             data: DiagnosisData | None = None) -> Disturbance:
    """The :class:`Disturbance` of one line's fitted sinusoids, sized at the sensor.

    The sinusoids are fitted to the force as matched; where that force went
    through the parallel filter (``band_hz``) the line was attenuated by
    :func:`band_gain`, which is divided out of the amplitude and RMS reported.
    """
    gains = [band_gain(e.data.band_hz, freq) for e in data.experiments] if data is not None \
        else [1.0] * len(waves)
    used = [(w, g) for w, g in zip(waves, gains, strict=True) if np.any(w)]
    total = np.concatenate([w / max(g, 1e-3) for w, g in zip(waves, gains, strict=True)])
    rms = float(np.sqrt(np.mean(total**2))) if total.size else 0.0
    amps = [math.sqrt(2.0 * float(np.mean(w**2))) / max(g, 1e-3) for w, g in used]
    sizes = [w.size for w, _ in used]
    amp = float(np.average(amps, weights=sizes)) if used else 0.0
    return Disturbance(freq, amp, rms, prom, len(used))
