"""The run of ``fcomp plant check PLANT.toml`` (options and help: :mod:`fcomp.cli.plant`): the
plant file's figures, the compensators' default tuning and the margins of the loop as it runs
(:mod:`controllers.loop_analysis`), hence here, above the plants."""

from __future__ import annotations

import argparse
import shlex
import sys
from typing import Any

from controllers.plant_model import ControlModel
from fcomp.cli import common
from fcomp.cli.common import emit_result, json_target, report_dir, result_text
from fcomp.errors import FcompError
from fcomp.models import make_model
from fcomp.outputs import InputSet
from plants.check import check_plant
from plants.planfile import PlantFileError, read_plant_file


def margin_lines(doc: dict[str, Any], tuning_doc: dict[str, Any]) -> list[str]:
    """The printed margins of a plant check: the loop's, at mid stroke and its worst point,
    and each controller's worst."""
    m = doc
    req = m["requirement"]

    def fig(d: dict[str, Any]) -> str:
        if not d.get("stable", True):
            return f"unstable: a {d['mode_hz']:.3g} Hz mode growing {d['growth']:.3g}/s"
        gm = "inf" if d["gain"] is None else f"{d['gain']:.3g}"
        pm = "inf" if d["phase_deg"] is None else f"{d['phase_deg']:.1f} deg"
        ms = "inf" if d["ms"] is None else f"{d['ms']:.3g}"
        return f"GM {gm}, PM {pm}, Ms {ms}"

    def where(d: dict[str, Any]) -> str:
        params = ", ".join(f"{k} {100 * v:+.3g} %" for k, v in d["parameters"].items() if v)
        fr = ("sliding" if d["friction"] == "sliding"
              else f"at rest in pre-sliding (sigma0 x{d['presliding_factor']:.3g})")
        return (f"{100 * d['fraction']:.3g} % of the stroke ({1e3 * d['position']:.4g} mm), "
                f"{params or 'nominal parameters'}, {fr}")

    w = m["worst"]
    brk = {"valve": "the valve command", "position": "the position sensor"}
    mid = m["mid"]
    lines = [
        f"loop as it runs: {m['control_rate']:.4g} Hz, computation delay {m['delay']} "
        f"sample(s), {len(m['grid'])} grid points (stroke x parameter box x friction); "
        f"requirement GM >= {req['gain']:g} (6 dB), PM >= {req['phase_deg']:g} deg, "
        f"Ms <= {req['ms']:g}: {'met everywhere' if m['meets'] else 'NOT met'}",
        f"  mid stroke (nominal, sliding): at the valve "
        f"{fig(_refined(mid['valve']))}; at the position sensor {fig(_refined(mid['position']))}",
        f"  worst point: {fig(_refined(w['refined']))} broken at {brk[w['break']]}, at "
        f"{where(w)}",
        f"  over the grid: smallest GM {_num(m['gain'], '.3g')}, smallest PM "
        f"{_num(m['phase_deg'], '.1f')} deg, largest Ms {_num(m['ms'], '.3g')}",
    ]
    for name, c in m["controllers"].items():
        cw = c["worst"]
        lines.append(f"  {name} as coded ({c['points']} points, {c['where']}): worst "
                     f"{fig(cw)} broken at {brk[cw['break']]}, at {where(cw)}")
    for name, why in m.get("controllers_failed", {}).items():
        lines.append(f"  {name}: not analysed ({why})")
    return lines


def _num(v: float | None, spec: str) -> str:
    return "inf" if v is None else format(v, spec)


def _refined(d: dict[str, Any]) -> dict[str, Any]:
    return {"gain": d["gain"], "phase_deg": d["phase_deg"], "ms": d["ms"],
            "stable": d["stable"], "growth": d.get("growth"), "mode_hz": d.get("mode_hz")}


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
        f"uncertainty: {doc['uncertainty_text']}",
        *doc["tuning_lines"],
        *margin_lines(doc["margins"], doc["tuning"]),
    ])


def run_check(args: argparse.Namespace) -> int:
    """Check a plant file and print (or write as JSON) what an engineer checks first, with the
    margins of the loop as it runs; ``--report DIR`` draws them."""
    from fcomp.outputs import staged_folder

    out = json_target(args.json)
    folder = report_dir(getattr(args, "report", None))
    inputs = InputSet()
    inputs.file(args.file, "PLANT.toml")
    common.check_outputs(inputs, [("--json", out)], [("--report", folder, "report")])
    try:
        pf = read_plant_file(args.file)
    except PlantFileError as exc:
        for line in exc.problems:  # one line per bad value
            sys.stderr.write(f"fcomp: error: {line}\n")
        return 2
    try:  # a valve that passes no flow was refused when the file was read
        doc = check_plant(pf)
        model = plant_model(pf)
        tuning = model.tuning  # FcompError (one line, exit 2): no tuning meets the requirement
        from controllers.loop_analysis.summary import analyse

        loop = analyse(model, tuning)
    except FcompError as exc:  # the figures of a plant that cannot be run: the file named
        raise FcompError(str(exc) if pf.label in str(exc) else f"{pf.label}: {exc}") from None
    doc["tuning"] = tuning.as_dict()
    doc["tuning_lines"] = tuning.lines()
    doc["margins"] = loop.as_dict()
    doc["uncertainty"] = pf.ranges.as_dict()
    doc["uncertainty_text"] = pf.ranges.describe()
    doc = common.with_warnings(doc)
    if folder is not None:
        from controllers.cli.plant_report import report

        command = "fcomp " + shlex.join(common.ARGV) if common.ARGV else None
        with staged_folder(folder, "--report", "report",
                           note=command or "fcomp plant check") as tmp:
            report(pf, doc, loop, command).write(tmp / "report.html")
        common.wrote(folder / "report.html")
    text = {k: v for k, v in doc.items() if k not in ("tuning_lines", "uncertainty_text")}
    emit_result(result_text(text), args.json, out, summary(doc))
    return 0


def plant_model(pf: Any) -> ControlModel:
    """The controller model a plant check tunes: the plant file with the ``nmlgm`` friction of
    the plant kind's parameter set (its viscous slope and bristle enter the loop analysis)."""
    return ControlModel(pf, make_model("nmlgm", params=pf.friction_set))


def plant_tuning(pf: Any) -> Any:
    """The compensators' default tuning on a plant file (:mod:`controllers.tuning`)."""
    return plant_model(pf).tuning
