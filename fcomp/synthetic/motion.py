"""Motion plans: what the rig does during a record, on the fine integration grid.

Per experiment (seeded): smooth slides at speeds spread over two decades,
reversals with and without a stop, dwells from 0.05 s to 3 s, small
displacement loops (presliding), sinusoidal sweeps, and a change of the
pressure-sum level half way. Every move has raised-cosine speed ramps, so
velocity and acceleration are known exactly (no differentiation).

Two plans (:data:`MOTIONS`, :func:`plan_record`'s ``motion``): ``"standard"``
(:func:`schedule`, the original generator's) and ``"presliding"``
(:func:`schedule_presliding`): many small displacement cycles at several
frequencies, and only a few slides of about 20 mm -- a record dominated by
presliding, as a positioning rig holding a load or a valve spool dithering
around a set point produces.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from fcomp.errors import FcompError


@dataclass
class Plan:
    """Piecewise motion on the fine grid: velocity, acceleration, pressure sum."""

    dt: float
    x0: float
    stroke: float
    v: list[np.ndarray] = field(default_factory=list)
    a: list[np.ndarray] = field(default_factory=list)
    S: list[np.ndarray] = field(default_factory=list)
    x: float = 0.0
    level: float = 3e5

    def __post_init__(self) -> None:
        self.x = self.x0

    @property
    def duration(self) -> float:
        return sum(seg.size for seg in self.v) * self.dt

    def _push(self, v: np.ndarray, a: np.ndarray) -> None:
        self.v.append(v)
        self.a.append(a)
        self.S.append(np.full(v.size, self.level))
        self.x += float(np.sum(v) * self.dt)

    def dwell(self, T: float) -> None:
        n = max(1, int(round(T / self.dt)))
        self._push(np.zeros(n), np.zeros(n))

    def move(self, d: float, V: float, t_ramp: float) -> None:
        """A smooth move of signed distance ``d`` at cruise speed ``V`` (raised-cosine ramps)."""
        d = float(np.clip(self.x + d, 0.03 * self.stroke, 0.97 * self.stroke) - self.x)
        dist = abs(d)
        if dist < 1e-6:
            return
        V = min(V, dist / t_ramp)  # short moves: triangular-ish profile
        T = dist / V + t_ramp
        n = max(4, int(round(T / self.dt)))
        t = (np.arange(n) + 0.5) * self.dt
        T = n * self.dt
        u_up = np.clip(t / t_ramp, 0.0, 1.0)
        u_dn = np.clip((T - t) / t_ramp, 0.0, 1.0)
        shape = np.minimum(0.5 * (1 - np.cos(np.pi * u_up)), 0.5 * (1 - np.cos(np.pi * u_dn)))
        dshape = np.where(
            u_up < u_dn,
            np.where(t < t_ramp, 0.5 * np.pi / t_ramp * np.sin(np.pi * u_up), 0.0),
            np.where(T - t < t_ramp, -0.5 * np.pi / t_ramp * np.sin(np.pi * u_dn), 0.0),
        )
        scale = dist / (np.sum(shape) * self.dt)  # hit the distance exactly
        s = math.copysign(1.0, d)
        self._push(s * scale * shape, s * scale * dshape)

    def loops(self, A: float, f: float, cycles: int) -> None:
        """``x = x0 + s*A*(1 - cos(2*pi*f*t))``: closed displacement cycles starting at rest."""
        s = 1.0 if self.x < 0.5 * self.stroke else -1.0
        n = max(8, int(round(cycles / f / self.dt)))
        t = (np.arange(n) + 0.5) * self.dt
        w = 2 * np.pi * cycles / (n * self.dt)
        self._push(s * A * w * np.sin(w * t), s * A * w * w * np.cos(w * t))

    def pressure(self, level: float, tau: float = 0.15) -> None:
        """Change the pressure sum during a 1 s dwell (first-order transition, ``tau`` s)."""
        n = max(1, int(round(1.0 / self.dt)))
        t = (np.arange(n) + 0.5) * self.dt
        S = level + (self.level - level) * np.exp(-t / tau)
        self.v.append(np.zeros(n))
        self.a.append(np.zeros(n))
        self.S.append(S)
        self.level = level


#: Speed classes (m/s) the slides cycle through, so every record spans two decades.
SPEED_CLASSES = ((0.003, 0.015), (0.015, 0.06), (0.06, 0.25))
#: Dwell classes (s) before the dwell-slides, alternating short and long.
DWELL_CLASSES = ((0.1, 0.4), (0.8, 3.0))
MOTION_KINDS = ("slide", "reverse", "dwell-slide", "loops", "sweep")



def log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    """A draw uniform in ``ln`` between ``lo`` and ``hi``."""
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))

def schedule(plan: Plan, rng: np.random.Generator, duration: float, levels: Sequence[float],
             a_max: float, loop_amplitude: tuple[float, float] = (2e-5, 3e-4)) -> None:
    """Fill ``plan`` with a realistic motion of about ``duration`` seconds.

    The motion kinds (:data:`MOTION_KINDS`) are drawn from a shuffled deck, so
    every kind comes before any repeats; slide speeds cycle through
    :data:`SPEED_CLASSES` and dwells through :data:`DWELL_CLASSES` (values
    log-uniform within a class); small loops have amplitudes log-uniform in
    ``loop_amplitude`` (m). The pressure level changes once, half way.
    """
    L = plan.stroke
    plan.level = float(levels[0])
    plan.dwell(0.3)
    changed = len(levels) < 2
    deck: list[str] = []
    n_slide = n_dwell = int(rng.integers(3))

    while plan.duration < duration:
        if not changed and plan.duration > 0.5 * duration:
            plan.pressure(float(levels[1]))
            changed = True
        if not deck:
            deck = [MOTION_KINDS[i] for i in rng.permutation(len(MOTION_KINDS))]
        kind = deck.pop()
        V = log_uniform(rng, *SPEED_CLASSES[n_slide % len(SPEED_CLASSES)])
        n_slide += 1
        t_ramp = max(0.01, V / a_max * rng.uniform(1.0, 2.5))
        towards = 1.0 if plan.x < 0.5 * L else -1.0
        d = towards * min(V * rng.uniform(0.4, 1.2) + V * t_ramp, 0.35 * L)
        if kind == "slide":
            plan.move(d, V, t_ramp)
            plan.dwell(log_uniform(rng, 0.05, 0.4))
        elif kind == "reverse":  # out and straight back: a reversal without a stop
            plan.move(d, V, t_ramp)
            plan.move(-0.6 * d, V, t_ramp)
        elif kind == "dwell-slide":
            plan.dwell(log_uniform(rng, *DWELL_CLASSES[n_dwell % len(DWELL_CLASSES)]))
            n_dwell += 1
            plan.move(d, V, t_ramp)
        elif kind == "loops":  # small displacement cycles (presliding), at most 1 s
            plan.loops(log_uniform(rng, *loop_amplitude), float(rng.uniform(2.0, 5.0)), 2)
            plan.dwell(0.1)
        else:  # one sinusoidal sweep, at most 1 s
            f = float(rng.uniform(1.0, 2.5))
            A = min(0.12 * L, 0.15 / (2 * np.pi * f))
            plan.loops(A, f, 1)
            plan.dwell(0.1)


#: Motion plans (:func:`plan_record`'s ``motion``).
MOTIONS = ("standard", "presliding")
#: Loop frequencies (Hz) of the presliding-dominated motion, cycled through.
PRESLIDING_FREQUENCIES = (0.5, 1.0, 2.0, 4.0, 8.0)
#: Length (m) and speed range (m/s) of its few slides.
PRESLIDING_SLIDE = 0.02
PRESLIDING_SPEEDS = (0.01, 0.06)
#: Slides per experiment of the presliding-dominated motion.
PRESLIDING_SLIDES = 2


def schedule_presliding(plan: Plan, rng: np.random.Generator, duration: float,
                        levels: Sequence[float], a_max: float,
                        amplitude: tuple[float, float] = (1e-5, 2.5e-4)) -> None:
    """Fill ``plan`` with a presliding-dominated motion of about ``duration`` seconds.

    Blocks of small displacement cycles ``x0 + A*(1 - cos(2*pi*f*t))`` (1-4 cycles of at
    most 2 s, ``A`` log-uniform in ``amplitude``, ``f`` cycling through
    :data:`PRESLIDING_FREQUENCIES` from a random start), each followed by a rest of
    0.05-0.5 s (log-uniform); :data:`PRESLIDING_SLIDES` slides of
    ``PRESLIDING_SLIDE`` x U(0.75, 1.25) (towards mid-stroke, at most 30 % of it) at a
    speed log-uniform in :data:`PRESLIDING_SPEEDS`, each after a third of the time
    between them and followed by a rest of 0.2-1 s; the pressure level changes once,
    half way. About four fifths of the moving samples are in loops, a fifth of the
    record at rest.
    """
    L = plan.stroke
    plan.level = float(levels[0])
    plan.dwell(0.3)
    changed = len(levels) < 2
    slides_at = [duration * (k + 1) / (PRESLIDING_SLIDES + 1) for k in range(PRESLIDING_SLIDES)]
    k_f = int(rng.integers(len(PRESLIDING_FREQUENCIES)))

    while plan.duration < duration:
        if not changed and plan.duration > 0.5 * duration:
            plan.pressure(float(levels[1]))
            changed = True
        if slides_at and plan.duration >= slides_at[0]:
            slides_at.pop(0)
            V = log_uniform(rng, *PRESLIDING_SPEEDS)
            t_ramp = max(0.01, V / a_max * rng.uniform(1.0, 2.5))
            towards = 1.0 if plan.x < 0.5 * L else -1.0
            plan.move(towards * min(PRESLIDING_SLIDE * rng.uniform(0.75, 1.25), 0.3 * L),
                      V, t_ramp)
            plan.dwell(log_uniform(rng, 0.2, 1.0))
            continue
        f = PRESLIDING_FREQUENCIES[k_f % len(PRESLIDING_FREQUENCIES)]
        k_f += 1
        cycles = max(1, min(int(rng.integers(1, 5)), int(2.0 * f)))
        plan.loops(log_uniform(rng, *amplitude), f, cycles)
        plan.dwell(log_uniform(rng, 0.05, 0.5))


@dataclass(frozen=True)
class Motion:
    """The whole record's motion on the fine grid (all experiments, one after the other).

    Attributes
    ----------
    t, x : (n,) s, m
        Time and position at the nodes where the fine intervals start (a 1 s gap
        in ``t`` between experiments; the position is continuous).
    v, a : (n,) m/s, m/s^2
        Velocity and acceleration of each fine interval (midpoint values).
    S : (n,) Pa
        Pressure sum ``p1 + p2`` (gauge).
    experiment : (n,)
        Experiment number (1, 2, ...).
    dt : s
        Fine step.
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    S: np.ndarray
    experiment: np.ndarray
    dt: float


def plan_record(rng: np.random.Generator, *, experiments: int, duration: float, dt: float,
                stroke: float, levels: Sequence[float], a_max: float,
                loop_amplitude: tuple[float, float], motion: str = "standard",
                presliding_amplitude: tuple[float, float] = (1e-5, 2.5e-4)) -> Motion:
    """Schedule ``experiments`` experiments sharing ``duration`` seconds; the fine-grid motion.

    Experiment ``e`` runs at the pressure levels ``levels[e]`` then
    ``levels[e + 1]`` (cyclically); it starts where the previous one ended.
    ``motion`` picks the plan (:data:`MOTIONS`): :func:`schedule` with loops of
    ``loop_amplitude``, or :func:`schedule_presliding` with loops of
    ``presliding_amplitude``.
    """
    if motion not in MOTIONS:
        raise FcompError(f"unknown motion {motion!r}; known: {', '.join(MOTIONS)}")
    parts: dict[str, list[np.ndarray]] = {k: [] for k in ("t", "v", "a", "x", "S", "e")}
    t_start = 0.0
    x0 = 0.5 * stroke
    for e in range(experiments):
        plan = Plan(dt=dt, x0=x0, stroke=stroke)
        lv = [levels[(e + k) % len(levels)] for k in range(2)]
        if motion == "presliding":
            schedule_presliding(plan, rng, duration / experiments, lv, a_max,
                                presliding_amplitude)
        else:
            schedule(plan, rng, duration / experiments, lv, a_max, loop_amplitude)
        n_keep = int(round(duration / experiments / dt))  # the record ends where it ends
        v = np.concatenate(plan.v)[:n_keep]
        x = x0 + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
        t = t_start + np.arange(v.size) * dt
        parts["t"].append(t)
        parts["v"].append(v)
        parts["a"].append(np.concatenate(plan.a)[:n_keep])
        parts["x"].append(x)
        parts["S"].append(np.concatenate(plan.S)[:n_keep])
        parts["e"].append(np.full(v.size, e + 1.0))
        t_start = t[-1] + 1.0  # a one-second gap between experiments
        x0 = float(x[-1])
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    return Motion(t=cat["t"], x=cat["x"], v=cat["v"], a=cat["a"], S=cat["S"],
                  experiment=cat["e"], dt=dt)


def along(t: Sequence[np.ndarray], x: Sequence[np.ndarray], S: Sequence[np.ndarray],
          dt: float) -> Motion:
    """A fine-grid :class:`Motion` through given sampled experiments (position ``x`` at the
    times ``t``, pressure sum ``S``): ``x`` interpolated linearly onto the grid of step ``dt``,
    ``v`` and ``a`` its differences; the experiments one after the other with a one-second
    gap, as :func:`plan_record` lays them out."""
    parts: dict[str, list[np.ndarray]] = {k: [] for k in ("t", "v", "a", "x", "S", "e")}
    t_start = 0.0
    for e, (te, xe, se) in enumerate(zip(t, x, S, strict=True)):
        grid = te[0] + np.arange(int(round((te[-1] - te[0]) / dt)) + 1) * dt
        xs = np.interp(grid, te, xe)
        v = np.diff(xs, append=xs[-1]) / dt
        parts["t"].append(t_start + grid - te[0])
        parts["x"].append(xs)
        parts["v"].append(v)
        parts["a"].append(np.gradient(v, dt))
        parts["S"].append(np.interp(grid, te, se))
        parts["e"].append(np.full(grid.size, e + 1.0))
        t_start = parts["t"][-1][-1] + 1.0
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    return Motion(t=cat["t"], x=cat["x"], v=cat["v"], a=cat["a"], S=cat["S"],
                  experiment=cat["e"], dt=dt)
