"""``fcomp simulate PLANT --friction NAME [--params SET] --input SPEC --duration S
[--rate HZ] -o OUT.csv`` -- writes a measurement (CSV + TOML sidecar).

Plants: motion (input: velocity, m/s), hydraulic (valve current, A),
pneumatic (valve command, -1..1), presliding-rig (differential valve
command, V), force-rig (external force, N). ``--params`` takes a parameter
set (the plant's and the friction's values), a fit's JSON or a model file (the
friction's values; the plant keeps its own). ``--set NAME=VALUE`` changes a
friction *or* plant parameter (SI units, e.g. ``--set mass=50``); ``--x0
NAME=VALUE`` changes one state of the documented default initial state
(e.g. ``--x0 x=0.05``). The ODE plants run on the engine of
``fcomp.simulation`` (``--method``, ``--rtol``, ``--atol``, ``--max-steps``; ``--coupling`` for
friction with discrete memory, ``nmlgm-hysteresis``); ``--max-steps`` bounds the whole run,
and a long run shows its progress on a terminal. Warnings (one line each, also in the
sidecar's ``warnings``): ``aliasing`` (input content above the Nyquist frequency of
``--rate``), ``command-saturation`` (a command outside the plant's documented range),
``cavitation`` (a hydraulic chamber at its ``p_min`` floor).
``--friction MODEL.json`` takes a model file (docs/model-file.md: ``fcomp fit
--save-model``) instead of a model name; its measurement terms are not plant
friction and are dropped (a ``measurement-terms`` warning says so).
``--plant-params PLANT.toml`` runs the hydraulic or pneumatic plant of a plant
file (docs/plants.md, "Plant files"; ``fcomp plant template``) instead of the
built-in one; a friction model *named* then takes the values of ``--params``
or of the built-in plant of that kind. ``--plant-params SET`` takes the plant's
values from a parameter set. With ``--friction MODEL.json`` the file gives the
friction's values and ``--params`` is refused (as on every command).
"""

from __future__ import annotations

import argparse

from fcomp.cli import common
from fcomp.cli.common import add_model_options, finite_float, provided


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="simulate a plant with a friction model",
                       description=__doc__)
    p.add_argument("plant", help="plant name: motion, hydraulic, pneumatic, presliding-rig, "
                   "force-rig")
    common.add_friction_option(p)
    common.add_params_option(p, "the plant's parameter set; a set gives the plant's values "
                             "too")
    p.add_argument("--plant-params", default=None, metavar="SET|PLANT.toml",
                   help="the plant's values: a parameter set (fcomp list params) or a plant "
                   "file (hydraulic or pneumatic; fcomp plant template) instead of the "
                   "built-in plant's")
    p.add_argument("--input", required=True, metavar="SPEC",
                   help="sine:amplitude=A,frequency=F | step:amplitude=A | csv:PATH")
    p.add_argument("--duration", required=True, type=finite_float, help="simulated time, s")
    p.add_argument("--rate", type=finite_float, default=1000.0, help="output sample rate, Hz")
    p.add_argument("-o", "--output", required=True, metavar="OUT.csv",
                   help="the measurement written (OUT.csv and its sidecar OUT.toml)")
    p.add_argument("--x0", action="append", default=[], metavar="STATE=VALUE",
                   help="initial value of one state (SI: pressures absolute, x within the "
                   "stroke); repeatable; default: the plant's documented initial state")
    p.add_argument("--method", default=None,
                   help="integration method: rodas4 (default), radau, bdf, lsoda")
    p.add_argument("--rtol", type=finite_float, default=None,
                   help="relative tolerance (default 1e-6)")
    p.add_argument("--atol", type=finite_float, default=None,
                   help="absolute tolerance in units of each state's scale (default 1e-6)")
    p.add_argument("--max-steps", type=int, default=None, dest="max_steps",
                   help="largest number of integration steps (default 1e7)")
    p.add_argument("--coupling", type=finite_float, default=None, metavar="S",
                   help="longest coupling interval (s) for friction with discrete memory "
                   "(nmlgm-hysteresis; default 1e-4)")
    common.add_progress_option(p)
    add_model_options(p)
    p.set_defaults(func=provided("simulate"))
