"""The run of ``fcomp compensate`` (options and help: :mod:`fcomp.cli.compensate`): what a
better friction model buys in closed loop, as JSON, a summary and a report."""

from __future__ import annotations

import argparse
import shlex
from typing import Any

from controllers import CONTROLLERS
from controllers.compensate import (
    DEFAULT_CONTROLLERS,
    compensate,
    default_samples,
    report,
    resolve_plant,
)
from controllers.robustness import MAX_SAMPLES
from controllers.tasks import TASKS
from fcomp.cli import common
from fcomp.cli.common import emit_result, json_target, report_dir, result_text
from fcomp.effects import load_effects_module
from fcomp.errors import FcompError
from fcomp.modelfile import is_model_file
from fcomp.models import MODELS
from fcomp.outputs import InputSet, staged_folder
from fcomp.parallel import check_scheduler
from fcomp.progress import progress_bar


def _plant(args: argparse.Namespace) -> Any:
    """The plant file of ``--plant-params`` (its kind checked against ``--plant``) or the
    built-in plant of ``--plant``."""
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
    """The conclusion (:func:`controllers.conclusions.of_compensation`), then the ratios
    per controller and task, as printed."""
    from controllers.conclusions import of_compensation

    base = doc["baseline"]
    others = [m for m in doc["models"] if m != base]
    lines = [*of_compensation(doc).lines(), "",f"compensate on {doc['plant']['name']} ({doc['plant']['kind']}), true friction "
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
    """Run ``fcomp compensate``: every controller with every model, the ratios to the
    baseline's errors, the report."""
    if args.task is not None and args.reference is not None:
        raise FcompError("--task and --reference: give one of them")
    out = json_target(args.json)
    folder = report_dir(args.report)
    scheduler = check_scheduler(args.scheduler)
    common.check_jobs(args.jobs)
    if args.samples is not None and not 0 <= args.samples <= MAX_SAMPLES:
        raise FcompError(f"--samples must be 0 to {MAX_SAMPLES} draws (each one closed-loop "
                         f"run per controller and model), got {args.samples}")
    if not 0 <= args.spread < 1:
        raise FcompError(f"--spread must lie in [0, 1), got {args.spread:g}")
    if args.seed < 0:
        raise FcompError(f"--seed must be a non-negative integer, got {args.seed}")
    controllers = tuple(common.name_list(args.controllers, "--controllers")
                        or DEFAULT_CONTROLLERS)
    for c in controllers:
        CONTROLLERS.get(c)
    if args.task is not None:
        TASKS.get(args.task)
    models = common.name_list(args.controller_friction, "--controller-friction") or []
    inputs = InputSet()
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction),
                         ("--reference", args.reference), ("--effects", args.effects),
                         *(("--controller-friction", m) for m in models)):
        if spec is not None and (option in ("--reference", "--effects")
                                 or spec.lower().endswith((".toml", ".json"))):
            inputs.file(spec, option)
    common.check_outputs(inputs, [("--json", out)], [("--report", folder, "report")])
    if args.effects is not None:
        load_effects_module(args.effects)
    for m in [args.friction, *models]:
        if not is_model_file(m):
            MODELS.get(m)
    plant = _plant(args)
    _fitted_ranges(args, plant, models)
    n_jobs = _count(args, controllers, len(models))
    bar = progress_bar("compensate", n_jobs, enabled=not args.no_progress)
    try:
        res = compensate(plant, args.friction, models, controllers=controllers,
                         task=args.task, reference=args.reference, fast=args.fast,
                         samples=args.samples, spread=args.spread, seed=args.seed,
                         workers=args.jobs,
                         scheduler=scheduler, keep_signals=folder is not None,
                         progress=lambda done, total: bar.update(done - bar.n),
                         effects=args.effects)
    finally:
        bar.close()
    doc = common.with_warnings(res.as_dict())
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else None
    if folder is not None:
        with staged_folder(folder, "--report", "report",
                           note=command or "fcomp compensate") as tmp:
            report(res, command).write(tmp / "report.html")
        common.wrote(folder / "report.html")
    emit_result(result_text(doc), args.json, out, summary(doc))
    return 0


def _fitted_ranges(args: argparse.Namespace, plant: Any, models: list[str]) -> None:
    """Warn for each model file used beyond the ranges it was fitted on, before any run
    (:func:`controllers.loop_range.range_warnings`)."""
    from controllers.compensate import read_reference
    from controllers.loop_range import range_warnings

    tasks = ([read_reference(args.reference, plant.values["stroke"])] if args.reference
             else [TASKS.get(args.task)] if args.task else [TASKS.get(n) for n in TASKS.names()])
    for option, line in range_warnings([("--friction", args.friction),
                                        *(("--controller-friction", m) for m in models)],
                                       plant, tasks, args.fast, args.effects):
        common.warn("fitted-range", line, option)


def _count(args: argparse.Namespace, controllers: tuple[str, ...], n_models: int) -> int:
    """How many closed-loop runs the command makes (for the progress bar)."""
    tasks = 1 if args.task is not None or args.reference is not None else len(TASKS.names())
    samples = default_samples(args.fast) if args.samples is None else args.samples
    return len(controllers) * n_models * (tasks + samples)
