"""``fcomp compensate --plant-params PLANT.toml --controller-friction BASE.json,DIAG.json
[--friction TRUE.json | --truths T1,T2 --truth-draws N] [--controllers C,...] [--task T |
--reference REF.csv] [--fast|--full] [--samples N] [--json OUT] [--report DIR] [--jobs N]
[--scheduler ADDRESS]`` -- what a better friction model buys in closed loop, under every
friction your plant may have.

On the plant of a plant file (or ``--plant hydraulic|pneumatic``, a built-in
plant), every controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``,
``mpc``; ``--controllers`` a subset) is built once with each model of
``--controller-friction`` (model files, named by their stems; the first is the
baseline) and run on the standard tasks (``slow-sine``, ``steps``,
``low-velocity-ramp``, ``seed002-sine``; ``--task`` one, ``--fast`` their short
versions) or on a reference of your own (``--reference REF.csv``: columns ``t``
(s) and ``x_ref`` (m, absolute position inside the stroke), times increasing).

Which friction the plant runs: without ``--friction``, every run is repeated
under each **candidate truth** -- the compared models themselves, draws from
each model file's standard errors (``--truth-draws``, default 4, 2 with
``--fast``), the rivals a diagnosis wrote into its model file, and the models
of ``--truths`` -- and a model is recommended only where it beats the baseline
under every one of them. ``--friction TRUE`` runs one true friction you know
(a generated record's truth); if it is one of the compared models, the
comparison is circular and a warning says so.

Reported: per truth, controller, model and task the RMS, max, reversal and
hunting errors (on the true position) and the run's status -- ``ok``, or not
ranked: ``skipped`` (a controller that cannot be built on the model, said
before any run), ``failed``, ``flagged`` (never moved, saturated throughout,
a limit cycle, a failed solver); the ratios to the baseline's errors under
each truth (below 1 the model helps) and a short robustness Monte Carlo on one
task (``steps``, or the one given): ``--samples`` draws (default 8, 4 with
``--fast``; 0 none; at most 1000) spread over the truths, every parameter of
the truth and the moving mass off by a factor uniform in 1 +- 0.2
(``--spread``), every controller and model on the same draws. Models run
outside the positions they were fitted on are said in the warnings.
Measurement terms of a model file (force offset, fitted mass, channel lag)
are dropped with a warning. The runs go to local processes (``--jobs``) or
to a Dask cluster (``--scheduler ADDRESS``). A comparison in which every run
failed or was flagged ends with exit status 2 (its result still written).

JSON: ``{"plant", "friction", "mode", "truths", "models", "baseline",
"controllers", "tasks", "runs": [{"truth", "controller", "model", "task",
"status", "rms_error", "max_error", "reversal_error", "hunting",
"steady_state_error", ...}], "ratios": {truth: {controller: {task: {model:
{error: ratio}}}}}, "across_truths", "robustness", "warnings"}`` (errors in m);
``--report DIR`` draws them (docs/your-cylinder.md).
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
    common.add_friction_option(p, required=False,
                               help="the plant's one true friction, if you know it (a model "
                               "file or a model name); default: every candidate truth")
    common.add_option(p, "--controller-friction", "--models", required=True,
                      metavar="M1,M2,...",
                      help="the controllers' friction models, the first the baseline: model "
                      "files (BASE.json,DIAG.json; named by their stems) or model names")
    p.add_argument("--truths", default=None, metavar="T1,T2,...",
                   help="more candidate truths (model files or names), beside the compared "
                   "models, their uncertainty draws and their rivals")
    p.add_argument("--truth-draws", type=int, default=None, metavar="N",
                   help="candidate truths drawn from each model file's standard errors "
                   "(default 4, 2 with --fast; 0: none)")
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
                   help="robustness draws (default 8, 4 with --fast; 0: none; at most "
                   "1000)")
    p.add_argument("--spread", type=finite_float, default=0.2,
                   help="half width of the draws' uniform factors on the true friction and "
                   "the mass (default 0.2: +-20 %%)")
    p.add_argument("--seed", type=int, default=2026, help="seed of the draws and the noise")
    common.add_effects_option(p)
    common.add_closed_loop_run_options(p)
    p.set_defaults(func=provided("compensate"))
