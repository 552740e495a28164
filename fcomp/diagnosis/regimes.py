"""Friction regimes of a record: pre-sliding, reversal, sliding, dwell/break-away.

Every sample gets one regime, so errors can be reported per regime and the
worst places found. The segmentation reads only the motion (and, for the
presliding length, the force near reversals); its thresholds come from the
data (:class:`~fcomp.conditioning.Scales`), not from constants tuned to a rig:

``v_rest``
    speed below which the piston is at rest: the largest of five times the
    velocity noise (``1.4826*median|second difference of v|/sqrt(6)``), 2e-4
    of the speed scale, and one position-resolution step per 20 samples.
``d_pre``
    presliding length: ``Fc/sigma0`` with ``sigma0`` read off the force zero
    crossings after reversals (:func:`fcomp.conditioning.bristle_stiffness`,
    ``d_pre = dx_half/ln 2``), clamped to [2 resolutions, 5 % of the stroke].
    The force settles on the new side within about ``3*d_pre``.
``t_dwell``
    shortest rest that counts as a dwell: ``max(10*dt, 0.05 s)``.

Per sample, with the *run* the maximal stretch of motion in one direction:

* at rest: ``dwell/break-away``;
* in a run whose whole excursion stays below ``3*d_pre``: ``pre-sliding``;
* within ``3*d_pre`` of the run's start: ``dwell/break-away`` after a dwell,
  ``reversal`` after a change of direction (with or without a short stop);
* otherwise ``sliding``.

Samples up to the end of the first run that travels ``6*d_pre`` in an
experiment, and on until the piston has slid :data:`WARMUP_SLIDE` of the
stroke since it first moved, are the *warm-up*: the model's friction states
(bristle, film, contact age) start from rest while the real seal carries an
unknown history (how long it rested, where it stopped), so they are left out
of every fit and score. The bristle forgets within a few presliding lengths;
the contact age of a seal that rested before the record began is erased only
by sliding a distance no record states (0.1-1 mm for elastomer seals), and
the first break-away's dwell is unknown (at least the rest the record shows).
The warm-up never takes more than :data:`WARMUP_SHARE` of an experiment
beyond the first long run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fcomp.conditioning import bristle_stiffness
from fcomp.diagnosis.data import DiagnosisData

REGIMES: tuple[str, ...] = ("pre-sliding", "reversal", "sliding", "dwell/break-away")
PRESLIDING, REVERSAL, SLIDING, DWELL = range(4)
#: Transition zone after a start or reversal, in presliding lengths.
TRANSITION = 3.0
#: Warm-up excursion at the start of each experiment, in presliding lengths.
WARMUP = 6.0
#: Warm-up sliding distance since the first motion, as a share of the stroke.
WARMUP_SLIDE = 0.01
#: Longest warm-up beyond the first long run, as a share of the experiment's samples.
WARMUP_SHARE = 0.1
#: A held rest whose force swings by more than this many noise levels ...
UNRESOLVED_NOISE = 10.0
#: ... and this share of the friction level holds motion the position misses.
UNRESOLVED_LEVEL = 0.3


@dataclass(frozen=True)
class Segmentation:
    """Regimes and motion history of every sample (concatenated over experiments).

    Attributes
    ----------
    regime : (N,) int
        Index into :data:`REGIMES`.
    valid : (N,) bool
        Not in a warm-up (see the module docstring).
    time_since_reversal, displacement_since_reversal : (N,) s, m
        Since the last change of direction (or the experiment start).
    dwell_time : (N,) s
        Length of the rest before the current run started (0 after a reversal
        without a stop); at rest, the time at rest so far.
    v_rest, d_pre, t_dwell
        The thresholds used (m/s, m, s).
    starts : list of (index, dwell_s, reversal)
        Every run start: sample index, rest before it (s), whether it reverses.
    unresolved : int
        Samples left out because the position missed motion there
        (:func:`unresolved_rests`).
    """

    regime: np.ndarray
    valid: np.ndarray
    time_since_reversal: np.ndarray
    displacement_since_reversal: np.ndarray
    dwell_time: np.ndarray
    v_rest: float
    d_pre: float
    t_dwell: float
    starts: list[tuple[int, float, bool]]
    unresolved: int = 0

    def mask(self, name: str) -> np.ndarray:
        """Samples of regime ``name``."""
        return self.regime == REGIMES.index(name)

    def counts(self) -> dict[str, int]:
        return {r: int(np.sum(self.regime == i)) for i, r in enumerate(REGIMES)}

    def events(self, data: DiagnosisData) -> tuple[np.ndarray, np.ndarray]:
        """Time since the last event (s) and its class, for every sample.

        Events are the run starts that change the contact: a reversal (class 2)
        and a start after a rest of at least ``t_dwell`` (class 1). A start after
        a shorter pause in the same direction continues the run before it (near
        rest a noisy velocity stutters, and every stutter would restart the
        clock). Samples before their experiment's first event get ``inf`` and
        class 0.
        """
        t = data.signal("t")
        since = np.full(data.n, np.inf)
        kind = np.zeros(data.n, dtype=int)
        events = sorted((k, 2 if rev else 1) for k, dw, rev in self.starts
                        if rev or dw >= self.t_dwell)
        for e in data.experiments:
            mine = [ev for ev in events if e.start <= ev[0] < e.stop]
            for j, (k, cls) in enumerate(mine):
                stop = mine[j + 1][0] if j + 1 < len(mine) else e.stop
                since[k:stop] = t[k:stop] - t[k]
                kind[k:stop] = cls
        return since, kind


def rest_speed(v: np.ndarray, speed_scale: float, resolution: float, dt: float) -> float:
    """``v_rest`` (m/s), see the module docstring."""
    d2 = v[2:] - 2.0 * v[1:-1] + v[:-2]
    moving = np.abs(v[1:-1]) > 0
    noise = 1.4826 * float(np.median(np.abs(d2[moving]))) / math.sqrt(6.0) if moving.any() else 0.0
    return max(5.0 * noise, 2e-4 * speed_scale, resolution / (20.0 * dt))


def presliding_length(data: DiagnosisData) -> float:
    """``d_pre`` (m), see the module docstring."""
    sc = data.scales
    est = []
    for e in data.experiments:
        s = e.data.sig
        sigma0 = bristle_stiffness(s["x"], s["v"], e.data.y, sc.force)
        if sigma0 is not None and sigma0 > 0:
            est.append(sc.force / sigma0)
    d = float(np.median(est)) if est else 20.0 * sc.resolution
    return float(np.clip(d, 2.0 * sc.resolution, 0.05 * sc.stroke))


def segment(data: DiagnosisData) -> Segmentation:
    """The :class:`Segmentation` of ``data`` (see the module docstring)."""
    sc = data.scales
    n = data.n
    regime = np.full(n, SLIDING, dtype=int)
    valid = np.ones(n, dtype=bool)
    tsr = np.zeros(n)
    dsr = np.zeros(n)
    dwell = np.zeros(n)
    starts: list[tuple[int, float, bool]] = []
    if data.steady_state:
        v = data.signal("v")
        regime[np.abs(v) == 0] = DWELL
        return Segmentation(regime, valid, tsr, dsr, dwell, 0.0, 0.0, 0.0, starts)
    v_all = data.signal("v")
    v_rest = rest_speed(v_all, sc.speed, sc.resolution, sc.dt)
    d_pre = presliding_length(data)
    t_dwell = max(10.0 * sc.dt, 0.05)
    zone = TRANSITION * d_pre
    for e in data.experiments:
        s = e.data.sig
        sl = slice(e.start, e.stop)
        r, ok, a, b, c, st = _segment_one(s["t"], s["x"], s["v"], v_rest, zone, t_dwell,
                                          WARMUP * d_pre, WARMUP_SLIDE * sc.stroke)
        regime[sl], valid[sl], tsr[sl], dsr[sl], dwell[sl] = r, ok, a, b, c
        starts += [(e.start + k, dw, rev) for k, dw, rev in st]
    unresolved = unresolved_rests(data)
    valid &= ~unresolved & ~data.bridged  # samples inserted across a logger's pause: no data
    return Segmentation(regime, valid, tsr, dsr, dwell, v_rest, d_pre, t_dwell, starts,
                        int(unresolved.sum()))


def unresolved_rests(data: DiagnosisData) -> np.ndarray:
    """Samples held at rest while the force moves like friction: motion the position misses.

    Where the position shows no motion the velocity is held at zero
    (:mod:`fcomp.conditioning`), and a friction model holds its force. If the
    measured force still swings there -- its range over a held rest (2nd to
    98th percentile) exceeds both :data:`UNRESOLVED_NOISE` noise levels and
    :data:`UNRESOLVED_LEVEL` of the friction level -- the piston moved by less
    than the position resolution (a small loop, a creep) and friction followed
    it: no model can predict those samples from this position signal, so they
    are left out of every fit and score (reported as ``unresolved`` in the
    JSON ``signals``). The noise level is the robust spread of the force about
    each rest's median.
    """
    v, y = data.signal("v"), data.y
    held = v == 0.0
    out = np.zeros(data.n, dtype=bool)
    if not held.any():
        return out
    runs = []
    for e in data.experiments:
        h = held[e.start:e.stop]
        edges = np.flatnonzero(np.diff(np.concatenate([[0], h.astype(int), [0]])))
        runs += [(e.start + a, e.start + b) for a, b in zip(edges[::2], edges[1::2], strict=True)
                 if b - a >= 10]
    if not runs:
        return out
    dev = np.concatenate([y[a:b] - np.median(y[a:b]) for a, b in runs])
    noise = 1.4826 * float(np.median(np.abs(dev)))
    limit = max(UNRESOLVED_NOISE * noise, UNRESOLVED_LEVEL * data.scales.force)
    for a, b in runs:
        lo, hi = np.percentile(y[a:b], [2.0, 98.0])
        if hi - lo > limit:
            out[a:b] = True
    return out


def _segment_one(t: np.ndarray, x: np.ndarray, v: np.ndarray, v_rest: float, zone: float,
                 t_dwell: float, warmup: float, slide: float):
    n = t.size
    direction = np.where(v > v_rest, 1, np.where(v < -v_rest, -1, 0))
    regime = np.full(n, SLIDING, dtype=int)
    tsr = np.zeros(n)
    dsr = np.zeros(n)
    dwell = np.zeros(n)
    starts: list[tuple[int, float, bool]] = []
    # runs of constant direction (0 = rest)
    change = np.nonzero(np.diff(direction) != 0)[0] + 1
    bounds = [0, *change.tolist(), n]
    last_dir = 0
    t_rev, x_rev = t[0], x[0]
    rest_len = 0.0
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        d = int(direction[a])
        if d == 0:
            regime[a:b] = DWELL
            rest_len = float(t[min(b, n - 1)] - t[a])
            dwell[a:b] = t[a:b] - t[a]
            tsr[a:b] = t[a:b] - t_rev
            dsr[a:b] = np.abs(x[a:b] - x_rev)
            continue
        reversal = last_dir != 0 and d != last_dir
        if reversal or last_dir == 0:
            t_rev, x_rev = t[a - 1] if a > 0 else t[a], x[a - 1] if a > 0 else x[a]
        after_dwell = rest_len >= t_dwell
        starts.append((a, rest_len, reversal))
        disp = np.abs(x[a:b] - (x[a - 1] if a > 0 else x[a]))
        excursion = float(np.max(np.abs(x[a:b] - x_rev)))
        if excursion < zone:
            regime[a:b] = PRESLIDING
        else:
            early = disp < zone
            if after_dwell:
                regime[a:b][early] = DWELL
            elif reversal:
                regime[a:b][early] = REVERSAL
        tsr[a:b] = t[a:b] - t_rev
        dsr[a:b] = np.abs(x[a:b] - x_rev)
        dwell[a:b] = rest_len if after_dwell else 0.0
        rest_len = 0.0
        last_dir = d
    valid = np.ones(n, dtype=bool)
    end = n
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):  # warm-up: to the end of the
        if direction[a] != 0 and float(np.ptp(x[a:b])) >= warmup:  # first run of >= `warmup`
            end = b
            break
    # ... and on until the piston has slid `slide` since it first moved
    slid = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(x)) * (direction[1:] != 0))])
    far = int(np.searchsorted(slid, slide))
    valid[:min(max(end, far), end + int(WARMUP_SHARE * n))] = False
    return regime, valid, tsr, dsr, dwell, starts
