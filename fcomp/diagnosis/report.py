"""The diagnosis report: every figure of the compare / diagnose / add / error-fall loop.

:func:`figures` draws them (matplotlib, object-oriented API, no pyplot state)
from a fitted :class:`~fcomp.diagnosis.loop.Diagnosis`; :func:`write_report`
puts them with the tables and a plain-language account of the physics of
every accepted effect into one self-contained HTML page
(:class:`fcomp.report.Report`). All errors are in newtons, on held-out data.

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
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.features import feature_values
from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.regimes import REGIMES, Segmentation
from fcomp.diagnosis.residuals import worst_segments
from fcomp.effects import EFFECTS
from fcomp.errors import FcompError
from fcomp.report import Report, notebook_html

if TYPE_CHECKING:  # the results draw themselves through this module, which sits below them
    from fcomp.diagnosis.compare import Comparison
    from fcomp.diagnosis.loop import Diagnosis

_UNITS = {"t": "s", "v": "m/s", "a": "m/s^2", "x": "m", "p1+p2": "bar",
          "time_since_reversal": "s", "displacement_since_reversal": "m", "dwell_time": "s"}
#: Features drawn in other units than SI: name -> factor (``p1+p2`` in bar, not raw Pa).
_SHOWN_SCALE = {"p1+p2": 1e-5}
_COLORS = {"measured": "0.25", "baseline": "#c0392b", "final": "#2356a8"}
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


def _check(diag: Diagnosis) -> None:
    if not hasattr(diag, "verdict_"):
        raise FcompError("the diagnosis is not fitted: call fit(data) before drawing it")


def _legend_above(ax: Any, ncol: int = 3, **kw: Any) -> None:
    """A legend above the axes, never over the data."""
    ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=ncol,
              frameon=False, borderaxespad=0.0, **kw)


def fig_regimes(obj: Diagnosis | Comparison | View) -> Figure:
    """RMS error per regime of every model drawn (held-out samples of a diagnosis).

    A regime with fewer than :data:`MIN_REGIME_SAMPLES` judged samples gets no
    bar (its RMS would rest on a handful of samples): it is marked "too few".
    """
    vw = view(obj)
    fig = Figure(figsize=(7.0, 3.6))
    ax = fig.add_subplot()
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
    top = 1.1 * top if top > 0 else 1.0
    for x, n in zip(xs, names, strict=True):
        if (counts[n]["n"] or 0) < MIN_REGIME_SAMPLES:
            ax.text(float(x), 0.05 * top, "too few\nsamples", ha="center", va="bottom", fontsize=7,
                    color="0.4")
    ax.set_xticks(xs, [f"{n}\n(n={counts[n]['n']})" for n in names], fontsize=8)
    ax.set_ylabel(f"{vw.judged_label} RMS error (N)")
    ax.set_ylim(0, top)
    _legend_above(ax, ncol=2)
    fig.tight_layout()
    return fig


def _binned(f: np.ndarray, r: np.ndarray) -> tuple[list[float], list[float]]:
    """Means of ``r`` over bins of equal count along ``f``."""
    order = np.argsort(f)
    fb, rb = f[order], r[order]
    nb = max(5, min(40, fb.size // 50))
    edges = np.linspace(0, fb.size, nb + 1).astype(int)
    pairs = [(fb[a:b].mean(), rb[a:b].mean())
             for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]
    return [a for a, _ in pairs], [b for _, b in pairs]


def fig_residuals(obj: Diagnosis | Comparison | View) -> Figure:
    """Judged residual against each feature (every model drawn), with binned means; each
    panel is titled with its feature and how strongly the last model's residual follows it."""
    vw = view(obj)
    feats = feature_values(vw.data, vw.segmentation)
    te = vw.judged
    n = len(feats)
    cols = 4
    rows = math.ceil(n / cols)
    fig = Figure(figsize=(12.0, 2.9 * rows))
    for i, (name, f) in enumerate(feats.items()):
        ax = fig.add_subplot(rows, cols, i + 1)
        shown = f[te] * _SHOWN_SCALE.get(name, 1.0)
        for s in vw.series:
            r = s.fit.plain_residual[te]
            ax.plot(shown, r, ".", ms=1.5, alpha=0.35, color=_COLORS[s.colour])
            cx, cy = _binned(shown, r)
            ax.plot(cx, cy, "-", color=_COLORS[s.colour], lw=1.5, label=s.label.split(":")[0])
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(f"{name} ({_UNITS.get(name, '-')})", fontsize=8)
        ax.set_title(f"{name}: strength {vw.strength.get(name, 0.0):.2f}", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_major_locator(MaxNLocator(nbins=4))
        ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 3), useMathText=True)
        ax.xaxis.get_offset_text().set_fontsize(7)
        if i % cols == 0:
            ax.set_ylabel("residual y - F (N)", fontsize=8)
        if i == 0:
            ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def fig_loops(obj: Diagnosis | Comparison | View) -> Figure:
    """Measured and modelled force-velocity and force-displacement loops (judged samples)."""
    vw = view(obj)
    fig = Figure(figsize=(11.0, 4.0))
    te = vw.judged
    v, x, y = vw.data.signal("v"), vw.data.signal("x"), vw.data.y
    ax1 = fig.add_subplot(1, 2, 1)
    ax2 = fig.add_subplot(1, 2, 2)
    for ax, q, lab in ((ax1, v, "velocity v (m/s)"), (ax2, x, "position x (m)")):
        ax.plot(q[te], y[te], ".", ms=1.5, color=_COLORS["measured"], label="measured")
        for s in vw.series:
            ax.plot(q[te], s.fit.F_hat[te], ".", ms=1.0, color=_COLORS[s.colour],
                    label=s.label.split(":")[0])
        ax.set_xlabel(lab)
        ax.set_ylabel("friction force (N)")
    ax1.legend(fontsize=7, markerscale=6)
    if vw.data.steady_state:
        ax1.set_title("steady-state points", fontsize=9)
    fig.tight_layout()
    return fig


def _window_plot(ax: Any, vw: View, a: int, b: int, title: str) -> None:
    t = vw.data.signal("t")
    ax.plot(t[a:b], vw.data.y[a:b], color=_COLORS["measured"], lw=1.0, label="measured")
    for k, s in enumerate(vw.series):
        ax.plot(t[a:b], s.fit.F_hat[a:b], color=_COLORS[s.colour], lw=1.0,
                ls="--" if k and k == len(vw.series) - 1 else "-", label=s.label.split(":")[0])
    ax.set_title(title, fontsize=8)
    ax.set_xlabel("t (s)", fontsize=8)
    ax.set_ylabel("F (N)", fontsize=8)
    ax.tick_params(labelsize=7)


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
    fig = Figure(figsize=(11.0, 3.2))
    who = vw.first.label.split(":")[0]
    for i, (a, b, rms) in enumerate(wins):
        ax = fig.add_subplot(1, max(len(wins), 1), i + 1)
        pad = (b - a) // 2
        a0, b0 = max(a - pad, 0), min(b + pad, vw.data.n)
        counts = np.bincount(vw.segmentation.regime[a:b], minlength=len(REGIMES))
        _window_plot(ax, vw, a0, b0, f"{who} RMS {rms:.3g} N, mostly "
                     f"{REGIMES[int(np.argmax(counts))]}")
        if i == 0:
            ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def fig_candidates(diag: Diagnosis) -> Figure:
    """First-step candidates: held-out RMS after adding each (qualifying ones dark)."""
    cands = [c for c in diag.candidates_ if math.isfinite(c.rms_heldout)]
    fig = Figure(figsize=(7.0, 0.35 * max(len(cands), 3) + 1.2))
    ax = fig.add_subplot()
    ys = np.arange(len(cands))
    ax.barh(ys, [c.rms_heldout for c in cands],
            color=["#1f7a3d" if c.qualifies else "0.7" for c in cands])
    ax.axvline(diag.rms_baseline_, color=_COLORS["baseline"], lw=1.2, label="baseline")
    ax.axvline(diag.noise_floor_.value, color="0.3", ls="--", lw=1, label="noise floor")
    ax.set_yticks(ys, [c.effect for c in cands], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("held-out RMS error after adding the effect (N)")
    ax.legend(fontsize=7)
    fig.tight_layout()
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
    fig = Figure(figsize=(7.0, 3.4))
    ax = fig.add_subplot()
    ax.plot(range(len(vals)), vals, "o-", color=_COLORS["final"])
    for i, val in enumerate(vals):
        ax.annotate(f"{val:.3g} N", (i, val), textcoords="offset points", xytext=(0, 6),
                    ha="center", fontsize=8)
    ax.axhline(diag.noise_floor_.value, color="0.4", ls="--", lw=1, label="noise floor")
    ax.set_xticks(range(len(vals)), labels, fontsize=8)
    ax.set_ylabel("held-out RMS error (N)")
    ax.set_ylim(0, max(vals) * 1.2)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def fig_before_after(obj: Diagnosis | View) -> Figure:
    """A judged stretch of about two seconds: measured force and every model drawn (where
    the last one gains most on the first)."""
    vw = view(obj)
    te = vw.judged
    idx = np.flatnonzero(te)
    fig = Figure(figsize=(11.0, 3.2))
    ax = fig.add_subplot()
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
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


FIGURES: dict[str, Callable[[Any], Figure]] = {
    "regimes": fig_regimes,
    "residuals": fig_residuals,
    "loops": fig_loops,
    "worst": fig_worst,
    "candidates": fig_candidates,
    "error_fall": fig_error_fall,
    "before_after": fig_before_after,
}


def figures(diag: Diagnosis) -> dict[str, Figure]:
    """Every figure of the report by name (see the module docstring)."""
    _check(diag)
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


def short_reason(reason: str, limit: int = 110) -> str:
    """The first clause of a candidate's ``reason`` (the rest counted), for a table cell."""
    parts = [p for p in reason.split("; ") if p]
    if not parts:
        return ""
    first = parts[0] if len(parts[0]) <= limit else parts[0][: limit - 3].rstrip() + "..."
    return first + (f" (+{len(parts) - 1} more)" if len(parts) > 1 else "")


def fig_plant(comps: Any) -> Figure:
    """Plant domain: measured and simulated ``x``, ``p1``, ``p2`` of each record (one
    :class:`~plants.comparison.PlantComparison` or a list of them)."""
    items = comps if isinstance(comps, list | tuple) else [comps]
    names = [k for k in ("x", "p1", "p2") if any(k in c.rms for c in items)]
    fig = Figure(figsize=(11.0, 2.6 * max(len(names), 1)))
    scale = {"x": (1e3, "mm"), "p1": (1e-5, "bar"), "p2": (1e-5, "bar")}
    for i, k in enumerate(names):
        ax = fig.add_subplot(len(names), 1, i + 1)
        for c in items:
            if k not in c.rms:
                continue
            f, unit = scale[k]
            line = ax.plot(c.t, c.measured[k] * f, lw=1.0, label=f"{c.label} measured")[0]
            ax.plot(c.t, c.predicted[k] * f, lw=1.0, ls="--", color=line.get_color(),
                    label=f"{c.label} {c.plant} (RMS {c.rms[k] * f:.3g} {unit})")
            ax.set_ylabel(f"{k} ({unit})", fontsize=8)
        ax.tick_params(labelsize=7)
        _legend_above(ax, ncol=2)
    if names:
        fig.axes[-1].set_xlabel("t (s)", fontsize=8)
    fig.tight_layout()
    return fig


def _comparison_rows(obj: Comparison) -> tuple[str, list[list[Any]]]:
    """A title and the key numbers of a comparison (for notebooks)."""
    rows = [["model", obj.model.describe(), ""],
            [f"RMS error ({obj.judged_label} samples)", f"{obj.rms:.4g}", "N"],
            ["noise floor", f"{obj.noise_floor:.3g}", "N"]]
    rows += [[f"regime {k}", "-" if v["rms"] is None else f"{v['rms']:.4g}",
              f"N (n={v['n']})"] for k, v in obj.regimes.items()]
    rows += [[f"plant {c.plant}, {k}", f"{v:.3g}", "m" if k == "x" else "Pa"]
             for c in obj.plant for k, v in c.rms.items()]
    top = obj.residual_features[:3]
    rows.append(["residual follows", ", ".join(f"{f.feature} {f.strength:.2f}"
                                               for f in top), "strength"])
    return f"Comparison: {obj.model.describe()} on {', '.join(obj.data.labels[:3])}", rows


def _summary_rows(obj: Diagnosis | Comparison) -> tuple[str, list[list[Any]]]:
    """A title and the key numbers of a diagnosis or a comparison (for notebooks)."""
    if hasattr(obj, "view"):  # a Comparison
        return _comparison_rows(cast("Comparison", obj))
    _check(obj)
    d = obj.to_dict()
    rows = [["baseline", d["baseline"], ""],
            ["added", ", ".join(d["added"]) or "nothing", ""],
            ["held-out RMS, baseline", f"{d['rms_baseline']:.4g}", "N"],
            ["held-out RMS, final", f"{d['rms_final']:.4g}", "N"],
            ["noise floor", f"{d['noise_floor']:.3g}", "N"],
            ["verdict", d["verdict"], ""],
            ["reason", d["reason"], ""]]
    return f"Diagnosis: {d['baseline']} on {', '.join(obj.data_.labels[:3])}", rows


def comparison_html(comp: Comparison) -> str:
    """``Comparison._repr_html_``: the key numbers and the per-regime errors."""
    title, rows = _summary_rows(comp)
    return notebook_html(title, rows, fig_regimes(comp))


def diagnosis_html(diag: Diagnosis) -> str:
    """``Diagnosis._repr_html_``: the verdict, the errors and the error-fall chart."""
    if not hasattr(diag, "verdict_"):
        return f"<pre>{diag!r}</pre>"
    title, rows = _summary_rows(diag)
    return notebook_html(title, rows, fig_error_fall(diag))


def build_comparison_report(comp: Comparison, *, command: str | None = None) -> Report:
    """The :class:`~fcomp.report.Report` of a comparison: the diagnosis report's first two
    sections (errors per regime, where the model fails) for one model, and the plant domain."""
    d = comp.to_dict()
    labels = comp.data.labels
    rep = Report(f"Comparison: {comp.model.describe()} on {', '.join(labels[:3])}"
                 + (" ..." if len(labels) > 3 else ""),
                 subtitle=f"RMS {comp.rms:.4g} N over the {comp.judged_label} samples "
                 f"(noise floor {comp.noise_floor:.3g} N)"
                 + ("; fitted on the training samples" if comp.fitted else
                    "; the model's own values"),
                 command=command, config={"model": d["description"], "fitted": comp.fitted,
                                          "split": comp.split})
    if d["warnings"]:
        rep.section("What a careful engineer would question", level=3)
        rep.table(["warning", "parameter", "what it means"],
                  [[w["code"], w["parameter"] or "", w["message"]] for w in d["warnings"]])
    comparison_sections(rep, comp)
    rep.parameters({k: v for k, v in d["params"].items()}, heading="Parameters (SI units)")
    return rep


def comparison_sections(rep: Report, comp: Comparison) -> Report:
    """Add a comparison's sections to ``rep``: errors per regime, where the model fails
    (residual against every feature, loops, worst windows) and the plant domain."""
    figs = comparison_figures(comp)
    rep.section("1. Errors per regime")
    rep.figure(figs["regimes"], f"RMS error per regime over the {comp.judged_label} samples "
               "(pre-sliding, reversal, sliding, dwell/break-away); a regime with too few "
               "samples has no bar.")
    rep.table(["regime", "RMS (N)", "samples"],
              [[k, v["rms"], v["n"]] for k, v in comp.regimes.items()], digits=[None, 4, 0])
    rep.section("2. Where the model fails")
    rep.figure(figs["residuals"], "Residual (measured minus model) against every feature; "
               "lines: binned means. Each title gives how strongly the residual follows the "
               "feature (share of its mean square a nearest-neighbour regression explains on "
               "held-out samples).")
    rep.figure(figs["loops"], "Force-velocity and force-displacement loops, measured and "
               "modelled.")
    rep.figure(figs["worst"], "The windows where the model fails most.")
    rep.figure(figs["before_after"], "A stretch of about two seconds where the model fails "
               "most.")
    rep.table(["feature", "strength"], [[f.feature, f.strength]
                                        for f in comp.residual_features], digits=[None, 3])
    if comp.plant:
        rep.section("3. Plant domain")
        rep.figure(figs["plant"], "The plant simulated with each record's command from its "
                   "measured initial state (dashed) beside the measured signals.")
        rep.table(["record", "plant", "signal", "RMS"],
                  [[c.label, c.plant, k, f"{v:.4g} {'m' if k == 'x' else 'Pa'}"]
                   for c in comp.plant for k, v in c.rms.items()])
    return rep


def build_fit_report(fit: Any, comp: Comparison | None, *, command: str | None = None,
                     note: str = "") -> Report:
    """The report of a fit (``fcomp fit --report``): the estimates and their warnings, the fit
    drawn, and -- where the record takes it -- the comparison's sections for the fitted model."""
    d = fit.to_dict()
    rep = Report(f"Fit: {fit.model_.describe()} on {fit.data_.label}",
                 subtitle=f"{fit.method_} fit, target {fit.target_}, RMS {fit.rms_:.4g} N over "
                 f"{fit.n_samples_} samples", command=command,
                 config={"model": d["model"], "method": d["method"]})
    rep.section("Estimates")
    pct = round(100 * fit.confidence)
    rep.table(["parameter", "value", "stderr", f"{pct} % interval", "unit"], fit.rows(),
              caption="Estimates with standard errors robust to the residuals' "
              "autocorrelation; held parameters are not determined by the record.")
    if d["warnings"]:
        rep.table(["warning", "parameter", "what it means"],
                  [[w["code"], w["parameter"] or "", w["message"]] for w in d["warnings"]],
                  caption="Plausibility of the estimates.")
    rep.figure(fit.plot(), "The measured force and the fitted model, over time and against "
               "the velocity.")
    if comp is None:
        rep.note(f"No comparison by regime: {note}", kind="warn")
        return rep
    rep.paragraph(f"The fitted model beside the record, as `fcomp compare` shows it: RMS "
                  f"{comp.rms:.4g} N over the {comp.judged_label} samples (noise floor "
                  f"{comp.noise_floor:.3g} N).")
    return comparison_sections(rep, comp)


def write_fit_report(fit: Any, comp: Comparison | None, directory: str | Path, *,
                     command: str | None = None, note: str = "") -> Path:
    """Write ``DIRECTORY/report.html`` of a fit (:func:`build_fit_report`)."""
    return _write(build_fit_report(fit, comp, command=command, note=note), directory)


def write_comparison_report(comp: Comparison, directory: str | Path, *,
                            command: str | None = None) -> Path:
    """Write ``DIRECTORY/report.html`` of a comparison (self-contained); return its path."""
    return _write(build_comparison_report(comp, command=command), directory)


def _physics(effect: str) -> str:
    cls = EFFECTS.get(effect)
    return " ".join((cls.__doc__ or cls.signature or "").split())


def build_report(diag: Diagnosis, *, command: str | None = None) -> Report:
    """The :class:`~fcomp.report.Report` of a fitted diagnosis."""
    _check(diag)
    d = diag.to_dict()
    nf = diag.noise_floor_
    rep = Report(f"Friction diagnosis: {d['baseline']} on {', '.join(diag.data_.labels[:3])}"
                 + (" ..." if len(diag.data_.labels) > 3 else ""),
                 subtitle=f"verdict: {d['verdict']}; held-out RMS {d['rms_baseline']:.4g} N "
                 f"-> {d['rms_final']:.4g} N (noise floor {nf.value:.3g} N)",
                 command=command,
                 config={"baseline": d["baseline"], "split": diag.split_.description,
                         "effects": [c.effect for c in diag.candidates_] or d["added"]})
    rep.section("Summary")
    if d["added"]:
        rep.paragraph(f"Added, in order: {', '.join('`' + e + '`' for e in d['added'])}. "
                      f"Final model: `{d['model']}`.")
    else:
        rep.paragraph("No effect qualified: the baseline is kept.")
    kind = "ok" if d["verdict"] == "explained" and not d["baseline_dependent"] else "warn"
    if d["verdict"] == "explained":
        rep.note(f"Verdict `explained` -- {d['reason']}.", kind=kind)
    else:
        rep.note(f"Verdict `unexplained-structure` -- {d['reason']}. No catalogue entry "
                 "qualified to explain it: it is reported rather than papered over with the "
                 "least-bad wrong effect.", kind=kind)
    other = d.get("other_baseline")
    if other:
        same = ("finds the same effects" if not d["baseline_dependent"] else
                "finds OTHER effects: the answer depends on the baseline")
        rep.paragraph(f"Baseline check: the same records diagnosed from `{other['baseline']}` "
                      f"(the other kind of baseline) {same} -- "
                      f"{', '.join('`' + e + '`' for e in other['added']) or 'nothing'} added, "
                      f"verdict `{other['verdict']}`, held-out RMS {other['rms_baseline']:.4g} "
                      f"-> {other['rms_final']:.4g} N. It ran because "
                      f"{d['baseline_check']['why']}.")
    elif d["baseline_check"]["why"] != "not asked for":
        rep.paragraph(f"Baseline check not run: {d['baseline_check']['why']} "
                      "(`--baseline-check` runs it).")
    if d["warnings"]:
        rep.section("What a careful engineer would question", level=3)
        rep.table(["warning", "parameter", "what it means"],
                  [[w["code"], w["parameter"] or "", w["message"]] for w in d["warnings"]],
                  caption="Plausibility of the fits (baseline, each accepted step, final model) "
                  "and what the held-out samples cannot judge.")
    if d.get("disturbances"):
        rep.section("Periodic disturbances", level=3)
        rep.table(["frequency (Hz)", "amplitude (N)", "RMS (N)", "over the background",
                   "experiments"],
                  [[x["frequency_hz"], x["amplitude"], x["rms"], x["prominence"],
                    x["experiments"]] for x in d["disturbances"]],
                  caption="Narrow lines in the residual that follow no motion feature (a "
                  "pump's pulsation, a fan, mains hum, a valve dither): fitted as sinusoids "
                  "and taken off the force before the diagnosis, so they are neither in the "
                  "noise floor nor explained by an effect.", digits=[3, 3, 3, 1, 0])
    sig = d["signals"]
    rep.table(["quantity", "value", "unit"], [
        ["velocity driving the friction states", f"{sig['velocity']} -- {sig['reason']}", ""],
        ["samples left out (motion the position misses)",
         str(sig.get("unresolved_samples", 0)), ""],
        ["held-out RMS, baseline (scored: a prediction band costs)", d["rms_baseline"], "N"],
        ["held-out RMS, final (scored)", d["rms_final"], "N"],
        ["held-out RMS of y - F, baseline / final",
         f"{d['rms_plain']['baseline']:.4g} / {d['rms_plain']['final']:.4g}", "N"],
        ["noise floor (" + nf.method + f", {nf.n_samples} samples)", nf.value, "N"],
        ["held-out split", diag.split_.description, ""],
        ["experiments", str(len(diag.data_.experiments)), ""],
        ["force from", diag.data_.source, ""],
        *([["lag of the force channel (fitted)", 1e3 * sig["force_lag_s"], "ms"]]
          if sig.get("force_lag_s") is not None else []),
        ["rest speed / presliding length", f"{diag.segmentation_.v_rest:.3g} m/s / "
         f"{diag.segmentation_.d_pre:.3g} m", ""],
    ], caption="The diagnosis at a glance (errors on held-out samples).", digits=4)

    figs = figures(diag)
    rep.section("1. Compare: errors per regime")
    rep.figure(figs["regimes"], "Held-out RMS error per regime (pre-sliding, reversal, "
               "sliding, dwell/break-away) for the baseline and the final model; dashed: the "
               "noise floor estimated from the data.")
    rows = [[r, diag.regimes_["baseline"][r]["rms"], diag.regimes_["final"][r]["rms"],
             diag.regimes_["final"][r]["n"]] for r in [*REGIMES, "all"]]
    rep.table(["regime", "baseline RMS (N)", "final RMS (N)", "held-out samples"], rows,
              digits=[None, 4, 4, 0])
    cov = diag.split_.coverage
    if cov:
        rows = [[kind_, name, n["train"], n["heldout"]]
                for kind_, bins in cov.items() for name, n in bins.items()]
        rep.table(["operating point", "", "training samples", "held-out samples"], rows,
                  caption="Where the held-out samples are: per experiment, direction, speed "
                  "class and pressure level (a point without held-out samples is not judged).",
                  digits=[None, None, 0, 0])
    rep.section("2. Where the model fails")
    rep.figure(figs["residuals"], "Held-out residual (measured minus model) against time, "
               "velocity, acceleration, position, pressure sum, time and displacement since the "
               "last reversal and dwell time before the start; lines: binned means. The title "
               "gives how strongly the final residual still follows the feature (share of its "
               "mean square a nearest-neighbour regression explains on held-out data).")
    rep.figure(figs["loops"], "Force-velocity and force-displacement loops, measured and "
               "modelled (held-out samples).")
    rep.figure(figs["worst"], "The held-out windows where the baseline fails most, with the "
               "final model.")
    rep.section("3. Which effect is missing")
    if diag.candidates_:
        rep.figure(figs["candidates"], "First step: held-out RMS error after adding each "
                   "candidate and refitting; green candidates qualify (clear, significant fall "
                   "agreed by the information criterion).")
        rows = [[c.effect, c.rms_heldout, c.z, c.p, c.delta_bic, "yes" if c.qualifies else "no",
                 EFFECTS.get(c.effect).signature, short_reason(c.reason)]
                for c in diag.candidates_]
        rep.table(["candidate", "held-out RMS (N)", "z", "p", "dBIC", "qualifies",
                   "residual signature it explains", "why not"], rows,
                  caption="The first reason each candidate fails the acceptance rule (all "
                  "reasons, with their numbers: the JSON's `candidates[].reason`).",
                  digits=[None, 4, 2, 3, 1, None, None, None])
    if diag.skipped_:
        rep.table(["effect", "not a candidate because"],
                  [[k, v] for k, v in sorted(diag.skipped_.items())])
    if d["ties"]:
        rep.section("Confounded effects", level=3)
        for group in d["ties"]:
            both = [e for e in group if e in d["added"]]
            rep.paragraph("These explain the data equally well: " +
                          ", ".join(f"`{e}`" for e in group) + "; " + (
                              f"`{group[0]}` was added. " if len(both) < 2 else
                              ", ".join(f"`{e}`" for e in both) + " are all in the model "
                              "and the record does not fix how the force splits between "
                              "them. ") + "The experiments that tell them apart:")
            rep.bullets([f"`{e}`: {d['tie_experiments'][group[0]][e]}" for e in group])
    rep.section("4. Add it and watch the error fall")
    rep.figure(figs["error_fall"], "Held-out RMS error after each accepted step; dashed: the "
               "noise floor.")
    rep.table(["step", "effect", "RMS before (N)", "RMS after (N)", "accepted", "forced",
               "fit flags"],
              [[i + 1, s["effect"], s["rms_before"], s["rms_after"], s["accepted"], s["forced"],
                ", ".join(sorted({f"{w['code']} ({w['parameter']})" for w in s["warnings"]}))
                or "-"]
               for i, s in enumerate(d["steps"])], digits=[0, None, 4, 4, None, None, None])
    rep.figure(figs["before_after"], "Before and after: measured force, baseline and final "
               "model over a held-out stretch.")
    if d["added"]:
        rep.section("The physics of the added effects", level=3)
        for e in d["added"]:
            rep.paragraph(f"**{e}** -- {_physics(e)}".replace("**", ""))
    rep.section("Residual structure left")
    rep.table(["feature", "strength"], [[f["feature"], f["strength"]]
                                        for f in d["residual_features"]], digits=[None, 3])
    rep.parameters({k: v for k, v in d["params"].items()},
                   heading="Final parameters (SI units)")
    return rep


def write_report(diag: Diagnosis, directory: str | Path, *, command: str | None = None) -> Path:
    """Write the report of a fitted diagnosis to ``DIRECTORY/report.html`` and return its path.

    The page is self-contained (figures embedded, no script, opens offline):
    the verdict and its reason, the errors per regime, the residual against
    every feature, the loops and worst windows, the candidates and why each
    failed, the error fall, the physics of every added effect and the final
    parameters (:func:`build_report` gives the :class:`~fcomp.report.Report`
    to add sections to). ``command`` is recorded in the footer. The folder is
    created if missing; an existing ``report.html`` in it is replaced
    atomically. ``Diagnosis.write_report`` calls it.
    """
    return _write(build_report(diag, command=command), directory)


def _write(rep: Report, directory: str | Path) -> Path:
    out = Path(directory)
    if out.exists() and not out.is_dir():
        raise FcompError(f"--report {out}: exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    return rep.write(out / "report.html")
