"""The run of ``fcomp simulate`` (options and help: :mod:`fcomp.cli.simulate`): a plant with a
friction model, written as a measurement, with the warnings of the run."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from fcomp.cli.common import (
    Progress,
    check_outputs,
    friction_model,
    output_path,
    parse_assignments,
    refuse_params_with_model_file,
    warn,
    warn_fitted_range,
    write_measurement,
)
from fcomp.errors import FcompError
from fcomp.inputs import parse_input, sampling_warning
from fcomp.modelfile import check_range, is_model_file
from fcomp.outputs import InputSet
from plants import PLANTS
from plants.base import OdePlant, output_times
from plants.planfile import read_plant_file


def run(args: argparse.Namespace) -> int:
    """Run ``fcomp simulate`` (:mod:`fcomp.cli.simulate`): write the run as a measurement."""
    out = output_path(args.output)
    refuse_params_with_model_file(args.friction, args.params, plant_option=True)
    plant_cls = PLANTS.get(args.plant)
    values_file = args.params is not None and is_model_file(args.params)
    params = args.params if args.params is not None and not values_file \
        else plant_cls.default_params
    plant_set: Any = params
    plant_file = args.plant_params is not None and args.plant_params.lower().endswith(".toml")
    if plant_file:
        pf = read_plant_file(args.plant_params)
        if pf.kind != args.plant:
            raise FcompError(f"--plant-params {args.plant_params}: a {pf.kind} plant, not "
                             f"{args.plant}; run `fcomp simulate {pf.kind} ...`")
        plant_set = pf.parameter_set()
    elif args.plant_params is not None:
        plant_set = args.plant_params  # a parameter set: the plant's values
    u = parse_input(args.input)
    inputs = InputSet()
    if u.kind == "csv":
        inputs.file(args.input.split(":", 1)[1].strip(), "--input")
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    for option, spec in (("--friction", args.friction), ("--params", args.params)):
        if spec is not None and is_model_file(spec):
            inputs.file(spec, option)
    if plant_file:
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
    model = friction_model(args.friction, args.params if values_file else params, args)
    plant: Any = (plant_cls(model, plant_set, overrides=overrides)  # type: ignore[call-arg]
                  if overrides else plant_cls(model, plant_set))
    x0 = parse_assignments(args.x0, option="--x0") if args.x0 else None
    _check_x0(plant, x0)
    label = args.friction if is_model_file(args.friction) else (
        args.params if values_file else model.describe())
    start = (x0 or {}).get("x", plant.default_state().get("x")) \
        if isinstance(plant, OdePlant) else None
    check_range(model, x=None if start is None else [start], label=label)  # meaningless there?
    aliasing = sampling_warning(u, args.rate)
    if aliasing is not None:
        warn(aliasing.code, aliasing.template, "--input")
    if isinstance(plant, OdePlant):
        _command_range(plant, plant.input_samples(u, t))
    with Progress(f"simulate {args.plant}", args.duration, enabled=not args.no_progress):
        result = plant.simulate(u, args.duration, args.rate, x0=x0, **engine)
    _cavitation(plant, result)
    p = [result[n] for n in ("p1", "p2") if n in result]
    warn_fitted_range(model, label, "--friction", x=result.get("x"), v=result.get("v"),
                      p=np.concatenate(p) if p else None)
    result.meta.setdefault("simulation", {})["input"] = args.input
    csv, toml = write_measurement(result, out)
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
