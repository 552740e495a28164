"""The add / refit / score loop: which catalogue effect is missing, if any.

:class:`Diagnosis` (sklearn style: options in the constructor, :meth:`fit`
returns ``self``, results in ``*_`` attributes) runs the whole procedure:

1. **Data.** The records are cut into experiments (:mod:`.data`), segmented
   into regimes (:mod:`.regimes`), split into training and held-out samples
   by experiment or contiguous segment (:mod:`.split`); the noise floor is
   estimated from them (:mod:`.noise`).
2. **Baseline.** The baseline model is fitted on the training samples
   (:mod:`.refit`) and scored on the held-out ones.
3. **Search.** At every step each applicable candidate (:mod:`.catalogue`)
   is added to the current model, the whole model is refitted from
   data-driven starts, and scored on held-out data. A candidate
   *qualifies* when all of these hold:

   * the held-out RMS falls, and falls clearly where the candidate acts:
     on the held-out pieces (contiguous, about 0.25 s, :func:`heldout_pieces`;
     steady-state points are pieces of their own) where the candidate changes
     the prediction materially (by a tenth of the noise floor, RMS), the RMS
     falls by at least ``max(0.1*noise_floor, 0.02*rms_before)`` and by at
     least half the excess mean square over the noise floor there,
     ``rms_before^2 - rms_after^2 >= 0.5*(rms_before^2 - noise_floor^2)`` (a
     small dent in a large unexplained residual is not a found effect); both
     RMS values without the 1 % of samples where both residuals are largest
     (:func:`paired_trimmed_rms`: a spike both carry is timing, one the
     candidate removes is what it explains).
     Judging the fall where the candidate acts lets an effect that shows only
     at break-aways or reversals be found in a record that is mostly sliding;
   * the fall is significant: a Diebold-Mariano test on the squared-error
     differences of those pieces, with a long-run (Newey-West) variance for
     the correlated residuals, has a one-sided p-value of at most 0.05
     (:func:`fall_test`);
   * the Bayesian information criterion on the training residuals, computed
     with the effective sample size of the candidate's residuals, agrees:
     ``dBIC = n_eff*ln(RSS_after/RSS_before) + dk*ln(n_eff) < 0``.

   The qualifying candidate with the lowest held-out RMS is added. Every
   other qualifying candidate whose held-out RMS is within 10 % of the best
   one's fall of it explains the data equally well (a practical equivalence:
   with correlated residuals a significance test between two near-identical
   predictions finds differences nobody could act on): they are reported
   together as a *tie* (a confounded group), each with the experiment that
   would tell them apart. The search stops when no candidate qualifies, when the
   held-out RMS is within 5 % of the noise floor (after the first step,
   which is always evaluated), or after ``max_steps``.
   Every applicable candidate is tried again at every step: an effect
   masked by a larger one (a direction asymmetry under a pressure
   dependence) can make the error worse at the first step and be the right
   one at the second.
   Once the search stops, a *backward check* takes each searched effect out
   again (last added first) and refits the rest: an effect that would no
   longer qualify when put back is redundant -- it stood in for part of what
   a later effect explains -- and stays out (``removed_``).
4. **Verdict.** The final residual is tested for structure left
   (:mod:`.features`): ``unexplained-structure`` when some feature explains
   at least :data:`STRUCTURE_MIN` of its held-out mean square *and* the part
   it explains is at least half the noise floor (RMS), when the residual near
   starts and reversals (weighted as the fits weigh it: :func:`.refit.sample_weights`)
   repeats as a function of the time since the event (:func:`.features.event_structure`)
   or, not in phase, lifts the RMS there above :data:`EVENT_EXCESS` noise floors
   or rings there (a narrow band of power quiet stretches lack, :func:`.features.event_ring`),
   or when the final
   held-out RMS, without its largest 1 % of samples (isolated timing spikes,
   :func:`trimmed_rms`), is more than twice the noise floor; else ``explained``.
   The tool never accepts an effect that does not qualify just because
   structure remains: it says so instead.

:meth:`Diagnosis.add_effect` is the one call that adds an effect (from the
catalogue or registered by the user) to the current model, refits it and
records the step, so the error-fall chart shows it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import sys
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

import fcomp.diagnosis.catalogue as catalogue
import fcomp.diagnosis.disturbance as disturbance
from fcomp.diagnosis.data import DiagnosisData, prepare
from fcomp.diagnosis.features import (
    TRIM,
    FeatureStrength,
    drift_fall,
    event_ring,
    event_structure,
    paired_trimmed_rms,
    residual_structure,
    trimmed_rms,
)
from fcomp.diagnosis.noise import NoiseFloor, effective_sample_size, noise_floor
from fcomp.diagnosis.refit import (
    RIG_EXTRAS,
    FitResult,
    Refit,
    sample_weights,
    score_noise_share,
)
from fcomp.diagnosis.regimes import REGIMES, Segmentation, segment
from fcomp.diagnosis.residuals import regime_errors
from fcomp.diagnosis.split import Split, make_split
from fcomp.effects import EFFECTS, Effect
from fcomp.errors import FcompError
from fcomp.identification.plausibility import FitWarning
from fcomp.measurement import Measurement
from fcomp.models import FrictionModel, make_model
from fcomp.parallel import executor, process_pool

#: Largest one-sided p-value of a held-out fall that counts as significant.
ACCEPT_P = 0.05
#: A clear fall: at least this fraction of the noise floor ...
FALL_NOISE = 0.1
#: ... and this share of the excess mean square over the noise floor.
EXCESS_SHARE = 0.5
#: ... and of the held-out RMS before.
FALL_RELATIVE = 0.02
#: Falls below this share of the record's force scale are rounding, not evidence
#: (an exact table of points is fitted to 1e-15 N by the right model already).
FALL_NUMERIC = 1e-9
#: An effect that declares the regimes its signature lives in (``Effect.acts_in``) must
#: take at least this share of its held-out fall (in mean square) there.
SIGNATURE_SHARE = 2.0 / 3.0
#: Candidates within this share of the best candidate's fall tie with it.
TIE_SHARE = 0.1
#: The search stops when the held-out RMS is within this factor of the noise floor.
AT_FLOOR = 1.05
#: Feature strength above which the residual "still follows" a feature.
STRUCTURE_MIN = 0.15
#: Structure must explain at least this RMS, in noise floors, to count: a structure
#: smaller than the noise is a law's shape not quite matched, not a missing effect.
STRUCTURE_RMS = 1.0
#: ... and this share of the friction level (the record's force scale).
STRUCTURE_LEVEL = 0.015
#: Residual RMS (trimmed) after events above this many noise floors is structure after
#: events even where it does not repeat in phase (a ring whose start the velocity jitters).
EVENT_EXCESS = 3.0
#: A ring after events (:func:`.features.event_ring`) counts when this share of its excess
#: power lies in three adjacent bins (narrow: a mode, not a misplaced step) ...
RING_CONCENTRATION = 0.6
#: ... and it carries this many noise floors (RMS in the windows after events) ...
RING_NOISE = 0.5
#: ... and this share of the friction level: a mode is no law's shape left unmatched, so
#: it counts below the noise that :data:`STRUCTURE_RMS` asks of other structure.
RING_LEVEL = 0.005
#: Residual RMS (trimmed, :func:`trimmed_rms`) above this many noise floors is
#: unexplained structure whatever the features say.
EXCESS_MAX = 2.0
#: The baseline and each accepted model are refitted with this many times the budget.
POLISH_NFEV = 4
VERDICTS = ("explained", "unexplained-structure")


@dataclass
class Candidate:
    """One candidate effect at one step, refitted and scored.

    Attributes
    ----------
    effect : str
    fit : FitResult or None
        ``None`` when the refit failed (``reason`` says why).
    rms_heldout : N
    fall : N
        ``rms_before - rms_heldout``.
    z, p : float
        Statistic of the fall test (:func:`fall_test`) and its one-sided p-value.
    delta_bic : float
        BIC change on the training residuals with the effective sample size.
    qualifies : bool
        Whether it passes the acceptance rule.
    reason : str
        Why it does not qualify (empty when it does).
    """

    effect: str
    fit: FitResult | None
    rms_heldout: float
    fall: float = math.nan
    z: float = math.nan
    p: float = math.nan
    delta_bic: float = math.nan
    qualifies: bool = False
    reason: str = ""
    form: str | None = None


@dataclass
class Step:
    """One step of the loop: the effect tried (best candidate, or forced) and its outcome."""

    effect: str
    rms_before: float
    rms_after: float
    accepted: bool
    forced: bool = False
    candidates: list[Candidate] = field(default_factory=list)
    tie: list[str] = field(default_factory=list)
    fit: FitResult | None = None
    removed: str = ""
    warnings: list[FitWarning] = field(default_factory=list)


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r**2))) if r.size else math.nan


def heldout_pieces(test: np.ndarray, starts: Sequence[int], dt: float) -> list[np.ndarray]:
    """Held-out samples cut into contiguous pieces for the fall test.

    Each run of held-out samples (not crossing an experiment start) is cut into
    pieces of about ``max(0.25 s, 20 samples)``; a shorter tail joins the piece
    before it.
    """
    length = max(20, int(round(0.25 / dt)))
    cut = np.zeros(test.size, dtype=bool)
    cut[list(starts)] = True
    edges = np.flatnonzero(np.diff(np.concatenate([[0], test.astype(int), [0]])))
    pieces: list[np.ndarray] = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        inner = [a, *[int(k) for k in np.flatnonzero(cut[a + 1:b]) + a + 1], b]
        for lo, hi in zip(inner[:-1], inner[1:], strict=True):
            n = (hi - lo) // length
            bounds = [lo + k * length for k in range(max(n, 1))] + [hi]
            for u, w in zip(bounds[:-1], bounds[1:], strict=True):
                if w - u >= 5:
                    pieces.append(np.arange(u, w))
    return pieces


def fall_test(r_before: np.ndarray, r_after: np.ndarray, blocks: Sequence[np.ndarray],
              min_change: float) -> tuple[float, float]:
    """``(z, p)``: does the held-out error fall where the prediction changed?

    A test of equal predictive accuracy in the manner of Diebold & Mariano
    (1995) on the squared-error differences ``d_t = r_before_t^2 - r_after_t^2``
    of the held-out pieces where the two models' predictions differ materially
    (RMS difference at least ``min_change``), *conditional on the prediction
    change*: with ``D_t = r_before_t - r_after_t`` (the change, fixed by the
    training samples, independent of the held-out noise),
    ``d_t = D_t^2 + 2*D_t*r_after_t``, so the held-out randomness of ``sum(d)`` is
    that of ``2*sum(g)``, ``g_t = D_t*r_after_t``. ``z = sum(d) / (2*sqrt(V))``,
    one-sided normal p-value, ``V`` the Newey-West (Bartlett-weighted) long-run
    variance of ``sum(g)`` with autocovariances taken within each piece only, up
    to lag ``L = len/4`` of the piece: residuals are correlated in time, and the
    test accounts for it. Fewer than two such pieces: ``p = 1`` (a change seen
    once is not evidence).

    Why conditional: the variance of ``d`` itself counts the spread of ``D^2``
    -- of the effect's own size from event to event -- as noise. An effect
    acting on a few large events (break-away peaks after dwells, a tight spot
    met a few times) then tests at ``z ~ sqrt(events)`` however far above the
    noise each event stands (``z`` 1.4 for a 2.25 -> 0.79 N fall carried by three
    break-aways). Conditional on ``D`` its evidence grows with the size of the
    events against the residual left, as it should; for a change spread over the
    record the two tests agree (checked candidate by candidate).
    """
    used = changed_pieces(r_before, r_after, blocks, min_change)
    if len(used) < 2:
        return math.nan, 1.0
    total = float(sum(np.sum(r_before[b] ** 2 - r_after[b] ** 2) for b in used))
    gs = [(r_before[b] - r_after[b]) * r_after[b] for b in used]
    mean = float(sum(np.sum(g) for g in gs)) / sum(g.size for g in gs)
    var = 0.0
    for g in gs:
        c = g - mean
        var += float(c @ c)
        lag = g.size // 4
        for k in range(1, lag + 1):
            var += 2.0 * (1.0 - k / (lag + 1)) * float(c[k:] @ c[:-k])
    if var <= 0.0:
        return (math.copysign(math.inf, total), 0.0 if total > 0 else 1.0) if total else (0.0, 0.5)
    z = total / (2.0 * math.sqrt(var))
    return z, float(stats.norm.sf(z))


def changed_pieces(r_before: np.ndarray, r_after: np.ndarray, blocks: Sequence[np.ndarray],
                   min_change: float) -> list[np.ndarray]:
    """The held-out pieces where the prediction changed by at least ``min_change`` (RMS, N)."""
    return [b for b in blocks
            if float(np.sqrt(np.mean((r_before[b] - r_after[b]) ** 2))) >= min_change]


def delta_bic(before: FitResult, after: FitResult, train: np.ndarray,
              n_eff: float | None = None) -> float:
    """``n_eff*ln(RSS_after/RSS_before) + (k_after - k_before)*ln(n_eff)`` (training residuals).

    ``n_eff`` defaults to the effective sample size of ``after``'s residual; fits
    compared with each other against one ``before`` (the forms of an effect) must
    share one, or the fit with the more correlated residual -- often the better
    fit, whose error is left in a few places -- counts fewer samples and looks worse.
    """
    ra, rb = after.residual[train], before.residual[train]
    rss_a, rss_b = float(ra @ ra), float(rb @ rb)
    if rss_b <= 0 or rss_a <= 0:
        return -math.inf if rss_a < rss_b else math.inf
    n_eff = max(effective_sample_size(ra) if n_eff is None else n_eff, 2.0)
    return n_eff * math.log(rss_a / rss_b) + (after.n_params - before.n_params) * math.log(n_eff)


# ------------------------------------------------------------- parallel jobs
#: Evaluation budget of a refit without exact sensitivities (finite differences).
NONSYMBOLIC_NFEV = 8


def _ready() -> None:
    """A worker's first job: nothing; unpickling it imports this module and what it needs."""


def refit_candidate(refit: Refit, prop: catalogue.Proposal, current: FitResult
                    ) -> FitResult | str:
    """Refit one proposal; a string says why it could not be.

    A model without exact sensitivities (discrete memory, finite-difference
    Jacobians, slow) is first *screened*: its data-driven start must lower the
    training error of the current model, else it is not refitted.
    """
    try:
        if not prop.model.symbolic:
            probe = refit.result(prop.model, {}, 0)
            if not probe.rms_train < current.rms_train:
                return ("screened out: its data-driven start does not lower the training error "
                        f"({probe.rms_train:.4g} N >= {current.rms_train:.4g} N)")
            return refit.fit(prop.model, prop.starts, prop.free, max_nfev=NONSYMBOLIC_NFEV)
        return refit.fit(prop.model, prop.starts, prop.free,
                         reference=refit.train_cost(current.model, current.values), fast=True)
    except (FcompError, ValueError, ArithmeticError) as exc:
        return f"refit failed: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}"


def timed_refit_candidate(refit: Refit, prop: catalogue.Proposal, current: FitResult
                          ) -> tuple[FitResult | str, float]:
    """:func:`refit_candidate` and the seconds it took where it ran (a worker's own clock)."""
    t0 = time.perf_counter()
    out = refit_candidate(refit, prop, current)
    return out, time.perf_counter() - t0


class Diagnosis:
    """Compare a model with measurements, find the missing effect, add it, watch the error fall.

    Parameters
    ----------
    baseline
        Model name (``coulomb`` ... ``gms``) or a :class:`~fcomp.models.base.FrictionModel`.
    effects
        Candidate effect names (default: every registered effect at :meth:`fit` time).
    add
        Effects to add first, in order, whatever the rule says (one step each).
    search
        Search the candidates after the forced additions.
    split
        ``"auto"``, ``"experiment"`` or ``"segment"`` (:mod:`.split`).
    cutoff_hz
        Cutoff of the filter deriving ``v``, ``a`` from ``x`` (default from the rate).
    max_steps
        Most effects the search adds.
    n_jobs
        Processes refitting candidates in parallel (default: the CPU count, at most 4).
    scheduler
        Address of a Dask distributed scheduler: the candidate refits run on its
        workers instead (:mod:`fcomp.parallel`; the results are the same).
    max_nfev
        Evaluation budget of each refit.
    max_samples
        Largest record a refit runs on (longer ones are block-averaged for fitting).
    progress
        Show a progress bar on stderr.
    check_baseline
        After the search, diagnose the record again from a baseline of the other
        kind (static <-> dynamic, :func:`other_baseline`) and say whether the
        answer depends on the baseline (``baseline_dependent_``): ``True``
        always, ``False`` never, ``"auto"`` (default) when the first answer is
        doubtful (:meth:`doubts`: the final fit flagged, a tie, or structure left) --
        a second opinion costs a second diagnosis, and a clean answer from
        well-determined fits does not need one.

    Attributes
    ----------
    data_, segmentation_, split_, noise_floor_
        The prepared data, regimes, held-out split and noise floor.
    baseline_fit_, fit_ : FitResult
        The baseline and the final model fitted on the training samples.
    steps_ : list of Step
    candidates_ : list of Candidate
        First-step candidates, best first.
    ties_ : list of list of str
    added_ : list of str
        Effects in the final model, in the order they were added.
    removed_ : list of str
        Searched effects the backward check took out again (redundant once
        later effects were in; their steps are marked not accepted).
    skipped_ : dict
        Effect -> why it was not a candidate (at the last step it was considered).
    rms_baseline_, rms_final_ : N
        Held-out RMS of the baseline and the final model.
    verdict_ : str
        ``"explained"`` or ``"unexplained-structure"``.
    reason_ : str
        The rule that decided the verdict, with its numbers.
    baseline_dependent_ : bool
        Whether a baseline of the other kind finds other effects (``check_baseline``).
    other_ : Diagnosis or None
        That other diagnosis.
    baseline_check_ : dict
        ``{"ran": bool, "why": str}``: whether the check ran, and why (or why not).
    warnings_ : list of FitWarning
        What a careful engineer would question: the plausibility of the baseline's
        and the final model's fits (:mod:`fcomp.identification.plausibility`) and
        what the held-out data cannot judge (``heldout-coverage``).
    residual_features_ : list of FeatureStrength
        Features of the final held-out residual, strongest first.
    """

    def __init__(
        self,
        baseline: str | FrictionModel,
        *,
        effects: Sequence[str] | None = None,
        add: Sequence[str | Effect] = (),
        search: bool = True,
        split: str = "auto",
        cutoff_hz: float | None = None,
        max_steps: int = 6,
        n_jobs: int | None = None,
        scheduler: str | None = None,
        max_nfev: int = 60,
        max_samples: int = 40_000,
        progress: bool = False,
        check_baseline: bool | str = "auto",
    ) -> None:
        self.baseline = baseline
        self.effects = effects
        self.add = add
        self.search = search
        self.split = split
        self.cutoff_hz = cutoff_hz
        self.max_steps = max_steps
        self.n_jobs = n_jobs
        self.scheduler = scheduler
        self.max_nfev = max_nfev
        self.max_samples = max_samples
        self.progress = progress
        self.check_baseline = check_baseline

    # ------------------------------------------------------------------ fit
    def fit(self, data: Measurement | Sequence[Measurement] | DiagnosisData) -> Diagnosis:
        """Run the diagnosis on ``data`` (one or several measurements); returns ``self``."""
        model = make_model(self.baseline) if isinstance(self.baseline, str) else self.baseline
        if not isinstance(model, FrictionModel):
            raise FcompError(f"baseline must be a model name or a FrictionModel, got "
                             f"{self.baseline!r}")
        names = list(self.effects) if self.effects is not None else EFFECTS.names()
        for n in [*names, *self.add]:
            EFFECTS.get(n if isinstance(n, str) else n.name)  # unknown names fail here
        self.baseline_name_ = self.baseline if isinstance(self.baseline, str) else model.describe()
        self.__dict__.pop("baseline_check_", None)
        self.baseline_dependent_ = False
        self.data_ = data if isinstance(data, DiagnosisData) else prepare(
            data, cutoff_hz=self.cutoff_hz)
        self.segmentation_ = segment(self.data_)
        self._check_support(model)
        self.split_ = make_split(self.data_, self.segmentation_.valid, self.split)
        self.noise_floor_ = noise_floor(self.data_, self.segmentation_)
        self._refit = Refit(self.data_, self.split_, self.segmentation_.d_pre,
                            max_nfev=self.max_nfev, max_samples=self.max_samples,
                            noise=self.noise_floor_.value)
        self._blocks = [np.array([k]) for k in np.flatnonzero(self.split_.test)] \
            if self.data_.steady_state else \
            heldout_pieces(self.split_.test, [e.start for e in self.data_.experiments],
                                   self.data_.scales.dt)
        self._bar = _progress(self.progress)
        # a pool lent by the diagnosis whose baseline check this is (:meth:`_other_baseline`)
        self._lent: Executor | None = self.__dict__.pop("_lent_pool", None)
        self._pool: Executor | None = self._lent
        self._seconds: dict[tuple[str, str | None], float] = {}  # a refit's duration, by form
        self._cluster = contextlib.ExitStack()
        self._fitting = True
        try:  # one path shuts this diagnosis's workers down, whatever happens
            try:
                if self.search:
                    self._start_workers(len(names))
                starts = catalogue.baseline_starts(model, self.data_, self.segmentation_,
                                                   self.split_.train)
                first = self._refit.fit(model, starts)
                first = self._disturbances(model, first, starts)
                # the channel lag is the record's: fixed by this unweighted fit, then held
                if "lag" in first.values:
                    self._refit.hold("lag", first.values["lag"])
                # the fits from here on weigh samples by how well the motion fixes the prediction
                if first.spread is not None:
                    self._refit.set_weights(first.spread, self.noise_floor_.value)
                self.baseline_fit_ = self._polish(self._refit.fit(model, [first.values, *starts]))
                self._tick(f"baseline {model.describe()}")
                self.fit_ = self.baseline_fit_
                self.steps_: list[Step] = []
                self.candidates_: list[Candidate] = []
                self.ties_: list[list[str]] = []
                self.added_: list[str] = []
                self.skipped_: dict[str, str] = {}
                self.removed_: list[str] = []
                self._forms: dict[str, str | None] = {}
                self._instances: dict[str, Effect] = {}
                for name in self.add:
                    self.add_effect(name)
                if self.search:
                    self._search(names)
                    self._backward()
                    self._swaps(names)
                    self._partners_in_model()
                self._late_disturbances()
            finally:
                self._bar.close()
                self._fitting = False
            self._conclude()
            self._check(model, names)  # a second diagnosis: it borrows these workers
        finally:
            self._close_workers()
        return self

    def _start_workers(self, candidates: int) -> None:
        """Start the local worker processes now, beside the baseline fit, not when the first
        step needs them: each takes a second or more to start and import fcomp, on the
        critical path of the first step otherwise. Not for fewer than two ``candidates``
        (their refits run here, :meth:`_workers`)."""
        if self.scheduler or self._pool is not None:
            return
        pool = self._workers(candidates)
        for _ in range(self._n_workers() if pool is not None else 0):
            pool.submit(_ready)  # type: ignore[union-attr]

    def _close_workers(self) -> None:
        """Shut down this diagnosis's own pool (not a lent one) and its cluster context."""
        if self._pool is not None and self._pool is not self._lent:
            self._pool.shutdown()
        self._pool = None
        self._cluster.close()

    def _disturbances(self, model: FrictionModel, first: FitResult,
                      starts: list[dict[str, float]]) -> FitResult:
        """Find periodic disturbances in the first fit's residual (:mod:`.disturbance`); take
        them off the force, estimate the noise floor again and refit the baseline."""
        self.disturbances_: list[disturbance.Disturbance] = []
        if not self._take_lines(first):
            return first
        self._tick("periodic disturbance removed")
        return self._refit.fit(model, [first.values, *starts])

    def _late_disturbances(self) -> None:
        """Lines the baseline's misfit hid, looked for again in the final model's residual.

        A pump's 5 N line under a baseline misfit of 33 N (a missing viscous law)
        does not stand out of the first fit's residual; once the search has explained
        the misfit it does. It is then taken out as the first check takes its lines
        out, and the final model refitted on the cleaned force, so that the verdict
        and the noise floor are those of the record without it.
        """
        fit = self.fit_
        if fit.plain is None or not self._take_lines(fit):
            return
        if fit.spread is not None:
            self._refit.set_weights(fit.spread, self.noise_floor_.value)
        self._tick("periodic disturbance removed")
        self.fit_ = self._polish(self._refit.fit(fit.model, [fit.values], list(fit.values)))
        self.baseline_fit_ = self._refit.rescore(self.baseline_fit_)

    def _take_lines(self, fit: FitResult) -> bool:
        """Lines of ``fit``'s plain residual not yet reported, sized against the noise floor
        left without them (:data:`disturbance.MIN_SHARE`): taken off the force, reported in
        ``disturbances_``, the noise floor estimated again and the refits rebuilt on the
        cleaned force (held terms kept). Whether any line was taken."""
        assert fit.plain is not None
        known = [d.frequency_hz for d in self.disturbances_]
        # gated where the model could not place its prediction (a static law's jump at a
        # reversal within the timing uncertainty: a broadband spike that buries a line)
        weights = None if fit.spread is None else sample_weights(fit.spread,
                                                                   self.noise_floor_.value)
        since = self.segmentation_.events(self.data_)[0]
        lines = [ln for ln in disturbance.find(fit.plain, self._refit.motion_prediction(fit),
                                                self.data_, weights, since)
                 if all(abs(ln[0] - f) > disturbance.SAME_HZ for f in known)]
        if not lines:
            return False
        cleaned = disturbance.without(self.data_, [w for _, _, w in lines])
        floor = noise_floor(cleaned, self.segmentation_).value
        # sized in the force as matched (a band-limited force attenuates a line), reported
        # at the sensor
        keep = [(ln, disturbance.describe(*ln, self.data_)) for ln, d in
                ((ln, disturbance.describe(*ln)) for ln in lines)
                if d.rms >= disturbance.MIN_SHARE * floor]
        if not keep:
            return False
        self.data_ = disturbance.without(self.data_, [ln[2] for ln, _ in keep])
        self.noise_floor_ = noise_floor(self.data_, self.segmentation_)
        self.disturbances_ = [*self.disturbances_, *(d for _, d in keep)]
        held = dict(self._refit.held)
        self._refit = Refit(self.data_, self.split_, self.segmentation_.d_pre,
                            max_nfev=self.max_nfev, max_samples=self.max_samples,
                            noise=self.noise_floor_.value)
        for name, value in held.items():
            self._refit.hold(name, value)
        return True

    def doubts(self) -> list[str]:
        """Why the answer might depend on the baseline (empty: a clean answer).

        The final model's fit flagged (a parameter at a bound, an interval
        through zero, an implausible mass, ...), a tie, or a verdict of
        ``unexplained-structure``. The baseline's own flags do not count when
        effects were added: a baseline that misses an effect is expected to
        bend its parameters (the final model, once they are added, is what is
        asserted).
        """
        out = []
        if self.verdict_ != "explained":
            out.append(f"the verdict is {self.verdict_}")
        fits = sorted({w.code for w in self._final_warnings})
        if fits:
            out.append(f"the final fit is flagged ({', '.join(fits)})")
        if self.ties_:
            out.append("effects tie")
        return out

    def _check(self, model: FrictionModel, names: list[str]) -> None:
        """Run the baseline check as ``check_baseline`` asks, and fold its answer in."""
        self.other_ = None
        if self.check_baseline not in (True, False, "auto"):
            raise FcompError(f"check_baseline must be True, False or 'auto', got "
                             f"{self.check_baseline!r}")
        doubts = self.doubts()
        if self.check_baseline is False:
            self.baseline_check_ = {"ran": False, "why": "not asked for"}
        elif self.check_baseline == "auto" and not doubts:
            self.baseline_check_ = {"ran": False, "why": "a clean answer: final fit not flagged, "
                                    "no tie, explained to the noise"}
        else:
            why = "asked for" if self.check_baseline is True else "; ".join(doubts)
            self._bar = _progress(self.progress)
            try:
                self.other_ = self._other_baseline(model, names)
            finally:
                self._bar.close()
            self.baseline_check_ = {"ran": self.other_ is not None, "why": why if self.other_
                                    is not None else "no baseline of the other kind fits "
                                    "these data"}
        self._fold_dependence()

    def _fold_dependence(self) -> None:
        """``baseline_dependent_``, and the other baseline's answer in the reason if it differs."""
        dep = self.baseline_dependence()
        self.baseline_dependent_ = bool(dep and dep["dependent"])
        if dep and dep["dependent"]:
            self.reason_ += (f"; the effects found depend on the baseline: from "
                             f"{dep['baseline']} the diagnosis adds "
                             f"{', '.join(dep['added']) or 'nothing'} ({dep['verdict']})")

    def _other_baseline(self, model: FrictionModel, names: list[str]) -> Diagnosis | None:
        """The same diagnosis from a baseline of the other kind, or None where none applies."""
        other = other_baseline(model, self.data_, self.segmentation_)
        if other is None:
            return None
        self._tick(f"baseline check: {other}")
        d = Diagnosis(other, effects=names, add=[], search=self.search, split=self.split,
                      cutoff_hz=self.cutoff_hz, max_steps=self.max_steps, n_jobs=self.n_jobs,
                      scheduler=self.scheduler,
                      max_nfev=self.max_nfev, max_samples=self.max_samples,
                      check_baseline=False)
        d._lent_pool = self._pool  # type: ignore[attr-defined]  # the same workers, warm
        try:
            return d.fit(self.data_)
        except FcompError:
            return None

    def baseline_dependence(self) -> dict[str, Any] | None:
        """Whether the effects found depend on the baseline, and the other baseline's answer.

        The added effects are compared after leaving out, on each side, the
        effects the *other* baseline already holds (``presliding`` added to a
        static map is part of LuGre) and counting the members of a reported tie
        as one. ``None`` without a check.
        """
        other = getattr(self, "other_", None)
        if other is None:
            return None
        mine = _comparable(self.added_, self.ties_, other.baseline_fit_.model)
        theirs = _comparable(other.added_, other.ties_, self.baseline_fit_.model)
        return {"dependent": not _same_findings(mine, theirs), "baseline": other.baseline_name_,
                "added": list(other.added_), "verdict": other.verdict_,
                "rms_baseline": other.rms_baseline_, "rms_final": other.rms_final_}

    def _tick(self, what: str) -> None:
        self._bar.set_postfix_str(what, refresh=False)
        self._bar.update(1)

    def _check_support(self, model: FrictionModel) -> None:
        """Refuse a baseline the data cannot support, saying why."""
        data, seg = self.data_, self.segmentation_
        v = data.signal("v")
        moving = int(np.sum(np.abs(v) > max(seg.v_rest, 1e-12)))
        label = ", ".join(data.labels[:3]) + (" ..." if len(data.labels) > 3 else "")
        if moving < 20:
            raise FcompError(f"{label}: the piston hardly moves ({moving} samples faster than "
                             f"{seg.v_rest:.3g} m/s): there is no friction to compare "
                             f"{model.describe()!r} with")
        if model.n_states and data.steady_state:
            raise FcompError(f"baseline {model.describe()!r} is a dynamic model (states "
                             f"{', '.join(model.state_names)}) but the data are steady-state "
                             "points without a motion history: use a static baseline "
                             "(coulomb, coulomb-viscous, stribeck)")
        if model.n_states and not seg.starts:
            raise FcompError(f"{label}: the record has no start or reversal, so the states of "
                             f"the dynamic baseline {model.describe()!r} are not determined; "
                             "use a static baseline or record through reversals")
        n_par = len(model.flat_params())
        usable = int(seg.valid.sum())
        if usable < 10 * n_par:
            raise FcompError(f"{label}: only {usable} usable samples for the {n_par} "
                             f"parameters of {model.describe()!r}; record longer")

    # ---------------------------------------------------------------- steps
    def add_effect(self, effect: str | Effect) -> Diagnosis:
        """Add ``effect`` to the current model, refit, score and record the step (forced).

        Works after :meth:`fit` (or inside it, for ``add``); the effect may be a
        catalogue entry or one the user registered
        (:func:`fcomp.effects.register_effect`), by name or as a configured
        instance (``make_effect("cogging", period=0.01)``: its configuration is
        kept, its parameter values are the start of the refit).
        """
        if not hasattr(self, "fit_"):
            raise FcompError("call fit(data) before add_effect")
        instance = effect if isinstance(effect, Effect) else None
        name = effect.name if isinstance(effect, Effect) else effect
        EFFECTS.get(name)
        reason = (catalogue.applicability(name, self._context())
                  if instance is None else _instance_applicability(instance, self.fit_.model,
                                                                   self.data_))
        if reason is not None:
            raise FcompError(f"effect {name!r} cannot be added to {self.fit_.model.describe()}: "
                             f"{reason}")
        cand = (self._evaluate([name]) if instance is None  # one job: no worker processes
                else self._evaluate_instance(instance))[0]
        if cand.fit is None:
            raise FcompError(f"adding {name!r}: {cand.reason}")
        before = self.fit_
        fit = self._polish(cand.fit)
        self._forms[name] = cand.form
        if instance is not None:
            self._instances[name] = instance
        self.steps_.append(Step(name, before.rms_test, fit.rms_test, cand.qualifies,
                                forced=True, candidates=[cand], fit=fit))
        self.fit_ = fit
        self.added_.append(name)
        if hasattr(self, "verdict_"):
            self._conclude()
        return self

    def remove_effect(self, effect: str) -> Diagnosis:
        """Take ``effect`` out of the current model again and refit the rest (after :meth:`fit`).

        The step that added it is marked not accepted and the effect is listed in
        ``removed_`` (the error-fall chart shows the removal); the verdict is
        judged again.
        """
        if not hasattr(self, "verdict_"):
            raise FcompError("call fit(data) before remove_effect")
        if effect not in self.added_:
            raise FcompError(f"effect {effect!r} is not in the model (added: "
                             f"{', '.join(self.added_) or 'none'})")
        others = [n for n in self.added_ if n != effect]
        try:
            reduced = self._rebuilt(others)
        except (FcompError, ValueError) as exc:
            raise FcompError(f"cannot remove {effect!r}: {str(exc).splitlines()[0]}") from None
        self.fit_, self.added_ = reduced, others
        self.removed_.append(effect)
        self._instances.pop(effect, None)
        self.ties_ = [t for t in self.ties_ if t[0] != effect]
        for st in self.steps_:
            if st.effect == effect and (st.accepted or st.forced) and not st.removed:
                st.accepted = False
                st.removed = "removed on request"
        self._conclude()
        return self

    def _evaluate_instance(self, effect: Effect) -> list[Candidate]:
        """Refit ``current + effect`` (a configured instance) and judge it."""
        model = self.fit_.model.with_effects(effect)
        flat = model.flat_params()
        start = {**flat, **{k: v for k, v in self.fit_.values.items() if k in flat or k in RIG_EXTRAS}}
        res = self._run([catalogue.Proposal(effect.name, model, [start])])[0]
        if isinstance(res, str):
            return [Candidate(effect.name, None, math.nan, reason=res)]
        return [self._judge(effect.name, res)]

    # ------------------------------------------------------------- display
    def __repr__(self) -> str:
        name = self.baseline if isinstance(self.baseline, str) else self.baseline.describe()
        if not hasattr(self, "verdict_"):
            return f"<Diagnosis from {name}: not fitted>"
        return (f"<Diagnosis from {name}: added {', '.join(self.added_) or 'nothing'}; "
                f"held-out RMS {self.rms_baseline_:.4g} -> {self.rms_final_:.4g} N; "
                f"{self.verdict_}>")

    def _repr_html_(self) -> str:
        from fcomp.diagnosis.report import diagnosis_html

        return diagnosis_html(self)

    def write_report(self, directory: str | Path, *, command: str | None = None) -> Path:
        """Write the self-contained ``DIRECTORY/report.html`` (:func:`.report.write_report`)."""
        from fcomp.diagnosis.report import write_report

        return write_report(self, directory, command=command)

    def _context(self) -> catalogue.Context:
        return catalogue.Context(self.data_, self.segmentation_, self.split_.train, self.fit_)

    def _evaluate(self, names: list[str]) -> list[Candidate]:
        """Refit ``current + effect`` for every name and judge it against the current fit."""
        ctx = self._context()
        out: list[Candidate | None] = [None] * len(names)
        proposals = []
        index = []
        for i, name in enumerate(names):
            try:
                forms = catalogue.propose_all(name, ctx)
            except (FcompError, ValueError) as exc:
                out[i] = Candidate(name, None, math.nan, reason=f"cannot start: {exc}")
                continue
            proposals += forms
            index += [i] * len(forms)
        results = self._run(proposals)
        best: dict[int, tuple[FitResult | str, str | None]] = {}
        train = self.split_.train
        n_eff = effective_sample_size(self.fit_.residual[train])
        for j, prop, res in zip(index, proposals, results, strict=True):
            # of an effect's forms, the one the information criterion prefers on the
            # training samples (a richer form must earn its parameters), all counted
            # with the current model's effective sample size
            prev = best.get(j, (None, None))[0]
            if prev is None or (isinstance(prev, str) and not isinstance(res, str)) or (
                    not isinstance(res, str) and not isinstance(prev, str)
                    and delta_bic(self.fit_, res, train, n_eff)
                    < delta_bic(self.fit_, prev, train, n_eff)):
                best[j] = (res, prop.form)
        for j, (res, form) in best.items():
            name = names[j]
            if isinstance(res, str):
                out[j] = Candidate(name, None, math.nan, reason=res, form=form)
                continue
            out[j] = dataclasses.replace(self._judge(name, res), form=form)
        return [c for c in out if c is not None]

    def _run(self, proposals: list[catalogue.Proposal]) -> list[FitResult | str]:
        """Refit every proposal: in the diagnosis's worker processes where there are several.

        Each job carries everything it needs -- the record (:class:`Refit`, whose
        derived records are rebuilt in the worker), the proposal and the current
        fit -- as plain picklable values, so the workers are started with
        ``spawn`` (the default on macOS and Windows) and nothing passes through
        module state; the same job runs on a Dask worker
        (:func:`refit_candidate`).
        """
        results: list[FitResult | str] = [""] * len(proposals)
        pool = self._workers(len(proposals))
        if pool is not None:
            pending = {pool.submit(timed_refit_candidate, self._refit, proposals[i], self.fit_): i
                       for i in self._longest_first(proposals)}
            while pending:
                try:
                    for fut in as_completed(list(pending), timeout=WATCH_SECONDS):
                        i = pending.pop(fut)
                        results[i], seconds = fut.result()
                        self._seconds[(proposals[i].effect, proposals[i].form)] = seconds
                        self._tick(proposals[i].effect)
                except TimeoutError:
                    if _workers_alive(pool):
                        continue
                    # the local pool lost its workers without a word (seen once in a
                    # test run: futures pending, no process left): finish the jobs here
                    for fut, i in pending.items():
                        fut.cancel()
                        results[i] = refit_candidate(self._refit, proposals[i], self.fit_)
                        self._tick(proposals[i].effect)
                    pending.clear()
                    pool.shutdown(wait=False, cancel_futures=True)
                    self._pool = None
        else:
            for i, prop in enumerate(proposals):
                # each job sees the boxes as they were, as a worker process would
                boxes = self._refit.box_state()
                results[i] = refit_candidate(self._refit, prop, self.fit_)
                self._refit.set_box_state(boxes)
                self._tick(prop.effect)
        for res in results:  # a box a worker's fit had to widen holds here too
            if isinstance(res, FitResult):
                self._refit.adopt_boxes(res)
        return results

    def _longest_first(self, proposals: Sequence[catalogue.Proposal]) -> list[int]:
        """The order to submit ``proposals`` to the workers in: the longest jobs first.

        The refits of one step take from a fraction of a second (a static term)
        to many seconds (a memory model): submitted in catalogue order, the
        longest often started last and ran alone while the other workers idled
        (longest-processing-time-first scheduling). A job's length is what the
        same effect and form took at the previous step of this diagnosis; one not
        run yet goes first, the models without exact sensitivities (finite
        differences) and then those with more states first. The results do not
        depend on the order (each job is independent).
        """
        def key(i: int) -> tuple[bool, float, bool, int]:
            prop = proposals[i]
            took = self._seconds.get((prop.effect, prop.form))
            return (took is not None, -(took or 0.0), prop.model.symbolic, -prop.model.n_states)

        return sorted(range(len(proposals)), key=key)

    def _n_workers(self) -> int:
        """The local worker processes to use (``n_jobs``; default the CPUs, at most 4)."""
        return self.n_jobs if self.n_jobs is not None else min(os.cpu_count() or 1, 4)

    def _workers(self, jobs: int) -> Executor | None:
        """The diagnosis's process pool (``spawn``), started on first use within :meth:`fit`;
        None to run here (one job, one process, or a later :meth:`add_effect`)."""
        n_jobs = self._n_workers()
        if (n_jobs < 2 and not self.scheduler) or jobs < 2 or not getattr(self, "_fitting", False):
            return None
        if self._pool is None and self.scheduler:
            self._pool = self._cluster.enter_context(executor(self.scheduler))
        if self._pool is None:
            self._pool = process_pool(n_jobs, spawn=True)  # runs the user's --effects code
        return self._pool

    def _judge(self, name: str, res: FitResult) -> Candidate:
        before = self.fit_
        nf = self.noise_floor_.value
        fall = before.rms_test - res.rms_test
        pieces = changed_pieces(before.residual, res.residual, self._blocks, FALL_NOISE * nf)
        z, p = fall_test(before.residual, res.residual, pieces, 0.0)  # pieces already chosen
        dbic = delta_bic(before, res, self.split_.train)
        reasons = []
        if not fall > 0:
            reasons.append(f"held-out RMS does not fall ({before.rms_test:.4g} -> "
                           f"{res.rms_test:.4g} N)")
        changed = np.concatenate(pieces) if pieces else np.zeros(0, dtype=int)
        if changed.size:  # isolated timing spikes are in both and no effect explains them
            rb, ra = paired_trimmed_rms(before.residual[changed], res.residual[changed])
        else:
            rb = ra = before.rms_test
        need = max(FALL_NOISE * nf, FALL_RELATIVE * rb, FALL_NUMERIC * self.data_.scales.force)
        if fall > 0 and rb - ra < need:
            reasons.append(f"where it changes the prediction the held-out RMS falls by "
                           f"{rb - ra:.3g} N < {need:.3g} N")
        # the floor of the scored residual where the candidate acts: the noise, and what the
        # right model would score within the timing windows of the events there (never the
        # band of the motions a model chose to depend on)
        excess = rb**2 - nf**2 * _timing_share(before, changed, nf)
        share = (rb**2 - ra**2) / excess if excess > 0 else 0.0
        if fall > 0 and rb - ra >= need and share < EXCESS_SHARE:
            reasons.append(f"explains only {100 * share:.0f} % of the excess over the noise "
                           f"floor where it acts (< {100 * EXCESS_SHARE:.0f} %)")
        if not p <= ACCEPT_P:
            reasons.append(f"fall not significant (z = {z:.2g}, p = {p:.2g} > {ACCEPT_P:g})")
        inside = self._signature_share(name, before.residual, res.residual)
        if fall > 0 and inside is not None and inside < SIGNATURE_SHARE:
            where = ", ".join(EFFECTS.get(name).acts_in)
            reasons.append(f"its fall lies outside its signature: {100 * inside:.0f} % of the "
                           f"held-out fall where it acts ({where}; < "
                           f"{100 * SIGNATURE_SHARE:.0f} %)")
        drift = self._drift(before)
        if fall > 0 and drift >= (1.0 - TIE_SHARE) * fall:
            reasons.append(f"confounded with time: a slow drift of the friction level alone "
                           f"takes {drift:.3g} N off the held-out RMS (this effect "
                           f"{fall:.3g} N)")
        if not dbic < 0:
            reasons.append(f"BIC does not agree (dBIC = {dbic:.3g})")
        return Candidate(name, res, res.rms_test, fall, z, p, dbic, not reasons,
                         "; ".join(reasons))

    def _signature_share(self, name: str, before: np.ndarray, after: np.ndarray
                         ) -> float | None:
        """Share of the held-out fall in mean square, ``sum(before^2 - after^2)``, that lies in
        the regimes effect ``name`` declares (``Effect.acts_in``); None when it declares none
        or nothing falls."""
        acts_in = EFFECTS.get(name).acts_in
        if not acts_in:
            return None
        unknown = [r for r in acts_in if r not in REGIMES]
        if unknown:
            raise FcompError(f"effect {name!r}: acts_in names regimes {unknown}; known: "
                             f"{', '.join(REGIMES)}")
        test = self.split_.test
        gain = before[test] ** 2 - after[test] ** 2
        total = float(np.sum(gain))
        if not total > 0:
            return None
        there = np.isin(self.segmentation_.regime[test], [REGIMES.index(r) for r in acts_in])
        return float(np.sum(gain[there])) / total

    def _drift(self, fit: FitResult) -> float:
        """:func:`.features.drift_fall` of ``fit`` (computed once per fit)."""
        if getattr(self, "_drift_of", (None, 0.0))[0] is not fit:
            self._drift_of = (fit, drift_fall(fit.residual, fit.F_hat, self.data_,
                                              self.split_.train, self.split_.test))
        return self._drift_of[1]

    def _search(self, names: list[str]) -> None:
        for step_no in range(self.max_steps):
            if step_no and self.fit_.rms_test <= AT_FLOOR * self.noise_floor_.value:
                break
            todo = []
            ctx = self._context()
            for name in names:
                if name in self.added_:
                    continue
                reason = catalogue.applicability(name, ctx)
                if reason is not None:
                    self.skipped_[name] = reason
                    continue
                self.skipped_.pop(name, None)
                todo.append(name)
            if not todo:
                break
            cands = self._evaluate(todo)
            ranked = sorted(cands, key=lambda c: (math.isnan(c.rms_heldout), c.rms_heldout))
            good = [c for c in ranked if c.qualifies]
            if good and self._control(good[0]):  # the gain was the optimiser's: judge again
                cands = self._again(cands)
                ranked = sorted(cands, key=lambda c: (math.isnan(c.rms_heldout),
                                                      c.rms_heldout))
                good = [c for c in ranked if c.qualifies]
            if step_no == 0 and not self.added_:
                self.candidates_ = ranked
            if not good:
                best = ranked[0]
                self.steps_.append(Step(best.effect, self.fit_.rms_test,
                                        best.rms_heldout, False, candidates=ranked))
                break
            best = good[0]
            tie = self._tie(best, good)
            fit = self._reweighted(self._polish(best.fit))  # type: ignore[arg-type]
            self._forms[best.effect] = best.form
            self.steps_.append(Step(best.effect, self.fit_.rms_test, fit.rms_test, True,
                                    candidates=ranked, tie=tie, fit=fit))
            if len(tie) > 1:
                self.ties_.append(tie)
            self.fit_ = fit
            self.added_.append(best.effect)

    def _control(self, best: Candidate) -> bool:
        """Refit the current model from the best candidate's values; True if that alone helps.

        A candidate refitted from fresh starts may land in a better optimum of
        the parameters it shares with the current model -- a gain of the
        optimiser, not of the effect. The current model, started from the
        candidate's values of its own parameters, is refitted; if its held-out
        error then falls clearly (by a tenth of the noise floor) it replaces
        the current fit and the candidates are judged again against it.
        """
        assert best.fit is not None
        own = {k: v for k, v in best.fit.values.items()
               if k in self.fit_.values}
        if set(own) != set(self.fit_.values):
            return False
        try:
            control = self._polish(self._refit.fit(self.fit_.model, [own, self.fit_.values],
                                                   list(self.fit_.values)))
        except FcompError:
            return False
        if not control.rms_test < self.fit_.rms_test - FALL_NOISE * self.noise_floor_.value:
            return False
        self._tick("control refit")
        self.fit_ = self._reweighted(control)
        if self.steps_:
            self.steps_[-1].fit = self.fit_
            self.steps_[-1].rms_after = self.fit_.rms_test
        else:
            self.baseline_fit_ = self.fit_
        return True

    def _again(self, cands: list[Candidate]) -> list[Candidate]:
        """``cands`` judged again after :meth:`_control` replaced the current fit.

        The candidates that qualified are refitted from the new current fit (their
        gain may have been the optimiser's); the others keep their refits and are
        judged against the new fit: it is better on the training samples than the one
        they failed to beat, and a refit from it (the earlier start moved to a lower
        point of the same parameters) would not change that -- refitting them all
        doubled the step's time for the same answer.
        """
        redo = [c.effect for c in cands if c.qualifies]
        fresh = {c.effect: c for c in self._evaluate(redo)}
        return [fresh[c.effect] if c.effect in fresh else
                c if c.fit is None else dataclasses.replace(self._judge(c.effect, c.fit),
                                                            form=c.form)
                for c in cands]

    def _rebuilt(self, names: Sequence[str]) -> FitResult:
        """The baseline with the effects ``names`` (in order) refitted from the current values.

        A fit of the same structure seen earlier (the baseline, or the model before
        a later effect was added) is a start too, and is kept if the refit does not
        beat it on the training samples: refitted from the full model's values
        alone, a reduced model can settle in a worse optimum (a stiff bristle's test
        error 84 N where the same structure had reached 60 N), and the effect taken
        out would look needed when it is not, or not needed when it is.
        """
        model = self.baseline_fit_.model
        for n in names:
            if n in self._instances:
                model = model.with_effects(self._instances[n])
                continue
            # configured with its current values: an effect at its defaults can be a no-op
            # that attaches differently (presliding's rigid bristle is the static map, and
            # nonlocal-memory then finds no bristle to replace)
            own = set(EFFECTS.get(n).Params.from_flat({}).flat())
            values = {k: v for k, v in self.fit_.values.items() if k in own}
            model = model.with_effects(catalogue.configured(
                n, self.data_, values or None,
                **catalogue.form_of(n, self._forms.get(n)).config))
        flat = model.flat_params()
        start = {k: v for k, v in self.fit_.values.items() if k in flat or k in RIG_EXTRAS}
        known = [f for f in self._known_fits(model) if set(f.values) == set(start)]
        # the parameters fitted now that remain (terms held for the record stay held)
        fit = self._polish(self._refit.fit(model, [start, *(f.values for f in known)],
                                           list(start)))
        # and never a worse fit than one of that structure already seen
        return min([fit, *known], key=lambda f: f.rms_train)

    def _known_fits(self, model: FrictionModel) -> list[FitResult]:
        """The baseline and accepted step fits whose model has the structure of ``model``."""
        fits = [self.baseline_fit_, *(s.fit for s in self.steps_ if s.accepted and s.fit)]
        return [f for f in fits if f is not None and f.model.describe() == model.describe()
                and set(f.model.flat_params()) == set(model.flat_params())]

    def _backward(self) -> None:
        """Drop searched effects that later additions made redundant (a backward check).

        Effects are added one at a time, so an early one may only have stood
        in for part of what a later one explains (a position-dependent level
        for a direction asymmetry seen at the ends of the stroke). Once the
        search stops, each searched effect -- last added first -- is taken out
        and the rest refitted; if putting it back would no longer qualify by
        the acceptance rule, it stays out (listed in ``removed_``, its step
        marked not accepted). Forced effects (``add``) are never removed.
        """
        searched = [s.effect for s in self.steps_ if s.accepted and not s.forced]
        if len(self.added_) < 2:
            return
        for effect in reversed(searched):
            others = [n for n in self.added_ if n != effect]
            try:
                reduced = self._rebuilt(others)
            except (FcompError, ValueError):  # a later effect builds on it (nonlocal-memory
                continue                     # on presliding): it stays
            self._tick(f"without {effect}")
            full = self.fit_
            self.fit_ = reduced
            verdict = self._judge(effect, full)
            self.fit_ = full
            if verdict.qualifies:
                continue
            self.fit_ = reduced
            self.added_ = others
            self.removed_.append(effect)
            self.ties_ = [t for t in self.ties_ if t[0] != effect]  # its tie went with it
            for st in self.steps_:
                if st.effect == effect and st.accepted and not st.forced:
                    st.accepted = False
                    st.removed = verdict.reason

    def _swaps(self, names: list[str]) -> None:
        """Try each searched effect's confounded partners in its place; a tie where one fits
        as well.

        Some effects give the same force over the motions a record holds (an
        offset of the force and a direction asymmetry of the levels, while
        sliding: :attr:`Effect.confounded`). Which one the search takes first
        can hinge on a few samples at rest. Once the search stops, each searched
        effect with a partner not in the model is taken out, the rest refitted,
        and the partner evaluated as a candidate in its place: if its held-out
        RMS comes within :data:`TIE_SHARE` of the fall the effect brought, the
        two are reported as a tie (with the experiment that separates them).
        """
        for step in [s for s in self.steps_ if s.accepted and not s.forced]:
            effect = step.effect
            partners = [p for p in EFFECTS.get(effect).confounded
                        if p in names and p not in self.added_
                        and not any(effect in t and p in t for t in self.ties_)]
            if not partners or effect not in self.added_:
                continue
            others = [n for n in self.added_ if n != effect]
            try:
                reduced = self._rebuilt(others)
            except (FcompError, ValueError):
                continue
            full = self.fit_
            self.fit_ = reduced
            try:
                ctx = self._context()
                fit_in = [p for p in partners if catalogue.applicability(p, ctx) is None]
                cands = [c for c in self._evaluate(fit_in) if c.fit is not None] if fit_in else []
            finally:
                self.fit_ = full
            self._tick(f"in place of {effect}")
            fall = reduced.rms_test - full.rms_test
            close = [c.effect for c in cands
                     if fall > 0 and c.rms_heldout - full.rms_test <= TIE_SHARE * fall]
            if not close:
                continue
            step.tie = list(self._join_tie(effect, close))

    def _partners_in_model(self) -> None:
        """Report declared confounded partners that are *both* in the final model as a tie.

        Effects that give the same force over the motions a record holds
        (:attr:`Effect.confounded`: an offset of the force and a direction
        asymmetry of the levels, while sliding) can both be accepted, one after
        the other, each taking part of what the record shows. How the force
        then splits between them is not fixed by the record (sliding, ``Fc+ +
        offset`` and ``Fc- - offset`` are seen, not the three terms), so they are
        reported together, with the experiment that separates them, as for a
        partner that fits in the other's place (:meth:`_swaps`). The first added
        leads the group.
        """
        for i, effect in enumerate(self.added_):
            self._join_tie(effect, [p for p in self.added_[i + 1:]
                                    if p in EFFECTS.get(effect).confounded
                                    or effect in EFFECTS.get(p).confounded])

    def _join_tie(self, effect: str, others: Sequence[str]) -> list[str]:
        """The tie holding ``effect`` (led by it when new), grown by ``others``."""
        tie = next((t for t in self.ties_ if effect in t), None)
        if tie is None:
            if not others:
                return [effect]
            tie = [effect]
            self.ties_.append(tie)
        tie += [e for e in others if e not in tie]
        return tie

    def _reweighted(self, fit: FitResult) -> FitResult:
        """``fit`` polished again after the sample weights follow its own prediction.

        The weights (:meth:`Refit.set_weights`) come from the uncertainty of the
        current model's prediction; a model accepted with another structure (a
        bristle where a static map jumped) changes where that is, so it is
        refitted with its own weights before the next step starts from it. A
        held channel lag is first estimated again for it (:meth:`Refit.refit_held`).
        """
        if "lag" in self._refit.held:  # the channel lag, estimated again for this model
            self._refit.refit_held("lag", fit)
            fit = self._refit.rescore(fit)
        if fit.spread is None:
            return fit
        self._refit.set_weights(fit.spread, self.noise_floor_.value)
        return self._polish(fit, fresh=True)

    def _polish(self, fit: FitResult, fresh: bool = False) -> FitResult:
        """``fit`` continued to convergence (:data:`POLISH_NFEV` times the budget), if that helps.

        Every candidate is refitted from the current model with the normal
        budget; were the current model itself short of its optimum, any
        candidate would gain from the extra iterations alone and look like a
        found effect. So the baseline and every accepted model are polished
        first; the better of the two fits (training error) is kept. With
        ``fresh`` the model's base parameters also start afresh from the data
        (:func:`catalogue.baseline_starts`, the effects' parameters kept): an
        accepted model may carry a local optimum the candidate's refit landed in,
        which the next candidate's fresh start would otherwise escape and be
        credited for.
        """
        if not fit.model.symbolic or not fit.values:
            return fit
        starts = [fit.values]
        if fresh:
            try:
                base = catalogue.baseline_starts(fit.model, self.data_, self.segmentation_,
                                                 self.split_.train)
            except (FcompError, ValueError, ArithmeticError):
                base = []
            starts += [{**fit.values, **{k: v for k, v in b.items() if k in fit.values}}
                       for b in base[:2]]
        try:
            more = self._refit.fit(fit.model, starts, list(fit.values),
                                   max_nfev=POLISH_NFEV * self.max_nfev)
        except FcompError:
            return fit
        return more if more.rms_train < fit.rms_train else fit

    def _tie(self, best: Candidate, good: list[Candidate]) -> list[str]:
        return [best.effect, *(c.effect for c in good[1:]
                               if c.rms_heldout - best.rms_heldout <= TIE_SHARE * best.fall)]

    # -------------------------------------------------------------- verdict
    def _fit_warnings(self, fit: FitResult, what: str) -> list[FitWarning]:
        """The plausibility warnings of one fit of the diagnosis, each naming the fit."""
        try:
            found = self._refit.plausibility(fit, self.data_.rig)
        except (FcompError, ValueError, ArithmeticError, np.linalg.LinAlgError):
            return []
        return [FitWarning(w.code, w.parameter, f"{what}: {w.message}") for w in found]

    def _collect_warnings(self) -> None:
        """Fit warnings of the baseline, of every accepted step and of the final model."""
        out = self._fit_warnings(self.baseline_fit_, f"baseline {self.baseline_name_}")
        self._final_warnings = list(out)
        for st in self.steps_:
            if st.accepted and st.fit is not None and st.fit is not self.fit_:
                st.warnings = self._fit_warnings(st.fit, f"after + {st.effect}")
        if self.fit_ is not self.baseline_fit_:
            final = self._fit_warnings(self.fit_, f"final model {self.fit_.model.describe()}")
            for st in self.steps_:
                if st.fit is self.fit_:
                    st.warnings = final
            out += final
            self._final_warnings = final
        self.warnings_ = out + list(self.split_.warnings)

    def _conclude(self) -> None:
        data, seg, split = self.data_, self.segmentation_, self.split_
        self.rms_baseline_ = self.baseline_fit_.rms_test
        self.rms_final_ = self.fit_.rms_test
        # where structure is left: the tolerant residual (a shape the model could place);
        # how large the error is: the scored residual (:func:`.refit.scored_residual`)
        located = self.fit_.located
        self.residual_features_ = residual_structure(located, data, seg,
                                                     split.train, split.test)
        nf = self.noise_floor_.value
        # what counts: a structure as large as the noise and as a small share of the
        # friction level (a filtered, reconstructed force has a floor far below that)
        least = max(STRUCTURE_RMS * nf, STRUCTURE_LEVEL * data.scales.force)
        top = self.residual_features_[0] if self.residual_features_ else None
        structured = (top is not None and top.strength >= STRUCTURE_MIN
                      and self.rms_final_ * math.sqrt(top.strength) >= least)
        # after starts and reversals, where a jump of the law within the timing uncertainty
        # of the event leaves spikes no model could place, the residual counts as the fits
        # weigh it (a static map's full-level step one sample early is not a structure)
        r_events = located
        if self.fit_.spread is not None:
            r_events = r_events * np.sqrt(sample_weights(self.fit_.spread, nf))
        ev = event_structure(r_events, data, seg, split.train, split.test)
        self.event_structure_ = ev
        event = ev is not None and ev.strength >= STRUCTURE_MIN and ev.rms >= least
        # a structure after events whose phase wanders from event to event lifts the
        # window's RMS (trimmed, weighted) well above the noise all the same
        ev_excess = 0.0 if ev is None else math.sqrt(max(ev.local**2 - nf**2, 0.0))
        event_excess = (ev is not None and not event and ev.local > EVENT_EXCESS * nf
                        and ev_excess >= least)
        ring = event_ring(r_events, data, seg, split.test)
        self.event_ring_ = ring
        ringing = (ring is not None and not (event or event_excess)
                   and ring.concentration >= RING_CONCENTRATION
                   and ring.rms >= max(RING_NOISE * nf, RING_LEVEL * data.scales.force))
        trimmed = trimmed_rms(self.fit_.residual[split.test])
        # the right model's score within the timing windows of the events (a static law's
        # jump is placed only within them): the floor the scored error is held against
        nf_t = nf * math.sqrt(_timing_share(self.fit_, np.flatnonzero(split.test), nf))
        limit = max(EXCESS_MAX * nf_t, nf_t + STRUCTURE_LEVEL * data.scales.force)
        excess = trimmed > limit
        lines = getattr(self, "disturbances_", [])
        self.verdict_ = ("unexplained-structure" if structured or event or event_excess
                         or ringing or excess or lines else "explained")
        after = ("" if ev is None else f"structure after events: within "
                 f"{1e3 * ev.window:.0f} ms of every start and reversal the held-out residual ")
        if event and not structured:
            assert ev is not None
            self.reason_ = (f"{after}repeats (strength "
                            f"{ev.strength:.2f} >= {STRUCTURE_MIN:g} of the time since the "
                            f"event; it carries {ev.rms:.3g} N RMS >= {least:.3g} N there)")
        elif event_excess and not structured:
            assert ev is not None
            self.reason_ = (f"{after}(without its largest "
                            f"{100 * TRIM:g} %) is {ev.local:.3g} N RMS, above {EVENT_EXCESS:g} "
                            f"noise floors of {nf:.3g} N, with {ev_excess:.3g} N RMS above the "
                            f"noise >= {least:.3g} N (it does not repeat in phase: "
                            f"strength {ev.strength:.2f})")
        elif ringing and not structured:
            assert ring is not None
            self.reason_ = (f"structure after events: a ring at {ring.frequency:.3g} Hz after "
                            f"every start and reversal ({ring.events} held-out windows; "
                            f"{100 * ring.concentration:.0f} % of the excess power within "
                            f"three bins) carries {ring.rms:.3g} N RMS there, >= "
                            f"{max(RING_NOISE * nf, RING_LEVEL * data.scales.force):.3g} N "
                            f"({RING_NOISE:g} noise floor, {100 * RING_LEVEL:g} % of the "
                            "friction level): a rig mode no friction law explains")
        elif structured:
            assert top is not None
            self.reason_ = (f"structure: the held-out residual still follows {top.feature} "
                            f"(strength {top.strength:.2f} >= {STRUCTURE_MIN:g}; it carries "
                            f"{self.rms_final_ * math.sqrt(top.strength):.3g} N RMS >= "
                            f"{least:.3g} N, a noise floor and {100 * STRUCTURE_LEVEL:g} % of "
                            "the friction level)")
        floor_words = (f"{nf:.3g} N" if nf_t <= 1.0005 * nf else
                       f"{nf_t:.3g} N: {nf:.3g} N of noise and what the right model scores "
                       "within the events' timing windows")
        if excess and not (structured or event or event_excess or ringing):
            self.reason_ = (f"excess: the held-out RMS without its largest {100 * TRIM:g} % "
                            f"({trimmed:.3g} N) is above {limit:.3g} N ({EXCESS_MAX:g} noise "
                            f"floors of {floor_words}, and the floor plus "
                            f"{100 * STRUCTURE_LEVEL:g} % of the friction level), though no "
                            "single feature explains it")
        elif not (structured or event or event_excess or ringing):
            self.reason_ = (f"at the noise: held-out RMS without its largest {100 * TRIM:g} % "
                            f"{trimmed:.3g} N within {limit:.3g} N (noise floor "
                            f"{floor_words}), and no structure carries {least:.3g} N")
        if lines:
            what = ", ".join(f"{d.frequency_hz:.4g} Hz ({d.amplitude:.3g} N amplitude)"
                             for d in lines)
            self.reason_ = (f"periodic disturbance: a narrow line in the residual that follows "
                            f"no motion feature at {what}, taken off the force before the "
                            f"diagnosis (no friction law explains it: look for a pump, a fan, "
                            f"mains hum, a valve dither); the rest: {self.reason_}")
        self.regimes_ = {
            "baseline": regime_errors(self.baseline_fit_.residual, seg, split.test),
            "final": regime_errors(self.fit_.residual, seg, split.test),
        }
        self._collect_warnings()
        edge = sorted({w.parameter for w in self._final_warnings
                       if w.code == "at-bound" and w.parameter})
        if edge:
            self.reason_ += (f"; the final fit sits at a bound of its box for {', '.join(edge)} "
                             "(after the boxes the record's scale set were widened): the "
                             "error may be the box's, not the model's")
        if hasattr(self, "baseline_check_"):  # an effect added or removed after the check
            self._fold_dependence()

    # ----------------------------------------------------------------- JSON
    def signals(self) -> dict[str, Any]:
        """Which velocity drove the friction states, from which force, and why (JSON ``signals``).

        ``velocity`` (``"x"``, ``"v"``, ``"fused"``, or ``"mixed"`` when records
        differ), ``force`` and ``reason`` summarise; ``unresolved_samples``
        counts the samples left out because the position missed motion there
        (:func:`fcomp.diagnosis.regimes.unresolved_rests`); ``force_lag_s`` is the
        lag of a driving force's channel, fitted with the first (unweighted) baseline
        fit, held in the weighted fits and estimated again (alone, unweighted) for
        every model accepted (s; None for a load cell): pressure transducers and their lines lag, and a force
        reconstructed from them misses ``lag*dD/dt`` where ``D`` changes fast;
        ``records`` holds the full conditioning of every file
        (:class:`fcomp.conditioning.Conditioning`).
        """
        recs = [c.to_dict() for c in self.data_.signals]
        if not recs:
            return {"velocity": "v", "force": self.data_.source, "records": [],
                    "reason": "steady-state points: the velocity of each point as given"}
        kinds = {r["velocity"] for r in recs}
        lag = self.fit_.values.get("lag")
        return {"velocity": kinds.pop() if len(kinds) == 1 else "mixed",
                "force": self.data_.source,
                "force_lag_s": None if lag is None else float(lag),
                "unresolved_samples": self.segmentation_.unresolved,
                "reason": "; ".join(dict.fromkeys(f"{r['label']}: {r['reason']}" for r in recs)),
                "records": recs}

    def model_file(self, source: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The final model as a model file's document (:mod:`fcomp.modelfile`): the
        friction with every effect accepted and its fitted values; a fitted ``mass``, the
        channel ``lag``, a ``force-offset`` or ``inertia-error`` as measurement terms.
        ``source`` (``command``, ``data``) says where it comes from."""
        from fcomp.models.document import model_document

        if not hasattr(self, "verdict_"):
            raise FcompError("this Diagnosis is not fitted yet: call fit(data) first")
        return model_document(self.fit_.model, measurement=self.fit_.values,
                              source={"diagnosis": {"baseline": self.baseline_name_,
                                                    "added": list(self.added_),
                                                    "verdict": self.verdict_},
                                      **dict(source or {})})

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``fcomp diagnose`` (public contract, plus extra keys; ``model_file``:
        :meth:`model_file`)."""
        if not hasattr(self, "verdict_"):
            raise FcompError("this Diagnosis is not fitted yet: call fit(data) first")

        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        def candidate(c: Candidate) -> dict[str, Any]:
            return {"effect": c.effect, "form": c.form, "rms_heldout": num(c.rms_heldout),
                    "qualifies": c.qualifies, "z": num(c.z), "p": num(c.p),
                    "delta_bic": num(c.delta_bic),
                    "reason": c.reason or "qualifies by the acceptance rule"}

        test = self.split_.test

        def plain(fit: FitResult) -> float | None:
            return num(_rms(fit.plain_residual[test]))

        return {
            "baseline": self.baseline_name_,
            "rms_baseline": self.rms_baseline_,
            "added": list(self.added_),
            "steps": [{"effect": s.effect, "rms_before": s.rms_before, "rms_after":
                       num(s.rms_after), "accepted": bool(s.accepted), "forced": s.forced,
                       "removed": bool(s.removed),
                       "removed_because": s.removed or None,
                       "candidates": [candidate(c) for c in s.candidates],
                       "warnings": [w.to_dict() for w in s.warnings]}
                      for s in self.steps_],
            "candidates": [candidate(c) for c in self.candidates_],
            "ties": [list(t) for t in self.ties_],
            "removed": list(self.removed_),
            "rms_final": self.rms_final_,
            "rms_plain": {"baseline": plain(self.baseline_fit_), "final": plain(self.fit_)},
            "error_measure": ("held-out RMS of the scored residual: the logarithmic score of "
                              "the model's prediction band with the noise floor, in N (equal "
                              "to the plain residual where the motion fixes the prediction; "
                              "a wider band costs); rms_plain: y - F_hat"),
            "noise_floor": self.noise_floor_.value,
            "verdict": self.verdict_,
            "reason": self.reason_,
            "signals": self.signals(),
            "baseline_dependent": self.baseline_dependent_,
            "baseline_check": dict(self.baseline_check_),
            "other_baseline": self.baseline_dependence(),
            "residual_features": [{"feature": f.feature, "strength": round(f.strength, 4)}
                                  for f in self.residual_features_],
            "model": self.fit_.model.describe(),
            "params": {k: num(v) for k, v in self.fit_.values.items()},
            "model_params": {k: num(float(v)) for k, v in self.fit_.model.flat_params().items()},
            "regimes": self.regimes_,
            "tie_experiments": {t[0]: {e: EFFECTS.get(e).experiment_for(self.data_.kind) for e in t}
                                for t in self.ties_},
            "skipped": dict(self.skipped_),
            "split": self.split_.description,
            "noise_method": self.noise_floor_.method,
            "disturbances": [d.to_dict() for d in getattr(self, "disturbances_", [])],
            "units": "N",
            "warnings": [w.to_dict() for w in self.warnings_],
            "model_file": self.model_file(),
        }


#: The baseline of the other kind the baseline check uses (static <-> dynamic).
OTHER_BASELINE = {"static": "lugre", "dynamic": "stribeck"}


def other_baseline(model: FrictionModel, data: DiagnosisData, seg: Segmentation
                   ) -> str | None:
    """The baseline of the other kind for the check, or None if the data cannot take it.

    A static map's check is ``lugre`` (not on steady-state points or records
    without a start); a dynamic model's is the ``stribeck`` map.
    """
    if model.n_states:
        return OTHER_BASELINE["dynamic"]
    if data.steady_state or not seg.starts:
        return None
    return OTHER_BASELINE["static"]


def _comparable(added: Sequence[str], ties: Sequence[Sequence[str]],
                other: FrictionModel) -> frozenset[frozenset[str]]:
    """The added effects the ``other`` baseline does not already hold, each as its tie group."""
    out = set()
    for name in added:
        try:
            if not EFFECTS.get(name)().applies_to(other):
                continue  # part of the other baseline (presliding in LuGre)
        except (TypeError, ValueError):
            pass
        group = next((t for t in ties if name in t), [name])
        out.add(frozenset(group))
    return frozenset(out)


def _same_findings(mine: frozenset[frozenset[str]], theirs: frozenset[frozenset[str]]) -> bool:
    """Whether two diagnoses found the same effects, a tie on either side matching any member.

    Each finding is its tie group (one name when there is no tie); a finding of
    one side is matched by a finding of the other that shares a member, and the
    two agree when every finding on each side is matched (a tie reported on one
    side only is no disagreement).
    """
    def covered(a: frozenset[frozenset[str]], b: frozenset[frozenset[str]]) -> bool:
        return all(any(g & h for h in b) for g in a)

    return covered(mine, theirs) and covered(theirs, mine)


def _instance_applicability(effect: Effect, model: FrictionModel, data: DiagnosisData
                            ) -> str | None:
    """Why a configured effect cannot be added to ``model`` on ``data`` (None if it can)."""
    if not effect.applies_to(model):
        return f"already part of {model.describe()} or not applicable to it"
    for sig in effect.needs:
        if not data.available.get(sig, False):
            return f"needs {sig}: {data.reasons.get(sig, 'not available')}"
    return None


def _timing_share(fit: FitResult, where: np.ndarray, nf: float) -> float:
    """:func:`.refit.score_noise_share` of ``fit``'s timing band at the samples ``where``."""
    if fit.timing_spread is None or not where.size:
        return 1.0
    return score_noise_share(fit.timing_spread[where], nf)


#: How often (s) a diagnosis waiting on its local worker processes checks they are alive.
WATCH_SECONDS = 10.0


def _workers_alive(pool: Executor) -> bool:
    """Whether a local process pool still has a live worker (a pool of another kind, a Dask
    client, is taken to be alive: it reports its own failures)."""
    procs = getattr(pool, "_processes", None)
    if procs is None:
        return True
    return any(p.is_alive() for p in list(procs.values()))


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def set_postfix_str(self, s: str, refresh: bool = True) -> None:
        pass

    def close(self) -> None:
        pass


def _progress(enabled: bool) -> Any:
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(desc="diagnose", unit="fit", file=sys.stderr, leave=False)


__all__ = ["VERDICTS", "Candidate", "Diagnosis", "NoiseFloor", "Segmentation", "Split", "Step",
           "FeatureStrength", "DiagnosisData"]
