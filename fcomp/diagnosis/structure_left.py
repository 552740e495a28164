"""What the structure left in the final residual follows, how large it is, and which
experiment would tell more.

A verdict of ``unexplained-structure`` (:mod:`.verdict`) says *that* the final
model leaves structure; this module says *what* it follows, in figures an
engineer can act on and a program (the next experiment's designer) can read:

* for every residual feature (:mod:`.features`; time, pressure sum, position,
  time and displacement since the last reversal -- the pre-sliding excursion --,
  speed, acceleration, dwell time) its held-out strength, the RMS it carries
  (N), its *own* strength once the features ranked above it are taken out
  (features that are one phase on a periodic stroke, position and displacement
  since reversal, are one finding, not two), its shape (binned means of the
  direction-signed residual, and a size in the feature's terms: the level change
  over the record, per bar, along the stroke, within the first milliseconds after
  a reversal), the range the record covers, and the experiment that varies it;
* for structure locked to the events (:func:`.features.event_structure`,
  :func:`.features.event_ring`) and for periodic disturbances
  (:mod:`.disturbance`): the time since the event or the line's frequency;
* the structure's size against the noise floor.

Each feature's experiment is data (:data:`STRUCTURES`: what to vary, over which
range, and why), so a feature added beside these (a stroke count, a distance to
the end of the stroke) brings its own words by adding an entry.

Sources: the residual-feature strengths are those of :mod:`.features` (a
k-nearest-neighbour mean fitted on the training residual, scored on the
held-out one; a cubic for time).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.disturbance import Disturbance
from fcomp.diagnosis.features import (
    NEIGHBOURS,
    FeatureStrength,
    feature_values,
    knn_predict,
    poly_predict,
)
from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.regimes import Segmentation
from fcomp.diagnosis.verdict import Verdict


@dataclass(frozen=True)
class Quantity:
    """A residual feature as the structure report words it.

    Attributes
    ----------
    words
        What it is, in words (``"time"``, ``"the pressure sum p1 + p2"``).
    unit
        Its SI unit.
    vary
        What an experiment must vary to tell more (a key the experiment designer
        reads: ``time``, ``pressure``, ``position``, ``reversal``, ``excursion``,
        ``speed``, ``acceleration``, ``dwell``, ``event``, ``line``).
    experiment
        The experiment that would tell more, in words.
    """

    words: str
    unit: str
    vary: str
    experiment: str


#: Feature -> how the structure report words it and which experiment varies it. A feature
#: added to the residual features brings an entry here.
STRUCTURES: dict[str, Quantity] = {
    "t": Quantity(
        "time", "s", "time",
        "repeat one identical motion at the start, the middle and the end of a session and "
        "after the rig has rested cold: a friction level that changes between identical "
        "repeats is a drift (temperature, seal swelling, run-in), not a law of the motion"),
    "p1+p2": Quantity(
        "the pressure sum p1 + p2", "Pa", "pressure",
        "record identical motions at three or more chamber pressure levels, in both "
        "directions and at two speeds at each level, so that pressure is not confounded "
        "with speed or direction"),
    "x": Quantity(
        "the position x", "m", "position",
        "record slow constant-speed strokes over the whole stroke in both directions, and "
        "the same motion shifted along the stroke: a structure fixed in position belongs to "
        "the bore or the rod"),
    "v": Quantity(
        "the speed v", "m/s", "speed",
        "record constant-speed runs at eight or more speeds spread over two decades, in "
        "both directions"),
    "a": Quantity(
        "the acceleration a", "m/s^2", "acceleration",
        "record runs to one cruise speed with ramps of three or more lengths (the same "
        "speeds reached at different accelerations)"),
    "time_since_reversal": Quantity(
        "the time since the last reversal", "s", "reversal",
        "record reversals at several rates, with and without a hold at the turn: a "
        "transition that lasts a fixed time is a lag or a rig mode, one that lasts a fixed "
        "distance is pre-sliding"),
    "displacement_since_reversal": Quantity(
        "the pre-sliding excursion (displacement since the last reversal)", "m",
        "excursion",
        "record small displacement cycles of growing amplitude, with nested minor loops, at "
        "two rates: the force-displacement curve after a reversal and its memory of earlier "
        "reversal points"),
    "dwell_time": Quantity(
        "the dwell time before the start", "s", "dwell",
        "record starts after dwells of 0.1, 0.3, 1, 3 and 10 s, each repeated, in both "
        "directions"),
    "time_since_event": Quantity(
        "the time since the last start or reversal", "s", "event",
        "record starts and reversals at a higher sample rate, and a tap or step test of the "
        "rig at rest: structure locked to the events is a transition the model lacks or a "
        "rig mode the events ring"),
    "line": Quantity(
        "a fixed frequency, whatever the piston does", "Hz", "line",
        "record the force with the piston at rest and the pump, fan or valve dither running, "
        "then switched off: a line that stays is the rig's, not friction"),
}

#: A feature is listed when its own strength (after the features above it) reaches this
#: share of the verdict's structure threshold ...
LIST_SHARE = 0.5
#: ... and the RMS it carries this share of the verdict's least structure (N).
LIST_RMS = 0.5
#: Bins of a feature's shape.
BINS = 8
#: Most features listed.
MOST = 4


@dataclass(frozen=True)
class Follows:
    """One thing the structure left follows (SI units; N for forces).

    ``strength`` is the share of the held-out residual's mean square a smooth function
    of the feature explains, ``own`` that share once the features listed before it are
    taken out; ``rms`` the RMS it carries (N); ``change`` the size of its shape (N:
    peak to peak of the binned means of the direction-signed residual, or the level
    change a trend in time brings over the record); ``per`` and ``slope`` a trend
    (``slope`` N per ``per``); ``covered`` the range the record covers;
    ``bins``/``means`` the shape.
    """

    feature: str
    strength: float
    own: float
    rms: float
    change: float
    covered: tuple[float, float]
    bins: tuple[float, ...] = ()
    means: tuple[float, ...] = ()
    slope: float | None = None
    per: str = ""
    note: str = ""

    @property
    def quantity(self) -> Quantity:
        return STRUCTURES.get(self.feature, Quantity(self.feature, "", self.feature,
                                                     f"record the motion varying {self.feature}"))

    def to_dict(self) -> dict[str, Any]:
        q = self.quantity
        return {"feature": self.feature, "words": q.words, "unit": q.unit,
                "strength": round(self.strength, 4), "own_strength": round(self.own, 4),
                "rms": _num(self.rms), "change": _num(self.change),
                "slope": None if self.slope is None else _num(self.slope),
                "slope_per": self.per or None,
                "covered": [_num(self.covered[0]), _num(self.covered[1])],
                "shape": {"bins": [_num(b) for b in self.bins],
                          "mean": [_num(m) for m in self.means]},
                "vary": q.vary, "experiment": q.experiment, "note": self.note or None}


@dataclass(frozen=True)
class StructureLeft:
    """What the final residual's structure follows (:func:`structure_left`).

    ``present`` is the verdict's ``unexplained-structure``; ``follows`` the features it
    follows, strongest own share first (at least one when it is present: the strongest,
    however weak, with a note); ``rms``/``floor``/``excess`` the held-out RMS, the noise
    floor and the excess ``sqrt(rms^2 - floor^2)`` (N).
    """

    present: bool
    cause: str
    rms: float
    floor: float
    excess: float
    follows: tuple[Follows, ...] = ()
    strengths: tuple[FeatureStrength, ...] = field(default=(), repr=False)

    @property
    def experiments(self) -> list[dict[str, str]]:
        """The experiments that would tell more, one per distinct quantity, in order."""
        out: dict[str, dict[str, str]] = {}
        for f in self.follows:
            q = f.quantity
            out.setdefault(q.vary, {"vary": q.vary, "because": f.feature,
                                    "experiment": q.experiment})
        return list(out.values())

    def to_dict(self) -> dict[str, Any]:
        return {"present": self.present, "cause": self.cause, "rms": _num(self.rms),
                "noise_floor": _num(self.floor), "excess": _num(self.excess),
                "follows": [f.to_dict() for f in self.follows],
                "next_experiments": self.experiments}

    def sentence(self) -> str:
        """One line: what the structure follows, with its size (empty when nothing does)."""
        if not self.follows:
            return ""
        parts = [describe(f) for f in self.follows[:2]]
        return "; ".join(parts)


def _num(x: float) -> float | None:
    return float(x) if x is not None and math.isfinite(x) else None


def describe(f: Follows) -> str:
    """``f`` in words with its figures (a clause)."""
    q = f.quantity
    size = f"strength {f.strength:.2f}, {f.rms:.3g} N RMS"
    if f.slope is not None and f.per:
        shape = f"{f.slope:+.3g} N per {f.per}, {f.change:.3g} N over the record"
    elif f.feature in ("time_since_event", "line"):
        shape = f.note
    else:
        shape = f"{f.change:.3g} N peak to peak of its binned means"
    text = f"{q.words} ({size}; {shape})"
    if f.note and f.feature not in ("time_since_event", "line"):
        text += f" -- {f.note}"
    return text


def _prediction(f: np.ndarray, r: np.ndarray, side: np.ndarray, train: np.ndarray,
                where: np.ndarray, k: int, smooth: bool) -> np.ndarray:
    """The smooth function of ``f`` (per side) fitted on the training residual, at ``where``."""
    pred = np.zeros(int(where.sum()))
    lo, hi = np.percentile(f[train | where], [1.0, 99.0])
    span = max(float(hi - lo), 1e-300) / 50.0
    for s in np.unique(side[where]):
        tr = train & (side == s)
        here = side[where] == s
        if tr.sum() < max(k, 10) or not here.any():
            continue
        if smooth:
            pred[here] = poly_predict(f[tr], r[tr], f[where][here])
        else:
            pred[here] = knn_predict(f[tr], r[tr], f[where][here], k, span)
    return pred


def _explained(f: np.ndarray, r: np.ndarray, side: np.ndarray, train: np.ndarray,
               test: np.ndarray, smooth: bool) -> tuple[float, int]:
    """Held-out strength of ``f`` for ``r`` and its best ``k`` (as :func:`.features.strength`)."""
    ss = float(np.sum(r[test] ** 2))
    if ss <= 0:
        return 0.0, 0
    best = (0.0, 0)
    for k in ((0,) if smooth else NEIGHBOURS):
        pred = _prediction(f, r, side, train, test, k, smooth)
        val = 1.0 - float(np.sum((r[test] - pred) ** 2)) / ss
        if val > best[0]:
            best = (val, k)
    return max(best[0], 0.0), best[1]


def _shape(name: str, f: np.ndarray, r: np.ndarray, s: np.ndarray, test: np.ndarray,
           data: DiagnosisData) -> tuple[tuple[float, ...], tuple[float, ...], float,
                                         float | None, str]:
    """Binned means of the direction-signed residual against ``f`` (held-out samples), their
    peak to peak (N), and for time and pressure a trend: slope (N per ``per``)."""
    fs_, rs = f[test], (s * r)[test]
    moving = s[test] != 0
    fs_, rs = fs_[moving], rs[moving]
    if fs_.size < 2 * BINS:
        return (), (), 0.0, None, ""
    edges = np.unique(np.percentile(fs_, np.linspace(0.0, 100.0, BINS + 1)))
    if edges.size < 3:
        return (), (), 0.0, None, ""
    idx = np.clip(np.searchsorted(edges, fs_, side="right") - 1, 0, edges.size - 2)
    count = np.bincount(idx, minlength=edges.size - 1)
    total = np.bincount(idx, weights=rs, minlength=edges.size - 1)
    centre = np.bincount(idx, weights=fs_, minlength=edges.size - 1)
    ok = count >= 5
    means = total[ok] / count[ok]
    bins = centre[ok] / count[ok]
    change = float(np.ptp(means)) if means.size else 0.0
    slope, per = None, ""
    if name in ("t", "p1+p2") and fs_.size > 10 and float(np.ptp(fs_)) > 0:
        # a level trend: least squares of the signed residual on the feature
        c = np.polyfit(fs_, rs, 1)
        unit = 1.0 if name == "t" else 1e5
        slope = float(c[0]) * unit
        per = "s" if name == "t" else "bar"
        change = abs(float(c[0])) * float(np.ptp(f[np.isfinite(f)]))
    return tuple(map(float, bins)), tuple(map(float, means)), change, slope, per


def structure_left(fit: FitResult, data: DiagnosisData, seg: Segmentation, train: np.ndarray,
                   test: np.ndarray, verdict: Verdict,
                   lines: Sequence[Disturbance] = ()) -> StructureLeft:
    """What the structure in ``fit``'s held-out residual follows (module docstring).

    Features are ranked by the verdict's strengths (:attr:`.verdict.Verdict.features`);
    each one after the first is scored again on the residual with the smooth functions
    of the features listed before it taken out (its *own* strength), and listed while
    that share and the RMS it carries reach :data:`LIST_SHARE` and :data:`LIST_RMS` of
    the verdict's thresholds, at most :data:`MOST`. A structure locked to the events
    and periodic lines are listed as the time since the event and a line.
    """
    rule = verdict.rule
    present = verdict.verdict != "explained"
    rms = verdict.rms_final
    floor = verdict.noise
    excess = math.sqrt(max(rms * rms - floor * floor, 0.0))
    r = fit.located
    side = data.signal("s")
    values = feature_values(data, seg)
    out: list[Follows] = []
    taken = np.zeros(data.n)
    least_share = LIST_SHARE * rule.structure_min
    least_rms = LIST_RMS * verdict.least
    for fsr in verdict.features:
        if len(out) >= MOST or fsr.feature not in values:
            break
        f = values[fsr.feature]
        smooth = fsr.feature == "t"
        if out:
            rest = r - taken
            own, k = _explained(f, rest, side, train, test, smooth)
        else:
            own, k = fsr.strength, fsr.neighbours
        carried = rms * math.sqrt(max(own, 0.0))
        if out and (own < least_share or carried < least_rms):
            continue
        if not out and not present and (fsr.strength < rule.structure_min
                                        or carried < verdict.least):
            break  # explained: nothing to name
        where = train | test
        taken = taken.copy()
        taken[where] += _prediction(f, r - (taken if out else 0.0), side, train, where, k,
                                    smooth)
        bins, means, change, slope, per = _shape(fsr.feature, f, r, side, test, data)
        finite = f[np.isfinite(f)]
        covered = (float(np.min(finite)), float(np.max(finite))) if finite.size else \
            (math.nan, math.nan)
        note = "" if fsr.strength >= rule.structure_min or out else (
            "no single feature explains the structure: this is the strongest")
        out.append(Follows(fsr.feature, fsr.strength, own, rms * math.sqrt(max(fsr.strength,
                                                                                0.0)),
                           change, covered, bins, means, slope, per, note))
    ev, ring = verdict.event, verdict.ring
    if verdict.cause in ("event-repeats", "event-excess") and ev is not None:
        carried = ev.rms if verdict.cause == "event-repeats" else verdict.event_excess
        out.insert(0, Follows("time_since_event", ev.strength, ev.strength, carried, carried,
                              (0.0, ev.window), note=(
                                  f"within {1e3 * ev.window:.0f} ms of every start and "
                                  f"reversal, {carried:.3g} N RMS there")))
    elif verdict.cause == "ring" and ring is not None:
        out.insert(0, Follows("time_since_event", 0.0, 0.0, ring.rms, ring.rms,
                              (0.0, 0.2), note=(f"a ring at {ring.frequency:.3g} Hz after "
                                                f"starts and reversals, {ring.rms:.3g} N RMS "
                                                "there")))
    for d in lines:
        out.append(Follows("line", 0.0, 0.0, d.rms, 2.0 * d.amplitude,
                           (d.frequency_hz, d.frequency_hz),
                           note=f"a line at {d.frequency_hz:.4g} Hz, {d.amplitude:.3g} N "
                                "amplitude, taken off the force"))
    return StructureLeft(present, verdict.cause, rms, floor, excess, tuple(out),
                         tuple(verdict.features))


def follows_from_doc(doc: Mapping[str, Any]) -> list[Mapping[str, Any]]:
    """The ``follows`` entries of a diagnosis JSON's ``structure_left`` (empty without)."""
    left = doc.get("structure_left") or {}
    return list(left.get("follows") or [])
