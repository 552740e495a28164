"""``fcomp compare DATA.csv [DATA2.csv ...] --friction NAME [--params SET|FIT.json|MODEL.json] [--plant NAME]
[--json OUT] [--report DIR]`` -- one given model beside the records.

The model (``--friction``, with the values of a parameter set, a fit's JSON or
a model file given by ``--params``, effects added by ``--add-effect`` and values changed
by ``--set``) is run along each record's measured motion and its friction
force compared with the measured one: the RMS error per regime
(pre-sliding, reversal, sliding, dwell/break-away), how strongly the residual
still follows every feature (velocity, acceleration, position, pressure,
time and displacement since the last reversal, dwell time), the
force-velocity and force-position loops and the windows where the model
fails most. Without ``--fit`` the model is compared as given, on every usable
sample; with ``--fit`` it is first fitted on the training samples and judged
on the held-out ones. ``--plant NAME`` also simulates that plant with each
record's valve command ``u`` and compares ``x``, ``p1``, ``p2``. ``--friction
MODEL.json`` takes a model file (docs/model-file.md: ``fcomp fit
--save-model``) with its values; its measurement terms (offset, fitted mass)
are used, as they describe these records.

JSON (``--json OUT``, ``-`` for standard output)::

    {"model", "rms", "regimes": {REGIME: {"rms", "n"}, ..., "all": ...},
     "residual_features": [{"feature", "strength"}, ...], "worst": [...],
     "plant": {RECORD: {"plant", "rms": {"x", "p1", "p2"}}}, "params", "warnings"}

(errors in N; plant-domain errors in m and Pa); ``--report DIR`` writes the
figures into a self-contained ``DIR/report.html``. ``--jobs N`` / ``--scheduler
ADDRESS`` run the plant-domain replays (one per record) in local processes or on
a Dask cluster, with the results of a serial run; the force domain is one
computation over all the records together (a joint split; with ``--fit``, one
fit) and runs in the command's own process.
"""

from __future__ import annotations

import argparse
import shlex
from dataclasses import replace
from typing import Any

from fcomp.cli import common
from fcomp.cli.common import emit_result, finite_float, json_target, report_dir, result_text
from fcomp.errors import FcompError, term
from fcomp.identification.plausibility import FitWarning
from fcomp.parallel import check_scheduler


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("compare", help="put one given model beside measurements: errors per "
                       "regime, residual against every feature, loops, worst windows",
                       description=__doc__)
    p.add_argument("data", nargs="+", metavar="DATA.csv",
                   help="measurement(s) (CSV + TOML sidecar); several files = several experiments")
    common.add_friction_option(p, "--model", help="the friction model: a name (fcomp list "
                               "models), or a model file (fcomp fit --save-model) with its values")
    common.add_params_option(p, "the model's defaults")
    common.add_model_options(p)  # --add-effect, --effects, --set
    p.add_argument("--fit", action="store_true",
                   help="fit the model on the training samples first and judge it on the "
                   "held-out ones")
    p.add_argument("--mass", type=finite_float, default=None, metavar="KG",
                   help="moving mass for records with a driving force and no rig.mass "
                   "(default: a fit JSON's params.mass)")
    p.add_argument("--plant", default=None, metavar="NAME",
                   help="also compare in the plant domain: simulate this plant with the "
                   "records' command u (hydraulic, pneumatic, ...)")
    p.add_argument("--plant-params", default=None, metavar="SET|PLANT.toml",
                   help="parameter set of the plant (default: the plant's), or a plant file "
                   "(fcomp plant template; its kind is the plant)")
    p.add_argument("--split", default="auto", choices=["auto", "experiment", "segment"],
                   help="train/held-out split (for --fit and the feature strengths)")
    p.add_argument("--cutoff", type=finite_float, default=None, metavar="HZ",
                   help="cutoff of the zero-phase filter deriving v, a from x (default: from "
                   "the sample rate and the position noise, and a fit's 10 Hz for the RMS on "
                   "the whole record; a --params FIT.json fitted with another --cutoff: that)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    p.add_argument("--report", metavar="DIR", default=None,
                   help="write a self-contained HTML report with every figure to "
                   "DIR/report.html")
    common.add_parallel_options(p, what="the plant-domain replays (--plant), one per record")
    common.add_progress_option(p)
    p.set_defaults(func=run)


def summary(doc: dict[str, Any]) -> str:
    """The printed summary of a comparison's JSON: the conclusion
    (:func:`fcomp.conclusions.of_comparison`) first, then the errors per regime."""
    from fcomp.conclusions import of_comparison

    where = ("" if doc["fitted"] else "on the whole record, as fcomp fit measures it; "
             f"scored {doc['rms_scored']:.4g} N ")
    lines = [*of_comparison(doc).lines(), "", f"model {doc['description']} ({'fitted on the training samples' if doc['fitted'] else 'as given'}): "
             f"RMS {doc['rms']:.4g} N {where}over the {doc['judged']} samples "
             f"(scored: a prediction band the motion leaves costs; plain y - F "
             f"{doc['rms_plain']:.4g} N; noise floor {doc['noise_floor']:.3g} N)"]
    lines.append("  scored RMS per regime:")
    for name, r in doc["regimes"].items():
        rms = "-" if r["rms"] is None else f"{r['rms']:.4g} N"
        lines.append(f"  {name:18s} {rms:>12s}  ({r['n']} samples)")
    top = ", ".join(f"{f['feature']} {f['strength']:.2f}" for f in doc["residual_features"][:3])
    lines.append(f"residual follows: {top} (strength)")
    for label, pc in doc["plant"].items():
        errs = ", ".join(f"{k} {v * 1e3:.3g} mm" if k == "x" else f"{k} {v * 1e-5:.3g} bar"
                         for k, v in pc["rms"].items())
        lines.append(f"plant {pc['plant']} on {label}: RMS {errs}")
    return "\n".join(lines)


def _undetermined(args: argparse.Namespace, document: dict[str, Any] | None
                  ) -> FitWarning | None:
    """A ``not-identified`` warning for the parameters the model's own file says were not
    determined when it was fitted (``stderr`` ``null`` in the model file or the fit's JSON):
    compare then trusts the model as little as the fit or diagnosis that made it did."""
    from fcomp.modelfile import is_model_file

    if is_model_file(args.friction):
        source, doc = args.friction, common.params_document(args.friction)
    elif document is not None:
        source, doc = args.params, document
    else:
        return None
    inner = doc.get("model_file")
    if "format" not in doc and isinstance(inner, dict):
        doc = inner
    stderr = doc.get("stderr")
    names = sorted(k for k, v in (stderr or {}).items() if v is None) \
        if isinstance(stderr, dict) else []
    if not names:
        return None
    return FitWarning("not-identified", ",".join(names),
                      f"{source}: {', '.join(names)} not determined by the fit that made this "
                      "model (no standard error in the file): their values are not to be "
                      "trusted")


def _fit_cutoff(doc: dict[str, Any] | None) -> float | None:
    """The cut-off (Hz) of a fit's JSON given as ``--params``, if not the default: compared
    with it, the model scores the fit's RMS."""
    from fcomp.identification.target import CUTOFF_HZ

    cutoff = None if doc is None else doc.get("cutoff_hz")
    if isinstance(cutoff, int | float) and not isinstance(cutoff, bool) and cutoff > 0 \
            and cutoff != CUTOFF_HZ:
        return float(cutoff)
    return None


def _values_from(args: argparse.Namespace, doc: dict[str, Any] | None) -> str:
    """Where the compared model's values come from, in words (the report's subtitle): the
    model file, the ``--params`` file ``doc`` (a model file has a ``format``), a set."""
    from fcomp.modelfile import is_model_file

    spec, friction = args.params, args.friction
    if is_model_file(friction):
        where = f"the model file `{friction}`"
    elif doc is not None:
        where = f"the {'model file' if 'format' in doc else 'fit file'} `{spec}`"
    elif spec is not None:
        where = f"the parameter set `{spec}`"
    else:
        where = "the model's default values"
    return where + (" with --set " + ", ".join(f"`{a}`" for a in args.set) if args.set else "")


def run(args: argparse.Namespace) -> int:
    from fcomp.api import compare
    from fcomp.measurement import Measurement
    from fcomp.modelfile import is_model_file
    from fcomp.models.fitted_range import signal_ranges
    from fcomp.outputs import staged_folder
    from fcomp.registry import PLANT_TOOLS, PLANTS

    out = json_target(args.json)
    report = report_dir(args.report)
    if args.cutoff is not None and not args.cutoff > 0:
        raise FcompError(f"--cutoff must be a positive frequency in Hz, got {args.cutoff:g}")
    common.check_jobs(args.jobs)
    scheduler = check_scheduler(args.scheduler)
    if args.mass is not None and not args.mass >= 0:
        raise FcompError(f"--mass must be a non-negative number of kg, got {args.mass:g}")
    plant_params: Any = args.plant_params
    if plant_params is not None and plant_params.lower().endswith(".toml"):
        pf = PLANT_TOOLS.get("read_plant_file")(plant_params)
        if args.plant not in (None, pf.kind):
            raise FcompError(f"--plant-params {plant_params}: a {pf.kind} plant, not "
                             f"{args.plant}")
        args.plant, plant_params = pf.kind, pf.parameter_set()
    if args.plant is not None:
        PLANTS.get(args.plant)  # an unknown name now, with the list of known ones
    inputs = common.measurement_inputs(args.data)
    for option, spec in (("--params", args.params), ("--friction", args.friction)):
        if spec is not None and spec.lower().endswith(".json"):
            inputs.file(spec, option)
    if args.plant_params is not None and args.plant_params.lower().endswith(".toml"):
        inputs.file(args.plant_params, "--plant-params")
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    common.check_outputs(inputs, [("--json", out)], [("--report", report, "report")])
    given = bool(args.params or args.set or args.fit or args.friction.lower().endswith(".json"))
    document = (common.params_document(args.params)  # read once, for all three uses
                if args.params is not None and is_model_file(args.params)
                and not is_model_file(args.friction) else None)
    model, mass = common.model_with_params(args, use="model compared", measured=True,
                                           document=document)
    cutoff = args.cutoff if args.cutoff is not None else _fit_cutoff(document)
    values_from = _values_from(args, document)
    data = [Measurement.read(p) for p in args.data]
    for d in data:
        common.warn_sidecar(d)
    with common.Activity(f"compare {args.friction}", enabled=not args.no_progress):
        comp = compare(data, model, fit=args.fit,
                       mass=args.mass if args.mass is not None else mass, split=args.split,
                       cutoff_hz=cutoff, plant=args.plant, plant_params=plant_params,
                       jobs=args.jobs, scheduler=scheduler)
    seen = signal_ranges([e.data.sig for e in comp.data.experiments], comp.data.available)
    common.warn_fitted_range(model, args.friction if is_model_file(args.friction) else  # as the
                             args.params or model.describe(), "--friction", **seen)  # fit saw them
    if not given:  # part of the result: the report's conclusion weighs it as the console's
        comp = replace(comp, warnings=[*comp.warnings, FitWarning(
            "default-params", "params", f"the model {model.describe()} is compared with its "
            f"default values: give {term('params')} (a fit's JSON or a parameter set) or "
            "--fit for a model that belongs to these records")])
    undetermined = _undetermined(args, document)
    if undetermined is not None:  # as the fit that made the model said: not to be trusted
        comp = replace(comp, warnings=[*comp.warnings, undetermined])
    doc = common.with_warnings({**comp.to_dict(), "friction": args.friction})
    text = result_text(doc)
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else None
    if report is not None:
        with staged_folder(report, "--report", "report", note=command or "fcomp compare") as tmp:
            comp.write_report(tmp, command=command, values_from=values_from)
        common.wrote(report / "report.html")
    emit_result(text, args.json, out, summary(doc))
    return 0

