"""Choose and size the programme: a greedy T-/A-optimal selection of primitives.

Each candidate primitive (:func:`.primitives.candidates`) is scored once per question: the
T-criterion of every rival pair (:func:`.criteria.t_criterion`) and the Fisher information of
every questioned parameter (:func:`.criteria.jacobian`). Both add over primitives. The
programme grows one primitive at a time, the one with the largest gain per second of

    sum_q log(1 + T_q / T_TARGET)  +  sum_p log(se_before_p / se_after_p)

(a balanced design: a question already answered gains little), until every tie and
untested effect reaches :data:`T_TARGET`, every parameter's standard error has fallen by
:data:`SHRINK`, or the budget (:data:`EXPERIMENTS_MAX` experiments of ``duration_max``) is
spent (Fedorov's sequential construction; Atkinson, Donev & Tobias 2007, ch. 11).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fcomp.planning.criteria import force, jacobian, predicted_stderr, t_criterion
from fcomp.planning.primitives import Block, candidates, signals
from fcomp.planning.questions import Question
from fcomp.planning.rig import Rig

#: The non-centrality a question is answered at (about 30 noise floors of evidence: a
#: margin over the 5-sigma of a clean test for the refits and held-out splits of a
#: re-diagnosis).
T_TARGET = 1000.0
#: Below this non-centrality the rig cannot tell the rivals apart at all.
T_BLOCKED = 25.0
#: The factor a parameter's standard error should fall by.
SHRINK = 2.0
#: The most experiments a programme holds.
EXPERIMENTS_MAX = 6


@dataclass
class Scores:
    """Per candidate: the T-criterion per (question, rival) and the information per
    parameter question (the diagonal, the parameter alone)."""

    blocks: list[Block]
    seconds: np.ndarray
    T: dict[tuple[int, str], np.ndarray] = field(default_factory=dict)
    info: dict[int, np.ndarray] = field(default_factory=dict)


def score(rig: Rig, questions: list[Question], sigma: float, mass_from_pressures: bool,
          blocks: list[Block] | None = None) -> Scores:
    """Score every candidate primitive on every question."""
    blocks = candidates(rig) if blocks is None else blocks
    sc = Scores(blocks, np.array([b.v.size / rig.rate for b in blocks]))
    sigs = [signals(b, rig) for b in blocks]
    cache: dict[int, list[np.ndarray]] = {}

    def forces(model: object) -> list[np.ndarray]:
        key = id(model)
        if key not in cache:
            cache[key] = [force(model, s) for s in sigs]  # type: ignore[arg-type]
        return cache[key]

    for i, q in enumerate(questions):
        if q.kind == "parameter":
            continue
        names = list(q.models)
        ref = forces(q.models[names[0]])
        for other in names[1:]:
            fo = forces(q.models[other])
            sc.T[(i, other)] = np.array([t_criterion(a, b, sigma) for a, b in zip(ref, fo, strict=False)])
    for i, q in enumerate(questions):
        if q.kind != "parameter" or q.parameter is None or not q.models:
            continue
        model = next(iter(q.models.values()))
        sc.info[i] = np.array([float(np.sum(jacobian(model, s, [q.parameter],
                                                     mass_from_pressures) ** 2)) / sigma**2
                               for s in sigs])
    return sc


def _objective(T: dict[tuple[int, str], float], info: dict[int, float],
               before: dict[int, float | None]) -> float:
    val = sum(np.log1p(t / T_TARGET) for t in T.values())
    for i, inf in info.items():
        se = predicted_stderr(np.array([[inf]]), [before.get(i)])[0]
        se0 = before.get(i)
        ref = se0 if se0 else 1.0
        val += float(np.log(ref / se)) if np.isfinite(se) else 0.0
    return float(val)


def _done(T: dict[tuple[int, str], float], info: dict[int, float],
          before: dict[int, float | None]) -> bool:
    if any(t < T_TARGET for t in T.values()):
        return False
    for i, inf in info.items():
        se0 = before.get(i)
        se = predicted_stderr(np.array([[inf]]), [se0])[0]
        if se0 is None or not se * SHRINK <= se0:
            return False
    return True


def choose(sc: Scores, rig: Rig, questions: list[Question]) -> list[int]:
    """The chosen primitives' indices (greedy, gain per second, within the budget)."""
    budget = EXPERIMENTS_MAX * rig.duration_max * 0.9
    before = {i: q.stderr_before for i, q in enumerate(questions) if q.kind == "parameter"}
    T = {k: 0.0 for k in sc.T}
    info = {i: 0.0 for i in sc.info if np.any(sc.info[i] > 0)}  # a value no motion informs
    chosen: list[int] = []                                       # is no goal
    used = 0.0
    least = min(rig.duration_max, budget)  # at least one whole experiment to re-diagnose
    while used < budget and (used < least or not _done(T, info, before)):
        base = _objective(T, info, before)
        best, gain = -1, 0.0
        for j in range(len(sc.blocks)):
            if used + sc.seconds[j] > budget:
                continue
            T2 = {k: T[k] + sc.T[k][j] for k in T}
            I2 = {i: info[i] + sc.info[i][j] for i in info}
            g = (_objective(T2, I2, before) - base) / sc.seconds[j]
            if j in chosen:
                g *= 0.5  # a repeat tells less than a new primitive (the model may be wrong)
            if g > gain:
                best, gain = j, g
        if best < 0:
            break
        chosen.append(best)
        used += sc.seconds[best]
        T = {k: T[k] + sc.T[k][best] for k in T}
        info = {i: info[i] + sc.info[i][best] for i in info}
    return chosen


def bound(sc: Scores, rig: Rig, key: tuple[int, str]) -> float:
    """The largest T-criterion the budget could reach for one rival pair alone."""
    budget = EXPERIMENTS_MAX * rig.duration_max * 0.9
    rate = sc.T[key] / sc.seconds
    total, used = 0.0, 0.0
    for j in np.argsort(-rate):
        if used + sc.seconds[j] > budget:
            continue
        total += sc.T[key][j]
        used += sc.seconds[j]
    return float(total)
