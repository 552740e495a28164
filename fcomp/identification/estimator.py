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
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy.linalg import block_diag
from scipy.special import stdtrit

from fcomp.errors import ConvergenceError, FcompError
from fcomp.identification.dynamic import EXTRAS, Dependent, TrajectoryProblem
from fcomp.identification.guess import (
    bristle_stiffness,
    default_v_min,
    linear_start,
    stribeck_start,
)
from fcomp.identification.hysteresis_fit import EXTERNAL, INTERNAL, fit_hysteresis
from fcomp.identification.plausibility import FitWarning, RigContext, check_fit, correlations
from fcomp.identification.problem import ParameterVector, Solution, base_name, side_suffix, solve
from fcomp.identification.static import (
    SteadyStateMap,
    fit_steady_state,
    steady_state_points,
)
from fcomp.identification.target import FitData, fit_data
from fcomp.identification.uncertainty import Uncertainty, estimate
from fcomp.measurement import Measurement
from fcomp.models import FrictionModel, make_model
from fcomp.models.gms import GMSModel
from fcomp.models.hysteresis import HYSTERESIS_NAMES, HysteresisFamily
from fcomp.parameters import Directional, ParamSpec, spec

#: Hysteresis-function segment parameters fitted from transition curves.
SEGMENT_NAMES = (*EXTERNAL, *INTERNAL)
#: Parameters never fitted by default: numerical thresholds, reference values and the
#: hysteresis segment boundaries (seed 000 fixes them from the loop's shape, Table 2).
ALWAYS_FIXED = ("v_eps", "p_ref", "v_ref", *(n for n in HYSTERESIS_NAMES if n not in SEGMENT_NAMES))
EXTRA_SPECS: dict[str, ParamSpec] = {
    "mass": spec("mass", "kg", 0.0, 0.0, math.inf, "moving mass", directional=False),
    "offset": spec("offset", "N", 0.0, -math.inf, math.inf, "constant force offset",
                   directional=False),
}
METHODS = ("auto", "steady-state", "samples", "trajectory")
#: A trajectory fit that stops without converging holds the model parameters whose
#: standard error where it stopped exceeds this many times their magnitude, and refits the
#: others (the record does not determine the held ones: their interval spans zero).
HOLD_RELATIVE_ERROR = 1.0
#: Evaluation budget of the finite-difference refinement of the hysteresis segments
#: (each evaluation costs one simulation per parameter).
HYSTERESIS_REFINE_NFEV = 50


def default_free(model: FrictionModel) -> list[str]:
    """Flat names fitted by default: every finite parameter but :data:`ALWAYS_FIXED`."""
    return [n for n, v in model.flat_params().items()
            if base_name(n) not in ALWAYS_FIXED and math.isfinite(v)]


def equality_constraints(model: FrictionModel,
                         free: Sequence[str]) -> tuple[list[str], list[Dependent]]:
    """Free names without the parameters tied by an equality, and those ties.

    The generalized Maxwell-slip model requires ``sum(alpha_i) = 1``: the last
    free ``alpha`` becomes ``1 - (the other alphas)``.
    """
    if not isinstance(model, GMSModel):
        return list(free), []
    alphas = [f"alpha{i}" for i in range(1, model.n_elements + 1)]
    free_alpha = [a for a in alphas if a in free]
    if len(free_alpha) <= 1:  # a single free alpha is fixed by the others
        return [n for n in free if n not in free_alpha], []
    last = free_alpha[-1]
    flat = model.flat_params()
    const = 1.0 - sum(flat[a] for a in alphas if a not in free_alpha)
    return ([n for n in free if n != last],
            [Dependent(last, const, {a: -1.0 for a in free_alpha[:-1]})])


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
        RMS of the force residual (N) over the fitted samples.
    converged_ : bool
    message_ : str
    model_ : FrictionModel
        The model with the fitted values.
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

    # results (set by fit)
    params_: dict[str, float]
    stderr_: dict[str, float]
    ci_: dict[str, tuple[float, float]]
    units_: dict[str, str]
    cov_: np.ndarray
    param_names_: list[str]
    rms_: float
    converged_: bool
    message_: str
    model_: FrictionModel
    fixed_: dict[str, float]
    not_identifiable_: list[str]
    at_bound_: list[str]
    method_: str
    n_samples_: int
    n_eff_: float
    tau_int_: float
    nfev_: int
    v_min_: float
    stages_: list[dict[str, Any]]
    target_: str
    uncertainty_: Uncertainty | None
    bounds_: dict[str, tuple[float, float]]
    context_: RigContext
    warnings_: list[FitWarning]
    _failure: str
    _extras: dict[str, float]
    _target_kind: tuple[str, bool]
    _deps: list[Dependent]

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
        cutoff_hz: float = 10.0,
        substeps: int = 1,
        max_nfev: int = 200,
        confidence: float = 0.95,
        refine_hysteresis: bool = True,
        strict: bool = True,
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

    def _free_names(self, model: FrictionModel) -> list[str]:
        flat = model.flat_params()
        if self.free is None:
            free = default_free(model)
        else:
            free = []
            for name in self.free:
                if name in flat:
                    free.append(name)
                elif name + "_pos" in flat:
                    free += [name + "_pos", name + "_neg"]
                else:
                    raise FcompError(f"{model.describe()}: no parameter {name!r} to fit; "
                                     f"known: {', '.join(flat)}")
        fixed = set(self.fixed or ())
        for name in fixed:
            if name not in flat:
                raise FcompError(f"{model.describe()}: no parameter {name!r} to fix; "
                                 f"known: {', '.join(flat)}")
        return [n for n in free if n not in fixed]

    def _specs(self, model: FrictionModel, names: Sequence[str],
               values: Mapping[str, float]) -> dict[str, ParamSpec]:
        """Bounds of the fitted names; ``Fc <= Fs`` against a fixed partner."""
        specs = dict(model.param_specs())
        specs.update(EXTRA_SPECS)
        out = {n: specs[n] for n in names}
        for n in names:
            sfx = side_suffix(n)
            if base_name(n) == "Fc":
                partner = next((p for p in ("Fs" + sfx, "Fs") if p in values), None)
                if partner and partner not in names:
                    out[n] = dataclasses.replace(out[n], upper=float(values[partner]))
            if base_name(n) == "Fs":
                partner = next((p for p in ("Fc" + sfx, "Fc") if p in values), None)
                if partner and partner not in names:
                    out[n] = dataclasses.replace(out[n], lower=float(values[partner]))
        return out

    def _start(self, model: FrictionModel, d: FitData, v_min: float) -> dict[str, float]:
        """Start values of every model parameter and the extras (module :mod:`.guess`)."""
        flat = dict(model.flat_params())
        start = dict(flat)
        names = {base_name(n) for n in flat}
        visc = "B" if "B" in names else ("sigma2" if "sigma2" in names else None)
        directional = any(n.endswith("_pos") for n in flat)
        ls = linear_start(d, v_min, offset=self.offset, directional=directional,
                          viscous=visc is not None)
        v, f = d.sig["v"], ls.friction

        def put(name: str, pos: float, neg: float) -> None:
            if name in flat:
                start[name] = 0.5 * (pos + neg)
            else:
                start[name + "_pos"], start[name + "_neg"] = pos, neg

        if "Fc" in names:
            put("Fc", *ls.Fc)
        if visc is not None:
            put(visc, *ls.B)
        if "Fs" in names:
            hump = [stribeck_start(v[sel], f[sel], fc, b, v_min)
                    for sel, fc, b in ((v > 0, ls.Fc[0], ls.B[0]), (v < 0, ls.Fc[1], ls.B[1]))]
            put("Fs", hump[0][0], hump[1][0])
            put("vs", hump[0][1], hump[1][1])
        g = 0.5 * (ls.Fc[0] + ls.Fc[1])
        if "sigma0" in names:
            x = d.sig["x"]
            sigma0 = bristle_stiffness(x, v, f, g)
            start["sigma0"] = sigma0 if sigma0 is not None else g / 1e-4
        if "sigma1" in names:
            moving = np.abs(v) >= v_min
            start["sigma1"] = 0.1 * g / float(np.median(np.abs(v[moving])))
        if ls.mass is not None:
            start["mass"] = ls.mass
        if self.offset:
            start["offset"] = ls.offset
        for k, val in (self.initial or {}).items():
            if k not in start:
                raise FcompError(f"initial value for unknown parameter {k!r}")
            start[k] = float(val)
        return start

    @staticmethod
    def _scales(pv_names: Sequence[str], start: Mapping[str, float], G: np.ndarray,
                y: np.ndarray) -> dict[str, float]:
        """Typical magnitudes: ``|start|``, or (start 0) the change giving 1 % of the force RMS."""
        ref = 0.01 * float(np.sqrt(np.mean(y**2))) or 1e-3
        out = {}
        for j, n in enumerate(pv_names):
            if abs(start[n]) > 0:
                out[n] = abs(start[n])
            else:
                col = float(np.sqrt(np.mean(G[:, j] ** 2)))
                out[n] = ref / col if col > 0 else 1.0
        return out

    @staticmethod
    def _insensitive(jacobian_at: Any, names: Sequence[str], start: Mapping[str, float],
                     ref: float) -> list[str]:
        """Names whose Jacobian column vanishes at the start and at 3 perturbed points.

        ``jacobian_at(values) -> G`` (samples x names). A column counts as zero when
        ``rms(G_j)*|theta_j| < 1e-9*ref`` (``ref`` the force RMS), or is exactly zero
        for a parameter starting at 0. Structural zeros (``sigma0`` in a steady-state
        map, ``tau_h0`` in a record without rest) vanish at every point; a
        parameter that merely starts where it has no effect does not.
        """
        rng = np.random.default_rng(12345)
        alive = np.zeros(len(names), dtype=bool)
        for trial in range(4):
            vals = dict(start)
            if trial:
                for n in names:
                    if n not in EXTRAS:
                        vals[n] = start[n] * float(np.exp(0.3 * rng.standard_normal()))
            G = jacobian_at(vals)
            for j, n in enumerate(names):
                col = G[:, j]
                if start[n] == 0.0:
                    alive[j] |= bool(np.any(col != 0.0))
                else:
                    alive[j] |= float(np.sqrt(np.mean(col**2))) * abs(vals[n]) >= 1e-9 * ref
            if alive.all():
                break
        return [n for n, a in zip(names, alive, strict=True) if not a]

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
        self._fit(data)
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

    def _fit(self, data: Measurement) -> FrictionFit:
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
        if isinstance(model, HysteresisFamily):
            return self._fit_hysteresis_model(model, data, d)
        v_min = self.v_min if self.v_min is not None else default_v_min(d.sig["v"])
        free, self._deps = equality_constraints(model, self._free_names(model))
        extras = (["mass"] if d.inertia is not None else []) + (["offset"] if self.offset else [])
        if not free and not extras:
            raise FcompError(f"{model.describe()}: nothing to fit (every parameter fixed)")
        start = self._start(model, d, v_min)
        self.stages_ = []
        self.not_identifiable_ = []
        self.target_ = d.source
        dynamic = model.n_states > 0
        moving = np.abs(d.sig["v"]) >= v_min

        if not dynamic and self.method == "trajectory":
            raise FcompError(f"{model.describe()} is a static map: use method 'auto', "
                             "'steady-state' or 'samples'")
        if dynamic and self.method in ("steady-state", "samples"):
            raise FcompError(f"{model.describe()} is dynamic: use method 'auto' or 'trajectory'")

        if not dynamic:
            use_ss = self.method == "steady-state" or (
                self.method == "auto" and d.inertia is None)
            if use_ss:
                done = self._static_stage(model, d, free, start, v_min,
                                          required=self.method == "steady-state", final=True)
                # auto: the steady-state characteristic only where it determines every parameter
                if done is not None and (self.method == "steady-state" or (
                        done[1].converged and bool(np.all(done[2].identifiable)))):
                    return self._finish(model, d, moving, *done)
                self.not_identifiable_ = []
            return self._trajectory_stage(model, d, free, extras, start, moving, "samples")
        if self.method == "auto" and model.symbolic:
            self._static_stage(model, d, free, start, v_min, required=False, final=False)
        return self._trajectory_stage(model, d, free, extras, start,
                                      np.ones(d.n, dtype=bool), "trajectory")

    def _fit_hysteresis_model(self, model: HysteresisFamily, data: Measurement,
                              d: FitData) -> FrictionFit:
        """Seed 000's new model: the NMLGM part by the trajectory fit of the carrier model
        (symbolic, exact sensitivities), then ``c_i, k_i`` from transition curves
        (:mod:`.hysteresis_fit`), refined (``refine_hysteresis``) by a trajectory fit
        of the full model with finite differences, the other parameters held."""
        free = self._free_names(model)
        seg = [n for n in free if n in SEGMENT_NAMES]
        carrier = model.carrier()
        cflat = carrier.flat_params()
        extras = (["mass"] if d.inertia is not None else []) + (["offset"] if self.offset else [])
        cfree = [n for n in free if n in cflat]
        sub: FrictionFit | None = None
        if cfree or extras:
            sub = FrictionFit(
                carrier, offset=self.offset, estimate_mass=self.estimate_mass, mass=self.mass,
                free=cfree, initial={k: v for k, v in (self.initial or {}).items()
                                     if k in cflat or k in EXTRAS},
                method=self.method, v_min=self.v_min, min_duration=self.min_duration,
                cutoff_hz=self.cutoff_hz, substeps=self.substeps, max_nfev=self.max_nfev,
                confidence=self.confidence, strict=False,
            ).fit(data)
            cvals = sub.model_.flat_params()
            ext = dict(sub._extras)
        else:
            cvals, ext = dict(cflat), {}
        f = d.y - ext.get("offset", 0.0)
        if "mass" in ext and d.inertia is not None:
            f = f - ext["mass"] * d.inertia
        hmodel = model.with_params(**cvals)
        values = hmodel.flat_params()
        specs = hmodel.param_specs()
        stages = list(sub.stages_) if sub else []
        hyst_names: list[str] = []
        not_ident = list(sub.not_identifiable_) if sub else []
        if seg:
            hf = fit_hysteresis(d.sig["x"], f, values, specs, free=seg, max_nfev=self.max_nfev,
                                level=self.confidence, label=d.label)
            stages.append({"stage": "transition-curves", "parameters": hf.names,
                           "curves": hf.curves, "rms": hf.rms,
                           "evaluations": hf.solution.nfev, "converged": hf.solution.converged})
            not_ident += hf.not_identifiable
            values.update(hf.values)
            hyst_names = hf.names
        fd = FitData(d.sig, f, None, d.source, d.mass, d.label)
        hmodel = hmodel.with_params(**{n: values[n] for n in hyst_names})
        if hyst_names and self.refine_hysteresis:
            pv = ParameterVector.build(hyst_names, values, {n: specs[n] for n in hyst_names})
            prob = TrajectoryProblem(hmodel, fd, pv, substeps=self.substeps)
            sol = solve(pv, prob, max_nfev=min(self.max_nfev, HYSTERESIS_REFINE_NFEV),
                        compress=False, what=f"{d.label}: hysteresis refinement")
            unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=self.confidence)
            stages.append({"stage": "hysteresis-trajectory", "parameters": hyst_names,
                           "rms": float(np.sqrt(np.mean(sol.residuals**2))),
                           "evaluations": sol.nfev, "converged": sol.converged})
            h_theta, h_unc, converged, message = sol.theta, unc, sol.converged, sol.message
            h_units = pv.units
        elif hyst_names:
            h_theta = np.array([hf.values[n] for n in hyst_names])
            h_unc, converged, message = hf.uncertainty, hf.solution.converged, \
                hf.solution.message
            h_units = tuple(specs[n].unit for n in hyst_names)
        else:
            h_theta, h_unc, converged, message, h_units = np.zeros(0), None, True, "", ()
        hvals = dict(zip(hyst_names, map(float, h_theta), strict=True))
        try:
            self.model_ = hmodel.with_params(**hvals)
        except ValueError as exc:
            raise ConvergenceError(f"{d.label}: the fit ended on invalid parameters ({exc})") \
                from None
        # results: the carrier fit's, then the segment parameters (block-diagonal covariance)
        self.params_, self.stderr_, self.ci_, self.units_ = {}, {}, {}, {}
        covs = []
        if sub is not None:
            self.params_.update(sub.params_)
            self.stderr_.update(sub.stderr_)
            self.ci_.update(sub.ci_)
            self.units_.update(sub.units_)
            covs.append(sub.cov_)
        if h_unc is not None:
            keep = [j for j, ok in enumerate(h_unc.identifiable) if ok]
            for j in keep:
                n = hyst_names[j]
                self.params_[n] = hvals[n]
                self.stderr_[n] = float(h_unc.stderr[j])
                self.ci_[n] = (float(h_unc.ci_low[j]), float(h_unc.ci_high[j]))
                self.units_[n] = h_units[j]
            not_ident += [hyst_names[j] for j, ok in enumerate(h_unc.identifiable) if not ok]
            covs.append(h_unc.cov[np.ix_(keep, keep)])
        self.param_names_ = list(self.params_)
        self.cov_ = block_diag(*covs) if covs else np.zeros((0, 0))
        self.not_identifiable_ = not_ident
        self.stages_ = stages
        self.fixed_ = {k: float(v) for k, v in self.model_.flat_params().items()
                       if k not in self.params_}
        self.tau_int_ = sub.tau_int_ if sub else (h_unc.tau_int if h_unc else 1.0)
        self.n_eff_ = sub.n_eff_ if sub else (h_unc.n_eff if h_unc else float(d.n))
        self.uncertainty_ = h_unc
        self.method_ = "trajectory+transition-curves"
        self.converged_ = bool(converged and (sub.converged_ if sub else True))
        self.message_ = message if sub is None else f"{sub.message_}; {message}".strip("; ")
        self.nfev_ = sum(s_["evaluations"] for s_ in stages)
        self.v_min_ = sub.v_min_ if sub else default_v_min(d.sig["v"])
        self._extras = ext
        self._target_kind = (d.source, d.inertia is not None)
        self.target_ = d.source
        run = TrajectoryProblem(self.model_, fd, ParameterVector.build(
            [], {}, {}), substeps=self.substeps).predict(np.zeros(0))
        self.rms_ = float(np.sqrt(np.mean((f - run) ** 2)))
        self.n_samples_ = d.n
        self.at_bound_ = list(sub.at_bound_) if sub else []
        self.bounds_ = {**(sub.bounds_ if sub else {}),
                        **{n: (specs[n].lower, specs[n].upper) for n in hyst_names}}
        self._failure = f"{d.label}: fitting {model.describe()} did not converge ({self.message_})"
        return self

    def _static_stage(self, model: FrictionModel, d: FitData, free: list[str],
                      start: dict[str, float], v_min: float, *, required: bool,
                      final: bool) -> tuple | None:
        """Seed 002's steady-state fit; updates ``start`` (first stage) or is the result."""
        tied = {k for dep in self._deps for k in (dep.name, *dep.coef)}
        free = [n for n in free if n not in tied]
        y = d.y if d.inertia is None else d.y - start["mass"] * d.inertia
        s = d.sig
        pts = steady_state_points(s["t"], s["v"], s["a"], y, v_min=v_min,
                                  min_duration=self.min_duration, x=s["x"], p1=s["p1"],
                                  p2=s["p2"])
        # parameters the steady-state map depends on
        ss_free: list[str] = []
        if len(pts):
            fmap = SteadyStateMap(model, free)
            ref = float(np.sqrt(np.mean(pts.F**2))) or 1.0
            dead = self._insensitive(lambda vals: fmap(pts, {k: vals[k] for k in free})[1],
                                     free, start, ref)
            ss_free = [n for n in free if n not in dead]
        names = ss_free + (["offset"] if self.offset else [])
        if len(pts) < 3 * len(names) or not names:
            if required:
                raise FcompError(
                    f"{d.label}: only {len(pts)} steady-state force-velocity points for "
                    f"{len(names)} parameters (need steady runs of at least "
                    f"{self.min_duration} s above {v_min:.3g} m/s); use method 'samples'")
            return None
        _, Gs = SteadyStateMap(model, ss_free)(pts, {k: start[k] for k in ss_free})
        if self.offset:
            Gs = np.hstack([Gs, np.ones((len(pts), 1))])
        scales = self._scales(names, start, Gs, pts.F)
        pv = ParameterVector.build(names, start, self._specs(model, names, start), scales)
        budget = self.max_nfev if final else min(self.max_nfev, 60)
        res = fit_steady_state(model, pts, pv, max_nfev=budget, level=self.confidence)
        self.stages_.append({"stage": "steady-state", "parameters": names,
                             "points": len(pts), "rms": res.rms,
                             "evaluations": res.solution.nfev,
                             "converged": res.solution.converged})
        if final:
            self.not_identifiable_ += [n for n in free if n not in ss_free]
            return pv, res.solution, res.uncertainty, "steady-state", None
        if res.solution.converged:  # keep only well-determined values (stderr < 50 %)
            for n, se in zip(names, res.uncertainty.stderr, strict=True):
                if se < 0.5 * abs(res.values[n]):
                    start[n] = res.values[n]
        return None

    def _trajectory_stage(self, model: FrictionModel, d: FitData, free: list[str],
                          extras: list[str], start: dict[str, float], mask: np.ndarray,
                          method: str) -> FrictionFit:
        names = free + extras
        probe_pv = ParameterVector.build(names, start, self._specs(model, names, start))
        prob = TrajectoryProblem(model, d, probe_pv, mask=mask, substeps=self.substeps,
                                 dependent=self._deps)

        def jacobian_at(vals: Mapping[str, float]) -> np.ndarray:
            G = prob(np.array([vals[n] for n in probe_pv.names]), True)[1]
            if G is None:
                raise RuntimeError("the trajectory problem returned no Jacobian")
            return G

        ref = float(np.sqrt(np.mean(d.y[mask] ** 2))) or 1.0
        dead = [n for n in self._insensitive(jacobian_at, names, start, ref) if n not in EXTRAS]
        if dead:
            self.not_identifiable_ += dead
            names = [n for n in names if n not in dead]
        if not names:
            raise FcompError(f"{d.label}: the record determines none of the parameters of "
                             f"{model.describe()}")
        G = jacobian_at(start)[:, [j for j, n in enumerate(probe_pv.names) if n in names]]
        scales = self._scales(names, start, G, d.y[mask])
        pv = ParameterVector.build(names, start, self._specs(model, names, start), scales)
        prob = TrajectoryProblem(model, d, pv, mask=mask, substeps=self.substeps,
                                 dependent=self._deps)
        sol = solve(pv, prob, max_nfev=self.max_nfev, what=f"fit of {model.describe()}",
                    compress=prob.jacobian_is_free)
        unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=self.confidence)
        self._stage(method, pv, sol)
        while not sol.converged:  # hold what the record barely determines, refit the rest
            held = self._undetermined(pv, sol, unc)
            if not held:
                break
            reached = dict(zip(pv.names, map(float, sol.theta), strict=True))
            model = model.with_params(**{n: reached[n] for n in held})
            keep = [n for n in pv.names if n not in held]
            pv = ParameterVector.build(keep, reached, self._specs(model, keep, {
                **model.flat_params(), **reached}), {n: pv.scale[pv.index(n)] for n in keep})
            prob = TrajectoryProblem(model, d, pv, mask=mask, substeps=self.substeps,
                                     dependent=self._deps)
            sol = solve(pv, prob, max_nfev=self.max_nfev, what=f"fit of {model.describe()}",
                        compress=prob.jacobian_is_free)
            unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=self.confidence)
            self.not_identifiable_ += held
            self._stage(f"{method}, {', '.join(held)} held", pv, sol)
        return self._finish(model, d, mask, pv, sol, unc, method, prob)

    def _stage(self, name: str, pv: ParameterVector, sol: Solution) -> None:
        """Record a least-squares stage in ``stages_``."""
        self.stages_.append({"stage": name, "parameters": list(pv.names),
                             "rms": float(np.sqrt(np.mean(sol.residuals**2))),
                             "evaluations": sol.nfev, "converged": sol.converged})

    def _undetermined(self, pv: ParameterVector, sol: Solution, unc: Uncertainty) -> list[str]:
        """Model parameters a stopped solve barely determines: standard error above
        :data:`HOLD_RELATIVE_ERROR` times ``max(|value|, scale)`` (none of ``mass``,
        ``offset`` or the parameters tied by an equality); empty if that would leave
        nothing to fit."""
        tied = {k for dep in self._deps for k in (dep.name, *dep.coef)}
        mag = np.maximum(np.abs(sol.theta), pv.scale)
        weak = [n for n, se, m in zip(pv.names, unc.stderr, mag, strict=True)
                if not se <= HOLD_RELATIVE_ERROR * m and n not in EXTRAS and n not in tied]
        return weak if len(weak) < len(pv.names) else []

    # --------------------------------------------------------------- results
    def _finish(self, model: FrictionModel, d: FitData, mask: np.ndarray, pv: ParameterVector,
                sol: Solution, unc: Uncertainty, method: str,
                prob: TrajectoryProblem | None) -> FrictionFit:
        names = list(pv.names)
        theta = sol.theta
        # a parameter the record does not determine: a null direction at the solution, a
        # 100 % change moving the prediction by less than 1e-6 of the residual RMS, or a
        # standard error above 1000 times its magnitude. Held; the others' errors recomputed.
        r_rms = float(np.sqrt(np.mean(sol.residuals**2))) or 1e-300
        mag = np.maximum(np.abs(theta), pv.scale)
        effect = np.sqrt(np.mean(sol.jacobian**2, axis=0)) * mag
        bad: list[str] = []
        for _ in range(len(names)):
            keep = [j for j, n in enumerate(names) if n not in bad]
            new = [names[j] for i, j in enumerate(keep)
                   if not unc.identifiable[i] or effect[j] < 1e-6 * r_rms
                   or unc.stderr[i] > 1e3 * mag[j]]
            if not new:
                break
            bad += new
            keep = [j for j, n in enumerate(names) if n not in bad]
            if not keep:
                raise FcompError(f"{d.label}: the record determines none of the parameters of "
                                 f"{model.describe()}")
            unc = estimate(sol.jacobian[:, keep], sol.residuals, theta[keep],
                           level=self.confidence, autocorrelated=method != "steady-state")
        self.not_identifiable_ += bad
        values = dict(zip(names, map(float, theta), strict=True))
        model_values = {k: v for k, v in values.items() if k not in EXTRAS}
        for dep in self._deps:
            model_values[dep.name] = dep.value(model_values)
        try:
            self.model_ = model.with_params(**model_values)
        except ValueError as exc:
            raise ConvergenceError(f"{d.label}: the fit ended on invalid parameters ({exc})") \
                from None
        est = [n for n in names if n not in bad]
        self.param_names_ = est
        self.params_ = {n: values[n] for n in est}
        self.stderr_ = {n: float(s) for n, s in zip(est, unc.stderr, strict=True)}
        self.ci_ = {n: (float(lo), float(hi))
                    for n, lo, hi in zip(est, unc.ci_low, unc.ci_high, strict=True)}
        self.cov_ = unc.cov
        self.units_ = {n: u for n, u in zip(names, pv.units, strict=True) if n in est}
        self._add_dependent(est, unc, model_values)
        self.fixed_ = {k: float(v) for k, v in self.model_.flat_params().items()
                       if k not in self.params_}
        self.tau_int_ = unc.tau_int
        self.n_eff_ = unc.n_eff
        self.uncertainty_ = unc
        self.method_ = method
        self.converged_ = sol.converged
        self.message_ = sol.message
        self.nfev_ = sum(s["evaluations"] for s in self.stages_)
        self.v_min_ = self.v_min if self.v_min is not None else default_v_min(d.sig["v"])
        self._extras = {k: values[k] for k in EXTRAS if k in values}
        self._target_kind = (d.source, d.inertia is not None)
        if prob is None:  # the steady-state fit: the record's force error over moving samples
            prob = TrajectoryProblem(model, d, pv, mask=mask, substeps=self.substeps,
                                     dependent=self._deps)
        F_hat = prob.predict(theta)
        r = d.y[mask] - F_hat[mask]
        self.rms_ = float(np.sqrt(np.mean(r**2)))
        self.n_samples_ = int(mask.sum())
        self.at_bound_ = [n for n, a in zip(names, sol.at_bound, strict=True) if a and n in est]
        specs = self._specs(model, est, {**model.flat_params(), **values})
        self.bounds_ = {n: (specs[n].lower, specs[n].upper) for n in est}
        self._failure = (f"{d.label}: fitting {model.describe()} did not converge ({sol.message}; "
                         f"{sol.nfev} evaluations); try fixing parameters (--fix) or a longer, "
                         "richer record")
        return self

    def _add_dependent(self, est: list[str], unc: Uncertainty,
                       values: Mapping[str, float]) -> None:
        """Report parameters tied by equalities, with the propagated standard error."""
        for dep in self._deps:
            c = np.array([dep.coef.get(n, 0.0) for n in est])
            var = float(c @ unc.cov @ c) if c.any() else 0.0
            se = math.sqrt(max(var, 0.0)) if math.isfinite(var) else math.inf
            q = float(stdtrit(max(unc.n_eff - len(est), 1.0), 0.5 + self.confidence / 2.0))
            val = values[dep.name]
            self.params_[dep.name] = val
            self.stderr_[dep.name] = se
            self.ci_[dep.name] = (val - q * se, val + q * se)
            self.units_[dep.name] = self.model_.param_specs()[dep.name].unit

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
        """Predicted force ``F_model + mass*(a + g*s_o) + offset`` (N) along ``data``'s motion."""
        d = self._data(data)
        s = d.sig
        from fcomp.trajectory import friction_along_motion

        F = friction_along_motion(self.model_, s["t"], s["v"], a=s["a"], x=s["x"], p1=s["p1"],
                                  p2=s["p2"], substeps=self.substeps).F
        if "mass" in self._extras and d.inertia is not None:
            F = F + self._extras["mass"] * d.inertia
        return F + self._extras.get("offset", 0.0)

    def score(self, data: Measurement) -> float:
        """RMS force error (N) of the fitted model on ``data`` (e.g. a validation record)."""
        return float(np.sqrt(np.mean((self.target(data) - self.predict(data)) ** 2)))

    def to_dict(self) -> dict[str, Any]:
        """The JSON report (public contract: ``model``, ``params``, ``stderr``, ``rms``; more keys)."""
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
        }
