"""The figures of docs/design.md from the design chain's results.

    python benchmarks/design_chain.py --seeds 31 32 --out chain.json
    python docs/make_design_figures.py chain.json [more.json ...]   # docs/figures/design_*.png

``design_separation.png``: predicted against achieved separation of every rival pair along
the recorded programme (the factor-2 band shaded); ``design_stderr.png``: each undetermined
value's standard error before, predicted after, and achieved after the re-diagnosis.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402

from fcomp import figstyle  # noqa: E402

FIGURES = Path(__file__).resolve().parent / "figures"


def main(paths: list[str]) -> None:
    rows = [r for p in paths for r in json.loads(Path(p).read_text())]
    qs = [q for r in rows for q in r.get("questions", [])]
    pairs = [q for q in qs if q["kind"] != "parameter" and q.get("achieved") is not None]
    with figstyle.style():
        fig, ax = figstyle.new_figure(3.6)
        for kind, mark in (("tie", "o"), ("untested", "s")):
            mine = [q for q in pairs if q["kind"] == kind]
            if mine:
                ax.loglog([q["predicted"] for q in mine], [q["achieved"] for q in mine], mark,
                          label=kind)
        lim = np.array([0.1, 100.0])
        ax.fill_between(lim, lim / 2, lim * 2, alpha=0.15, label="within a factor of 2")
        ax.plot(lim, lim, "k-", lw=0.8)
        ax.set_xlabel("predicted separation (noise floors)")
        ax.set_ylabel("achieved (noise floors)")
        figstyle.legend_above(ax, ncol=3)
        figstyle.save(fig, FIGURES / "design_separation.png")
        params = [q for q in qs if q["kind"] == "parameter" and q.get("before")]
        if params:
            fig, ax = figstyle.new_figure(3.6)
            x = np.arange(len(params))
            for off, key, lab in ((-0.25, "before", "before"), (0.0, "predicted",
                                                                "predicted after"),
                                  (0.25, "achieved", "achieved after")):
                ax.bar(x + off, [q.get(key) or np.nan for q in params], 0.25, label=lab)
            ax.set_yscale("log")
            ax.set_xticks(x, [q["label"] for q in params], rotation=45)
            ax.set_ylabel("standard error")
            figstyle.legend_above(ax, ncol=3)
            figstyle.save(fig, FIGURES / "design_stderr.png")


if __name__ == "__main__":
    main(sys.argv[1:])
