"""Refit a model on the training samples of several experiments; predict everywhere.

The diagnosis refits every candidate model (a baseline plus effects) on the
*training* samples only and scores it on the held-out ones
(:mod:`.scoring`). The fit is the engine's own,
:func:`fcomp.identification.records.fit_records`: one parameter vector, the
model simulated from rest along each experiment's measured motion, the
residuals and Jacobians of every experiment's training samples stacked, a
bounded trust-region solve. What a diagnosis adds is only its settings:

* **Bounds from the data scale.** Each parameter's box is the data box of
  :mod:`.boxes` (its spec bounds intersected with a box set by its unit and
  the record's scales), widened when a fit is pinned at its edge.
* **Several starts, two stages.** The guesses of :mod:`.catalogue` may give
  several starting points; each gets a short fit (:data:`PROBE_NFEV`
  evaluations, on a copy block-averaged to at most :data:`PROBE_SAMPLES`
  samples: the probes only rank the starts) and the best continues to
  convergence. A candidate whose best probe does not lower the training cost
  of the model it would extend by :data:`MIN_GAIN` stops there (it could not
  qualify). The Stribeck exponent ``n`` and the other :data:`STAGED` names
  are held at their start values in a first stage and freed in a second
  one: with ``n`` free from the outset a record with few distinct sliding
  speeds lets the fit slide into a flat valley (``n < 1`` with a large
  viscous term) that matches the training speeds and fails on the others.
* **Sample weights and held terms.** After the first fit each training
  sample weighs how well the measured motion fixes the prediction there
  (:meth:`Refit.set_weights`), and the record's channel lag is held
  (:meth:`Refit.hold`).

Long records are fitted on a block-averaged copy with at most
``max_samples`` samples (every signal and the target averaged over blocks of
``q`` samples, so displacement is preserved:
:meth:`~fcomp.identification.records.Record.averaged`); predictions and every
score are always computed on the full record.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.diagnosis.boxes import BoxState, DataBoxes
from fcomp.diagnosis.data import DiagnosisData, Experiment
from fcomp.diagnosis.scoring import (
    prediction_band,
    sample_weights,
    scored_residual,
    timing_windows,
)
from fcomp.diagnosis.split import Split
from fcomp.identification.dynamic import EXTRAS
from fcomp.identification.engine import ALWAYS_FIXED, default_free
from fcomp.identification.plausibility import (
    FitWarning,
    RigContext,
    check_fit,
    check_held,
    correlations,
)
from fcomp.identification.problem import ParameterVector, base_name
from fcomp.identification.records import Record, RecordsProblem, fit_records, fit_specs
from fcomp.identification.target import FitData, block_mean
from fcomp.identification.uncertainty import estimate
from fcomp.models.base import FrictionModel
from fcomp.trajectory import friction_along_motion

#: Names other modules import from here: the weights and the noise share of the scores
#: (:mod:`.scoring`) and the data boxes (:mod:`.boxes`).
__all__ = ["CANDIDATE_SAMPLES", "MIN_GAIN", "PROBE_NFEV", "PROBE_SAMPLES", "RIG_EXTRAS",
           "STAGED", "FitResult", "FitUncertainty", "Refit", "fixed_names"]

#: Evaluations of each short probe fit when there are several starts.
PROBE_NFEV = 20
#: Smallest share of the training cost a candidate's probes must remove to be refitted fully.
MIN_GAIN = 0.002
#: Largest record the short probes of several starts run on (block-averaged beyond it).
PROBE_SAMPLES = 8_000
#: Largest record a candidate's refit runs on (the accepted model is then polished on the
#: full record).
CANDIDATE_SAMPLES = 15_000
#: Parameters held at their start values in the first stage of a fit.
STAGED = ("n", "p_visc", "kappa_s", "i_pre")
#: Fitted terms of the record, not of the model, carried from fit to fit: the moving mass
#: of a driving force and the lag of its channel (:mod:`fcomp.identification.dynamic`).
RIG_EXTRAS = ("mass", "lag")


@dataclass
class FitResult:
    """A model fitted on the training samples, and its prediction everywhere.

    Attributes
    ----------
    model : FrictionModel
        The model with the fitted values.
    values : dict
        Fitted values by flat name (``mass`` included when it is fitted).
    F_hat, residual : (N,) N
        Prediction and ``y - F_hat`` at every sample.
    rms_train, rms_test : N
        RMS residual over the training and the held-out samples.
    n_params : int
        Number of fitted parameters.
    converged : bool
    nfev : int
        Model evaluations.
    spread : (N,) N or None
        Width of the band the model could be expected to predict at each sample
        (:func:`.scoring.tolerant_residual`): the uncertainty of its prediction that the
        measured motion leaves.
    tolerant : (N,) N or None
        The tolerant residual (:func:`.scoring.tolerant_residual`): the distance of the
        measurement from that band. It shows *where* structure is left (the
        verdict's features, the effects' guesses) but never decides: a wider band
        would lower it.
    plain : (N,) N or None
        ``y - F_hat``, the plain residual (reported beside the deciding one).
    boxes : dict or None
        The boxes of parameters widened beyond their data box (:meth:`.boxes.DataBoxes.widen`).
    stderr : dict or None
        Standard errors of the fitted values by flat name, set when the fit's plausibility
        is checked (:meth:`Refit.plausibility`; the model file's ``stderr``).
    timing_spread : (N,) N or None
        Width of the band from the timing windows alone (the prediction along the
        measured motion, widened by :func:`.scoring.timing_windows`): the part of ``spread``
        no choice of the model's makes wider (:func:`.scoring.score_noise_share`).

    Notes
    -----
    ``residual`` -- and so ``rms_train``/``rms_test`` -- is the *scored*
    residual (:func:`.scoring.scored_residual`): the logarithmic score of the prediction
    band with the noise floor, in newtons. It equals the plain residual where
    the band is a point, and a wider band always costs, so no model can win by
    being uncertain.
    """

    model: FrictionModel
    values: dict[str, float]
    F_hat: np.ndarray = dataclasses.field(repr=False)
    residual: np.ndarray = dataclasses.field(repr=False)
    rms_train: float
    rms_test: float
    n_params: int
    converged: bool
    nfev: int
    spread: np.ndarray | None = dataclasses.field(default=None, repr=False)
    tolerant: np.ndarray | None = dataclasses.field(default=None, repr=False)
    plain: np.ndarray | None = dataclasses.field(default=None, repr=False)
    boxes: dict[str, tuple[float, float]] | None = None
    timing_spread: np.ndarray | None = dataclasses.field(default=None, repr=False)
    stderr: dict[str, float] | None = None

    @property
    def located(self) -> np.ndarray:
        """The residual that *locates* structure: the tolerant one where there is one."""
        return self.tolerant if self.tolerant is not None else self.residual

    @property
    def plain_residual(self) -> np.ndarray:
        """``y - F_hat`` (the scored residual where a result carries no plain one)."""
        return self.plain if self.plain is not None else self.residual


def fixed_names(model: FrictionModel) -> set[str]:
    """Flat names never fitted: numerical thresholds, references, effects' ``fixed`` lists."""
    out = {n for n in model.flat_params() if base_name(n) in ALWAYS_FIXED}
    for e in model.effects:
        out |= {n for n in e.params.flat() if base_name(n) in getattr(e, "fixed", ())}
    return out


class Refit:
    """Fits and predictions of models on one record and split (see the module docstring).

    Parameters
    ----------
    data
        The record.
    split
        Training and held-out samples.
    d_pre
        Presliding length (m) of the record (for the stiffness bounds).
    max_nfev
        Evaluation budget of each fit.
    max_samples
        Largest number of samples a fit runs on (longer records are block-averaged).
    noise
        The record's noise floor (N, RMS): the measurement noise of the scored
        residual (:func:`.scoring.scored_residual`). ``None`` scores the plain
        residual (each prediction taken as a point).
    """

    def __init__(self, data: DiagnosisData, split: Split, d_pre: float, *,
                 max_nfev: int = 60, max_samples: int = 40_000,
                 noise: float | None = None) -> None:
        self.data = data
        self.split = split
        self.d_pre = d_pre
        self.noise = noise
        self.max_nfev = max_nfev
        self.q = max(1, math.ceil(data.n / max_samples))
        #: block sizes of the probes' and of a candidate's records
        self.q_probe = max(self.q, math.ceil(data.n / PROBE_SAMPLES))
        self.q_candidate = max(self.q, math.ceil(data.n / CANDIDATE_SAMPLES))
        self.windows = timing_windows(data.signal("v"), data.scales.dt, data.scales.resolution)
        #: :data:`RIG_EXTRAS` estimated once and held from then on (:meth:`hold`)
        self.held: dict[str, float] = {}
        #: model parameters the record cannot determine, kept at their model values in every
        #: fit from now on (:meth:`keep`)
        self.kept: set[str] = set()
        #: the data boxes, widened when a fit was pinned at their edge (:mod:`.boxes`)
        self.boxes = DataBoxes(data.scales, d_pre)
        #: the weight of every sample (:meth:`set_weights`; None: unweighted)
        self._weights: np.ndarray | None = None
        self._build_records()

    def _build_records(self) -> None:
        self._by_q: dict[int, list[Record]] = {}
        self._weighted: dict[int, list[Record]] = {}
        for q in (self.q, self.q_probe, self.q_candidate):
            self._records(q)

    def __getstate__(self) -> dict[str, Any]:
        """A lean copy for another process: the records and their weights are rebuilt there."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_by_q", "_weighted")}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._build_records()

    def _training(self) -> list[tuple[Experiment, np.ndarray]]:
        """Every experiment with training samples, and its training mask."""
        out = []
        for e in self.data.experiments:
            train = self.split.train[e.start:e.stop]
            if train.any():
                out.append((e, train))
        return out

    def _records(self, q: int) -> list[Record]:
        """The fit records averaged over blocks of ``q`` samples (cached): per experiment
        with training samples, its data with the held extras taken out (:meth:`hold`),
        the training mask and the sample weights (:meth:`set_weights`)."""
        if q not in self._by_q:
            self._by_q[q] = [Record(e.data, train).holding(self.held).averaged(q)
                             for e, train in self._training()]
        if self._weights is None:
            return self._by_q[q]
        if q not in self._weighted:
            w = self._weights
            self._weighted[q] = [dataclasses.replace(r, weights=block_mean(w[e.start:e.stop], q))
                                 for r, (e, _) in zip(self._by_q[q], self._training(),
                                                      strict=True)]
        return self._weighted[q]

    def hold(self, name: str, value: float) -> None:
        """Hold the rig extra ``name`` (``"lag"``) at ``value`` in every fit from now on.

        A channel lag is a property of the record, not of the friction model, so
        it is estimated once, by the first fit, and held: the sample weights of
        the later fits (:meth:`set_weights`) distrust exactly the samples where
        the driving force changes fast, which are the ones that fix the lag
        (weighted fits took a 1.5 ms lag to 0.55 ms). The fit records carry the
        force with the held term taken out; the predictions add it back, and
        :class:`FitResult` values report it.
        """
        if name not in RIG_EXTRAS:
            raise KeyError(f"no rig extra {name!r}")
        self.held[name] = float(value)
        self._build_records()

    def keep(self, names: Sequence[str]) -> None:
        """Keep the model parameters ``names`` at their model values in every fit from now on.

        An accepted effect holds what the record cannot determine at its no-op value
        (:meth:`fcomp.effects.Effect.held`: the vented chamber's ``dA2`` of an area
        error, the chamber weight ``kd`` of a pressure law with one chamber at a
        constant pressure, a form's held term): the refits of every later step free
        the whole model, and a parameter held only in the step that added it was
        fitted again there (``kd`` of a pressure law came back at 1.7e-7 /Pa after a
        direction asymmetry's step on a single-acting cylinder)."""
        self.kept |= set(names)

    def refit_held(self, name: str, fit: FitResult) -> float:
        """Estimate the held extra ``name`` again for ``fit``'s model, and hold the new value.

        A lag held from the first fit carries that model's error: a baseline
        missing an effect that acts where the force changes fast (pre-sliding
        memory) took a 1.7 ms lag to 3.5 ms. When the model changes, the extra is
        estimated again *jointly with the model*: every parameter of ``fit``'s model and
        the extra refitted together, unweighted (the sample weights distrust exactly the
        samples where the force changes fast, which fix a lag), from ``fit``'s values and
        the held value, on the candidates' block-averaged record; only the extra is kept
        (the model is then refitted, weighted, with it held). Estimated alone with the
        model fixed, a lag settled where the model compensates it -- the lag and the
        bristle damping trade against each other (-1.82 ms for 0.52 ms true, and a step
        left at 40 N; jointly -0.71 ms and 16 N). The other extras are held meanwhile.
        Returns the new value.
        """
        saved_held, saved_weights = dict(self.held), self._weights
        self.held = {k: float(v) for k, v in fit.values.items() if k in RIG_EXTRAS and k != name}
        self._weights = None
        self._build_records()
        try:
            free = [*self.free_names(fit.model), name]
            start = {**{k: v for k, v in fit.values.items() if k in free},
                     name: saved_held.get(name, 0.0)}
            value = self.fit(fit.model, [start], list(dict.fromkeys(free)),
                             fast=True).values[name]
        finally:
            self.held, self._weights = saved_held, saved_weights
            self._build_records()
        self.hold(name, value)
        return float(value)

    def rescore(self, fit: FitResult) -> FitResult:
        """``fit`` scored again with the extras now held (:meth:`hold`)."""
        values = {k: v for k, v in fit.values.items() if k not in self.held}
        return self.result(fit.model, values, fit.n_params, fit.converged, fit.nfev)

    def set_weights(self, spread: np.ndarray, noise: float) -> None:
        """Weigh each sample by how well the measured motion fixes the prediction there.

        ``w = 1/(1 + (spread/(2*noise))^2)`` with ``spread`` the width of the band
        the current model could be expected to predict (:attr:`FitResult.spread`,
        :func:`.scoring.sample_weights`):
        where a friction law jumps by its whole level within the timing
        uncertainty of an event, or differs along motions as consistent with
        the position, a sample says little about the parameters and would
        otherwise dominate the squares (a static law's 500 N step one sample
        early). Fits after this weigh their residuals by ``sqrt(w)``.
        """
        self._weights = sample_weights(spread, noise)
        self._weighted = {}

    # ------------------------------------------------------------ predict
    def predict(self, model: FrictionModel, values: Mapping[str, float] | None = None
                ) -> np.ndarray:
        """Predicted force (N) at every sample of the record (full rate)."""
        return self._predictions(model, values, alternatives=False)[0]

    def _predictions(self, model: FrictionModel, values: Mapping[str, float] | None,
                     alternatives: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(F_hat, lo, hi)``: the prediction and its range along the alternative motions."""
        vals = dict(values or {})
        rig = {**self.held, **{k: vals.pop(k) for k in RIG_EXTRAS if k in vals}}
        out, lo, hi = [], [], []
        for e in self.data.experiments:
            F = self._predict_one(model, e.data, vals, rig, e.data.sig)
            f_lo, f_hi = F.copy(), F.copy()
            if alternatives:
                for alt in e.alternatives:
                    sig = dict(e.data.sig, v=alt.v, a=alt.a)
                    Fa = self._predict_one(model, e.data, vals, rig, sig)
                    np.minimum(f_lo, Fa, out=f_lo)
                    np.maximum(f_hi, Fa, out=f_hi)
            out.append(F)
            lo.append(f_lo)
            hi.append(f_hi)
        return np.concatenate(out), np.concatenate(lo), np.concatenate(hi)

    def motion_prediction(self, fit: FitResult) -> np.ndarray:
        """``fit``'s prediction without its channel-lag term ``-lag*dD/dt``: what the model
        predicts from the motion alone.

        The lag term is built from the measured driving force, so it carries
        whatever that channel carries: a pump's line on ``p1`` reappeared in the
        prediction through it, and the disturbance check (:mod:`.disturbance`)
        took the line for the motion's and let it pass into the noise floor.
        """
        lag = fit.values.get("lag", self.held.get("lag"))
        if not lag or not self.data.fits_lag:
            return fit.F_hat
        return fit.F_hat - float(lag) * np.concatenate(
            [e.data.extra_column("lag") for e in self.data.experiments])

    @staticmethod
    def _predict_one(model: FrictionModel, d: FitData, vals: Mapping[str, float],
                     rig: Mapping[str, float], s: Mapping[str, np.ndarray]) -> np.ndarray:
        """The prediction along the motion ``s`` of the record ``d``, with its
        :data:`RIG_EXTRAS` (as :class:`~fcomp.identification.dynamic.TrajectoryProblem`)."""
        F = d.band_limited(friction_along_motion(
            model, s["t"], s["v"], a=s["a"], x=s["x"], p1=s["p1"], p2=s["p2"],
            values=vals or None).F)
        for name, value in rig.items():
            col = d.extra_column(name)
            if col is not None:
                F = F + value * col
        return F

    def result(self, model: FrictionModel, values: Mapping[str, float], n_params: int,
               converged: bool = True, nfev: int = 0) -> FitResult:
        """The :class:`FitResult` of ``model`` with ``values`` (scored on the full record).

        The residual that decides is the scored one (:func:`.scoring.scored_residual`)
        of the prediction's band (:func:`.scoring.prediction_band`: its range along the
        record's alternative motions, widened by the timing windows) with the
        noise floor; the tolerant and the plain residual ride along.
        """
        values = {**values, **self.held}
        model_vals = {k: v for k, v in values.items() if k not in RIG_EXTRAS}
        fitted = model.with_params(**model_vals) if model_vals else model
        extras = {k: values[k] for k in RIG_EXTRAS if k in values}
        F_hat, lo, hi = self._predictions(fitted, extras, alternatives=True)
        y = self.data.y
        low, high = prediction_band(lo, hi, [e.start for e in self.data.experiments],
                                    self.windows)
        tolerant = y - np.clip(y, low, high)
        plain = y - F_hat
        t_low, t_high = prediction_band(F_hat, F_hat, [e.start for e in self.data.experiments],
                                        self.windows)
        sigma = self.noise if self.noise is not None and self.noise > 0 else None
        if sigma is None:
            r = plain
        else:  # a floor of zero (an exact table): a band still costs, at rounding scale
            r = scored_residual(y, F_hat, low, high,
                                max(sigma, 1e-12 * self.data.scales.force))
        tr, te = self.split.train, self.split.test
        return FitResult(fitted, dict(values), F_hat, r, _rms(r[tr]), _rms(r[te]), n_params,
                         converged, nfev, high - low, tolerant, plain,
                         {k: v for k, v in self.boxes.wide.items() if k in values} or None,
                         t_high - t_low)


    # ---------------------------------------------------------------- fit
    def free_names(self, model: FrictionModel) -> list[str]:
        fixed = fixed_names(model) | self.kept
        names = [n for n in default_free(model) if n not in fixed]
        if self.data.fits_mass:
            names.append("mass")
        if self.data.fits_lag:
            names.append("lag")
        return [n for n in names if n not in self.held]

    def box_state(self) -> BoxState:
        """The widened boxes and their counts (to restore with :meth:`set_box_state`)."""
        return self.boxes.state()

    def set_box_state(self, state: BoxState) -> None:
        self.boxes.set_state(state)

    def adopt_boxes(self, fit: FitResult) -> None:
        """Take over the boxes a fit elsewhere (a worker process) widened."""
        self.boxes.adopt(fit.boxes or {})

    def train_cost(self, model: FrictionModel, values: Mapping[str, float]) -> float:
        """Sum of squared residuals over the training samples of the probe records (N^2).

        The measure the probes of :meth:`fit` minimise (plain residuals on the
        block-averaged records, weighted as the fits weigh them), so a candidate's
        probes can be compared with it.
        """
        vals = {k: v for k, v in values.items() if k not in RIG_EXTRAS}
        rig = {k: values[k] for k in RIG_EXTRAS if k in values and k not in self.held}
        total = 0.0
        for rec in self._records(self.q_probe):
            m = rec.mask if rec.mask is not None else slice(None)
            r = (rec.data.y - self._predict_one(model, rec.data, vals, rig, rec.data.sig))[m]
            if rec.weights is not None:
                r = r * np.sqrt(rec.weights[m])
            total += float(r @ r)
        return total

    def fit(self, model: FrictionModel, starts: Sequence[Mapping[str, float]] = (),
            free: Sequence[str] | None = None, *, max_nfev: int | None = None,
            reference: float | None = None, fast: bool = False) -> FitResult:
        """Fit ``model`` on the training samples from the best of ``starts``.

        Each start maps flat names to values (missing names: the model's
        current values); ``free`` the names to fit (default :meth:`free_names`; held
        extras, :meth:`hold`, are never free);
        ``max_nfev`` overrides the evaluation budget. With ``reference`` (the
        training cost of the model a candidate would replace,
        :meth:`train_cost`) a refit whose best short probe does not lower it by
        :data:`MIN_GAIN` stops there: a candidate that cannot even improve the
        training fit cannot qualify, and its full refit would be wasted.
        ``fast`` fits on a copy block-averaged to :data:`CANDIDATE_SAMPLES` (a
        candidate's refit; the model accepted is polished on the full record).
        The fit is :func:`~fcomp.identification.records.fit_records` (module
        docstring); a solution pinned at the edge of a data box is fitted again in
        the widened box (:meth:`.boxes.DataBoxes.widen`). Returns the
        :class:`FitResult`, scored on the full record.
        """
        max_nfev = max_nfev or self.max_nfev
        names = [n for n in free if n not in self.held and n not in self.kept] \
            if free is not None else self.free_names(model)
        if not names:
            return self.result(model, {}, 0)
        # a model parameter named like an identification extra ("offset" of the
        # force-offset effect) is fitted as that extra: the model's own copy is zero
        clash = {n: 0.0 for n in names if n in EXTRAS and n in model.flat_params()}
        if clash:
            model = model.with_params(**clash)
        records = self._records(self.q_candidate if fast else self.q)
        bounds = self.boxes.bounds(model, names)

        def magnitudes(start: Mapping[str, float]) -> dict[str, float]:
            return self.boxes.magnitudes(model, names, start)

        def keep_going(cost: float) -> bool:
            return reference is None or not cost > (1.0 - MIN_GAIN) * reference

        out = fit_records(model, records, names, starts=starts, bounds=bounds,
                          scales=magnitudes, max_nfev=max_nfev,
                          probe_nfev=min(PROBE_NFEV, max_nfev),
                          probe_records=self._records(self.q_probe), keep_going=keep_going,
                          staged=[n for n in names if base_name(n) in STAGED], compress=True)
        nfev = out.nfev
        if out.probed_only:
            return self.result(model, out.values, len(names), False, nfev)
        # pinned at an edge of a box the record's scale set: try the wider box first
        while True:
            pinned = [(n, -1 if out.values[n] <= 0.5 * (bounds[n][0] + bounds[n][1]) else 1)
                      for n, at in zip(names, out.solution.at_bound, strict=True) if at]
            if not [self.boxes.widen(model, n, side) for n, side in pinned].count(True):
                break
            bounds = self.boxes.bounds(model, names)
            out = fit_records(model, records, names, starts=[out.values], bounds=bounds,
                              scales=magnitudes, max_nfev=max_nfev, compress=True)
            nfev += out.nfev
        return self.result(model, out.values, len(names), out.converged, nfev)

    def uncertainty(self, fit: FitResult) -> FitUncertainty:
        """Standard errors, intervals and correlations of ``fit``'s fitted parameters.

        From the Jacobian at the estimate over the training samples, weighed as the
        fit weighed them (batch-means HAC,
        :func:`fcomp.identification.uncertainty.estimate`); the extras held from an
        earlier fit (:meth:`hold`, the channel ``lag``) and the parameters kept
        (:meth:`keep`) are not among them.
        """
        names = [n for n in fit.values if n not in self.held]
        if not names:
            return FitUncertainty({}, {}, {}, {})
        base = fit.model
        specs = fit_specs(base, names, self.boxes.bounds(base, names))
        pv = ParameterVector.build(names, fit.values, specs,
                                   self.boxes.magnitudes(base, names, fit.values))
        theta = np.array([fit.values[n] for n in names])
        r, G = RecordsProblem(base, self._records(self.q), pv)(theta, True)
        assert G is not None
        unc = estimate(G, r, theta)
        return FitUncertainty(
            dict(zip(names, map(float, unc.stderr), strict=True)),
            {n: (float(lo), float(hi))
             for n, lo, hi in zip(names, unc.ci_low, unc.ci_high, strict=True)},
            correlations(names, unc.cov),
            {n: (specs[n].lower, specs[n].upper) for n in names},
            {n: specs[n].unit for n in names})

    def plausibility(self, fit: FitResult, context: RigContext | None = None
                     ) -> list[FitWarning]:
        """The plausibility warnings of ``fit`` (:func:`fcomp.identification.plausibility.check_fit`).

        Standard errors, intervals and correlations from :meth:`uncertainty`; bounds
        are the data boxes the fit searched (:func:`data_bounds`). The extras held
        from an earlier fit (:meth:`hold`, the channel ``lag``) are checked against
        their boxes too (:func:`fcomp.identification.plausibility.check_held`: at a
        bound, a negative lag), after the fitted parameters.
        """
        held_names = [n for n in self.held if n in fit.values]
        held: list[FitWarning] = []
        if held_names:
            hs = fit_specs(fit.model, held_names, self.boxes.bounds(fit.model, held_names))
            held = check_held({n: float(fit.values[n]) for n in held_names},
                              {n: (hs[n].lower, hs[n].upper) for n in held_names},
                              units={n: hs[n].unit for n in held_names},
                              dt=self.q * self.data.scales.dt, context=context)
        unc = self.uncertainty(fit)
        if not unc.stderr:
            return held
        fit.stderr = dict(unc.stderr)  # what the model file writes
        return check_fit(fit.values, unc.stderr, unc.ci, unc.bounds, unc.correlations,
                         fit.converged, context, units=unc.units) + held


@dataclass(frozen=True)
class FitUncertainty:
    """Standard errors (same units as the values), 95 % intervals, correlations, the boxes
    searched and the units of a fit's parameters (:meth:`Refit.uncertainty`)."""

    stderr: dict[str, float]
    ci: dict[str, tuple[float, float]]
    correlations: dict[tuple[str, str], float]
    bounds: dict[str, tuple[float, float]]
    units: dict[str, str] = dataclasses.field(default_factory=dict)


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r**2))) if r.size else math.nan
