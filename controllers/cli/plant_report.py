"""The HTML report of ``fcomp plant check --report DIR``: the loop as it runs, drawn.

It opens with its conclusion (does the tuned loop meet the requirement
everywhere, and where is it tightest), then shows the Bode and Nyquist plots of
the loop at mid stroke and at its worst point, both break points (the valve
command, the position sensor), the margin map over the stroke (every grid point:
parameter box and friction regimes), each controller's margins as coded, the
tuning and the grid (:mod:`controllers.loop_analysis.summary`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fcomp import figstyle as fs
from fcomp.conclusions import Conclusion
from fcomp.report import Report

_BREAK = {"valve": "at the valve command", "position": "at the position sensor"}


def conclusion(doc: dict[str, Any]) -> Conclusion:
    """What the check found, first."""
    m = doc["margins"]
    w = m["worst"]
    gm = "inf" if w["gain"] is None else f"{w['gain']:.3g}"
    pm = "inf" if w["phase_deg"] is None else f"{w['phase_deg']:.1f} deg"
    where = (f"{100 * w['fraction']:.3g} % of the stroke, "
             f"{'sliding' if w['friction'] == 'sliding' else 'at rest in pre-sliding'}, "
             f"{_BREAK[w['break']]}")
    if m["meets"]:
        finding = (f"The tuned loop as it runs meets GM >= 2, PM >= 30 deg and Ms <= 2 at all "
                   f"{len(m['grid'])} grid points; it is tightest at {where} (GM {gm}, PM {pm},"
                   f" Ms {w['ms']:.3g}).")
        reasons: tuple[str, ...] = ()
        level = "high"
    else:
        finding = (f"The tuned loop misses the requirement at {where}: {w['why']}.")
        reasons = ("the tuning given in the plant file does not meet the requirement",)
        level = "low"
    failing = [n for n, c in m["controllers"].items() if c["worst"]["why"]]
    if failing:
        reasons = (*reasons, *(f"{n} as coded misses it: {m['controllers'][n]['worst']['why']}"
                               for n in failing))
        level = "medium" if level == "high" else level
    steps = ("the margins hold for the parameter box of [uncertainty]; widen it where you know "
             "less, and check again",)
    return Conclusion(finding, level, reasons, steps)


def _bode_nyquist(loop: Any, title: str) -> Any:
    """Bode magnitude and phase and the Nyquist curve of both open loops of a point."""
    fig, axes = fs.new_figure(height=6.2, nrows=2, ncols=2)
    dt = next(iter(loop.systems.values())).dt
    w = np.logspace(-1, math.log10(math.pi / dt), 1500)
    for brk, sys in loop.systems.items():
        L = np.asarray(sys(np.exp(1j * w * dt)), dtype=complex).reshape(-1)
        m = loop.margins[brk]
        lab = f"{_BREAK[brk]} (GM {m.gain:.3g}, PM {m.phase:.0f} deg, Ms {m.ms:.3g})" \
            if m.stable else f"{_BREAK[brk]} (unstable)"
        axes[0, 0].semilogx(w, 20 * np.log10(np.abs(L)), label=lab)
        axes[1, 0].semilogx(w, np.degrees(np.unwrap(np.angle(L))), label=lab)
        axes[0, 1].plot(L.real, L.imag, label=lab)
        axes[1, 1].plot(L.real, L.imag)
    axes[0, 0].axhline(0.0, color="0.5", lw=0.8)
    axes[0, 0].set_ylabel("|L| (dB)")
    axes[1, 0].set_ylabel("phase of L (deg)")
    axes[1, 0].set_xlabel("frequency (rad/s)")
    axes[0, 0].set_title(title)
    for ax, lim in ((axes[0, 1], 4.0), (axes[1, 1], 1.6)):
        t = np.linspace(0, 2 * math.pi, 200)
        ax.plot(-1 + 0.5 * np.cos(t), 0.5 * np.sin(t), color="0.6", lw=0.8, ls="--")
        ax.plot([-1], [0], "k+", ms=10)
        ax.set_xlim(-lim, lim * 0.6)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("Re L")
    axes[0, 1].set_ylabel("Im L")
    axes[1, 1].set_ylabel("Im L (near -1)")
    fs.legend_top(fig, axes[0, 0], ncol=1)
    return fig


def _margin_map(doc: dict[str, Any]) -> Any:
    """Gain margin, phase margin and Ms over the stroke: every grid point (box and friction
    regimes), the nominal sliding loop drawn as a line, the requirement as a band."""
    m = doc["margins"]
    fig, axes = fs.new_figure(height=6.4, nrows=3, sharex=True)
    keys = (("gain", "gain margin", 2.0), ("phase_deg", "phase margin (deg)", 30.0),
            ("ms", "peak sensitivity Ms", 2.0))
    marks = {"valve": "o", "position": "s"}
    colours = {"valve": "C0", "position": "C3"}
    for ax, (k, lab, req) in zip(axes, keys, strict=True):
        for brk in m["breaks"]:
            xs, ys, xn, yn = [], [], [], []
            for p in m["grid"]:
                v = p[brk][k]
                if v is None or not p[brk]["stable"]:
                    continue
                x = 100 * p["fraction"]
                xs.append(x)
                ys.append(v)
                if p["friction"] == "sliding" and not any(p["parameters"].values()):
                    xn.append(x)
                    yn.append(v)
            ax.plot(xs, ys, marks[brk], ms=3, alpha=0.35, color=colours[brk],
                    label=f"{_BREAK[brk]}, grid")
            order = np.argsort(xn)
            ax.plot(np.array(xn)[order], np.array(yn)[order], "-", lw=1.6, color=colours[brk],
                    label=f"{_BREAK[brk]}, nominal, sliding")
        ax.axhline(req, color="0.3", lw=1.0, ls="--")
        ax.set_ylabel(lab)
        if k == "gain":
            ax.set_yscale("log")
            fs.plain_log_ticks(ax)
    axes[-1].set_xlabel("position (% of the stroke)")
    fs.legend_top(fig, axes[0], ncol=2)
    return fig


def report(pf: Any, doc: dict[str, Any], loop: Any, command: str | None) -> Report:
    """The report of a plant check (module docstring)."""
    m = doc["margins"]
    rep = Report(f"Plant check: {doc['name']}",
                 subtitle=f"{doc['kind']} plant {doc['file']}: the loop as it runs",
                 command=command, config={"uncertainty": doc["uncertainty"]})
    rep.conclusion(conclusion(doc))
    rep.section("The loop at mid stroke and at its worst point")
    rep.paragraph(
        f"The sampled loop as it runs ({m['control_rate']:g} Hz, zero-order hold, "
        f"{m['delay']} sample(s) of computation delay): the plant linearised where it holds "
        "its load, the PID family's law with the force-to-valve inversion as coded. `L` is "
        "the loop broken at the valve command or at the position sensor, closed as `1 + L`; "
        "the dashed circle is `|1 + L| = 1/2` (Ms = 2).")
    rep.figure(_bode_nyquist(loop.refined["mid"], "mid stroke, nominal, sliding"),
               "Bode and Nyquist plots at mid stroke (nominal parameters, sliding piston).")
    wp = loop.grid.points[loop.worst].describe()
    rep.figure(_bode_nyquist(loop.refined["worst"], "worst point"),
               f"Bode and Nyquist plots at the worst point: {wp}.")
    rep.section("Margins over the stroke and the parameter box")
    rep.figure(_margin_map(doc), "Gain margin, phase margin and Ms at every grid point "
               "(markers), the nominal sliding loop (lines), the requirement (dashed).")
    rows = []
    for name, c in m["controllers"].items():
        w = c["worst"]
        rows.append([name, c["points"], c["where"], f"{100 * w['fraction']:.3g} %",
                     w["friction"], w["break"], w["gain"], w["phase_deg"], w["ms"],
                     w["why"] or "met"])
    rep.section("Each controller as coded")
    rep.table(["controller", "points", "where", "worst at", "friction", "break", "GM",
               "PM (deg)", "Ms", "requirement"], rows, digits=[None, None, None, None, None,
                                                               None, 3, 1, 3, None],
              caption="The controllers linearised as coded (Jacobians of their exported "
              "step) at their worst point.")
    rep.section("Tuning")
    rep.bullets(doc["tuning_lines"])
    rep.section("Grid")
    worst_rows = sorted(m["grid"], key=lambda p: min(
        (p[b]["gain"] or 1e9) / 2 if p[b]["stable"] else -1 for b in m["breaks"]))[:25]
    rep.table(["position (%)", "parameters", "friction", "GM valve", "PM valve", "Ms valve",
               "GM position", "PM position", "Ms position"],
              [[100 * p["fraction"],
                ", ".join(f"{k} {100 * v:+.3g}%" for k, v in p["parameters"].items() if v)
                or "nominal",
                p["friction"] if p["friction"] == "sliding"
                else f"pre-sliding x{p['presliding_factor']:.3g}",
                p["valve"]["gain"], p["valve"]["phase_deg"], p["valve"]["ms"],
                p["position"]["gain"], p["position"]["phase_deg"], p["position"]["ms"]]
               for p in worst_rows],
              caption=f"The 25 points of least gain margin of {len(m['grid'])} (all of them in "
              "the JSON's margins.grid).", digits=[3, None, None, 3, 1, 3, 3, 1, 3])
    rep.parameters({"uncertainty": doc["uncertainty"], "delay": m["delay"]})
    return rep


__all__ = ["conclusion", "report"]
