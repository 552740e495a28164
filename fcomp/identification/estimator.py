"""The public estimator: :class:`FrictionFit` identifies any friction model from a measurement.

Procedure (docs/identification.md has the full account):

1. **Target.** The force to match and the motion (:mod:`.target`): a
   measured ``F``; or the friction reconstructed with the known mass; or,
   without a mass, the driving force with ``mass`` as a fitted parameter.
2. **Start.** Levels, mass and offset by linear least squares, the Stribeck
   hump and the bristle stiffness read off the data (:mod:`.guess`).
3. **Static stage** (seed 002's procedure, :mod:`.static`): the parameters
   the steady-state map depends on are fitted by weighted least squares to
   the binned steady-state force-velocity points. For static maps without a
   mass to estimate this *is* the fit (``method_ = "steady-state"``) when the
   record holds enough steady points; otherwise static maps are fitted to
   every moving sample (``"samples"``).
4. **Trajectory stage** (dynamic models, :mod:`.dynamic`): every free
   parameter (``sigma0``, ``sigma1``, film time constants, ``T`` with the
   static ones, plus ``mass``/``offset``) by minimising the force error of
   the model simulated along the measured motion, with the exact
   sensitivity Jacobian (finite differences for non-symbolic models).
5. **Uncertainty** (:mod:`.uncertainty`): standard errors from the
   autocorrelation-robust (batch-means) sandwich covariance, Student-t
   confidence intervals on the effective sample size. Parameters the data do
   not determine (zero sensitivity at the start; or, at the solution, a null
   direction, a negligible effect or a standard error above 1000 times the
   value) are held (at the start value, resp. the value reached) and listed
   in ``not_identifiable_``. A trajectory fit that stops without converging
   holds the parameters it barely determines where it stopped (standard error
   above :data:`HOLD_RELATIVE_ERROR` times the value) and refits the others.
6. **Plausibility** (:mod:`.plausibility`): values at a bound, intervals of
   positive quantities reaching zero, an implausible mass, parameters not
   determined or trading off, non-convergence: ``warnings_``.

Which stages run is the *strategy*'s business (:mod:`.strategies`: static
maps, models with continuous states, models with discrete memory), chosen
from the model's capabilities or given (``strategy=``); the stages are those
of the fitting engine (:mod:`.engine`), which runs every trajectory stage
through :mod:`.records` -- the entry point for fitting one parameter vector to
several records (:func:`~.records.fit_records`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from fcomp.errors import ConvergenceError, FcompError
from fcomp.identification.engine import (
    ALWAYS_FIXED,
    EXTRA_SPECS,
    HOLD_RELATIVE_ERROR,
    METHODS,
    SEGMENT_NAMES,
    FitJob,
    FitOutcome,
    FitSettings,
    default_free,
    equality_constraints,
)
from fcomp.identification.plausibility import FitWarning, RigContext, check_fit, correlations
from fcomp.identification.strategies import HYSTERESIS_REFINE_NFEV, FitStrategy, strategy_for
from fcomp.identification.target import CUTOFF_HZ, FitData, fit_data
from fcomp.measurement import Measurement
from fcomp.modelfile import split_measurement
from fcomp.models import FrictionModel, make_model
from fcomp.parameters import Directional
from fcomp.trajectory import friction_along_motion

__all__ = ["ALWAYS_FIXED", "EXTRA_SPECS", "HOLD_RELATIVE_ERROR", "HYSTERESIS_REFINE_NFEV",
           "MEASURED", "METHODS", "SEGMENT_NAMES", "FrictionFit", "default_free",
           "directional_model", "equality_constraints", "model_rms", "predicted"]


#: What :func:`model_rms` measures, in words.
MEASURED = ("the model's RMS error on the whole record (measured force minus the model run "
            "along the measured motion, with the record's fitted mass, offset; as fcomp fit "
            "and fcomp compare print it)")


def model_rms(model: FrictionModel, data: Measurement | Sequence[Measurement], *,
              cutoff_hz: float = CUTOFF_HZ, substeps: int = 1) -> float:
    """The one RMS error (N) of a model on a record, as ``fcomp fit`` and ``fcomp compare``
    print it.

    The model runs along the record's measured motion (:func:`~.target.fit_data`: ``v``
    and ``a`` from their columns, else from ``x`` by the zero-phase filter at
    ``cutoff_hz``, a driving force through the same filter) and its force, with the
    model's measurement terms put back (:attr:`~fcomp.models.base.FrictionModel.measurement`:
    a fitted ``offset``, and ``mass`` times the acceleration where the record gives a
    driving force and no ``rig.mass``), is compared with the measured (or
    reconstructed) force at every sample; several records are pooled.

    Raises
    ------
    FcompError
        For a record with a driving force and no ``rig.mass`` when the model carries
        no mass, or a record a fit could not read.
    """
    records = [data] if isinstance(data, Measurement) else list(data)
    squares, n = 0.0, 0
    for meas in records:
        d = fit_data(meas, cutoff_hz=cutoff_hz)
        squares += float(np.sum((d.y - predicted(model, d, substeps)) ** 2))
        n += d.n
    return math.sqrt(squares / n) if n else math.nan


def predicted(model: FrictionModel, d: FitData, substeps: int = 1) -> np.ndarray:
    """The force (N) ``model`` predicts for the target of ``d``: its friction run along the
    motion, with its measurement terms (:attr:`~fcomp.models.base.FrictionModel.measurement`)
    put back: the ``offset``, and ``mass`` times the inertia column where ``d`` has one
    (a driving force, no known mass).

    Raises
    ------
    FcompError
        Where ``d`` needs a mass and the model carries none.
    """
    friction, record = split_measurement(model)
    s = d.sig
    F = friction_along_motion(friction, s["t"], s["v"], a=s["a"], x=s["x"], p1=s["p1"],
                              p2=s["p2"], substeps=substeps).F
    if d.inertia is None:
        return F
    if "mass" not in record:
        raise FcompError(f"{d.label}: the record gives a driving force and no rig.mass: the "
                         "model carries no fitted mass to compare with")
    return F + record["mass"] * d.inertia


def directional_model(model: FrictionModel) -> FrictionModel:
    """``model`` with every direction-capable parameter split into ``_pos``/``_neg`` values."""
    params = model.params
    flat: dict[str, float] = {}
    for s in type(params).SPECS:
        raw = getattr(params, s.name)
        if s.directional and not isinstance(raw, Directional):
            flat[s.name + "_pos"] = flat[s.name + "_neg"] = float(raw)
    if not flat:
        return model
    return model._rebuild(type(params).from_flat(flat, base=params), model.effects)


class FrictionFit:
    """Identify a friction model from a measurement, with standard errors (sklearn style).

    Parameters
    ----------
    model
        Model name (``coulomb`` ... ``nmlgm``, ``gms``, ...) or a
        :class:`~fcomp.models.base.FrictionModel` (its values are the start of
        the parameters not read off the data, and the values of the fixed ones).
    offset
        Fit a constant force offset ``offset`` (N).
    estimate_mass
        ``None``: estimate ``mass`` (kg) exactly when the data hold a driving
        force (``F_ext``, pressures) but no ``F`` column and no mass is known;
        ``True``/``False`` force or forbid it.
    mass
        Known moving mass (kg), overriding the sidecar's ``rig.mass``.
    free
        Flat names to fit (default :func:`default_free`).
    fixed
        Flat name -> value to hold fixed (removed from the free set).
    directional
        Fit separate ``v > 0`` / ``v < 0`` values of every direction-capable
        parameter (``Fc``, ``Fs``, ``vs``, ``n``, ``sigma2``/``B``, ``vb``).
    initial
        Flat name -> start value, overriding the data-based start.
    method
        ``"auto"`` (see the module docstring), ``"steady-state"`` (static maps
        on the steady-state characteristic only), ``"samples"`` (static maps
        on every moving sample) or ``"trajectory"`` (dynamic models without
        the static stage).
    v_min
        Speed (m/s) below which samples count as at rest for the static
        parts (default :func:`~fcomp.identification.guess.default_v_min`).
    min_duration
        Shortest steady run (s) for the steady-state points.
    cutoff_hz
        Cut-off (Hz) of the zero-phase filter deriving ``v``, ``a`` from ``x``
        when the data hold no ``v``/``a`` columns (the driving force is
        filtered alike, :mod:`.target`).
    substeps
        Integration steps per sample interval in the trajectory stage.
    max_nfev
        Evaluation budget of each least-squares stage.
    confidence
        Level of the confidence intervals ``ci_``.
    refine_hysteresis
        For models with seed 000's hysteresis function: refine the segment
        parameters ``c_i, k_i`` found from the transition curves by a
        trajectory fit of the full model (finite differences: one simulation
        per parameter and iteration, ~10 us per sample).
    strict
        Raise :class:`~fcomp.errors.ConvergenceError` when the fit does not
        converge (after setting the result attributes).
    strategy
        The :class:`~.strategies.FitStrategy` (default: the one the model's
        capabilities call for, :func:`~.strategies.strategy_for`).

    Attributes
    ----------
    params_, stderr_ : dict
        Estimates and standard errors by flat name (``mass``/``offset`` included).
    ci_ : dict
        Name -> ``(low, high)`` confidence interval at ``confidence``.
    cov_ : ndarray
        Covariance of the estimates, in the order of ``param_names_``.
    units_ : dict
        SI unit of each estimate.
    rms_ : float
        The fitted model's RMS error (N) on the record: the one RMS of a model on a
        record (:func:`model_rms`) that ``fcomp compare`` prints too, so
        ``fcomp.compare(fit.model_, record).rms == fit.rms_``. For a trajectory fit it
        is the residual the fit minimised.
    rms_fit_ : float
        RMS of the least-squares residual (N) the fit minimised, over the samples it
        fitted (the steady-state points of a ``"steady-state"`` fit, the moving samples
        of a ``"samples"`` one).
    rms_measured_ : str
        How ``rms_`` was measured (in words).
    converged_ : bool
    message_ : str
    model_ : FrictionModel
        The model with the fitted values, carrying the terms of the record the fit
        estimated beside the friction (``model_.measurement``: ``mass``, ``offset``,
        ``lag``), so that ``fcomp.compare(fit.model_, record)`` compares it as fitted.
    fixed_ : dict
        Model parameters held fixed, with their values.
    not_identifiable_ : list
        Parameters the data did not determine (held, not reported in ``params_``).
    method_ : str
        ``"steady-state"``, ``"samples"`` or ``"trajectory"``.
    n_samples_, n_eff_, tau_int_ :
        Samples in the residual, effective sample size, residual
        autocorrelation time (samples).
    stages_ : list of dict
        One entry per least-squares stage (name, parameters, rms, evaluations, converged).
    target_ : str
        Where the fitted force came from (``"F"``, ``"reconstructed"``, ``"driving-force"``).
    bounds_ : dict
        Name -> ``(lower, upper)``, the box each estimate was searched in.
    context_ : RigContext
        The rig the record's sidecar describes (kind, known mass, geometry).
    warnings_ : list of FitWarning
        Plausibility warnings of the estimates (:func:`.plausibility.check_fit`):
        ``at-bound``, ``interval-crosses-zero``, ``mass-implausible``,
        ``not-identified``, ``not-converged``; empty when none.
    """

    def __init__(
        self,
        model: str | FrictionModel,
        *,
        offset: bool = False,
        estimate_mass: bool | None = None,
        mass: float | None = None,
        free: Sequence[str] | None = None,
        fixed: Mapping[str, float] | None = None,
        directional: bool = False,
        initial: Mapping[str, float] | None = None,
        method: str = "auto",
        v_min: float | None = None,
        min_duration: float = 0.05,
        cutoff_hz: float = CUTOFF_HZ,
        substeps: int = 1,
        max_nfev: int = 200,
        confidence: float = 0.95,
        refine_hysteresis: bool = True,
        strict: bool = True,
        strategy: FitStrategy | None = None,
    ) -> None:
        self.model = model
        self.offset = offset
        self.estimate_mass = estimate_mass
        self.mass = mass
        self.free = free
        self.fixed = fixed
        self.directional = directional
        self.initial = initial
        self.method = method
        self.v_min = v_min
        self.min_duration = min_duration
        self.cutoff_hz = cutoff_hz
        self.substeps = substeps
        self.max_nfev = max_nfev
        self.confidence = confidence
        self.refine_hysteresis = refine_hysteresis
        self.strict = strict
        self.strategy = strategy

    # ---------------------------------------------------------------- setup
    def _base_model(self) -> FrictionModel:
        model = make_model(self.model) if isinstance(self.model, str) else self.model
        if not isinstance(model, FrictionModel):
            raise FcompError(f"model must be a name or a FrictionModel, got {self.model!r}")
        if self.directional:
            model = directional_model(model)
        if self.fixed:
            model = model.with_params(**{k: float(v) for k, v in self.fixed.items()})
        return model

    # ------------------------------------------------------------------ fit
    def fit(self, data: Measurement) -> FrictionFit:
        """Identify the model from ``data``; returns ``self`` with the ``*_`` attributes set.

        Raises
        ------
        ConvergenceError
            With ``strict``, when the fit does not converge (after setting the
            attributes, ``warnings_`` included).
        """
        self._failure = ""
        self.data_ = data
        self._fit(data)
        try:
            self.rms_, self.rms_measured_ = self.score(data), MEASURED
        except (FcompError, ValueError) as exc:  # a record the model cannot run along
            self.rms_ = self.rms_fit_
            self.rms_measured_ = (f"the least-squares residual of the fit ({MEASURED} "
                                  f"fails: {str(exc).splitlines()[0]})")
        self.context_ = RigContext.from_meta(data.meta, mass=self.mass)
        self.warnings_ = self.plausibility()
        if not self.converged_ and self.strict:
            raise ConvergenceError(self._failure)
        return self

    def plausibility(self, context: RigContext | None = None) -> list[FitWarning]:
        """The plausibility warnings of the fitted values (:func:`.plausibility.check_fit`)
        for the rig ``context`` (default: the record's, ``context_``)."""
        held = self.held_
        return check_fit(
            {**self.params_, **held},
            {**self.stderr_, **dict.fromkeys(held, math.inf)},
            self.ci_, self.bounds_,
            correlations(self.param_names_, self.cov_), self.converged_,
            context or self.context_,
            units={n: self.unit(n) for n in (*self.params_, *held)},
            confidence=self.confidence, message=self.message_)

    @property
    def held_(self) -> dict[str, float]:
        """The parameters the record did not determine (``not_identifiable_``) with the
        values they were held at."""
        self._check_fitted()
        known = {**self._extras, **self.fixed_}
        return {n: known[n] for n in self.not_identifiable_ if n in known}

    def unit(self, name: str) -> str:
        """The SI unit of a fitted or held parameter (``""`` for an unknown name)."""
        if name in self.units_:
            return self.units_[name]
        specs = {**self.model_.param_specs(), **EXTRA_SPECS}
        return specs[name].unit if name in specs else ""

    def settings(self) -> FitSettings:
        """The settings the fitting engine reads (:class:`~.engine.FitSettings`)."""
        return FitSettings(
            offset=self.offset, free=self.free, fixed=self.fixed, initial=self.initial,
            method=self.method, v_min=self.v_min, min_duration=self.min_duration,
            substeps=self.substeps, max_nfev=self.max_nfev, confidence=self.confidence,
            refine_hysteresis=self.refine_hysteresis)

    def _fit(self, data: Measurement) -> None:
        if self.method not in METHODS:
            raise FcompError(f"method {self.method!r}: choose one of {', '.join(METHODS)}")
        if not 0.0 < self.confidence < 1.0:
            raise FcompError(f"confidence must be in (0, 1), got {self.confidence}")
        model = self._base_model()
        d = fit_data(data, estimate_mass=self.estimate_mass, mass=self.mass,
                     cutoff_hz=self.cutoff_hz)
        if self.directional and self.offset:
            raise FcompError("direction-dependent levels and a constant offset are confounded "
                             "(both shift v > 0 and v < 0 forces apart/together); fit one of them")
        self.strategy_ = self.strategy or strategy_for(model)
        self._adopt(self.strategy_.fit(FitJob(self.settings(), model, d)), d)

    def _adopt(self, out: FitOutcome, d: FitData) -> None:
        """Set the result attributes from the strategy's outcome."""
        from fcomp.models.fitted_range import signal_ranges

        self.model_ = out.model.with_measurement(self._measurement_terms(out.extras)) \
            .with_fitted_range(signal_ranges([d.sig]))  # where the model was seen
        self.params_, self.stderr_, self.ci_ = out.params, out.stderr, out.ci
        self.units_, self.cov_, self.param_names_ = out.units, out.cov, out.param_names
        self.rms_fit_, self.converged_, self.message_ = out.rms, out.converged, out.message
        self.fixed_, self.not_identifiable_ = out.fixed, out.not_identifiable
        self.at_bound_, self.method_ = out.at_bound, out.method
        self.n_samples_, self.n_eff_, self.tau_int_ = out.n_samples, out.n_eff, out.tau_int
        self.nfev_, self.v_min_, self.stages_ = out.nfev, out.v_min, out.stages
        self.target_, self.uncertainty_, self.bounds_ = out.target, out.uncertainty, out.bounds
        self._extras = out.extras
        self._target_kind = (d.source, d.inertia is not None)
        self._failure = out.failure

    def _measurement_terms(self, extras: Mapping[str, float]) -> dict[str, float]:
        """The terms of the record the fitted model carries (``model_.measurement``): the
        fitted (or held) ``mass``, ``offset``, ``lag``, and a given ``mass``."""
        from fcomp.models.document import MEASUREMENT_PARAMS

        terms = {k: float(v) for k, v in extras.items()
                 if k in MEASUREMENT_PARAMS and math.isfinite(float(v))}
        if self.mass is not None and "mass" not in terms:
            terms["mass"] = float(self.mass)
        return terms

    # -------------------------------------------------------------- predict
    def _check_fitted(self) -> None:
        if not hasattr(self, "params_"):
            raise FcompError("this FrictionFit is not fitted yet: call fit(measurement) first")

    def target(self, data: Measurement) -> np.ndarray:
        """The force the fit compares with (N), built from ``data`` the way the fit did."""
        return self._data(data).y

    def _data(self, data: Measurement) -> FitData:
        self._check_fitted()
        return fit_data(data, estimate_mass=self._target_kind[1], mass=self.mass,
                        cutoff_hz=self.cutoff_hz)

    def predict(self, data: Measurement) -> np.ndarray:
        """Predicted force ``F_model + mass*(a + g*s_o) + offset`` (N) along ``data``'s motion
        (:func:`predicted`)."""
        d = self._data(data)  # first: a fit not fitted yet says so
        return predicted(self.model_, d, self.substeps)

    def plot(self, data: Measurement | None = None) -> Any:
        """The fit drawn: measured (or reconstructed) force and the fitted model over time and
        against the velocity, for ``data`` (default: the record fitted)."""
        from fcomp import figstyle as fs

        data = self.data_ if data is None else data
        d = self._data(data)
        y, F = d.y, self.predict(data)
        t, v = d.sig["t"], d.sig["v"]
        fig, (ax1, ax2) = fs.new_figure(height=3.6, ncols=2, sharey=True)
        fs.plot_gapped(ax1, t, y, color=fs.COLORS["measured"], lw=0.8,
                       label=f"measured ({self.target_})")
        fs.plot_gapped(ax1, t, F, color=fs.COLORS["final"], lw=0.8,
                       label=f"fitted {self.model_.describe()}")
        ax2.plot(fs.scaled("v", v), y, ".", color=fs.COLORS["measured"], ms=1.5)
        ax2.plot(fs.scaled("v", v), F, ".", color=fs.COLORS["final"], ms=1.0)
        ax1.set_xlabel("t (s)")
        ax2.set_xlabel(fs.label("velocity v", "v"))
        ax1.set_ylabel("force (N)")
        fs.legend_top(fig, ax1, ncol=2)
        rms = self.rms_ if data is self.data_ else self.score(data)  # not simulated again
        ax2.set_title(f"RMS error {rms:.3g} N")
        return fig

    def rows(self) -> list[list[str]]:
        """The estimates as table rows: name, value, standard error, interval, unit."""
        from fcomp.report import format_value

        self._check_fitted()
        out = [[n, format_value(v), "-", "at a bound", self.unit(n)]
               if n in self.at_bound_ else  # its standard error and interval mean nothing
               [n, format_value(v), format_value(self.stderr_[n]),
                f"[{format_value(self.ci_[n][0])}, {format_value(self.ci_[n][1])}]", self.unit(n)]
               for n, v in self.params_.items()]
        out += [[n, format_value(v), "-", "held: not determined", self.unit(n)]
                for n, v in self.held_.items()]
        return out

    def __repr__(self) -> str:
        name = self.model if isinstance(self.model, str) else self.model.describe()
        if not hasattr(self, "params_"):
            return f"<FrictionFit {name}: not fitted>"
        return (f"<FrictionFit {self.model_.describe()}: {len(self.params_)} estimates from "
                f"{self.n_samples_} samples, RMS {self.rms_:.4g} N, {len(self.warnings_)} "
                f"warning(s)>")

    def _repr_html_(self) -> str:
        from fcomp.report import notebook_html

        if not hasattr(self, "params_"):
            return f"<pre>{self!r}</pre>"
        pct = round(100 * self.confidence)
        rows = [["parameter", "value", "stderr", f"{pct} % interval", "unit"], *self.rows(),
                ["RMS error", f"{self.rms_:.4g}", "", "", "N"]]
        rows += [["warning", w.code, w.parameter or "", w.message, ""] for w in self.warnings_]
        try:
            fig = self.plot()
        except (FcompError, ValueError):
            fig = None
        return notebook_html(f"Fit: {self.model_.describe()} ({self.method_})", rows, fig)

    def score(self, data: Measurement) -> float:
        """The fitted model's RMS error (N) on ``data`` (e.g. a validation record): the one
        RMS of a model on a record (:func:`model_rms`, with this fit's cut-off), which is
        :attr:`rms_` for the record fitted."""
        self._check_fitted()
        return model_rms(self.model_, data, cutoff_hz=self.cutoff_hz, substeps=self.substeps)

    def model_file(self, source: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The fitted model as a model file's document (:mod:`fcomp.modelfile`): the
        model with its values and standard errors; a fitted ``mass`` and ``offset`` as
        measurement terms. ``source`` (``command``, ``data``) says where it comes from.
        """
        from fcomp.models.document import model_document

        self._check_fitted()
        return model_document(self.model_, stderr=self.stderr_, measurement=self._extras,
                              source={"fit": self.method_, **dict(source or {})})

    def to_dict(self) -> dict[str, Any]:
        """The JSON report (public contract: ``model``, ``params``, ``stderr``, ``rms``; more
        keys; ``model_file``: :meth:`model_file`)."""
        self._check_fitted()

        def num(x: float) -> float | str:
            return float(x) if math.isfinite(x) else ("inf" if x > 0 else "-inf")

        lineage = getattr(self.model_, "lineage", ()) or (self.model_.name,)
        name = self.model if isinstance(self.model, str) else lineage[0]
        return {
            "model": name,
            "effects": [e.name for e in self.model_.effects],
            "params": dict(self.params_),
            "stderr": dict(self.stderr_),
            "rms": self.rms_,
            "rms_measured": self.rms_measured_,
            "rms_fit": self.rms_fit_,
            "cutoff_hz": self.cutoff_hz,
            "ci": {k: list(v) for k, v in self.ci_.items()},
            "confidence": self.confidence,
            "units": dict(self.units_),
            "fixed": {k: num(v) for k, v in self.fixed_.items()},
            "not_identifiable": list(self.not_identifiable_),
            "at_bound": list(self.at_bound_),
            "method": self.method_,
            "target": self.target_,
            "converged": self.converged_,
            "message": self.message_,
            "n_samples": self.n_samples_,
            "n_eff": self.n_eff_,
            "tau_int": self.tau_int_,
            "evaluations": self.nfev_,
            "stages": self.stages_,
            "warnings": [w.to_dict() for w in self.warnings_],
            "model_file": self.model_file(),
        }
