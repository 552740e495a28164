"""Study ``missing-physics``: the diagnose loop end to end, on a generated case and on real data.

The loop of ``fcomp diagnose`` (:class:`fcomp.diagnosis.Diagnosis`): compare a
baseline friction model with a measurement, find which physical effect of
the catalogue is missing, add it, refit, and watch the held-out error fall
to the noise floor -- or say that structure is left which no catalogue
entry explains.

Two kinds of data:

**Generated cases** (:func:`fcomp.synthetic.generate`): a rig measurement
from an independent truth (its own integrator and, where an effect admits
several laws, a different law from the package's) with one *hidden* effect
and coloured force noise of known standard deviation. The truth is kept
apart; the study then checks what the loop cannot see: whether the added
effect is the hidden one (or tied with it), whether the final held-out
error reaches the true noise level, and whether the noise floor estimated
from the data matches the noise that was added. One case hides an effect
*outside* the catalogue (``ripple``, a rod scratch): the honest answer there
is ``unexplained-structure``.

**Real data**: the TU Delft pneumatic seal-friction tests (Zillen, Vallery &
Smit; ``fcomp.datasets``, CC0), a 25 mm cylinder with the chamber held at
constant pressure and the piston pushed back and forth, diagnosed from the
Coulomb-viscous baseline (seed 001's model).

Every diagnosis is written in full beside the study report
(``DIR/diagnosis-CASE/report.html``, the report of ``fcomp diagnose``) and
summarised here; summary.json holds the ``fcomp diagnose`` JSON of each.
All errors in newtons, on held-out data.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fcomp import conclusions
from fcomp.errors import FcompError
from fcomp.figstyle import legend_above
from fcomp.measurement import Measurement
from fcomp.parallel import run_tasks
from fcomp.progress import progress_bar, ticker
from fcomp.report import Link
from studies.base import Finding, Study, StudyConfig, StudyOutput

#: Colours of the models in the stretch figure (baseline, then the final model).
STRETCH_COLORS = ("#c0392b", "#2356a8", "#27864a")


@dataclass(frozen=True)
class GeneratedCase:
    """A synthetic measurement with one hidden effect, diagnosed from ``baseline``."""

    hidden: str
    base: str = "lugre"
    baseline: str = "lugre"
    seed: int = 1
    noise_std: float = 0.4

    @property
    def name(self) -> str:
        return f"generated-{self.hidden}"


@dataclass(frozen=True)
class RealCase:
    """A file of a shipped data set, diagnosed from ``baseline``."""

    dataset: str
    file: str
    baseline: str

    @property
    def name(self) -> str:
        stem = self.file.rsplit(".", 1)[0].replace("_", "-").lower()
        return f"{self.dataset}-{stem}-{self.baseline}"


#: Full run: three hidden catalogue effects, one outside the catalogue, two real files.
#: (The Stribeck hump is hidden from a Coulomb-viscous baseline: LuGre already has one.)
GENERATED = (GeneratedCase("pressure-dependence"),
             GeneratedCase("stribeck", base="coulomb-viscous", baseline="coulomb-viscous"),
             GeneratedCase("dwell-time"), GeneratedCase("ripple"))
REAL = (RealCase("zillen", "O-ring_3bar.csv", "coulomb-viscous"),
        RealCase("zillen", "NAPN_3bar.csv", "coulomb-viscous"))
#: Fast mode (CI): one generated case, one real file, a shorter search.
FAST_GENERATED = (GeneratedCase("pressure-dependence"),)
FAST_REAL = (RealCase("zillen", "O-ring_3bar.csv", "coulomb-viscous"),)
#: Relative run time of the cases (CPU seconds of a full run), to start the longest first.
CASE_COST = {"zillen-o-ring-3bar-coulomb-viscous": 48.0, "zillen-napn-3bar-coulomb-viscous": 35.0,
             "generated-pressure-dependence": 31.0, "generated-dwell-time": 10.0,
             "generated-ripple": 7.0, "generated-stribeck": 5.0}
#: Diagnosis options: full run and fast mode. The fast mode, which exercises the pipeline,
#: leaves out the baseline check (a second diagnosis of each case from a baseline of the
#: other kind: half its run time); each diagnosis report says so.
OPTIONS: dict[str, Any] = {"max_steps": 4, "max_nfev": 60}
FAST_OPTIONS: dict[str, Any] = {"max_steps": 2, "max_nfev": 30, "check_baseline": False}
#: Why a fast run's diagnosis has no baseline check (its report and JSON say it).
FAST_NO_CHECK = "not run in fast mode"
#: Synthetic record: duration (s), experiments, rate (Hz). The fast mode keeps it: with
#: fewer held-out blocks the loop's permutation test cannot reach its significance level.
RECORD = {"duration": 12.0, "experiments": 3, "rate": 500.0}
FAST_RECORD = RECORD


def _diagnose(data: Measurement, baseline: str, options: dict[str, Any]) -> Any:
    import dataclasses

    from fcomp.diagnosis import Diagnosis

    diag = Diagnosis(baseline, progress=False, **options).fit(data)
    if options.get("check_baseline", "auto") is False:  # the fast mode's: say why
        diag.result_ = dataclasses.replace(diag.result_, check={"ran": False,
                                                                "why": FAST_NO_CHECK})
    return diag


def recovered(hidden: str, result: dict[str, Any]) -> bool:
    """Did the loop find ``hidden``: added it, or added an effect tied with it?

    For an effect outside the catalogue, recovering it means saying so: the
    verdict is ``unexplained-structure``.
    """
    from fcomp.synthetic import OUTSIDE

    if hidden in OUTSIDE:
        return result["verdict"] == "unexplained-structure"
    if hidden in result["added"]:
        return True
    return any(hidden in group for group in result["ties"])


def run_generated(case: GeneratedCase, record: dict[str, Any],
                  options: dict[str, Any]) -> tuple[dict[str, Any], Any]:
    """Generate, diagnose, and judge one case against its hidden truth."""
    from fcomp.synthetic import OUTSIDE, generate

    rec = generate([case.hidden], base=case.base, seed=case.seed, noise_std=case.noise_std,
                   **record)
    diag = _diagnose(rec.measurement, case.baseline, options)
    res = diag.to_dict()
    out = {
        "case": case.name, "hidden": case.hidden, "truth_base": case.base,
        "in_catalogue": case.hidden not in OUTSIDE,
        "recovered": recovered(case.hidden, res),
        "true_noise_std": case.noise_std,
        "noise_floor_error": res["noise_floor"] / case.noise_std - 1.0,
        "final_over_true_noise": res["rms_final"] / case.noise_std,
        "samples": int(rec.measurement.columns["t"].size),
        "diagnosis": res,
    }
    return out, diag


def run_real(case: RealCase, options: dict[str, Any]) -> tuple[dict[str, Any], Any]:
    """Diagnose one shipped measurement."""
    import fcomp.datasets as datasets

    data = datasets.load(case.dataset, case.file)
    diag = _diagnose(data, case.baseline, options)
    res = diag.to_dict()
    return {"case": case.name, "dataset": case.dataset, "file": case.file,
            "samples": int(data.columns["t"].size), "fall": 1.0 - res["rms_final"]
            / res["rms_baseline"], "diagnosis": res}, diag


def findings(res: dict[str, Any]) -> list[str]:
    """Conclusions from the numbers."""
    out = []
    for g in res["generated"]:
        d = g["diagnosis"]
        what = (f"added {', '.join(d['added']) or 'nothing'}" +
                (f" (tied: {'; '.join(', '.join(t) for t in d['ties'])})" if d["ties"] else ""))
        out.append(
            f"Hidden `{g['hidden']}` ({'in' if g['in_catalogue'] else 'outside'} the catalogue) "
            f"on a `{g['truth_base']}` truth, baseline `{d['baseline']}`: {what}; held-out RMS "
            f"{d['rms_baseline']:.3f} -> {d['rms_final']:.3f} N against a true noise of "
            f"{g['true_noise_std']:.2f} N (estimated floor {d['noise_floor']:.3f} N); verdict "
            f"`{d['verdict']}`: " + ("recovered." if g["recovered"] else "NOT recovered."))
    for r in res["real"]:
        d = r["diagnosis"]
        out.append(
            f"Real data `{r['file']}` ({r['samples']} samples), baseline `{d['baseline']}`: "
            f"added {', '.join(d['added']) or 'nothing'}"
            + (f" (tied: {'; '.join(', '.join(t) for t in d['ties'])})" if d["ties"] else "")
            + f"; held-out RMS {d['rms_baseline']:.3f} -> {d['rms_final']:.3f} N "
            f"({100 * r['fall']:.0f} % lower), noise floor {d['noise_floor']:.3f} N, verdict "
            f"`{d['verdict']}`"
            + (f"; the residual still follows {d['residual_features'][0]['feature']}."
               if d["verdict"] != "explained" and d["residual_features"] else "."))
    return out


def below_floor(case: dict[str, Any]) -> str | None:
    """A flag when a case's final held-out RMS error lies below the noise floor estimated
    from its data, by the rule of ``fcomp diagnose`` (:func:`fcomp.conclusions.below_floor`:
    a model cannot beat the noise on samples it was not fitted to), else ``None``."""
    d = case["diagnosis"]
    final, floor = d.get("rms_final"), d.get("noise_floor")
    if not conclusions.below_floor(final, floor):
        return None
    name = case.get("file") or case["case"]
    return (f"`{name}`: the final model's held-out RMS error, {final:.3f} N, is "
            f"{100 * (1 - final / floor):.0f} % below the noise floor estimated from the data, "
            f"{floor:.3f} N. No model beats the noise on data it was not fitted to: either it "
            "over-fits (the held-out samples are not independent of the fitted ones) or the "
            f"floor estimate is too high. Its verdict `{d['verdict']}` is not confirmed.")


def finding(res: dict[str, Any]) -> Finding:
    """The conclusion: does the loop find the hidden effect, what it does on real data, and
    the numbers not to trust (a held-out error below the noise floor)."""
    gen, real = res["generated"], res["real"]
    n_ok = sum(g["recovered"] for g in gen)
    status, level = (("confirmed", "ok") if n_ok == len(gen) else
                     ("partly confirmed", "warn") if n_ok else ("not confirmed", "bad"))
    found = (f"The diagnose loop found the hidden effect in {n_ok} of {len(gen)} generated "
             "cases (" + "; ".join(
                 f"{g['hidden']}: {g['diagnosis']['rms_baseline']:.2f} -> "
                 f"{g['diagnosis']['rms_final']:.2f} N held-out RMS against "
                 f"{g['true_noise_std']:.2f} N of noise" for g in gen) + ")")
    if real:
        found += ("; on the real records it lowered the held-out error " + "; ".join(
            f"of {r['file']} from {r['diagnosis']['rms_baseline']:.2f} to "
            f"{r['diagnosis']['rms_final']:.2f} N by adding "
            f"{', '.join(r['diagnosis']['added']) or 'nothing'}" for r in real))
    return Finding(
        status, level, found + ".",
        sure=f"{len(gen)} generated case(s), one noise seed each, and {len(real)} real "
             "record(s); on real data there is no truth to check the added effects against, "
             "only the held-out error and the noise floor estimated from the same data.",
        next="run fcomp diagnose on your own records; where the final error sits at or below "
             "the noise floor, confirm the added effects on a second record (or a longer one) "
             "before building them into a compensator.",
        flags=[f for f in (below_floor(c) for c in (*gen, *real)) if f],
        confidence="high" if len(gen) >= 3 and n_ok == len(gen) else "medium")


@dataclass(frozen=True)
class CaseJob:
    """One case of the study as a picklable job (:func:`run_case`): the case, how to run it
    and the folder its full diagnosis report goes to."""

    case: GeneratedCase | RealCase
    record: dict[str, Any]
    options: dict[str, Any]
    folder: Path
    command: str


def run_case(job: CaseJob) -> tuple[dict[str, Any], dict[str, bytes]]:
    """Diagnose one case, write its full diagnosis report, render the study's figures of it.

    Returns the case's results and its figures (PNG bytes by name): everything
    the report needs, so the case can run in another process.
    """
    from fcomp.diagnosis.figures import fig_before_after, fig_error_fall
    from fcomp.diagnosis.report import write_report as write_diagnosis
    from fcomp.figstyle import apply_floor
    from fcomp.report import render_png

    if isinstance(job.case, GeneratedCase):
        res, diag = run_generated(job.case, job.record, job.options)
    else:
        res, diag = run_real(job.case, job.options)
    write_diagnosis(diag, job.folder, command=job.command)
    fall = fig_error_fall(diag)
    apply_floor(fall)
    return res, {"error-fall": render_png(fall),
                 "before-after": render_png(fig_stretch(diag, fig_before_after(diag)))}


def fig_stretch(diag: Any, chosen: Any) -> Any:
    """The held-out stretch of ``chosen`` (the diagnosis figure that picks where the added
    effects matter most; its time range is reused): measured force, baseline and final
    model, with the velocity and the position that explain them beneath; lines break at
    gaps and experiment boundaries."""
    from fcomp import figstyle
    from fcomp.diagnosis.figures import view

    lines = chosen.axes[0].lines if chosen.axes else []
    span = lines[0].get_xdata() if lines else np.array([])
    vw = view(diag)
    t = vw.data.signal("t")
    a, b = ((int(np.searchsorted(t, span[0])), int(np.searchsorted(t, span[-1], "right")))
            if len(span) else (0, t.size))
    starts = [e.start - a for e in vw.data.experiments if a < e.start < b]
    sig = {"v": figstyle.scaled("v", vw.data.signal("v")[a:b])}
    if vw.data.available.get("x"):  # a measured position
        sig["x"] = figstyle.scaled("x", vw.data.signal("x")[a:b])
    fig, axes = figstyle.new_figure(height=2.4 + 1.6 * len(sig), nrows=1 + len(sig),
                                    sharex=True,
                                    gridspec_kw={"height_ratios": [2.0] + [1.0] * len(sig)})
    tt, y, *models = figstyle.break_gaps(t[a:b], vw.data.y[a:b],
                                         *(sr.fit.F_hat[a:b] for sr in vw.series), starts=starts)
    axes[0].plot(tt, y, color="#222222", lw=1.1, label="measured")
    for k, (sr, F) in enumerate(zip(vw.series, models, strict=True)):
        axes[0].plot(tt, F, lw=1.3, ls="--" if k == len(models) - 1 and k else "-",
                     color=STRETCH_COLORS[k % len(STRETCH_COLORS)],
                     label=sr.label.split(":")[0])
    axes[0].set_ylabel("force (N)")
    legend_above(axes[0], ncol=len(vw.series) + 1)
    labels = {"v": figstyle.label("velocity", "v"), "x": figstyle.label("position", "x")}
    for ax, (key, values) in zip(axes[1:], sig.items(), strict=True):
        ax.plot(*figstyle.break_gaps(t[a:b], values, starts=starts), color="#4a6fa5", lw=1.1)
        ax.set_ylabel(labels[key])
        if key == "v":
            ax.axhline(0.0, color="#999999", lw=0.8)
    axes[-1].set_xlabel("time (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
    return fig


def _case_section(out: StudyOutput, name: str, title: str, res: dict[str, Any],
                  figures: dict[str, bytes], link: str) -> None:
    rep = out.report
    d = res["diagnosis"]
    rep.section(title, level=3)
    rep.table(["step", "effect", "RMS before [N]", "RMS after [N]", "accepted"],
              [[i + 1, s["effect"], s["rms_before"], s["rms_after"], s["accepted"]]
               for i, s in enumerate(d["steps"])],
              caption=f"The loop on `{name}` (held-out errors; noise floor "
              f"{d['noise_floor']:.3f} N).", digits=[0, None, 4, 4, None])
    if d["candidates"]:
        rep.table(["first-step candidate", "held-out RMS [N]"],
                  [[c["effect"], c["rms_heldout"]] for c in d["candidates"][:6]],
                  caption="First step: the best candidates (all in the full report).",
                  digits=[None, 4])
    out.figure(figures["error-fall"], f"{name}-error-fall",
               f"`{name}`: held-out RMS error after each accepted step; dashed: noise floor.")
    out.figure(figures["before-after"], f"{name}-before-after",
               f"`{name}`: measured force, baseline and final model over a held-out stretch, "
               "with the piston's velocity (and position, where measured) that explain it; "
               "lines break where samples are missing.")
    rep.bullets([Link(f"full diagnosis report of {name}", link)])


def _added(d: dict[str, Any]) -> str:
    """The effects added, and in brackets those tied with them."""
    ties = "; ".join(", ".join(t) for t in d["ties"])
    return (", ".join(d["added"]) or "nothing") + (f" ({ties})" if ties else "")


def _fall(d: dict[str, Any]) -> str:
    return f"{d['rms_baseline']:.3f} -> {d['rms_final']:.3f}"


def _verdict(case: dict[str, Any]) -> str:
    """The verdict, with a flag where the final error lies below the noise floor."""
    verdict = case["diagnosis"]["verdict"]
    return verdict + (" (below the noise floor: check)" if below_floor(case) else "")


class MissingPhysicsStudy(Study):
    """The diagnose loop end to end on generated and real data."""

    name = "missing-physics"
    cost = 150.0
    title = "Missing physics: the diagnose loop on generated and real measurements"
    summary = ("Compare, find the missing effect, add it, watch the held-out error fall: on "
               "generated cases with a hidden effect and on the TU Delft seal-friction tests.")
    figure_label = "Report figure"
    table_label = "Report table"

    def headline(self, results: dict[str, Any]) -> str:
        g = results["generated"]
        r = results["real"]
        return (f"hidden effect recovered in {sum(x['recovered'] for x in g)} of {len(g)} "
                f"generated cases; real data: " + ", ".join(
                    f"{x['file']} {x['diagnosis']['rms_baseline']:.2f} -> "
                    f"{x['diagnosis']['rms_final']:.2f} N" for x in r))

    def finding(self, results: dict[str, Any]) -> Finding:
        return finding(results)

    def key_figure(self, results: dict[str, Any]) -> str | None:
        cases = [*results["real"], *results["generated"]]
        return f"{cases[0]['case']}-before-after" if cases else None

    def build(self, out: StudyOutput, config: StudyConfig) -> dict[str, Any]:
        gen = FAST_GENERATED if config.fast else GENERATED
        real = FAST_REAL if config.fast else REAL
        options = FAST_OPTIONS if config.fast else OPTIONS
        record = FAST_RECORD if config.fast else RECORD
        # the cases run side by side on local processes, each diagnosis in its own process
        # (n_jobs 1: the same results, without a pool per diagnosis); with a cluster the
        # cases run here in turn and the cluster runs their candidate refits
        parallel = {"scheduler": config.scheduler} if config.scheduler else {"n_jobs": 1}
        command = f"(part of) {config.command or 'fcomp study'}"
        cases: list[GeneratedCase | RealCase] = [*gen, *real]
        jobs = [CaseJob(c, record, {**options, **parallel},
                        out.directory / f"diagnosis-{c.name}", command) for c in cases]
        order = sorted(range(len(jobs)), key=lambda i: -CASE_COST.get(cases[i].name, 1.0))
        bar = progress_bar("missing-physics", len(jobs), unit="case", enabled=config.progress)
        try:
            done = run_tasks(run_case, [jobs[i] for i in order],
                             workers=1 if config.scheduler else config.local_workers(),
                             progress=ticker(bar))
        finally:
            bar.close()
        ran: dict[str, tuple[dict[str, Any], dict[str, bytes]]] = {
            cases[i].name: r for i, r in zip(order, done, strict=True)}
        results: dict[str, Any] = {"generated": [ran[c.name][0] for c in gen],
                                   "real": [ran[c.name][0] for c in real]}
        figures = {name: r[1] for name, r in ran.items()}
        results["settings"] = {"options": options, "record": record,
                               "units": {"rms": "N", "noise_floor": "N"}}
        results["findings"] = findings(results)
        if not results["generated"] or not results["real"]:
            raise FcompError("missing-physics: no case was run")

        rep = out.report
        rep.section("Findings")
        rep.bullets(results["findings"])
        if config.fast:
            rep.note("Fast mode (CI): one generated case, one real file, at most two steps and "
                     "a smaller fit budget; run without `--fast` for the full set.", kind="info")
        rep.section("Method")
        rep.paragraph(
            "Each measurement goes through `fcomp.diagnosis.Diagnosis` (the engine of "
            "`fcomp diagnose`): experiments cut and segmented into regimes, a held-out split, "
            "the noise floor estimated from the data, the baseline fitted, then every "
            "applicable catalogue effect added in turn, the model refitted and scored on "
            "held-out samples; an effect is accepted only if the error falls clearly and "
            "significantly and the information criterion agrees.")
        rep.paragraph(
            "Generated cases come from `fcomp.synthetic`, which never imports the package's "
            "models: a truth friction with one hidden effect (for the Stribeck hump a "
            "Lorentzian law, for the dwell time Kato's law on the measured dwell), coloured "
            f"force noise of {GENERATED[0].noise_std:g} N. The truth is used only afterwards, "
            "to judge the outcome.")
        rep.section("Generated cases")
        rep.table(["hidden", "added (tied)", "RMS [N]", "noise / floor [N]", "verdict",
                   "recovered"],
                  [[g["hidden"], _added(g["diagnosis"]), _fall(g["diagnosis"]),
                    f"{g['true_noise_std']:.2f} / {g['diagnosis']['noise_floor']:.3f}",
                    _verdict(g), "yes" if g["recovered"] else "no"]
                   for g in results["generated"]],
                  caption="The loop against the hidden truth: the effect hidden in the data, "
                  "the effects added (in brackets: tied with them), the held-out RMS error of "
                  "the baseline and the final model, the true noise and the floor estimated "
                  "from the data.")
        for g in results["generated"]:
            _case_section(out, g["case"], f"Hidden {g['hidden']}", g, figures[g["case"]],
                          f"diagnosis-{g['case']}/report.html")
        rep.section("Real data: TU Delft seal-friction tests")
        rep.paragraph(
            "Zillen, Vallery & Smit (TU Delft, CC0): a 25 mm pneumatic cylinder, chamber at "
            "constant pressure, the piston pushed back and forth over about 40 mm at 5-20 mm/s "
            "by a load cell; friction F = p A + F_ext - m a. No measured mass is given; the "
            "diagnosis treats the inertia term like any other candidate.")
        rep.table(["file", "baseline", "added (tied)", "RMS [N]", "noise floor [N]",
                   "verdict"],
                  [[r["file"], r["diagnosis"]["baseline"], _added(r["diagnosis"]),
                    _fall(r["diagnosis"]), r["diagnosis"]["noise_floor"], _verdict(r)]
                   for r in results["real"]],
                  caption="The loop on real measurements: held-out RMS error of the baseline "
                  "and the final model.", digits=[None, None, None, None, 3, None])
        for r in results["real"]:
            _case_section(out, r["case"], r["file"], r, figures[r["case"]],
                          f"diagnosis-{r['case']}/report.html")
        rep.parameters({"diagnosis options": options, "synthetic record": record},
                       heading="Settings")
        return results


STUDY = MissingPhysicsStudy()
main = STUDY.main
