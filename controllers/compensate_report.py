"""The figures and the HTML report of ``fcomp compensate`` (:mod:`controllers.compensate`).

The report opens with the conclusion (:func:`controllers.conclusions.of_compensation`),
then shows what the plant ran (the candidate truths), each compared model's
median-task ratio under every truth (where a recommendation holds or does not),
the ratios with the absolute errors under each truth, what was not ranked and
why, the tracking errors, the robustness draws and every run.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from controllers.compensate import RATIO_ERRORS, CompensateResult


def _truth(result: CompensateResult, truth: str | None) -> str:
    return truth if truth is not None else next(iter(result.ratios), "")


def figure_tracking(result: CompensateResult, task: str, truth: str | None = None) -> Any:
    """Tracking error ``r - x`` (um) over time on ``task`` under ``truth`` (default the
    first), one panel per controller, every model's run overlaid (the nominal runs; needs
    ``keep_signals``)."""
    from fcomp import figstyle as fs

    tr = _truth(result, truth)
    shown = [c for c in result.controllers
             if any((tr, c, m, task) in result.signals for m in result.models)]
    fig, axes2 = fs.new_figure(height=1.4 + 1.6 * max(len(shown), 1), nrows=max(len(shown), 1),
                               squeeze=False, sharex=True)
    axes = axes2[:, 0]
    for ax, c in zip(axes, shown, strict=False):
        for i, m in enumerate(result.models):
            sig = result.signals.get((tr, c, m, task))
            if sig is None:
                continue
            fs.plot_gapped(ax, sig["t"], (sig["r"] - sig["x"]) * 1e6, lw=1.0, color=f"C{i}",
                           label=f"{m} ({result.models[m]})")
        ax.set_ylabel(f"{c}\nerror (\u00b5m)")
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.grid(alpha=0.3)
    fs.legend_above(axes[0], ncol=2)
    axes[-1].set_xlabel("time (s)")
    return fig


def figure_ratios(result: CompensateResult, truth: str | None = None,
                  error: str = "rms_error") -> Any:
    """Bar chart of the ratios of ``error`` under ``truth`` (default the first; log scale):
    per controller, one bar per task and compared model, drawn from 1 (the baseline) down in
    green where the model beats the baseline, up in red where it does worse; tasks and models
    told apart by hatching; a run not ranked has no bar."""
    from matplotlib.patches import Patch

    from fcomp import figstyle as fs

    by = result.ratios.get(_truth(result, truth), {})
    fig, ax = fs.new_figure(height=3.6, width=fs.HALF_WIDTH + 1.6)
    others = [m for m in result.models if m != result.baseline]
    groups = [(t, m) for t in result.tasks for m in others]
    width = 0.8 / max(len(groups), 1)
    x = np.arange(len(result.controllers))
    hatches = ["", "//", "..", "xx", "\\\\", "++", "oo"]
    shown: list[float] = []
    handles = []
    for j, (t, m) in enumerate(groups):
        vals = [((by.get(c, {}).get(t, {}).get(m) or {}).get(error)) for c in
                result.controllers]
        ratio = np.array([np.nan if v is None else float(v) for v in vals])
        ok = np.isfinite(ratio) & (ratio > 0)
        colours = [fs.COLORS["good"] if r < 1.0 else fs.COLORS["bad"] for r in ratio[ok]]
        hatch = hatches[j % len(hatches)]
        ax.bar((x - 0.4 + (j + 0.5) * width)[ok], ratio[ok] - 1.0, width, bottom=1.0,
               color=colours, hatch=hatch, edgecolor="white", linewidth=0.5)
        shown += list(ratio[ok])
        handles.append(Patch(facecolor="0.75", hatch=hatch, edgecolor="white",
                             label=f"{m} on {t}" if len(others) > 1 else t))
    handles += [Patch(color=fs.COLORS["good"], label="better than the baseline"),
                Patch(color=fs.COLORS["bad"], label="worse")]
    ax.axhline(1.0, color="0.2", lw=1.0)
    ax.set_yscale("log")
    reach = max([1.25, *(max(r, 1.0 / r) for r in shown)]) * 1.15
    ax.set_ylim(1.0 / reach, reach)
    fs.plain_log_ticks(ax)
    ax.set_xticks(x, list(result.controllers))
    ax.set_xlim(-0.6, len(result.controllers) - 0.4)
    ax.set_ylabel(f"{error.replace('_', ' ')} / baseline's")
    ax.grid(alpha=0.3, axis="y")
    fs.legend_above(ax, handles=handles)
    return fig


def figure_across(result: CompensateResult) -> Any:
    """Per controller and compared model, its median-task RMS ratio under every truth (one
    point each, log scale; green below 1, red above): where the points straddle 1 the
    truths disagree and no recommendation holds."""
    from fcomp import figstyle as fs

    rows = [(c, m, a) for c, per in result.across.items() if result.uses_friction.get(c)
            for m, a in per.items()]
    fig, ax = fs.new_figure(height=1.2 + 0.42 * max(len(rows), 1),
                            width=fs.HALF_WIDTH + 1.6)
    shown: list[float] = []
    for i, (_c, _m, a) in enumerate(rows):
        vals = [v for v in a["per_truth"].values() if v is not None]
        if not vals:
            ax.text(1.0, i, "not ranked", va="center", ha="center", fontsize=9, color="0.4")
            continue
        colours = [fs.COLORS["good"] if v < 1.0 else fs.COLORS["bad"] for v in vals]
        ax.plot([min(vals), max(vals)], [i, i], "-", color="0.7", lw=1.0, zorder=1)
        ax.scatter(vals, [i] * len(vals), c=colours, s=22, zorder=2)
        shown += vals
    ax.axvline(1.0, color="0.2", lw=1.0)
    ax.set_xscale("log")
    reach = max([1.25, *(max(r, 1.0 / r) for r in shown)]) * 1.15
    ax.set_xlim(1.0 / reach, reach)
    fs.plain_log_ticks(ax, axis="x")
    ax.set_yticks(range(len(rows)), [f"{c}: {m}" for c, m, _ in rows])
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xlabel(f"median-task RMS error / {result.baseline}'s, one point per truth")
    ax.grid(alpha=0.3, axis="x")
    return fig


def figure_robustness(result: CompensateResult) -> Any:
    """The robustness draws: per controller, each compared model's RMS-error ratio to the
    baseline on the same draw (:func:`controllers.robustness.draw_distribution`)."""
    from controllers.robustness import draw_distribution
    from fcomp import figstyle as fs

    fig, ax = fs.new_figure(height=3.4, width=fs.HALF_WIDTH + 1.6)
    per = result.robustness["controllers"]
    others = [m for m in result.models if m != result.baseline]
    dist = {f"{c}: {m}" if len(others) > 1 else c: {"ratio": {"values":
            per[c]["ratio"].get(m, {}).get("values", [])}} for c in result.controllers
            for m in others}
    draw_distribution(ax, dist, list(dist), metric="ratio")
    ax.axhline(1.0, color="0.2", lw=1.0)
    lo, hi = ax.get_ylim()
    reach = max(1.25, hi, 1.0 / lo)
    ax.set_ylim(1.0 / reach, reach)
    fs.plain_log_ticks(ax)
    ax.set_ylabel("RMS error / baseline's (same draw)")
    return fig


def _um(value: Any) -> float | None:
    return None if value is None else float(value) * 1e6


def report(result: CompensateResult, command: str | None = None) -> Any:
    """The result as a :class:`~fcomp.report.Report` (module docstring)."""
    from controllers.conclusions import of_compensation
    from fcomp.report import Report

    doc = result.as_dict()
    others = [m for m in result.models if m != result.baseline]
    truths = list(result.truths)
    rep = Report(f"Compensation on {result.plant['name']}: what the friction model buys",
                 subtitle=f"{len(result.controllers)} controllers x {len(result.models)} "
                 f"models x {len(result.tasks)} task(s) under {len(truths)} "
                 f"{'true friction' if result.mode == 'given' else 'candidate truths'}",
                 command=command,
                 config={"plant": result.plant["label"], "plant friction": result.friction,
                         **{f"model {k}": v for k, v in result.models.items()},
                         "tasks": ", ".join(result.tasks), "fast": result.fast})
    rep.conclusion(of_compensation(doc))
    for w in result.warnings:
        rep.note(w["message"], kind="warn")
    rep.section("What the plant ran")
    rep.paragraph("The friction the simulated plant ran in each run (its *truth*). "
                  + ("One true friction was given." if result.mode == "given" else
                     "Nobody knows the plant's friction, so every run is repeated under each "
                     "candidate truth: the compared models, draws from each model's own "
                     "uncertainty (its standard errors), the rivals its diagnosis found and "
                     "the truths named. A truth that is a compared model makes that model "
                     "exact: a model is recommended only where it wins under every truth."))
    rep.table(["truth", "origin", "friction", "is the compared model", "what it is"],
              [[k, t["origin"], t["description"], t["equals"] or "-", t["note"]]
               for k, t in result.truths.items()])
    rep.section("Across the truths")
    rep.paragraph(f"Each compared model's median RMS-error ratio to `{result.baseline}` over "
                  "the tasks, under every truth; *better* only where it is below 1 under all "
                  "of them.")
    rep.figure(figure_across(result), "Median-task RMS ratio under each truth (log scale).")
    rep.table(["controller", "model", *truths, "holds"],
              [[c, m, *[a["per_truth"].get(t) for t in truths], a["holds"]]
               for c, per in result.across.items() for m, a in per.items()],
              digits=[None, None, *[3] * len(truths), None])
    rep.section("Ratios under each truth")
    by = {(r["truth"], r["controller"], r["model"], r["task"]): r for r in result.runs}
    for tr in truths:
        rep.section(f"Truth {tr}", level=3)
        rep.figure(figure_ratios(result, tr), f"RMS tracking-error ratio per controller and "
                   f"task under truth {tr} (log scale; no bar: not ranked).")
        rows = []
        for c in result.controllers:
            for t in result.tasks:
                base = by.get((tr, c, result.baseline, t)) or {}
                for m in others:
                    run = by.get((tr, c, m, t)) or {}
                    rat = (result.ratios.get(tr, {}).get(c, {}).get(t, {}).get(m) or {})
                    rows.append([c, t, m, rat.get("rms_error"), _um(run.get("rms_error")),
                                 _um(base.get("rms_error")), rat.get("max_error")])
        rep.table(["controller", "task", "model", "RMS ratio", "RMS (µm)",
                   f"{result.baseline} RMS (µm)", "max ratio"], rows,
                  digits=[None, None, None, 3, 3, 3, 3])
    rep.section("Not ranked")
    out = [r for r in result.runs if r["status"] != "ok"]
    if out:
        rep.paragraph("Runs that did not do the task, failed or could not be built: reported "
                      "with their errors, never ranked.")
        rep.table(["truth", "controller", "model", "task", "status", "RMS (µm)"],
                  [[r["truth"], r["controller"], r["model"], r["task"], r["status"],
                    _um(r["rms_error"])] for r in out], digits=[None] * 5 + [3])
    else:
        rep.paragraph("Every run did the task and is ranked.")
    if result.signals:
        rep.section("Tracking errors")
        for t in result.tasks:
            rep.figure(figure_tracking(result, t), f"Tracking error on {t} under truth "
                       f"{truths[0]}, every model.")
    rep.section("Robustness")
    rob = result.robustness
    if rob["samples"]:
        rep.paragraph(f"{rob['samples']} draws on `{rob['task']}`, spread over the truths "
                      f"(draw i under truth i mod {len(truths)}): every fitted parameter of "
                      f"the truth and the moving mass times a factor uniform in "
                      f"1 +- {rob['spread']:g}; every controller and model on the same draws.")
        rep.figure(figure_robustness(result), "RMS-error ratio to the baseline on every "
                   "draw (line: median).")
        rep.table(["controller", "model", "median ratio", "p10", "p90", "draws better",
                   "paired draws"],
                  [[c, m, r.get("median"), r.get("p10"), r.get("p90"), r.get("better"),
                    r.get("paired_draws")]
                   for c in result.controllers
                   for m, r in rob["controllers"][c]["ratio"].items()],
                  digits=[None, None, 3, 3, 3, 2, 0])
    else:
        rep.paragraph("No robustness draws (samples 0).")
    rep.section("Runs")
    rep.table(["truth", "controller", "model", "task", "status", "RMS (µm)", "max (µm)",
               "reversal (µm)", "hunting (µm)"],
              [[r["truth"], r["controller"], r["model"], r["task"], r["status"],
                *[_um(r[e]) for e in RATIO_ERRORS]]
               for r in result.runs], digits=[None] * 5 + [3, 3, 3, 3])
    return rep


__all__ = ["figure_across", "figure_ratios", "figure_robustness", "figure_tracking", "report"]
