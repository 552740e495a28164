"""``fcomp study NAME [--out DIR] [--fast] [--scheduler ADDRESS]`` -- run a study; writes
DIR/summary.json, figures and DIR/report.html (``all``: every study in DIR/NAME/ and
DIR/index.html). ``--scheduler`` sends the study's independent jobs (the closed-loop runs
of ``compensators``, the candidate refits of ``missing-physics``) to a Dask cluster; the
results are those of a local run."""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path


def add_parser(sub: argparse._SubParsersAction) -> None:
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
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from fcomp.errors import FcompError
    from fcomp.outputs import check_folder_target
    from fcomp.parallel import check_scheduler
    from studies import STUDIES
    from studies.base import StudyConfig, StudyError

    study = STUDIES.get(args.name)
    scheduler = check_scheduler(args.scheduler)
    if args.workers is not None and args.workers < 1:
        raise FcompError(f"--workers must be a positive integer, got {args.workers}")
    if args.out is not None and not args.out.strip():
        raise FcompError("--out: no folder name given (an empty argument)")
    out = Path(args.out) if args.out else Path(f"study-{args.name}")
    check_folder_target("--out", out, "study")
    words = ["fcomp", "study", args.name, "--out", str(out)] + (["--fast"] if args.fast else [])
    config = StudyConfig(out=out, fast=args.fast, command=shlex.join(words), out_label="--out",
                         scheduler=scheduler, workers=args.workers,
                         progress=not args.no_progress)
    try:
        study.main(config)
    except StudyError as exc:
        sys.stderr.write(f"fcomp: error: {exc}\n")
        return 1
    reports = " and ".join(str(out / f) for f in study.report_files)
    print(f"wrote {out / 'summary.json'}, {reports}")
    return 0
