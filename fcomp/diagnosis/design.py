"""The design of a record: which operating factors it varies, and which it varies together.

A friction law is a function of a few factors of the motion -- the sliding
speed, the direction of travel, the chamber pressures, the position along the
stroke. A record separates two laws only where it varies their factors apart:
a record whose every stroke runs at one speed in each direction cannot tell a
law in the speed (a Stribeck curve, a viscous slope) from a law in the direction
(a direction asymmetry); a record whose retracting speed falls as the pressure
rises (the TU Delft seals: 10.0, 7.9, 5.5, 6.5 mm/s at 1, 3, 5, 7 bar) cannot
tell a speed law from a pressure law, whatever the held-out error says -- held
out within the same experiments, both predict alike. :func:`record_design` reads
the design off the record (:class:`Design`: the levels of every factor per
experiment, and each pair varied together as a :class:`Confounding`, with the
ranges it spans and the experiment that would separate it); the search reports
the effects whose factors the design confounds as a tie
(:func:`design_ties`), and the design rides in the JSON (``design``) for the
experiment designer.

Factors (the names effects declare in :attr:`fcomp.effects.Effect.factors`):

``speed``
    the sliding speed (steady runs, per direction);
``direction``
    the direction of travel;
``pressure``
    the chamber pressure sum ``p1 + p2`` (its level per experiment);
``position``
    the position along the stroke;
``distance-since-reversal``
    the travel since the last reversal (pre-sliding, memory): on a fixed stroke the
    same thing as the position in each direction;
``experiment``
    the experiment itself (a file, a session): whatever changed between them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.regimes import SLIDING, Segmentation

FACTORS = ("speed", "direction", "pressure", "position", "distance-since-reversal",
           "experiment")
#: A direction runs at one speed in an experiment when its steady sliding speeds lie
#: within this share of their median (10th to 90th percentile).
ONE_SPEED = 0.25
#: Two speeds (or levels) differ when their ratio exceeds this.
DISTINCT = 1.2
#: Speeds follow the pressure when their correlation over the levels reaches this ...
FOLLOWS = 0.7
#: ... and they change by at least this share over the pressure range.
FOLLOWS_SPAN = 0.2
#: Pressure levels closer than this share of the pressure span (or 1 kPa) are one level.
SAME_LEVEL = 0.05
#: A stroke is fixed when every long run's reversal points lie within this share of the
#: stroke of the record's two ends.
FIXED_STROKE = 0.1
#: Fewest sliding samples of an experiment and direction to read a speed off.
MIN_SLIDING = 30
DIRECTIONS = ("extending", "retracting")


@dataclass(frozen=True)
class Confounding:
    """Two factors a record varies together (so laws in them give the same force there).

    Attributes
    ----------
    factors : (str, str)
        The two factors (:data:`FACTORS`).
    why : str
        What the record does, in words with its figures.
    over : dict
        Factor -> ``[low, high]`` (SI) over which they are varied together.
    separates : str
        The experiment that would separate them.
    """

    factors: tuple[str, str]
    why: str
    over: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    separates: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"factors": list(self.factors), "why": self.why,
                "over": {k: [float(a), float(b)] for k, (a, b) in self.over.items()},
                "separates": self.separates}


@dataclass(frozen=True)
class Design:
    """The operating factors of a record (SI units) and those it varies together.

    Attributes
    ----------
    experiments : tuple of str
        Experiment labels, in the order of the per-experiment values.
    pressure : tuple of float
        Mean ``p1 + p2`` (Pa, gauge) of each experiment's moving samples.
    pressure_levels : tuple of float
        The distinct pressure levels (Pa).
    speed : dict
        ``"extending"``/``"retracting"`` -> the median steady sliding speed (m/s, > 0)
        of each experiment in that direction (nan where it does not slide that way).
    one_speed : bool
        Every experiment runs at one speed in each direction.
    stroke : (float, float)
        The position range of the motion (m, 1st to 99th percentile).
    fixed_stroke : bool
        Every run reverses within :data:`FIXED_STROKE` of the stroke's ends: position
        and distance since the reversal are the same feature.
    confounded : tuple of Confounding
    """

    experiments: tuple[str, ...]
    pressure: tuple[float, ...]
    pressure_levels: tuple[float, ...]
    speed: Mapping[str, tuple[float, ...]]
    one_speed: bool
    stroke: tuple[float, float]
    fixed_stroke: bool
    confounded: tuple[Confounding, ...] = ()

    def confounds(self, a: str, b: str) -> Confounding | None:
        """The confounding of factors ``a`` and ``b`` (either order), or None."""
        for c in self.confounded:
            if {a, b} == set(c.factors):
                return c
        return None

    def speed_levels(self, direction: str) -> list[float]:
        """The distinct speeds (m/s) the record slides at in ``direction``."""
        return _levels([s for s in self.speed.get(direction, ()) if math.isfinite(s)],
                       relative=DISTINCT - 1.0)

    def to_dict(self) -> dict[str, Any]:
        """JSON values (the diagnosis JSON's ``design``)."""
        return {
            "experiments": list(self.experiments),
            "pressure": [float(p) for p in self.pressure],
            "pressure_levels": [float(p) for p in self.pressure_levels],
            "speed": {d: [None if not math.isfinite(s) else float(s) for s in v]
                      for d, v in self.speed.items()},
            "speed_levels": {d: [float(s) for s in self.speed_levels(d)] for d in self.speed},
            "one_speed_per_direction": self.one_speed,
            "stroke": [float(self.stroke[0]), float(self.stroke[1])],
            "fixed_stroke": self.fixed_stroke,
            "confounded": [c.to_dict() for c in self.confounded],
            "units": {"pressure": "Pa", "speed": "m/s", "stroke": "m"},
        }


def _levels(values: Sequence[float], *, relative: float = 0.0, absolute: float = 0.0
            ) -> list[float]:
    """The distinct levels of ``values`` (sorted): neighbours closer than ``absolute`` or
    ``relative`` of the larger are one level (their mean)."""
    out: list[list[float]] = []
    for v in sorted(values):
        if out and (v - out[-1][-1] <= absolute or
                    v - out[-1][-1] <= relative * max(abs(v), abs(out[-1][-1]))):
            out[-1].append(v)
        else:
            out.append([v])
    return [float(np.mean(g)) for g in out]


def _bar(p: float) -> str:
    return f"{p / 1e5:.3g} bar"


def _mm_s(v: float) -> str:
    return f"{1e3 * v:.3g} mm/s"


def record_design(data: DiagnosisData, seg: Segmentation) -> Design:
    """The :class:`Design` of a record (module docstring)."""
    v = data.signal("v")
    psum = data.signal("p1") + data.signal("p2")
    sliding = (seg.regime == SLIDING) & seg.valid & (v != 0)
    labels, pressure = [], []
    speed: dict[str, list[float]] = {d: [] for d in DIRECTIONS}
    spread_ok = True
    for e in data.experiments:
        sl = slice(e.start, e.stop)
        labels.append(e.label)
        moving = v[sl] != 0
        pressure.append(float(np.mean(psum[sl][moving])) if moving.any()
                        else float(np.mean(psum[sl])))
        for d, sign in zip(DIRECTIONS, (1, -1), strict=True):
            m = sliding[sl] & (np.sign(v[sl]) == sign)
            if m.sum() < MIN_SLIDING:
                speed[d].append(math.nan)
                continue
            s = np.abs(v[sl][m])
            med = float(np.median(s))
            p10, p90 = np.percentile(s, [10.0, 90.0])
            speed[d].append(med)
            if (p90 - p10) > 2.0 * ONE_SPEED * med:
                spread_ok = False
    sc = data.scales
    span = max(float(np.ptp(pressure)) if pressure else 0.0, 0.0)
    levels = _levels(pressure, absolute=max(1000.0, SAME_LEVEL * span)) \
        if data.available.get("p1", False) else _levels(pressure[:1])
    stroke = (sc.x_min, sc.x_max)
    fixed = _fixed_stroke(data, seg) if data.available.get("x", False) else False
    design = Design(tuple(labels), tuple(pressure), tuple(levels),
                    {d: tuple(s) for d, s in speed.items()}, spread_ok, stroke, fixed)
    conf = _confoundings(design, data)
    return Design(design.experiments, design.pressure, design.pressure_levels, design.speed,
                  design.one_speed, design.stroke, design.fixed_stroke, tuple(conf))


#: The shape of the Stribeck curve: what a record sliding at one speed per direction cannot
#: determine (its exponent and form; the level and the speed stay free).
STRIBECK_SHAPE = ("n", "kappa_s")


def held_by_design(design: Design) -> dict[str, str]:
    """Parameters the design cannot determine -> why: held at their model values in every
    fit of the diagnosis (:meth:`.refit.Refit.keep`).

    A record that slides at one speed in each direction samples the Stribeck curve at
    two speeds and in the turns; the curve's exponent and form then shape only the
    turns, where the bristle and the pressure channel act too, and a free exponent runs
    to the edge of its box (``n`` = 6 on the TU Delft seals) to make the curve a step
    between the two speeds -- a direction asymmetry in disguise. They are held
    (``n`` at its model value, 2 for an exponential curve; ``kappa_s`` at 0).
    """
    if not design.one_speed:
        return {}
    return {name: ("held: the record slides at one speed in each direction, so the "
                   "Stribeck curve's shape between the speeds it never slides at is not "
                   "the record's to tell (constant-speed runs at several speeds would "
                   "determine it)") for name in STRIBECK_SHAPE}


def _fixed_stroke(data: DiagnosisData, seg: Segmentation) -> bool:
    """Whether every long run reverses near the stroke's two ends (:data:`FIXED_STROKE`)."""
    sc = data.scales
    x = data.signal("x")
    tol = FIXED_STROKE * sc.stroke
    ends = [k for k, _, rev in seg.starts if rev]
    if len(ends) < 3:
        return False
    at = x[np.clip(np.array(ends) - 1, 0, x.size - 1)]
    near = (np.abs(at - sc.x_min) <= tol) | (np.abs(at - sc.x_max) <= tol)
    return bool(np.mean(near) >= 0.9)


def _confoundings(d: Design, data: DiagnosisData) -> list[Confounding]:
    out: list[Confounding] = []
    ext, ret = (np.array(d.speed[k], dtype=float) for k in DIRECTIONS)
    both = np.isfinite(ext) & np.isfinite(ret)
    # speed <-> direction: one speed per direction in every experiment, the two apart
    if d.one_speed and both.any():
        ratio = np.maximum(ext[both], ret[both]) / np.minimum(ext[both], ret[both])
        if np.mean(ratio > DISTINCT) >= 0.5:
            out.append(Confounding(
                ("speed", "direction"),
                f"each experiment runs at one speed in each direction (extending "
                f"{_range(ext)}, retracting {_range(ret)}): a law in the speed and a law in "
                "the direction give the same force",
                {"extending speed": _span(ext), "retracting speed": _span(ret)},
                "constant-speed runs at two or more speeds in each direction, at one "
                "pressure level" if data.available.get("p1", False) else
                "constant-speed runs at two or more speeds in each direction"))
    # speed <-> pressure: the speed of a direction changes with the pressure level
    if d.one_speed and len(d.pressure_levels) >= 2:
        p = np.array(d.pressure, dtype=float)
        for name, s in zip(DIRECTIONS, (ext, ret), strict=True):
            ok = np.isfinite(s)
            if ok.sum() < 2 or np.ptp(p[ok]) <= 0:
                continue
            change = float(np.ptp(s[ok]) / np.max(s[ok]))
            r = float(np.corrcoef(p[ok], s[ok])[0, 1]) if ok.sum() >= 3 and np.ptp(s[ok]) > 0 \
                else math.copysign(1.0, float(s[ok][-1] - s[ok][0]))
            if change >= FOLLOWS_SPAN and abs(r) >= FOLLOWS:
                pairs = sorted(zip(p[ok], s[ok], strict=True))
                out.append(Confounding(
                    ("speed", "pressure"),
                    f"the {name} speed {'falls' if r < 0 else 'rises'} with the pressure ("
                    + ", ".join(f"{_mm_s(sv)} at {_bar(pv)}" for pv, sv in pairs)
                    + "): a law in the speed reproduces levels that change with the pressure",
                    {"pressure": (float(p[ok].min()), float(p[ok].max())),
                     f"{name} speed": _span(s)},
                    f"the same {name} speed at every pressure level (or two speeds at one "
                    "level)"))
                break
    # pressure <-> experiment: each experiment holds one pressure level
    if len(d.pressure_levels) >= 2 and data.available.get("p1", False):
        within = _pressure_within(data)
        if not within:
            out.append(Confounding(
                ("pressure", "experiment"),
                f"each experiment holds one pressure level ({len(d.pressure_levels)} levels, "
                f"{_bar(min(d.pressure_levels))} to {_bar(max(d.pressure_levels))}): a "
                "change of the rig between experiments (a re-mounted seal, another day's "
                "temperature) looks like a pressure law",
                {"pressure": (min(d.pressure_levels), max(d.pressure_levels))},
                "a pressure level recorded twice, in separate sessions, or the pressure "
                "stepped within one experiment"))
    if d.fixed_stroke:
        out.append(Confounding(
            ("position", "distance-since-reversal"),
            f"every run reverses at the ends of one stroke ({1e3 * d.stroke[0]:.3g} to "
            f"{1e3 * d.stroke[1]:.3g} mm): the position and the distance since the "
            "reversal are one feature in each direction",
            {"position": d.stroke},
            "strokes of two or more lengths, or reversals at several places along the "
            "stroke"))
    return out


def _pressure_within(data: DiagnosisData) -> bool:
    """Whether some experiment varies the pressure sum by more than a tenth of the span."""
    psum = data.signal("p1") + data.signal("p2")
    span = float(np.percentile(psum, 99.0) - np.percentile(psum, 1.0))
    for e in data.experiments:
        p = psum[e.start:e.stop]
        if p.size and float(np.percentile(p, 95.0) - np.percentile(p, 5.0)) > 0.1 * span:
            return True
    return False


def _span(s: np.ndarray) -> tuple[float, float]:
    ok = s[np.isfinite(s)]
    return (float(ok.min()), float(ok.max())) if ok.size else (math.nan, math.nan)


def _range(s: np.ndarray) -> str:
    lo, hi = _span(s)
    if not math.isfinite(lo):
        return "none"
    return _mm_s(lo) if hi <= DISTINCT * lo else f"{_mm_s(lo)} to {_mm_s(hi)}"


__all__ = ["FACTORS", "STRIBECK_SHAPE", "Confounding", "Design", "held_by_design",
           "record_design"]
