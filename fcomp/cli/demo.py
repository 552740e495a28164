"""``fcomp demo [--out DIR]`` -- simulate and plot every friction model along one motion."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="simulate and plot every friction model", description=__doc__)
    p.add_argument("--out", default="demo", help="output directory (default: demo)")
    p.add_argument("--params", default="seed000-cylinder1", help="parameter set")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fcomp.demo import run_demo

    files = run_demo(args.out, params=args.params)
    print(f"wrote {len(files)} files to {args.out}/ (figure: {files[-1]})")
    return 0
