"""The run of ``fcomp export`` (options and help: :mod:`fcomp.cli.export`): a controller's step
as C code, compiled, checked against the Python controller and timed."""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path
from typing import Any

from controllers import CONTROLLERS
from controllers.export import EXPORTABLE, MAX_TIMING_STEPS, export_controller
from controllers.plant_model import ControlModel
from controllers.tasks import TASKS
from fcomp.cli import common
from fcomp.cli.common import emit_result, json_target
from fcomp.errors import FcompError
from fcomp.outputs import InputSet, check_folder_target, staged_folder
from plants import PLANTS
from plants.planfile import KINDS, read_plant_file

#: Controller options that are counts (integers).
INTEGER_OPTIONS = ("horizon", "substeps", "qp_iterations")


def control_model(args: argparse.Namespace) -> Any:
    """The :class:`~controllers.plant_model.ControlModel` (plant and friction) of the options.

    The hook where a plant file (``--plant-params``) and a model file
    (``--friction FILE.json``) resolve: whatever they give, the export takes a
    ``ControlModel``.
    """
    from fcomp.modelfile import is_model_file

    common.refuse_params_with_model_file(args.friction, args.params)
    plant_set = None if args.params is None or is_model_file(args.params) else args.params
    if args.plant_params is not None:
        plant_file = read_plant_file(args.plant_params)
        if args.plant not in (None, plant_file.kind):
            raise FcompError(f"--plant-params {args.plant_params}: a {plant_file.kind} plant, "
                             f"not {args.plant}")
        params = plant_set or PLANTS.get(plant_file.kind).default_params
        return ControlModel(plant_file, common.friction_model(
            args.friction, args.params if plant_set is None and args.params else params, args,
            use="controller friction"), plant_set)
    plant = args.plant or "hydraulic"
    if plant not in KINDS:
        raise FcompError(f"--plant {plant!r}: the controllers run on "
                         f"{' or '.join(sorted(KINDS))}")
    params = plant_set or PLANTS.get(plant).default_params
    friction = common.friction_model(args.friction,
                                     args.params if plant_set is None and args.params else params,
                                     args, use="controller friction")
    return ControlModel(plant, friction, plant_set)


def _fitted_range(args: argparse.Namespace, model: Any) -> None:
    """Warn when the model file is used beyond the ranges it was fitted on (before the
    export: :func:`controllers.model_range.fitted_range_warnings`)."""
    from controllers.model_range import fitted_range_warnings
    from plants.planfile import builtin_plant_file

    plant_file = (read_plant_file(args.plant_params) if args.plant_params is not None
                  else builtin_plant_file(model.plant_name))
    for option, line in fitted_range_warnings([("--friction", args.friction)], plant_file,
                                       [TASKS.get(args.task)], False, args.effects):
        common.warn("fitted-range", line, option)


def summary(doc: dict[str, Any]) -> str:
    lines = [f"export {doc['controller']} on {doc['plant']}: {len(doc['files'])} files in "
             f"{doc['folder']}", f"  step: {doc['step']}",
             f"  runs at {doc['rate']:g} Hz: call it every {1e3 * doc['sample_time']:g} ms"
             + ("" if doc["rate"] == doc["plant_rate"] else
                f" (the plant file's [control] rate is {doc['plant_rate']:g} Hz)")]
    fs = doc["fail_safe"]
    lines.append(f"  fail-safe layer: safe output {fs['safe_output']} after "
                 f"{fs['fault_latch']} faulty samples in a row, resumes after "
                 f"{fs['fault_recover']} good ones")
    if doc["equivalent"] is None:
        lines.append("  not compiled, checked or timed (see the warning)")
    else:
        fc = doc["fault_check"]
        lines.append(f"  equivalent to the Python controller ({doc['python_reference']}): "
                     f"{'yes' if doc['equivalent'] else 'NO'} (max relative difference "
                     f"{doc['max_rel_diff']:.3g} step by step, {doc['free_run_max_rel_diff']:.3g} "
                     f"free-running, over {doc['steps_checked']} closed-loop steps; on hostile "
                     f"input {fc['max_rel_diff']:.3g} over {fc['samples']} steps, {fc['faults']} "
                     f"faults, {fc['latches']} latches, {fc['recoveries']} recoveries, fault "
                     f"states {'the same' if fc['same_faults'] else 'DIFFERENT'})")
        lines.append(f"  compiled step time (CPU time of the step): median "
                     f"{doc['step_time_median'] * 1e6:.3g} us, max "
                     f"{doc['step_time_max'] * 1e6:.3g} us over {doc['timed_steps']} steps; "
                     f"wall-clock worst {doc['step_time_wall_max'] * 1e6:.3g} us (with the time "
                     "the processor was given to other processes)")
    return "\n".join(lines)


#: Longest closed-loop check of an export (s): every controller step of it is simulated.
MAX_CHECK_S = 3600.0


def run(args: argparse.Namespace) -> int:
    """Run ``fcomp export``: the controller's step as C, compiled, checked and timed."""
    CONTROLLERS.get(args.controller)
    if args.controller not in EXPORTABLE:
        raise FcompError(f"export: controller {args.controller} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    TASKS.get(args.task)
    if not 0 < args.duration <= MAX_CHECK_S:  # the closed-loop check runs all of it
        raise FcompError(f"--duration {args.duration:g}: the check's closed loop lasts more "
                         f"than 0 and at most {MAX_CHECK_S:g} s")
    if not 100_000 <= args.timing_steps <= MAX_TIMING_STEPS:
        raise FcompError(f"--timing-steps {args.timing_steps}: time 100000 to "
                         f"{MAX_TIMING_STEPS} steps (two times of each are kept in memory)")
    out = json_target(args.json)
    if not args.output.strip():
        raise FcompError("-o: no folder name given (an empty argument)")
    folder = Path(args.output)
    check_folder_target("-o", folder, "export")
    inputs = InputSet()
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction),
                         ("--params", args.params)):
        if spec is not None and spec.lower().endswith((".toml", ".json")):
            inputs.file(spec, option)
    common.check_outputs(inputs, [("--json", out)], [("-o", folder, "export")])
    options: dict[str, Any] = dict(common.parse_assignments(args.option, option="--option"))
    for k in INTEGER_OPTIONS:  # counts given on the command line as numbers
        if k in options and float(options[k]).is_integer():
            options[k] = int(options[k])
    model = control_model(args)
    _fitted_range(args, model)
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else "fcomp export"
    with staged_folder(folder, "-o", "export", note=command) as tmp, \
            common.Activity(f"export {args.controller}", enabled=not args.no_progress):
        res = export_controller(args.controller, model, tmp, options=options, task=args.task,
                                duration=args.duration, timing_steps=args.timing_steps)
    for w in res.warnings:
        common.warn("export", w.replace(str(tmp), str(folder)))
    doc = res.as_dict()
    doc["files"] = [str(folder / Path(f).name) for f in doc["files"]]
    doc = {"controller": doc.pop("controller"), "plant": model.describe(),
           "friction": model.friction.describe(), "folder": str(folder), **doc}
    doc = common.with_warnings(doc)
    emit_result(common.result_text(doc), args.json, out, summary(doc))
    return 0
