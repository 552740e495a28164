"""Motion primitives an engineer recognises, built smooth enough for a rig to follow.

Every primitive is a :class:`Block`: it starts and ends at rest, its velocity is a chain
of minimum-jerk ramps (Flash & Hogan 1985: ``v(s) = v0 + (v1 - v0)(10s^3 - 15s^4 + 6s^5)``,
so position, speed and acceleration are continuous and the peak acceleration is
``1.875*|v1 - v0|/T``), held at one pressure level:

* ``run``: out and back over a part of the stroke at a constant speed;
* ``dwell``: a slow slide, a rest of a chosen length, the reversal that breaks away;
* ``loops``: small back-and-forth moves of a chosen amplitude (pre-sliding);

:func:`candidates` spreads them over the rig's speeds, stroke parts, dwells, amplitudes and
pressure levels; the optimiser (:mod:`.optimiser`) chooses and sizes the programme from them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fcomp.planning.rig import RAMP_MIN, Rig

#: Peak acceleration of a minimum-jerk ramp per (speed change / ramp time).
MJ_PEAK = 1.875
#: Rest at the ends of a run and between moves (s).
SETTLE = 0.3
#: Distance of the slide into and out of a dwell, as a fraction of the stroke.
DWELL_SLIDE = 0.05
#: Margin kept from both ends of the stroke (fraction).
MARGIN = 0.05


def _ramp(v0: float, v1: float, T: float, dt: float) -> np.ndarray:
    n = max(int(round(T / dt)), 2)
    s = (np.arange(n) + 0.5) / n
    return v0 + (v1 - v0) * (10 * s**3 - 15 * s**4 + 6 * s**5)


def move(distance: float, speed: float, rig: Rig) -> np.ndarray:
    """The velocity samples (at the rig's rate) of a move of ``distance`` (m, signed) at
    cruise ``speed`` (m/s, capped so the ramps fit), starting and ending at rest."""
    dt = 1.0 / rig.rate
    d = abs(distance)
    if d == 0:
        return np.zeros(0)
    v = min(speed, rig.speed_max)
    Tr = max(RAMP_MIN, MJ_PEAK * v / rig.accel_max)
    if v * Tr > d:  # no room to cruise: a shorter, slower move of ramps only
        v = d / Tr
        if MJ_PEAK * v / Tr > rig.accel_max:  # never faster than the rig follows
            Tr = math.sqrt(MJ_PEAK * d / rig.accel_max)
            v = d / Tr
    up = _ramp(0.0, v, Tr, dt)
    cruise = np.full(max(int(round((d - v * Tr) / v / dt)), 0), v)
    prof = np.concatenate([up, cruise, up[::-1]])
    prof *= d / (np.sum(prof) * dt)  # the exact distance
    return math.copysign(1.0, distance) * prof


def hold(T: float, rig: Rig) -> np.ndarray:
    """Rest for ``T`` seconds."""
    return np.zeros(max(int(round(T / (1.0 / rig.rate))), 1))


@dataclass(frozen=True)
class Block:
    """One primitive: ``kind`` and its sizes (``speed`` m/s, ``span`` (x0, x1) m,
    ``dwell`` s, ``amplitude`` m, ``level`` Pa), its velocity samples from rest to rest
    (``v``) starting at ``x0``."""

    kind: str
    level: float
    x0: float
    v: np.ndarray
    speed: float = 0.0
    span: tuple[float, float] = (0.0, 0.0)
    dwell: float = 0.0
    amplitude: float = 0.0

    def describe(self) -> str:
        bar = f"{self.level / 1e5:.3g} bar"
        if self.kind == "run":
            return (f"constant-speed run at {self.speed * 1e3:.3g} mm/s over "
                    f"{self.span[0] * 1e3:.4g}-{self.span[1] * 1e3:.4g} mm, {bar}")
        if self.kind == "dwell":
            return f"reversal after a {self.dwell:.3g} s dwell at {self.x0 * 1e3:.4g} mm, {bar}"
        return f"pre-sliding loops of {self.amplitude * 1e6:.4g} um at {self.x0 * 1e3:.4g} mm, {bar}"


def run(speed: float, span: tuple[float, float], level: float, rig: Rig) -> Block:
    """Out and back over ``span`` at ``speed``, resting :data:`SETTLE` at each end."""
    d = span[1] - span[0]
    v = np.concatenate([move(d, speed, rig), hold(SETTLE, rig), move(-d, speed, rig),
                        hold(SETTLE, rig)])
    return Block("run", level, span[0], v, speed=speed, span=span)


def dwell(T: float, at: float, level: float, rig: Rig) -> Block:
    """A slow slide into ``at``, a rest of ``T`` s, then the break-away the other way and back
    (the static friction after a dwell of that length, in both directions)."""
    d = DWELL_SLIDE * rig.stroke
    slow = max(0.05 * rig.speed_max, 1e-3)
    v = np.concatenate([move(d, slow, rig), hold(T, rig), move(-d, slow, rig), hold(T, rig),
                        move(d, slow, rig), hold(SETTLE, rig), move(-d, slow, rig),
                        hold(SETTLE, rig)])
    return Block("dwell", level, at, v, speed=slow, dwell=T)


def loops(amplitude: float, at: float, level: float, rig: Rig, cycles: int = 4) -> Block:
    """``cycles`` small back-and-forth moves of ``amplitude`` around ``at`` (pre-sliding)."""
    speed = min(rig.speed_max, 4 * amplitude / RAMP_MIN)
    one = [move(amplitude, speed, rig), move(-2 * amplitude, speed, rig), move(amplitude, speed, rig)]
    v = np.concatenate([*one * cycles, hold(SETTLE, rig)])
    return Block("loops", level, at, v, amplitude=amplitude)


def speeds(rig: Rig, n: int = 6) -> list[float]:
    """``n`` speeds spread geometrically from a hundredth of the fastest to the fastest."""
    lo = max(rig.speed_max / 100.0, 1e-4)
    return list(np.geomspace(lo, rig.speed_max, n))


def candidates(rig: Rig) -> list[Block]:
    """The candidate primitives within the rig's limits (longer than half an experiment
    dropped)."""
    lo, hi = MARGIN * rig.stroke, (1 - MARGIN) * rig.stroke
    third = (hi - lo) / 3
    spans = [(lo, hi)] + [(lo + k * third, lo + (k + 1) * third) for k in range(3)]
    mid = 0.5 * rig.stroke
    out: list[Block] = []
    for level in rig.levels():
        for s in speeds(rig):
            out += [run(s, sp, level, rig) for sp in spans]
        out += [dwell(T, mid, level, rig) for T in (0.1, 0.5, 2.0, 5.0)]
        out += [loops(a * rig.stroke, mid, level, rig) for a in (1e-4, 5e-4, 2.5e-3, 1e-2)]
    limit = 0.5 * rig.duration_max * rig.rate
    return [b for b in out if b.v.size <= limit]


def signals(block: Block, rig: Rig) -> dict[str, np.ndarray]:
    """The block's sampled motion and pressures (``t``, ``x``, ``v``, ``a``, ``p1``, ``p2``)."""
    dt = 1.0 / rig.rate
    v = block.v
    x = block.x0 + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
    t = np.arange(v.size) * dt
    p2 = block.level if rig.double_acting else 0.0
    return {"t": t, "x": x, "v": v, "a": np.gradient(v, dt),
            "p1": np.full(v.size, block.level), "p2": np.full(v.size, p2)}
