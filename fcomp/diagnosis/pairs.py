"""Effects found in pairs where single steps cannot.

The search adds one effect at a time, and a candidate qualifies when it takes
at least half the excess over the noise floor where it acts
(:class:`.rule.AcceptanceRule`, ``excess_share``). Two effects missing at once
can defeat that: each acts where the other's excess is too, so each alone
explains too little of the excess there, however significant its fall. From
LuGre on the TU Delft O-ring and Circle records at 1-7 bar every candidate
failed only that test -- ``area-error`` z = 23, ``direction-asymmetry`` z = 28,
``pressure-dependence`` z = 16 -- and the search stopped with "no catalogue
effect explains" for textbook pressure dependence; with ``pressure-dependence``
forced, the asymmetry qualified at once (1.12 -> 0.49 N).

So when no single candidate qualifies, the most promising ones -- those whose
fall is significant and which fail only for its size (``small-share``,
``small-fall``), at most :data:`PAIR_CANDIDATES` of them, best first -- are
refitted in pairs (the better one's fit extended by the other, each of the
other's forms; the information criterion picks the form as for a single): the
pairs of the best singles first, at most :data:`MAX_PAIRS`, never two effects
declared confounded with each other (``Effect.confounded``: an offset and a
direction asymmetry take the same excess twice -- on the O-ring and Circle
files the three best singles were ``area-error``, ``force-offset`` and
``direction-asymmetry``, and pairing them among themselves left the pressure law
out). A pair is accepted when

* the pair qualifies by the rule against the current model (where either acts),
  and
* each member qualifies by the rule against the other alone: neither is
  carried by its partner (the backward check's question, asked at once).

The best such pair (lowest held-out RMS) is added as two steps, marked as a
pair in the JSON (``pairs``, and ``pair`` in both steps). The cost is a
refit per pair, at the steps where nothing single qualifies *and* two or more
candidates fell significantly: none at all on a record where the last step's
candidates show no significant fall.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Protocol

import fcomp.diagnosis.catalogue as catalogue
from fcomp.diagnosis.noise import effective_sample_size
from fcomp.diagnosis.refit import FitResult, Refit
from fcomp.diagnosis.rule import AcceptanceRule, Ground, Judgement, delta_bic
from fcomp.diagnosis.workers import refit_all
from fcomp.effects import EFFECTS
from fcomp.errors import FcompError
from fcomp.progress import Tick

#: Most single candidates considered for pairs (the best by held-out RMS) ...
PAIR_CANDIDATES = 5
#: ... and most pairs refitted (the pairs of the best singles first).
MAX_PAIRS = 3
#: The tests a promising candidate may fail: the size of its fall, nothing else.
SIZE_ONLY = ("small-share", "small-fall")


class Judged(Protocol):
    """A candidate of a step as the pair search reads it (:class:`.search.Candidate`)."""

    @property
    def effect(self) -> str: ...

    @property
    def fit(self) -> FitResult | None: ...

    @property
    def form(self) -> str | None: ...

    @property
    def judgement(self) -> Judgement | None: ...

    @property
    def rms_heldout(self) -> float: ...


@dataclass(frozen=True)
class Pair:
    """Two effects refitted together and judged.

    Attributes
    ----------
    effects : (str, str)
        The pair, the better single first.
    forms : (str or None, str or None)
        The form of each.
    fit : FitResult
        The model with both.
    judgement : Judgement
        The pair against the current model.
    marginal : (Judgement, Judgement)
        Each member against the model with the other alone (first: the first
        member's, judged against the second alone).
    singles : (float, float)
        The held-out RMS of each member alone (N).
    """

    effects: tuple[str, str]
    forms: tuple[str | None, str | None]
    fit: FitResult
    judgement: Judgement
    marginal: tuple[Judgement, Judgement]
    singles: tuple[float, float]

    @property
    def qualifies(self) -> bool:
        return self.judgement.qualifies and all(m.qualifies for m in self.marginal)

    @property
    def rms_heldout(self) -> float:
        return self.fit.rms_test

    def to_dict(self) -> dict[str, object]:
        return {"effects": list(self.effects), "forms": list(self.forms),
                "rms_alone": [float(r) for r in self.singles],
                "rms_together": float(self.fit.rms_test),
                "z": _num(self.judgement.z), "qualifies": self.qualifies}


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def promising(ranked: Sequence[Judged], rule: AcceptanceRule) -> list[Judged]:
    """The candidates whose fall is significant and which fail only for its size, best
    first, at most :data:`PAIR_CANDIDATES`."""
    out = []
    for c in ranked:
        j = c.judgement
        if c.fit is None or j is None or j.qualifies or not j.fall > 0 or not j.p <= rule.accept_p:
            continue
        if all(f.code in SIZE_ONLY for f in j.failures):
            out.append(c)
    return out[:PAIR_CANDIDATES]


def confounded(a: str, b: str) -> bool:
    """Whether effects ``a`` and ``b`` are declared to give the same force over the motions a
    record holds (:attr:`fcomp.effects.Effect.confounded`, either way): such a pair takes the
    same excess twice and cannot pass its members' tests against each other."""
    return b in EFFECTS.get(a).confounded or a in EFFECTS.get(b).confounded


def pairs_of(cands: Sequence[Judged]) -> list[tuple[int, int]]:
    """The pairs of ``cands`` (indices, the better first) worth refitting: not confounded with
    each other, best singles first (the sum of their held-out RMS), at most
    :data:`MAX_PAIRS`."""
    out = [(i, j) for i in range(len(cands)) for j in range(i + 1, len(cands))
           if not confounded(cands[i].effect, cands[j].effect)]
    out.sort(key=lambda ij: cands[ij[0]].rms_heldout + cands[ij[1]].rms_heldout)
    return out[:MAX_PAIRS]


def _acts_in(*names: str) -> tuple[str, ...]:
    """Where a pair acts: the union of its members' regimes (anywhere if either is)."""
    parts = [EFFECTS.get(n).acts_in for n in names]
    if any(not p for p in parts):
        return ()
    return tuple(dict.fromkeys(r for p in parts for r in p))


def find_pair(ranked: Sequence[Judged], *, refit: Refit, ground: Ground, rule: AcceptanceRule,
              current: FitResult, context: Callable[[FitResult], catalogue.Context],
              pool: Executor | None, tick: Tick,
              seconds: dict[tuple[str, str | None], float]
              ) -> tuple[Pair | None, list[Pair], Executor | None]:
    """The best qualifying pair of the step's promising candidates (module docstring).

    Returns the pair (None if none qualifies), every pair judged, and the executor to use
    from now on (:func:`.workers.refit_all`).
    """
    cands = promising(ranked, rule)
    chosen = pairs_of(cands)
    if not chosen:
        return None, [], pool
    train = ground.split.train
    n_eff = effective_sample_size(current.residual[train])
    best: dict[tuple[int, int], tuple[FitResult, str | None]] = {}
    kept = set(refit.kept)
    tick("pairs: " + ", ".join(f"{cands[i].effect} + {cands[j].effect}" for i, j in chosen))
    for i in sorted({i for i, _ in chosen}):  # the better single's fit extended by the other
        a = cands[i]
        assert a.fit is not None
        ctx = context(a.fit)
        proposals: list[catalogue.Proposal] = []
        index: list[int] = []
        for j in (j for i_, j in chosen if i_ == i):
            b = cands[j]
            if catalogue.applicability(b.effect, ctx) is not None:
                continue
            try:
                props = catalogue.propose_all(b.effect, ctx)
            except (FcompError, ValueError):
                continue
            proposals += props
            index += [j] * len(props)
        if not proposals:
            continue
        # what the first member holds stays held in the pair's refit (:meth:`.Refit.keep`)
        refit.kept = kept | set(catalogue.held_of(a.effect, a.form, ctx))
        try:
            results, pool = refit_all(refit, proposals, current, pool, tick, seconds)
        finally:
            refit.kept = kept
        for j, prop, res in zip(index, proposals, results, strict=True):
            if isinstance(res, str):
                continue
            prev = best.get((i, j))
            if prev is None or (delta_bic(current, res, train, n_eff)
                                < delta_bic(current, prev[0], train, n_eff)):
                best[(i, j)] = (res, prop.form)
    judged = []
    for (i, j), (fit, form) in best.items():
        a, b = cands[i], cands[j]
        assert a.fit is not None and b.fit is not None
        whole = rule.judge(current, fit, ground, _acts_in(a.effect, b.effect))
        of_a = rule.judge(b.fit, fit, ground, EFFECTS.get(a.effect).acts_in)
        of_b = rule.judge(a.fit, fit, ground, EFFECTS.get(b.effect).acts_in)
        judged.append(Pair((a.effect, b.effect), (a.form, form), fit, whole, (of_a, of_b),
                           (a.rms_heldout, b.rms_heldout)))
    good = sorted((p for p in judged if p.qualifies), key=lambda p: p.rms_heldout)
    return (good[0] if good else None), judged, pool


__all__ = ["MAX_PAIRS", "PAIR_CANDIDATES", "Pair", "confounded", "find_pair", "pairs_of",
           "promising"]
