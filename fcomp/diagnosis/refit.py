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
from functools import lru_cache
from typing import Any

import numpy as np
from scipy.integrate import trapezoid
from scipy.special import log_ndtr

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
#: A fit pinned at a data-box edge is retried with that edge this many times farther out
#: (:meth:`Refit.widen`) ...
WIDEN_FACTOR = 10.0
#: ... at most this many times per parameter and side.
WIDEN_TRIES = 2
#: Units whose data boxes come from the record's scale alone, and widen.
WIDENED_UNITS = ("N", "Ns/m", "N/m", "m/s", "m", "s", "kg")
#: Parameters whose box is a physical rule (a Stribeck exponent's range, a passive bristle
#: damping): never widened.
UNWIDENED = ("n", "sigma1", "lag")
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
        "m^2": sc.force / max(sc.p_span, abs(sc.p_mid), 1.0),
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
    tolerant : (N,) N or None
        The tolerant residual (:func:`tolerant_residual`): the distance of the
        measurement from that band. It shows *where* structure is left (the
        verdict's features, the effects' guesses) but never decides: a wider band
        would lower it.
    plain : (N,) N or None
        ``y - F_hat``, the plain residual (reported beside the deciding one).
    boxes : dict or None
        The boxes of parameters widened beyond their data box (:meth:`Refit.widen`).
    timing_spread : (N,) N or None
        Width of the band from the timing windows alone (the prediction along the
        measured motion, widened by :func:`timing_windows`): the part of ``spread``
        no choice of the model's makes wider (:func:`score_noise_share`).

    Notes
    -----
    ``residual`` -- and so ``rms_train``/``rms_test`` -- is the *scored*
    residual (:func:`scored_residual`): the logarithmic score of the prediction
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

    @property
    def located(self) -> np.ndarray:
        """The residual that *locates* structure: the tolerant one where there is one."""
        return self.tolerant if self.tolerant is not None else self.residual

    @property
    def plain_residual(self) -> np.ndarray:
        """``y - F_hat`` (the scored residual where a result carries no plain one)."""
        return self.plain if self.plain is not None else self.residual


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


def prediction_band(lo: np.ndarray, hi: np.ndarray, starts: Sequence[int],
                    windows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The band ``[low, high]`` (N) the model could be expected to predict at each sample.

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
    samples (in the experiment; ``starts`` are its first samples).
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
    return low, high


def tolerant_residual(y: np.ndarray, lo: np.ndarray, hi: np.ndarray, starts: Sequence[int],
                      windows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The distance of ``y`` from the band the model could be expected to predict (N).

    ``y`` minus its projection onto :func:`prediction_band`. Where the motion is
    well measured and the prediction smooth the band is narrower than the noise
    and this is the plain residual. It locates structure a model could place
    (the verdict's features) but it is *not* an error measure to rank models
    by: a wider band lowers it (a mass relabelled as a lead term, whose band
    along the motion ensemble is 27 N wide, scored 0.33 N against a plain
    4.1 N). :func:`scored_residual` is. Returns the residual and the band's width (N).
    """
    low, high = prediction_band(lo, hi, starts, windows)
    return y - np.clip(y, low, high), high - low


#: Log of the peak density of a unit normal, ``ln(1/sqrt(2*pi))``.
_LOG_PEAK = -0.5 * math.log(2.0 * math.pi)


def scored_residual(y: np.ndarray, F_hat: np.ndarray, low: np.ndarray, high: np.ndarray,
                    sigma: float) -> np.ndarray:
    """The logarithmic score of the prediction band, as a residual in newtons.

    The model predicts "somewhere in ``[low, high]``" (:func:`prediction_band`)
    and the measurement adds noise of standard deviation ``sigma`` (the noise
    floor), so its predictive density of ``y`` is the uniform band convolved
    with that noise,

    ``p(y) = [Phi((high - y)/sigma) - Phi((low - y)/sigma)] / (high - low)``

    (the normal density ``phi((y - F_hat)/sigma)/sigma`` for a point band). The
    logarithmic score ``-ln p(y)`` is a *strictly proper* scoring rule
    (Gneiting & Raftery 2007, J. Am. Stat. Assoc. 102:359, sect. 4.1): a
    forecaster cannot improve its expected score by widening or shifting its
    band away from what it believes. Expressed against the best possible score,
    that of a point prediction hitting ``y`` (``p = 1/(sigma*sqrt(2*pi))``),

    ``e^2 = -2*sigma^2*ln(p(y)*sigma*sqrt(2*pi))  >= 0``,

    ``e = sign(y - F_hat)*sqrt(e^2)`` is the plain residual ``y - F_hat`` where
    the band is a point, and a band of width ``W`` around the measurement costs
    ``e^2 ~ 2*sigma^2*ln(W/(sigma*sqrt(2*pi)))``: a static law's 40 N jump placed
    within its timing window costs about three noise floors instead of 40 N,
    while a 27 N band where a point prediction would do costs what it is. The
    RMS of ``e`` is the diagnosis's deciding error; its mean square is twice
    ``sigma^2`` times the mean log-score excess, so comparing two models' RMS
    compares their mean log scores.
    """
    y = np.asarray(y, dtype=float)
    s = max(float(sigma), 1e-300)
    width = high - low
    a = (high - y) / s
    b = (low - y) / s  # a >= b
    # Phi(a) - Phi(b) in the tail where it is accurate: Phi(-b) - Phi(-a) above the centre
    flip = a + b > 0
    upper, lower = np.where(flip, -b, a), np.where(flip, -a, b)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lu, ll = log_ndtr(upper), log_ndtr(lower)
        log_mass = lu + np.log1p(-np.exp(np.minimum(ll - lu, 0.0)))
        e2 = -2.0 * (log_mass - np.log(width / s) - _LOG_PEAK)
    narrow = ~(width > 1e-6 * s) | ~np.isfinite(e2)
    if narrow.any():  # a point band (or a mass lost to rounding): the normal density
        centre = 0.5 * (low + high)
        e2 = np.where(narrow, ((y - np.where(width > 1e-6 * s, np.clip(y, low, high), centre))
                               / s) ** 2, e2)
    sign = np.where(y >= F_hat, 1.0, -1.0)
    return sign * s * np.sqrt(np.maximum(e2, 0.0))


@lru_cache(maxsize=1)
def _score_share_table() -> tuple[np.ndarray, np.ndarray]:
    """``(k, g(k))`` on a log grid: :func:`score_noise_share` of one band, by quadrature."""
    ks = np.concatenate([[0.0], np.geomspace(1e-2, 1e5, 141)])
    gs = np.ones(ks.size)
    for i, k in enumerate(ks[1:], start=1):
        y = np.linspace(-0.5 * k - 12.0, 0.5 * k + 12.0, 20_001)
        lo, hi = np.full(y.size, -0.5 * k), np.full(y.size, 0.5 * k)
        e2 = scored_residual(y, np.zeros(y.size), lo, hi, 1.0) ** 2
        dens = np.exp(-0.5 * e2) / math.sqrt(2.0 * math.pi)  # p(y) itself, from e^2
        gs[i] = float(trapezoid(dens * e2, y) / trapezoid(dens, y))
    return ks, gs


def score_noise_share(width: np.ndarray, sigma: float) -> float:
    """Mean ``E[e^2]/sigma^2`` of the scored residual of a *right* model over bands ``width``.

    Where a model's prediction is known only within a band of width
    ``W = k*sigma`` (an event placed within its timing window), even the right
    model scores more than the noise: for the truth anywhere in the band
    (uniform) and normal noise, ``g(k) = E[e^2]/sigma^2`` is twice the
    differential entropy of the predictive density in units of ``sigma``, less
    ``ln(2*pi)`` (1 at ``k = 0``, ``2*ln(k) - ln(2*pi)`` for a wide band), computed
    once by quadrature on a grid of ``k`` and interpolated in ``ln k``. The verdict
    compares a final error with ``sigma*sqrt`` of this share over the *timing*
    band alone (:attr:`FitResult.timing_spread`), never over the band of the
    motions a model chose to depend on, so a wide band is never excused.
    """
    if width.size == 0 or not sigma > 0:
        return 1.0
    ks, gs = _score_share_table()
    k = np.clip(np.asarray(width, dtype=float) / sigma, 0.0, ks[-1])
    small = k < ks[1]
    g = np.interp(np.log(np.maximum(k, ks[1])), np.log(ks[1:]), gs[1:])
    g = np.where(small, 1.0 + (gs[1] - 1.0) * (k / ks[1]) ** 2, g)
    return float(np.mean(g))


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
    noise
        The record's noise floor (N, RMS): the measurement noise of the scored
        residual (:func:`scored_residual`). ``None`` scores the plain residual
        (each prediction taken as a point).
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
        self.windows = timing_windows(data.signal("v"), data.scales.dt, data.scales.resolution)
        #: :data:`RIG_EXTRAS` estimated once and held from then on (:meth:`hold`)
        self.held: dict[str, float] = {}
        #: data boxes widened because a fit was pinned at their edge (:meth:`widen`)
        self.wide: dict[str, tuple[float, float]] = {}
        self._widened: dict[tuple[str, int], int] = {}
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

        The residual that decides is the scored one (:func:`scored_residual`)
        of the prediction's band (:func:`prediction_band`: its range along the
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
                         {k: v for k, v in self.wide.items() if k in values} or None,
                         t_high - t_low)

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
        wide = getattr(self, "wide", {})
        for n in names:
            sp = all_specs[n]
            lo, hi = wide.get(n) or data_bounds(sp, self.data.scales, self.d_pre)
            out[n] = dataclasses.replace(sp, lower=lo, upper=hi, lower_open=False)
        return out

    def widen(self, model: FrictionModel, name: str, side: int) -> bool:
        """Widen the data box of ``name`` on ``side`` (-1 lower, +1 upper); False if it cannot.

        The data boxes (:func:`data_bounds`) come from the record's scales, and a
        scale is an estimate: a soft pneumatic seal's bristle (1.5e4 N/m) lay below
        a stiffness box set by a presliding length read off a record of small
        loops. A fit pinned at a data-box edge is therefore retried in a box
        :data:`WIDEN_FACTOR` times wider on that side (within the spec's own
        bounds), at most :data:`WIDEN_TRIES` times per parameter. Only the boxes
        of positive quantities set by the record's scale widen; the boxes that
        encode a physical rule (``n``, the passive ``sigma1``, the level laws'
        coefficients, a channel lag) do not. The widened box holds for every later
        fit of the record, so models stay compared on the same boxes.
        """
        specs = dict(model.param_specs())
        specs.update(EXTRA_SPECS)
        sp = specs.get(name)
        if sp is None or sp.lower < 0 or name in UNWIDENED or sp.unit not in WIDENED_UNITS:
            return False
        lo, hi = self.wide.get(name) or data_bounds(sp, self.data.scales, self.d_pre)
        count = self._widened.get((name, side), 0)
        if count >= WIDEN_TRIES:
            return False
        if side < 0:
            new_lo = max(sp.lower, lo / WIDEN_FACTOR) if lo > 0 else lo
            if not new_lo < lo:
                return False
            self.wide[name] = (new_lo, hi)
        else:
            new_hi = min(sp.upper, hi * WIDEN_FACTOR)
            if not new_hi > hi:
                return False
            self.wide[name] = (lo, new_hi)
        self._widened[(name, side)] = count + 1
        return True

    def box_state(self) -> tuple[dict[str, tuple[float, float]], dict[tuple[str, int], int]]:
        """The widened boxes and their counts (to restore with :meth:`set_box_state`)."""
        return dict(self.wide), dict(self._widened)

    def set_box_state(self, state: tuple[dict[str, tuple[float, float]],
                                         dict[tuple[str, int], int]]) -> None:
        self.wide, self._widened = dict(state[0]), dict(state[1])

    def adopt_boxes(self, fit: FitResult) -> None:
        """Take over the boxes a fit elsewhere (a worker process) widened."""
        for name, box in (fit.boxes or {}).items():
            lo, hi = self.wide.get(name, box)
            self.wide[name] = (min(lo, box[0]), max(hi, box[1]))

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

        def solve(st: dict[str, float], k: int) -> tuple[Any, int]:
            return self._solve(model, self._pv(model, first, st, specs), k, records=probe)

        def resume(st: dict[str, float], sol: Any) -> dict[str, float]:
            return dict(st, **dict(zip(first, map(float, sol.theta), strict=True)))

        cost, sol, st, nfev = best_start(start_list, solve, budget, model.describe(),
                                         resume=resume)
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
        # pinned at an edge of a box the record's scale set: try the wider box first
        while True:
            pinned = [(n, -1 if values[n] <= 0.5 * (specs[n].lower + specs[n].upper) else 1)
                      for n, at in zip(names, sol.at_bound, strict=True) if at]
            if not [self.widen(model, n, side) for n, side in pinned].count(True):
                break
            specs = self.specs(model, names)
            sol, k = self._solve(model, self._pv(model, names, values, specs), max_nfev,
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
        data boxes the fit searched (:func:`data_bounds`). The extras held from an
        earlier fit (:meth:`hold`, the channel ``lag``) are checked against their
        boxes too (:func:`fcomp.identification.plausibility.check_held`: at a bound,
        a negative lag), after the fitted parameters.
        """
        from fcomp.identification.plausibility import check_held

        held_names = [n for n in self.held if n in fit.values]
        held: list[FitWarning] = []
        if held_names:
            hs = self.specs(fit.model, held_names)
            held = check_held({n: float(fit.values[n]) for n in held_names},
                              {n: (hs[n].lower, hs[n].upper) for n in held_names},
                              units={n: hs[n].unit for n in held_names},
                              dt=self.q * self.data.scales.dt, context=context)
        names = [n for n in fit.values if n not in self.held]
        if not names:
            return held
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
                         fit.converged, context, units=units) + held

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
