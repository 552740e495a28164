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

from dataclasses import dataclass

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
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

    ``smooth`` replaces the nearest-neighbour mean by a cubic in ``f`` (returned
    ``k`` = 0): used for time, where neighbours in time are the adjacent
    training blocks and would credit any autocorrelated residual to ``t``;
    a cubic only sees slow trends (drift).
    """
    ss = float(np.sum(r[test] ** 2))
    if ss <= 0:
        return 0.0, 0
    lo, hi = np.percentile(f[train | test], [1.0, 99.0])
    max_span = max(float(hi - lo), 1e-300) / 50.0
    best = (0.0, 0)
    for k in ((0,) if smooth else NEIGHBOURS):
        pred = np.zeros(int(test.sum()))
        rt = r[test]
        for s in (-1.0, 1.0):
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


#: Windows (s) after every start and reversal in which :func:`event_structure` looks.
EVENT_WINDOWS: tuple[float, ...] = (0.05, 0.1, 0.2)


@dataclass(frozen=True)
class EventStructure:
    """How strongly the held-out residual repeats in the window after starts and reversals."""

    window: float
    strength: float
    rms: float
    share: float


def event_structure(r: np.ndarray, data: DiagnosisData, seg: Segmentation, train: np.ndarray,
                    test: np.ndarray) -> EventStructure | None:
    """The strongest structure locked to the events (starts, reversals), or None.

    A structure that follows every start or reversal for a short time -- a rig
    mode rung by the break-away, a transient no model term describes -- is a
    small share of a whole record and escapes the record-wide strengths of
    :func:`residual_structure`. Restricted to the samples within ``w`` of the
    last start or reversal (``w`` in :data:`EVENT_WINDOWS`), the strength of
    the time since the event (:func:`strength`) and the RMS it carries there,
    ``rms_local*sqrt(strength)``, are computed; the window where that RMS is
    largest is returned.
    """
    if data.steady_state:
        return None
    side = data.signal("s")
    tsr = seg.time_since_reversal
    best = None
    for w in EVENT_WINDOWS:
        loc = tsr < w
        tl, el = train & loc, test & loc
        if el.sum() < 50 or tl.sum() < 50:
            continue
        st, _ = strength(tsr, r, side, tl, el)
        rms = float(np.sqrt(np.mean(r[el] ** 2)))
        found = EventStructure(w, st, rms * float(np.sqrt(st)), float(el.sum() / test.sum()))
        if best is None or found.rms > best.rms:
            best = found
    return best

