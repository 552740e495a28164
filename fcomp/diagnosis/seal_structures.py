"""Seal structures named in what the final model leaves: drift over the strokes, an end
zone, a ripple along the bore.

A residual feature (:mod:`.features`) says *what* the structure left follows;
an expert looking at a seal's record also names *which* structure it is and how
large, because each points at a cause and an experiment:

``creep`` (:func:`stroke_creep`)
    the friction level creeping up (or down) from stroke to stroke within an
    experiment -- run-in, warming, the grease redistributing (up to 20 % over ten
    strokes on the TU Delft seals): the per-stroke mean of the sign-corrected
    residual ``s*r`` in the middle of the stroke, its linear trend over the
    strokes; the change from the first to the last stroke, in newtons and as a
    share of the friction level;
``end-zone`` (:func:`end_zones`)
    a zone at an end of the stroke where the friction is higher (or lower) --
    a cushion, a tighter bore near the cap, the seal meeting a port (+4 N over
    the last 3 mm of the extended end at 7 bar): the mean of ``s*r`` over the
    last 2.5-12.5 % of the stroke, approached while sliding, against the middle
    of the stroke in the same direction, per experiment;
``experiment-level`` (:func:`experiment_levels`)
    the levels of the experiments departing from the model by different amounts --
    a session effect, a re-mounted seal, or a law in what the experiments differ by
    (the pressure) of another form than the model's: each experiment's mean ``s*r``
    in the middle of the stroke, per direction, and their spread;
``ripple`` (:func:`stroke_ripple`)
    a periodic force along the stroke -- the layers of a 3D-printed bore, a
    machining pattern (0.5 N peak to peak, 3 mm period): the residual in the
    middle of the stroke, each stroke's trend taken off, binned along ``x`` and
    searched for a narrow peak in its spectrum (periods from four bins to a
    quarter of the stroke); its amplitude by least squares on the samples.

Each is reported (:func:`seal_structures`, the JSON's ``structures``) when it
carries at least what the verdict counts as structure: a noise floor and 1.5 %
of the friction level (:class:`.verdict.VerdictRule`), the ripple half of that in
amplitude (a periodic structure counts below the noise, as a rig mode does). They
describe; they decide nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.regimes import SLIDING, Segmentation

#: End-zone widths tried, as shares of the stroke.
END_WIDTHS = (0.025, 0.05, 0.075, 0.125)
#: The middle of the stroke (each side's share left out) the end zones are compared with.
MIDDLE = 0.2
#: Fewest samples of an end zone, a stroke's middle, a ripple's profile.
MIN_SAMPLES = 30
#: A ripple's spectral peak must stand this many times above the median of its band.
RIPPLE_PROMINENCE = 20.0
#: Fewest strokes for a creep.
MIN_STROKES = 4
#: A creep's trend must stand this many standard errors from zero.
CREEP_Z = 3.0


@dataclass(frozen=True)
class SealStructure:
    """One structure named in the final residual (N, m).

    Attributes
    ----------
    name : str
        ``experiment-level``, ``creep``, ``end-zone`` or ``ripple``.
    size : N
        Its size: the change over the strokes (creep), the mean excess in the zone
        (end zone), the amplitude (ripple).
    text : str
        The structure in words, with its figures.
    figures : dict
        Its figures (SI), for the JSON.
    """

    name: str
    size: float
    text: str
    figures: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "size": float(self.size), "text": self.text,
                **self.figures}


@dataclass(frozen=True)
class _Sliding:
    """What every detector reads: the sign-corrected residual ``s*r``, the steady sliding
    samples, the middle of the stroke, the reversals (a mask) and the pressure sum."""

    v: np.ndarray
    x: np.ndarray
    sr: np.ndarray
    use: np.ndarray
    mid: np.ndarray
    reversals: np.ndarray
    psum: np.ndarray

    def parts(self) -> tuple[np.ndarray, ...]:
        """``(v, x, sr, use, mid, reversals, psum)``."""
        return self.v, self.x, self.sr, self.use, self.mid, self.reversals, self.psum

    @classmethod
    def of(cls, r: np.ndarray, data: DiagnosisData, seg: Segmentation) -> _Sliding:
        v, x = data.signal("v"), data.signal("x")
        sc = data.scales
        reversals = np.zeros(data.n, dtype=bool)
        for k, _, rev in seg.starts:
            if rev:
                reversals[k] = True
        return cls(v, x, np.sign(v) * r, seg.valid & (seg.regime == SLIDING) & (v != 0),
                   (x > sc.x_min + MIDDLE * sc.stroke) & (x < sc.x_max - MIDDLE * sc.stroke),
                   reversals, data.signal("p1") + data.signal("p2"))


def _bar(p: float) -> str:
    return f"{p / 1e5:.2g} bar"


def _where(data: DiagnosisData, i: int, psum: np.ndarray) -> str:
    e = data.experiments[i]
    at = f" at {_bar(float(np.mean(psum[e.start:e.stop])))}" if data.available.get("p1") else ""
    return f"{e.label}{at}"


def end_zones(r: np.ndarray, data: DiagnosisData, seg: Segmentation, least: float
              ) -> list[SealStructure]:
    """The largest end zone of the stroke in the sign-corrected residual (module docstring),
    per end; those of at least ``least`` newtons."""
    v, x, sr, use, mid, _, psum = _Sliding.of(r, data, seg).parts()
    sc = data.scales
    stroke = sc.stroke
    out = []
    for end, sign, name in ((sc.x_max, 1, "extended"), (sc.x_min, -1, "retracted")):
        best: tuple[float, float, int] | None = None  # (excess, width, experiment)
        for i, e in enumerate(data.experiments):
            sl = slice(e.start, e.stop)
            toward = use[sl] & (np.sign(v[sl]) == sign)
            base = toward & mid[sl]
            if base.sum() < MIN_SAMPLES:
                continue
            level = float(np.mean(sr[sl][base]))
            for w in END_WIDTHS:
                zone = toward & (np.abs(x[sl] - end) <= w * stroke)
                if zone.sum() < MIN_SAMPLES:
                    continue
                excess = float(np.mean(sr[sl][zone])) - level
                if best is None or abs(excess) > abs(best[0]):
                    best = (excess, w * stroke, i)
        if best is not None and abs(best[0]) >= least:
            excess, width, i = best
            out.append(SealStructure("end-zone", abs(excess), (
                f"friction {'higher' if excess > 0 else 'lower'} by {abs(excess):.2g} N over "
                f"the last {1e3 * width:.2g} mm of the {name} end of the stroke "
                f"({_where(data, i, psum)})"),
                {"end": name, "excess": excess, "width": width,
                 "experiment": data.experiments[i].label}))
    return out


def stroke_creep(r: np.ndarray, F_hat: np.ndarray, data: DiagnosisData, seg: Segmentation,
                 least: float) -> list[SealStructure]:
    """The level's creep from stroke to stroke (module docstring): the experiment with the
    largest significant change, if it is at least ``least`` newtons."""
    v, x, sr, use, mid, reversals, psum = _Sliding.of(r, data, seg).parts()
    best: tuple[float, float, int, int] | None = None  # (change, share, experiment, strokes)
    for i, e in enumerate(data.experiments):
        sl = slice(e.start, e.stop)
        stroke_no = np.cumsum(reversals[sl]) // 2  # a back-and-forth cycle
        pts = []
        for k in np.unique(stroke_no):
            sel = use[sl] & mid[sl] & (stroke_no == k)
            if sel.sum() >= MIN_SAMPLES:
                pts.append((float(k), float(np.mean(sr[sl][sel])),
                            float(np.mean(np.abs(F_hat[sl][sel])))))
        if len(pts) < MIN_STROKES:
            continue
        k_, m_, lev = (np.array(c) for c in zip(*pts, strict=True))
        A = np.column_stack([np.ones_like(k_), k_ - k_.mean()])
        coef, *_ = np.linalg.lstsq(A, m_, rcond=None)
        resid = m_ - A @ coef
        dof = max(len(pts) - 2, 1)
        se = math.sqrt(float(resid @ resid) / dof / max(float(np.sum((k_ - k_.mean()) ** 2)),
                                                        1e-300))
        if not abs(coef[1]) > CREEP_Z * se:
            continue
        change = float(coef[1] * (k_.max() - k_.min()))
        share = change / max(float(np.mean(lev)), 1e-12)
        if best is None or abs(change) > abs(best[0]):
            best = (change, share, i, len(pts))
    if best is None or abs(best[0]) < least:
        return []
    change, share, i, n = best
    return [SealStructure("creep", abs(change), (
        f"the friction level {'creeps up' if change > 0 else 'falls'} over the strokes by "
        f"{abs(change):.2g} N ({100 * abs(share):.0f} % of the level) from the first to the "
        f"last of {n} strokes ({_where(data, i, psum)}): run-in, warming or the grease moving "
        "-- the strokes of a record are not alike"),
        {"change": change, "share": share, "strokes": n,
         "experiment": data.experiments[i].label})]


def stroke_ripple(r: np.ndarray, data: DiagnosisData, seg: Segmentation, least: float
                  ) -> list[SealStructure]:
    """A periodic force along the stroke (module docstring), if its amplitude is at least
    ``least`` newtons."""
    if not data.available.get("x", False):
        return []
    v, x, sr, use, mid, reversals, _ = _Sliding.of(r, data, seg).parts()
    sc = data.scales
    stroke = sc.stroke
    run = np.cumsum(reversals) + 1000 * data.experiment_index()
    bin_width = max(2.0 * sc.resolution, stroke / 2000.0)
    best: tuple[float, float, float] | None = None  # (amplitude, period, prominence)
    for sign in (1, -1):
        sel = use & mid & (np.sign(v) == sign)
        if sel.sum() < 10 * MIN_SAMPLES:
            continue
        y = sr.copy()
        for k in np.unique(run[sel]):  # each stroke's own trend (creep, level) taken off
            q = sel & (run == k)
            if q.sum() >= 10:
                y[q] = sr[q] - np.polyval(np.polyfit(x[q], sr[q], 1), x[q])
        xs, ys = x[sel], y[sel]
        lo = float(xs.min())
        idx = ((xs - lo) / bin_width).astype(int)
        count = np.bincount(idx)
        total = np.bincount(idx, weights=ys)
        filled = count > 0
        if filled.sum() < MIN_SAMPLES:
            continue
        prof = np.where(filled, total / np.maximum(count, 1), 0.0)
        prof[filled] -= float(np.mean(prof[filled]))
        n = prof.size
        power = np.abs(np.fft.rfft(prof * np.hanning(n))) ** 2
        freq = np.fft.rfftfreq(n, bin_width)
        band = (freq >= 4.0 / (n * bin_width)) & (freq <= 1.0 / (4.0 * bin_width))
        if band.sum() < 8:
            continue
        j = int(np.argmax(np.where(band, power, 0.0)))
        prominence = float(power[j] / max(float(np.median(power[band])), 1e-300))
        # the period refined between the neighbouring bins of the spectrum, the amplitude by
        # least squares on the samples themselves
        amp, period = max(_sinusoid(xs, ys, 1.0 / f) for f in
                          np.linspace(freq[max(j - 1, 1)], freq[min(j + 1, freq.size - 1)], 41))
        if prominence >= RIPPLE_PROMINENCE and (best is None or amp > best[0]):
            best = (amp, period, prominence)
    if best is None or best[0] < 0.5 * least:
        return []
    amp, period, prominence = best
    return [SealStructure("ripple", amp, (
        f"a ripple along the stroke: {2 * amp:.2g} N peak to peak with a period of "
        f"{1e3 * period:.2g} mm (a pattern of the bore: print layers, machining marks)"),
        {"amplitude": amp, "period": period, "prominence": prominence})]


def experiment_levels(r: np.ndarray, data: DiagnosisData, seg: Segmentation, least: float
                      ) -> list[SealStructure]:
    """Levels that differ between experiments beyond what the model gives them (module
    docstring): each experiment's mean sign-corrected residual ``s*r`` over its steady
    sliding in the middle of the stroke, per direction; named when the experiments' means
    spread by at least ``least`` newtons (RMS about their mean)."""
    if len(data.experiments) < 2:
        return []
    v, _, sr, use, mid, _, psum = _Sliding.of(r, data, seg).parts()
    best: tuple[float, list[tuple[int, float]], str] | None = None
    for sign, name in ((1, "extending"), (-1, "retracting")):
        means = []
        for i, e in enumerate(data.experiments):
            sel = (use & mid & (np.sign(v) == sign))[e.start:e.stop]
            if sel.sum() >= MIN_SAMPLES:
                means.append((i, float(np.mean(sr[e.start:e.stop][sel]))))
        if len(means) < 2:
            continue
        m = np.array([b for _, b in means])
        spread = float(np.sqrt(np.mean((m - m.mean()) ** 2)))
        if best is None or spread > best[0]:
            best = (spread, means, name)
    if best is None or best[0] < least:
        return []
    spread, means, direction = best
    low, high = min(means, key=lambda q: q[1]), max(means, key=lambda q: q[1])
    return [SealStructure("experiment-level", spread, (
        f"the experiments' levels depart from the model by {spread:.2g} N RMS while "
        f"{direction} ({_where(data, high[0], psum)} {high[1]:+.2g} N, "
        f"{_where(data, low[0], psum)} {low[1]:+.2g} N): what changed between the experiments "
        "beyond what the model gives them -- another session, a re-mounted seal, a law of "
        "another form in what they differ by"),
        {"direction": direction, "spread": spread,
         "levels": {data.experiments[i].label: lv for i, lv in means}})]


def _sinusoid(x: np.ndarray, y: np.ndarray, period: float) -> tuple[float, float]:
    """``(amplitude, period)`` of the least-squares sinusoid of ``period`` in ``x`` through ``y``."""
    A = np.column_stack([np.sin(2 * np.pi * x / period), np.cos(2 * np.pi * x / period)])
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    return float(np.hypot(coef[0], coef[1])), float(period)


def seal_structures(r: np.ndarray, F_hat: np.ndarray, data: DiagnosisData,
                    seg: Segmentation, least: float) -> list[SealStructure]:
    """Every seal structure the residual ``r`` (N, plain) of the model ``F_hat`` carries
    (module docstring); ``least`` is the size that counts as structure (N)."""
    if data.steady_state or not data.available.get("x", False) or not least > 0:
        return []
    return [*experiment_levels(r, data, seg, least), *stroke_creep(r, F_hat, data, seg, least),
            *end_zones(r, data, seg, least), *stroke_ripple(r, data, seg, least)]


__all__ = ["SealStructure", "end_zones", "experiment_levels", "seal_structures",
           "stroke_creep", "stroke_ripple"]
