"""``fcomp diagnose DATA.csv [DATA2.csv ...] --friction NAME [--json OUT] [--report DIR]``.

Compare the baseline friction model (``--friction``) with the measurement(s), find which
physical effect is missing, add it, refit, and watch the held-out error fall
(:class:`fcomp.diagnosis.Diagnosis`). Several files are several experiments
(e.g. runs at different pressure levels); a file with an ``experiment``
column is split by it. Prints a summary; ``--json OUT`` writes

    {"baseline", "rms_baseline", "added", "steps": [{"effect", "rms_before",
     "rms_after", "accepted"}, ...], "candidates": [{"effect", "rms_heldout"}, ...],
     "ties", "rms_final", "noise_floor", "verdict", "residual_features": [{"feature",
     "strength"}, ...], ...}

(all errors in newtons, on held-out data; ``-`` writes to standard output)
and ``--report DIR`` a self-contained ``DIR/report.html`` with every figure.
``--friction MODEL.json`` starts from a model file (a model with effects,
diagnosed further). ``--save-model MODEL.json`` writes the final model as a model file
(docs/model-file.md; the JSON's ``model_file`` is the same document), a fitted
mass, the channel lag and measurement effects in it as measurement terms.
``--add-effect EFFECT`` adds an effect (catalogue or registered with ``--effects
MODULE.py``) before the search, whatever the acceptance rule says.
"""

from __future__ import annotations

import argparse
import shlex

from fcomp.cli import common
from fcomp.cli.common import emit_result, finite_float, json_target, result_text
from fcomp.errors import FcompError
from fcomp.parallel import check_scheduler


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("diagnose", help="compare a model with measurements, find and add the "
                       "missing effect", description=__doc__)
    p.add_argument("data", nargs="+", metavar="DATA.csv",
                   help="measurement(s) (CSV + TOML sidecar); several files = several experiments")
    common.add_friction_option(p, "--baseline", help="the baseline friction model: a name "
                               "(fcomp list models), or a model file (a model with effects to "
                               "diagnose further)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write a self-contained HTML report to DIR/report.html")
    common.add_add_effect_option(p, "--add", help="add this effect first (and refit), "
                                 "whatever the rule says; repeatable")
    p.add_argument("--effects", metavar="MODULE.py", default=None,
                   help="a Python file that registers the user's own effects (they become "
                   "candidates too)")
    p.add_argument("--candidates", metavar="E1,E2,...", default=None,
                   help="effects to try (default: every registered effect)")
    p.add_argument("--no-search", action="store_true",
                   help="only the baseline and the --add-effect effects; no search")
    p.add_argument("--split", default="auto", choices=["auto", "experiment", "segment"],
                   help="held-out split: by experiment (4+ experiments under auto) or by "
                   "contiguous segment")
    p.add_argument("--cutoff", type=finite_float, default=None, metavar="HZ",
                   help="cutoff of the zero-phase filter deriving v, a from x (default: from "
                   "the sample rate and the position noise)")
    p.add_argument("--max-steps", type=int, default=6, metavar="N",
                   help="most effects the search adds (default 6)")
    check = p.add_mutually_exclusive_group()
    check.add_argument("--baseline-check", action="store_true",
                       help="always diagnose again from a baseline of the other kind (static "
                       "<-> dynamic) to say whether the answer depends on the baseline (by "
                       "default only when the answer is doubtful: the final fit flagged, a "
                       "tie, or structure left)")
    check.add_argument("--no-baseline-check", action="store_true",
                       help="never run that baseline check")
    common.add_parallel_options(p, what="the candidate refits", default="CPU count, at most 4")
    common.add_save_model_option(p, "the diagnosis's final model")
    common.add_progress_option(p)
    p.set_defaults(func=run)


def _clauses(text: str) -> list[str]:
    """``text`` split at its top-level ``"; "`` (not inside parentheses)."""
    out, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and text.startswith("; ", i):
            out.append(text[start:i])
            start = i + 2
    return [*out, text[start:]]


def summary(doc: dict) -> str:
    """The printed summary of a diagnosis JSON: the conclusion
    (:func:`fcomp.conclusions.of_diagnosis`) first, then the steps, the baseline check and
    the verdict's reasons, one per line (the warnings go to stderr, grouped)."""
    from fcomp.conclusions import of_diagnosis

    lines = [*of_diagnosis(doc).lines(), "", f"baseline {doc['baseline']}: held-out RMS {doc['rms_baseline']:.4g} N "
             f"(noise floor {doc['noise_floor']:.3g} N, {doc['noise_method']}; {doc['split']})"]
    for i, s in enumerate(doc["steps"], 1):
        tag = "accepted" if s["accepted"] else "rejected"
        if s.get("pair"):
            partners = [e for e in s["pair"] if e != s["effect"]]
            tag += f" as a pair with {', '.join(partners)} (neither qualified alone)"
        if s.get("removed"):
            tag = "accepted, then removed (redundant once later effects were in)"
        if s.get("forced"):
            tag = "added on request" + ("" if s["accepted"] else " (the rule would reject it)")
        if s.get("form") and s["accepted"] and any(
                f.get("kept") and f["effect"] == s["effect"] for f in doc.get("forms") or []):
            tag += f", in its {s['form']} form"
        after = "-" if s["rms_after"] is None else f"{s['rms_after']:.4g}"
        lines.append(f"step {i}: + {s['effect']:22s} {s['rms_before']:.4g} -> {after} N  {tag}")
    lines += _forms_lines(doc)
    if doc["ties"]:
        for t in doc["ties"]:
            both = [e for e in t if e in doc["added"]]
            held = f"{' and '.join(both)} all in the model" if len(both) > 1 else \
                f"{t[0]} added"
            lines.append(f"tie (confounded, {held}): " + ", ".join(t))
            for e, exp in doc["tie_experiments"][t[0]].items():
                lines.append(f"    {e}: {exp}")
    for s in doc["steps"]:  # close by the fall's share, but told apart by the held-out data
        for t in s.get("tie_tests") or []:
            if s["accepted"] and t["close"] and t["separated"]:
                lines.append(f"not a tie: {t['effect']} fits within the fall's share of "
                             f"{s['effect']}, but the held-out data tell them apart (worse by "
                             f"{t['difference']:.3g} N where they differ, p = {t['p']:.2g})")
    plain = doc.get("rms_plain") or {}
    lines.append(f"added: {', '.join(doc['added']) or 'nothing'}; final model {doc['model']}; "
                 f"held-out RMS {doc['rms_final']:.4g} N"
                 + (f" (plain y - F: {plain['baseline']:.4g} -> {plain['final']:.4g} N)"
                    if plain.get("final") is not None and plain.get("baseline") is not None
                    else ""))
    for c in doc.get("confounding") or []:
        lines.append(f"confounded by the record's design: {' / '.join(c['effects'])}: "
                     f"{c['why']}; to separate them: record {c['separates']}")
    for st in doc.get("structures") or []:
        lines.append(f"named in what is left: {st['text']}")
    for d in doc.get("disturbances") or []:
        lines.append(f"periodic disturbance: {d['frequency_hz']:.4g} Hz, amplitude "
                     f"{d['amplitude']:.3g} N (follows no motion; taken off the force)")
    other = doc.get("other_baseline")
    if other:
        same = "the same effects" if not doc["baseline_dependent"] else "OTHER effects"
        lines.append(f"baseline check ({doc['baseline_check']['why']}): from "
                     f"{other['baseline']} the diagnosis finds {same} "
                     f"({', '.join(other['added']) or 'nothing'}; {other['verdict']})")
    elif doc["baseline_check"]["why"] != "not asked for":
        lines.append(f"baseline check not run: {doc['baseline_check']['why']} "
                     "(--baseline-check runs it)")
    lines.append(f"verdict: {doc['verdict']}, because:")
    lines += [f"  - {part}" for part in _clauses(doc["reason"])]
    return "\n".join(lines)


def _forms_lines(doc: dict) -> list[str]:
    """One line per accepted effect whose richer forms were tried (:mod:`fcomp.diagnosis.forms`)."""
    out = []
    by: dict[str, list[dict]] = {}
    for f in doc.get("forms") or []:
        by.setdefault(f["effect"], []).append(f)
    for effect, forms in by.items():
        parts = [f"{f['form']} {'kept' if f['kept'] else 'not kept'} ("
                 + ("-" if f["rms_heldout"] is None else f"{f['rms_heldout']:.4g} N")
                 + ("" if f["kept"] or f["qualifies"] else f": {f['reason'].split(';')[0]}")
                 + ")" for f in forms]
        out.append(f"forms of {effect} tried: " + "; ".join(parts))
    return out


def run(args: argparse.Namespace) -> int:
    from fcomp.diagnosis import Diagnosis
    from fcomp.diagnosis.report import write_report
    from fcomp.effects import load_effects_module
    from fcomp.measurement import Measurement
    from fcomp.modelfile import is_model_file, read_model
    from fcomp.outputs import staged_folder

    out = json_target(args.json)
    report = common.report_dir(args.report)
    if args.max_steps < 0:
        raise FcompError(f"--max-steps must be a non-negative integer, got {args.max_steps}")
    common.check_jobs(args.jobs)
    if args.cutoff is not None and not args.cutoff > 0:
        raise FcompError(f"--cutoff must be a positive frequency in Hz, got {args.cutoff:g}")
    saved = common.model_target(args.save_model)
    common.guard_outputs(args.data, args.effects, [("--json", out), ("--save-model", saved)],
                         [("--report", report, "report")], models=[("--friction", args.friction)])
    if args.effects is not None:
        load_effects_module(args.effects)
    baseline = args.friction
    if is_model_file(baseline):
        mf = read_model(baseline, args.effects)
        if mf.measurement_terms:
            common.warn("measurement-terms", mf.dropped_note("baseline (the diagnosis finds "
                        "its own)"), "friction")
        baseline = mf.model
    candidates = common.name_list(args.candidates, "--candidates")
    data = [Measurement.read(p) for p in args.data]
    for d in data:
        common.warn_sidecar(d)
    diag = Diagnosis(baseline, candidates=candidates, add=args.add_effect,
                     search=not args.no_search, split=args.split, cutoff_hz=args.cutoff,
                     max_steps=args.max_steps, n_jobs=args.jobs,
                     scheduler=check_scheduler(args.scheduler),
                     progress=not args.no_progress,
                     check_baseline=(True if args.baseline_check else
                                     False if args.no_baseline_check else "auto"))
    diag.fit(data)
    doc = common.with_warnings({**diag.to_dict(),
                                "model_file": diag.model_file(common.model_source(args.data))})
    text = result_text(doc)
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else None
    if report is not None:
        with staged_folder(report, "--report", "report", note=command or "fcomp diagnose") as tmp:
            write_report(diag, tmp, command=command)
        common.wrote(report / "report.html")
    emit_result(text, args.json, out, summary(doc))
    common.save_model_file(doc["model_file"], saved, args.json)
    return 0

