"""Study ``presliding``, the figures: pressures, displacements and force loops of the runs.

Each function draws one figure of the report (:mod:`studies.presliding_report`)
from the cases (:mod:`studies.presliding_runs`) and the summary
(:mod:`studies.presliding_analysis`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fcomp.figstyle import legend_above
from studies.base import StudyOutput
from studies.presliding_analysis import MEM_LOOP_DEPTH, MEM_LOOP_START, MODELS
from studies.presliding_runs import Case

LABELS = {"nmlgm": "NMLGM", "nmlgm-hysteresis": "new model (NMLGM + F(z))"}
COLORS = {"nmlgm": "#c0392b", "nmlgm-hysteresis": "#2f6db5"}


def axes_style(ax: Any, title: str, xl: str, yl: str) -> None:
    ax.set_title(title, fontsize=9.5)
    ax.set_xlabel(xl)
    ax.set_ylabel(yl)
    ax.grid(True, alpha=0.3)


def fig_case(out: StudyOutput, case: Case, name: str, caption: str) -> None:
    fig, axes = out.subplots(1, 3, figsize=(11.5, 3.5))
    r = case.new
    axes[0].plot(r.t, r.p1 / 1e5, color="#444", lw=0.9, label="p1")
    axes[0].plot(r.t, r.p2 / 1e5, color="#999", lw=0.9, label="p2")
    axes_style(axes[0], "pressures", "t [s]", "p [bar gauge]")
    legend_above(axes[0])
    for key, run in (("nmlgm", case.nmlgm), ("nmlgm-hysteresis", case.new)):
        axes[1].plot(run.t, run.x * 1e3, color=COLORS[key], lw=0.9, label=LABELS[key])
        axes[2].plot(run.x * 1e3, run.F, color=COLORS[key], lw=0.9)
    axes_style(axes[1], "displacement", "t [s]", "x [mm]")
    legend_above(axes[1], ncol=1)
    axes_style(axes[2], "friction force - displacement", "x [mm]", "F [N]")
    out.figure(fig, name, caption)


def fig_fig4(out: StudyOutput, cases: list[Case], cyl: int) -> None:
    rows = [c for c in cases if c.cylinder == cyl and c.figure == "fig4"]
    fig, axes = out.subplots(1, len(rows), figsize=(3.8 * len(rows), 3.4), sharey=True)
    for ax, c in zip(np.atleast_1d(axes), rows, strict=True):
        for key, run in (("nmlgm", c.nmlgm), ("nmlgm-hysteresis", c.new)):
            ax.plot(run.x * 1e3, run.F, color=COLORS[key], lw=0.9, label=LABELS[key])
        axes_style(ax, c.programme.label, "x [mm]", "F [N]")
    legend_above(np.atleast_1d(axes)[0], ncol=1)
    paper_fig = {1: "4", 2: "7", 3: "8"}[cyl]
    out.figure(fig, f"fig{paper_fig}-cylinder{cyl}",
               f"Seed 000 Fig. {paper_fig} conditions, cylinder {cyl}: p1 raised to the paper's "
               "peak values and released (p2 = 0); friction force against displacement.")


def fig_replay(out: StudyOutput, cases: list[Case], res: dict[str, Any]) -> None:
    ref = next(c for c in cases if c.cylinder == 1 and c.figure == "fig10").new
    fig, axes = out.subplots(1, 2, figsize=(11.0, 3.8))
    axes[0].plot(ref.x * 1e3, ref.F, color="k", lw=1.4, label="reference (new model on the rig)")
    for key in MODELS:
        axes[0].plot(ref.x * 1e3, res["_replays"][key], color=COLORS[key], lw=0.9, ls="--",
                     label=f"{LABELS[key]}, driven by its velocity")
    axes_style(axes[0], "force-displacement (seed 000 Figs. 14, 19)", "x [mm]", "F [N]")
    legend_above(axes[0], ncol=1)
    axes[1].plot(ref.t, ref.F, color="k", lw=1.4, label="reference")
    for key in MODELS:
        axes[1].plot(ref.t, res["_replays"][key], color=COLORS[key], lw=0.9, ls="--",
                     label=LABELS[key])
    axes_style(axes[1], "friction force in time (seed 000 Fig. 20)", "t [s]", "F [N]")
    out.figure(fig, "replay",
               "Each model driven by the velocity of the reference run (Fig. 10 programme, "
               "cylinder 1), as the seed drove its Figs. 14 and 19: the NMLGM's loops have the "
               "wrong size and shape, the new model follows the reference.")


def fig_memory(out: StudyOutput, res: dict[str, Any]) -> None:
    fig, axes = out.subplots(1, 2, figsize=(11.0, 3.8), sharey=True)
    for ax, key in zip(axes, MODELS, strict=True):
        c = res["_memory"][key]["curves"]
        ax.plot(c["x_without"] * 1e3, c["F_without"], color="#bbb", lw=2.2,
                label="without internal loops")
        ax.plot(c["x_with"] * 1e3, c["F_with"], color=COLORS[key], lw=0.9,
                label="with two internal loops")
        axes_style(ax, LABELS[key], "x [mm]", "F [N]")
        legend_above(ax, ncol=1)
    out.figure(fig, "memory",
               "Memory protocol: a displacement cycle with two internal loops (starting at x = "
               f"{MEM_LOOP_START * 1e3:g} mm, {MEM_LOOP_DEPTH * 1e3:g} mm deep) over the same "
               "cycle without them. A model with nonlocal memory returns to the loop's start and "
               "continues on the grey curve.")


def fig_size(out: StudyOutput, cases: list[Case], res: dict[str, Any]) -> None:
    rows = [c for c in cases if c.cylinder == 1 and c.figure == "fig12a"]
    fig, axes = out.subplots(1, 2, figsize=(11.0, 3.8))
    for c in rows:
        p = max(w[1] for w in c.programme.waypoints)
        axes[0].plot(c.new.x * 1e3, c.new.F, lw=0.9, label=f"p1 to {p / 1e5:.2f} bar")
    axes_style(axes[0], "new model, Fig. 12a programmes", "x [mm]", "F [N]")
    legend_above(axes[0], ncol=1)
    ls = np.array(res["loop_size_vs_pressure"])
    axes[1].plot(ls[:, 0] / 1e5, ls[:, 1] * 1e3, "o-", color=COLORS["nmlgm-hysteresis"],
                 label="new model (p1 varied)")
    ln = np.array(res["loop_size_vs_pressure_nmlgm"])
    axes[1].plot(ln[:, 0] / 1e5, ln[:, 1] * 1e3, "s--", color=COLORS["nmlgm"],
                 label="NMLGM (p1 varied)")
    if "loop_size_vs_p2" in res:
        l2 = np.array(res["loop_size_vs_p2"])
        axes[1].plot(l2[:, 0] / 1e5, l2[:, 1] * 1e3, "^-", color="#8e44ad",
                     label="new model (p2 varied)")
    axes_style(axes[1], "loop size against pressure (Fig. 12)", "peak pressure [bar gauge]",
        "displacement span [mm]")
    legend_above(axes[1], ncol=1)
    out.figure(fig, "loop-size",
               "Seed 000 Fig. 12: the loop grows with the peak pressure (cylinder 1).")
