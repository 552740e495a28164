"""Ties the record's design makes: effects acting through factors it varies together.

The held-out error cannot separate two laws in factors a record varies together:
held out within the same experiments, a Stribeck curve that reproduces the
levels of 1, 3 and 5 bar through their retracting speeds (10.0, 7.9, 5.5 mm/s)
predicts the held-out blocks as well as the pressure law it stands in for, and
fails only where the design breaks the pattern (at 7 bar, 6.5 mm/s: -8.85 N
predicted, -11.22 N measured). :func:`design_ties` reports such pairs as ties
once the search has stopped: an accepted effect and a candidate of the same step
whose fall was significant, or two effects both in the final model, whose
declared factors (:attr:`fcomp.effects.Effect.factors`) the design confounds
(:class:`.design.Confounding`). Each tie carries the confounding -- the factors,
the ranges over which the record varies them together, the experiment that
separates them -- in ``Search.confounding`` (the JSON's ``confounding``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fcomp.diagnosis.design import Confounding, Design
from fcomp.diagnosis.revision import join_tie
from fcomp.diagnosis.search import Candidate, Search
from fcomp.effects import EFFECTS


def factors(effect: str) -> tuple[str, ...]:
    """The factors effect ``effect`` declares (none for an unknown name)."""
    try:
        return tuple(EFFECTS.get(effect).factors)
    except (KeyError, ValueError, AttributeError):
        return ()


def confounding_of(design: Design, a: str, b: str) -> Confounding | None:
    """The confounding of the design between a factor of effect ``a`` and one of ``b``."""
    for fa in factors(a):
        for fb in factors(b):
            if fa != fb:
                found = design.confounds(fa, fb)
                if found is not None:
                    return found
    return None


def _evidence(c: Candidate, accept_p: float) -> bool:
    """Whether a candidate's held-out fall is real: it falls, significantly."""
    return c.judgement is not None and c.fall > 0 and c.p <= accept_p


def design_ties(search: Search, design: Design) -> None:
    """Report the pairs of effects the record's design cannot tell apart (module docstring)."""
    accept_p = search.rule.accept_p
    pairs: list[tuple[str, str, Confounding]] = []
    for step in search.steps:
        if not step.accepted or step.forced or step.effect not in search.added:
            continue
        for c in step.candidates:
            if c.effect == step.effect or not _evidence(c, accept_p):
                continue
            found = confounding_of(design, step.effect, c.effect)
            if found is not None:
                pairs.append((step.effect, c.effect, found))
    added = list(search.added)
    for i, a in enumerate(added):
        for b in added[i + 1:]:
            found = confounding_of(design, a, b)
            if found is not None:
                pairs.append((a, b, found))
    for a, b, found in pairs:
        join_tie(search.ties, a, [b])
        entry = _entry(a, b, found)
        if entry not in search.confounding:
            search.confounding.append(entry)


def _entry(a: str, b: str, c: Confounding) -> dict[str, Any]:
    return {"effects": [a, b], **c.to_dict()}


def separating(confounding: Sequence[dict[str, Any]], tie: Sequence[str]) -> list[str]:
    """The experiments that separate the members of ``tie`` the design confounds."""
    out: list[str] = []
    for entry in confounding:
        if set(entry["effects"]) <= set(tie) and entry["separates"] not in out:
            out.append(entry["separates"])
    return out


__all__ = ["confounding_of", "design_ties", "factors", "separating"]
