"""A logger's pauses: bridged where the motion on both sides shows what the piston did.

A pause of the logger (a time step longer than :data:`.data.GAP_FACTOR` sampling
intervals) used to start a new experiment: the model simulated from rest after it and
its warm-up left out of every fit and score, although the seal went on sliding or
resting meanwhile. Pieces after a pause lost their warm-up and their first events; a
bump along the stroke found after a cut left its residual following the displacement
since the (artificial) reversal at the cut.

Where the motion on both sides of a pause shows that the piston did not turn or start
within it, the pause is *bridged* instead (:func:`bridge`): samples at the record's
sampling interval are inserted across it, the position a cubic Hermite curve through the
positions and speeds at both ends (one direction throughout, its speed never changing
sign), the other columns linear between the ends; the friction states run across the
bridge and carry the history into the samples after it. The inserted samples are marked
(``bridged``): they are in no fit, score, noise floor or spectrum. Two motions are
bridged:

* **a rest**: the piston at rest at both ends at the same position (within two position
  steps): the bridge is a rest, and the seal ages through it as it did;
* **a slide**: the piston moving the same way at both ends, and the distance covered
  within :data:`SLIDE_TOLERANCE` of what the mean of the two speeds gives over the
  pause (a constant acceleration; plus four position steps): no stop or reversal fits
  in it.

Any other pause -- a turn, a start or a stop inside it, or a record without a position
-- still starts a new experiment.
"""

from __future__ import annotations

import math

import numpy as np

from fcomp.conditioning import resolution
from fcomp.measurement import Measurement

#: Seconds of samples (at least :data:`SIDE_MIN` of them) each side of a pause whose
#: positions give its speed there.
SIDE_SECONDS = 0.02
SIDE_MIN = 3
#: A slide's distance must match the mean speed times the pause within this share.
SLIDE_TOLERANCE = 0.1
#: Position steps a rest may move, and a slide's distance may differ, besides that share.
REST_STEPS = 2.0
SLIDE_STEPS = 4.0


def _speed(t: np.ndarray, x: np.ndarray) -> float:
    """The least-squares slope of ``x`` over ``t`` (m/s)."""
    tt = t - t.mean()
    den = float(tt @ tt)
    return float(tt @ (x - x.mean()) / den) if den > 0 else 0.0


def kind(t: np.ndarray, x: np.ndarray, i: int, interval: float, q: float) -> str | None:
    """How the pause after sample ``i`` can be bridged (``"rest"``, ``"slide"``), or None."""
    k = max(SIDE_MIN, int(math.ceil(SIDE_SECONDS / interval)))
    if i + 1 < k or t.size - (i + 1) < k:
        return None
    before, after = slice(i + 1 - k, i + 1), slice(i + 1, i + 1 + k)
    v0, v1 = _speed(t[before], x[before]), _speed(t[after], x[after])
    span = float(t[i + 1] - t[i])
    dx = float(x[i + 1] - x[i])
    still = REST_STEPS * q / (k * interval)  # a speed the position cannot tell from rest
    if abs(v0) <= still and abs(v1) <= still and abs(dx) <= REST_STEPS * q:
        return "rest"
    if abs(v0) <= still or abs(v1) <= still or v0 * v1 <= 0:
        return None
    if abs(dx - 0.5 * (v0 + v1) * span) > SLIDE_TOLERANCE * abs(dx) + SLIDE_STEPS * q:
        return None
    return "slide" if np.all(_hermite_speed(v0, v1, dx, span) * v0 > 0) else None


def _hermite_speed(v0: float, v1: float, dx: float, span: float, n: int = 64) -> np.ndarray:
    """The speed along the cubic Hermite curve of a bridge, at ``n + 1`` points."""
    s = np.linspace(0.0, 1.0, n + 1)
    d00, d10, d01, d11 = 6 * s * s - 6 * s, 3 * s * s - 4 * s + 1, -6 * s * s + 6 * s, \
        3 * s * s - 2 * s
    return (d00 * 0.0 + d10 * span * v0 + d01 * dx + d11 * span * v1) / span


def _inserted(meas: Measurement, i: int, how: str, interval: float
              ) -> dict[str, np.ndarray]:
    """The columns of the samples bridging the pause after sample ``i``."""
    t = meas.t
    t0, t1 = float(t[i]), float(t[i + 1])
    m = max(int(round((t1 - t0) / interval)) - 1, 1)
    s = np.arange(1, m + 1) / (m + 1)
    span = t1 - t0
    # a + s*(b - a): exactly a where both ends agree (a label column stays a label)
    out = {k: v[i] + s * (v[i + 1] - v[i]) for k, v in meas.columns.items()}
    out["t"] = t0 + s * span
    if "x" in meas and how == "slide":
        x = meas["x"]
        k = max(SIDE_MIN, int(math.ceil(SIDE_SECONDS / interval)))
        v0 = _speed(t[i + 1 - k:i + 1], x[i + 1 - k:i + 1])
        v1 = _speed(t[i + 1:i + 1 + k], x[i + 1:i + 1 + k])
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        out["x"] = h00 * x[i] + h10 * span * v0 + h01 * x[i + 1] + h11 * span * v1
        if "v" in meas:
            d00, d10 = 6 * s * s - 6 * s, 3 * s * s - 4 * s + 1
            d01, d11 = -6 * s * s + 6 * s, 3 * s * s - 2 * s
            out["v"] = (d00 * x[i] + d10 * span * v0 + d01 * x[i + 1] + d11 * span * v1) / span
    elif "x" in meas:  # a rest: the position held, no speed
        out["x"] = np.full(m, float(meas["x"][i]))
        if "v" in meas:
            out["v"] = np.zeros(m)
    if "a" in meas:
        a = meas["a"]
        out["a"] = np.zeros(m) if how == "rest" else a[i] + s * (a[i + 1] - a[i])
    return out


def bridge(meas: Measurement, gaps: np.ndarray, interval: float
           ) -> tuple[Measurement, np.ndarray, np.ndarray]:
    """``meas`` with its bridgeable pauses bridged (module docstring).

    ``gaps`` marks the samples a pause follows (one flag per sample, the last False).
    Returns the record with the bridges inserted, the mask of the inserted samples, and
    the flags of the pauses left (after which a new experiment starts), per sample of the
    new record.
    """
    if "x" not in meas or not gaps.any():
        return meas, np.zeros(len(meas), dtype=bool), gaps
    t, x = meas.t, meas["x"]
    q = resolution(x)
    pieces: list[dict[str, np.ndarray]] = []
    marks: list[np.ndarray] = []
    left: list[np.ndarray] = []
    start = 0
    for i in np.flatnonzero(gaps):
        how = kind(t, x, int(i), interval, q)
        if how is None:
            continue
        pieces.append({k: v[start:i + 1] for k, v in meas.columns.items()})
        marks.append(np.zeros(i + 1 - start, dtype=bool))
        left.append(gaps[start:i + 1].copy())
        left[-1][-1] = False
        inserted = _inserted(meas, int(i), how, interval)
        pieces.append(inserted)
        m = inserted["t"].size
        marks.append(np.ones(m, dtype=bool))
        left.append(np.zeros(m, dtype=bool))
        start = int(i) + 1
    if not pieces:
        return meas, np.zeros(len(meas), dtype=bool), gaps
    pieces.append({k: v[start:] for k, v in meas.columns.items()})
    marks.append(np.zeros(len(meas) - start, dtype=bool))
    left.append(gaps[start:].copy())
    cols = {k: np.concatenate([p[k] for p in pieces]) for k in meas.columns}
    return Measurement(cols, dict(meas.meta)), np.concatenate(marks), np.concatenate(left)
