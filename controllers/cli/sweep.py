"""The run of ``fcomp sweep`` (options and help: :mod:`fcomp.cli.sweep`): Monte Carlo and
parameter grids over compensators and friction-model mismatch, as JSON, a summary and a
report."""

from __future__ import annotations

import argparse
import shlex
from typing import Any

import numpy as np

from controllers import CONTROLLERS
from controllers.conclusions import of_sweep
from controllers.harness import LoopConfig, control_model, friction_label
from controllers.model_range import fitted_range_warnings
from controllers.robustness import Grid, Sweep, distributions, draw_distribution, run_jobs
from controllers.tasks import TASKS
from fcomp import figstyle as fs
from fcomp.cli import common
from fcomp.cli.common import emit_result, json_target, report_dir, result_text
from fcomp.errors import FcompError
from fcomp.modelfile import is_model_file, seal_friction
from fcomp.models import MODELS
from fcomp.outputs import staged_folder
from fcomp.parallel import check_scheduler
from fcomp.progress import progress_bar
from fcomp.report import Report
from plants.planfile import builtin_plant_file, read_plant_file

#: Metrics of a run that do not depend on the machine (solve times do).
METRICS = ("rms_error", "max_error", "steady_state_error")


def _factors(items: list[str]) -> dict[str, tuple[float, ...]]:
    out: dict[str, tuple[float, ...]] = {}
    for item in items:
        if "=" not in item:
            raise FcompError(f"--grid {item!r}: expected PARAM=F1,F2,...")
        name, values = (s.strip() for s in item.split("=", 1))
        if name in out:
            raise FcompError(f"--grid {name}: given twice")
        try:
            out[name] = tuple(common.finite_float(v) for v in values.split(",") if v.strip())
        except argparse.ArgumentTypeError as exc:
            raise FcompError(f"--grid {item!r}: {exc}") from None
    return out


def _friction(spec: str, option: str, effects: str | None) -> Any:
    """A friction option's model: a registered name (checked), or a model file's friction
    (its measurement terms dropped with a warning)."""
    if not is_model_file(spec):
        MODELS.get(spec)
        return spec
    model, dropped = seal_friction(spec, "plant or controller friction", effects)
    if dropped:
        common.warn("measurement-terms", dropped, option)
    return model


def _plan(args: argparse.Namespace) -> Any:
    """The :class:`~controllers.robustness.Sweep` or :class:`~controllers.robustness.Grid`."""
    plant_file = None
    if args.plant_params is not None:
        plant_file = read_plant_file(args.plant_params)
        if args.plant not in (None, plant_file.kind):
            raise FcompError(f"--plant-params {args.plant_params}: a {plant_file.kind} plant, "
                             f"not {args.plant}")
    plant = plant_file.kind if plant_file is not None else args.plant or "hydraulic"
    if plant not in ("hydraulic", "pneumatic"):
        raise FcompError(f"--plant {plant!r}: the closed loops run on hydraulic or pneumatic")
    TASKS.get(args.task)
    controllers = tuple(common.name_list(args.controllers, "--controllers") or ())
    for c in controllers:
        CONTROLLERS.get(c)
    base = LoopConfig(plant=plant, friction=_friction(args.friction, "--friction", args.effects),
                      plant_file=plant_file)
    if plant_file is not None:  # its explicit tuning without margins: refused before any run
        _ = control_model(base).tuning
    names = common.name_list(args.controller_friction, "--controller-friction") or []
    frictions = tuple(_friction(f, "--controller-friction", args.effects) for f in names)
    for option, line in fitted_range_warnings(  # the models' fitted ranges, before any run
            [("--friction", args.friction), *(("--controller-friction", f) for f in names)],
            plant_file or builtin_plant_file(plant), [TASKS.get(args.task)], args.fast,
            args.effects):
        common.warn("fitted-range", line, option)
    if args.grid or frictions:
        return Grid(plant=plant, task=args.task, controllers=controllers,
                    factors=_factors(args.grid), controller_frictions=frictions,
                    seed=args.seed, fast=args.fast, base=base)
    try:
        lo, hi = (common.finite_float(v) for v in args.noise.split(","))
    except (ValueError, argparse.ArgumentTypeError):
        raise FcompError(f"--noise {args.noise!r}: expected LO,HI (two numbers)") from None
    return Sweep(plant=plant, task=args.task, controllers=controllers,
                 samples=args.samples, spread=args.spread, noise=(lo, hi), seed=args.seed,
                 fast=args.fast, base=base)


def summary(doc: dict[str, Any]) -> str:
    """The conclusion (:func:`controllers.conclusions.of_sweep`), then the errors per
    controller (Monte Carlo) or per grid point, as printed."""
    lines = [*of_sweep(doc).lines(), "",f"{doc['mode']} on {doc['plant']}, task {doc['task']}: {len(doc['runs'])} runs"]
    if doc["mode"] == "monte-carlo":
        for c, d in doc["distributions"].items():
            r = d["rms_error"]
            lines.append(f"  {c:16s} RMS median {r['median'] * 1e6:9.3g} um (10-90 %: "
                         f"{r['p10'] * 1e6:.3g}-{r['p90'] * 1e6:.3g} um), {d['failed']} of "
                         f"{d['runs']} failed")
    else:
        for pt in doc["points"]:
            errs = ", ".join(f"{c} {v * 1e6:.3g}" if v is not None else f"{c} failed"
                             for c, v in pt["rms_error"].items())
            lines.append(f"  point {pt['point']} {pt['label']}: RMS [um] {errs}")
    return "\n".join(lines)


def result(plan: Any, runs: list[dict[str, Any]], labels: list[str] | None = None
           ) -> dict[str, Any]:
    """The JSON of a sweep (machine-dependent timings left out of the runs' metrics); the
    controllers' friction models of a grid are named by ``labels`` (as given: a name, a
    model file) or by their descriptions."""
    clean = [{**r, "metrics": None if r["metrics"] is None else
              {k: v for k, v in r["metrics"].items() if not k.startswith("solve_time")}}
             for r in runs]
    doc: dict[str, Any] = {"mode": "grid" if isinstance(plan, Grid) else "monte-carlo",
                           "plant": plan.plant, "task": plan.task,
                           "controllers": list(plan.controllers), "fast": plan.fast,
                           "runs": clean, "units": {"errors": "m"}}
    if isinstance(plan, Grid):
        doc["grid"] = {k: list(v) for k, v in plan.factors.items()}
        names = list(labels) if labels else [friction_label(f) for f in
                                             plan.controller_frictions]
        doc["controller_frictions"] = names
        points = []
        grid = plan.points()
        per = len(grid) // max(len(names), 1)  # points per model (frictions outermost)
        for i, (mismatch, friction) in enumerate(grid):
            mine = [r for r in clean if r["sample"] == i]
            name = names[i // per] if names else friction_label(friction)
            label = ", ".join([f"{k}x{mismatch[k]:g}" for k in plan.factors]
                              + ([f"controller model {name}"]
                                 if plan.controller_frictions else []))
            points.append({"point": i, "label": label, "mismatch": mismatch,
                           "controller_friction": name,
                           "rms_error": {r["controller"]: (r["metrics"] or {}).get("rms_error")
                                         for r in mine}})
        doc["points"] = points
    else:
        doc.update(samples=plan.samples, spread=plan.spread, noise=list(plan.noise),
                   seed=plan.seed, distributions=distributions(clean, METRICS))
    return doc


def report(doc: dict[str, Any], command: str | None) -> Any:
    """The sweep's :class:`~fcomp.report.Report`: the distributions (Monte Carlo) or the
    error at every grid point."""
    rep = Report(f"Sweep: {doc['mode']} on {doc['plant']}, task {doc['task']}",
                 subtitle=f"{len(doc['runs'])} closed-loop runs of "
                 f"{', '.join(doc['controllers'])}", command=command,
                 config={k: doc[k] for k in ("mode", "plant", "task", "fast")})
    rep.conclusion(of_sweep(doc))
    fig, ax = fs.new_figure(height=3.8, width=fs.HALF_WIDTH + 1.6)
    if doc["mode"] == "monte-carlo":
        shown = draw_distribution(ax, doc["distributions"], doc["controllers"], scale=1e6)
        ax.set_ylabel("RMS tracking error (\u00b5m)")
        rep.figure(fig, f"RMS tracking error over the {doc['samples']} draws, per controller "
                   f"(log scale; {'box: quartiles, whiskers 10-90 %' if shown == 'box' else 'every draw a point, line: median'}).")
        rep.table(["controller", "RMS median (µm)", "p10 (µm)", "p90 (µm)", "runs", "failed"],
                  [[c, d["rms_error"]["median"] * 1e6, d["rms_error"]["p10"] * 1e6,
                    d["rms_error"]["p90"] * 1e6, d["runs"], d["failed"]]
                   for c, d in doc["distributions"].items()], digits=[None, 3, 3, 3, 0, 0])
    else:
        xs = np.arange(len(doc["points"]))
        for c in doc["controllers"]:
            ys = [pt["rms_error"].get(c) for pt in doc["points"]]
            ax.plot(xs, [np.nan if y is None else y * 1e6 for y in ys], "o-", label=c)
        ax.set_xticks(xs, [pt["label"] for pt in doc["points"]], rotation=30, ha="right")
        ax.set_xlim(-0.5, len(xs) - 0.5)
        ax.set_yscale("log")
        fs.plain_log_ticks(ax)
        ax.set_ylabel("RMS tracking error (\u00b5m)")
        ax.grid(alpha=0.3)
        fs.legend_above(ax, ncol=5)
        rep.figure(fig, "RMS tracking error at every grid point, per controller (log scale).")
        rep.table(["point", *doc["controllers"]],
                  [[pt["label"], *[None if pt["rms_error"].get(c) is None
                                   else pt["rms_error"][c] * 1e6 for c in doc["controllers"]]]
                   for pt in doc["points"]],
                  caption="RMS tracking error (µm) at every grid point.",
                  digits=[None, *[3] * len(doc["controllers"])])
    rep.table(["controller", "point/draw", "status"],
              [[r["controller"], r["sample"], r["status"]] for r in doc["runs"]
               if r["status"] != "ok"] or [["-", "-", "every run ok"]])
    return rep


def run(args: argparse.Namespace) -> int:
    """Run ``fcomp sweep``: the plan's closed-loop runs, their JSON, summary and report."""
    out = json_target(args.json)
    folder = report_dir(args.report)
    scheduler = check_scheduler(args.scheduler)
    if args.seed < 0:
        raise FcompError(f"--seed must be a non-negative integer, got {args.seed}")
    common.check_jobs(args.jobs)
    inputs = common.plant_inputs(args)
    common.check_outputs(inputs, [("--json", out)], [("--report", folder, "report")])
    plan = _plan(args)
    jobs = plan.jobs()
    bar = progress_bar("sweep", len(jobs), enabled=not args.no_progress)
    try:
        runs = run_jobs(jobs, workers=args.jobs, scheduler=scheduler,
                        progress=lambda done, total: bar.update(done - bar.n))
    finally:
        bar.close()
    doc = common.with_warnings(result(plan, runs, common.name_list(
        args.controller_friction, "--controller-friction")))
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else None
    if folder is not None:
        with staged_folder(folder, "--report", "report", note=command or "fcomp sweep") as tmp:
            report(doc, command).write(tmp / "report.html")
        common.wrote(folder / "report.html")
    emit_result(result_text(doc), args.json, out, summary(doc))
    return 0
