"""``fcomp export CONTROLLER --plant hydraulic|pneumatic [--params SET] [--friction MODEL]
-o DIR [--json OUT]`` -- a controller's step as C code for a real-time target.

The controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``, ``mpc``) built on the
plant with the friction model (``--friction`` with ``--params``,
``--add-effect``, ``--set``, as ``simulate`` takes them) becomes one CasADi
function ``step(state, y, ref) -> (u, state_next)``, generated as C behind a
plain interface (``fcomp_ctrl.h``: ``fcomp_ctrl_init``, ``fcomp_ctrl_step``,
``fcomp_ctrl_step_ref``; fixed memory, nothing allocated) with a ``Makefile``
and ``example.c``, written to DIR. With a C compiler (``$FCOMP_CC``, else
``$CC``, cc, gcc, clang) fcomp builds it, runs it in closed loop against the
Python plant on ``--task`` for ``--duration`` s, checks that its commands
equal the Python controller's at every sample (relative 1e-9) and times
``--timing-steps`` compiled steps in a C loop. No compiler: the code is still
written, ``equivalent`` is null and a warning says why (exit 0).

JSON: ``{"controller", "plant", "friction", "files", "equivalent", "max_rel_diff",
"step_time_median", "step_time_max", ...,"warnings"}`` (times in s). ``mpc`` is exported
in its fixed-iteration form (``controllers.mpc_fixed``: the QP by 30 ADMM iterations
instead of DAQP, which cannot be generated as C), checked against that form in Python.
"""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path
from typing import Any

from fcomp.cli import common
from fcomp.cli.common import add_model_options, emit_result, finite_float, json_target
from fcomp.errors import FcompError

#: Controller options that are counts (integers).
INTEGER_OPTIONS = ("horizon", "substeps", "qp_iterations")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="a controller's step as C code (CasADi), compiled, "
                       "checked against the Python controller and timed",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("controller", help="pid, pid-ff, lugre-observer, ekf or mpc (its "
                   "fixed-iteration form)")
    p.add_argument("--plant", default=None, help="hydraulic (default) or pneumatic; with "
                   "--plant-params, its kind")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="the plant as a file (docs/plants.md: fcomp plant template)")
    p.add_argument("--params", default=None,
                   help="parameter set of the plant and the friction model (default: the "
                   "plant's)")
    p.add_argument("--friction", default="nmlgm",
                   help="the controller's friction model: a name or a model file MODEL.json "
                   "(default nmlgm)")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="folder for the C files (replaced whole; fcomp's own or new)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    p.add_argument("--task", default="seed002-sine",
                   help="closed-loop task of the check (default seed002-sine)")
    p.add_argument("--duration", type=finite_float, default=0.6,
                   help="length of the closed-loop check, s (default 0.6)")
    p.add_argument("--timing-steps", type=int, default=100_000, metavar="N",
                   help="compiled steps timed (default and least 100000)")
    p.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                   help="a controller option (observer_gain=30, bandwidth=50, ...); repeatable")
    add_model_options(p)
    p.set_defaults(func=run)


def control_model(args: argparse.Namespace) -> Any:
    """The :class:`~controllers.plant_model.ControlModel` (plant and friction) of the options.

    The hook where a plant file (``--plant-params``) and a model file
    (``--friction FILE.json``) resolve: whatever they give, the export takes a
    ``ControlModel``.
    """
    from controllers.plant_model import ControlModel
    from plants import PLANTS
    from plants.planfile import KINDS

    if args.plant_params is not None:
        from plants.planfile import read_plant_file

        plant_file = read_plant_file(args.plant_params)
        if args.plant not in (None, plant_file.kind):
            raise FcompError(f"--plant-params {args.plant_params}: a {plant_file.kind} plant, "
                             f"not {args.plant}")
        params = args.params if args.params is not None else PLANTS.get(
            plant_file.kind).default_params
        return ControlModel(plant_file, common.friction_model(
            args.friction, params, args, use="controller friction"), args.params)
    plant = args.plant or "hydraulic"
    if plant not in KINDS:
        raise FcompError(f"--plant {plant!r}: the controllers run on "
                         f"{' or '.join(sorted(KINDS))}")
    params = args.params if args.params is not None else PLANTS.get(plant).default_params
    friction = common.friction_model(args.friction, params, args,
                                     use="controller friction")
    return ControlModel(plant, friction, args.params)


def summary(doc: dict[str, Any]) -> str:
    lines = [f"export {doc['controller']} on {doc['plant']}: {len(doc['files'])} files in "
             f"{doc['folder']}", f"  step: {doc['step']}"]
    if doc["equivalent"] is None:
        lines.append("  not compiled, checked or timed (see the warning)")
    else:
        lines.append(f"  equivalent to the Python controller ({doc['python_reference']}): "
                     f"{'yes' if doc['equivalent'] else 'NO'} (max relative difference "
                     f"{doc['max_rel_diff']:.3g} step by step, {doc['free_run_max_rel_diff']:.3g} "
                     f"free-running, over {doc['steps_checked']} closed-loop steps)")
        lines.append(f"  compiled step time: median {doc['step_time_median'] * 1e6:.3g} us, "
                     f"max {doc['step_time_max'] * 1e6:.3g} us over {doc['timed_steps']} steps")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from controllers import CONTROLLERS
    from controllers.export import EXPORTABLE, export_controller
    from controllers.tasks import TASKS
    from fcomp.outputs import InputSet, check_folder_target, staged_folder

    CONTROLLERS.get(args.controller)
    if args.controller not in EXPORTABLE:
        raise FcompError(f"export: controller {args.controller} is not exported (exported: "
                         f"{', '.join(EXPORTABLE)})")
    TASKS.get(args.task)
    out = json_target(args.json)
    if not args.output.strip():
        raise FcompError("-o: no folder name given (an empty argument)")
    folder = Path(args.output)
    check_folder_target("-o", folder, "export")
    inputs = InputSet()
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction)):
        if spec is not None and spec.lower().endswith((".toml", ".json")):
            inputs.file(spec, option)
    common.check_outputs(inputs, [("--json", out)], [("-o", folder, "export")])
    options: dict[str, Any] = dict(common.parse_assignments(args.option, option="--option"))
    for k in INTEGER_OPTIONS:  # counts given on the command line as numbers
        if k in options and float(options[k]).is_integer():
            options[k] = int(options[k])
    model = control_model(args)
    command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else "fcomp export"
    with staged_folder(folder, "-o", "export", note=command) as tmp:
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
