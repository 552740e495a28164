"""``fcomp plant template hydraulic|pneumatic`` and ``fcomp plant check PLANT.toml`` --
your plant as a file.

``template KIND`` prints a commented plant file to start from (the built-in
plant of that kind; docs/plants.md, "Plant files"): the geometry in ``[rig]``
with the keys of a record's sidecar (``bore``, ``rod``, ``stroke``, ``mass``,
``orientation``), then ``[supply]``, ``[valve]`` (with the command and rate
limits), ``[lines]``, ``[fluid]`` or ``[gas]``, ``[sensors]`` and
``[control]``. Redirect it to a file and edit it.

``check FILE`` reads the file (every bad value one ``fcomp: error:`` line,
exit status 2; a valve that passes no flow -- ``kv``, ``cd``, ``w``,
``A_valve`` or the sonic conductance 0 -- is refused the same way) and prints
what an engineer checks first: the natural frequency and damping of the oil
(air) column at mid stroke from python-control's linearisation of the plant,
beside the hand formula; the valve-limited speed in both directions; the force
range the pressures allow and the weight; the valve bandwidth against the
control rate; the compensators' default tuning; and the **margins of the loop
as it runs** (``controllers.loop_analysis``: the sampled plant with its valve,
chambers and load linearised where it holds the load, the zero-order hold, the
computation delay of ``[control] delay``, the controller as coded) broken at
the valve command and at the position sensor, over the stroke, the parameter
box of ``[uncertainty]`` and the friction regimes: at mid stroke and at the
worst point, and each force-based controller's. ``--json OUT`` writes
``{"kind", "name", "natural_frequency", "natural_frequency_hz", "damping",
"hand_formula", "equilibrium", "valve_limited_speed", "force_range", "weight",
"valve_bandwidth_hz", "control_rate", "tuning", "margins", "uncertainty",
"warnings"}`` (SI units: rad/s, Hz, m/s, N, Pa). ``tuning`` is the
compensators' default tuning derived from the plant (``controllers.tuning``,
with the ``nmlgm`` friction of the plant kind's parameter set); explicit
``[control]`` values win and are checked -- a tuning that misses GM >= 2, PM
>= 30 deg, Ms <= 2 anywhere on the grid is refused (exit 2, one line naming the
worst point). ``margins`` has ``gain``, ``phase_deg`` (the smallest over the
grid), ``ms`` (the largest), ``worst`` (``position``, ``fraction``,
``parameters``, ``friction``, ``break`` and its margins), ``mid``,
``requirement``, ``meets``, ``grid`` (every point) and ``controllers``.
``--report DIR`` writes ``DIR/report.html``.
"""

from __future__ import annotations

import argparse

from fcomp.cli.common import provided


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plant", help="your plant as a file: print a template, check a file",
                       description=__doc__)
    actions = p.add_subparsers(dest="action", metavar="ACTION", parser_class=type(p))
    actions.required = True
    t = actions.add_parser("template", help="print a commented plant file to start from")
    t.add_argument("kind", choices=["hydraulic", "pneumatic"], help="the servo's kind")
    t.set_defaults(func=provided("plant template"))
    c = actions.add_parser("check", help="natural frequency, damping, valve-limited speed, "
                           "force range and the margins of the loop as it runs")
    c.add_argument("file", metavar="PLANT.toml", help="the plant file")
    c.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    c.add_argument("--report", metavar="DIR", default=None,
                   help="write an HTML report to DIR (Bode and Nyquist plots of the loop as it "
                        "runs, the margin map over the stroke and the grid)")
    c.set_defaults(func=provided("plant check"))
