"""The diagnosis report: the figures of the loop with its tables and its account, as HTML.

:func:`write_report` puts the figures of a fitted
:class:`~fcomp.diagnosis.loop.Diagnosis` (:mod:`fcomp.diagnosis.figures`) with
the tables and a plain-language account of the physics of every accepted
effect into one self-contained HTML page (:class:`fcomp.report.Report`);
:func:`write_comparison_report` and :func:`write_fit_report` do the same for a
comparison and a fit, :func:`diagnosis_html` and :func:`comparison_html` give
the notebook summaries. All errors are in newtons, on held-out data.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from fcomp import figstyle as fs
from fcomp.conclusions import of_comparison, of_diagnosis, of_fit
from fcomp.diagnosis.figures import (
    check_fitted,
    comparison_figures,
    fig_error_fall,
    fig_regimes,
    figures,
)
from fcomp.diagnosis.regimes import REGIMES
from fcomp.effects import EFFECTS
from fcomp.errors import FcompError
from fcomp.report import Report, notebook_html

if TYPE_CHECKING:  # the results draw themselves through this module, which sits below them
    from fcomp.diagnosis.compare import Comparison
    from fcomp.diagnosis.loop import Diagnosis

def short_reason(reason: str, limit: int = 110) -> str:
    """The first clause of a candidate's ``reason`` (the rest counted), for a table cell."""
    parts = [p for p in reason.split("; ") if p]
    if not parts:
        return ""
    first = parts[0] if len(parts[0]) <= limit else parts[0][: limit - 3].rstrip() + "..."
    return first + (f" (+{len(parts) - 1} more)" if len(parts) > 1 else "")


def _comparison_rows(obj: Comparison) -> tuple[str, list[list[Any]]]:
    """A title and the key numbers of a comparison (for notebooks)."""
    rows = [["model", obj.model.describe(), ""],
            ["RMS error" + (" (held-out samples)" if obj.fitted else " (whole record)"),
             f"{obj.rms:.4g}", "N"],
            [f"scored RMS error ({obj.judged_label} samples)", f"{obj.rms_scored:.4g}", "N"],
            ["noise floor", f"{obj.noise_floor:.3g}", "N"]]
    rows += [[f"regime {k}", "-" if v["rms"] is None else f"{v['rms']:.4g}",
              f"N (n={v['n']})"] for k, v in obj.regimes.items()]
    rows += [[f"plant {c.plant}, {k}", f"{fs.scaled(k, v):.3g}", fs.scale_of(k).unit]
             for c in obj.plant for k, v in c.rms.items()]
    top = obj.residual_features[:3]
    rows.append(["residual follows", ", ".join(f"{f.feature} {f.strength:.2f}"
                                               for f in top), "strength"])
    return f"Comparison: {obj.model.describe()} on {', '.join(obj.data.labels[:3])}", rows


def _summary_rows(obj: Diagnosis | Comparison) -> tuple[str, list[list[Any]]]:
    """A title and the key numbers of a diagnosis or a comparison (for notebooks)."""
    if hasattr(obj, "view"):  # a Comparison
        return _comparison_rows(cast("Comparison", obj))
    check_fitted(obj)
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


def parameter_units(model: Any) -> dict[str, str]:
    """Unit of every parameter of ``model`` and of the identification extras (``mass`` kg,
    ``offset`` N, ``lag`` s); ``"-"`` for a pure number."""
    from fcomp.identification.records import EXTRA_SPECS

    specs = {**EXTRA_SPECS, **model.param_specs()}
    return {k: (getattr(s, "unit", "") or "-") for k, s in specs.items()}


def build_comparison_report(comp: Comparison, *, command: str | None = None,
                            values_from: str | None = None) -> Report:
    """The :class:`~fcomp.report.Report` of a comparison: the diagnosis report's first two
    sections (errors per regime, where the model fails) for one model, and the plant domain.

    ``values_from`` says where the model's values come from (``"the fit file fit.json"``, ``"the
    parameter set seed001"``, ``"the model's default values"``); without it a comparison that
    was not fitted says "the values given"."""
    d = comp.to_dict()
    labels = comp.data.labels
    source = ("fitted on the training samples" if comp.fitted else
              f"values from {values_from}" if values_from else "the values given")
    rep = Report(f"Comparison: {comp.model.describe()} on {', '.join(labels[:3])}"
                 + (" ..." if len(labels) > 3 else ""),
                 subtitle=f"RMS {comp.rms:.4g} N" + ("" if comp.fitted else " on the whole "
                 f"record; scored {comp.rms_scored:.4g} N") + f" over the {comp.judged_label} "
                 f"samples (noise floor {comp.noise_floor:.3g} N); {source}",
                 command=command, config={"model": d["description"], "fitted": comp.fitted,
                                          "split": comp.split,
                                          **({"values from": values_from} if values_from
                                             else {})})
    rep.conclusion(of_comparison(d))
    if d["warnings"]:
        rep.section("What a careful engineer would question", level=3)
        rep.table(["warning", "parameter", "what it means"],
                  [[w["code"], w["parameter"] or "", w["message"]] for w in d["warnings"]])
    comparison_sections(rep, comp)
    rep.parameters({k: v for k, v in d["params"].items()}, heading="Parameters",
                   units=parameter_units(comp.model),
                   caption="The values compared" + (f" ({source})." if source else "."))
    return rep


def comparison_sections(rep: Report, comp: Comparison) -> Report:
    """Add a comparison's sections to ``rep``: errors per regime, where the model fails
    (residual against every feature, loops, worst windows) and the plant domain."""
    figs = comparison_figures(comp)
    rep.section("1. Errors per regime")
    why = ("" if comp.fitted else f" The headline RMS, {comp.rms:.4g} N, is another measure: "
           "over every sample of the record, as fcomp fit measures it; the scored RMS here "
           f"({comp.rms_scored:.4g} N over all judged samples) leaves out the warm-ups and "
           "charges a prediction band the motion leaves rather than its centre.")
    rep.figure(figs["regimes"], f"Scored RMS error per regime over the {comp.judged_label} "
               "samples (pre-sliding, reversal, sliding, dwell/break-away); a regime with too "
               f"few samples has no bar.{why}")
    rep.table(["regime", "scored RMS (N)", "samples"],
              [[k, v["rms"], v["n"]] for k, v in comp.regimes.items()], digits=[None, None, 0],
              caption=f"Scored RMS per regime over the {comp.judged_label} samples.{why}")
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
        rep.table(["record", "plant", "signal", "RMS", "unit"],
                  [[c.label, c.plant, k, fs.scaled(k, v), fs.scale_of(k).unit]
                   for c in comp.plant for k, v in c.rms.items()], digits=None)
    return rep


def build_fit_report(fit: Any, comp: Comparison | None, *, command: str | None = None,
                     note: str = "") -> Report:
    """The report of a fit (``fcomp fit --report``): the estimates and their warnings, the fit
    drawn, and -- where the record takes it -- the comparison's sections for the fitted model."""
    d = fit.to_dict()
    rep = Report(f"Fit: {fit.model_.describe()} on {fit.data_.label}",
                 subtitle=f"{fit.method_} fit on {fit.n_samples_} samples, target "
                 f"{fit.target_}, RMS {fit.rms_:.4g} N on the whole record",
                 command=command,
                 config={"model": d["model"], "method": d["method"]})
    rep.conclusion(of_fit(d))
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
                  f"{comp.rms:.4g} N on the whole record (the fit's RMS); scored "
                  f"{comp.rms_scored:.4g} N over the {comp.judged_label} samples, the measure "
                  f"of the regimes below (a prediction band the motion leaves costs; noise "
                  f"floor {comp.noise_floor:.3g} N).")
    return comparison_sections(rep, comp)


def write_fit_report(fit: Any, comp: Comparison | None, directory: str | Path, *,
                     command: str | None = None, note: str = "") -> Path:
    """Write ``DIRECTORY/report.html`` of a fit (:func:`build_fit_report`)."""
    return _write(build_fit_report(fit, comp, command=command, note=note), directory)


def write_comparison_report(comp: Comparison, directory: str | Path, *,
                            command: str | None = None, values_from: str | None = None) -> Path:
    """Write ``DIRECTORY/report.html`` of a comparison (self-contained); return its path
    (``values_from``: :func:`build_comparison_report`)."""
    return _write(build_comparison_report(comp, command=command, values_from=values_from),
                  directory)


def _physics(effect: str) -> str:
    cls = EFFECTS.get(effect)
    return " ".join((cls.__doc__ or cls.signature or "").split())


def build_report(diag: Diagnosis, *, command: str | None = None) -> Report:
    """The :class:`~fcomp.report.Report` of a fitted diagnosis."""
    check_fitted(diag)
    d = diag.to_dict()
    nf = diag.noise_floor_
    rep = Report(f"Friction diagnosis: {d['baseline']} on {', '.join(diag.data_.labels[:3])}"
                 + (" ..." if len(diag.data_.labels) > 3 else ""),
                 subtitle=f"verdict: {d['verdict']}; held-out RMS {d['rms_baseline']:.4g} N "
                 f"-> {d['rms_final']:.4g} N (noise floor {nf.value:.3g} N)",
                 command=command,
                 config={"baseline": d["baseline"], "split": diag.split_.description,
                         "effects": [c.effect for c in diag.candidates_] or d["added"]})
    rep.conclusion(of_diagnosis(d))
    rep.section("Summary")
    if d["added"]:
        rep.paragraph(f"Added, in order: {', '.join('`' + e + '`' for e in d['added'])}. "
                      f"Final model: `{d['model']}`.")
    else:
        rep.paragraph("No effect qualified: the baseline is kept.")
    kind = of_diagnosis(d).tone  # the conclusion's colour: never green beside "How sure: low"
    if d["verdict"] == "explained":
        rep.note(f"Verdict `explained` -- {d['reason']}.", kind=kind)
    else:
        rep.note(f"Verdict `unexplained-structure` -- {d['reason']}. No catalogue entry "
                 "qualified to explain it: it is reported rather than papered over with the "
                 "least-bad wrong effect.", kind=kind)
    left = d.get("structure_left") or {}
    figs = figures(diag)
    if left.get("follows"):
        structure_section(rep, left, figs["structure"])
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
        ["held-out RMS, baseline (refitted on the training part; scored: a prediction band "
         "costs)", d["rms_baseline"], "N"],
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
    ], caption="The diagnosis at a glance (errors on held-out samples: each model refitted "
       "on the training part, so not the RMS of a given model on the whole record that fit and "
       "compare print).", digits=4)

    rep.section("1. Compare: errors per regime")
    rep.figure(figs["regimes"], "Held-out RMS error per regime (pre-sliding, reversal, "
               "sliding, dwell/break-away) for the baseline and the final model; dashed: the "
               "noise floor estimated from the data.")
    rows = [[r, diag.regimes_["baseline"][r]["rms"], diag.regimes_["final"][r]["rms"],
             diag.regimes_["final"][r]["n"]] for r in [*REGIMES, "all"]]
    rep.table(["regime", "baseline RMS (N)", "final RMS (N)", "held-out samples"], rows,
              digits=[None, None, None, 0])
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
    seals_sections(rep, d)
    rep.section("Residual structure left")
    rep.table(["feature", "strength", "RMS it carries (N)"],
              [[f["feature"], f["strength"], f.get("rms")] for f in d["residual_features"]],
              digits=[None, 3, 3])
    if d.get("structures"):
        rep.bullets([st["text"] for st in d["structures"]])
    final_parameters(rep, d, parameter_units(diag.fit_.model))
    return rep


def final_parameters(rep: Report, d: Mapping[str, Any], units: Mapping[str, str]) -> Report:
    """The final parameters with their standard errors and what the record did not determine
    (the JSON's ``params``, ``stderr`` and the model file's ``undetermined``)."""
    rep.section("Final parameters")
    stderr = d.get("stderr") or {}
    undetermined = (d.get("model_file") or {}).get("undetermined") or {}
    rows = []
    for k, v in d["params"].items():
        se = stderr.get(k)
        flag = undetermined.get(k, "")
        rows.append([k, v, "-" if se is None or flag.startswith("at-bound") else se,
                     units.get(k, "") or "-", flag.split(":", 1)[0] if flag else ""])
    for k in d.get("held_by_design") or {}:
        if k not in d["params"] and k in (d.get("model_params") or {}):
            rows.append([k, d["model_params"][k], "-", units.get(k, "") or "-", "held"])
    return rep.table(["parameter", "value", "standard error", "unit", "not determined"], rows,
                     caption="Standard errors: batch-means (HAC) from the final fit's Jacobian "
                     "on the training samples, as fcomp fit's. A value at a bound of its box, "
                     "not identified, with an interval through zero or held by the record's "
                     "design is not determined by the record: the model file lists it under "
                     "`undetermined`, and loading it warns.", digits=[None, 4, 3, None, None])


def seals_sections(rep: Report, d: Mapping[str, Any]) -> Report:
    """Pairs, forms, the record's design and its ties (issue 43), where the diagnosis has
    them."""
    if d.get("pairs"):
        rep.section("Effects found in pairs", level=3)
        rep.table(["pair", "held-out RMS alone (N)", "together (N)", "z", "qualifies",
                   "added"],
                  [[" + ".join(p["effects"]), " / ".join(f"{r:.4g}" for r in p["rms_alone"]),
                    p["rms_together"], p["z"], p["qualifies"], p["accepted"]]
                   for p in d["pairs"]],
                  caption="Where no single candidate qualified, the promising ones (significant "
                  "falls short only of their size) refitted in pairs; a pair is added when it "
                  "qualifies and each member qualifies against the other alone.",
                  digits=[None, None, 4, 2, None, None])
    if d.get("forms"):
        rep.section("Forms of the effects tried", level=3)
        rep.table(["effect", "form", "held-out RMS before (N)", "after (N)", "kept", "why not"],
                  [[f["effect"], f["form"], f["rms_before"], f["rms_heldout"], f["kept"],
                    "" if f["kept"] else short_reason(f["reason"])] for f in d["forms"]],
                  caption="Richer forms of an accepted effect, each refitted in place of the "
                  "one accepted and kept only when the acceptance rule accepts it against that "
                  "form on the held-out data.", digits=[None, None, 4, 4, None, None])
    design = d.get("design") or {}
    if design.get("confounded"):
        rep.section("What the record's design varies together", level=3)
        rep.table(["factors", "what the record does", "to separate them, record"],
                  [[" / ".join(c["factors"]), c["why"], c["separates"]]
                   for c in design["confounded"]],
                  caption="Laws in factors a record varies together give the same force on it; "
                  "effects acting through them are reported as a tie (the JSON's "
                  "`confounding`).")
        for c in d.get("confounding") or []:
            rep.note(f"{' / '.join('`' + e + '`' for e in c['effects'])}: the record's design "
                     f"cannot tell them apart ({c['why']}); to separate them, record "
                     f"{c['separates']}.", kind="warn")
    return rep


def structure_section(rep: Report, left: dict[str, Any], figure: Any) -> Report:
    """The report's account of what the structure left follows (:mod:`.structure_left`, the
    JSON's ``structure_left``): its size against the noise floor, a table of what it
    follows with the experiment that would tell more, and ``figure`` (``structure``)."""
    present = left.get("present")
    rep.section("What the structure left follows", level=3)
    rep.paragraph(
        f"The final model's held-out RMS is {left['rms']:.3g} N against a noise floor of "
        f"{left['noise_floor']:.3g} N: {left['excess']:.3g} N (RMS) above the noise. "
        + ("It follows:" if present else "The strongest features (below the verdict's "
           "rule):"))
    rows = []
    for f in left["follows"]:
        size = (f"{f['slope']:+.3g} N per {f['slope_per']}, {f['change']:.3g} N over the record"
                if f.get("slope") is not None else f"{f['change']:.3g} N peak to peak"
                if f.get("change") is not None else "")
        if f.get("note"):
            size = f"{size}; {f['note']}" if size else f["note"]
        rows.append([f["words"], f["strength"], f["own_strength"], f["rms"], size,
                     f["experiment"]])
    rep.table(["follows", "strength", "own strength", "RMS it carries (N)", "shape",
               "the experiment that would tell more"], rows, digits=[None, 3, 3, 3, None, None],
              caption="Strength: the share of the held-out residual's mean square a smooth "
              "function of the feature explains; own strength: the same once the features "
              "above it are taken out (features that are one phase of a periodic stroke are "
              "one finding). Shape: the binned means of the residual signed by the direction "
              "of motion (a friction level above the model's is positive both ways).")
    rep.figure(figure, "The final model's held-out residual, signed by the "
               "direction of motion, against what it follows, with its binned means.")
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


#: The figures (and their view) the results and the studies draw through this module.
__all__ = ["build_comparison_report", "build_fit_report", "build_report", "comparison_html",
           "comparison_sections", "diagnosis_html", "short_reason", "write_comparison_report",
           "write_fit_report", "write_report"]
