"""``fcomp simulate PLANT --friction NAME [--params SET] --input SPEC --duration S
[--rate HZ] -o OUT.csv`` -- writes a measurement (CSV + TOML sidecar).

Plants: motion (input: velocity, m/s), hydraulic (valve current, A),
pneumatic (valve command, -1..1), presliding-rig (differential valve
command, V), force-rig (external force, N). ``--set NAME=VALUE`` changes a
friction *or* plant parameter (SI units, e.g. ``--set mass=50``); ``--x0
NAME=VALUE`` changes one state of the documented default initial state
(e.g. ``--x0 x=0.05``). The ODE plants run on the engine of
``fcomp.simulation`` (``--method``, ``--rtol``, ``--atol``, ``--max-steps``; ``--coupling`` for
friction with discrete memory, ``nmlgm-hysteresis``); ``--max-steps`` bounds the whole run,
and a long run shows its progress on a terminal. Warnings (one line each, also in the
sidecar's ``warnings``): ``aliasing`` (input content above the Nyquist frequency of
``--rate``), ``command-saturation`` (a command outside the plant's documented range),
``cavitation`` (a hydraulic chamber at its ``p_min`` floor).
``--friction MODEL.json`` takes a model file (docs/model-file.md: ``fcomp fit
--save-model``) instead of a model name; its measurement terms are not plant
friction and are dropped (a ``measurement-terms`` warning says so).
``--plant-params PLANT.toml`` runs the hydraulic or pneumatic plant of a plant
file (docs/plants.md, "Plant files"; ``fcomp plant template``) instead of the
built-in one; a friction model *named* then takes the values of ``--params``
or of the built-in plant of that kind.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from fcomp.cli.common import (
    Progress,
    add_model_options,
    check_outputs,
    current_warnings,
    finite_float,
    friction_model,
    output_path,
    parse_assignments,
    warn,
)
from fcomp.errors import FcompError
from fcomp.inputs import parse_input, sampling_warning
from fcomp.outputs import InputSet


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="simulate a plant with a friction model",
                       description=__doc__)
    p.add_argument("plant", help="plant name: motion, hydraulic, pneumatic, presliding-rig, "
                   "force-rig")
    p.add_argument("--friction", required=True, metavar="NAME|MODEL.json",
                   help="friction model name, or a model file (fcomp fit --save-model)")
    p.add_argument("--params", default=None, help="parameter set name (default: the plant's)")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="a plant file (hydraulic or pneumatic; fcomp plant template) instead "
                   "of the built-in plant's parameters")
    p.add_argument("--input", required=True, metavar="SPEC",
                   help="sine:amplitude=A,frequency=F | step:amplitude=A | csv:PATH")
    p.add_argument("--duration", required=True, type=finite_float, help="simulated time, s")
    p.add_argument("--rate", type=finite_float, default=1000.0, help="output sample rate, Hz")
    p.add_argument("-o", "--output", required=True, metavar="OUT.csv")
    p.add_argument("--x0", action="append", default=[], metavar="STATE=VALUE",
                   help="initial value of one state (SI: pressures absolute, x within the "
                   "stroke); repeatable; default: the plant's documented initial state")
    p.add_argument("--method", default=None,
                   help="integration method: rodas4 (default), radau, bdf, lsoda")
    p.add_argument("--rtol", type=finite_float, default=None,
                   help="relative tolerance (default 1e-6)")
    p.add_argument("--atol", type=finite_float, default=None,
                   help="absolute tolerance in units of each state's scale (default 1e-6)")
    p.add_argument("--max-steps", type=int, default=None, dest="max_steps",
                   help="largest number of integration steps (default 1e7)")
    p.add_argument("--coupling", type=finite_float, default=None, metavar="S",
                   help="longest coupling interval (s) for friction with discrete memory "
                   "(nmlgm-hysteresis; default 1e-4)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress line on a terminal during long runs")
    add_model_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fcomp.modelfile import is_model_file
    from plants import PLANTS
    from plants.base import OdePlant, output_times

    out = output_path(args.output)
    plant_cls = PLANTS.get(args.plant)
    params = args.params if args.params is not None else plant_cls.default_params
    plant_set: Any = params
    if args.plant_params is not None:
        from plants.planfile import read_plant_file

        pf = read_plant_file(args.plant_params)
        if pf.kind != args.plant:
            raise FcompError(f"--plant-params {args.plant_params}: a {pf.kind} plant, not "
                             f"{args.plant}; run `fcomp simulate {pf.kind} ...`")
        plant_set = pf.parameter_set()
    u = parse_input(args.input)
    inputs = InputSet()
    if u.kind == "csv":
        inputs.file(args.input.split(":", 1)[1].strip(), "--input")
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    if is_model_file(args.friction):
        inputs.file(args.friction, "--friction")
    if args.plant_params is not None:
        inputs.file(args.plant_params, "--plant-params")
    check_outputs(inputs, [("-o", out)])
    t = output_times(args.duration, args.rate)
    engine = {k: getattr(args, k) for k in ("method", "rtol", "atol", "max_steps", "coupling")
              if getattr(args, k) is not None}
    assignments = parse_assignments(args.set)
    plant_names: set[str] = set()
    if issubclass(plant_cls, OdePlant):
        plant_names = set(plant_cls.Params.names())
    elif engine:
        raise FcompError(f"--{next(iter(engine)).replace('_', '-')} applies to the ODE plants; "
                         f"plant {args.plant} evaluates the friction along a prescribed motion")
    overrides = {k: v for k, v in assignments.items() if k in plant_names}
    args.set = [f"{k}={v!r}" for k, v in assignments.items() if k not in plant_names]
    model = friction_model(args.friction, params, args)
    plant: Any = (plant_cls(model, plant_set, overrides=overrides)  # type: ignore[call-arg]
                  if overrides else plant_cls(model, plant_set))
    x0 = parse_assignments(args.x0, option="--x0") if args.x0 else None
    _check_x0(plant, x0)
    aliasing = sampling_warning(u, args.rate)
    if aliasing is not None:
        warn(aliasing.code, aliasing.template, "--input")
    if isinstance(plant, OdePlant):
        _command_range(plant, plant.input_samples(u, t))
    with Progress(f"simulate {args.plant}", args.duration, enabled=not args.no_progress):
        result = plant.simulate(u, args.duration, args.rate, x0=x0, **engine)
    _cavitation(plant, result)
    result.meta.setdefault("simulation", {})["input"] = args.input
    ws = current_warnings()
    if ws:
        result.meta["warnings"] = ws
    csv, toml = result.write(out)
    print(f"wrote {csv} and {toml} ({len(result)} samples)")
    return 0


def _check_x0(plant: Any, x0: dict[str, float] | None) -> None:
    """Refuse initial states no plant can start from (a negative absolute pressure, a piston
    outside its stroke)."""
    flat = plant.plant_params.flat() if hasattr(plant, "plant_params") else {}
    for name, value in (x0 or {}).items():
        if name == "x" and "stroke" in flat and not 0.0 <= value <= flat["stroke"]:
            raise FcompError(f"--x0 x={value:g}: the piston of plant {plant.name} moves within "
                             f"its stroke, 0 to {flat['stroke']:g} m")
        if name in ("p1", "p2") and name in getattr(plant, "plant_states", ()) and value < 0:
            raise FcompError(f"--x0 {name}={value:g}: chamber pressures of plant {plant.name} "
                             "are absolute (Pa) and cannot be negative")


def _command_range(plant: Any, U: np.ndarray) -> None:
    """Warn when the command leaves the range the plant documents (the valve saturates)."""
    p = plant.plant_params.flat()
    if plant.name == "pneumatic":
        lim = float(p["u_max"])
        bad = np.abs(U[:, 0]) > lim
        desc = f"the valve command reaches {np.max(np.abs(U[:, 0])):g}, beyond the documented " \
               f"range -{lim:g}..{lim:g} (u_max): the valve saturates fully open"
    elif plant.name == "presliding-rig":
        lim = float(p["u_full"])
        bad = np.any((U < 0.0) | (lim < U), axis=1)
        desc = f"the valve commands u1, u2 leave the range 0..{lim:g} V (u_full): the " \
               "pressure valves saturate"
    elif plant.name == "hydraulic" and float(p["kv"]) > 0:
        lim = SPOOL_STROKE / float(p["kv"])
        bad = np.abs(U[:, 0]) > lim
        desc = f"the valve current reaches {np.max(np.abs(U[:, 0])):g} A, a spool opening " \
               f"kv*|u| of {float(p['kv']) * np.max(np.abs(U[:, 0])) * 1e3:.3g} mm, beyond " \
               f"the {SPOOL_STROKE * 1e3:g} mm stroke of a servo-valve spool (the model has " \
               "no spool stop)"
    else:
        return
    if bad.any():
        warn("command-saturation", f"{desc} in {100 * bad.mean():.3g} % of the samples",
             "--input")


#: A servo-valve spool's stroke (m): beyond it ``kv*u`` has no physical meaning.
SPOOL_STROKE = 1e-3


def _cavitation(plant: Any, result: Any) -> None:
    """Warn when a chamber pressure sat at the hydraulic plant's cavitation floor."""
    flat = getattr(plant, "plant_params", None)
    if flat is None or "p_min" not in flat.flat():
        return
    p_min = float(flat.flat()["p_min"])
    p_atm = float(result.meta.get("p_atm", 101325.0))
    for name in ("p1", "p2"):
        if name not in result:
            continue
        at = result[name] + p_atm <= p_min * (1.0 + 1e-6) + 1e-9
        if at.any():
            t = result.t[at]
            warn("cavitation", f"chamber pressure {name} fell to the cavitation floor "
                 f"p_min = {p_min:g} Pa (absolute) in {int(at.sum())} samples between "
                 f"t = {t[0]:.4g} and {t[-1]:.4g} s: the oil cavitates there and the "
                 "results depend on the floor model", name)
