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
import sys
from typing import Any

from fcomp.cli import common
from fcomp.cli.common import emit_result, json_target, result_text


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plant", help="your plant as a file: print a template, check a file",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    actions = p.add_subparsers(dest="action", metavar="ACTION", parser_class=type(p))
    actions.required = True
    t = actions.add_parser("template", help="print a commented plant file to start from")
    t.add_argument("kind", choices=["hydraulic", "pneumatic"], help="the servo's kind")
    t.set_defaults(func=run_template)
    c = actions.add_parser("check", help="natural frequency, damping, valve-limited speed and "
                           "force range of a plant file")
    c.add_argument("file", metavar="PLANT.toml", help="the plant file")
    c.add_argument("--json", metavar="OUT", default=None,
                   help="write the result as JSON to OUT ('-' for standard output)")
    c.set_defaults(func=run_check)


def run_template(args: argparse.Namespace) -> int:
    from plants.planfile import template

    sys.stdout.write(template(args.kind))
    return 0


def summary(doc: dict[str, Any]) -> str:
    """The printed figures of a plant check."""
    eq, sp, fr = doc["equilibrium"], doc["valve_limited_speed"], doc["force_range"]
    fluid = "oil" if doc["kind"] == "hydraulic" else "air"
    return "\n".join([
        f"{doc['kind']} plant {doc['name']} ({doc['file']})",
        f"natural frequency at mid stroke ({fluid} column, linearised): "
        f"{doc['natural_frequency']:.4g} rad/s ({doc['natural_frequency_hz']:.4g} Hz); hand "
        f"formula {doc['hand_formula']:.4g} rad/s",
        f"damping ratio: {doc['damping']:.3g}",
        f"  at rest holding the load: u = {eq['u']:.4g}, p1 = {eq['p1'] / 1e5:.4g} bar, "
        f"p2 = {eq['p2'] / 1e5:.4g} bar (absolute), V1 = {eq['V1'] * 1e6:.4g} cm^3, "
        f"V2 = {eq['V2'] * 1e6:.4g} cm^3",
        f"valve-limited speed: extending {sp['extend']:.4g} m/s, retracting "
        f"{-sp['retract']:.4g} m/s",
        f"force range: {fr['min']:.5g} to {fr['max']:.5g} N (weight {doc['weight']:.4g} N)",
        f"valve bandwidth {doc['valve_bandwidth_hz']:.4g} Hz; control rate "
        f"{doc['control_rate']:.4g} Hz",
        *doc["tuning_lines"],
    ])


def run_check(args: argparse.Namespace) -> int:
    from fcomp.outputs import InputSet
    from plants.check import check_plant
    from plants.planfile import PlantFileError, read_plant_file

    out = json_target(args.json)
    inputs = InputSet()
    inputs.file(args.file, "PLANT.toml")
    common.check_outputs(inputs, [("--json", out)])
    try:
        pf = read_plant_file(args.file)
    except PlantFileError as exc:
        for line in exc.problems:  # one line per bad value
            sys.stderr.write(f"fcomp: error: {line}\n")
        return 2
    doc = check_plant(pf)
    tuning = plant_tuning(pf)  # FcompError (one line, exit 2): explicit values without margins
    doc["tuning"] = tuning.as_dict()
    doc["tuning_lines"] = tuning.lines()
    doc = common.with_warnings(doc)
    text = {k: v for k, v in doc.items() if k != "tuning_lines"}
    emit_result(result_text(text), args.json, out, summary(doc))
    return 0


def plant_tuning(pf: Any) -> Any:
    """The compensators' default tuning on a plant file (:mod:`controllers.tuning`), with the
    controllers' friction model the ``nmlgm`` of the plant kind's parameter set (its viscous
    slope and bristle damping enter the rules)."""
    from controllers.plant_model import ControlModel
    from fcomp.models import make_model

    return ControlModel(pf, make_model("nmlgm", params=pf.friction_set)).tuning
