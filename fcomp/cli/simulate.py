"""``fcomp simulate PLANT --friction NAME [--params SET] --input SPEC --duration S
[--rate HZ] -o OUT.csv`` -- writes a measurement (CSV + TOML sidecar)."""

from __future__ import annotations

import argparse

from fcomp.cli.common import add_model_options, build_model, output_path
from fcomp.inputs import parse_input


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="simulate a plant with a friction model",
                       description=__doc__)
    p.add_argument("plant", help="plant name: motion, hydraulic, pneumatic, presliding-rig, "
                   "force-rig")
    p.add_argument("--friction", required=True, help="friction model name")
    p.add_argument("--params", default=None, help="parameter set name (default: the plant's)")
    p.add_argument("--input", required=True, metavar="SPEC",
                   help="sine:amplitude=A,frequency=F | step:amplitude=A | csv:PATH")
    p.add_argument("--duration", required=True, type=float, help="simulated time, s")
    p.add_argument("--rate", type=float, default=1000.0, help="output sample rate, Hz")
    p.add_argument("-o", "--output", required=True, metavar="OUT.csv")
    add_model_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from plants import PLANTS

    out = output_path(args.output)
    plant_cls = PLANTS.get(args.plant)
    params = args.params if args.params is not None else plant_cls.default_params
    model = build_model(args.friction, params, args)
    u = parse_input(args.input)
    plant = plant_cls(model, params)
    result = plant.simulate(u, args.duration, args.rate)
    result.meta.setdefault("simulation", {})["input"] = args.input
    csv, toml = result.write(out)
    print(f"wrote {csv} and {toml} ({len(result)} samples)")
    return 0
