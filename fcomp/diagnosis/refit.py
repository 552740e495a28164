"""Refit a model on the training samples of several experiments; predict everywhere.

The diagnosis refits every candidate model (a baseline plus effects) on the
*training* samples only and scores it on the held-out ones. The fit is the
trajectory least squares of :mod:`fcomp.identification` -- the model
simulated along each experiment's measured motion
(:class:`~fcomp.identification.dynamic.TrajectoryProblem`, exact
sensitivities, bounded trust-region solve of
:func:`~fcomp.identification.problem.solve`) -- with three additions a
diagnosis needs:

* **Several experiments, one parameter vector.** Residuals and Jacobians of
  every experiment's training samples are stacked; each experiment is
  simulated from rest over its whole length.
* **Bounds from the data scale.** Each parameter's box is its
  :class:`~fcomp.parameters.ParamSpec` bounds intersected with a box set by
  its unit and the record's :class:`~fcomp.conditioning.Scales`
  (:func:`data_bounds`), so no fit can run away to a value the record could
  not support (a stiffness softer than the stroke allows, a time constant
  shorter than a sample...).
* **Several starts, two stages.** The guesses of :mod:`.catalogue` may give
  several starting points; each gets a short fit (:data:`PROBE_NFEV`
  evaluations, on a copy block-averaged to at most :data:`PROBE_SAMPLES`
  samples: the probes only rank the starts) and the best continues to
  convergence on the full-rate record. A candidate whose best probe does not
  lower the training cost of the model it would extend by :data:`MIN_GAIN`
  stops there (it could not qualify). The Stribeck exponent
  ``n`` is held at its start value in this first stage and freed in a second
  one: with ``n`` free from the outset a record with few distinct sliding
  speeds lets the fit slide into a flat valley (``n < 1`` with a large
  viscous term) that matches the training speeds and fails on the others.

Long records are fitted on a block-averaged copy with at most
``max_samples`` samples (every signal and the target averaged over blocks of
``q`` samples, so displacement is preserved); predictions and every score
are always computed on the full record.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.conditioning import Scales
from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.split import Split
from fcomp.identification.dynamic import EXTRAS, TrajectoryProblem
from fcomp.identification.estimator import ALWAYS_FIXED, EXTRA_SPECS, default_free
from fcomp.identification.plausibility import FitWarning, RigContext, check_fit, correlations
from fcomp.identification.problem import ParameterVector, base_name, solve
from fcomp.identification.records import best_start
from fcomp.identification.target import FitData
from fcomp.identification.uncertainty import estimate
from fcomp.models.base import FrictionModel
from fcomp.parameters import ParamSpec
from fcomp.trajectory import friction_along_motion

#: Evaluations of each short probe fit when there are several starts.
PROBE_NFEV = 20
#: Smallest share of the training cost a candidate's probes must remove to be refitted fully.
MIN_GAIN = 0.002
#: Largest record the short probes of several starts run on (block-averaged beyond it).
PROBE_SAMPLES = 8_000
#: Largest record a candidate's refit runs on (the accepted model is then polished on the
#: full record).
CANDIDATE_SAMPLES = 15_000
#: Softest stiffness allowed: its presliding range ``F/k`` is at most this many ``d_pre``.
PRESLIDING_SPAN = 20.0
#: Parameters held at their start values in the first stage of a fit.
STAGED = ("n", "p_visc", "kappa_s", "i_pre")
#: Half-width, in unit scales, of the box of a pressure level-law coefficient.
LEVEL_LAW_SPAN = 2.0
#: Fitted terms of the record, not of the model, carried from fit to fit: the moving mass
#: of a driving force and the lag of its channel (:mod:`fcomp.identification.dynamic`).
RIG_EXTRAS = ("mass", "lag")


def unit_scale(unit: str, sc: Scales, d_pre: float) -> float:
    """The natural magnitude of a quantity of ``unit`` in this record (SI)."""
    table = {
        "N": sc.force,
        "Ns/m": sc.force / sc.speed,
        "N/m": sc.force / max(d_pre, sc.resolution),
        "m/s": sc.speed,
        "m/s^2": sc.accel,
        "m": sc.stroke,
        "s": max(sc.duration, 10 * sc.dt),
        "1/Pa": 1.0 / max(sc.p_span, abs(sc.p_mid), 1.0),
        "1/Pa^2": 1.0 / max(sc.p_span, abs(sc.p_mid), 1.0) ** 2,
        "kg": sc.force / sc.accel,
        "Pa": max(sc.p_span, abs(sc.p_mid), 1.0),
    }
    return float(table.get(unit, 1.0))


def data_bounds(spec: ParamSpec, sc: Scales, d_pre: float) -> tuple[float, float]:
    """Box of a parameter: its spec bounds intersected with a data-derived box.

    Positive quantities (spec lower bound >= 0) are confined to
    ``[lo_u, hi_u]`` by unit: forces ``[0, 20 F]``; viscous coefficients
    ``[0, 50 F/V]``; stiffnesses ``[F/min(0.5*stroke, 20*d_pre), F/(0.2*resolution)]``
    (a bristle softer than that would make the presliding range twenty times
    the record's measured presliding length ``d_pre``: a soft spring then acts
    as a slow integrator that fits training segments and fails on others);
    the bristle damping ``sigma1 <= 4 F/V``, so that the model stays
    dissipative at the record's speeds (``sigma1*|v| <= 4*Fc``,
    :meth:`~fcomp.models.lugre_family.LuGreFamily.passivity`);
    speeds ``[1e-4 V, 100 V]``; lengths ``[0.2*resolution, stroke]``;
    time constants ``[dt/2, 10*duration]``; dimensionless numbers keep their
    spec box (an open lower bound becomes 1e-3). Signed quantities get
    ``+-20`` unit scales, but the coefficients of a level law in the pressures
    (``1/Pa``, ``1/Pa^2``) only ``+-2``: across the record's pressure span the
    law may change the friction level by twice its mid value, no more (a
    box twenty times wider let a refit wander where the law turns the level
    negative at a pressure of the record). ``F``, ``V`` are the force and speed
    scales.
    """
    u = spec.unit
    s = unit_scale(u, sc, d_pre)
    lo_s, hi_s = spec.lower, spec.upper
    if spec.lower >= 0:
        box = {
            "N": (0.0, 20.0 * s),
            "Ns/m": (0.0, 50.0 * s),
            "N/m": (sc.force / min(0.5 * sc.stroke, PRESLIDING_SPAN * max(d_pre, sc.resolution)),
                    sc.force / (0.2 * sc.resolution)),
            "m/s": (1e-4 * sc.speed, 100.0 * sc.speed),
            "m": (0.2 * sc.resolution, sc.stroke),
            "s": (0.5 * sc.dt, 10.0 * sc.duration),
            "kg": (0.0, 20.0 * s),
        }.get(u, (lo_s, hi_s))
        lo = max(lo_s, box[0])
        hi = min(hi_s, box[1])
        if spec.lower_open and lo <= spec.lower:
            lo = spec.lower + (1e-3 if u == "-" else 1e-9 * s)
    else:
        k = LEVEL_LAW_SPAN if u in ("1/Pa", "1/Pa^2") else 20.0
        lo, hi = max(lo_s, -k * s), min(hi_s, k * s)
    if spec.name == "n":
        lo = max(lo, 0.2)
        hi = min(hi, 6.0)
    if spec.name == "sigma1":  # dissipative bristle over the record's speeds
        hi = min(hi, 4.0 * sc.force / sc.speed)
    return float(lo), float(hi)



def sample_weights(spread: np.ndarray, noise: float) -> np.ndarray:
    """``w = 1/(1 + (spread/(2*noise))^2)``: how much a sample can tell, given the width
    ``spread`` (N) of the band the model's prediction could take there and the noise floor
    (:meth:`Refit.set_weights`)."""
    ratio = np.minimum(np.asarray(spread) / (2.0 * max(noise, 1e-300)), 1e100)
    return 1.0 / (1.0 + ratio**2)


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
        (:func:`tolerant_residual`): the uncertainty of its prediction that the
        measured motion leaves.
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


#: Largest timing tolerance (s) of :func:`tolerant_residual`.
MAX_TIMING = 0.02


def timing_windows(v: np.ndarray, dt: float, resolution: float) -> np.ndarray:
    """Timing uncertainty of every sample, in samples: ``w_k = ceil(q/(|v_k|*dt))``, 1 to 20 ms.

    The time the piston needs to move one position resolution ``q`` at its
    speed there: an event placed by the position -- a start, a stop, a
    reversal -- is known only to within that time. At speed it is one sample;
    near a turning point of a slow motion, or at rest, it reaches
    :data:`MAX_TIMING`.
    """
    w_max = max(1, int(round(MAX_TIMING / dt)))
    speed = np.abs(v)
    with np.errstate(divide="ignore"):
        w = np.where(speed > 0, np.ceil(resolution / (np.maximum(speed, 1e-300) * dt)), w_max)
    return np.clip(w, 1, w_max).astype(int)


def tolerant_residual(y: np.ndarray, lo: np.ndarray, hi: np.ndarray, starts: Sequence[int],
                      windows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The distance of ``y`` from what the model could be expected to predict there (N).

    The model runs along a motion reconstructed from sampled, quantised
    positions, so what it predicts at a sample is known only within

    * the range ``[lo, hi]`` of its predictions along motions as consistent
      with the measured position as the one used
      (:func:`fcomp.conditioning.motion_ensemble`: a creep within an encoder
      step, the turning point of a slow loop), and
    * the time the piston takes to move one position resolution
      (:func:`timing_windows`, ``w_k`` samples): an event -- a start, a stop, a
      velocity reversal where a friction law jumps by its whole level -- is
      placed only to within that time,

    so the range is widened to the lowest and highest value within ``w_k``
    samples (in the experiment; ``starts`` are its first samples). The residual
    is ``y`` minus its projection onto that band. Where the motion is well
    measured and the prediction smooth the band is narrower than the noise and
    this is the plain residual; a structure the model predicts nowhere near
    is never hidden. Returns the residual and the band's width (N).
    """
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    n = lo.size
    w = np.ones(n, dtype=int) if windows is None else windows
    bounds = [*sorted(set(starts) | {0}), n]
    low = lo.copy()
    high = hi.copy()
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        ws = w[a:b]
        for k in np.unique(ws):
            sel = ws == k
            size = 2 * int(k) + 1
            low[a:b][sel] = minimum_filter1d(lo[a:b], size, mode="nearest")[sel]
            high[a:b][sel] = maximum_filter1d(hi[a:b], size, mode="nearest")[sel]
    return y - np.clip(y, low, high), high - low


def fixed_names(model: FrictionModel) -> set[str]:
    """Flat names never fitted: numerical thresholds, references, effects' ``fixed`` lists."""
    out = {n for n in model.flat_params() if base_name(n) in ALWAYS_FIXED}
    for e in model.effects:
        out |= {n for n in e.params.flat() if base_name(n) in getattr(e, "fixed", ())}
    return out


def _block_mean(arr: np.ndarray, q: int) -> np.ndarray:
    m = arr.size // q
    head = arr[: m * q].reshape(m, q).mean(axis=1)
    return np.concatenate([head, [arr[m * q:].mean()]]) if arr.size % q else head


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
    """

    def __init__(self, data: DiagnosisData, split: Split, d_pre: float, *,
                 max_nfev: int = 60, max_samples: int = 40_000) -> None:
        self.data = data
        self.split = split
        self.d_pre = d_pre
        self.max_nfev = max_nfev
        self.q = max(1, math.ceil(data.n / max_samples))
        self.windows = timing_windows(data.signal("v"), data.scales.dt, data.scales.resolution)
        #: :data:`RIG_EXTRAS` estimated once and held from then on (:meth:`hold`)
        self.held: dict[str, float] = {}
        self._build_records()

    def _build_records(self) -> None:
        self._records = self._fit_records(self.q)
        self._by_q: dict[int, list[tuple[FitData, np.ndarray]]] = {self.q: self._records}
        self._probe_records = self._coarse(PROBE_SAMPLES)
        self._candidate_records = self._coarse(CANDIDATE_SAMPLES)
        self._record_weights: dict[int, list[np.ndarray | None]] = {}

    def __getstate__(self) -> dict[str, Any]:
        """A lean copy for another process: the records and their weights are rebuilt there."""
        drop = {"_records", "_by_q", "_probe_records", "_candidate_records", "_record_weights"}
        return {k: v for k, v in self.__dict__.items() if k not in drop}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._build_records()

    def _coarse(self, samples: int) -> list[tuple[FitData, np.ndarray]]:
        """The fit records averaged over blocks so that at most ``samples`` remain (cached)."""
        q = max(self.q, math.ceil(self.data.n / samples))
        if q not in self._by_q:
            self._by_q[q] = self._fit_records(q)
        return self._by_q[q]

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

    def refit_held(self, name: str, fit: FitResult) -> float:
        """Estimate the held extra ``name`` again for ``fit``'s model, and hold the new value.

        A lag held from the first fit carries that model's error: a baseline
        missing an effect that acts where the force changes fast (pre-sliding
        memory) took a 1.7 ms lag to 3.5 ms. When the model changes, the extra is
        refitted alone, unweighted, with every other value of ``fit`` fixed (the
        other extras held meanwhile). Returns the new value.
        """
        saved_held, saved_weights = dict(self.held), getattr(self, "_weights", None)
        self.held = {k: float(v) for k, v in fit.values.items() if k in RIG_EXTRAS and k != name}
        self._weights = None
        self._build_records()
        try:
            value = self.fit(fit.model, [{name: saved_held.get(name, 0.0)}],
                             [name]).values[name]
        finally:
            self.held, self._weights = saved_held, saved_weights
        self.hold(name, value)
        return float(value)

    def rescore(self, fit: FitResult) -> FitResult:
        """``fit`` scored again with the extras now held (:meth:`hold`)."""
        values = {k: v for k, v in fit.values.items() if k not in self.held}
        return self.result(fit.model, values, fit.n_params, fit.converged, fit.nfev)

    def set_weights(self, spread: np.ndarray, noise: float) -> None:
        """Weigh each sample by how well the measured motion fixes the prediction there.

        ``w = 1/(1 + (spread/(2*noise))^2)`` with ``spread`` the width of the band
        the current model could be expected to predict (:attr:`FitResult.spread`):
        where a friction law jumps by its whole level within the timing
        uncertainty of an event, or differs along motions as consistent with
        the position, a sample says little about the parameters and would
        otherwise dominate the squares (a static law's 500 N step one sample
        early). Fits after this weigh their residuals by ``sqrt(w)``.
        """
        self._weights = sample_weights(spread, noise)
        self._record_weights = {}

    def _weights_of(self, records: list[tuple[FitData, np.ndarray]]
                    ) -> list[np.ndarray | None]:
        """The square roots of the weights of ``records``' training samples (None: unweighted)."""
        w = getattr(self, "_weights", None)
        if w is None:
            return [None] * len(records)
        key = id(records)
        if key not in self._record_weights:
            q = next(k for k, v in self._by_q.items() if v is records)
            out: list[np.ndarray | None] = []
            for e in self.data.experiments:
                train = self.split.train[e.start:e.stop]
                if not train.any():
                    continue
                we = w[e.start:e.stop]
                if q > 1:
                    we = _block_mean(we, q)
                    train = _block_mean(train.astype(float), q) > 0.999
                out.append(np.sqrt(we[train]))
            self._record_weights[key] = out
        return self._record_weights[key]

    def _fit_records(self, q: int) -> list[tuple[FitData, np.ndarray]]:
        """Per experiment with training samples: the data averaged over blocks of ``q``
        samples, and the training mask."""
        out = []
        for e in self.data.experiments:
            train = self.split.train[e.start:e.stop]
            if not train.any():
                continue
            d = e.data
            for name, value in self.held.items():  # the held terms moved to the target
                d = d.holding(name, value)
            if q > 1:
                sig = {k: _block_mean(v, q) for k, v in d.sig.items() if k != "s"}
                from fcomp.models.base import side_of

                sig["s"] = side_of(sig["v"])
                inertia = None if d.inertia is None else _block_mean(d.inertia, q)
                rate = None if d.drive_rate is None else _block_mean(d.drive_rate, q)
                d = FitData(sig, _block_mean(d.y, q), inertia, d.source, d.mass, d.label,
                            d.band_hz, rate)
                train = _block_mean(train.astype(float), q) > 0.999
            out.append((d, train))
        return out

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

        The residual is the tolerant one (:func:`tolerant_residual`): the
        prediction's range along the record's alternative motions, widened by
        the timing windows.
        """
        values = {**values, **self.held}
        model_vals = {k: v for k, v in values.items() if k not in RIG_EXTRAS}
        fitted = model.with_params(**model_vals) if model_vals else model
        extras = {k: values[k] for k in RIG_EXTRAS if k in values}
        F_hat, lo, hi = self._predictions(fitted, extras, alternatives=True)
        r, spread = tolerant_residual(self.data.y, lo, hi,
                                      [e.start for e in self.data.experiments], self.windows)
        tr, te = self.split.train, self.split.test
        return FitResult(fitted, dict(values), F_hat, r, _rms(r[tr]), _rms(r[te]), n_params,
                         converged, nfev, spread)

    # ---------------------------------------------------------------- fit
    def free_names(self, model: FrictionModel) -> list[str]:
        fixed = fixed_names(model)
        names = [n for n in default_free(model) if n not in fixed]
        if self.data.fits_mass:
            names.append("mass")
        if self.data.fits_lag:
            names.append("lag")
        return [n for n in names if n not in self.held]

    def specs(self, model: FrictionModel, names: Sequence[str]) -> dict[str, ParamSpec]:
        """Specs of ``names`` with the data-derived bounds of :func:`data_bounds`."""
        all_specs = dict(model.param_specs())
        all_specs.update(EXTRA_SPECS)
        out = {}
        for n in names:
            sp = all_specs[n]
            lo, hi = data_bounds(sp, self.data.scales, self.d_pre)
            out[n] = dataclasses.replace(sp, lower=lo, upper=hi, lower_open=False)
        return out

    def scales(self, model: FrictionModel, names: Sequence[str], start: Mapping[str, float]
               ) -> dict[str, float]:
        """Typical magnitudes (solver ``x_scale``): ``|start|``, at least 1 % of the unit scale."""
        specs = dict(model.param_specs())
        specs.update(EXTRA_SPECS)
        out = {}
        for n in names:
            v = abs(float(start[n]))
            floor = self.data.scales.dt if n == "lag" else \
                0.01 * unit_scale(specs[n].unit, self.data.scales, self.d_pre)
            out[n] = max(v, floor) if math.isfinite(v) else 10.0 * floor
        return out

    def train_cost(self, model: FrictionModel, values: Mapping[str, float]) -> float:
        """Sum of squared residuals over the training samples of the probe records (N^2).

        The measure the probes of :meth:`fit` minimise (plain residuals on the
        block-averaged records), so a candidate's probes can be compared with it.
        """
        vals = {k: v for k, v in values.items() if k not in RIG_EXTRAS}
        rig = {k: values[k] for k in RIG_EXTRAS if k in values and k not in self.held}
        total = 0.0
        recs = self._probe_records
        weights = self._weights_of(recs)
        for (d, m), w in zip(recs, weights, strict=True):
            r = (d.y - self._predict_one(model, d, vals, rig, d.sig))[m]
            if w is not None:
                r = r * w
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
        Returns the :class:`FitResult`, scored on the full record.
        """
        max_nfev = max_nfev or self.max_nfev
        names = [n for n in free if n not in self.held] if free is not None else \
            self.free_names(model)
        if not names:
            return self.result(model, {}, 0)
        # a model parameter named like an identification extra ("offset" of the
        # force-offset effect) is fitted as that extra: the model's own copy is zero
        clash = {n: 0.0 for n in names if n in EXTRAS and n in model.flat_params()}
        if clash:
            model = model.with_params(**clash)
        base = dict(model.flat_params())
        for extra in RIG_EXTRAS:
            if extra in names:
                base[extra] = 0.0
        start_list = [dict(base, **s) for s in starts] or [base]
        specs = self.specs(model, names)
        # stage 1: shape exponents held at their start values (they open flat
        # valleys, e.g. n < 1 with a large viscous term, when few speeds are seen)
        first = [n for n in names if base_name(n) not in STAGED] or names
        several = len(start_list) > 1
        budget = min(PROBE_NFEV, max_nfev) if several else max_nfev
        main = self._candidate_records if fast else self._records
        probe = self._probe_records if several else main
        cost, sol, st, nfev = best_start(
            start_list, lambda st: self._solve(model, self._pv(model, first, st, specs), budget,
                                               records=probe), model.describe())
        st = dict(st, **dict(zip(first, map(float, sol.theta), strict=True)))
        if reference is not None and several and cost > (1.0 - MIN_GAIN) * reference:
            values = {n: float(st[n]) for n in names}
            return self.result(model, values, len(names), False, nfev)
        if len(start_list) > 1:
            sol, k = self._solve(model, self._pv(model, first, st, specs), max_nfev,
                                 records=main)
            nfev += k
            st = dict(st, **dict(zip(first, map(float, sol.theta), strict=True)))
        if first != names:  # stage 2: everything free
            sol, k = self._solve(model, self._pv(model, names, st, specs), max_nfev,
                                 records=main)
            nfev += k
        values = dict(zip(names, map(float, sol.theta), strict=True))
        return self.result(model, values, len(names), sol.converged, nfev)

    def plausibility(self, fit: FitResult, context: RigContext | None = None
                     ) -> list[FitWarning]:
        """The plausibility warnings of ``fit`` (:func:`fcomp.identification.plausibility.check_fit`).

        Standard errors, intervals and correlations from the Jacobian at the
        estimate over the training samples (batch-means HAC,
        :func:`fcomp.identification.uncertainty.estimate`); bounds are the
        data boxes the fit searched (:func:`data_bounds`).
        """
        names = [n for n in fit.values if n not in self.held]
        if not names:
            return []
        base = fit.model
        specs = self.specs(base, names)
        pv = self._pv(base, names, fit.values, specs)
        problems = [TrajectoryProblem(base, d, pv, mask=m) for d, m in self._records]
        weights = self._weights_of(self._records)
        theta = np.array([fit.values[n] for n in names])
        rs, Gs = [], []
        for p, w in zip(problems, weights, strict=True):
            r, G = p(theta, True)
            assert G is not None
            if w is not None:  # as the fit weighed them
                r, G = r * w, G * w[:, None]
            rs.append(r)
            Gs.append(G)
        unc = estimate(np.vstack(Gs), np.concatenate(rs), theta)
        stderr = dict(zip(names, map(float, unc.stderr), strict=True))
        ci = {n: (float(lo), float(hi))
              for n, lo, hi in zip(names, unc.ci_low, unc.ci_high, strict=True)}
        bounds = {n: (specs[n].lower, specs[n].upper) for n in names}
        units = {n: specs[n].unit for n in names}
        return check_fit(fit.values, stderr, ci, bounds, correlations(names, unc.cov),
                         fit.converged, context, units=units)

    def _pv(self, model: FrictionModel, names: Sequence[str], start: Mapping[str, float],
            specs: Mapping[str, ParamSpec]) -> ParameterVector:
        return ParameterVector.build(list(names), start, {n: specs[n] for n in names},
                                     self.scales(model, names, start))

    def _solve(self, model: FrictionModel, pv: ParameterVector, budget: int, *,
               records: list[tuple[FitData, np.ndarray]] | None = None):
        recs = self._records if records is None else records
        problems = [TrajectoryProblem(model, d, pv, mask=m) for d, m in recs]
        weights = self._weights_of(recs)

        def fun(theta: np.ndarray, need_jac: bool = True
                ) -> tuple[np.ndarray, np.ndarray | None]:
            rs: list[np.ndarray] = []
            Gs: list[np.ndarray] = []
            for p, w in zip(problems, weights, strict=True):
                r, G = p(theta, need_jac)
                if w is not None:
                    r = r * w
                    G = None if G is None else G * w[:, None]
                rs.append(r)
                if G is not None:
                    Gs.append(G)
            if len(Gs) < len(problems):
                return np.concatenate(rs), None
            return np.concatenate(rs), np.vstack(Gs)

        sol = solve(pv, fun, max_nfev=budget, what=f"fit of {model.describe()}")
        return sol, sum(p.evaluations for p in problems) // max(len(problems), 1)


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r**2))) if r.size else math.nan
