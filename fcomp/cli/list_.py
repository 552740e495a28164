"""``fcomp list [WHAT]`` -- the registered names (models, effects, plants, params, ...)."""

from __future__ import annotations

import argparse


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("list", help="list registered names", description=__doc__)
    p.add_argument("what", nargs="?", default="all",
                   choices=["all", "models", "effects", "plants", "params", "controllers",
                            "studies"])
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import fcomp.paramsets as paramsets
    from fcomp.effects import EFFECTS
    from fcomp.models import MODELS
    from fcomp.registry import CONTROLLERS, PLANTS, STUDIES

    groups = {
        "models": MODELS.names(),
        "effects": [f"{n}: {EFFECTS.get(n).signature}" for n in EFFECTS.names()],
        "plants": PLANTS.names(),
        "params": [f"{n}: {paramsets.SOURCES.get(n, '')}" for n in paramsets.names()],
    }
    for name, registry in (("controllers", CONTROLLERS), ("studies", STUDIES)):
        if registry.names():  # none: a build without that package
            groups[name] = registry.names()
    for name, items in groups.items():
        if args.what in ("all", name):
            print(f"{name}:")
            for item in items:
                print(f"  {item}")
    return 0
