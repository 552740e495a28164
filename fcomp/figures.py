"""Figures shared by the layers above: the legend placement and the plant-domain figure.

The diagnosis figures (:mod:`fcomp.diagnosis.figures`) and the plant-domain
comparison (:class:`plants.comparison.PlantComparison`) both draw here, below
either of them (matplotlib, object-oriented API, no pyplot state).
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure

from fcomp.figstyle import legend_above

__all__ = ["fig_plant", "legend_above"]




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
        legend_above(ax, ncol=2)
    if names:
        fig.axes[-1].set_xlabel("t (s)", fontsize=8)
    fig.tight_layout()
    return fig
