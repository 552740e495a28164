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
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from fcomp.diagnosis.compare import worst_segments
from fcomp.diagnosis.features import feature_values
from fcomp.diagnosis.loop import Diagnosis
from fcomp.diagnosis.regimes import REGIMES
from fcomp.effects import EFFECTS
from fcomp.errors import FcompError
from fcomp.report import Report

_UNITS = {"t": "s", "v": "m/s", "a": "m/s^2", "x": "m", "p1+p2": "Pa",
          "time_since_reversal": "s", "displacement_since_reversal": "m", "dwell_time": "s"}
_COLORS = {"measured": "0.25", "baseline": "#c0392b", "final": "#2356a8"}


def _check(diag: Diagnosis) -> None:
    if not hasattr(diag, "verdict_"):
        raise FcompError("the diagnosis is not fitted: call fit(data) before drawing it")


def fig_regimes(diag: Diagnosis) -> Figure:
    """Held-out RMS error per regime, baseline and final model."""
    fig = Figure(figsize=(7.0, 3.4))
    ax = fig.add_subplot()
    names = [*REGIMES, "all"]
    xs = np.arange(len(names))
    for k, (which, off) in enumerate((("baseline", -0.2), ("final", 0.2))):
        vals = [diag.regimes_[which][n]["rms"] or 0.0 for n in names]
        ax.bar(xs + off, vals, width=0.4, color=_COLORS[which],
               label=f"{which}: {diag.baseline_fit_.model.describe() if k == 0 else diag.fit_.model.describe()}")
    ax.axhline(diag.noise_floor_.value, color="0.4", ls="--", lw=1, label="noise floor")
    ax.set_xticks(xs, [f"{n}\n(n={diag.regimes_['final'][n]['n']})" for n in names], fontsize=8)
    ax.set_ylabel("held-out RMS error (N)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def fig_residuals(diag: Diagnosis) -> Figure:
    """Held-out residual against each feature (baseline and final), with binned means."""
    feats = feature_values(diag.data_, diag.segmentation_)
    te = diag.split_.test
    n = len(feats)
    cols = 4
    rows = math.ceil(n / cols)
    fig = Figure(figsize=(12.0, 2.8 * rows))
    strength = {f.feature: f.strength for f in diag.residual_features_}
    for i, (name, f) in enumerate(feats.items()):
        ax = fig.add_subplot(rows, cols, i + 1)
        for which, res in (("baseline", diag.baseline_fit_), ("final", diag.fit_)):
            r = res.residual[te]
            ax.plot(f[te], r, ".", ms=1.5, alpha=0.35, color=_COLORS[which])
            order = np.argsort(f[te])
            fb, rb = f[te][order], r[order]
            nb = max(5, min(40, fb.size // 50))
            edges = np.linspace(0, fb.size, nb + 1).astype(int)
            cx = [fb[a:b].mean() for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]
            cy = [rb[a:b].mean() for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]
            ax.plot(cx, cy, "-", color=_COLORS[which], lw=1.5, label=which)
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(f"{name} ({_UNITS.get(name, '-')})", fontsize=8)
        ax.set_title(f"final strength {strength.get(name, 0.0):.2f}", fontsize=8)
        ax.tick_params(labelsize=7)
        if i % cols == 0:
            ax.set_ylabel("residual y - F (N)", fontsize=8)
        if i == 0:
            ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def fig_loops(diag: Diagnosis) -> Figure:
    """Measured and modelled force-velocity and force-displacement loops (held-out)."""
    fig = Figure(figsize=(11.0, 4.0))
    te = diag.split_.test
    v, x, y = diag.data_.signal("v"), diag.data_.signal("x"), diag.data_.y
    ax1 = fig.add_subplot(1, 2, 1)
    ax2 = fig.add_subplot(1, 2, 2)
    for ax, q, lab in ((ax1, v, "velocity v (m/s)"), (ax2, x, "position x (m)")):
        ax.plot(q[te], y[te], ".", ms=1.5, color=_COLORS["measured"], label="measured")
        ax.plot(q[te], diag.baseline_fit_.F_hat[te], ".", ms=1.0, color=_COLORS["baseline"],
                label="baseline")
        ax.plot(q[te], diag.fit_.F_hat[te], ".", ms=1.0, color=_COLORS["final"], label="final")
        ax.set_xlabel(lab)
        ax.set_ylabel("friction force (N)")
    ax1.legend(fontsize=7, markerscale=6)
    if diag.data_.steady_state:
        ax1.set_title("steady-state points", fontsize=9)
    fig.tight_layout()
    return fig


def _window_plot(ax: Any, diag: Diagnosis, a: int, b: int, title: str) -> None:
    t = diag.data_.signal("t")
    ax.plot(t[a:b], diag.data_.y[a:b], color=_COLORS["measured"], lw=1.0, label="measured")
    ax.plot(t[a:b], diag.baseline_fit_.F_hat[a:b], color=_COLORS["baseline"], lw=1.0,
            label="baseline")
    ax.plot(t[a:b], diag.fit_.F_hat[a:b], color=_COLORS["final"], lw=1.0, ls="--", label="final")
    ax.set_title(title, fontsize=8)
    ax.set_xlabel("t (s)", fontsize=8)
    ax.set_ylabel("F (N)", fontsize=8)
    ax.tick_params(labelsize=7)


def worst_windows(diag: Diagnosis, count: int = 3) -> list[tuple[int, int, float]]:
    """The ``count`` held-out windows (about 0.25 s) where the baseline fails most."""
    width = max(10, int(round(0.25 / diag.data_.scales.dt)))
    bounds = [e.start for e in diag.data_.experiments[1:]]
    segs = worst_segments(diag.baseline_fit_.residual, diag.split_.test, width, count, bounds)
    return [(s.start, s.stop, s.rms) for s in segs]


def fig_worst(diag: Diagnosis) -> Figure:
    """The worst held-out windows of the baseline, with the final model."""
    wins = worst_windows(diag)
    fig = Figure(figsize=(11.0, 3.2))
    for i, (a, b, rms) in enumerate(wins):
        ax = fig.add_subplot(1, max(len(wins), 1), i + 1)
        pad = (b - a) // 2
        a0, b0 = max(a - pad, 0), min(b + pad, diag.data_.n)
        counts = np.bincount(diag.segmentation_.regime[a:b], minlength=len(REGIMES))
        _window_plot(ax, diag, a0, b0, f"baseline RMS {rms:.3g} N, mostly "
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


def fig_before_after(diag: Diagnosis) -> Figure:
    """A held-out stretch of about two seconds: measured, baseline and final force."""
    te = diag.split_.test
    idx = np.flatnonzero(te)
    fig = Figure(figsize=(11.0, 3.2))
    ax = fig.add_subplot()
    if idx.size:
        width = max(20, int(round(2.0 / diag.data_.scales.dt)))
        r = diag.baseline_fit_.residual ** 2 - diag.fit_.residual ** 2
        c = np.concatenate([[0.0], np.cumsum(np.where(te, r, 0.0))])
        starts = idx[idx + width <= diag.data_.n]
        a = int(starts[np.argmax(c[starts + width] - c[starts])]) if starts.size else int(idx[0])
        _window_plot(ax, diag, a, min(a + width, diag.data_.n),
                     "held-out stretch where the added effects matter most")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


FIGURES = {
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
                      f"-> {other['rms_final']:.4g} N.")
    if d["warnings"]:
        rep.section("What a careful engineer would question", level=3)
        rep.table(["warning", "parameter", "what it means"],
                  [[w["code"], w["parameter"] or "", w["message"]] for w in d["warnings"]],
                  caption="Plausibility of the fits (baseline, each accepted step, final model) "
                  "and what the held-out samples cannot judge.")
    sig = d["signals"]
    rep.table(["quantity", "value", "unit"], [
        ["velocity driving the friction states", f"{sig['velocity']} -- {sig['reason']}", ""],
        ["samples left out (motion the position misses)", sig.get("unresolved_samples", 0),
         ""],
        ["held-out RMS, baseline", d["rms_baseline"], "N"],
        ["held-out RMS, final", d["rms_final"], "N"],
        ["noise floor (" + nf.method + f", {nf.n_samples} samples)", nf.value, "N"],
        ["held-out split", diag.split_.description, ""],
        ["experiments", len(diag.data_.experiments), ""],
        ["force from", diag.data_.source, ""],
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
                 EFFECTS.get(c.effect).signature, c.reason] for c in diag.candidates_]
        rep.table(["candidate", "held-out RMS (N)", "z", "p", "dBIC", "qualifies",
                   "residual signature it explains", "why not"], rows,
                  digits=[None, 4, 2, 3, 1, None, None, None])
    if diag.skipped_:
        rep.table(["effect", "not a candidate because"],
                  [[k, v] for k, v in sorted(diag.skipped_.items())])
    if d["ties"]:
        rep.section("Confounded effects", level=3)
        for group in d["ties"]:
            rep.paragraph("These explain the data equally well: " +
                          ", ".join(f"`{e}`" for e in group) + f"; `{group[0]}` was added. "
                          "The experiments that tell them apart:")
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
    """Write ``DIRECTORY/report.html`` (self-contained) and return its path."""
    out = Path(directory)
    if out.exists() and not out.is_dir():
        raise FcompError(f"--report {out}: exists and is not a directory")
    rep = build_report(diag, command=command)
    out.mkdir(parents=True, exist_ok=True)
    return rep.write(out / "report.html")
