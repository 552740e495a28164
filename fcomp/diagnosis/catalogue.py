"""The effect catalogue as a diagnosis sees it: candidates, applicability, starting values.

Every registered effect (:data:`fcomp.effects.EFFECTS`: the catalogue of
models.md 1.8 and the user's own) is a candidate, and every one is treated
through the same interface: the diagnosis hooks of
:class:`~fcomp.effects.Effect` (its module docstring is the contract). This
module holds no table and no case of any effect by name; what is particular
to an effect sits on its class, in its own module of :mod:`fcomp.effects`
(:mod:`fcomp.effects.catalogue` lists them) or the user's module. For each candidate this module says

* whether it applies to the current model and to the data
  (:func:`applicability`): the effect must change the model
  (:meth:`~fcomp.effects.Effect.applies_to`), the signals it ``needs`` must be
  measured and informative, steady-state points admit only effects that are
  not ``dynamic`` (and have no ``states``), and the effect itself may say why
  the record cannot show it (:meth:`~fcomp.effects.Effect.unsuitable`: a fitted
  mass for a mass error, no start after a dwell for an ageing at rest);
* what residual signature it explains and which experiment isolates it (the
  effect's ``signature`` and ``experiment``), and its physics (the effect
  class docstring), for reports (:func:`describe`);
* where its refit starts (:func:`propose`, one proposal per form of
  :meth:`~fcomp.effects.Effect.diagnosis_forms`): the effect configured for
  the record (:meth:`~fcomp.effects.Effect.diagnosis_config`), its
  *data-driven guesses* of the new parameters read off the current residual
  ``r = y - F_hat`` and the motion (:meth:`~fcomp.effects.Effect.guess`, on a
  :class:`~fcomp.effects.record.RecordView` built here by :func:`record_view`),
  warm and fresh starts of the model's other parameters, and the parameters
  held at their no-op values (the form's ``held`` and
  :meth:`~fcomp.effects.Effect.held`). A user's effect without hooks starts
  from its defaults.

Guesses only start the refit; every parameter of the model is refitted.
:func:`baseline_starts` reads the starts of the baseline fit off the data.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType
from typing import Any

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.refit import RIG_EXTRAS, FitResult
from fcomp.diagnosis.regimes import Segmentation
from fcomp.effects import EFFECTS, Effect, make_effect
from fcomp.effects.record import DiagnosisForm, RecordView, stribeck_hump_start
from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel


@dataclass(frozen=True)
class Context:
    """What a guess reads: the record, its regimes, the training samples, the current fit."""

    data: DiagnosisData
    seg: Segmentation
    train: np.ndarray
    current: FitResult

    @cached_property
    def view(self) -> RecordView:
        """The record and the current fit as the effects' hooks read them."""
        return record_view(self)


def record_view(ctx: Context) -> RecordView:
    """The :class:`~fcomp.effects.record.RecordView` of a context (what an effect's hooks read)."""
    data, seg, current = ctx.data, ctx.seg, ctx.current
    names = data.experiments[0].data.sig.keys()
    return RecordView(
        signals=MappingProxyType({k: data.signal(k) for k in names}),
        y=data.y, F_hat=current.F_hat, train=ctx.train,
        residual=current.located,
        params=MappingProxyType(dict(current.model.flat_params())),
        values=MappingProxyType(dict(current.values)),
        scales=data.scales, v_rest=seg.v_rest, d_pre=seg.d_pre, t_dwell=seg.t_dwell,
        dwell_starts=tuple((k, dw) for k, dw, _ in seg.starts if dw >= seg.t_dwell),
        fits_mass=data.fits_mass, steady_state=data.steady_state,
        available=MappingProxyType(dict(data.available)),
        reasons=MappingProxyType(dict(data.reasons)), source=data.source,
        force_channels=data.force_channels)


@dataclass(frozen=True)
class Proposal:
    """A candidate model and the starts of its refit (flat values of that model).

    ``free`` lists the parameters to refit (``None``: all of them); models
    without exact sensitivities (discrete memory) refit a reduced set.
    """

    effect: str
    model: FrictionModel
    starts: list[dict[str, float]]
    free: list[str] | None = None
    form: str | None = None


def describe(name: str) -> dict[str, str]:
    """Signature, experiment and physics (class docstring) of a registered effect."""
    cls = EFFECTS.get(name)
    doc = (cls.__doc__ or "").strip()
    return {"effect": name, "signature": cls.signature, "experiment": cls.experiment,
            "physics": " ".join(doc.split())}


#: Signals a steady-state point lacks whatever the record holds: an effect that reads
#: one is judged on the motion first (a steady-state record: "needs a motion").
_MOTION_SIGNALS = {"a": "an acceleration"}


def applicability(name: str, ctx: Context) -> str | None:
    """``None`` if effect ``name`` is a candidate for the current model on the record of
    ``ctx``, else why not."""
    model, data = ctx.current.model, ctx.data
    cls = EFFECTS.get(name)
    try:
        probe = cls()
    except (TypeError, ValueError) as exc:
        return f"cannot be built with its defaults ({exc})"
    if not probe.applies_to(model):
        return f"already part of {model.describe()} or not applicable to it"
    for sig in cls.needs:
        if sig not in _MOTION_SIGNALS and not data.available.get(sig, False):
            return f"needs {sig}: {data.reasons.get(sig, 'not available')}"
    if data.steady_state and (cls.dynamic or bool(cls.states)):
        return "needs a motion (the data are steady-state points)"
    for sig in cls.needs:
        if sig in _MOTION_SIGNALS and not data.available.get(sig, False):
            return f"needs {_MOTION_SIGNALS[sig]}: {data.reasons.get(sig, 'none')}"
    try:
        effect = configured(name, data)
    except ValueError as exc:
        return str(exc).split("\n")[0]
    reason = effect.unsuitable(ctx.view)
    if reason is not None:
        return reason
    try:
        model.with_effects(effect)
    except ValueError as exc:
        return str(exc).split("\n")[0]
    return None


def configured(name: str, data: DiagnosisData, params: dict[str, float] | None = None,
               **config: Any) -> Effect:
    """The effect ``name`` configured for the record (its
    :meth:`~fcomp.effects.Effect.diagnosis_config`, then ``config``), with ``params``
    (default: its defaults)."""
    cls = EFFECTS.get(name)
    return make_effect(name, params or None, **{**cls.diagnosis_config(data.scales), **config})


def form_of(name: str, form: str | None) -> DiagnosisForm:
    """The form of effect ``name`` labelled ``form`` (:meth:`~fcomp.effects.Effect.diagnosis_forms`);
    a label it does not list is taken as its configuration ``form``."""
    cls = EFFECTS.get(name)
    for f in (*cls.diagnosis_forms(), *cls.refined_forms()):
        if f.name == form:
            return f
    return DiagnosisForm(form, {"form": form} if form is not None else {})


def attach(model: FrictionModel, name: str, data: DiagnosisData, form: str | None = None
           ) -> FrictionModel:
    """``model`` with the effect ``name`` (in ``form``) at its defaults, configured for the
    record."""
    return model.with_effects(configured(name, data, None, **form_of(name, form).config))


def propose_all(name: str, ctx: Context) -> list[Proposal]:
    """One :func:`propose` per form of the effect (its
    :meth:`~fcomp.effects.Effect.forms_for` the current model; one for most)."""
    return [propose(name, ctx, form=f.name)
            for f in EFFECTS.get(name).forms_for(ctx.current.model)]


def propose(name: str, ctx: Context, form: str | None = None) -> Proposal:
    """The candidate ``current model + name`` (in ``form``) with the starts of its refit."""
    model = ctx.current.model
    shape = form_of(name, form)
    effect = configured(name, ctx.data, None, **shape.config)
    alternatives = effect.guess(ctx.view, form)
    own_names = set(EFFECTS.get(name).Params.from_flat({}).flat())
    models = [model.with_effects(configured(
        name, ctx.data, {k: v for k, v in p.items() if k in own_names}, **shape.config))
        for p in alternatives]
    # a guess may also move parameters of the model itself (a stiffer bristle)
    starts = [{**m.flat_params(), **{k: v for k, v in p.items()
                                     if k not in own_names and k in m.flat_params()}}
              for m, p in zip(models, alternatives, strict=True)]
    # the same effect guess on a fresh start of the other parameters: the warm
    # start may sit in a local minimum the missing effect pushed it into
    base = models[0]
    own = {k: v for k, v in type(base.params)().flat().items() if k in base.params.flat()}
    # every variant of the levels (a hump, none, one below every sliding speed): a
    # warm start without the hump and a fresh one of the same kind can both miss it
    # (a pressure law refitted to 3.4 N from both, 0.45 N from the hump's start)
    freshes = []
    for var in baseline_starts(base, ctx.data, ctx.seg, ctx.train, stiffness=(1.0,)):
        fr = {**own, **var}
        freshes.append({k: v for k, v in fr.items() if k in starts[0]
                        and k not in alternatives[0] and math.isfinite(v)})
    fresh = freshes[0]
    # parameters the current fit pushed to a bound of their box were likely bent by the
    # missing effect: the warm starts take their fresh values instead
    for st in starts:
        st.update({k: fresh[k] for k in _at_bound(ctx, st) if k in fresh})
    starts += [{**starts[0], **fr} for fr in freshes]
    rig = {k: ctx.current.values[k] for k in RIG_EXTRAS if k in ctx.current.values}
    for s in starts:
        s.update(rig)
    held = [*effect.held(ctx.view), *shape.held]
    free = None
    if held:
        from fcomp.diagnosis.refit import fixed_names
        from fcomp.identification.estimator import default_free

        fixed = fixed_names(models[0])
        free = [n for n in default_free(models[0]) if n not in fixed and n not in held]
        free += [k for k in RIG_EXTRAS if k in ctx.current.values]
        # the effect's own defaults (a structural effect leaves no effect object behind:
        # its terms are features of the family, and Dahl's exponent is a no-op at 1, not 0)
        noop = dict(effect.Params().flat())
        if models[0].effects:
            noop.update(models[0].effects[-1].Params().flat())
        for st in starts:  # a held term stays at its no-op value
            st.update({n: noop.get(n, 0.0) for n in held})
    return Proposal(name, models[0], starts, free, form=form)


def held_of(name: str, form: str | None, ctx: Context) -> list[str]:
    """What effect ``name`` in ``form`` holds on the record of ``ctx``: its
    :meth:`~fcomp.effects.Effect.held` parameters and its form's."""
    shape = form_of(name, form)
    try:
        effect = configured(name, ctx.data, None, **shape.config)
        return [*effect.held(ctx.view), *shape.held]
    except (FcompError, ValueError, KeyError):
        return list(shape.held)


def _at_bound(ctx: Context, values: dict[str, float]) -> list[str]:
    """Names of the current fit's parameters that sit on a bound of their data box."""
    from fcomp.diagnosis.boxes import data_bounds

    model = ctx.current.model
    out = []
    for n, sp in model.param_specs().items():
        if n not in ctx.current.values or n not in values:
            continue
        lo, hi = data_bounds(sp, ctx.data.scales, ctx.seg.d_pre)
        v = ctx.current.values[n]
        span = hi - lo if math.isfinite(hi - lo) else max(abs(v), 1.0)
        if v <= lo + 1e-6 * span or v >= hi - 1e-6 * span:
            out.append(n)
    return out


# ------------------------------------------------------------------ baseline
def baseline_starts(model: FrictionModel, data: DiagnosisData, seg: Segmentation,
                    train: np.ndarray, stiffness: Sequence[float] = (1.0, 4.0)
                    ) -> list[dict[str, float]]:
    """Starts of the baseline fit, read off the training samples.

    Levels and the viscous coefficient by linear least squares on the sliding
    samples (:func:`fcomp.identification.guess.linear_start`), the Stribeck
    hump (:func:`~fcomp.effects.record.stribeck_hump_start`, and once more with
    ``vs`` at the lowest sliding speed ``v_min``: a Stribeck speed below every
    speed the record slides at leaves no hump in the sliding samples, only at
    break-away), then the steady-state map fitted to the steady sliding points
    (:func:`_static_stage`, seed 002's procedure), the bristle stiffness
    ``Fc/d_pre`` from the presliding length times each of ``stiffness`` (by
    default two starts, a factor of four apart), a small bristle damping (its term a tenth of ``Fc`` at the
    median speed), the film speed ``vb`` ten times the speed scale (almost the
    classical curve); everything else from the model's defaults.
    """
    from fcomp.diagnosis.regimes import SLIDING
    from fcomp.identification.guess import linear_start
    from fcomp.identification.target import FitData

    flat = dict(model.flat_params())
    use = train & (seg.regime == SLIDING)  # no presliding / reversal / break-away transients
    if use.sum() < 20:
        use = train
    sig = {k: data.signal(k)[use] for k in ("t", "v", "a", "x", "p1", "p2", "s")}
    inertia = None
    if data.fits_mass:
        inertia = np.concatenate([e.data.inertia for e in data.experiments])[use]
    d = FitData(sig, data.y[use], inertia, data.source, None, "training samples")
    names = {n.removesuffix("_pos").removesuffix("_neg") for n in flat}
    visc = "B" if "B" in names else ("sigma2" if "sigma2" in names else None)
    v_min = max(seg.v_rest, 0.02 * data.scales.speed)
    ls = linear_start(d, v_min, offset=False, directional=False, viscous=visc is not None)
    Fc = float(ls.Fc[0])
    start: dict[str, float] = {}

    def put(name: str, value: float) -> None:
        if name in flat:
            start[name] = value
        elif name + "_pos" in flat:
            start[name + "_pos"] = start[name + "_neg"] = value

    put("Fc", Fc)
    if visc is not None:
        put(visc, float(ls.B[0]))
    if ls.mass is not None:
        start["mass"] = ls.mass
    if "Fs" in names:
        Fs, vs = stribeck_hump_start(d.sig["v"], ls.friction, Fc, float(ls.B[0]), v_min)
        put("Fs", max(Fs, Fc))
        put("vs", vs)
    if "vb" in names:
        put("vb", 10.0 * data.scales.speed)
    if "sigma1" in names:
        moving = np.abs(d.sig["v"]) >= v_min
        med = float(np.median(np.abs(d.sig["v"][moving]))) if moving.any() else data.scales.speed
        put("sigma1", 0.1 * Fc / med)
    static = _static_stage(model, data, seg, train, start, v_min)
    variants = [dict(start, **static), start] if static else [start]
    if start.get("vs", start.get("vs_pos", 0.0)) > 2.0 * v_min:
        # a hump below every sliding speed of the record shows only at break-away
        variants.append({k: v_min if k in ("vs", "vs_pos", "vs_neg") else v
                         for k, v in start.items()})
    if "sigma0" not in names:
        return variants
    out = []
    for k in stiffness:
        for var in variants:
            out.append(dict(var, sigma0=k * var.get("Fc", Fc) / seg.d_pre))
    return out


def _static_stage(model: FrictionModel, data: DiagnosisData, seg: Segmentation,
                  train: np.ndarray, start: dict[str, float], v_min: float
                  ) -> dict[str, float]:
    """The model's own steady-state parameters fitted to the steady sliding points (seed 002).

    Steady runs of the training samples are binned by speed per direction
    (:func:`fcomp.identification.static.steady_state_points`) and the model's
    steady-state map is fitted to them (:func:`~fcomp.identification.static.fit_steady_state`)
    in the parameters it depends on (but the exponent ``n``, see
    :data:`fcomp.diagnosis.refit.STAGED`); effect parameters keep their values.
    Returns the fitted values (empty when there are too few points).
    """
    from fcomp.diagnosis.boxes import data_bounds
    from fcomp.diagnosis.refit import fixed_names
    from fcomp.identification.problem import ParameterVector
    from fcomp.identification.static import SteadyStateMap, fit_steady_state, steady_state_points

    if not model.symbolic:
        return {}
    from fcomp.diagnosis.refit import STAGED
    from fcomp.identification.problem import base_name

    own = [n for n in model.params.flat() if n not in fixed_names(model)
           and math.isfinite(model.params.flat()[n]) and base_name(n) not in STAGED]
    from fcomp.identification.static import SteadyStatePoints

    def points(min_duration: float, rel_change: float) -> SteadyStatePoints:
        found = []
        for e in data.experiments:
            m = train[e.start:e.stop]
            s = e.data.sig
            if m.sum() >= 10:
                found.append(steady_state_points(
                    s["t"][m], s["v"][m], s["a"][m], e.data.y[m], v_min=v_min,
                    min_duration=min_duration, rel_change=rel_change, x=s["x"][m],
                    p1=s["p1"][m], p2=s["p2"][m]))
        found = [p for p in found if len(p)]
        if not found:
            return SteadyStatePoints(*[np.zeros(0)] * 6)
        return SteadyStatePoints(*[np.concatenate([getattr(p, f) for p in found])
                                   for f in ("v", "F", "count", "x", "p1", "p2")])

    def distinct(p: SteadyStatePoints) -> int:  # speeds more than 20 % apart, per side
        key = np.sign(p.v) * np.round(np.log(np.maximum(np.abs(p.v), 1e-12)) / 0.2)
        return int(np.unique(key).size)

    if data.steady_state:  # every sample is a steady-state point
        v = data.signal("v")[train]
        keep = v != 0
        pts = SteadyStatePoints(v[keep], data.y[train][keep], np.ones(int(keep.sum())),
                                data.signal("x")[train][keep], data.signal("p1")[train][keep],
                                data.signal("p2")[train][keep])
    else:
        pts = points(0.05, 0.1)
        if distinct(pts) < 8:  # few steady runs: admit slower-changing stretches too
            pts = points(max(10 * data.scales.dt, 0.02), 0.3)
    if len(pts) == 0:
        return {}
    values = {**model.flat_params(), **start}
    try:
        _, G = SteadyStateMap(model, own)(pts, {k: values[k] for k in own})
    except (ValueError, FcompError):
        return {}
    norm = np.sqrt(np.mean(G**2, axis=0)) * np.array([abs(values[n]) or 1.0 for n in own])
    free = [n for n, c in zip(own, norm, strict=True) if c > 1e-9 * max(norm.max(), 1e-300)]
    if distinct(pts) < len(free) + 3 or not free:
        return {}
    specs = {}
    for n, sp in model.param_specs().items():
        if n in free:
            lo, hi = data_bounds(sp, data.scales, seg.d_pre)
            specs[n] = dataclasses.replace(sp, lower=lo, upper=hi, lower_open=False)
    pv = ParameterVector.build(free, values, specs, {n: max(abs(values[n]), 1e-6) for n in free})
    try:
        res = fit_steady_state(model, pts, pv, max_nfev=100)
    except (ValueError, FcompError, np.linalg.LinAlgError):
        return {}
    return {k: float(v) for k, v in res.values.items() if k in free}
