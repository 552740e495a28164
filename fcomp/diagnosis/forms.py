"""Richer forms of an accepted effect, chosen by the held-out data.

Tried only where the residual still follows a factor of the effect (a pressure law's
``p1 + p2``: :func:`still_follows`), so a record the plain form explains pays nothing.

An effect is found in its plainest form (a pressure law linear in ``p1 + p2``);
an expert then tries the forms the physics allows (a contact force that
saturates with the pressure, a power of the pressure, the viscous part changing
with it too: :meth:`fcomp.effects.Effect.refined_forms`). :func:`refine` refits
the model with each such form in place of the accepted one, from the accepted
values, and keeps the best form the acceptance rule accepts against the accepted
one on the held-out data (:meth:`.rule.AcceptanceRule.judge`: a clear,
significant fall, half the excess where it acts, the information criterion); a
form that only bends to the training samples is refused as any candidate is.
Every form tried is listed in the JSON (``forms``) with its held-out RMS and the
rule's reason.

A candidate not yet accepted whose plain form falls significantly but short of half the
excess where it acts is tried in its richer forms too (:func:`candidate_forms`), before
the search looks for a pair: a law of another form is the first thing an expert suspects
when a significant effect explains too little.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import fcomp.diagnosis.catalogue as catalogue
from fcomp.diagnosis.features import residual_structure
from fcomp.diagnosis.refit import RIG_EXTRAS, FitResult, fixed_names
from fcomp.diagnosis.rule import Judgement
from fcomp.diagnosis.wording import QUALIFIES, judgement_text
from fcomp.diagnosis.workers import refit_all
from fcomp.effects import EFFECTS, Effect
from fcomp.errors import FcompError
from fcomp.identification.engine import default_free
from fcomp.models.base import FrictionModel

if TYPE_CHECKING:
    from fcomp.diagnosis.search import Search


#: The residual feature that follows each factor an effect's law acts through.
FACTOR_FEATURES = {"pressure": "p1+p2", "speed": "v", "position": "x",
                   "distance-since-reversal": "displacement_since_reversal"}
#: A richer form is tried when the residual still follows a factor of the effect this much
#: (the verdict's structure strength, :class:`.verdict.VerdictRule`).
FOLLOWS = 0.15


def still_follows(search: Search, name: str) -> bool:
    """Whether the current residual still follows a factor of effect ``name`` (held-out
    strength of its feature, :func:`.features.residual_structure`, at least
    :data:`FOLLOWS`): only then are its richer forms worth their refits."""
    wanted = {FACTOR_FEATURES[f] for f in EFFECTS.get(name).factors if f in FACTOR_FEATURES}
    if not wanted:
        return True
    g = search.ground
    found = residual_structure(search.current.located, g.data, g.segmentation, g.split.train,
                               g.split.test)
    return any(f.feature in wanted and f.strength >= FOLLOWS for f in found)


def replaced(model: FrictionModel, effect: Effect) -> FrictionModel:
    """``model`` with its add-on effect of ``effect``'s name replaced by ``effect``."""
    effects = tuple(effect if e.name == effect.name else e for e in model.effects)
    return model._rebuild(model.params, effects)


def _proposals(search: Search, name: str, base: FitResult) -> list[catalogue.Proposal]:
    """The refits of ``base`` (a fit whose model holds effect ``name``) with each of the
    effect's refined forms in place of its own, started from ``base``'s values."""
    own = next((e for e in base.model.effects if e.name == name), None)
    if own is None:
        return []
    ctx = search.context(base)
    data = search.ground.data
    own_flat = dict(own.params.flat())
    proposals = []
    for f in EFFECTS.get(name).refined_forms():
        try:
            guesses = catalogue.configured(name, data, own_flat, **f.config).guess(ctx.view,
                                                                                  f.name)
            if not guesses:
                continue
            # a guess may make a parameter direction-dependent (kp -> kp_pos, kp_neg)
            split = {k[:-4] for k in guesses[0] if k.endswith(("_pos", "_neg"))}
            effect = catalogue.configured(
                name, data, {**{k: v for k, v in own_flat.items() if k not in split},
                             **guesses[0]}, **f.config)
            model = replaced(base.model, effect)
        except (FcompError, ValueError, ArithmeticError):
            continue
        flat = model.flat_params()
        start = {k: v for k, v in base.values.items() if k in flat or k in RIG_EXTRAS}
        held = set(catalogue.held_of(name, f.name, ctx)) | search.refit.kept
        free = [n for n in default_free(model) if n not in fixed_names(model) and n not in held]
        free += [k for k in RIG_EXTRAS if k in base.values]
        proposals.append(catalogue.Proposal(name, model, [{**start, **g} for g in guesses],
                                            free, form=f.name))
    return proposals


def _tried(search: Search, name: str, base: FitResult, before: FitResult
           ) -> list[tuple[str | None, FitResult, Judgement]]:
    """Each refined form of ``name`` refitted from ``base`` and judged against ``before``
    where the effect acts; every form tried listed in ``search.refined``."""
    proposals = _proposals(search, name, base)
    if not proposals:
        return []
    search.tick(f"forms of {name}")
    t0 = time.perf_counter()
    results, search.pool = refit_all(search.refit, proposals, search.current, search.pool,
                                     search.tick, search.seconds)
    took = time.perf_counter() - t0
    acts = EFFECTS.get(name).acts_in
    judged = []
    for prop, res in zip(proposals, results, strict=True):
        if isinstance(res, str):
            search.refined.append({"effect": name, "form": prop.form, "rms_heldout": None,
                                   "qualifies": False, "reason": res, "kept": False,
                                   "seconds": took})
            continue
        judged.append((prop.form, res, search.rule.judge(before, res, search.ground, acts)))
    good = min((x for x in judged if x[2].qualifies), key=lambda x: x[1].rms_test,
               default=None)
    for form, res, j in judged:
        search.refined.append({**_entry(name, form, res.rms_test, j.z, j.qualifies,
                                        judgement_text(j) or QUALIFIES,
                                        good is not None and form == good[0],
                                        before.rms_test), "seconds": took})
    return judged


def refine(search: Search, name: str) -> None:
    """Try the refined forms of the accepted effect ``name`` (module docstring); the
    current fit, the step that added it and ``search.forms`` take the form kept."""
    current = search.current
    if not EFFECTS.get(name).refined_forms() or not any(
            e.name == name for e in current.model.effects) or not still_follows(search, name):
        return
    good = sorted((x for x in _tried(search, name, current, current) if x[2].qualifies),
                  key=lambda x: x[1].rms_test)
    if not good:
        return
    kept = good[0][0]
    fit = search.reweighted(search.polish(good[0][1]))
    search.forms[name] = kept
    for i in range(len(search.steps) - 1, -1, -1):  # the step that added it, now in this form
        st = search.steps[i]
        if st.effect == name and st.accepted:
            search.steps[i] = dataclasses.replace(st, fit=fit, rms_after=fit.rms_test,
                                                  form=kept)
            break
    search.fit = fit
    search.keep_held()


def candidate_forms(search: Search, promising: Sequence[tuple[str, FitResult]]
                    ) -> list[tuple[str, str | None, FitResult, Judgement]]:
    """The refined forms of a step's promising candidates (``(effect, its fit)``: a
    significant fall that fails only for its size, :func:`.pairs.promising`), each judged
    against the current model as any candidate is.

    An effect whose plain form falls short of half the excess where it acts may be there
    in a form the catalogue's first does not have (the Zillen seals' pressure law: linear
    in ``p1 + p2`` it explained 47 % of the excess on O-ring and Circle 1-7 bar, z = 17,
    and whether it qualified hung on which blocks were held out); its richer forms were
    tried only once it was accepted. Returns ``(effect, form, fit, judgement)`` of every
    form refitted."""
    out = []
    for name, fit in promising:
        if not EFFECTS.get(name).refined_forms():
            continue
        out += [(name, form, res, j) for form, res, j in _tried(search, name, fit,
                                                                 search.current)]
    return out


def _entry(name: str, form: str | None, rms: float, z: float, qualifies: bool, reason: str,
           kept: bool, before: float) -> dict[str, Any]:
    return {"effect": name, "form": form, "rms_before": before, "rms_heldout": rms,
            "z": z if z == z else None, "qualifies": qualifies, "reason": reason,
            "kept": kept}


__all__ = ["FACTOR_FEATURES", "candidate_forms", "refine", "replaced", "still_follows"]
