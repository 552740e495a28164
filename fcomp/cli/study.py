"""``fcomp study NAME [--out DIR] [--fast] [--scheduler ADDRESS]`` -- run a study; writes
DIR/summary.json, figures and DIR/report.html (``all``: every study in DIR/NAME/ and
DIR/index.html). ``--scheduler`` sends the study's independent jobs (the closed-loop runs
of ``compensators``, the candidate refits of ``missing-physics``) to a Dask cluster; the
results are those of a local run.

``compensators`` also takes ``--plant-params PLANT.toml`` (the whole comparison on
the plant of a plant file, docs/plants.md, instead of the two built-in plants; the
results name it by the file's ``name``) and ``--friction NAME|MODEL.json`` (the
simulated plant's friction, default nmlgm of the plant's parameter set; the
controllers are built with the same model times the study's mismatch factors), and
``--effects MODULE.py`` (the user's effects a model file of ``--friction`` names, as
``simulate``, ``sweep`` and ``compensate`` take it). Other studies refuse them."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path


def add_parser(sub: argparse._SubParsersAction) -> None:
    from fcomp.cli import common

    p = sub.add_parser("study", help="run a study and write its report", description=__doc__)
    p.add_argument("name", help="study name: coulomb-viscous, friction-models, presliding, "
                   "compensators, missing-physics, all (`fcomp list studies` shows those "
                   "available)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default: study-NAME in the current directory)")
    p.add_argument("--fast", action="store_true",
                   help="fast mode: shorter runs, as in CI")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the independent jobs (closed-loop runs, candidate refits) on the "
                   "Dask distributed scheduler at ADDRESS (tcp://host:8786); default: local "
                   "processes")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="local worker processes (default: the study's choice)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars on stderr")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="compensators: run on the plant of a plant file (fcomp plant template) "
                   "instead of the built-in hydraulic and pneumatic plants")
    p.add_argument("--friction", default=None, metavar="NAME|MODEL.json",
                   help="compensators: the plant's true friction, a model name or a model file "
                   "(default nmlgm); the controllers get the same model with the study's "
                   "mismatch")
    common.add_effects_option(p, "registers the user's own effects a --friction model file "
                              "names (compensators)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fcomp.cli import common
    from fcomp.errors import FcompError
    from fcomp.outputs import InputSet
    from fcomp.parallel import check_scheduler
    from studies import STUDIES
    from studies.base import STUDY_OPTIONS, StudyConfig, StudyError

    study = STUDIES.get(args.name)
    given = {"plant_file": args.plant_params, "friction": args.friction,
             "effects": args.effects}
    for key, option in STUDY_OPTIONS.items():
        value = given[key]
        if value is None:
            continue
        if key not in study.options:
            takers = [n for n in STUDIES.names() if key in STUDIES.get(n).options]
            raise FcompError(f"{option} applies to the {' and '.join(takers)} study")
        if not value.strip():
            raise FcompError(f"{option}: no value given (an empty argument)")
    if args.plant_params is not None and not args.plant_params.lower().endswith(".toml"):
        raise FcompError(f"--plant-params {args.plant_params}: a plant file ends in .toml")
    scheduler = check_scheduler(args.scheduler)
    if args.workers is not None and args.workers < 1:
        raise FcompError(f"--workers must be a positive integer, got {args.workers}")
    if args.out is not None and not args.out.strip():
        raise FcompError("--out: no folder name given (an empty argument)")
    out = Path(args.out) if args.out else Path(f"study-{args.name}")
    inputs = InputSet()
    for option, spec in (("--plant-params", args.plant_params), ("--friction", args.friction)):
        if spec is not None and spec.lower().endswith((".toml", ".json")):
            inputs.file(spec, option)
    if args.effects is not None:
        inputs.file(args.effects, "--effects")
    common.check_outputs(inputs, [], [("--out", out, "study")])  # check_folder_target too
    words = ["fcomp", "study", args.name, "--out", str(out)] + (["--fast"] if args.fast else [])
    for key, option in STUDY_OPTIONS.items():
        if given[key] is not None:
            words += [option, given[key]]
    config = StudyConfig(out=out, fast=args.fast, command=shlex.join(words), out_label="--out",
                         scheduler=scheduler, workers=args.workers,
                         progress=not args.no_progress, plant_file=args.plant_params,
                         friction=args.friction, effects=args.effects)
    for warning in study.check(config):  # bad inputs: one line, before anything is written
        common.warn("measurement-terms", warning, "--friction")
    try:
        study.main(config)
    except StudyError as exc:
        sys.stderr.write(f"fcomp: error: {exc}\n")
        return 1
    reports = " and ".join(str(out / f) for f in study.report_files)
    print(f"wrote {out / 'summary.json'}, {reports}")
    return 0
