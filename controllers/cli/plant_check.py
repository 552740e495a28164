"""The run of ``fcomp plant check PLANT.toml`` (options and help: :mod:`fcomp.cli.plant`): the
plant file's figures with the compensators' default tuning, hence here, above the plants."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from controllers.plant_model import ControlModel
from fcomp.cli import common
from fcomp.cli.common import emit_result, json_target, result_text
from fcomp.errors import FcompError
from fcomp.models import make_model
from fcomp.outputs import InputSet
from plants.check import check_plant
from plants.planfile import PlantFileError, read_plant_file


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
    """Check a plant file and print (or write as JSON) what an engineer checks first."""
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
    try:
        doc = check_plant(pf)
        tuning = plant_tuning(pf)  # FcompError (one line, exit 2): explicit values without margins
    except FcompError as exc:  # the figures of a plant that cannot be run: the file named
        raise FcompError(str(exc) if pf.label in str(exc) else f"{pf.label}: {exc}") from None
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
    return ControlModel(pf, make_model("nmlgm", params=pf.friction_set)).tuning
