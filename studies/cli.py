"""The run of ``fcomp study NAME`` (options and help: :mod:`fcomp.cli.study`); importing this
module registers it with the command line (:data:`fcomp.registry.COMMANDS`, entry point
``fcomp.commands``)."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from fcomp.cli import common
from fcomp.errors import FcompError
from fcomp.parallel import check_scheduler
from fcomp.registry import COMMANDS
from studies import STUDIES
from studies.base import STUDY_OPTIONS, StudyConfig, StudyError


def run(args: argparse.Namespace) -> int:
    """Run ``fcomp study NAME``: check the options, run the study, name what it wrote."""
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
    common.check_jobs(args.jobs)
    if args.out is not None and not args.out.strip():
        raise FcompError("--out: no folder name given (an empty argument)")
    out = Path(args.out) if args.out else Path(f"study-{args.name}")
    inputs = common.plant_inputs(args)
    common.check_outputs(inputs, [], [("--out", out, "study")])  # check_folder_target too
    words = ["fcomp", "study", args.name, "--out", str(out)] + (["--fast"] if args.fast else [])
    for key, option in STUDY_OPTIONS.items():
        if given[key] is not None:
            words += [option, given[key]]
    config = StudyConfig(out=out, fast=args.fast, command=shlex.join(words), out_label="--out",
                         scheduler=scheduler, workers=args.jobs,
                         progress=not args.no_progress, plant_file=args.plant_params,
                         friction=args.friction, effects=args.effects)
    for warning in study.check(config):  # bad inputs: one line, before anything is written
        common.warn("measurement-terms", warning, "--friction")
    try:
        results = study.main(config)
    except StudyError as exc:
        sys.stderr.write(f"fcomp: error: {exc}\n")
        return 1
    print("\n".join(_conclusion(results)))
    reports = " and ".join(str(out / f) for f in study.report_files)
    print(f"wrote {out / 'summary.json'}, {reports}")
    return 0


def _conclusion(results: dict) -> list[str]:
    """What the study found, first (its finding as a conclusion); for ``all`` one line per
    study after it: its status in words and what it found."""
    from studies.base import Finding

    meta = results.get("meta") or {}
    lines = (Finding.from_dict(meta["finding"]).conclusion().lines()
             if meta.get("finding") else [])
    for name, run in (results.get("studies") or {}).items():
        found = run.get("finding")
        said = (f"{found['status']} ({found.get('confidence', 'medium')} confidence): "
                f"{found['found']}" if found else f"failed: {run.get('error')}")
        lines.append(f"  {name}: {said}")
    return lines


COMMANDS.register("study", run)
