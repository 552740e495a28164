"""The effect catalogue as a diagnosis sees it: signatures, applicability, starting values.

Every registered effect (:data:`fcomp.effects.EFFECTS`: the catalogue of
models.md 1.8 and the user's own) is a candidate. For each one this module
says

* whether it applies to the current model and to the data
  (:func:`applicability`): the effect must change the model
  (:meth:`~fcomp.effects.Effect.applies_to`), the signals it ``needs`` must be
  measured and informative, steady-state points admit only memoryless
  effects, a fitted mass excludes ``inertia-error``, ``dwell-time`` needs
  starts after a dwell;
* what residual signature it explains and which experiment isolates it (the
  effect's ``signature`` and ``experiment``), and its physics (the effect
  class docstring), for reports;
* where its refit starts (:func:`propose`): a *data-driven guess* of the new
  parameters read off the current residual ``r = y - F_hat`` and the motion
  (linear least squares for the additive effects, the low-speed hump for
  ``stribeck``, the presliding length for ``presliding``, the break-away
  peaks against the dwell time for ``dwell-time``, a small grid where a time
  constant or a speed must be found). A user's effect starts from its
  defaults.

Guesses only start the refit; every parameter of the model is refitted.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.regimes import Segmentation
from fcomp.effects import EFFECTS, Effect, make_effect
from fcomp.errors import FcompError
from fcomp.identification.guess import stribeck_start
from fcomp.models.base import FrictionModel

#: Effects that need a motion (memory, acceleration): not for steady-state points.
DYNAMIC_EFFECTS = frozenset({"presliding", "frictional-lag", "dwell-time", "nonlocal-memory",
                             "viscous-lead", "inertia-error"})
#: Effects that read the acceleration.
ACCELERATION_EFFECTS = frozenset({"viscous-lead", "inertia-error"})


@dataclass(frozen=True)
class Context:
    """What a guess reads: the record, its regimes, the training samples, the current fit."""

    data: DiagnosisData
    seg: Segmentation
    train: np.ndarray
    current: FitResult


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


def applicability(name: str, model: FrictionModel, data: DiagnosisData,
                  seg: Segmentation) -> str | None:
    """``None`` if effect ``name`` is a candidate for ``model`` on ``data``, else why not."""
    cls = EFFECTS.get(name)
    try:
        probe = cls()
    except (TypeError, ValueError) as exc:
        return f"cannot be built with its defaults ({exc})"
    if not probe.applies_to(model):
        return f"already part of {model.describe()} or not applicable to it"
    for sig in cls.needs:
        if not data.available.get(sig, False):
            return f"needs {sig}: {data.reasons.get(sig, 'not available')}"
    dynamic = name in DYNAMIC_EFFECTS or bool(cls.states)
    if data.steady_state and dynamic:
        return "needs a motion (the data are steady-state points)"
    if name in ACCELERATION_EFFECTS and not data.available.get("a", False):
        return f"needs an acceleration: {data.reasons.get('a', 'none')}"
    if name == "inertia-error" and data.fits_mass:
        return "the mass is already fitted (no rig.mass): a mass error is part of it"
    if name == "dwell-time" and not _dwell_starts(seg):
        return "the record has no start after a dwell"
    try:
        _attach(model, name, {}, data)
    except ValueError as exc:
        return str(exc).split("\n")[0]
    return None


def _config(name: str, data: DiagnosisData) -> dict[str, Any]:
    if name == "viscous":  # the exponent's reference speed: the record's
        return {"v_ref": data.scales.speed}
    if name == "nonlocal-memory":  # the form with continuous states and exact sensitivities
        return {"form": "maxwell-slip"}
    if name == "position-dependence":
        sc = data.scales
        pad = 0.02 * sc.stroke
        return {"x_min": sc.x_min - pad, "x_max": sc.x_max + pad}
    return {}


def attach(model: FrictionModel, name: str, data: DiagnosisData, form: str | None = None
           ) -> FrictionModel:
    """``model`` with the effect ``name`` (in ``form``) at its defaults, configured for the
    record."""
    return _attach(model, name, {}, data, **({"form": form} if form else {}))


def _attach(model: FrictionModel, name: str, params: dict[str, float],
            data: DiagnosisData, **config: Any) -> FrictionModel:
    effect: Effect = make_effect(name, params or None, **{**_config(name, data), **config})
    return model.with_effects(effect)


#: Effects whose forms the diagnosis refits side by side (the effect's configuration
#: ``form`` where it has one; else a set of parameters held, :data:`HELD`).
FORMS: dict[str, tuple[str, ...]] = {"frictional-lag": ("film", "speed-lag"),
                                     "direction-asymmetry": ("levels", "levels-viscous")}


def propose_all(name: str, ctx: Context) -> list[Proposal]:
    """One :func:`propose` per form of the effect (:data:`FORMS`; one for most)."""
    forms = FORMS.get(name)
    if not forms:
        return [propose(name, ctx)]
    return [propose(name, ctx, form=f) for f in forms]


def propose(name: str, ctx: Context, form: str | None = None) -> Proposal:
    """The candidate ``current model + name`` (in ``form``) with the starts of its refit."""
    model = ctx.current.model
    guess = GUESSES.get(name)
    extra = {"form": form} if form is not None else {}
    alternatives = guess(ctx, **extra) if guess is not None else [{}]
    if name in HELD_BY_FORM:  # forms that only hold parameters are no configuration
        extra = {}
    own_names = set(EFFECTS.get(name).Params.from_flat({}).flat())
    models = [_attach(model, name, {k: v for k, v in p.items() if k in own_names}, ctx.data,
                      **extra)
              for p in alternatives]
    # a guess may also move parameters of the model itself (a stiffer bristle)
    starts = [{**m.flat_params(), **{k: v for k, v in p.items()
                                     if k not in own_names and k in m.flat_params()}}
              for m, p in zip(models, alternatives, strict=True)]
    # the same effect guess on a fresh start of the other parameters: the warm
    # start may sit in a local minimum the missing effect pushed it into
    base = models[0]
    own = {k: v for k, v in type(base.params)().flat().items() if k in base.params.flat()}
    fresh = {**own, **baseline_starts(base, ctx.data, ctx.seg, ctx.train)[0]}
    fresh = {k: v for k, v in fresh.items() if k in starts[0] and k not in alternatives[0]
             and math.isfinite(v)}
    # parameters the current fit pushed to a bound of their box were likely bent by the
    # missing effect: the warm starts take their fresh values instead
    for st in starts:
        st.update({k: fresh[k] for k in _at_bound(ctx, st) if k in fresh})
    starts.append({**starts[0], **fresh})
    if "mass" in ctx.current.values:
        for s in starts:
            s["mass"] = ctx.current.values["mass"]
    held = HELD[name](ctx) if name in HELD else []
    held += list(HELD_BY_FORM.get(name, {}).get(form or "", ()))
    free = None
    if held:
        from fcomp.diagnosis.refit import fixed_names
        from fcomp.identification.estimator import default_free

        fixed = fixed_names(models[0])
        free = [n for n in default_free(models[0]) if n not in fixed and n not in held]
        if "mass" in ctx.current.values:
            free.append("mass")
        noop = models[0].effects[-1].Params().flat() if models[0].effects else {}
        for st in starts:  # a held term stays at its no-op value
            st.update({n: noop.get(n, 0.0) for n in held})
    return Proposal(name, models[0], starts, free, form=form)


def _at_bound(ctx: Context, values: dict[str, float]) -> list[str]:
    """Names of the current fit's parameters that sit on a bound of their data box."""
    from fcomp.diagnosis.refit import data_bounds

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


# ------------------------------------------------------------------ guesses
def _moving(ctx: Context) -> np.ndarray:
    v = ctx.data.signal("v")
    return ctx.train & (np.abs(v) > ctx.seg.v_rest)


def _level(ctx: Context) -> float:
    m = _moving(ctx)
    F = ctx.current.F_hat
    return float(np.median(np.abs(F[m]))) if m.any() else ctx.data.scales.force


def _ls(r: np.ndarray, col: np.ndarray) -> float:
    den = float(col @ col)
    return float(col @ r) / den if den > 0 else 0.0


def _viscous(ctx: Context) -> list[dict[str, float]]:
    m = _moving(ctx)
    c = _ls(ctx.current.residual[m], ctx.data.signal("v")[m])
    sc = ctx.data.scales
    c = c if c > 0 else 0.05 * sc.force / sc.speed
    return [{"sigma2": c}, {"sigma2": c, "p_visc": 0.6}]


def _stribeck(ctx: Context) -> list[dict[str, float]]:
    flat = ctx.current.model.flat_params()
    v = ctx.data.signal("v")
    m = ctx.train
    Fc = flat.get("Fc", flat.get("Fc_pos", _level(ctx)))
    B = flat.get("B", flat.get("sigma2", 0.0))
    Fs, vs = stribeck_start(v[m], ctx.data.y[m], Fc, B, ctx.seg.v_rest)
    exc = max(Fs - Fc, 0.1 * Fc)
    # the exponential form, and the fat-tailed rational one (its form has no gradient at 0)
    return [{"Fs_excess": exc, "vs": vs}, {"Fs_excess": exc, "vs": 4 * vs},
            {"Fs_excess": exc, "vs": vs / 4}, {"Fs_excess": exc, "vs": vs, "kappa_s": 0.7}]


def _presliding(ctx: Context) -> list[dict[str, float]]:
    """The stiffness from the presliding length, a factor of four either side; the bristle
    exponent stiffer and softer than LuGre's."""
    s0 = _level(ctx) / ctx.seg.d_pre
    return [{"sigma0": s0}, {"sigma0": 4 * s0}, {"sigma0": s0 / 4},
            {"sigma0": s0, "i_pre": 0.5}, {"sigma0": s0, "i_pre": 2.0}]


def _frictional_lag(ctx: Context, form: str = "film") -> list[dict[str, float]]:
    """A small grid of time constants: 10 and 50 ms (at least 5 and 25 samples); for the
    film, its speed ``vb`` at one and four Stribeck speeds; for the lagged speed, the
    whole lag and half of it."""
    flat = ctx.current.model.flat_params()
    vs = flat.get("vs", flat.get("vs_pos", 0.1 * ctx.data.scales.speed))
    dt = ctx.data.scales.dt
    taus = (max(5 * dt, 0.01), max(25 * dt, 0.05))
    if form == "speed-lag":
        return [{"tau_L": tau, "w_L": w} for tau in (*taus, 0.2) for w in (1.0, 0.5)]
    out = []
    for vb in (vs, 4 * vs):
        for tau in taus:
            out.append({"vb": vb, "tau_hp": tau, "tau_hn": tau, "tau_h0": 1.0})
    return out


def _dwell_starts(seg: Segmentation) -> list[tuple[int, float]]:
    return [(k, dw) for k, dw, _ in seg.starts if dw >= seg.t_dwell]


def _dwell_time(ctx: Context) -> list[dict[str, float]]:
    """Break-away peaks of the residual against the dwell time before each start."""
    seg, data = ctx.seg, ctx.data
    x, v = data.signal("x"), data.signal("v")
    r = ctx.current.residual
    zone = 3.0 * seg.d_pre
    dwells, peaks = [], []
    for k, dw in _dwell_starts(seg):
        j = k
        s = math.copysign(1.0, v[k]) if v[k] != 0 else 1.0
        while j < data.n and abs(x[j] - x[k]) < zone and j - k < 10_000:
            j += 1
        win = slice(k, max(j, k + 1))
        sel = ctx.train[win]
        if sel.any():
            dwells.append(dw)
            peaks.append(float(np.max(s * r[win][sel])))
    level = _level(ctx)
    if len(dwells) < 2:
        return [{"dFs": 0.2 * level, "tau_dwell": 1.0, "L_dwell": 2 * seg.d_pre}]
    d, p = np.array(dwells), np.array(peaks)
    best = None
    for tau in np.geomspace(max(d.min(), 0.01), max(d.max(), 0.02), 5):
        A = np.column_stack([np.ones_like(d), 1.0 - np.exp(-d / tau)])
        coef, *_ = np.linalg.lstsq(A, p, rcond=None)
        cost = float(np.sum((p - A @ coef) ** 2))
        if best is None or cost < best[0]:
            best = (cost, max(float(coef[1]), 0.05 * level), float(tau))
    _, dFs, tau = best  # type: ignore[misc]
    L = max(2 * seg.d_pre, 20 * data.scales.resolution)
    return [{"dFs": dFs, "tau_dwell": tau, "L_dwell": L},
            {"dFs": dFs, "tau_dwell": tau, "L_dwell": 8 * L},
            {"dFs": 1.5 * dFs, "tau_dwell": 0.3 * tau, "L_dwell": 2 * L, "k_dwell": 1.0}]


def _direction_asymmetry(ctx: Context, form: str = "levels-viscous"
                         ) -> list[dict[str, float]]:
    m = _moving(ctx)
    v, y = ctx.data.signal("v"), ctx.data.y
    pos, neg = m & (v > 0), m & (v < 0)
    if pos.sum() < 3 or neg.sum() < 3:
        return [{"r_neg": 1.0}]
    a, b = float(np.median(y[pos])), float(np.median(-y[neg]))
    ratio = b / a if a > 0 and b > 0 else 1.0
    starts = [{"r_neg": float(np.clip(ratio, 0.2, 5.0))}]
    flat = ctx.current.model.flat_params()
    visc = flat.get("sigma2", flat.get("B", 0.0))
    if visc > 0 and form != "levels":  # a slope of the residual while retracting, relative to the viscous one
        c = _ls(ctx.current.residual[neg], v[neg])
        starts.append({"r_neg": 1.0, "rv_neg": float(np.clip(1.0 + c / visc, 0.1, 9.0))})
    return starts


def _pressure(ctx: Context) -> list[dict[str, float]]:
    """The level change per pascal of ``p1 + p2`` by least squares; then with the chambers
    weighed apart and a curvature too (the sign-corrected residual regressed on
    ``|F_hat|*(dS, dD, dS^2)``)."""
    m = _moving(ctx)
    s = np.sign(ctx.data.signal("v"))
    p1, p2 = ctx.data.signal("p1"), ctx.data.signal("p2")
    d_ref = float(np.mean(p1 - p2))
    dS = p1 + p2 - ctx.data.scales.p_mid
    dD = p1 - p2 - d_ref
    F = np.abs(ctx.current.F_hat)
    rs = (s * ctx.current.residual)[m]
    kp = _ls(rs, (F * dS)[m])
    bound = 0.9 / max(float(np.max(np.abs(dS))), 1.0)
    ref = {"p_ref": ctx.data.scales.p_mid, "d_ref": d_ref}
    cols = np.column_stack([F * dS, F * dD, F * dS * dS])[m]
    use = _distinct_columns(cols)
    coef = np.zeros(3)
    coef[use], *_ = np.linalg.lstsq(cols[:, use], rs, rcond=None)
    bd = 0.9 / max(float(np.max(np.abs(dD))), 1.0)
    bq = 0.9 / max(float(np.max(dS * dS)), 1.0)
    full = {"kp": float(np.clip(coef[0], -bound, bound)), "kd": float(np.clip(coef[1], -bd, bd)),
            "kq": float(np.clip(coef[2], -bq, bq))}
    return [{"kp": float(np.clip(kp, -bound, bound)), **ref}, {**full, **ref}]


def _pressure_held(ctx: Context) -> list[str]:
    """The chamber weight ``kd`` and the curvature ``kq`` where the record cannot tell them
    from the level change ``kp`` (one chamber vented: ``p1 - p2`` is ``p1 + p2``; two
    pressure levels: the square is a line)."""
    m = _moving(ctx)
    p1, p2 = ctx.data.signal("p1"), ctx.data.signal("p2")
    dS = (p1 + p2 - ctx.data.scales.p_mid)[m]
    dD = (p1 - p2)[m] - float(np.mean((p1 - p2)[m]))
    use = _distinct_columns(np.column_stack([dS, dD, dS * dS - np.mean(dS * dS)]))
    return [n for i, n in enumerate(("kp", "kd", "kq")) if i not in use]


def _distinct_columns(cols: np.ndarray, max_corr: float = 0.98) -> list[int]:
    """Indices of the columns kept in order, each dropped that is nearly a multiple of a
    combination of the kept ones (its residual after projection is below
    ``sqrt(1 - max_corr^2)`` of its norm)."""
    kept: list[int] = []
    for j in range(cols.shape[1]):
        c = cols[:, j]
        norm = float(np.linalg.norm(c))
        if norm == 0:
            continue
        if kept:
            basis = cols[:, kept]
            coef, *_ = np.linalg.lstsq(basis, c, rcond=None)
            if np.linalg.norm(c - basis @ coef) < np.sqrt(1 - max_corr**2) * norm:
                continue
        kept.append(j)
    return kept


def _position(ctx: Context) -> list[dict[str, float]]:
    """Legendre coefficients by least squares, and a local box where the rest peaks.

    The sign-corrected training residual of the moving samples is regressed on
    ``|F_hat|*P_k(xi)`` (the smooth part); what remains, relative to
    ``|F_hat|``, is averaged in bins of 0.5 % of the stroke and its largest
    excursion (three bins smoothed) gives the box: centre, half-width (where it
    stays above half the peak), amplitude. Starts: the smooth part alone, the
    smooth part with the box, and the box alone.
    """
    m = _moving(ctx)
    cfg = _config("position-dependence", ctx.data)
    x = ctx.data.signal("x")
    xi = 2.0 * (x - cfg["x_min"]) / (cfg["x_max"] - cfg["x_min"]) - 1.0
    F = np.abs(ctx.current.F_hat)
    cols = np.column_stack([F * xi, F * 0.5 * (3 * xi**2 - 1), F * 0.5 * (5 * xi**3 - 3 * xi)])
    rs = np.sign(ctx.data.signal("v")) * ctx.current.residual
    coef, *_ = np.linalg.lstsq(cols[m], rs[m], rcond=None)
    coef = np.clip(coef, -0.9, 0.9)
    smooth_part = {"kx1": float(coef[0]), "kx2": float(coef[1]), "kx3": float(coef[2]),
                   "kb": 0.0}
    sc = ctx.data.scales
    rel = (rs - cols @ coef)[m] / np.maximum(F[m], 1e-3 * sc.force)
    width = max(0.005 * sc.stroke, 2.0 * sc.resolution)
    edges = np.arange(sc.x_min, sc.x_max + width, width)
    k = np.clip(np.digitize(x[m], edges) - 1, 0, max(edges.size - 2, 0))
    count = np.bincount(k, minlength=edges.size - 1)
    if edges.size < 4 or (count >= 5).sum() < 4:
        return [smooth_part]
    mean = np.where(count >= 5, np.bincount(k, rel, minlength=edges.size - 1)
                    / np.maximum(count, 1), 0.0)
    sm = np.convolve(mean, np.ones(3) / 3.0, mode="same")
    j = int(np.argmax(np.abs(sm)))
    peak = float(sm[j])
    lo = hi = j
    while lo > 0 and abs(sm[lo - 1]) > 0.5 * abs(peak) and np.sign(sm[lo - 1]) == np.sign(peak):
        lo -= 1
    while (hi < sm.size - 1 and abs(sm[hi + 1]) > 0.5 * abs(peak)
           and np.sign(sm[hi + 1]) == np.sign(peak)):
        hi += 1
    box = {"kb": float(np.clip(peak, -0.9, 2.9)),
           "xb": float(0.5 * (edges[lo] + edges[hi + 1])),
           "wb": float(0.5 * (edges[hi + 1] - edges[lo])),
           "eb": float(max(0.25 * width, sc.resolution))}
    return [smooth_part, {**smooth_part, **box},
            {"kx1": 0.0, "kx2": 0.0, "kx3": 0.0, **box}]


def _viscous_lead(ctx: Context) -> list[dict[str, float]]:
    flat = ctx.current.model.flat_params()
    visc = flat.get("sigma2", flat.get("B", flat.get("sigma2_pos", 0.0)))
    a = ctx.data.signal("a")
    m = ctx.train
    sc = ctx.data.scales
    T = _ls(ctx.current.residual[m], visc * a[m]) if visc > 0 else 0.0
    return [{"T": T if T > 0 else 0.05 * sc.speed / sc.accel}]


def _inertia(ctx: Context) -> list[dict[str, float]]:
    m = ctx.train
    return [{"dm": _ls(ctx.current.residual[m], ctx.data.signal("a")[m])}]


def _offset(ctx: Context) -> list[dict[str, float]]:
    return [{"offset": float(np.mean(ctx.current.residual[ctx.train]))}]


def _nonlocal_memory(ctx: Context) -> list[dict[str, float]]:
    """Maxwell-slip elements carrying most of the level, spread over one and two decades.

    The slip displacement of the softest element starts at three presliding
    lengths (the fitted bristle's ``Fc/sigma0``, else the record's); the
    elements' stiffness either constant (GMS) or scaling with the slip level
    (constant slip displacements), their shares equal. The bristle keeps its
    fitted stiffness for the share it still carries.
    """
    flat = ctx.current.model.flat_params()
    level = flat.get("Fc", flat.get("Fc_pos", _level(ctx)))
    s0 = flat.get("sigma0", level / ctx.seg.d_pre)
    d_pre = level / s0 if s0 > 0 else ctx.seg.d_pre
    out = []
    for spread, scaling in ((10.0, 0.0), (100.0, 0.0), (10.0, 1.0), (100.0, 1.0)):
        out.append({"ms_share": 0.9, "ms_dmax": 3.0 * d_pre, "ms_spread": spread,
                    "ms_shape": 0.0, "ms_scaling": scaling})
    return out


GUESSES: dict[str, Callable[[Context], list[dict[str, float]]]] = {
    "viscous": _viscous,
    "stribeck": _stribeck,
    "presliding": _presliding,
    "frictional-lag": _frictional_lag,
    "dwell-time": _dwell_time,
    "direction-asymmetry": _direction_asymmetry,
    "pressure-dependence": _pressure,
    "position-dependence": _position,
    "viscous-lead": _viscous_lead,
    "inertia-error": _inertia,
    "force-offset": _offset,
    "nonlocal-memory": _nonlocal_memory,
}


#: Per effect: the parameters a record cannot determine, held at their no-op values.
HELD: dict[str, Callable[[Context], list[str]]] = {"pressure-dependence": _pressure_held}
#: Per effect and form: the parameters that form holds at their no-op values.
HELD_BY_FORM: dict[str, dict[str, tuple[str, ...]]] = {
    "direction-asymmetry": {"levels": ("rv_neg",)}}


# ------------------------------------------------------------------ baseline
def baseline_starts(model: FrictionModel, data: DiagnosisData, seg: Segmentation,
                    train: np.ndarray) -> list[dict[str, float]]:
    """Starts of the baseline fit, read off the training samples.

    Levels and the viscous coefficient by linear least squares on the sliding
    samples (:func:`fcomp.identification.guess.linear_start`), the Stribeck
    hump (:func:`~fcomp.identification.guess.stribeck_start`), then the
    steady-state map fitted to the steady sliding points (:func:`_static_stage`,
    seed 002's procedure), the bristle
    stiffness ``Fc/d_pre`` from the presliding length (three starts, a factor
    of four apart), a small bristle damping (its term a tenth of ``Fc`` at the
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
        Fs, vs = stribeck_start(d.sig["v"], ls.friction, Fc, float(ls.B[0]), v_min)
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
    if "sigma0" not in names:
        return variants
    out = []
    for k in (1.0, 4.0):
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
    from fcomp.diagnosis.refit import data_bounds, fixed_names
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
