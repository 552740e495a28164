"""``fcomp study NAME [--out DIR] [--fast|--full] [--jobs N] [--scheduler ADDRESS]`` -- run a study; writes
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

from fcomp.cli import common
from fcomp.cli.common import provided


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("study", help="run a study and write its report", description=__doc__)
    p.add_argument("name", help="study name: coulomb-viscous, friction-models, presliding, "
                   "compensators, missing-physics, all (`fcomp list studies` shows those "
                   "available)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="output directory (default: study-NAME in the current directory)")
    common.add_length_options(p, "full", fast="shorter runs, as in CI",
                              full="the study's full runs")
    common.add_parallel_options(p, "--workers", what="the study's independent jobs (closed-loop "
                                "runs, candidate refits)", default="the study's choice")
    common.add_progress_option(p)
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="compensators: run on the plant of a plant file (fcomp plant template) "
                   "instead of the built-in hydraulic and pneumatic plants")
    common.add_friction_option(p, required=False,
                               help="compensators: the plant's true friction, a model name or "
                               "a model file (default nmlgm); the controllers get the same "
                               "model with the study's mismatch")
    common.add_effects_option(p, "registers the user's own effects a --friction model file "
                              "names (compensators)")
    p.set_defaults(func=provided("study"))
