"""``fcomp plant template hydraulic|pneumatic`` and ``fcomp plant check PLANT.toml`` --
your plant as a file.

``template KIND`` prints a commented plant file to start from (the built-in
plant of that kind; docs/plants.md, "Plant files"): the geometry in ``[rig]``
with the keys of a record's sidecar (``bore``, ``rod``, ``stroke``, ``mass``,
``orientation``), then ``[supply]``, ``[valve]`` (with the command and rate
limits), ``[lines]``, ``[fluid]`` or ``[gas]``, ``[sensors]`` and
``[control]``. Redirect it to a file and edit it.

``check FILE`` reads the file (every bad value one ``fcomp: error:`` line,
exit status 2) and prints what an engineer checks first: the natural
frequency and damping of the oil (air) column at mid stroke from
python-control's linearisation of the plant, beside the hand formula; the
valve-limited speed in both directions; the force range the pressures allow
and the weight; the valve bandwidth against the control rate; the compensators'
default tuning with its gain and phase margins. ``--json OUT``
writes ``{"kind", "name", "natural_frequency", "natural_frequency_hz",
"damping", "hand_formula", "equilibrium", "valve_limited_speed",
"force_range", "weight", "valve_bandwidth_hz", "control_rate", "tuning", "warnings"}``
(SI units: rad/s, Hz, m/s, N, Pa). ``tuning`` is the compensators' default
tuning derived from the plant (``controllers.tuning``, with the ``nmlgm``
friction of the plant kind's parameter set): force-loop and PID bandwidths,
derivative filter, observer gain, MPC horizon and weight, and the gain and
phase margins python-control computes for the loops; explicit ``[control]``
values win and are checked -- one without margins is refused (exit 2).
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
    c = actions.add_parser("check", help="natural frequency, damping, valve-limited speed and "
                           "force range of a plant file")
    c.add_argument("file", metavar="PLANT.toml", help="the plant file")
    c.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    c.set_defaults(func=provided("plant check"))
