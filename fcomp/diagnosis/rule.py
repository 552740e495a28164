"""The acceptance rule: does adding a candidate explain the held-out data better?

:class:`AcceptanceRule` is a small frozen value (its thresholds) with one
method, :meth:`AcceptanceRule.judge`, taking both fits as arguments and
returning a :class:`Judgement`: the figures of every test and the tests that
failed, as data (:class:`Failure`: a code and its numbers). The words are
written apart (:mod:`.wording`). A candidate *qualifies* when all of these
hold:

* the held-out RMS falls, and falls clearly where the candidate acts: on the
  held-out pieces (contiguous, about 0.25 s, :func:`heldout_pieces`;
  steady-state points are pieces of their own) where the candidate changes the
  prediction materially (by ``fall_noise`` of the noise floor, RMS), the RMS
  falls by at least ``max(fall_noise*noise_floor, fall_relative*rms_before)``
  and by at least ``excess_share`` of the excess mean square over the noise
  floor there, ``rms_before^2 - rms_after^2 >= excess_share*(rms_before^2 -
  noise_floor^2)``; both RMS values without the 1 % of samples where both
  residuals are largest (:func:`.features.paired_trimmed_rms`);
* the fall is significant: a Diebold-Mariano test on the squared-error
  differences of those pieces with a Newey-West long-run variance has a
  one-sided p-value of at most ``accept_p`` (:func:`fall_test`);
* where the effect declares the regimes its signature lives in
  (``Effect.acts_in``), at least ``signature_share`` of the fall lies there;
* the fall is not one a slow drift of the friction level alone would bring
  (:func:`.features.drift_fall`; confounded with time);
* the Bayesian information criterion on the training residuals, with the
  effective sample size of the candidate's residual, agrees (:func:`delta_bic`).

Another qualifying candidate *ties* with the best one of a step only when the record
cannot tell them apart (:meth:`AcceptanceRule.tie_test`): its held-out RMS is within
``tie_share`` of the step's fall of the best one's, *and* the best one is not better by
what any fall must show -- clear where the two predictions differ and significant by the
same paired test, the rival in the place of the model before, and piece by piece
(:func:`piece_test`), with no experiment of the record significantly the other way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.features import drift_fall, paired_trimmed_rms
from fcomp.diagnosis.noise import effective_sample_size
from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.regimes import REGIMES, Segmentation
from fcomp.diagnosis.scoring import score_noise_share
from fcomp.diagnosis.split import Split
from fcomp.errors import FcompError


@dataclass(frozen=True)
class Failure:
    """One test of the rule a candidate failed: its code and its figures (SI units).

    Codes: ``no-fall``, ``small-fall``, ``small-share``, ``not-significant``,
    ``outside-signature``, ``confounded-with-time``, ``bic``.
    """

    code: str
    figures: Mapping[str, float | str] = field(default_factory=dict)


@dataclass(frozen=True)
class Judgement:
    """What :meth:`AcceptanceRule.judge` found.

    Attributes
    ----------
    fall : N
        ``rms_before - rms_after`` on the held-out samples.
    z, p : float
        Statistic and one-sided p-value of :func:`fall_test`.
    delta_bic : float
        :func:`delta_bic` of the two fits.
    failures : tuple of Failure
        The tests failed, in the rule's order (empty: it qualifies).
    rule : AcceptanceRule
        The rule that judged.
    """

    fall: float
    z: float
    p: float
    delta_bic: float
    failures: tuple[Failure, ...]
    rule: AcceptanceRule

    @property
    def qualifies(self) -> bool:
        return not self.failures


@dataclass(frozen=True, eq=False)
class Ground:
    """What the rule judges on: the record, its regimes and split, the held-out pieces and
    the noise floor (N). Built by :meth:`of`; a slow drift's fall is cached per fit."""

    data: DiagnosisData
    segmentation: Segmentation
    split: Split
    noise: float
    blocks: tuple[np.ndarray, ...]
    _drift: dict[int, tuple[FitResult, float]] = field(default_factory=dict, repr=False)

    @classmethod
    def of(cls, data: DiagnosisData, segmentation: Segmentation, split: Split,
           noise: float) -> Ground:
        """The ground of a record: held-out samples cut into :func:`heldout_pieces` (each
        steady-state point a piece of its own)."""
        blocks = [np.array([k]) for k in np.flatnonzero(split.test)] if data.steady_state \
            else heldout_pieces(split.test, [e.start for e in data.experiments],
                                data.scales.dt)
        return cls(data, segmentation, split, noise, tuple(blocks))

    def drift(self, fit: FitResult) -> float:
        """:func:`.features.drift_fall` of ``fit`` (computed once per fit)."""
        known = self._drift.get(id(fit))
        if known is None or known[0] is not fit:
            known = (fit, drift_fall(fit.residual, fit.F_hat, self.data, self.split.train,
                                     self.split.test))
            self._drift.clear()
            self._drift[id(fit)] = known
        return known[1]

    def timing_share(self, fit: FitResult, where: np.ndarray) -> float:
        """:func:`.scoring.score_noise_share` of ``fit``'s timing band at the samples ``where``."""
        if fit.timing_spread is None or not where.size:
            return 1.0
        return score_noise_share(fit.timing_spread[where], self.noise)


@dataclass(frozen=True)
class AcceptanceRule:
    """The thresholds of the acceptance rule (module docstring) and the judge.

    Parameters
    ----------
    accept_p
        Largest one-sided p-value of a held-out fall that counts as significant.
    fall_noise
        A clear fall: at least this fraction of the noise floor ...
    excess_share
        ... and this share of the excess mean square over the noise floor ...
    fall_relative
        ... and this share of the held-out RMS before.
    fall_numeric
        Falls below this share of the record's force scale are rounding, not
        evidence (an exact table is fitted to 1e-15 N by the right model).
    signature_share
        An effect declaring the regimes of its signature must take at least this
        share of its held-out fall (mean square) there.
    tie_share
        Candidates within this share of the best candidate's fall tie with it unless
        the held-out data tell them apart (:meth:`tie_test`); a drift taking
        ``1 - tie_share`` of the fall confounds an effect with time.
    at_floor
        The search stops when the held-out RMS is within this factor of the noise floor.
    """

    accept_p: float = 0.05
    fall_noise: float = 0.1
    excess_share: float = 0.5
    fall_relative: float = 0.02
    fall_numeric: float = 1e-9
    signature_share: float = 2.0 / 3.0
    tie_share: float = 0.1
    at_floor: float = 1.05

    def __post_init__(self) -> None:
        for name in ("accept_p", "excess_share", "signature_share", "tie_share"):
            value = getattr(self, name)
            if not 0.0 < value < 1.0:
                raise FcompError(f"AcceptanceRule: {name} must lie in (0, 1), got {value!r}")
        for name in ("fall_noise", "fall_relative", "fall_numeric"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise FcompError(f"AcceptanceRule: {name} must be finite and >= 0, got "
                                 f"{value!r}")
        if not (math.isfinite(self.at_floor) and self.at_floor >= 1.0):
            raise FcompError(f"AcceptanceRule: at_floor must be finite and >= 1, got "
                             f"{self.at_floor!r}")

    def judge(self, before: FitResult, after: FitResult, ground: Ground,
              acts_in: Sequence[str] = ()) -> Judgement:
        """Judge ``after`` (the model with the candidate) against ``before`` on ``ground``.

        ``acts_in`` are the regimes the candidate's signature lives in (``Effect.acts_in``).
        """
        nf = ground.noise
        fall = before.rms_test - after.rms_test
        pieces = changed_pieces(before.residual, after.residual, ground.blocks,
                                self.fall_noise * nf)
        z, p = fall_test(before.residual, after.residual, pieces, 0.0)  # pieces chosen
        dbic = delta_bic(before, after, ground.split.train)
        out: list[Failure] = []
        if not fall > 0:
            out.append(Failure("no-fall", {"before": before.rms_test, "after": after.rms_test}))
        changed, rb, ra, need = self._where_changed(before, after, pieces, ground)
        if fall > 0 and rb - ra < need:
            out.append(Failure("small-fall", {"fall": rb - ra, "need": need}))
        # the floor of the scored residual where the candidate acts: the noise, and what the
        # right model would score within the timing windows of the events there
        excess = rb**2 - nf**2 * ground.timing_share(before, changed)
        share = (rb**2 - ra**2) / excess if excess > 0 else 0.0
        if fall > 0 and rb - ra >= need and share < self.excess_share:
            out.append(Failure("small-share", {"share": share, "least": self.excess_share}))
        if not p <= self.accept_p:
            out.append(Failure("not-significant", {"z": z, "p": p, "most": self.accept_p}))
        inside = signature_share(acts_in, before.residual, after.residual, ground)
        if fall > 0 and inside is not None and inside < self.signature_share:
            out.append(Failure("outside-signature", {"share": inside, "where": ", ".join(acts_in),
                                                     "least": self.signature_share}))
        drift = ground.drift(before)
        if fall > 0 and drift >= (1.0 - self.tie_share) * fall:
            out.append(Failure("confounded-with-time", {"drift": drift, "fall": fall}))
        if not dbic < 0:
            out.append(Failure("bic", {"delta_bic": dbic}))
        return Judgement(fall, z, p, dbic, tuple(out), self)

    def _where_changed(self, before: FitResult, after: FitResult,
                       pieces: Sequence[np.ndarray], ground: Ground
                       ) -> tuple[np.ndarray, float, float, float]:
        """``(changed, rms_before, rms_after, need)`` on the held-out ``pieces`` where the
        prediction changed: the samples, both RMS values without the 1 % of samples where
        both residuals are largest (:func:`.features.paired_trimmed_rms`), and the fall a
        clear one needs there (class docstring: ``fall_noise``, ``fall_relative``,
        ``fall_numeric``)."""
        changed = np.concatenate(pieces) if pieces else np.zeros(0, dtype=int)
        if changed.size:  # isolated timing spikes are in both and no effect explains them
            rb, ra = paired_trimmed_rms(before.residual[changed], after.residual[changed])
        else:
            rb = ra = before.rms_test
        need = max(self.fall_noise * ground.noise, self.fall_relative * rb,
                   self.fall_numeric * ground.data.scales.force)
        return changed, rb, ra, need

    def tie_test(self, best: FitResult, rival: FitResult, fall: float,
                 ground: Ground) -> TieTest:
        """Whether a qualifying ``rival`` ties with the ``best`` candidate of a step whose
        held-out fall (from the model before the step) was ``fall`` (N).

        A rival ties only when the record cannot tell the two apart: it is *close* --
        its held-out RMS within ``tie_share`` of the fall of the best one's,
        ``rms_rival - rms_best <= tie_share*fall`` -- and the best one is *not clearly
        and significantly better* by the test any fall must pass (:meth:`judge`), with
        the rival in the place of the model before: on the held-out pieces where the
        two predictions differ by ``fall_noise`` of the noise floor (RMS), the best one's
        RMS is below the rival's by at least ``max(fall_noise*noise_floor,
        fall_relative*rms_rival)`` and the paired test of equal predictive accuracy of
        Diebold & Mariano (1995) on the squared residuals, piece by piece with a
        Newey-West variance (:func:`fall_test`), rejects "the rival predicts as well" at
        one-sided ``p <= accept_p/2``, and so does the same comparison with the pieces as
        the units (:func:`piece_test`) -- half the level because the best one is named by
        the held-out RMS it is tested on, which makes a one-sided test at ``accept_p/2``
        the two-sided one at ``accept_p``; and no experiment of the record says the contrary: in
        none does the same test, the other way round, find the rival better at
        ``p <= accept_p/K`` (``K`` the experiments with such pieces; Bonferroni). Records
        that contradict each other -- one clearly better fitted by each candidate --
        show structure neither explains, and the pooled difference is the balance of two
        misfits, not evidence for one law (the Circle seal at 2, 4, 6 bar: the area
        error ahead of a Stribeck curve at 2 and 4 bar, behind it at 6).

        Why both tests: :func:`fall_test` is conditional on the prediction change and
        takes the best one's residual as the noise along it -- right when the best one is
        the record's law, as an accepted effect is meant to be. Two rivals may both miss
        structure the record holds; the misfit then varies from piece to piece, and
        :func:`piece_test` counts that spread as uncertainty (the O-ring at 3 and 7 bar: a
        force offset against a direction asymmetry, ``z`` 2.9 conditional, ``t`` 1.6 piece
        by piece, the offset ahead in 38 % of the 3 bar pieces: a tie). For a rival that
        misses the law itself the difference is there in piece after piece, and both
        tests find it.

        Why no closeness against the noise floor beside the fall's share: the noise
        floor is what the held-out residual of a model without systematic error
        reaches, so a rival whose RMS is several noise floors above the best one's
        carries a systematic misfit of about ``sqrt(rms_rival^2 - rms_best^2)`` that
        the best one has not. Seen in two or more held-out pieces against the noise,
        the paired test finds it, and the tie is broken by the data, not by a second
        threshold. Where the test cannot find it, the difference sits in fewer than two
        pieces or within the spread the residuals' correlation allows: one event, which
        the rule does not take as evidence for a fall either, and a threshold on the RMS
        would then decide on that one event. The clear-difference condition is the
        other side: a difference below a tenth of the noise floor where the
        predictions differ is within noise however long the record, and a tie stays a
        tie (both candidates at the noise floor, their predictions within it).
        """
        pieces = changed_pieces(rival.residual, best.residual, ground.blocks,
                                self.fall_noise * ground.noise)
        z, p = fall_test(rival.residual, best.residual, pieces, 0.0)  # pieces chosen
        _, piece_p = piece_test(rival.residual, best.residual, pieces)
        _, rr, rb, need = self._where_changed(rival, best, pieces, ground)
        groups = _by_experiment(pieces, [e.start for e in ground.data.experiments])
        contrary = min((fall_test(best.residual, rival.residual, g, 0.0)[1] for g in groups),
                       default=1.0)
        return TieTest(gap=rival.rms_test - best.rms_test, allowed=self.tie_share * fall,
                       difference=rr - rb, need=need, z=z, p=p, piece_p=piece_p,
                       contrary_p=contrary, experiments=len(groups), rule=self)


def _by_experiment(pieces: Sequence[np.ndarray], starts: Sequence[int]) -> list[list[np.ndarray]]:
    """The held-out ``pieces`` grouped by the experiment they lie in (experiments start at
    ``starts``, ascending; a piece never crosses a start, :func:`heldout_pieces`)."""
    out: dict[int, list[np.ndarray]] = {}
    for b in pieces:
        out.setdefault(int(np.searchsorted(starts, b[0], side="right")), []).append(b)
    return [out[k] for k in sorted(out)]


@dataclass(frozen=True)
class TieTest:
    """What :meth:`AcceptanceRule.tie_test` found: a rival against the best candidate.

    Attributes
    ----------
    gap, allowed : N
        ``rms_rival - rms_best`` on the held-out samples, and the closeness allowed,
        ``tie_share*fall``.
    difference, need : N
        ``rms_rival - rms_best`` (trimmed) on the held-out pieces where the two
        predictions differ, and the difference a clear one needs there.
    z, p : float
        The paired test (:func:`fall_test`) of the best one against the rival,
        one-sided: a small ``p`` says the best one predicts the held-out data better.
    piece_p : float
        One-sided p-value of :func:`piece_test`, the pieces as the units.
    contrary_p : float
        The smallest one-sided p-value of the same test the other way round (the rival
        better) in one experiment of the record.
    experiments : int
        The experiments holding held-out pieces where the two predictions differ.
    rule : AcceptanceRule
    """

    gap: float
    allowed: float
    difference: float
    need: float
    z: float
    p: float
    piece_p: float
    contrary_p: float
    experiments: int
    rule: AcceptanceRule

    @property
    def close(self) -> bool:
        """Within ``tie_share`` of the step's fall."""
        return self.gap <= self.allowed

    @property
    def separated(self) -> bool:
        """The held-out data tell the two apart: a clear difference, significant by both
        tests at ``accept_p/2`` each, and no experiment significantly the other way (at
        ``accept_p`` over the experiments)."""
        level = self.rule.accept_p / 2  # the best one is named by the data tested: two-sided
        return (self.difference >= self.need and self.p <= level and self.piece_p <= level
                and not self.contrary_p <= self.rule.accept_p / max(self.experiments, 1))

    @property
    def tie(self) -> bool:
        """Close, and not told apart by the held-out data."""
        return self.close and not self.separated

    def to_dict(self) -> dict[str, float | bool]:
        """The figures (N; ``z``, ``p``) and the outcome, for the JSON."""
        return {"gap": self.gap, "allowed": self.allowed, "difference": self.difference,
                "need": self.need, "z": self.z, "p": self.p, "piece_p": self.piece_p,
                "contrary_p": self.contrary_p,
                "experiments": self.experiments, "close": self.close,
                "separated": self.separated, "tie": self.tie}


def signature_share(acts_in: Sequence[str], before: np.ndarray, after: np.ndarray,
                    ground: Ground) -> float | None:
    """Share of the held-out fall in mean square, ``sum(before^2 - after^2)``, in the regimes
    ``acts_in``; None when none is declared or nothing falls."""
    if not acts_in:
        return None
    unknown = [r for r in acts_in if r not in REGIMES]
    if unknown:
        raise FcompError(f"acts_in names regimes {unknown}; known: {', '.join(REGIMES)}")
    test = ground.split.test
    gain = before[test] ** 2 - after[test] ** 2
    total = float(np.sum(gain))
    if not total > 0:
        return None
    there = np.isin(ground.segmentation.regime[test], [REGIMES.index(r) for r in acts_in])
    return float(np.sum(gain[there])) / total


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


def piece_test(r_before: np.ndarray, r_after: np.ndarray,
               pieces: Sequence[np.ndarray]) -> tuple[float, float]:
    """``(t, p)``: is the squared error lower after, piece by piece?

    The test of equal predictive accuracy of Diebold & Mariano (1995) on the
    squared-error differences ``d = r_before^2 - r_after^2``, unconditional, with the
    long-run variance estimated by batch means, each held-out piece a batch (Schmeiser
    1982; the pieces, about 0.25 s, are longer than the residuals' correlation): with
    ``m_k`` the mean of ``d`` over piece ``k`` of ``K``, ``t = mean(m) / (sd(m)/sqrt(K))``
    and the one-sided p-value of Student's t with ``K - 1`` degrees of freedom. The spread
    of ``m`` from piece to piece -- of the noise and of whatever either model misses --
    is the uncertainty; :func:`fall_test` conditions on the prediction change instead.
    Fewer than two pieces: ``p = 1``.
    """
    if len(pieces) < 2:
        return math.nan, 1.0
    m = np.array([float(np.mean(r_before[b] ** 2 - r_after[b] ** 2)) for b in pieces])
    sd = float(np.std(m, ddof=1))
    if not sd > 0:
        total = float(np.sum(m))
        return (math.copysign(math.inf, total), 0.0 if total > 0 else 1.0) if total else (0.0, 0.5)
    t = float(np.mean(m)) / (sd / math.sqrt(m.size))
    return t, float(stats.t.sf(t, m.size - 1))


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
