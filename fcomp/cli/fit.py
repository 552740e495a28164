"""``fcomp fit DATA.csv [DATA2.csv ...] --friction NAME [--offset] [--json OUT]`` -- identify a
friction model.

Prints a table of estimates with standard errors and confidence intervals
and the RMS force error (N). Where the sidecar gives no ``rig.mass`` and the
data hold a driving force (``F_ext``, pressures) but no ``F`` column, the
moving mass is estimated as well (``mass``). JSON (``--json OUT``, ``-`` for
standard output): ``{"model", "params", "stderr", "rms", "ci", "units",
"fixed", "not_identifiable", "method", ..., "warnings"}``. Parameters the record
does not determine are held and shown as such; plausibility warnings (a value at
a bound, an interval of a positive quantity reaching zero, an implausible mass,
parameters not determined or trading off) are printed under the table, one
``fcomp: warning: ...`` line each, and listed in the JSON's ``warnings``. A fit that does not converge
says so on one line and exits with status 2 (no JSON is written).
``--params SET|FIT.json|MODEL.json`` gives the start values (a parameter set, a fit's
JSON or a model file), ``--set NAME=VALUE`` one start value, ``--fix NAME=VALUE`` holds a
parameter.
Several records are fitted one by one, each on its own, in local processes
(``--jobs N``) or on a Dask cluster (``--scheduler ADDRESS``); the JSON is then
``{"model", "records": [{"data", "params", "stderr", "rms", ...}, ...], "warnings"}``.
``--friction MODEL.json`` starts the fit from a model file (its model, effects and
values). ``--save-model MODEL.json`` writes the fitted model as a model file
(docs/model-file.md; the JSON's ``model_file`` is the same document), a fitted
mass and offset in it as measurement terms.
``--report DIR`` draws the fit into ``DIR/report.html``: the estimates, the
measured and fitted force, and the fitted model compared with the record as
``fcomp compare`` does (errors per regime, residual against every feature,
loops, worst windows).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fcomp.cli import common
from fcomp.cli.common import (
    Activity,
    add_model_options,
    add_save_model_option,
    emit_result,
    finite_float,
    guard_outputs,
    json_target,
    model_source,
    model_target,
    name_list,
    parse_assignments,
    report_dir,
    result_text,
    save_model_file,
    warn,
    warn_sidecar,
    with_warnings,
)
from fcomp.errors import FcompError
from fcomp.parallel import check_scheduler

if TYPE_CHECKING:
    from fcomp.identification import FrictionFit


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fit", help="identify a friction model from a measurement, with "
                       "standard errors", description=__doc__)
    p.add_argument("data", nargs="+", metavar="DATA.csv",
                   help="measurement (CSV + TOML sidecar); several files are fitted one by "
                   "one, in parallel (--jobs, --scheduler)")
    common.add_friction_option(p, "--model", help="the friction model: a name (fcomp list "
                               "models), or a model file whose model and values start the fit")
    p.add_argument("--offset", action="store_true",
                   help="fit a constant force offset too (params.offset, N)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    common.add_params_option(p, "the model's defaults; the values start the fit and give "
                             "those the data do not determine")
    add_model_options(p)  # --add-effect, --effects, --set (start values of the fit)
    p.add_argument("--fix", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a parameter at VALUE (SI units) instead of fitting it; repeatable")
    p.add_argument("--free", default=None, metavar="NAME,NAME,...",
                   help="fit only these parameters (default: all but numerical thresholds)")
    p.add_argument("--directional", action="store_true",
                   help="fit separate values for v > 0 and v < 0 (Fc_pos, Fc_neg, ...)")
    p.add_argument("--mass", type=finite_float, default=None, metavar="KG",
                   help="known moving mass, overriding rig.mass (no mass estimation)")
    p.add_argument("--method", default="auto",
                   choices=["auto", "steady-state", "samples", "trajectory"],
                   help="auto (default): steady-state characteristic or samples for static "
                   "maps, steady-state start then trajectory for dynamic models")
    p.add_argument("--v-min", type=finite_float, default=None, metavar="M/S",
                   help="speed below which samples count as at rest (default 2%% of the "
                   "99th percentile of |v|)")
    p.add_argument("--cutoff", type=finite_float, default=10.0, metavar="HZ",
                   help="cut-off of the zero-phase filter that derives v and a from x when the "
                   "data have no v/a columns (default 10 Hz; the force is filtered alike)")
    p.add_argument("--confidence", type=finite_float, default=0.95,
                   help="level of the confidence intervals (default 0.95)")
    p.add_argument("--max-nfev", type=int, default=200, metavar="N",
                   help="evaluation budget of each least-squares stage (default 200)")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write a self-contained HTML report of the fit to DIR/report.html: the "
                   "estimates, the fit drawn, and the fitted model compared with the record "
                   "(errors per regime, residual against every feature, loops, worst windows)")
    add_save_model_option(p, "the fitted model")
    common.add_progress_option(p)
    common.add_parallel_options(p, what="the fits of several records")
    p.set_defaults(func=run)


def _table(f: FrictionFit, doc: dict[str, Any]) -> str:
    """The printed result: the conclusion (:func:`fcomp.conclusions.of_fit`), then the
    estimates, the parameters held (not determined by the record) and the RMS error (the
    plausibility warnings follow on stderr as ``fcomp: warning:`` lines)."""
    from fcomp.conclusions import of_fit

    lines = [*of_fit(doc).lines(), "", f"model {doc['model']}  ({f.method_} fit, target {f.target_}, "
             f"{f.n_samples_} samples)"]
    pct = round(100 * f.confidence)
    head = f"{'parameter':12s} {'value':>12s} {'stderr':>11s}   {pct}% interval{'':14s} unit"
    lines += [head, "-" * len(head)]
    for name, value, err, interval, unit in f.rows():
        lines.append(f"{name:12s} {value:>12s} {err:>11s}   {interval}".ljust(62) + f" {unit}")
    lines.append(f"rms force error {f.rms_:.4g} N; residual autocorrelation time "
                 f"{f.tau_int_:.3g} samples (effective sample size {f.n_eff_:.0f})")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from fcomp.identification import FrictionFit
    from fcomp.measurement import Measurement

    out = json_target(args.json)
    if args.max_nfev < 1:
        raise FcompError(f"--max-nfev must be a positive integer, got {args.max_nfev}")
    if args.v_min is not None and not args.v_min > 0:
        raise FcompError(f"--v-min must be a positive speed in m/s, got {args.v_min:g}")
    if not args.cutoff > 0:
        raise FcompError(f"--cutoff must be a positive frequency in Hz, got {args.cutoff:g}")
    if args.mass is not None and not args.mass >= 0:
        raise FcompError(f"--mass must be a non-negative number of kg, got {args.mass:g}")
    if not 0 < args.confidence < 1:
        raise FcompError(f"--confidence must be a level between 0 and 1 (e.g. 0.95), "
                         f"got {args.confidence:g}")
    report = report_dir(args.report)
    scheduler = check_scheduler(args.scheduler)
    common.check_jobs(args.jobs)
    if report is not None and len(args.data) > 1:
        raise FcompError("--report draws one fit: give one record (or fit the records one "
                         "by one)")
    saved = model_target(args.save_model)
    if saved is not None and len(args.data) > 1:
        raise FcompError("--save-model writes one fitted model: give one record (or fit the "
                         "records one by one)")
    guard_outputs(args.data, args.effects, [("--json", out), ("--save-model", saved)],
                  [("--report", report, "report")], models=[("--friction", args.friction), ("--params", args.params or "")])
    model, _ = common.model_with_params(args, use="model the fit starts from")
    initial = parse_assignments(args.set)
    fixed = parse_assignments(args.fix, "--fix")
    both = sorted(set(initial) & set(fixed))
    if both:
        raise FcompError(f"{both[0]}: given both --set (a start value) and --fix (held); "
                         "choose one")
    free = name_list(args.free, "--free")
    options = {"offset": args.offset, "mass": args.mass, "free": free, "fixed": fixed,
               "directional": args.directional, "initial": initial, "method": args.method,
               "v_min": args.v_min, "cutoff_hz": args.cutoff, "confidence": args.confidence,
               "max_nfev": args.max_nfev}
    records = [Measurement.read(p) for p in args.data]
    for d in records:
        warn_sidecar(d)
    if len(records) > 1:
        return _run_many(args, model, options, out, scheduler)
    data = records[0]
    fit = FrictionFit(model, **options)
    with Activity(f"fit {args.friction}", enabled=not args.no_progress):
        fit.fit(data)
    doc = with_warnings({**fit.to_dict(), "model_file": fit.model_file(model_source(args.data))})
    if report is not None:
        _write_report(fit, data, report, args)
    emit_result(result_text(doc), args.json, out, _table(fit, doc))
    save_model_file(doc["model_file"], saved, args.json)
    return 0


def fit_record(job: tuple[str, Any, dict[str, Any]]) -> dict[str, Any]:
    """Fit one record: ``(path, model, FrictionFit options)`` -> its JSON (a picklable job,
    run in a local process or on a Dask worker); a fit that fails gives ``{"error"}``."""
    from fcomp.identification import FrictionFit
    from fcomp.measurement import Measurement

    path, model, options = job
    try:
        fit = FrictionFit(model, **options).fit(Measurement.read(path))
    except FcompError as exc:
        return {"data": path, "error": str(exc).splitlines()[0]}
    return {"data": path, **fit.to_dict()}


def _run_many(args: argparse.Namespace, model: Any, options: dict[str, Any],
              out: Path | None, scheduler: str | None) -> int:
    """Several records, fitted one by one in parallel; JSON ``{"model", "records": [...]}``."""
    from fcomp.parallel import run_tasks
    from fcomp.progress import progress_bar

    jobs = [(path, model, options) for path in args.data]
    bar = progress_bar(f"fit {args.friction}", len(jobs), enabled=not args.no_progress,
                       unit="record")
    try:
        docs = run_tasks(fit_record, jobs, workers=args.jobs, scheduler=scheduler,
                         progress=lambda done, total: bar.update(done - bar.n))
    finally:
        bar.close()
    failed = [d for d in docs if "error" in d]
    if failed:
        raise FcompError(f"{failed[0]['data']}: {failed[0]['error']}"
                         + (f" (and {len(failed) - 1} more record(s))" if len(failed) > 1 else ""))
    for d in docs:
        for w in d["warnings"]:
            warn(w["code"], f"{d['data']}: {w['message']}", w["parameter"])
    doc = with_warnings({"model": docs[0]["model"], "records": docs})
    lines = [f"{d['data']}: rms {d['rms']:.4g} N; " + ", ".join(
        f"{k} {v:.4g}" for k, v in d["params"].items()) for d in docs]
    emit_result(result_text(doc), args.json, out, "\n".join(lines))
    return 0


def _write_report(fit: FrictionFit, data: Any, report: Path, args: argparse.Namespace) -> None:
    """The fit's report: estimates, the fit drawn, the fitted model compared with the record."""
    import shlex

    from fcomp.cli import common
    from fcomp.diagnosis.compare import compare, fitted_model
    from fcomp.diagnosis.report import write_fit_report
    from fcomp.outputs import staged_folder

    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else "fcomp fit"
    model, mass = fitted_model(fit)
    try:
        comp = compare(model, data, mass=mass)
    except FcompError as exc:  # e.g. steady-state points a dynamic view cannot take
        comp, why = None, str(exc)
    else:
        why = ""
    with staged_folder(report, "--report", "report", note=command) as tmp:
        write_fit_report(fit, comp, tmp, command=command, note=why)
    common.wrote(report / "report.html")
