"""Alternative motions as consistent with the measured position (:func:`motion_ensemble`),
and the timing of held stretches and turns."""

from __future__ import annotations

import numpy as np

from fcomp.conditioning.motion import Conditioning, Motion, condition_motion
from fcomp.conditioning.position import REST_NOISE_BAND, analog_noise
from fcomp.reconstruction import smooth

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

