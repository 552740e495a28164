"""Fit strategies: how a model is identified, one class per kind of model, one interface.

A strategy chains the stages of the fitting engine (:mod:`.engine`) for the
models it suits and returns a :class:`~.engine.FitOutcome`;
:class:`~.estimator.FrictionFit` takes one (``strategy=``, pluggable as
pysindy's optimizers are) or picks it from the model's capabilities
(:func:`strategy_for`):

:class:`StaticStrategy` (models without states: static maps)
    seed 002's steady-state characteristic (``method_ = "steady-state"``)
    where the record holds enough steady points and no mass is estimated,
    else every moving sample (``"samples"``);
:class:`TrajectoryStrategy` (models whose memory is their continuous states)
    the steady-state characteristic as a start (``method="auto"``), then the
    model simulated along the whole record, exact sensitivities
    (``"trajectory"``);
:class:`DiscreteMemoryStrategy` (models with discrete memory: seed 000's new model)
    the carrier model (the NMLGM part) by :class:`TrajectoryStrategy`, the
    segment parameters ``c_i, k_i`` of the hysteresis function from the
    record's transition curves (:mod:`.hysteresis_fit`), then refined by the
    same trajectory stage as every model, its gradient by finite differences
    (the gradient strategy the capability gives,
    :mod:`.dynamic`); ``"trajectory+transition-curves"``.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np
from scipy.linalg import block_diag

from fcomp.errors import ConvergenceError, FcompError
from fcomp.identification.dynamic import EXTRAS
from fcomp.identification.engine import SEGMENT_NAMES, FitJob, FitOutcome
from fcomp.identification.hysteresis_fit import fit_hysteresis
from fcomp.identification.target import FitData
from fcomp.models.base import FrictionModel
from fcomp.trajectory import friction_along_motion

#: Evaluation budget of the finite-difference refinement of the hysteresis segments
#: (each evaluation costs one simulation per parameter).
HYSTERESIS_REFINE_NFEV = 50


class FitStrategy(ABC):
    """How a kind of model is identified from one record (module docstring).

    A strategy is stateless: :meth:`fit` runs it on a :class:`~.engine.FitJob`
    (the model, the record, the settings) and returns the outcome.
    """

    #: the strategy's name (``"static"``, ``"trajectory"``, ``"discrete-memory"``)
    name: ClassVar[str] = ""

    @classmethod
    @abstractmethod
    def suits(cls, model: FrictionModel) -> bool:
        """Whether the strategy is the one for ``model`` (by its capabilities)."""

    @abstractmethod
    def fit(self, job: FitJob) -> FitOutcome:
        """Identify ``job.model`` from ``job.data`` with ``job.settings``."""


class StaticStrategy(FitStrategy):
    """Static maps: the steady-state characteristic, else every moving sample."""

    name = "static"

    @classmethod
    def suits(cls, model: FrictionModel) -> bool:
        return model.n_states == 0

    def fit(self, job: FitJob) -> FitOutcome:
        model, d, method = job.model, job.data, job.settings.method
        free, extras, start = job.prepare()
        if method == "trajectory":
            raise FcompError(f"{model.describe()} is a static map: use method 'auto', "
                             "'steady-state' or 'samples'")
        moving = np.abs(d.sig["v"]) >= job.v_min
        if method == "steady-state" or (method == "auto" and d.inertia is None):
            done = job.static_stage(model, free, start, required=method == "steady-state",
                                    final=True)
            # auto: the steady-state characteristic only where it determines every parameter
            if done is not None and (method == "steady-state" or (
                    done[1].converged and bool(np.all(done[2].identifiable)))):
                return job.finish(model, moving, *done, "steady-state", None)
            job.not_identifiable = []
        return job.trajectory_stage(model, free, extras, start, moving, "samples")


class TrajectoryStrategy(FitStrategy):
    """Models whose memory is their continuous states: steady-state start, then trajectory."""

    name = "trajectory"

    @classmethod
    def suits(cls, model: FrictionModel) -> bool:
        return model.n_states > 0 and model.discrete_memory() is None

    def fit(self, job: FitJob) -> FitOutcome:
        model, method = job.model, job.settings.method
        free, extras, start = job.prepare()
        if method in ("steady-state", "samples"):
            raise FcompError(f"{model.describe()} is dynamic: use method 'auto' or 'trajectory'")
        if method == "auto":
            job.static_stage(model, free, start, required=False, final=False)
        return job.trajectory_stage(model, free, extras, start,
                                    np.ones(job.data.n, dtype=bool), "trajectory")


class DiscreteMemoryStrategy(FitStrategy):
    """Models with discrete memory: carrier, transition curves, finite-difference refinement."""

    name = "discrete-memory"

    @classmethod
    def suits(cls, model: FrictionModel) -> bool:
        return model.discrete_memory() is not None

    def fit(self, job: FitJob) -> FitOutcome:
        model, d, s = job.model, job.data, job.settings
        memory = model.discrete_memory()
        if memory is None:
            raise FcompError(f"{model.describe()} has no discrete memory: "
                             f"use the {TrajectoryStrategy.name} strategy")
        free = job.free_names(model)
        seg = [n for n in free if n in SEGMENT_NAMES]
        carrier = memory.carrier()
        cflat = carrier.flat_params()
        cfree = [n for n in free if n in cflat]
        sub: FitOutcome | None = None
        if cfree or job.extras:  # the carrier (the NMLGM part): exact sensitivities
            csettings = dataclasses.replace(
                s, free=cfree, fixed=None,
                initial={k: v for k, v in (s.initial or {}).items() if k in cflat or k in EXTRAS})
            sub = strategy_for(carrier).fit(FitJob(csettings, carrier, d))
            cvals, ext = sub.model.flat_params(), dict(sub.extras)
        else:
            cvals, ext = dict(cflat), {}
        f = d.y - ext.get("offset", 0.0)
        if "mass" in ext and d.inertia is not None:
            f = f - ext["mass"] * d.inertia
        hmodel = model.with_params(**cvals)
        values = hmodel.flat_params()
        specs = hmodel.param_specs()
        stages = list(sub.stages) if sub else []
        not_ident = list(sub.not_identifiable) if sub else []
        hyst_names: list[str] = []
        seg_block: FitOutcome | None = None
        if seg:  # segment parameters from the transition curves
            hf = fit_hysteresis(d.sig["x"], f, values, specs, free=seg, max_nfev=s.max_nfev,
                                level=s.confidence, label=d.label)
            stages.append({"stage": "transition-curves", "parameters": hf.names,
                           "curves": hf.curves, "rms": hf.rms,
                           "evaluations": hf.solution.nfev, "converged": hf.solution.converged})
            not_ident += hf.not_identifiable
            values.update(hf.values)
            hyst_names = hf.names
        fd = FitData(d.sig, f, None, d.source, d.mass, d.label)
        hmodel = hmodel.with_params(**{n: values[n] for n in hyst_names})
        if hyst_names and s.refine_hysteresis:  # the common trajectory stage, FD gradient
            rjob = FitJob(dataclasses.replace(s, offset=False, free=hyst_names), hmodel, fd)
            seg_block = rjob.trajectory_stage(
                hmodel, list(hyst_names), [], values, np.ones(d.n, dtype=bool),
                "hysteresis-trajectory", max_nfev=min(s.max_nfev, HYSTERESIS_REFINE_NFEV))
            stages += rjob.stages
            not_ident += [n for n in seg_block.not_identifiable if n not in not_ident]
            hmodel = seg_block.model
        elif hyst_names:  # the transition curves' own estimates
            unc = hf.uncertainty
            keep = [j for j, ok in enumerate(unc.identifiable) if ok]
            not_ident += [hyst_names[j] for j, ok in enumerate(unc.identifiable) if not ok]
            try:
                hmodel = hmodel.with_params(**hf.values)
            except ValueError as exc:
                raise ConvergenceError(f"{d.label}: the fit ended on invalid parameters "
                                       f"({exc})") from None
            names = [hyst_names[j] for j in keep]
            seg_block = FitOutcome(
                model=hmodel, params={n: hf.values[n] for n in names},
                stderr={n: float(unc.stderr[j]) for n, j in zip(names, keep, strict=True)},
                ci={n: (float(unc.ci_low[j]), float(unc.ci_high[j]))
                    for n, j in zip(names, keep, strict=True)},
                units={n: specs[n].unit for n in names}, cov=unc.cov[np.ix_(keep, keep)],
                param_names=names, rms=hf.rms, converged=hf.solution.converged,
                message=hf.solution.message, fixed={}, not_identifiable=[], at_bound=[],
                method="transition-curves", n_samples=d.n, n_eff=unc.n_eff,
                tau_int=unc.tau_int, nfev=hf.solution.nfev, v_min=job.v_min, stages=[],
                target=d.source, uncertainty=unc, bounds={})
        return _merge(model, d, job, sub, seg_block, hmodel, stages, not_ident, ext,
                      {n: (specs[n].lower, specs[n].upper) for n in hyst_names}, s.substeps)


def _merge(model: FrictionModel, d: FitData, job: FitJob, sub: FitOutcome | None,
           seg: FitOutcome | None, fitted: FrictionModel, stages: list, not_ident: list[str],
           ext: dict[str, float], seg_bounds: dict[str, tuple[float, float]],
           substeps: int) -> FitOutcome:
    """The carrier's results, then the segment parameters' (block-diagonal covariance: the
    segment errors are conditional on the carrier values)."""
    params: dict[str, float] = {}
    stderr: dict[str, float] = {}
    ci: dict[str, tuple[float, float]] = {}
    units: dict[str, str] = {}
    covs = []
    for block in (sub, seg):
        if block is not None:
            params.update(block.params)
            stderr.update(block.stderr)
            ci.update(block.ci)
            units.update(block.units)
            covs.append(block.cov)
    converged = (seg.converged if seg else True) and (sub.converged if sub else True)
    message = "; ".join(m for m in ((sub.message if sub else ""),
                                    (seg.message if seg else "")) if m)
    F = friction_along_motion(fitted, d.sig["t"], d.sig["v"], a=d.sig["a"], x=d.sig["x"],
                              p1=d.sig["p1"], p2=d.sig["p2"], substeps=substeps).F
    unc = seg.uncertainty if seg else None
    return FitOutcome(
        model=fitted, params=params, stderr=stderr, ci=ci, units=units,
        cov=block_diag(*covs) if covs else np.zeros((0, 0)), param_names=list(params),
        rms=float(np.sqrt(np.mean((d.y - ext.get("offset", 0.0)
                                   - (ext["mass"] * d.inertia
                                      if "mass" in ext and d.inertia is not None else 0.0)
                                   - F) ** 2))),
        converged=converged, message=message,
        fixed={k: float(v) for k, v in fitted.flat_params().items() if k not in params},
        not_identifiable=not_ident, at_bound=list(sub.at_bound) if sub else [],
        method="trajectory+transition-curves", n_samples=d.n,
        n_eff=sub.n_eff if sub else (unc.n_eff if unc else float(d.n)),
        tau_int=sub.tau_int if sub else (unc.tau_int if unc else 1.0),
        nfev=sum(st["evaluations"] for st in stages), v_min=sub.v_min if sub else job.v_min,
        stages=stages, target=d.source, uncertainty=unc,
        bounds={**(sub.bounds if sub else {}), **seg_bounds}, extras=ext,
        failure=f"{d.label}: fitting {model.describe()} did not converge ({message})")


#: The strategies, asked in order which one suits a model.
STRATEGIES: tuple[type[FitStrategy], ...] = (
    DiscreteMemoryStrategy, StaticStrategy, TrajectoryStrategy)


def strategy_for(model: FrictionModel) -> FitStrategy:
    """The strategy that suits ``model`` (by its capabilities, :data:`STRATEGIES` in order)."""
    for cls in STRATEGIES:
        if cls.suits(model):
            return cls()
    raise FcompError(f"no fit strategy suits model {model.describe()!r}")
