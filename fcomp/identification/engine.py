"""The fitting engine: one model, one record, the stages every fit strategy is built from.

A :class:`FitJob` holds a model, a record (:class:`~.target.FitData`) and the
estimator's :class:`FitSettings`, and offers the stages a strategy
(:mod:`.strategies`) chains:

* :meth:`FitJob.prepare` -- the free names (less those tied by an equality,
  ``Params.UNIT_SUMS``), the extras (``mass`` where the record holds a
  driving force, ``offset`` on request) and the data-based start
  (:mod:`.guess`);
* :meth:`FitJob.static_stage` -- seed 002's weighted least squares on the
  binned steady-state characteristic (:mod:`.static`), as the fit itself or
  as a start;
* :meth:`FitJob.trajectory_stage` -- the model simulated along the motion
  against the target over the masked samples (:mod:`.records`, with the
  gradient strategy the model's capabilities allow), parameters the data do
  not determine held; a solve that stops without converging holds what it
  barely determines and refits the rest;
* :meth:`FitJob.finish` -- estimates, autocorrelation-robust standard
  errors and intervals (:mod:`.uncertainty`), the parameters not determined
  at the solution, the force error: a :class:`FitOutcome`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.special import stdtrit

from fcomp.conditioning import bristle_stiffness
from fcomp.errors import ConvergenceError, FcompError, term
from fcomp.identification.dynamic import EXTRAS, Dependent
from fcomp.identification.guess import default_v_min, linear_start, stribeck_start
from fcomp.identification.hysteresis_fit import EXTERNAL, INTERNAL
from fcomp.identification.problem import ParameterVector, Solution, base_name, side_suffix
from fcomp.identification.records import EXTRA_SPECS, Record, RecordsProblem, solve_records
from fcomp.identification.static import (
    SteadyStateMap,
    fit_steady_state,
    steady_state_points,
)
from fcomp.identification.target import FitData
from fcomp.identification.uncertainty import Uncertainty, estimate
from fcomp.models.base import FrictionModel
from fcomp.models.hysteresis import HYSTERESIS_NAMES
from fcomp.parameters import ParamSpec

#: Hysteresis-function segment parameters fitted from transition curves.
SEGMENT_NAMES = (*EXTERNAL, *INTERNAL)
#: Parameters never fitted by default: numerical thresholds, reference values and the
#: hysteresis segment boundaries (seed 000 fixes them from the loop's shape, Table 2).
ALWAYS_FIXED = ("v_eps", "p_ref", "v_ref", *(n for n in HYSTERESIS_NAMES if n not in SEGMENT_NAMES))
METHODS = ("auto", "steady-state", "samples", "trajectory")
#: A trajectory fit that stops without converging holds the model parameters whose
#: standard error where it stopped exceeds this many times their magnitude, and refits the
#: others (the record does not determine the held ones: their interval spans zero).
HOLD_RELATIVE_ERROR = 1.0

__all__ = ["ALWAYS_FIXED", "EXTRA_SPECS", "HOLD_RELATIVE_ERROR", "METHODS", "SEGMENT_NAMES",
           "FitJob", "FitOutcome", "FitSettings", "default_free", "equality_constraints"]


def default_free(model: FrictionModel) -> list[str]:
    """Flat names fitted by default: every finite parameter but :data:`ALWAYS_FIXED` and
    those its effects hold fixed (``Effect.fixed``: a reference pressure, the parameters
    a law's form does not use)."""
    fixed = {n for e in model.effects for n in getattr(e, "fixed", ())}
    return [n for n, v in model.flat_params().items()
            if base_name(n) not in ALWAYS_FIXED and base_name(n) not in fixed
            and math.isfinite(v)]


def equality_constraints(model: FrictionModel,
                         free: Sequence[str]) -> tuple[list[str], list[Dependent]]:
    """Free names without the parameters tied by an equality, and those ties.

    Every group of ``Params.UNIT_SUMS`` (the model's and its effects') sums to 1
    (the slip fractions of the generalized Maxwell-slip model): the group's last
    free name becomes ``1 - (the others)``; a group with one free name has it
    fixed by the others.
    """
    free = list(free)
    deps: list[Dependent] = []
    flat = model.flat_params()
    for owner in (model.params, *(e.params for e in model.effects)):
        for group, _why in type(owner).UNIT_SUMS:
            members = [n for n in group if n in free]
            if len(members) <= 1:
                free = [n for n in free if n not in members]
                continue
            last = members[-1]
            const = 1.0 - sum(flat[n] for n in group if n not in members)
            free = [n for n in free if n != last]
            deps.append(Dependent(last, const, {n: -1.0 for n in members[:-1]}))
    return free, deps


@dataclass(frozen=True)
class FitSettings:
    """The estimator's settings a job reads (:class:`~.estimator.FrictionFit` documents them)."""

    offset: bool = False
    free: Sequence[str] | None = None
    fixed: Mapping[str, float] | None = None
    initial: Mapping[str, float] | None = None
    method: str = "auto"
    v_min: float | None = None
    min_duration: float = 0.05
    substeps: int = 1
    max_nfev: int = 200
    confidence: float = 0.95
    refine_hysteresis: bool = True


@dataclass
class FitOutcome:
    """Everything a fit found (the ``*_`` attributes of :class:`~.estimator.FrictionFit`)."""

    model: FrictionModel
    params: dict[str, float]
    stderr: dict[str, float]
    ci: dict[str, tuple[float, float]]
    units: dict[str, str]
    cov: np.ndarray
    param_names: list[str]
    rms: float
    converged: bool
    message: str
    fixed: dict[str, float]
    not_identifiable: list[str]
    at_bound: list[str]
    method: str
    n_samples: int
    n_eff: float
    tau_int: float
    nfev: int
    v_min: float
    stages: list[dict[str, Any]]
    target: str
    uncertainty: Uncertainty | None
    bounds: dict[str, tuple[float, float]]
    extras: dict[str, float] = field(default_factory=dict)
    failure: str = ""


class FitJob:
    """One model fitted to one record with :class:`FitSettings` (module docstring).

    Parameters
    ----------
    settings
        The estimator's settings.
    model
        The model to fit (fixed values already set).
    data
        The record's signals and target.
    """

    def __init__(self, settings: FitSettings, model: FrictionModel, data: FitData) -> None:
        self.settings = settings
        self.model = model
        self.data = data
        self.v_min = settings.v_min if settings.v_min is not None else default_v_min(
            data.sig["v"])
        self.stages: list[dict[str, Any]] = []
        self.not_identifiable: list[str] = []
        self.deps: list[Dependent] = []

    # ---------------------------------------------------------------- setup
    @property
    def extras(self) -> list[str]:
        """``mass`` where the record holds a driving force, ``offset`` on request."""
        return ((["mass"] if self.data.inertia is not None else [])
                + (["offset"] if self.settings.offset else []))

    def free_names(self, model: FrictionModel) -> list[str]:
        """The names to fit: ``settings.free`` (a directional name gives both sides) or
        :func:`default_free`, less ``settings.fixed``."""
        flat = model.flat_params()
        s = self.settings
        if s.free is None:
            free = default_free(model)
        else:
            free = []
            for name in s.free:
                if name in flat:
                    free.append(name)
                elif name + "_pos" in flat:
                    free += [name + "_pos", name + "_neg"]
                else:
                    raise FcompError(f"{model.describe()}: no parameter {name!r} to fit; "
                                     f"known: {', '.join(flat)}")
        fixed = set(s.fixed or ())
        for name in fixed:
            if name not in flat:
                raise FcompError(f"{model.describe()}: no parameter {name!r} to fix; "
                                 f"known: {', '.join(flat)}")
        return [n for n in free if n not in fixed]

    def prepare(self) -> tuple[list[str], list[str], dict[str, float]]:
        """``(free, extras, start)``: the free names less the tied ones (their ties kept
        in :attr:`deps`), the extras and the start of every name."""
        model = self.model
        free, self.deps = equality_constraints(model, self.free_names(model))
        extras = self.extras
        if not free and not extras:
            raise FcompError(f"{model.describe()}: nothing to fit (every parameter fixed)")
        return free, extras, self.start(model)

    def specs(self, model: FrictionModel, names: Sequence[str],
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

    def start(self, model: FrictionModel) -> dict[str, float]:
        """Start values of every model parameter and the extras (module :mod:`.guess`)."""
        d, s, v_min = self.data, self.settings, self.v_min
        flat = dict(model.flat_params())
        start = dict(flat)
        names = {base_name(n) for n in flat}
        visc = "B" if "B" in names else ("sigma2" if "sigma2" in names else None)
        directional = any(n.endswith("_pos") for n in flat)
        ls = linear_start(d, v_min, offset=s.offset, directional=directional,
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
        if s.offset:
            start["offset"] = ls.offset
        for k, val in (s.initial or {}).items():
            if k not in start:
                raise FcompError(f"initial value for unknown parameter {k!r}")
            start[k] = float(val)
        return start

    @staticmethod
    def scales(pv_names: Sequence[str], start: Mapping[str, float], G: np.ndarray,
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
    def insensitive(jacobian_at: Callable[[Mapping[str, float]], np.ndarray],
                    names: Sequence[str], start: Mapping[str, float], ref: float) -> list[str]:
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

    def _tied(self) -> set[str]:
        return {k for dep in self.deps for k in (dep.name, *dep.coef)}

    # --------------------------------------------------------------- stages
    def static_stage(self, model: FrictionModel, free: list[str], start: dict[str, float], *,
                     required: bool, final: bool
                     ) -> tuple[ParameterVector, Solution, Uncertainty] | None:
        """Seed 002's steady-state fit; updates ``start`` (``final`` false: a start stage) or
        gives ``(pv, solution, uncertainty)`` for :meth:`finish` (``final``); ``None`` when
        the record holds too few steady points (an error if ``required``)."""
        s, d = self.settings, self.data
        tied = self._tied()
        free = [n for n in free if n not in tied]
        y = d.y if d.inertia is None else d.y - start["mass"] * d.inertia
        sig = d.sig
        pts = steady_state_points(sig["t"], sig["v"], sig["a"], y, v_min=self.v_min,
                                  min_duration=s.min_duration, x=sig["x"], p1=sig["p1"],
                                  p2=sig["p2"])
        # parameters the steady-state map depends on
        ss_free: list[str] = []
        if len(pts):
            fmap = SteadyStateMap(model, free)
            ref = float(np.sqrt(np.mean(pts.F**2))) or 1.0
            dead = self.insensitive(lambda vals: fmap(pts, {k: vals[k] for k in free})[1],
                                    free, start, ref)
            ss_free = [n for n in free if n not in dead]
        names = ss_free + (["offset"] if s.offset else [])
        if len(pts) < 3 * len(names) or not names:
            if required:
                raise FcompError(
                    f"{d.label}: only {len(pts)} steady-state force-velocity points for "
                    f"{len(names)} parameters (need steady runs of at least "
                    f"{s.min_duration} s above {self.v_min:.3g} m/s); use method 'samples'")
            return None
        _, Gs = SteadyStateMap(model, ss_free)(pts, {k: start[k] for k in ss_free})
        if s.offset:
            Gs = np.hstack([Gs, np.ones((len(pts), 1))])
        scales = self.scales(names, start, Gs, pts.F)
        pv = ParameterVector.build(names, start, self.specs(model, names, start), scales)
        budget = s.max_nfev if final else min(s.max_nfev, 60)
        res = fit_steady_state(model, pts, pv, max_nfev=budget, level=s.confidence)
        self.stages.append({"stage": "steady-state", "parameters": names,
                            "points": len(pts), "rms": res.rms,
                            "evaluations": res.solution.nfev,
                            "converged": res.solution.converged})
        if final:
            self.not_identifiable += [n for n in free if n not in ss_free]
            return pv, res.solution, res.uncertainty
        if res.solution.converged:  # keep only well-determined values (stderr < 50 %)
            for n, se in zip(names, res.uncertainty.stderr, strict=True):
                if se < 0.5 * abs(res.values[n]):
                    start[n] = res.values[n]
        return None

    def _solve(self, model: FrictionModel, pv: ParameterVector, mask: np.ndarray,
               max_nfev: int) -> tuple[Solution, RecordsProblem]:
        return solve_records(model, [Record(self.data, mask)], pv, max_nfev=max_nfev,
                             substeps=self.settings.substeps, dependent=self.deps)

    def trajectory_stage(self, model: FrictionModel, free: list[str], extras: list[str],
                         start: dict[str, float], mask: np.ndarray, method: str, *,
                         max_nfev: int | None = None) -> FitOutcome:
        """The model along the record against the target over ``mask`` (module docstring);
        ``method`` names the stage and the outcome's method."""
        s, d = self.settings, self.data
        budget = max_nfev or s.max_nfev
        names = free + extras
        probe_pv = ParameterVector.build(names, start, self.specs(model, names, start))
        probe = RecordsProblem(model, [Record(d, mask)], probe_pv, substeps=s.substeps,
                               dependent=self.deps)

        def jacobian_at(vals: Mapping[str, float]) -> np.ndarray:
            G = probe(np.array([vals[n] for n in probe_pv.names]), True)[1]
            if G is None:
                raise RuntimeError("the trajectory problem returned no Jacobian")
            return G

        ref = float(np.sqrt(np.mean(d.y[mask] ** 2))) or 1.0
        dead = [n for n in self.insensitive(jacobian_at, names, start, ref) if n not in EXTRAS]
        if dead:
            self.not_identifiable += dead
            names = [n for n in names if n not in dead]
        if not names:
            raise FcompError(f"{d.label}: the record determines none of the parameters of "
                             f"{model.describe()}")
        G = jacobian_at(start)[:, [j for j, n in enumerate(probe_pv.names) if n in names]]
        scales = self.scales(names, start, G, d.y[mask])
        pv = ParameterVector.build(names, start, self.specs(model, names, start), scales)
        sol, prob = self._solve(model, pv, mask, budget)
        unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=s.confidence)
        self.record_stage(method, pv, sol)
        while not sol.converged:  # hold what the record barely determines, refit the rest
            held = self.undetermined(pv, sol, unc)
            if not held:
                break
            reached = dict(zip(pv.names, map(float, sol.theta), strict=True))
            model = model.with_params(**{n: reached[n] for n in held})
            keep = [n for n in pv.names if n not in held]
            pv = ParameterVector.build(keep, reached, self.specs(model, keep, {
                **model.flat_params(), **reached}), {n: pv.scale[pv.index(n)] for n in keep})
            sol, prob = self._solve(model, pv, mask, budget)
            unc = estimate(sol.jacobian, sol.residuals, sol.theta, level=s.confidence)
            self.not_identifiable += held
            self.record_stage(f"{method}, {', '.join(held)} held", pv, sol)
        return self.finish(model, mask, pv, sol, unc, method, prob)

    def record_stage(self, name: str, pv: ParameterVector, sol: Solution) -> None:
        """Record a least-squares stage in :attr:`stages`."""
        self.stages.append({"stage": name, "parameters": list(pv.names),
                            "rms": float(np.sqrt(np.mean(sol.residuals**2))),
                            "evaluations": sol.nfev, "converged": sol.converged})

    def undetermined(self, pv: ParameterVector, sol: Solution, unc: Uncertainty) -> list[str]:
        """Model parameters a stopped solve barely determines: standard error above
        :data:`HOLD_RELATIVE_ERROR` times ``max(|value|, scale)`` (none of ``mass``,
        ``offset`` or the parameters tied by an equality); empty if that would leave
        nothing to fit."""
        tied = self._tied()
        mag = np.maximum(np.abs(sol.theta), pv.scale)
        weak = [n for n, se, m in zip(pv.names, unc.stderr, mag, strict=True)
                if not se <= HOLD_RELATIVE_ERROR * m and n not in EXTRAS and n not in tied]
        return weak if len(weak) < len(pv.names) else []

    # --------------------------------------------------------------- results
    def finish(self, model: FrictionModel, mask: np.ndarray, pv: ParameterVector,
               sol: Solution, unc: Uncertainty, method: str,
               prob: RecordsProblem | None) -> FitOutcome:
        """The outcome at the solution ``sol`` (module docstring)."""
        s, d = self.settings, self.data
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
                           level=s.confidence, autocorrelated=method != "steady-state")
        self.not_identifiable += bad
        values = dict(zip(names, map(float, theta), strict=True))
        model_values = {k: v for k, v in values.items() if k not in EXTRAS}
        for dep in self.deps:
            model_values[dep.name] = dep.value(model_values)
        try:
            fitted = model.with_params(**model_values)
        except ValueError as exc:
            raise ConvergenceError(f"{d.label}: the fit ended on invalid parameters ({exc})") \
                from None
        est = [n for n in names if n not in bad]
        if prob is None:  # the steady-state fit: the record's force error over moving samples
            prob = RecordsProblem(model, [Record(d, mask)], pv, substeps=s.substeps,
                                  dependent=self.deps)
        F_hat = prob.predict(theta)
        r = d.y[mask] - F_hat[mask]
        specs = self.specs(model, est, {**model.flat_params(), **values})
        out = FitOutcome(
            model=fitted,
            params={n: values[n] for n in est},
            stderr={n: float(se) for n, se in zip(est, unc.stderr, strict=True)},
            ci={n: (float(lo), float(hi))
                for n, lo, hi in zip(est, unc.ci_low, unc.ci_high, strict=True)},
            units={n: u for n, u in zip(names, pv.units, strict=True) if n in est},
            cov=unc.cov, param_names=est, rms=float(np.sqrt(np.mean(r**2))),
            converged=sol.converged, message=sol.message, fixed={},
            not_identifiable=list(self.not_identifiable),
            at_bound=[n for n, a in zip(names, sol.at_bound, strict=True) if a and n in est],
            method=method, n_samples=int(mask.sum()), n_eff=unc.n_eff, tau_int=unc.tau_int,
            nfev=sum(st["evaluations"] for st in self.stages), v_min=self.v_min,
            stages=list(self.stages), target=d.source, uncertainty=unc,
            bounds={n: (specs[n].lower, specs[n].upper) for n in est},
            extras={k: values[k] for k in EXTRAS if k in values},
            failure=(f"{d.label}: fitting {model.describe()} did not converge ({sol.message}; "
                     f"{sol.nfev} evaluations); try holding parameters ({term('fixed')}) or a longer, "
                     "richer record"))
        self._add_dependent(out, est, unc, model_values)
        out.fixed = {k: float(v) for k, v in fitted.flat_params().items()
                     if k not in out.params}
        return out

    def _add_dependent(self, out: FitOutcome, est: list[str], unc: Uncertainty,
                       values: Mapping[str, float]) -> None:
        """Report parameters tied by equalities, with the propagated standard error."""
        conf = self.settings.confidence
        for dep in self.deps:
            c = np.array([dep.coef.get(n, 0.0) for n in est])
            var = float(c @ unc.cov @ c) if c.any() else 0.0
            se = math.sqrt(max(var, 0.0)) if math.isfinite(var) else math.inf
            q = float(stdtrit(max(unc.n_eff - len(est), 1.0), 0.5 + conf / 2.0))
            val = values[dep.name]
            out.params[dep.name] = val
            out.stderr[dep.name] = se
            out.ci[dep.name] = (val - q * se, val + q * se)
            out.units[dep.name] = out.model.param_specs()[dep.name].unit
