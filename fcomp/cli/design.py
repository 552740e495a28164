"""``fcomp design DIAG.json --rig RIG.toml -o DIR [--json OUT] [--report DIR]``.

The next experiment: for every open question of a diagnosis (``fcomp diagnose --json``)
-- a tie, an effect the record could not test, a value left undetermined -- a programme
the rig runs within its limits (``--rig``, a TOML file: ``fcomp design --template`` writes
one with comments), chosen so that the rivals' predicted forces separate (T-optimal
design) and the values' intervals shrink. ``-o DIR`` gets one file per experiment in the
data format (``t``, ``x`` the position to follow, ``p1``/``p2`` the pressures to hold, a
sidecar); ``--json OUT`` writes ``{"experiments": [...], "questions": [{"kind", "rivals" |
"parameter", "predicted_separation", ...}], "warnings"}``. Record the programme, then
``fcomp diagnose OLD.csv DIR/experiment_*.csv`` answers the questions.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys

from fcomp.cli import common
from fcomp.cli.common import emit_result, finite_float, json_target
from fcomp.errors import FcompError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("design", help="the next experiment: what to measure to answer a "
                       "diagnosis's open questions, as files the rig runs", description=__doc__)
    p.add_argument("diagnosis", nargs="?", metavar="DIAG.json",
                   help="the --json output of fcomp diagnose")
    p.add_argument("--rig", metavar="RIG.toml", default=None,
                   help="the rig and its limits (fcomp design --template writes one)")
    p.add_argument("-o", "--output", metavar="DIR", default=None,
                   help="folder for the programme (one CSV + TOML per experiment)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the design as JSON to OUT ('-' for standard output)")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write a self-contained HTML report to DIR/report.html")
    p.add_argument("--noise", type=finite_float, default=None, metavar="N",
                   help="force noise in N (default: the rig file's, else the diagnosis's "
                   "noise floor)")
    p.add_argument("--template", action="store_true",
                   help="print a rig file with every key and its meaning, and stop")
    p.set_defaults(func=run)


def summary(doc: dict) -> str:
    """The printed summary: conclusion first, then each question and each experiment."""
    qs = doc["questions"]
    blocked = [w for w in doc["warnings"] if w["code"] == "limits-block"]
    lines = [f"Conclusion: {len(doc['experiments'])} experiment(s) answer "
             f"{len(qs) - len(blocked)} of {len(qs)} open question(s)"
             + (f"; {len(blocked)} blocked by the rig's limits" if blocked else "")]
    for q in qs:
        if q["kind"] == "parameter":
            b, a = q.get("stderr_before"), q.get("stderr_after")
            lines.append(f"  parameter {q['parameter']} ({q['reason']}): standard error "
                         f"{'?' if b is None else f'{b:.3g}'} -> "
                         f"{'?' if a is None else f'{a:.3g}'}")
        else:
            lines.append(f"  {q['kind']} {q['label']}: predicted separation "
                         f"{q['predicted_separation']:.3g} noise floors, "
                         f"{q['predicted_separation_refit']:.3g} once the rival's values "
                         "are refitted along the programme")
    for f, e in zip(doc["experiments"], doc["programme"], strict=False):
        lines.append(f"  {f}: {e['duration']:.1f} s at {e['level'] / 1e5:.3g} bar: "
                     + "; ".join(e["primitives"]))
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from fcomp.outputs import signals_held, staged_folder
    from fcomp.planning import TEMPLATE, design, read_rig
    from fcomp.planning.programme import measurement

    if args.template:
        sys.stdout.write(TEMPLATE)
        return 0
    if args.diagnosis is None or args.rig is None or args.output is None:
        raise FcompError("fcomp design needs DIAG.json, --rig RIG.toml and -o DIR "
                         "(fcomp design --template writes a rig file)")
    if args.noise is not None and not args.noise > 0:
        raise FcompError(f"--noise must be a positive force in N, got {args.noise:g}")
    out = json_target(args.json)
    report = common.report_dir(args.report)
    folder = common.report_dir(args.output, "-o")
    from fcomp.cli.targets import check_outputs
    from fcomp.outputs import InputSet

    inputs = InputSet()
    inputs.file(args.diagnosis, "DIAG.json")
    inputs.file(args.rig, "--rig")
    check_outputs(inputs, [("--json", out)],
                  [("-o", folder, "programme"), ("--report", report, "report")])
    rig = read_rig(args.rig)
    result = design(args.diagnosis, rig, noise=args.noise)
    blocked = any(w["code"] == "limits-block" for w in result.warnings_)
    if not result.experiments_ and not blocked:
        raise FcompError(f"{args.diagnosis}: nothing to design: " + "; ".join(
            w["message"] for w in result.warnings_))
    name = "experiment_{}"
    assert folder is not None
    # Every output or none: the programme and the report are built in temporary folders,
    # the JSON written last; the folders replace their targets only once it is written
    # (a full disk or a signal there leaves nothing), with Ctrl-C and SIGTERM held from
    # the JSON's writing to the last rename.
    with contextlib.ExitStack() as held, contextlib.ExitStack() as staged:
        tmp = staged.enter_context(staged_folder(folder, "-o", "programme",
                                                 note="fcomp design"))
        # (empty when the rig's limits block every question: the warnings say which limit)
        for k, e in enumerate(result.experiments_, start=1):
            m = measurement(e, rig, name.format(k), "pneumatic-cylinder")
            m.write(tmp / f"{name.format(k)}.csv")
        result.files_ = [str(folder / f"{name.format(k)}.csv")
                         for k in range(1, len(result.experiments_) + 1)]
        if report is not None:
            from fcomp.planning.report import write_report

            write_report(result, staged.enter_context(
                staged_folder(report, "--report", "report", note="fcomp design")))
            common.wrote(report / "report.html")
        doc = common.with_warnings(result.as_dict())
        held.enter_context(signals_held())
        emit_result(json.dumps(doc, indent=1), args.json, out, summary(doc))
    return 0
