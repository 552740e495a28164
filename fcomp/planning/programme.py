"""The programme: the chosen primitives packed into experiments (one pressure level each,
at most ``duration_max``), joined by minimum-jerk moves, as measurement files the rig runs.

Each experiment is a :class:`fcomp.measurement.Measurement` with ``t`` (s), ``x`` (m, the
position to follow, inside ``[0, stroke]``) and ``p1`` (and ``p2`` on a double-acting rig:
the pressures to hold, Pa gauge), and a sidecar naming the rig and the design.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fcomp.measurement import Measurement
from fcomp.planning.primitives import SETTLE, Block, hold, move
from fcomp.planning.rig import Rig


@dataclass(frozen=True)
class Experiment:
    """One file of the programme: its level, its primitives, its sampled signals."""

    level: float
    blocks: tuple[Block, ...]
    signals: dict[str, np.ndarray]

    @property
    def duration(self) -> float:
        return float(self.signals["t"][-1])


def _assemble(blocks: list[Block], level: float, rig: Rig) -> dict[str, np.ndarray]:
    dt = 1.0 / rig.rate
    home = 0.5 * rig.stroke
    parts, x = [hold(SETTLE, rig)], home
    for b in blocks:
        parts += [move(b.x0 - x, rig.speed_max / 2, rig), hold(SETTLE, rig), b.v]
        x = b.x0
    parts += [move(home - x, rig.speed_max / 2, rig), hold(SETTLE, rig)]
    v = np.concatenate(parts)
    xs = home + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
    t = np.arange(v.size) * dt
    p2 = level if rig.double_acting else 0.0
    return {"t": t, "x": np.clip(xs, 0.0, rig.stroke), "v": v, "a": np.gradient(v, dt),
            "p1": np.full(v.size, level), "p2": np.full(v.size, p2)}


def pack(blocks: list[Block], rig: Rig) -> list[Experiment]:
    """The blocks grouped by pressure level (lowest first), each group cut into experiments
    no longer than ``duration_max`` (with the joining moves)."""
    out: list[Experiment] = []
    for level in sorted({b.level for b in blocks}):
        mine = sorted((b for b in blocks if b.level == level),
                      key=lambda b: (b.kind, b.speed, b.dwell, b.amplitude))
        group: list[Block] = []
        for b in mine:
            trial = _assemble([*group, b], level, rig)
            if group and trial["t"][-1] > rig.duration_max:
                out.append(Experiment(level, tuple(group), _assemble(group, level, rig)))
                group = [b]
            else:
                group.append(b)
        if group:
            out.append(Experiment(level, tuple(group), _assemble(group, level, rig)))
    return out


def described(blocks: tuple[Block, ...] | list[Block]) -> list[str]:
    """The primitives in words, repeats counted (``3 x constant-speed run ...``)."""
    counts: dict[str, int] = {}
    for b in blocks:
        counts[b.describe()] = counts.get(b.describe(), 0) + 1
    return [f"{n} x {d}" if n > 1 else d for d, n in counts.items()]


def measurement(exp: Experiment, rig: Rig, name: str, kind: str) -> Measurement:
    """The experiment as a programme file (``t``, ``x``, ``p1`` [, ``p2``])."""
    cols = {"t": exp.signals["t"], "x": exp.signals["x"], "p1": exp.signals["p1"]}
    if rig.double_acting:
        cols["p2"] = exp.signals["p2"]
    meta = {"name": name, "kind": kind, "pressure": "gauge", "rig": rig.sidecar(),
            "programme": {"generator": "fcomp design", "level": exp.level,
                          "primitives": described(exp.blocks),
                          "note": "x is the position to follow; p1 (p2) the pressure(s) to "
                                  "hold; record F (or the pressures) while running it"}}
    return Measurement(cols, meta)
