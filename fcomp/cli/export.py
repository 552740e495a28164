"""``fcomp export CONTROLLER --plant hydraulic|pneumatic [--params SET|FIT.json|MODEL.json]
[--friction NAME|MODEL.json]
-o DIR [--json OUT]`` -- a controller's step as C code for a real-time target.

The controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``, ``mpc``) built on the
plant with the friction model (``--friction`` with ``--params``,
``--add-effect``, ``--set``, as ``simulate`` takes them), behind its fail-safe
layer (inputs validated, a safe output latched after repeated faults, recovery,
the valve's range and rate limit), becomes one CasADi
function ``step(state, y, ref) -> (u, state_next)``, generated as C behind a
plain interface (``fcomp_ctrl.h``: ``fcomp_ctrl_init``, ``fcomp_ctrl_step``,
``fcomp_ctrl_step_ref``, ``fcomp_ctrl_fault``; fixed memory, nothing allocated)
with a ``Makefile`` and ``example.c``, written to DIR. With a C compiler
(``$FCOMP_CC``, else ``$CC``, cc, gcc, clang) fcomp builds it, runs it in closed
loop against the Python plant on ``--task`` for ``--duration`` s, checks that its
commands equal the Python controller's at every sample (relative 1e-9), again on
hostile input (NaN, inf, 1e300, out-of-stroke readings, a sensor dropout), and
times ``--timing-steps`` compiled steps in a C loop (the CPU time of the step, and
the wall clock). No compiler, or one that fails: the code is still written,
``equivalent`` is null and a warning says why (exit 0).

JSON: ``{"controller", "plant", "friction", "files", "equivalent", "max_rel_diff",
"step_time_median", "step_time_max" (CPU time), "step_time_wall_max", "rate",
"plant_rate", "fail_safe", "fault_check", ...,"warnings"}`` (times in s). ``mpc`` is exported
in its fixed-iteration form (``controllers.mpc_fixed``: the QP by 30 ADMM iterations
instead of DAQP, which cannot be generated as C), checked against that form in Python.
"""

from __future__ import annotations

import argparse

from fcomp.cli import common
from fcomp.cli.common import add_model_options, finite_float, provided


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="a controller's step as C code (CasADi), compiled, "
                       "checked against the Python controller and timed",
                       description=__doc__)
    p.add_argument("controller", help="pid, pid-ff, lugre-observer, ekf or mpc (its "
                   "fixed-iteration form)")
    p.add_argument("--plant", default=None, help="hydraulic (default) or pneumatic; with "
                   "--plant-params, its kind")
    p.add_argument("--plant-params", default=None, metavar="PLANT.toml",
                   help="the plant as a file (docs/plants.md: fcomp plant template)")
    common.add_params_option(p, "the plant's parameter set; a set gives the plant's values "
                             "too")
    common.add_friction_option(p, required=False, default="nmlgm",
                               help="the controller's friction model: a name or a model file "
                               "(default nmlgm)")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="folder for the C files (replaced whole; fcomp's own or new)")
    p.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    p.add_argument("--task", default="seed002-sine",
                   help="closed-loop task of the check (default seed002-sine)")
    p.add_argument("--duration", type=finite_float, default=0.6,
                   help="length of the closed-loop check, s (default 0.6)")
    p.add_argument("--timing-steps", type=int, default=100_000, metavar="N",
                   help="compiled steps timed, 100000 (the default) to 5000000")
    p.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                   help="a controller option (observer_gain=30, bandwidth=50, ...); repeatable")
    add_model_options(p)
    common.add_progress_option(p)
    p.set_defaults(func=provided("export"))
