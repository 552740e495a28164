"""``fcomp compensate --plant-params PLANT.toml --friction TRUE.json --models
BASE.json,DIAG.json [--controllers C,...] [--task T | --reference REF.csv] [--fast]
[--samples N] [--json OUT] [--report DIR] [--scheduler ADDRESS]`` -- what a better
friction model buys in closed loop.

On the plant of a plant file (or ``--plant hydraulic|pneumatic``, a built-in
plant) whose simulated friction is ``--friction`` (a model file, or a model
name), every controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``,
``mpc``; ``--controllers`` a subset) is built once with each model of
``--models`` (model files, named by their stems; the first is the baseline)
and run on the standard tasks (``slow-sine``, ``steps``, ``low-velocity-ramp``,
``seed002-sine``; ``--task`` one, ``--fast`` their short versions) or on a
reference of your own (``--reference REF.csv``: columns ``t`` (s) and
``x_ref`` (m, absolute position inside the stroke), times increasing).

Reported: per controller, model and task the RMS, max, reversal and hunting
errors (on the true position), their ratios to the baseline's (below 1 the
model helps), and a short robustness Monte Carlo on one task (``steps``, or
the one given): ``--samples`` draws (default 8, 4 with ``--fast``; 0 none)
in which every parameter of the true friction and the moving mass are off by
a factor uniform in 1 +- 0.2 (``--spread``), every controller and model on the
same draws.
Measurement terms of a model file (force offset, fitted mass, channel lag)
are dropped with a warning. The runs go to local processes (``--workers``)
or to a Dask cluster (``--scheduler ADDRESS``).

JSON: ``{"plant", "friction", "models", "baseline", "controllers", "tasks",
"runs": [{"controller", "model", "task", "status", "rms_error", "max_error",
"reversal_error", "hunting", "steady_state_error", ...}], "ratios":
{controller: {task: {model: {error: ratio}}}}, "robustness", "warnings"}``
(errors in m); ``--report DIR`` draws them (docs/your-cylinder.md).
"""

from __future__ import annotations

import argparse
import shlex
from typing import Any

from fcomp.cli import common
from fcomp.cli.common import emit_result, finite_float, json_target, report_dir, result_text
from fcomp.errors import FcompError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("compensate", help="every compensator built with each friction model "
                       "(baseline vs diagnosed) on your plant: what the better model buys",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--plant", default=None,
                   help="hydraulic or pneumatic: a built-in plant; with --plant-params, its kind")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="the plant as a file (docs/plants.md: fcomp plant template)")
    p.add_argument("--friction", required=True, metavar="TRUE.json|NAME",
                   help="the plant's simulated (true) friction: a model file or a model name")
    p.add_argument("--models", required=True, metavar="BASE.json,DIAG.json,...",
                   help="the controllers' friction models, the first the baseline: model "
                   "files (named by their stems) or model names")
    p.add_argument("--controllers", default=None, metavar="C1,C2,...",
                   help="controllers to run (default: pid,pid-ff,lugre-observer,ekf,mpc)")
    p.add_argument("--task", default=None,
                   help="one standard task (default: slow-sine, steps, low-velocity-ramp, "
                   "seed002-sine)")
    p.add_argument("--reference", default=None, metavar="REF.csv",
                   help="your own reference instead: a CSV with columns t (s), x_ref (m)")
    p.add_argument("--fast", action="store_true", help="the short versions of the tasks")
    p.add_argument("--samples", type=int, default=None, metavar="N",
                   help="robustness draws (default 8, 4 with --fast; 0: none)")
    p.add_argument("--spread", type=finite_float, default=0.2,
                   help="half width of the draws' uniform factors on the true friction and "
                   "the mass (default 0.2: +-20 %%)")
    p.add_argument("--seed", type=int, default=2026, help="seed of the draws and the noise")
    common.add_effects_option(p)
    common.add_closed_loop_run_options(p)
    p.set_defaults(func=run)


def _plant(args: argparse.Namespace) -> Any:
    """The plant file of ``--plant-params`` (its kind checked against ``--plant``) or the
    built-in plant of ``--plant``."""
    from controllers.compensate import resolve_plant

    if args.plant_params is not None:
        if not args.plant_params.lower().endswith(".toml"):
            raise FcompError(f"--plant-params {args.plant_params}: a plant file ends in .toml")
        pf = resolve_plant(args.plant_params)
        if args.plant not in (None, pf.kind):
            raise FcompError(f"--plant-params {args.plant_params}: a {pf.kind} plant, not "
                             f"{args.plant}")
        return pf
    if args.plant is None:
        raise FcompError("give the plant: --plant-params PLANT.toml or --plant "
                         "hydraulic|pneumatic")
    if args.plant not in ("hydraulic", "pneumatic"):
        raise FcompError(f"--plant {args.plant!r}: the closed loops run on hydraulic or "
                         "pneumatic")
    return resolve_plant(args.plant)


def summary(doc: dict[str, Any]) -> str:
    """The ratios per controller and task, as printed."""
    base = doc["baseline"]
    others = [m for m in doc["models"] if m != base]
    lines = [f"compensate on {doc['plant']['name']} ({doc['plant']['kind']}), true friction "
             f"{doc['friction']}: {len(doc['runs'])} runs; RMS error ratio to {base} "
             "(below 1: better)"]
    for c in doc["controllers"]:
        for m in others:
            cells = []
            for t in doc["tasks"]:
                r = ((doc["ratios"].get(c, {}).get(t, {}).get(m)) or {}).get("rms_error")
                cells.append(f"{t} {'failed' if r is None else f'{r:.3g}'}")
            rob = doc["robustness"]["controllers"].get(c, {}).get("ratio", {}).get(m)
            extra = (f"; draws on {doc['robustness']['task']}: median {rob['median']:.3g}, "
                     f"better in {rob['better'] * 100:.0f} %"
                     if rob and rob.get("median") is not None else "")
            lines.append(f"  {c:15s} {m}: " + ", ".join(cells) + extra)
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from controllers import CONTROLLERS
    from controllers.compensate import DEFAULT_CONTROLLERS, compensate, report
    from controllers.tasks import TASKS
    from fcomp.modelfile import is_model_file
    from fcomp.outputs import InputSet, staged_folder
    from fcomp.parallel import check_scheduler, progress_bar

    if args.task is not None and args.reference is not None:
        raise FcompError("--task and --reference: give one of them")
    out = json_target(args.json)
    folder = report_dir(args.report)
    scheduler = check_scheduler(args.scheduler)
    if args.workers is not None and args.workers < 1:
        raise FcompError(f"--workers must be a positive integer, got {args.workers}")
    if args.samples is not None and args.samples < 0:
        raise FcompError(f"--samples must be 0 or more, got {args.samples}")
    if not 0 <= args.spread < 1:
        raise FcompError(f"--spread must lie in [0, 1), got {args.spread:g}")
    controllers = tuple(common.name_list(args.controllers, "--controllers")
                        or DEFAULT_CONTROLLERS)
    for c in controllers:
        CONTROLLERS.get(c)
    if args.task is not None:
        TASKS.get(args.task)
    models = common.name_list(args.models, "--models") or []
    inputs = InputSet()
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction),
                         ("--reference", args.reference), ("--effects", args.effects),
                         *(("--models", m) for m in models)):
        if spec is not None and (option in ("--reference", "--effects")
                                 or spec.lower().endswith((".toml", ".json"))):
            inputs.file(spec, option)
    common.check_outputs(inputs, [("--json", out)], [("--report", folder, "report")])
    if args.effects is not None:
        from fcomp.effects import load_effects_module

        load_effects_module(args.effects)
    for m in [args.friction, *models]:
        if not is_model_file(m):
            from fcomp.models import MODELS

            MODELS.get(m)
    plant = _plant(args)
    n_jobs = _count(args, controllers, len(models))
    bar = progress_bar("compensate", n_jobs, enabled=not args.no_progress)
    try:
        res = compensate(plant, args.friction, models, controllers=controllers,
                         task=args.task, reference=args.reference, fast=args.fast,
                         samples=args.samples, spread=args.spread, seed=args.seed,
                         workers=args.workers,
                         scheduler=scheduler, keep_signals=folder is not None,
                         progress=lambda done, total: bar.update(done - bar.n),
                         effects=args.effects)
    finally:
        bar.close()
    for w in res.warnings:
        common.warn(w["code"], w["message"], w["parameter"])
    doc = common.with_warnings(res.as_dict())
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else None
    if folder is not None:
        with staged_folder(folder, "--report", "report",
                           note=command or "fcomp compensate") as tmp:
            report(res, command).write(tmp / "report.html")
        if args.json != "-":
            print(f"wrote {folder / 'report.html'}")
    emit_result(result_text(doc), args.json, out, summary(doc))
    return 0


def _count(args: argparse.Namespace, controllers: tuple[str, ...], n_models: int) -> int:
    """How many closed-loop runs the command makes (for the progress bar)."""
    from controllers.compensate import default_samples
    from controllers.tasks import TASKS

    tasks = 1 if args.task is not None or args.reference is not None else len(TASKS.names())
    samples = default_samples(args.fast) if args.samples is None else args.samples
    return len(controllers) * n_models * (tasks + samples)
