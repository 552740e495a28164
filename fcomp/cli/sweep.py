"""``fcomp sweep [--plant P] [--task T] [--controllers C,...] [--samples N | --grid
PARAM=F1,F2,...] [--fast|--full] [--json OUT] [--report DIR] [--jobs N]
[--scheduler ADDRESS]`` -- Monte Carlo and
parameter grids over compensators and friction-model mismatch.

Every controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``, ``mpc``) runs
the task (``slow-sine``, ``steps``, ``low-velocity-ramp``, ``seed002-sine``) on
the plant (``hydraulic``, ``pneumatic``) in closed loop, the plant integrating
its true friction (``--friction``, default ``nmlgm``) while the controllers
know another:

* **Monte Carlo** (default): ``--samples`` draws; in each, every friction
  parameter of the controllers' model is multiplied by ``exp(N(0, spread^2))``
  and the sensor noise by a factor uniform in ``--noise LO,HI``; every
  controller sees the same draws;
* **grid** (``--grid PARAM=F1,F2,...``, repeatable, and/or
  ``--controller-friction A,B,...``): every combination of the factors on the
  controllers' model parameters and of the friction models the controllers
  are built with (friction-model mismatch).

``--plant-params PLANT.toml`` runs the loops on the plant of a plant file
(docs/plants.md, "Plant files": its parameters, sensors, valve limits and
control rate); ``--friction`` and ``--controller-friction`` also take model
files (``MODEL.json``, docs/model-file.md; their measurement terms are dropped
with a warning). A friction model *named* takes the values of the built-in
plant of the plant's kind.

The runs are independent jobs: local processes by default (``--jobs``),
or the Dask distributed cluster at ``--scheduler ADDRESS``; the results are
the same. JSON: ``{"mode", "plant", "task", "controllers", "runs": [{"controller",
"sample", "mismatch", "noise", "controller_friction", "status", "metrics"}, ...],
"distributions" (Monte Carlo) | "points" (grid), "warnings"}`` (errors in m,
times in s); ``--report DIR`` draws them.
"""

from __future__ import annotations

import argparse

from fcomp.cli import common
from fcomp.cli.common import finite_float, provided


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep", help="Monte Carlo and parameter grids over compensators and "
                       "friction-model mismatch (local processes or a Dask cluster)",
                       description=__doc__)
    p.add_argument("--plant", default=None,
                   help="hydraulic (default) or pneumatic; with --plant-params, its kind")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="a plant file (fcomp plant template) instead of the built-in plant")
    p.add_argument("--task", default="low-velocity-ramp",
                   help="slow-sine, steps, low-velocity-ramp (default), seed002-sine")
    p.add_argument("--controllers", default="pid,pid-ff,lugre-observer,ekf,mpc",
                   metavar="C1,C2,...", help="controllers to run (default: all five)")
    p.add_argument("--samples", type=int, default=20, metavar="N",
                   help="Monte Carlo draws (default 20, at most 10000)")
    p.add_argument("--spread", type=finite_float, default=0.3,
                   help="log-normal spread of the mismatch factors (default 0.3)")
    p.add_argument("--noise", default="0.5,3", metavar="LO,HI",
                   help="range of the sensor-noise factor (default 0.5,3)")
    p.add_argument("--grid", action="append", default=[], metavar="PARAM=F1,F2,...",
                   help="a grid instead of Monte Carlo: factors on one friction parameter of "
                   "the controllers' model (Fc, Fs, vs, sigma0, sigma1, sigma2, ...); repeatable")
    p.add_argument("--controller-friction", default=None, metavar="M1,M2,...",
                   help="grid over the friction models the controllers are built with "
                   "(e.g. lugre,nmlgm; friction-model mismatch)")
    common.add_friction_option(p, required=False, default="nmlgm",
                               help="the plant's true friction model: a name or a model file "
                               "(default nmlgm)")
    common.add_effects_option(p)
    p.add_argument("--seed", type=int, default=2026, help="seed of the draws and the noise")
    common.add_length_options(p, "fast", fast="the tasks' short durations",
                              full="full task durations")
    common.add_closed_loop_run_options(p)
    p.set_defaults(func=provided("sweep"))
