"""``fcomp demo [--out DIR]`` -- simulate and plot every friction model along one motion."""

from __future__ import annotations

import argparse

from fcomp.cli.common import Activity, add_progress_option


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="simulate and plot every friction model", description=__doc__)
    p.add_argument("--out", default="demo", help="output directory (default: demo)")
    p.add_argument("--params", default="seed000-cylinder1", metavar="SET",
                   help="parameter set of every model (default seed000-cylinder1; a fit's JSON "
                   "or a model file holds the values of one model, and the demo runs them all)")
    add_progress_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    import fcomp.paramsets as paramsets
    from fcomp.demo import run_demo
    from fcomp.errors import FcompError
    from fcomp.outputs import staged_folder

    if not args.out.strip():
        raise FcompError("--out: no folder name given (an empty argument)")
    if args.params.lower().endswith(".json"):
        raise FcompError(f"--params {args.params}: the demo runs every model, so it takes a "
                         "parameter set (fcomp list params); a fit's JSON or a model file is "
                         "one model: fcomp simulate --friction NAME --params FILE.json")
    paramsets.get(args.params)  # an unknown set is refused before anything is written
    out = Path(args.out)
    with staged_folder(out, "--out", "demo", note="fcomp demo") as staging, \
            Activity("demo", enabled=not args.no_progress):
        files = run_demo(staging, params=args.params)
    print(f"wrote {len(files) - 1} measurements (CSV + TOML) and the figure "
          f"{out / files[-1].name} to {out}/")
    return 0
