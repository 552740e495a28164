"""Residual features and how strongly the residual still follows each of them.

Features (per sample, SI units):

==============================  ==============================================
``t``                           time (s)
``v``                           velocity (m/s)
``a``                           acceleration (m/s^2)
``x``                           position (m)
``p1+p2``                       sum of the gauge chamber pressures (Pa)
``time_since_reversal``         time since the last change of direction (s)
``displacement_since_reversal`` distance from the last reversal point (m)
``dwell_time``                  rest before the current run started (s)
==============================  ==============================================

Strength (gradient-free regression, held-out): the residual is predicted
from one feature *and the direction of motion* (friction-like residuals
change sign with it) by a k-nearest-neighbour mean, fitted on the training
samples and applied to the held-out ones: for each held-out sample the mean
training residual of the ``k`` training samples with the nearest feature
values on the same side (0 where those neighbours lie further than 2 % of
the feature's range: the training samples do not cover that value). For time
``t`` a cubic in ``t`` per side replaces the neighbours (neighbours in time
are the adjacent training blocks and would credit any autocorrelated
residual to ``t``; a drift is slow). The strength is the fraction of the
held-out residual's mean square that this explains,

    strength = max(0, 1 - sum((r - r_knn)^2) / sum(r^2)),

the best over ``k`` in (10, 30, 100, 300). A residual that is noise gives
strengths near 0 for every feature; a residual that still follows a feature
(a position ripple: ``x``; a thermal drift: ``t``) gives a strength near the
share of its mean square that the structure carries.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fcomp.diagnosis.data import DiagnosisData, sessions
from fcomp.diagnosis.regimes import Segmentation

FEATURES: tuple[str, ...] = ("t", "v", "a", "x", "p1+p2", "time_since_reversal",
                             "displacement_since_reversal", "dwell_time")
NEIGHBOURS: tuple[int, ...] = (10, 30, 100, 300)


@dataclass(frozen=True)
class FeatureStrength:
    """How strongly the held-out residual follows one feature."""

    feature: str
    strength: float
    neighbours: int


def feature_values(data: DiagnosisData, seg: Segmentation) -> dict[str, np.ndarray]:
    """The features of :data:`FEATURES` that the data hold (see the module docstring)."""
    out: dict[str, np.ndarray] = {"t": data.signal("t"), "v": data.signal("v")}
    if data.available.get("a", False):
        out["a"] = data.signal("a")
    if data.available.get("x", False):
        out["x"] = data.signal("x")
    if data.available.get("p1", False):
        out["p1+p2"] = data.signal("p1") + data.signal("p2")
    if not data.steady_state:
        out["time_since_reversal"] = seg.time_since_reversal
        out["displacement_since_reversal"] = seg.displacement_since_reversal
        if np.any(seg.dwell_time > 0):
            out["dwell_time"] = seg.dwell_time
    return out


def knn_predict(f_train: np.ndarray, r_train: np.ndarray, f_test: np.ndarray, k: int,
                max_span: float = np.inf) -> np.ndarray:
    """Mean of ``r_train`` over the ``k`` training samples around ``f_test`` in sorted ``f``.

    The window of ``k`` sorted training values centred on each test value's
    insertion point (the ``k`` nearest neighbours up to one sample at the ends).
    Where the window spans more than ``max_span`` or does not contain the test
    value's neighbourhood (the training samples do not cover it) the
    prediction is 0: no information, rather than a guess from far away.
    """
    order = np.argsort(f_train, kind="stable")
    fs, rs = f_train[order], r_train[order]
    n = fs.size
    k = min(k, n)
    csum = np.concatenate([[0.0], np.cumsum(rs)])
    pos = np.searchsorted(fs, f_test)
    lo = np.clip(pos - k // 2, 0, n - k)
    pred = (csum[lo + k] - csum[lo]) / k
    far = np.maximum(fs[lo + k - 1] - f_test, f_test - fs[lo]) > max_span
    return np.where(far, 0.0, pred)


def poly_predict(f_train: np.ndarray, r_train: np.ndarray, f_test: np.ndarray,
                 degree: int = 3) -> np.ndarray:
    """A least-squares polynomial of ``degree`` in ``f`` (centred, scaled), fitted and applied."""
    c, w = float(np.mean(f_train)), float(np.ptp(f_train)) or 1.0
    coef = np.polyfit((f_train - c) / w, r_train, min(degree, max(f_train.size - 1, 0)))
    return np.polyval(coef, (f_test - c) / w)


def strength(f: np.ndarray, r: np.ndarray, side: np.ndarray, train: np.ndarray,
             test: np.ndarray, *, smooth: bool = False) -> tuple[float, int]:
    """Held-out strength of feature ``f`` for residual ``r``, and its best ``k``.

    ``side`` labels the groups predicted apart (the direction of motion, or any
    other labels: every value is a group).

    ``smooth`` replaces the nearest-neighbour mean by a cubic in ``f`` (returned
    ``k`` = 0): used for time, where neighbours in time are the adjacent
    training blocks and would credit any autocorrelated residual to ``t``;
    a cubic only sees slow trends (drift).
    """
    ss = float(np.sum(r[test] ** 2))
    if ss <= 0:
        return 0.0, 0
    groups = np.unique(side[test])
    lo, hi = np.percentile(f[train | test], [1.0, 99.0])
    max_span = max(float(hi - lo), 1e-300) / 50.0
    best = (0.0, 0)
    for k in ((0,) if smooth else NEIGHBOURS):
        pred = np.zeros(int(test.sum()))
        rt = r[test]
        for s in groups:
            tr = train & (side == s)
            te_local = side[test] == s
            if tr.sum() < max(k, 10) or not te_local.any():
                continue
            if smooth:
                pred[te_local] = poly_predict(f[tr], r[tr], f[test][te_local])
            else:
                pred[te_local] = knn_predict(f[tr], r[tr], f[test][te_local], k, max_span)
        val = 1.0 - float(np.sum((rt - pred) ** 2)) / ss
        if val > best[0]:
            best = (val, k)
    return max(best[0], 0.0), best[1]


def residual_structure(r: np.ndarray, data: DiagnosisData, seg: Segmentation,
                       train: np.ndarray, test: np.ndarray) -> list[FeatureStrength]:
    """Strength of every available feature for residual ``r``, strongest first."""
    side = data.signal("s")
    out = []
    for name, f in feature_values(data, seg).items():
        st, k = strength(f, r, side, train, test, smooth=name == "t")
        out.append(FeatureStrength(name, st, k))
    return sorted(out, key=lambda fs: -fs.strength)


#: Share of the largest residuals :func:`trimmed_rms` leaves out (isolated spikes).
TRIM = 0.01


def trimmed_rms(r: np.ndarray, drop: float = TRIM) -> float:
    """RMS of ``r`` without its largest ``drop`` share of ``|r|`` (N).

    Isolated spikes -- a start or stop that the derived velocity places one
    sample early or late, where a discontinuous friction law jumps by its
    full level -- are timing jitter, not structure a missing effect could
    explain; the verdict's excess tests ignore them this way.
    """
    if not r.size:
        return math.nan
    keep = np.sort(np.abs(r))[: max(1, int(math.ceil((1.0 - drop) * r.size)))]
    return float(np.sqrt(np.mean(keep**2)))


def paired_trimmed_rms(a: np.ndarray, b: np.ndarray, drop: float = TRIM) -> tuple[float, float]:
    """RMS of two residuals of the same samples without the spikes both carry (N, N).

    The samples dropped are the largest ``drop`` share of ``min(|a|, |b|)``: a
    timing spike (see :func:`trimmed_rms`) is in both residuals and no effect
    explains it, while a spike that one model removes -- a break-away excess
    after a dwell -- is what tells the two apart, and is kept. Trimming each
    residual by its own largest values would drop exactly those.
    """
    if not a.size:
        return math.nan, math.nan
    both = np.minimum(np.abs(a), np.abs(b))
    keep = np.argsort(both, kind="stable")[: max(1, int(math.ceil((1.0 - drop) * a.size)))]
    return float(np.sqrt(np.mean(a[keep] ** 2))), float(np.sqrt(np.mean(b[keep] ** 2)))


#: Windows (s) after every start and reversal in which :func:`event_structure` looks.
EVENT_WINDOWS: tuple[float, ...] = (0.05, 0.1, 0.2)


@dataclass(frozen=True)
class EventStructure:
    """How strongly the held-out residual repeats in the window after starts and reversals."""

    window: float
    strength: float
    rms: float
    share: float
    local: float = 0.0


def event_structure(r: np.ndarray, data: DiagnosisData, seg: Segmentation, train: np.ndarray,
                    test: np.ndarray) -> EventStructure | None:
    """The strongest structure locked to the events (reversals, starts), or None.

    A structure that follows every start for a short time -- a rig mode rung by
    the break-away, a transient no model term describes -- is a small share of a
    whole record and escapes the record-wide strengths of
    :func:`residual_structure`. Restricted to the samples within ``w`` of the
    last event, a reversal or a start after a rest (``w`` in
    :data:`EVENT_WINDOWS`; :meth:`.Segmentation.events`),
    the strength of the time since the start (:func:`strength`), predicted apart
    per class of event (reversal, start after a rest) and direction -- a
    mode rung only by the break-away after a rest is not diluted by the
    reversals that do not ring it -- and the RMS it carries there,
    ``rms_local*sqrt(strength)``, are computed; the window where that RMS is
    largest is returned, with the window's RMS without its largest 1 %
    (``local``, :func:`trimmed_rms`): a structure whose phase wanders from
    event to event (a rig mode rung at a start the velocity shows a few
    samples late) does not repeat as a function of the time since the event,
    but it still lifts the window's RMS far above the noise floor.
    """
    if data.steady_state:
        return None
    since, kind = seg.events(data)
    group = data.signal("s") * kind
    best = None
    for w in EVENT_WINDOWS:
        loc = since < w
        tl, el = train & loc, test & loc
        if el.sum() < 50 or tl.sum() < 50:
            continue
        st, _ = strength(np.where(loc, since, 0.0), r, group, tl, el)
        rms = float(np.sqrt(np.mean(r[el] ** 2)))
        found = EventStructure(w, st, rms * float(np.sqrt(st)), float(el.sum() / test.sum()),
                               trimmed_rms(r[el]))
        if best is None or found.rms > best.rms:
            best = found
    return best


def drift_fall(r: np.ndarray, F_hat: np.ndarray, data: DiagnosisData, train: np.ndarray,
               test: np.ndarray) -> float:
    """Held-out RMS fall (N) of the residual ``r`` by a slow drift of the friction level alone.

    A rival explanation of any law in a slow signal: friction levels changing
    over a session (temperature, run-in), ``F_hat*(1 + d(tau))``, ``d`` a cubic
    (Legendre ``P1..P3``, no constant) in the normalised time ``tau`` (-1 to 1
    over the session). Linearised about the current prediction, the residual it
    explains is ``F_hat*d(tau)``. The clock is the stamps': each session of
    :func:`fcomp.diagnosis.data.sessions` (one file, or files whose stamps run on)
    has its own cubic, so separate files are separate experiments, never a
    clock in the order they were named (four files at four pressures in
    pressure order would otherwise make a drift over "time" a copy of a
    pressure law). The coefficients are fitted by least squares on the moving
    training samples and the fall is the held-out RMS before minus after.
    Linearised, this is a lower bound of what a refit with the drift would
    achieve. When the motion wanders along the stroke over a session, a law in
    the position (or a pressure) can stand in for such a drift; a candidate
    whose fall this matches is confounded with time.
    """
    t = data.signal("t")
    cols = []
    for group in sessions(data):
        idx = np.concatenate([np.arange(data.experiments[i].start, data.experiments[i].stop)
                              for i in group])
        t0, t1 = float(t[idx].min()), float(t[idx].max())
        if t1 <= t0:
            continue
        tau = np.zeros(data.n)
        inside = np.zeros(data.n, dtype=bool)
        inside[idx] = True
        tau[idx] = 2.0 * (t[idx] - t0) / (t1 - t0) - 1.0
        for poly in (tau, 0.5 * (3.0 * tau**2 - 1.0), 0.5 * (5.0 * tau**3 - 3.0 * tau)):
            cols.append(np.where(inside, F_hat * poly, 0.0))
    if not cols:
        return 0.0
    moving = data.signal("v") != 0.0
    X = np.column_stack(cols)
    fit = train & moving
    if fit.sum() < 50 or not np.any(test):
        return 0.0
    coef, *_ = np.linalg.lstsq(X[fit], r[fit], rcond=None)
    pred = np.where(moving, X @ coef, 0.0)
    before = float(np.sqrt(np.mean(r[test] ** 2)))
    after = float(np.sqrt(np.mean((r - pred)[test] ** 2)))
    return before - after


def _mean_periodogram(r: np.ndarray, starts: list[int], n: int) -> np.ndarray:
    """Mean periodogram (Hann window, mean removed) of ``r`` over ``n`` samples from each start."""
    segs = np.stack([r[k:k + n] - np.mean(r[k:k + n]) for k in starts]) * np.hanning(n)
    return np.asarray(np.mean(np.abs(np.fft.rfft(segs, axis=1)) ** 2, axis=0))


#: Windows (s) after events whose spectra :func:`event_ring` compares with quiet ones.
RING_WINDOWS: tuple[float, ...] = (0.1, 0.2)
#: A ring shows at least this many cycles in a window (slower structure after events is
#: the friction law's transient, judged by :func:`event_structure`).
RING_CYCLES = 5.0
#: Quiet windows start at least this long (s) after the last event.
QUIET_AFTER = 0.4


@dataclass(frozen=True)
class EventRing:
    """A narrow band of power after events that quiet stretches do not have."""

    frequency: float
    rms: float
    concentration: float
    events: int


def event_ring(r: np.ndarray, data: DiagnosisData, seg: Segmentation, test: np.ndarray
               ) -> EventRing | None:
    """A ring after events, found by its power spectrum rather than its phase, or None.

    A lightly damped rig mode (a fixture, an oil or air column) rung at every
    start rings at its own frequency whatever the phase it starts with; a
    velocity that shows the start a few samples late scrambles that phase, so
    the average over events (:func:`event_structure`) cancels it. Its power
    does not cancel: the periodograms (Hann window) of the held-out residual
    in the ``W`` seconds after every event (``W`` in :data:`RING_WINDOWS`;
    only windows held out whole and free of the next event) are averaged and
    compared, bin by bin, with the average over windows of the same length
    that start at least :data:`QUIET_AFTER` after an event. A bin counts when
    its event power exceeds the quiet power by more than three standard
    errors of the two averages (``1/sqrt(n)`` relative each, chi-square with 2
    degrees of freedom per window); only bins of at least :data:`RING_CYCLES`
    cycles per window are looked at (slower structure is the friction law's
    transient -- a memory's curve after a reversal -- judged by
    :func:`event_structure`). The excess power of the counting bins, as a
    share of the event windows' power times their mean square, gives the RMS
    the ring carries there; ``concentration`` is the share of that excess in
    the three adjacent bins that carry most (a ring is narrow; a misplaced
    step is broadband). The window where the ring RMS is largest is returned.
    """
    if data.steady_state:
        return None
    since, _ = seg.events(data)
    t = data.signal("t")
    dt = data.scales.dt
    starts = np.flatnonzero(since == 0.0)
    # quiet stretches, tiled by windows from the start of each run of quiet samples
    quiet_ok = test & (since >= QUIET_AFTER) & np.isfinite(since)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], quiet_ok.astype(int), [0]])))
    runs = list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))
    best = None
    for w in RING_WINDOWS:
        n = int(round(w / dt))
        if n < 16:
            continue
        ev = [int(k) for k in starts if k + n <= data.n and test[k:k + n].all()
              and np.all(since[k:k + n] == t[k:k + n] - t[k])]
        quiet = [int(k) for a, b in runs for k in range(a, b - n + 1, n)]
        if len(ev) < 8 or len(quiet) < 8:
            continue
        p_ev, p_q = _mean_periodogram(r, ev, n), _mean_periodogram(r, quiet, n)
        f = np.fft.rfftfreq(n, dt)
        margin = 3.0 * np.sqrt(1.0 / len(ev) + 1.0 / len(quiet))
        look = f >= RING_CYCLES / w
        excess = np.where(look & (p_ev > p_q * (1.0 + margin)), p_ev - p_q, 0.0)
        total = float(np.sum(p_ev))
        if total <= 0 or not np.any(excess > 0):
            continue
        ms = float(np.mean(np.concatenate([r[k:k + n] ** 2 for k in ev])))
        rms = math.sqrt(ms * float(np.sum(excess)) / total)
        top = int(np.argmax(excess))
        lo, hi = max(top - 1, 0), min(top + 2, excess.size)
        conc = float(np.sum(excess[lo:hi]) / np.sum(excess))
        found = EventRing(float(f[top]), rms, conc, len(ev))
        if best is None or found.rms > best.rms:
            best = found
    return best
