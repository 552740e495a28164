"""Choose and size the programme: a greedy T-/A-optimal selection of primitives.

Each candidate primitive (:func:`.primitives.candidates`) is scored once per question: the
T-criterion of every rival pair (:func:`.criteria.t_criterion`) and the Fisher information of
every questioned parameter (:func:`.criteria.jacobian`). Both add over primitives. The
programme grows one primitive at a time, the one with the largest gain per second of

    sum_q log(1 + T_q / T_TARGET)  +  sum_p log(se_before_p / se_after_p)

(a balanced design: a question already answered gains little), with ``T_q`` the
T-criterion after the rival's values are refitted along the programme (:func:`refit_T`: a
difference the rival can take up by changing its values tells nothing), until every tie and
untested effect reaches :data:`T_TARGET`, every parameter's standard error has fallen by
:data:`SHRINK`, or the budget (:data:`EXPERIMENTS_MAX` experiments of ``duration_max``) is
spent (Fedorov's sequential construction; Atkinson, Donev & Tobias 2007, ch. 11).
"""

from __future__ import annotations

from collections.abc import Mapping
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
    """Per candidate: the T-criterion per (question, rival), and the Fisher information of
    the joint parameters ``joint`` (the fitted ones and those asked about: a parameter's
    interval after the programme counts what the others take from it)."""

    blocks: list[Block]
    seconds: np.ndarray
    T: dict[tuple[int, str], np.ndarray] = field(default_factory=dict)
    joint: list[str] = field(default_factory=list)
    prior: list[float | None] = field(default_factory=list)
    info: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))
    asked: dict[int, int] = field(default_factory=dict)
    #: per pair: the refitted rival's sensitivities, ``h_b = J_b^T dF_b / sigma^2`` and
    #: ``G_b = J_b^T J_b / sigma^2`` per block (:func:`refit_T`)
    H: dict[tuple[int, str], np.ndarray] = field(default_factory=dict)
    G: dict[tuple[int, str], np.ndarray] = field(default_factory=dict)


def refit_T(T: float, h: np.ndarray, G: np.ndarray) -> float:
    """The T-criterion once the rival's parameters are refitted along the motion
    (linearised, Atkinson & Fedorov 1975): ``T - h^T G^+ h`` -- what of the force
    difference no change of the rival's values can take up."""
    if h.size == 0:
        return T
    ridge = 1e-9 * max(float(np.trace(G)), 1e-300)
    sol = np.linalg.lstsq(G + ridge * np.eye(G.shape[0]), h, rcond=None)[0]
    return max(float(T - h @ sol), 0.0)


def refitted(q: Question, other: str) -> tuple[str, object]:
    """Which model of a pair is refitted: the rival of a tie, the model without the effect
    for an untested one (could the model without it mimic it?)."""
    names = list(q.models)
    name = names[0] if q.kind == "untested" else other
    return name, q.models[name]


def free_names(model: object) -> list[str]:
    """The values a refit may change: every finite parameter but the fixed references."""
    fixed = {n for e in getattr(model, "effects", ()) for n in getattr(e, "fixed", ())}
    flat = model.flat_params()  # type: ignore[attr-defined]
    return [n for n, v in flat.items() if n not in fixed and np.isfinite(v) and v != 0]


def joint_parameters(questions: list[Question], stderr: Mapping[str, float]
                     ) -> tuple[list[str], list[float | None], dict[int, int]]:
    """The parameters estimated together: those the diagnosis fitted (a standard error
    given) and those asked about; their prior standard errors; question -> index."""
    names = [k for k, v in stderr.items() if isinstance(v, (int, float)) and v > 0]
    asked: dict[int, int] = {}
    for i, q in enumerate(questions):
        if q.kind == "parameter" and q.parameter is not None:
            if q.parameter not in names:
                names.append(q.parameter)
            asked[i] = names.index(q.parameter)
    prior = [float(stderr[n]) if isinstance(stderr.get(n), (int, float)) else None
             for n in names]
    return names, prior, asked


def score(rig: Rig, questions: list[Question], sigma: float, mass_from_pressures: bool,
          blocks: list[Block] | None = None, stderr: Mapping[str, float] | None = None
          ) -> Scores:
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
            sc.T[(i, other)] = np.array([t_criterion(a, b, sigma)
                                         for a, b in zip(ref, fo, strict=True)])
            _, rival = refitted(q, other)
            free = free_names(rival)
            Js = [jacobian(rival, s, free, False) for s in sigs]  # type: ignore[arg-type]
            sc.H[(i, other)] = np.array([J.T @ (a - b) / sigma**2
                                         for J, a, b in zip(Js, ref, fo, strict=True)])
            sc.G[(i, other)] = np.array([J.T @ J / sigma**2 for J in Js])
    asked = [q for q in questions if q.kind == "parameter" and q.models]
    if asked:
        sc.joint, sc.prior, sc.asked = joint_parameters(questions, stderr or {})
        model = next(iter(asked[0].models.values()))
        mats = []
        for s in sigs:
            J = jacobian(model, s, sc.joint, mass_from_pressures)
            mats.append(J.T @ J / sigma**2)
        sc.info = np.array(mats)
    return sc


def _stderr(sc: Scores, total: np.ndarray) -> np.ndarray:
    return predicted_stderr(total, sc.prior)


Acc = dict[tuple[int, str], tuple[float, np.ndarray, np.ndarray]]


def _adjusted(acc: Acc) -> dict[tuple[int, str], float]:
    return {k: refit_T(*v) for k, v in acc.items()}


def _add(sc: Scores, acc: Acc, j: int) -> Acc:
    return {k: (t + sc.T[k][j], h + sc.H[k][j], G + sc.G[k][j]) for k, (t, h, G) in acc.items()}


def _objective(sc: Scores, acc: Acc, total: np.ndarray, goals: dict[int, int]) -> float:
    val = sum(np.log1p(t / T_TARGET) for t in _adjusted(acc).values())
    if goals:
        se = _stderr(sc, total)
        for k in goals.values():
            ref = sc.prior[k] or 1.0
            if np.isfinite(se[k]) and se[k] > 0:
                val += float(np.log(ref / se[k]))
    return float(val)


def _done(sc: Scores, acc: Acc, total: np.ndarray, goals: dict[int, int]) -> bool:
    if any(t < T_TARGET for t in _adjusted(acc).values()):
        return False
    if goals:
        se = _stderr(sc, total)
        for k in goals.values():
            p = sc.prior[k]
            if p is None or not se[k] * SHRINK <= p:
                return False
    return True


def choose(sc: Scores, rig: Rig, questions: list[Question]) -> list[int]:
    """The chosen primitives' indices (greedy, gain per second, within the budget)."""
    budget = EXPERIMENTS_MAX * rig.duration_max * 0.9
    acc: Acc = {k: (0.0, np.zeros(sc.H[k].shape[1]), np.zeros(sc.G[k].shape[1:]))
                for k in sc.T}
    k_joint = len(sc.joint)
    total = np.zeros((k_joint, k_joint))
    # a value no motion informs is no goal
    goals = {i: k for i, k in sc.asked.items() if sc.info.size and np.any(sc.info[:, k, k] > 0)}
    chosen: list[int] = []
    used = 0.0
    least = min(rig.duration_max, budget)  # at least one whole experiment to re-diagnose
    while used < budget and (used < least or not _done(sc, acc, total, goals)):
        base = _objective(sc, acc, total, goals)
        best, gain = -1, 0.0
        for j in range(len(sc.blocks)):
            if used + sc.seconds[j] > budget:
                continue
            tot2 = total + sc.info[j] if k_joint else total
            g = (_objective(sc, _add(sc, acc, j), tot2, goals) - base) / sc.seconds[j]
            if j in chosen:
                g *= 0.5  # a repeat tells less than a new primitive (the model may be wrong)
            if g > gain:
                best, gain = j, g
        if best < 0:
            break
        chosen.append(best)
        used += sc.seconds[best]
        acc = _add(sc, acc, best)
        if k_joint:
            total = total + sc.info[best]
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
