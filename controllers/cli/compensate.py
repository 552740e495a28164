"""The run of ``fcomp compensate`` (options and help: :mod:`fcomp.cli.compensate`): what a
better friction model buys in closed loop, as JSON, a summary and a report."""

from __future__ import annotations

import argparse
import shlex
from typing import Any

from controllers import CONTROLLERS
from controllers.compensate import (
    DEFAULT_CONTROLLERS,
    MAX_SAMPLES,
    MAX_TRUTH_DRAWS,
    compensate,
    resolve_plant,
)
from controllers.compensate_report import report
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


def _cell(ratio: float | None, run: dict[str, Any] | None, base: dict[str, Any] | None
          ) -> str:
    """A ratio with both RMS errors (``0.45 (12 vs 27 um)``), or why it is not ranked."""
    def um(r: dict[str, Any] | None) -> str:
        v = None if r is None else r.get("rms_error")
        return "-" if v is None else f"{v * 1e6:.3g}"

    if ratio is not None:
        return f"{ratio:.3g} ({um(run)} vs {um(base)} um)"
    for who, r in (("", run), ("baseline ", base)):
        if r is not None and r.get("status") != "ok":
            return f"not ranked ({who}{str(r['status']).split(':')[0]})"
    return "not ranked"


def summary(doc: dict[str, Any]) -> str:
    """The conclusion (:func:`controllers.conclusions.of_compensation`), then, as printed:
    each compared model's median-task ratio under every truth, the ratios with the absolute
    errors under each truth, what was not ranked and why, the robustness draws."""
    from controllers.conclusions import of_compensation

    base = doc["baseline"]
    others = [m for m in doc["models"] if m != base]
    truths = list(doc["truths"])
    uses = doc["uses_friction"]
    by = {(r["truth"], r["controller"], r["model"], r["task"]): r for r in doc["runs"]}
    what = ("the true friction given" if doc["mode"] == "given"
            else f"{len(truths)} candidate truths")
    lines = [*of_compensation(doc).lines(), "",
             f"compensate on {doc['plant']['name']} ({doc['plant']['kind']}): "
             f"{len(doc['runs'])} runs under {what} ({', '.join(truths)}); RMS error ratio to "
             f"{base} (below 1: better), with the RMS errors (model vs {base})"]
    lines.append("median-task ratio under each truth:")
    for c in doc["controllers"]:
        if not uses.get(c, True):
            lines.append(f"  {c:15s} uses no friction model (ratio 1)")
            continue
        for m in others:
            a = doc["across_truths"][c][m]
            cells = ", ".join(f"{t} {'-' if v is None else f'{v:.3g}'}"
                              for t, v in a["per_truth"].items())
            lines.append(f"  {c:15s} {m}: {cells} -> {a['holds']}")
    for t in truths:
        info = doc["truths"][t]
        lines.append(f"under {t} ({info['description']}"
                     + (f"; the compared model {info['equals']}" if info["equals"] else "")
                     + "):")
        for c in doc["controllers"]:
            if not uses.get(c, True):
                continue
            for m in others:
                cells = []
                for task in doc["tasks"]:
                    r = ((doc["ratios"].get(t, {}).get(c, {}).get(task, {}).get(m)) or {})
                    cells.append(f"{task} " + _cell(r.get("rms_error"), by.get((t, c, m, task)),
                                                    by.get((t, c, base, task))))
                lines.append(f"  {c:15s} {m}: " + ", ".join(cells))
    out = [r for r in doc["runs"] if r["status"] != "ok"]
    if out:
        groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
        for r in out:
            head = str(r["status"]).split(";")[0].split(" the ")[0]
            groups.setdefault((r["controller"], r["model"], head), []).append(r)
        lines.append(f"not ranked ({len(out)} of {len(doc['runs'])} runs):")
        for (c, m, _), rs in list(groups.items())[:8]:
            where = sorted({f"{r['task']} under {r['truth']}" for r in rs})
            lines.append(f"  {c} with {m} ({len(rs)} run{'s' if len(rs) > 1 else ''}: "
                         f"{', '.join(where[:3])}{' ...' if len(where) > 3 else ''}): "
                         f"{rs[0]['status']}")
        if len(groups) > 8:
            lines.append(f"  and {len(groups) - 8} more kinds (the runs in the JSON or report)")
    rob = doc["robustness"]
    if rob["samples"]:
        lines.append(f"robustness: {rob['samples']} draws on {rob['task']} over the truths:")
        for c in doc["controllers"]:
            for m in others:
                r = rob["controllers"].get(c, {}).get("ratio", {}).get(m)
                if r and r.get("median") is not None and uses.get(c, True):
                    lines.append(f"  {c:15s} {m}: median ratio {r['median']:.3g}, better in "
                                 f"{r['better'] * 100:.0f} % of {r['paired_draws']} draws")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run ``fcomp compensate``: every controller with every model under each truth, the
    ratios to the baseline's errors, the report; exit status 2 when no run could be ranked
    (the result still written)."""
    if args.task is not None and args.reference is not None:
        raise FcompError("--task and --reference: give one of them")
    if args.friction is not None and (args.truths is not None or args.truth_draws is not None):
        raise FcompError("--friction gives the plant's one true friction: no --truths or "
                         "--truth-draws with it")
    out = json_target(args.json)
    folder = report_dir(args.report)
    scheduler = check_scheduler(args.scheduler)
    common.check_jobs(args.jobs)
    for option, value, most in (("--samples", args.samples, MAX_SAMPLES),
                                ("--truth-draws", args.truth_draws, MAX_TRUTH_DRAWS)):
        if value is not None and value < 0:
            raise FcompError(f"{option} must be 0 or more, got {value}")
        if value is not None and value > most:
            raise FcompError(f"{option} {value}: at most {most} (each draw runs every "
                             "controller with every model)")
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
    truths = common.name_list(args.truths, "--truths") or []
    inputs = InputSet()
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction),
                         ("--reference", args.reference), ("--effects", args.effects),
                         *(("--controller-friction", m) for m in models),
                         *(("--truths", m) for m in truths)):
        if spec is not None and (option in ("--reference", "--effects")
                                 or spec.lower().endswith((".toml", ".json"))):
            inputs.file(spec, option)
    common.check_outputs(inputs, [("--json", out)], [("--report", folder, "report")])
    if args.effects is not None:
        load_effects_module(args.effects)
    for m in [*([args.friction] if args.friction is not None else []), *models, *truths]:
        if not is_model_file(m):
            MODELS.get(m)
    plant = _plant(args)
    _fitted_ranges(args, plant, models)
    bar = progress_bar("compensate", None, enabled=not args.no_progress)

    def tick(done: int, total: int) -> None:
        if bar.total != total:
            bar.total = total
        bar.update(done - bar.n)

    try:
        res = compensate(plant, args.friction, models, controllers=controllers,
                         task=args.task, reference=args.reference, fast=args.fast,
                         samples=args.samples, spread=args.spread, seed=args.seed,
                         truth_draws=args.truth_draws, truths=truths, workers=args.jobs,
                         scheduler=scheduler, keep_signals=folder is not None,
                         progress=tick, effects=args.effects)
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
    if not any(r["status"] == "ok" for r in doc["runs"]):
        where = (f"; each run's status is in {out}" if out is not None
                 else "; the summary above lists why")
        raise FcompError(f"compensate: no run could be ranked -- every one of the "
                         f"{len(doc['runs'])} runs failed, was flagged or skipped{where}")
    return 0


def _fitted_ranges(args: argparse.Namespace, plant: Any, models: list[str]) -> None:
    """Warn for each model file used beyond the ranges it was fitted on, before any run
    (:func:`controllers.model_range.fitted_range_warnings`)."""
    from controllers.compensate import read_reference
    from controllers.model_range import fitted_range_warnings

    tasks = ([read_reference(args.reference, plant.values["stroke"])] if args.reference
             else [TASKS.get(args.task)] if args.task else [TASKS.get(n) for n in TASKS.names()])
    for option, line in fitted_range_warnings([("--friction", args.friction),
                                        *(("--controller-friction", m) for m in models)],
                                       plant, tasks, args.fast, args.effects):
        common.warn("fitted-range", line, option)

