"""The checks after the search: each effect taken out again, its partners tried in its place.

* :func:`backward` -- effects are added one at a time, so an early one may only
  have stood in for part of what a later one explains; each searched effect,
  last added first, is taken out and the rest refitted: if putting it back would
  no longer qualify by the rule, it stays out (``removed``).
* :func:`swaps` -- effects that give the same force over the motions a record
  holds (``Effect.confounded``) are tried in each other's place: a partner that
  fits as well ties with the effect.
* :func:`partners_in_model` -- confounded partners both in the final model tie.
* :func:`remove` -- take an effect out on request.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

import fcomp.diagnosis.catalogue as catalogue
from fcomp.diagnosis.refit import RIG_EXTRAS, FitResult
from fcomp.diagnosis.search import Search
from fcomp.diagnosis.wording import judgement_text
from fcomp.effects import EFFECTS
from fcomp.errors import FcompError
from fcomp.models import FrictionModel


def rebuilt(search: Search, names: Sequence[str]) -> FitResult:
    """The baseline with the effects ``names`` (in order) refitted from the current values.

    A fit of the same structure seen earlier (the baseline, or the model before
    a later effect was added) is a start too, and is kept if the refit does not
    beat it on the training samples: refitted from the full model's values
    alone, a reduced model can settle in a worse optimum (a stiff bristle's test
    error 84 N where the same structure had reached 60 N), and the effect taken
    out would look needed when it is not, or not needed when it is.
    """
    model, start = reduced(search, names)
    known = [f for f in _known_fits(search, model) if set(f.values) == set(start)]
    # the parameters fitted now that remain (terms held for the record stay held)
    fit = search.polish(search.refit.fit(model, [start, *(f.values for f in known)],
                                         list(start)))
    # and never a worse fit than one of that structure already seen
    return min([fit, *known], key=lambda f: f.rms_train)


def reduced(search: Search, names: Sequence[str]) -> tuple[FrictionModel, dict[str, float]]:
    """The baseline with the effects ``names`` (in order), each configured with its current
    values, and the current values of what it fits (the start of :func:`rebuilt`)."""
    assert search.baseline_fit is not None
    current = search.current
    model = search.baseline_fit.model
    for n in names:
        if n in search.instances:
            model = model.with_effects(search.instances[n])
            continue
        # configured with its current values: an effect at its defaults can be a no-op
        # that attaches differently
        own = set(EFFECTS.get(n).Params.from_flat({}).flat())
        values = {k: v for k, v in current.values.items() if k in own}
        model = model.with_effects(catalogue.configured(
            n, search.ground.data, values or None,
            **catalogue.form_of(n, search.forms.get(n)).config))
    flat = model.flat_params()
    return model, {k: v for k, v in current.values.items() if k in flat or k in RIG_EXTRAS}


def _known_fits(search: Search, model: FrictionModel) -> list[FitResult]:
    """The baseline and accepted step fits whose model has the structure of ``model``."""
    fits = [search.baseline_fit, *(s.fit for s in search.steps if s.accepted and s.fit)]
    return [f for f in fits if f is not None and f.model.describe() == model.describe()
            and set(f.model.flat_params()) == set(model.flat_params())]


def _mark_removed(search: Search, effect: str, why: str, *, forced_too: bool) -> None:
    """Take ``effect`` out of the lists and mark the step that added it not accepted."""
    search.added = [n for n in search.added if n != effect]
    search.keep_held()
    search.removed.append(effect)
    search.ties = [t for t in search.ties if t[0] != effect]  # its tie went with it
    for i, st in enumerate(search.steps):
        if st.effect != effect or st.removed:
            continue
        if (st.accepted and not st.forced) or (forced_too and (st.accepted or st.forced)):
            search.steps[i] = dataclasses.replace(st, accepted=False, removed=why)


def backward(search: Search) -> None:
    """Drop searched effects that later additions made redundant (module docstring).

    Forced effects (``add``) are never removed.
    """
    searched = [s.effect for s in search.steps if s.accepted and not s.forced]
    if len(search.added) < 2:
        return
    for effect in reversed(searched):
        others = [n for n in search.added if n != effect]
        try:
            reduced = rebuilt(search, others)
        except (FcompError, ValueError):  # a later effect builds on it: it stays
            continue
        search.tick(f"without {effect}")
        verdict = search.judge(effect, search.current, before=reduced)
        if verdict.qualifies:
            continue
        search.fit = reduced
        _mark_removed(search, effect, judgement_text(verdict), forced_too=False)


def drop_no_ops(search: Search) -> None:
    """Take out searched effects whose fitted law does nothing on the record.

    An effect accepted early can end, once later effects carry what it stood in for,
    with its own law degenerate: a Stribeck curve whose break-away level equals the
    Coulomb level (``Fs - Fc`` of 0.3 mN on the NAPN seal, its speed at a bound of its
    box) changes no prediction. The backward check refits the model without it and can
    land in a worse optimum that makes it look needed (NAPN: the level trading against
    the pressure slope, 0.83 against 0.73 N). Here no refit decides: the model without
    the effect, with every other value as fitted, predicts the same force within a tenth
    of the noise floor (RMS over the usable samples) -- the effect is a no-op and goes.
    """
    g = search.ground
    usable = g.split.train | g.split.test
    for effect in [s.effect for s in search.steps if s.accepted and not s.forced]:
        if effect not in search.added:
            continue
        try:
            model, start = reduced(search, [n for n in search.added if n != effect])
            without = search.refit.result(model, start, len(start))
        except (FcompError, ValueError):
            continue
        change = search.current.F_hat[usable] - without.F_hat[usable]
        if float(np.sqrt(np.mean(change**2))) >= search.rule.fall_noise * g.noise:
            continue
        search.tick(f"{effect} does nothing")
        search.fit = search.polish(without)
        _mark_removed(search, effect, "its fitted law does nothing on this record: without it, "
                      "every other value as fitted, the prediction changes by less than a "
                      "tenth of the noise floor", forced_too=False)


def swaps(search: Search, names: Sequence[str]) -> None:
    """Try each searched effect's confounded partners in its place; a tie where one fits
    as well.

    Some effects give the same force over the motions a record holds
    (:attr:`Effect.confounded`). Which one the search takes first can hinge on a
    few samples at rest. Once the search stops, each searched effect with a
    partner not in the model is taken out, the rest refitted, and the partner
    evaluated as a candidate in its place: if its held-out RMS comes within
    ``tie_share`` of the fall the effect brought and the held-out data do not tell
    it from the model with the effect (:meth:`.rule.AcceptanceRule.tie_test`), the
    two are reported as a tie (with the experiment that separates them).
    """
    for k, step in enumerate(search.steps):
        if not step.accepted or step.forced:
            continue
        effect = step.effect
        partners = [p for p in EFFECTS.get(effect).confounded
                    if p in names and p not in search.added
                    and not any(effect in t and p in t for t in search.ties)]
        if not partners or effect not in search.added:
            continue
        others = [n for n in search.added if n != effect]
        try:
            reduced = rebuilt(search, others)
        except (FcompError, ValueError):
            continue
        full = search.current
        ctx = search.context(reduced)
        fit_in = [p for p in partners if catalogue.applicability(p, ctx) is None]
        cands = [c for c in search.evaluate(fit_in, reduced) if c.fit is not None] \
            if fit_in else []
        search.tick(f"in place of {effect}")
        fall = reduced.rms_test - full.rms_test
        if not fall > 0:
            continue
        tests = tuple((c.effect, search.rule.tie_test(full, c.fit, fall, search.ground))
                      for c in cands if c.fit is not None)
        tied = [name for name, t in tests if t.tie]
        step = dataclasses.replace(step, tie_tests=step.tie_tests + tests)
        if tied:
            step = dataclasses.replace(step, tie=tuple(join_tie(search.ties, effect, tied)))
        search.steps[k] = step


def partners_in_model(search: Search) -> None:
    """Report declared confounded partners that are *both* in the final model as a tie.

    Effects that give the same force over the motions a record holds
    (:attr:`Effect.confounded`) can both be accepted, one after the other, each
    taking part of what the record shows; how the force then splits between them
    is not fixed by the record, so they are reported together, with the experiment
    that separates them. The first added leads the group.
    """
    for i, effect in enumerate(search.added):
        join_tie(search.ties, effect, [p for p in search.added[i + 1:]
                                       if p in EFFECTS.get(effect).confounded
                                       or effect in EFFECTS.get(p).confounded])


def join_tie(ties: list[list[str]], effect: str, others: Sequence[str]) -> list[str]:
    """The tie of ``ties`` holding ``effect`` (led by it when new), grown by ``others``."""
    tie = next((t for t in ties if effect in t), None)
    if tie is None:
        if not others:
            return [effect]
        tie = [effect]
        ties.append(tie)
    tie += [e for e in others if e not in tie]
    return tie


def remove(search: Search, effect: str) -> None:
    """Take ``effect`` out of the current model and refit the rest (on request)."""
    if effect not in search.added:
        raise FcompError(f"effect {effect!r} is not in the model (added: "
                         f"{', '.join(search.added) or 'none'})")
    try:
        reduced = rebuilt(search, [n for n in search.added if n != effect])
    except (FcompError, ValueError) as exc:
        raise FcompError(f"cannot remove {effect!r}: {str(exc).splitlines()[0]}") from None
    search.fit = reduced
    search.instances.pop(effect, None)
    _mark_removed(search, effect, "removed on request", forced_too=True)
