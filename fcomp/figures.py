"""Figures shared by the layers above: the legend placement and the plant-domain figure.

The diagnosis figures (:mod:`fcomp.diagnosis.figures`) and the plant-domain
comparison (:class:`plants.comparison.PlantComparison`) both draw here, below
either of them (matplotlib, object-oriented API, no pyplot state).
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure

from fcomp import figstyle as fs
from fcomp.figstyle import legend_above

__all__ = ["fig_plant", "legend_above"]




def fig_plant(comps: Any) -> Figure:
    """Plant domain: measured and simulated ``x``, ``p1``, ``p2`` of each record (one
    :class:`~plants.comparison.PlantComparison` or a list of them)."""
    items = comps if isinstance(comps, list | tuple) else [comps]
    names = [k for k in ("x", "p1", "p2") if any(k in c.rms for c in items)]
    fig, axes = fs.new_figure(height=2.4 * max(len(names), 1) + 0.6, nrows=max(len(names), 1),
                              squeeze=False, sharex=True)
    for ax, k in zip(axes[:, 0], names, strict=False):
        unit = fs.scale_of(k).unit
        for c in items:
            if k not in c.rms:
                continue
            line = fs.plot_gapped(ax, c.t, fs.scaled(k, c.measured[k]), lw=1.0,
                                  label=f"{c.label} measured")[0]
            fs.plot_gapped(ax, c.t, fs.scaled(k, c.predicted[k]), lw=1.0, ls="--",
                           color=line.get_color(),
                           label=f"{c.label} {c.plant} (RMS {fs.scaled(k, c.rms[k]):.3g} {unit})")
        ax.set_ylabel(fs.label(k))
        fs.legend_above(ax, ncol=2)
    if names:
        axes[len(names) - 1, 0].set_xlabel("t (s)")
    return fig
