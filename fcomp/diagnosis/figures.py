"""The figures of the compare / diagnose / add / error-fall loop, by name.

:func:`figures` draws them (matplotlib, object-oriented API, no pyplot state)
from a fitted :class:`~fcomp.diagnosis.loop.Diagnosis`, :func:`comparison_figures`
those of a :class:`~fcomp.diagnosis.compare.Comparison`; every figure takes a
:class:`View` of either (:func:`view`). All errors are in newtons, on held-out
data. The report (:mod:`fcomp.diagnosis.report`) puts them into one HTML page.

Figures
-------
``regimes``        held-out RMS error per regime, baseline and final model
``residuals``      residual against every feature (baseline and final), with
                   the binned mean the residual still follows
``loops``          measured and modelled force-velocity and force-displacement
                   loops (held-out samples), baseline and final
``worst``          the held-out windows where the baseline fails most, with
                   the final model beside it
``candidates``     first-step candidates: held-out RMS after adding each
``error_fall``     held-out RMS after each step, with the noise floor
``before_after``   a held-out stretch: measured, baseline and final force
``structure``      what the structure left in the final residual follows: the
                   direction-signed held-out residual against each feature listed
                   (:mod:`fcomp.diagnosis.structure_left`), its binned means and size
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from fcomp import figstyle as fs
from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.features import feature_values
from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.regimes import REGIMES, Segmentation
from fcomp.diagnosis.residuals import worst_segments
from fcomp.errors import FcompError
from fcomp.figures import fig_plant

if TYPE_CHECKING:  # the results draw themselves through this module, which sits below them
    from fcomp.diagnosis.compare import Comparison
    from fcomp.diagnosis.loop import Diagnosis

#: Features are drawn in the units an engineer reads (:data:`fcomp.figstyle.SCALES`: x and
#: displacements in mm, v in mm/s, pressures in bar); the data stay SI.
_COLORS = {k: fs.COLORS[k] for k in ("measured", "baseline", "final")}
#: Fewest judged samples a regime needs for its bar (fewer: marked, not drawn).
MIN_REGIME_SAMPLES = 20


@dataclass(frozen=True)
class Series:
    """One model drawn in the figures: its label, colour (a key of the palette) and fit."""

    label: str
    colour: str
    fit: FitResult
    regimes: Mapping[str, Mapping[str, float | int | None]]


@dataclass(frozen=True)
class View:
    """What the figures draw: a record, the samples judged and one or more models beside it.

    Built from a fitted :class:`~fcomp.diagnosis.loop.Diagnosis` (baseline and final
    model, held-out samples) or from a :class:`~fcomp.diagnosis.compare.Comparison`
    (the one model compared) by :func:`view`; every figure takes either.
    """

    data: DiagnosisData
    segmentation: Segmentation
    judged: np.ndarray
    judged_label: str
    series: tuple[Series, ...]
    strength: Mapping[str, float]
    noise_floor: float | None

    @property
    def first(self) -> Series:
        return self.series[0]

    @property
    def last(self) -> Series:
        return self.series[-1]


def view(obj: Diagnosis | Comparison | View) -> View:
    """The :class:`View` of a diagnosis (baseline and final model) or a comparison."""
    if isinstance(obj, View):
        return obj
    if hasattr(obj, "view"):  # a Comparison builds its own view
        return obj.view()
    if not hasattr(obj, "verdict_"):
        raise FcompError("the diagnosis is not fitted: call fit(data) before drawing it")
    return View(obj.data_, obj.segmentation_, obj.split_.test, "held-out",
                (Series(f"baseline: {obj.baseline_fit_.model.describe()}", "baseline",
                        obj.baseline_fit_, obj.regimes_["baseline"]),
                 Series(f"final: {obj.fit_.model.describe()}", "final", obj.fit_,
                        obj.regimes_["final"])),
                {f.feature: f.strength for f in obj.residual_features_},
                obj.noise_floor_.value)


def check_fitted(diag: Diagnosis) -> None:
    """Refuse a diagnosis that is not fitted (nothing to draw or report)."""
    if not hasattr(diag, "verdict_"):
        raise FcompError("the diagnosis is not fitted: call fit(data) before drawing it")


def fig_regimes(obj: Diagnosis | Comparison | View) -> Figure:
    """RMS error per regime of every model drawn (held-out samples of a diagnosis).

    A regime with fewer than :data:`MIN_REGIME_SAMPLES` judged samples gets no
    bar (its RMS would rest on a handful of samples): it is marked "too few".
    """
    vw = view(obj)
    fig, ax = fs.new_figure(height=3.6, width=fs.HALF_WIDTH + 1.6)
    names = [*REGIMES, "all"]
    xs = np.arange(len(names))
    width = 0.8 / len(vw.series)
    top = 0.0
    for k, s in enumerate(vw.series):
        off = (k - (len(vw.series) - 1) / 2) * width
        vals = [s.regimes[n]["rms"] if (s.regimes[n]["n"] or 0) >= MIN_REGIME_SAMPLES
                else None for n in names]
        shown = [(x + off, v) for x, v in zip(xs, vals, strict=True) if v is not None]
        if shown:
            ax.bar([a for a, _ in shown], [b for _, b in shown], width=width,
                   color=_COLORS[s.colour], label=s.label)
            top = max(top, max(b for _, b in shown))
    counts = vw.last.regimes
    if vw.noise_floor is not None:
        ax.axhline(vw.noise_floor, color="0.4", ls="--", lw=1, label="noise floor")
        top = max(top, vw.noise_floor)
    top = 1.15 * top if top > 0 else 1.0
    for x, n in zip(xs, names, strict=True):
        if (counts[n]["n"] or 0) < MIN_REGIME_SAMPLES:
            fs.text_inside(ax, float(x), "too few\nsamples", frac=0.04)
    ax.set_xticks(xs, [f"{n}\n(n={counts[n]['n']})" for n in names])
    ax.set_xlim(-0.6, len(names) - 0.4)  # every category (and its bars) inside the axes
    ax.set_ylabel(f"{vw.judged_label} RMS error (N)")
    ax.set_ylim(0, top)
    fs.legend_above(ax, ncol=2)
    return fig


def fig_residuals(obj: Diagnosis | Comparison | View) -> Figure:
    """Judged residual against each feature (every model drawn), with binned means; each
    panel is titled with its feature and how strongly the last model's residual follows it."""
    vw = view(obj)
    feats = feature_values(vw.data, vw.segmentation)
    te = vw.judged
    n = len(feats)
    cols = 3
    rows = math.ceil(n / cols)
    fig, axes = fs.new_figure(height=2.6 * rows, nrows=rows, ncols=cols, squeeze=False,
                              sharey=True)
    flat = list(axes.ravel())
    for i, (name, f) in enumerate(feats.items()):
        ax = flat[i]
        shown = fs.scaled(name, f[te])
        for s in vw.series:
            r = s.fit.plain_residual[te]
            ax.plot(shown, r, ".", ms=1.5, alpha=0.35, color=_COLORS[s.colour])
            cx, cy = fs.binned_means(shown, r)
            ax.plot(cx, cy, "-", color=_COLORS[s.colour], lw=1.5,
                    label=f"{s.label.split(':')[0]} (binned mean)")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(fs.label(name.replace("_", " "), name))
        ax.set_title(f"strength {vw.strength.get(name, 0.0):.2f}")
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
        if i % cols == 0:
            ax.set_ylabel("residual y - F (N)")
    for ax in flat[n:]:
        ax.set_visible(False)
    fs.legend_top(fig, flat[0], ncol=len(vw.series))
    return fig


def fig_loops(obj: Diagnosis | Comparison | View) -> Figure:
    """Measured and modelled force-velocity and force-displacement loops (judged samples)."""
    vw = view(obj)
    fig, (ax1, ax2) = fs.new_figure(height=3.8, ncols=2, sharey=True)
    te = vw.judged
    v, x, y = vw.data.signal("v"), vw.data.signal("x"), vw.data.y
    for ax, q, name, lab in ((ax1, v, "v", "velocity v"), (ax2, x, "x", "position x")):
        ax.plot(fs.scaled(name, q[te]), y[te], ".", ms=1.5, color=_COLORS["measured"],
                label="measured")
        for s in vw.series:
            ax.plot(fs.scaled(name, q[te]), s.fit.F_hat[te], ".", ms=1.0,
                    color=_COLORS[s.colour], label=s.label.split(":")[0])
        ax.set_xlabel(fs.label(lab, name))
        ax.xaxis.set_major_locator(MaxNLocator(nbins=6))
    ax1.set_ylabel("friction force (N)")
    fs.legend_top(fig, ax1, ncol=len(vw.series) + 1, markerscale=6)
    if vw.data.steady_state:
        ax2.set_title("steady-state points")
    return fig


def _window_plot(ax: Any, vw: View, a: int, b: int, title: str) -> None:
    t = vw.data.signal("t")
    starts = [e.start - a for e in vw.data.experiments[1:] if a < e.start < b]  # no line across
    fs.plot_gapped(ax, t[a:b], vw.data.y[a:b], color=_COLORS["measured"], lw=1.0,
                   label="measured", starts=starts)
    for k, s in enumerate(vw.series):
        fs.plot_gapped(ax, t[a:b], s.fit.F_hat[a:b], color=_COLORS[s.colour], lw=1.0,
                       ls="--" if k and k == len(vw.series) - 1 else "-",
                       label=s.label.split(":")[0], starts=starts)
    ax.set_title(title)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("F (N)")
    ax.xaxis.set_major_locator(MaxNLocator(nbins=4))


def worst_windows(obj: Diagnosis | Comparison | View, count: int = 3
                  ) -> list[tuple[int, int, float]]:
    """The ``count`` judged windows (about 0.25 s) where the first model drawn (the
    diagnosis's baseline) fails most."""
    vw = view(obj)
    width = max(10, int(round(0.25 / vw.data.scales.dt)))
    bounds = [e.start for e in vw.data.experiments[1:]]
    segs = worst_segments(vw.first.fit.plain_residual, vw.judged, width, count, bounds)
    return [(s.start, s.stop, s.rms) for s in segs]


def fig_worst(obj: Diagnosis | Comparison | View) -> Figure:
    """The worst judged windows of the first model drawn, with the others."""
    vw = view(obj)
    wins = worst_windows(vw)
    fig, axes = fs.new_figure(height=3.4, ncols=max(len(wins), 1), squeeze=False)
    who = vw.first.label.split(":")[0]
    for i, (a, b, rms) in enumerate(wins):
        ax = axes[0, i]
        pad = (b - a) // 2
        a0, b0 = max(a - pad, 0), min(b + pad, vw.data.n)
        counts = np.bincount(vw.segmentation.regime[a:b], minlength=len(REGIMES))
        _window_plot(ax, vw, a0, b0, f"{who} {rms:.3g} N RMS,\nmostly "
                     f"{REGIMES[int(np.argmax(counts))]}")
    fs.legend_top(fig, axes[0, 0], ncol=len(vw.series) + 1)
    return fig


def fig_candidates(diag: Diagnosis) -> Figure:
    """First-step candidates: held-out RMS after adding each (qualifying ones dark)."""
    cands = [c for c in diag.candidates_ if math.isfinite(c.rms_heldout)]
    fig, ax = fs.new_figure(height=0.35 * max(len(cands), 3) + 1.5, width=fs.HALF_WIDTH + 1.6)
    ys = np.arange(len(cands))
    ax.barh(ys, [c.rms_heldout for c in cands],
            color=[fs.COLORS["good"] if c.qualifies else fs.COLORS["neutral"] for c in cands])
    ax.axvline(diag.rms_baseline_, color=_COLORS["baseline"], lw=1.2, label="baseline")
    ax.axvline(diag.noise_floor_.value, color="0.3", ls="--", lw=1, label="noise floor")
    ax.set_yticks(ys, [c.effect for c in cands])
    ax.invert_yaxis()
    ax.set_xlabel("held-out RMS error after adding the effect (N)")
    fs.legend_above(ax, ncol=2)
    return fig


def fig_error_fall(diag: Diagnosis) -> Figure:
    """Held-out RMS error after each step (accepted steps), with the noise floor."""
    labels = ["baseline"]
    vals = [diag.rms_baseline_]
    for s in diag.steps_:
        if s.accepted or s.forced or s.removed:
            labels.append(f"+ {s.effect}")
            vals.append(s.rms_after)
    if diag.removed_:
        labels.append("- " + ", ".join(diag.removed_))
        vals.append(diag.rms_final_)
    fig, ax = fs.new_figure(height=3.4, width=fs.HALF_WIDTH + 1.6)
    ax.plot(range(len(vals)), vals, "o-", color=_COLORS["final"])
    for i, val in enumerate(vals):
        ax.annotate(f"{val:.3g} N", (i, val), textcoords="offset points", xytext=(0, 6),
                    ha="center", fontsize=fs.FONT_MIN)
    ax.axhline(diag.noise_floor_.value, color="0.4", ls="--", lw=1, label="noise floor")
    ax.set_xticks(range(len(vals)), [lab.replace(", ", ",\n") for lab in labels])
    ax.set_xlim(-0.5, len(vals) - 0.5)
    ax.set_ylabel("held-out RMS error (N)")
    ax.set_ylim(0, max(vals) * 1.2)
    fs.legend_above(ax)
    return fig


def fig_before_after(obj: Diagnosis | View) -> Figure:
    """A judged stretch of about two seconds: measured force and every model drawn (where
    the last one gains most on the first)."""
    vw = view(obj)
    te = vw.judged
    idx = np.flatnonzero(te)
    fig, ax = fs.new_figure(height=3.2)
    if idx.size:
        width = max(20, int(round(2.0 / vw.data.scales.dt)))
        r = vw.first.fit.residual ** 2 - vw.last.fit.residual ** 2
        if len(vw.series) == 1:  # one model: where it fails most
            r = vw.first.fit.residual ** 2
        c = np.concatenate([[0.0], np.cumsum(np.where(te, r, 0.0))])
        starts = idx[idx + width <= vw.data.n]
        a = int(starts[np.argmax(c[starts + width] - c[starts])]) if starts.size else int(idx[0])
        _window_plot(ax, vw, a, min(a + width, vw.data.n),
                     f"{vw.judged_label} stretch where the added effects matter most"
                     if len(vw.series) > 1 else f"{vw.judged_label} stretch where the model "
                     "fails most")
        fs.legend_above(ax, ncol=len(vw.series) + 1)
    return fig


def fig_structure(diag: Diagnosis) -> Figure:
    """What the structure left follows: the final model's held-out residual, signed by the
    direction of motion (a friction level above the model's is positive both ways), against
    each feature the structure report lists (:attr:`.loop.Diagnosis.structure_left_`), with
    its binned means; each panel is titled with the strength and the newtons it carries.
    Nothing listed: the strongest feature, titled as such."""
    check_fitted(diag)
    left = diag.structure_left_
    vw = view(diag)
    feats = feature_values(vw.data, vw.segmentation)
    names = [f.feature for f in (left.follows if left is not None else ()) if f.feature in feats]
    titles = {f.feature: f"strength {f.strength:.2f}, {f.rms:.3g} N RMS"
              for f in (left.follows if left is not None else ())}
    if not names and diag.residual_features_:
        top = diag.residual_features_[0]
        names = [top.feature] if top.feature in feats else []
        titles[top.feature] = f"strongest: strength {top.strength:.2f} (below the rule)"
    if "time_since_event" in titles and "time_since_reversal" in feats:
        names = ["time_since_reversal", *[n for n in names if n != "time_since_reversal"]]
        titles["time_since_reversal"] = titles.get("time_since_reversal",
                                                   titles["time_since_event"])
    names = names[:3]
    fig, axes = fs.new_figure(height=3.2, ncols=max(len(names), 1), squeeze=False)
    te = vw.judged & (vw.data.signal("s") != 0)
    r = vw.data.signal("s") * vw.last.fit.plain_residual
    for i, name in enumerate(names):
        ax = axes[0, i]
        shown = fs.scaled(name, feats[name][te])
        ax.plot(shown, r[te], ".", ms=1.5, alpha=0.35, color=_COLORS["final"])
        cx, cy = fs.binned_means(shown, r[te])
        ax.plot(cx, cy, "-", color=_COLORS["baseline"], lw=1.8, label="binned mean")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(fs.label(name.replace("_", " "), name))
        ax.set_title(titles.get(name, ""))
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
    if not names:
        fs.text_inside(axes[0, 0], 0.5, "no structure left")
    axes[0, 0].set_ylabel("residual x sign(v) (N)")
    if names:
        fs.legend_above(axes[0, 0])
    return fig


FIGURES: dict[str, Callable[[Any], Figure]] = {
    "regimes": fig_regimes,
    "residuals": fig_residuals,
    "loops": fig_loops,
    "worst": fig_worst,
    "candidates": fig_candidates,
    "error_fall": fig_error_fall,
    "before_after": fig_before_after,
    "structure": fig_structure,
}


def figures(diag: Diagnosis) -> dict[str, Figure]:
    """Every figure of the report by name (see the module docstring)."""
    check_fitted(diag)
    return {name: fn(diag) for name, fn in FIGURES.items()}


#: The figures of a comparison (one model beside the records): those of the diagnosis
#: that need no search.
COMPARISON_FIGURES = ("regimes", "residuals", "loops", "worst", "before_after")


def comparison_figures(comp: Comparison, only: str | None = None) -> dict[str, Figure]:
    """The figures of a :class:`~fcomp.diagnosis.compare.Comparison` by name (the
    diagnosis's own, :data:`COMPARISON_FIGURES`; ``plant`` with a plant-domain comparison)."""
    names = [*COMPARISON_FIGURES, *(["plant"] if comp.plant else [])]
    if only is not None and only not in names:
        raise FcompError(f"figure {only!r}: choose one of {', '.join(names)}")
    out: dict[str, Figure] = {}
    for name in names if only is None else [only]:
        out[name] = fig_plant(comp.plant) if name == "plant" else FIGURES[name](comp)
    return out
