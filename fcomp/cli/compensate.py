"""``fcomp compensate --plant-params PLANT.toml --friction TRUE.json --controller-friction
BASE.json,DIAG.json [--controllers C,...] [--task T | --reference REF.csv] [--fast|--full]
[--samples N] [--json OUT] [--report DIR] [--jobs N] [--scheduler ADDRESS]`` -- what a better
friction model buys in closed loop.

On the plant of a plant file (or ``--plant hydraulic|pneumatic``, a built-in
plant) whose simulated friction is ``--friction`` (a model file, or a model
name), every controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``,
``mpc``; ``--controllers`` a subset) is built once with each model of
``--controller-friction`` (model files, named by their stems; the first is the baseline)
and run on the standard tasks (``slow-sine``, ``steps``, ``low-velocity-ramp``,
``seed002-sine``; ``--task`` one, ``--fast`` their short versions) or on a
reference of your own (``--reference REF.csv``: columns ``t`` (s) and
``x_ref`` (m, absolute position inside the stroke), times increasing).

Reported: per controller, model and task the RMS, max, reversal and hunting
errors (on the true position), their ratios to the baseline's (below 1 the
model helps), and a short robustness Monte Carlo on one task (``steps``, or
the one given): ``--samples`` draws (default 8, 4 with ``--fast``; 0 none)
in which every parameter of the true friction and the moving mass are off by
a factor uniform in 1 +- 0.2 (``--spread``), every controller and model on the
same draws.
Measurement terms of a model file (force offset, fitted mass, channel lag)
are dropped with a warning. The runs go to local processes (``--jobs``)
or to a Dask cluster (``--scheduler ADDRESS``).

JSON: ``{"plant", "friction", "models", "baseline", "controllers", "tasks",
"runs": [{"controller", "model", "task", "status", "rms_error", "max_error",
"reversal_error", "hunting", "steady_state_error", ...}], "ratios":
{controller: {task: {model: {error: ratio}}}}, "robustness", "warnings"}``
(errors in m); ``--report DIR`` draws them (docs/your-cylinder.md).
"""

from __future__ import annotations

import argparse

from fcomp.cli import common
from fcomp.cli.common import finite_float, provided


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("compensate", help="every compensator built with each friction model "
                       "(baseline vs diagnosed) on your plant: what the better model buys",
                       description=__doc__)
    p.add_argument("--plant", default=None,
                   help="hydraulic or pneumatic: a built-in plant; with --plant-params, its kind")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="the plant as a file (docs/plants.md: fcomp plant template)")
    common.add_friction_option(p, help="the plant's simulated (true) friction: a model file "
                               "or a model name")
    common.add_option(p, "--controller-friction", "--models", required=True,
                      metavar="M1,M2,...",
                      help="the controllers' friction models, the first the baseline: model "
                      "files (BASE.json,DIAG.json; named by their stems) or model names")
    p.add_argument("--controllers", default=None, metavar="C1,C2,...",
                   help="controllers to run (default: pid,pid-ff,lugre-observer,ekf,mpc)")
    p.add_argument("--task", default=None,
                   help="one standard task (default: slow-sine, steps, low-velocity-ramp, "
                   "seed002-sine)")
    p.add_argument("--reference", default=None, metavar="REF.csv",
                   help="your own reference instead: a CSV with columns t (s), x_ref (m)")
    common.add_length_options(p, "full", fast="the short versions of the tasks",
                              full="the tasks' full versions")
    p.add_argument("--samples", type=int, default=None, metavar="N",
                   help="robustness draws (default 8, 4 with --fast; 0: none; at most 10000)")
    p.add_argument("--spread", type=finite_float, default=0.2,
                   help="half width of the draws' uniform factors on the true friction and "
                   "the mass (default 0.2: +-20 %%)")
    p.add_argument("--seed", type=int, default=2026, help="seed of the draws and the noise")
    common.add_effects_option(p)
    common.add_closed_loop_run_options(p)
    p.set_defaults(func=provided("compensate"))
