"""The search: add, refit and score candidates, one step at a time.

:class:`Search` holds the working state of one diagnosis -- the record (through
its :class:`.refit.Refit`), the current fit, the steps so far -- and runs the
steps; the parallel work and the progress are handed in (an executor and a
callback, :mod:`.workers`), the acceptance rule too (:class:`.rule.AcceptanceRule`).

At every step each applicable candidate (:mod:`.catalogue`) is added to the
current model, the whole model refitted from data-driven starts and judged
against the current fit by the rule. The qualifying candidate with the lowest
held-out RMS is added; every other qualifying candidate whose held-out RMS is
within ``tie_share`` of the best one's fall of it, and which the held-out data do not
tell from the best one (:meth:`.rule.AcceptanceRule.tie_test`), explains the data
equally well and is reported with it as a *tie*. The search stops when no candidate qualifies,
when the held-out RMS is within ``at_floor`` of the noise floor (after the first
step, always evaluated), or after ``max_steps``. Every applicable candidate is
tried again at every step: an effect masked by a larger one can make the error
worse at the first step and be the right one at the second. The checks after the
search (backward, swaps, partners) are in :mod:`.revision`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import time
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import fcomp.diagnosis.catalogue as catalogue
import fcomp.diagnosis.disturbance as disturbance
import fcomp.diagnosis.forms as richer_forms
import fcomp.diagnosis.pairs as pairs
from fcomp.diagnosis.design import Design
from fcomp.diagnosis.noise import NoiseFloor, effective_sample_size, noise_floor
from fcomp.diagnosis.refit import RIG_EXTRAS, FitResult, Refit
from fcomp.diagnosis.rule import AcceptanceRule, Ground, Judgement, TieTest, delta_bic
from fcomp.diagnosis.scoring import sample_weights
from fcomp.diagnosis.wording import judgement_text
from fcomp.diagnosis.workers import refit_all
from fcomp.effects import EFFECTS, Effect
from fcomp.errors import FcompError
from fcomp.identification.plausibility import FitWarning
from fcomp.models import FrictionModel
from fcomp.progress import Tick

#: The baseline and each accepted model are refitted with this many times the budget.
POLISH_NFEV = 4


@dataclass(frozen=True)
class Candidate:
    """One candidate effect at one step, refitted and judged.

    Attributes
    ----------
    effect : str
    fit : FitResult or None
        ``None`` when the refit failed (``failure`` says why).
    rms_heldout : N
    judgement : Judgement or None
        The acceptance rule's findings (``None`` when the refit failed).
    failure : str
        Why the refit failed.
    form : str or None
        The effect's form refitted.
    """

    effect: str
    fit: FitResult | None
    rms_heldout: float
    judgement: Judgement | None = None
    failure: str = ""
    form: str | None = None

    @property
    def fall(self) -> float:
        """``rms_before - rms_heldout`` (N)."""
        return math.nan if self.judgement is None else self.judgement.fall

    @property
    def z(self) -> float:
        return math.nan if self.judgement is None else self.judgement.z

    @property
    def p(self) -> float:
        return math.nan if self.judgement is None else self.judgement.p

    @property
    def delta_bic(self) -> float:
        return math.nan if self.judgement is None else self.judgement.delta_bic

    @property
    def qualifies(self) -> bool:
        return self.judgement is not None and self.judgement.qualifies

    @property
    def reason(self) -> str:
        """Why it does not qualify, in words (empty when it does)."""
        return self.failure if self.judgement is None else judgement_text(self.judgement)


@dataclass(frozen=True)
class Step:
    """One step of the loop: the effect tried (best candidate, or forced) and its outcome."""

    effect: str
    rms_before: float
    rms_after: float
    accepted: bool
    forced: bool = False
    candidates: tuple[Candidate, ...] = ()
    tie: tuple[str, ...] = ()
    fit: FitResult | None = None
    removed: str = ""
    warnings: tuple[FitWarning, ...] = ()
    #: the two effects of a pair found together (:mod:`.pairs`), empty for a single
    pair: tuple[str, ...] = ()
    #: the form of the effect kept (a refined form, :mod:`.forms`; None: its first)
    form: str | None = None
    #: each other qualifying candidate (or confounded partner tried in the effect's place,
    #: :func:`.revision.swaps`) against the effect kept (:meth:`.rule.AcceptanceRule.tie_test`)
    tie_tests: tuple[tuple[str, TieTest], ...] = ()


@dataclass
class Search:
    """The working state of one diagnosis and its steps.

    Parameters
    ----------
    refit
        The record's refits (training samples, weights, held terms).
    ground
        What the rule judges on (held-out pieces, regimes, noise floor).
    noise_floor
        The noise floor and how it was estimated.
    rule
        The acceptance rule.
    pool
        Executor of the candidate refits (``None``: here).
    tick
        Progress callback.
    max_nfev, max_samples
        Evaluation budget of a refit, and the largest record one runs on.
    """

    refit: Refit
    ground: Ground
    noise_floor: NoiseFloor
    rule: AcceptanceRule
    pool: Executor | None
    tick: Tick
    max_nfev: int
    max_samples: int
    baseline_fit: FitResult | None = None
    fit: FitResult | None = None
    steps: list[Step] = field(default_factory=list)
    candidates: list[Candidate] = field(default_factory=list)
    ties: list[list[str]] = field(default_factory=list)
    added: list[str] = field(default_factory=list)
    removed: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    disturbances: list[disturbance.Disturbance] = field(default_factory=list)
    forms: dict[str, str | None] = field(default_factory=dict)
    instances: dict[str, Effect] = field(default_factory=dict)
    seconds: dict[tuple[str, str | None], float] = field(default_factory=dict)
    #: the record's design (:mod:`.design`) and the ties it makes (:mod:`.confounding`)
    design: Design | None = None
    confounding: list[dict[str, Any]] = field(default_factory=list)
    #: the pairs judged where no single candidate qualified (:mod:`.pairs`)
    pairs: list[dict[str, Any]] = field(default_factory=list)
    #: the refined forms of accepted effects tried (:mod:`.forms`)
    refined: list[dict[str, Any]] = field(default_factory=list)
    #: parameters the record's design cannot determine, held in every fit -> why
    #: (:func:`.design.held_by_design`)
    design_held: dict[str, str] = field(default_factory=dict)

    # --------------------------------------------------------------- baseline
    @property
    def current(self) -> FitResult:
        assert self.fit is not None, "the baseline is fitted first"
        return self.fit

    def fit_baseline(self, model: FrictionModel) -> None:
        """Fit the baseline on the training samples: an unweighted first fit, the record's
        periodic disturbances taken off, the channel lag held, the weights set from the
        first fit's prediction band, and the weighted fit polished."""
        g = self.ground
        starts = catalogue.baseline_starts(model, g.data, g.segmentation, g.split.train)
        first = self.refit.fit(model, starts)
        if self._take_lines(first):
            self.tick("periodic disturbance removed")
            first = self.refit.fit(model, [first.values, *starts])
        # the channel lag is the record's: fixed by this unweighted fit, then held
        if "lag" in first.values:
            self.refit.hold("lag", first.values["lag"])
        # the fits from here on weigh samples by how well the motion fixes the prediction
        if first.spread is not None:
            self.refit.set_weights(first.spread, self.ground.noise)
        self.baseline_fit = self.fit = self.polish(self.refit.fit(model, [first.values, *starts]))
        self.tick(f"baseline {model.describe()}")

    def late_disturbances(self) -> None:
        """Lines the baseline's misfit hid, looked for again in the final model's residual.

        A pump's 5 N line under a baseline misfit of 33 N (a missing viscous law)
        does not stand out of the first fit's residual; once the search has explained
        the misfit it does. It is then taken out as the first check takes its lines
        out, and the final model refitted on the cleaned force, so that the verdict
        and the noise floor are those of the record without it.
        """
        fit = self.current
        if fit.plain is None or not self._take_lines(fit):
            return
        if fit.spread is not None:
            self.refit.set_weights(fit.spread, self.ground.noise)
        self.tick("periodic disturbance removed")
        self.fit = self.polish(self.refit.fit(fit.model, [fit.values], list(fit.values)))
        assert self.baseline_fit is not None
        self.baseline_fit = self.refit.rescore(self.baseline_fit)

    def _take_lines(self, fit: FitResult) -> bool:
        """Lines of ``fit``'s plain residual not yet reported, sized against the noise floor
        left without them (:data:`.disturbance.MIN_SHARE`): taken off the force, reported in
        ``disturbances``, the noise floor estimated again and the refits rebuilt on the
        cleaned force (held terms kept). Whether any line was taken."""
        assert fit.plain is not None
        g = self.ground
        known = [d.frequency_hz for d in self.disturbances]
        # gated where the model could not place its prediction (a static law's jump at a
        # reversal within the timing uncertainty: a broadband spike that buries a line)
        weights = None if fit.spread is None else sample_weights(fit.spread, g.noise)
        since = g.segmentation.events(g.data)[0]
        lines = [ln for ln in disturbance.find(fit.plain, self.refit.motion_prediction(fit),
                                                g.data, weights, since)
                 if all(abs(ln[0] - f) > disturbance.SAME_HZ for f in known)]
        if not lines:
            return False
        cleaned = disturbance.without(g.data, [w for _, _, w in lines])
        floor = noise_floor(cleaned, g.segmentation).value
        # sized in the force as matched (a band-limited force attenuates a line), reported
        # at the sensor
        keep = [(ln, disturbance.describe(*ln, g.data)) for ln, d in
                ((ln, disturbance.describe(*ln)) for ln in lines)
                if d.rms >= disturbance.MIN_SHARE * floor]
        if not keep:
            return False
        data = disturbance.without(g.data, [ln[2] for ln, _ in keep])
        self.noise_floor = noise_floor(data, g.segmentation)
        self.ground = Ground.of(data, g.segmentation, g.split, self.noise_floor.value)
        self.disturbances = [*self.disturbances, *(d for _, d in keep)]
        held, kept = dict(self.refit.held), set(self.refit.kept)
        self.refit = Refit(data, g.split, g.segmentation.d_pre, max_nfev=self.max_nfev,
                           max_samples=self.max_samples, noise=self.noise_floor.value)
        for name, value in held.items():
            self.refit.hold(name, value)
        self.refit.kept = set(kept)
        return True

    # ------------------------------------------------------------------ steps
    def context(self, fit: FitResult | None = None) -> catalogue.Context:
        g = self.ground
        return catalogue.Context(g.data, g.segmentation, g.split.train, fit or self.current)

    def judge(self, name: str, after: FitResult, before: FitResult | None = None) -> Judgement:
        """The rule's judgement of ``after`` (with effect ``name``) against ``before``
        (default the current fit)."""
        return self.rule.judge(before or self.current, after, self.ground,
                               EFFECTS.get(name).acts_in)

    def run(self, names: Sequence[str], max_steps: int) -> None:
        """Search ``names`` for up to ``max_steps`` effects (module docstring)."""
        for step_no in range(max_steps):
            if step_no and self.current.rms_test <= self.rule.at_floor * self.ground.noise:
                break
            todo = []
            ctx = self.context()
            for name in names:
                if name in self.added:
                    continue
                reason = catalogue.applicability(name, ctx)
                if reason is not None:
                    self.skipped[name] = reason
                    continue
                self.skipped.pop(name, None)
                todo.append(name)
            if not todo:
                break
            cands = self.evaluate(todo)
            ranked = _ranked(cands)
            good = [c for c in ranked if c.qualifies]
            if good and self._control(good[0]):  # the gain was the optimiser's: judge again
                cands = self._again(cands)
                ranked = _ranked(cands)
                good = [c for c in ranked if c.qualifies]
            if step_no == 0 and not self.added:
                self.candidates = ranked
            if not good:  # a law of another form (:mod:`.forms`), in its plain one's place
                good = self._richer(ranked)
                ranked = _ranked([*good, *(c for c in ranked
                                           if c.effect not in {g.effect for g in good})])
            if not good:
                if self._pair(ranked):  # two effects missing at once (:mod:`.pairs`)
                    continue
                best = ranked[0]
                self.steps.append(Step(best.effect, self.current.rms_test, best.rms_heldout,
                                       False, candidates=tuple(ranked)))
                break
            best = good[0]
            assert best.fit is not None
            tests = tuple((c.effect, self.rule.tie_test(best.fit, c.fit, best.fall, self.ground))
                          for c in good[1:] if c.fit is not None)
            tie = [best.effect, *(name for name, t in tests if t.tie)]
            fit = self.reweighted(self.polish(best.fit))
            self.forms[best.effect] = best.form
            self.steps.append(Step(best.effect, self.current.rms_test, fit.rms_test, True,
                                   candidates=tuple(ranked), tie=tuple(tie), fit=fit,
                                   form=best.form, tie_tests=tests))
            if len(tie) > 1:
                self.ties.append(tie)
            self.fit = fit
            self.added.append(best.effect)
            self.keep_held()

    def _richer(self, ranked: list[Candidate]) -> list[Candidate]:
        """The step's promising candidates in their richer forms that qualify, best first
        (:func:`.forms.candidate_forms`)."""
        found = richer_forms.candidate_forms(self, [(c.effect, c.fit) for c in
                                                    pairs.promising(ranked, self.rule)
                                                    if c.fit is not None])
        best: dict[str, Candidate] = {}
        for name, form, fit, j in found:  # of an effect's forms, the best that qualifies
            if j.qualifies and (name not in best or fit.rms_test < best[name].rms_heldout):
                best[name] = Candidate(name, fit, fit.rms_test, j, form=form)
        return _ranked(list(best.values()))

    def _pair(self, ranked: list[Candidate]) -> bool:
        """Add the best qualifying pair of the step's promising candidates (:mod:`.pairs`),
        as two steps; whether one was added."""
        t0 = time.perf_counter()
        found, judged, self.pool = pairs.find_pair(
            ranked, refit=self.refit, ground=self.ground, rule=self.rule,
            current=self.current, context=self.context, pool=self.pool, tick=self.tick,
            seconds=self.seconds)
        took = time.perf_counter() - t0  # the pair search's cost, reported with each pair
        self.pairs += [{**p.to_dict(), "accepted": p is found, "seconds": took}
                       for p in judged]
        if found is None:
            return False
        first = next(c for c in ranked if c.effect == found.effects[0])
        fit = self.reweighted(self.polish(found.fit))
        before = self.current.rms_test
        for name, form in zip(found.effects, found.forms, strict=True):
            self.forms[name] = form
        self.steps.append(Step(found.effects[0], before, first.rms_heldout, True,
                               candidates=tuple(ranked), fit=None, pair=found.effects,
                               form=found.forms[0]))
        self.steps.append(Step(found.effects[1], first.rms_heldout, fit.rms_test, True,
                               candidates=(), fit=fit, pair=found.effects,
                               form=found.forms[1]))
        self.fit = fit
        self.added += list(found.effects)
        self.keep_held()
        return True

    def keep_held(self) -> None:
        """Keep what the effects in the model hold (their :meth:`~fcomp.effects.Effect.held`
        parameters and their form's) at their no-op values in every later fit
        (:meth:`.Refit.keep`): the candidates of later steps refit the whole model."""
        ctx = self.context()
        names: set[str] = set(self.design_held)
        for name in self.added:
            effect = self.instances.get(name)
            if effect is None:
                names |= set(catalogue.held_of(name, self.forms.get(name), ctx))
                continue
            names |= set(catalogue.form_of(name, self.forms.get(name)).held)
            with contextlib.suppress(FcompError, ValueError, KeyError):
                names |= set(effect.held(ctx.view))
        self.refit.kept = names

    def evaluate(self, names: Sequence[str], fit: FitResult | None = None) -> list[Candidate]:
        """Refit ``fit + effect`` (default the current fit) for every name and judge it."""
        current = fit or self.current
        ctx = self.context(current)
        out: list[Candidate | None] = [None] * len(names)
        proposals = []
        index = []
        for i, name in enumerate(names):
            try:
                forms = catalogue.propose_all(name, ctx)
            except (FcompError, ValueError) as exc:
                out[i] = Candidate(name, None, math.nan, failure=f"cannot start: {exc}")
                continue
            proposals += forms
            index += [i] * len(forms)
        results, self.pool = refit_all(self.refit, proposals, current, self.pool, self.tick,
                                       self.seconds)
        best: dict[int, tuple[FitResult | str, str | None]] = {}
        train = self.ground.split.train
        n_eff = effective_sample_size(current.residual[train])
        for j, prop, res in zip(index, proposals, results, strict=True):
            # of an effect's forms, the one the information criterion prefers on the
            # training samples (a richer form must earn its parameters), all counted
            # with the current model's effective sample size
            prev = best.get(j, (None, None))[0]
            if prev is None or (isinstance(prev, str) and not isinstance(res, str)) or (
                    not isinstance(res, str) and not isinstance(prev, str)
                    and delta_bic(current, res, train, n_eff)
                    < delta_bic(current, prev, train, n_eff)):
                best[j] = (res, prop.form)
        for j, (res, form) in best.items():
            name = names[j]
            if isinstance(res, str):
                out[j] = Candidate(name, None, math.nan, failure=res, form=form)
                continue
            out[j] = Candidate(name, res, res.rms_test, self.judge(name, res, current), form=form)
        return [c for c in out if c is not None]

    def evaluate_instance(self, effect: Effect) -> Candidate:
        """Refit ``current + effect`` (a configured instance) and judge it."""
        model = self.current.model.with_effects(effect)
        flat = model.flat_params()
        start = {**flat, **{k: v for k, v in self.current.values.items()
                            if k in flat or k in RIG_EXTRAS}}
        res = refit_all(self.refit, [catalogue.Proposal(effect.name, model, [start])],
                        self.current, None, self.tick, self.seconds)[0][0]
        if isinstance(res, str):
            return Candidate(effect.name, None, math.nan, failure=res)
        return Candidate(effect.name, res, res.rms_test, self.judge(effect.name, res))

    def force(self, name: str, instance: Effect | None) -> None:
        """Add effect ``name`` (or the configured ``instance``) whatever the rule says."""
        model = self.current.model
        reason = (catalogue.applicability(name, self.context()) if instance is None
                  else _instance_applicability(instance, model, self.ground))
        if reason is not None:
            raise FcompError(f"effect {name!r} cannot be added to {model.describe()}: {reason}")
        cand = self.evaluate([name])[0] if instance is None else self.evaluate_instance(instance)
        if cand.fit is None:
            raise FcompError(f"adding {name!r}: {cand.reason}")
        before = self.current
        fit = self.polish(cand.fit)
        self.forms[name] = cand.form
        if instance is not None:
            self.instances[name] = instance
        self.steps.append(Step(name, before.rms_test, fit.rms_test, cand.qualifies, forced=True,
                               candidates=(cand,), fit=fit))
        self.fit = fit
        self.added.append(name)
        self.keep_held()

    def _control(self, best: Candidate) -> bool:
        """Refit the current model from the best candidate's values; True if that alone helps.

        A candidate refitted from fresh starts may land in a better optimum of
        the parameters it shares with the current model -- a gain of the
        optimiser, not of the effect. The current model, started from the
        candidate's values of its own parameters, is refitted; if its held-out
        error then falls clearly (by ``fall_noise`` of the noise floor) it replaces
        the current fit and the candidates are judged again against it.
        """
        assert best.fit is not None
        cur = self.current
        own = {k: v for k, v in best.fit.values.items() if k in cur.values}
        if set(own) != set(cur.values):
            return False
        try:
            control = self.polish(self.refit.fit(cur.model, [own, cur.values], list(cur.values)))
        except FcompError:
            return False
        if not control.rms_test < cur.rms_test - self.rule.fall_noise * self.ground.noise:
            return False
        self.tick("control refit")
        self.fit = self.reweighted(control)
        if self.steps:
            self.steps[-1] = dataclasses.replace(self.steps[-1], fit=self.fit,
                                                 rms_after=self.fit.rms_test)
        else:
            self.baseline_fit = self.fit
        return True

    def _again(self, cands: list[Candidate]) -> list[Candidate]:
        """``cands`` judged again after :meth:`_control` replaced the current fit.

        The candidates that qualified are refitted from the new current fit (their
        gain may have been the optimiser's); the others keep their refits and are
        judged against the new fit: it is better on the training samples than the one
        they failed to beat, and a refit from it would not change that -- refitting
        them all doubled the step's time for the same answer.
        """
        fresh = {c.effect: c for c in self.evaluate([c.effect for c in cands if c.qualifies])}
        return [fresh[c.effect] if c.effect in fresh else
                c if c.fit is None else dataclasses.replace(c, judgement=self.judge(c.effect,
                                                                                    c.fit))
                for c in cands]

    def reweighted(self, fit: FitResult) -> FitResult:
        """``fit`` polished again after the sample weights follow its own prediction.

        The weights (:meth:`.Refit.set_weights`) come from the uncertainty of the
        current model's prediction; a model accepted with another structure (a
        bristle where a static map jumped) changes where that is, so it is
        refitted with its own weights before the next step starts from it. A
        held channel lag is first estimated again for it (:meth:`.Refit.refit_held`).
        """
        if "lag" in self.refit.held:  # the channel lag, estimated again for this model
            self.refit.refit_held("lag", fit)
            fit = self.refit.rescore(fit)
        if fit.spread is None:
            return fit
        self.refit.set_weights(fit.spread, self.ground.noise)
        return self.polish(fit, fresh=True)

    def polish(self, fit: FitResult, fresh: bool = False) -> FitResult:
        """``fit`` continued to convergence (:data:`POLISH_NFEV` times the budget), if that helps.

        Every candidate is refitted from the current model with the normal
        budget; were the current model itself short of its optimum, any
        candidate would gain from the extra iterations alone and look like a
        found effect. So the baseline and every accepted model are polished
        first; the better of the two fits (training error) is kept. With
        ``fresh`` the model's base parameters also start afresh from the data
        (:func:`.catalogue.baseline_starts`, the effects' parameters kept): an
        accepted model may carry a local optimum the candidate's refit landed in,
        which the next candidate's fresh start would otherwise escape and be
        credited for.
        """
        if not fit.model.symbolic or not fit.values:
            return fit
        starts = [fit.values]
        if fresh:
            g = self.ground
            try:
                base = catalogue.baseline_starts(fit.model, g.data, g.segmentation, g.split.train)
            except (FcompError, ValueError, ArithmeticError):
                base = []
            starts += [{**fit.values, **{k: v for k, v in b.items() if k in fit.values}}
                       for b in base[:2]]
        try:
            more = self.refit.fit(fit.model, starts, list(fit.values),
                                  max_nfev=POLISH_NFEV * self.max_nfev)
        except FcompError:
            return fit
        return more if more.rms_train < fit.rms_train else fit


def _ranked(cands: list[Candidate]) -> list[Candidate]:
    """Candidates best first (lowest held-out RMS; failed refits last)."""
    return sorted(cands, key=lambda c: (math.isnan(c.rms_heldout), c.rms_heldout))


def _instance_applicability(effect: Effect, model: FrictionModel, ground: Ground) -> str | None:
    """Why a configured effect cannot be added to ``model`` on the record (None if it can)."""
    if not effect.applies_to(model):
        return f"already part of {model.describe()} or not applicable to it"
    for sig in effect.needs:
        if not ground.data.available.get(sig, False):
            return f"needs {sig}: {ground.data.reasons.get(sig, 'not available')}"
    return None
