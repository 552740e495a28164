"""Margins of the loop as it runs, before and after (issue 39): the former tunings beside the
derived one, on the same grid.

For each plant (the built-in ``hydraulic`` and ``pneumatic``, ``docs/examples/axis40.toml``,
``docs/examples/axis50.toml``) it evaluates, on the loop as it runs
(:mod:`controllers.loop_analysis`: the grid over the stroke, the parameter box and the
friction regimes, both break points):

* **before**: the tuning the code at ``--baseline-rev`` (default ``2d5cfbf``) derives, read
  from a ``git worktree`` of it in a subprocess, with that code's law (forward-Euler
  integral, velocity compensation 1), without and with one sample of computation delay;
* **fixed**: the former fixed tuning (``benchmarks/bench_tuning.py``'s) on the built-in
  plants, with the former law and the delay;
* **after**: this code's derived tuning.

Printed: GM/PM/Ms at mid stroke (nominal, sliding; broken at the valve and at the position
sensor) and at the worst point of the grid, and whether the requirement (GM >= 2, PM >= 30
deg, Ms <= 2) holds everywhere::

    PYTHONPATH=. python3 benchmarks/bench_margins.py [--baseline-rev 2d5cfbf]
        [--plants hydraulic,...] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
PLANTS = ("hydraulic", "pneumatic", "docs/examples/axis40.toml", "docs/examples/axis50.toml")
#: The former fixed tuning (benchmarks/bench_tuning.py).
FIXED = {"hydraulic": (150.0, 40.0), "pneumatic": (120.0, 30.0)}

_BASELINE = r"""
import json, sys
from pathlib import Path
from controllers.plant_model import ControlModel
from fcomp.models import make_model
from plants.planfile import builtin_plant_file, read_plant_file
out = {}
for spec in sys.argv[1].split(","):
    pf = read_plant_file(Path(sys.argv[2]) / spec) if spec.endswith(".toml") \
        else builtin_plant_file(spec)
    tu = ControlModel(pf, make_model("nmlgm", params=pf.friction_set)).tuning
    g = tu.pid_gains
    out[spec] = {"kp": g.kp, "ki": g.ki, "kd": g.kd, "derivative_cutoff": g.derivative_cutoff,
                 "force_bandwidth": tu.force_bandwidth}
print(json.dumps(out))
"""


def baseline_tunings(rev: str, plants: list[str]) -> dict[str, dict[str, float]]:
    """The tunings the code at ``rev`` derives (a git worktree, a subprocess)."""
    with tempfile.TemporaryDirectory() as tmp:
        wt = Path(tmp) / "baseline"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(wt), rev],
                       check=True, capture_output=True)
        try:
            res = subprocess.run([sys.executable, "-c", _BASELINE, ",".join(plants), str(ROOT)],
                                 cwd=wt, env={"PYTHONPATH": str(wt), "PATH": "/usr/bin:/bin"},
                                 check=True, capture_output=True, text=True)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(wt)],
                           check=True, capture_output=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def evaluate(model: Any, fam: Any, delay: int) -> dict[str, Any]:
    """Mid-stroke and worst-point margins of a PID-family loop on the model's grid."""
    from controllers.loop_analysis.design import ratios
    from controllers.loop_analysis.grid import describe_at, mid_point, worst_index
    from controllers.loop_analysis.margins import loop_margins_from
    from controllers.tuning import model_grid

    grid = model_grid(model)
    if delay != grid.delay:
        from controllers.loop_analysis.grid import PlantGrid

        grid = PlantGrid(grid.points, grid.plants, grid.slopes, delay, grid.dt, grid.w,
                         grid.areas)
    r, arrays = ratios(grid, fam)
    i, brk = worst_index(arrays)
    j = mid_point(grid)
    mid = {b: loop_margins_from(arrays[b], (j,)) for b in arrays}
    return {"meets": bool(r.min() >= 1.0),
            "mid": {b: {"gain": m.gain, "phase_deg": m.phase, "ms": m.ms}
                    for b, m in mid.items()},
            "worst": describe_at(grid, arrays, i, brk)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--plants", default=",".join(PLANTS))
    ap.add_argument("--baseline-rev", default="2d5cfbf")
    ap.add_argument("--json", default=None, metavar="OUT")
    args = ap.parse_args(argv)
    from controllers.cli.plant_check import plant_model
    from controllers.loop_analysis.pid_family import PIDFamilyGains
    from plants.planfile import builtin_plant_file, read_plant_file

    plants = args.plants.split(",")
    base = baseline_tunings(args.baseline_rev, plants)
    rows = []
    for spec in plants:
        pf = read_plant_file(ROOT / spec) if spec.endswith(".toml") else builtin_plant_file(spec)
        model = plant_model(pf)
        b = base[spec]
        cases = [(f"before ({args.baseline_rev}), no delay", PIDFamilyGains(
                     b["kp"], b["ki"], b["kd"], b["derivative_cutoff"], b["force_bandwidth"],
                     1.0, forward_euler=True), 0),
                 (f"before ({args.baseline_rev}), 1 sample delay", PIDFamilyGains(
                     b["kp"], b["ki"], b["kd"], b["derivative_cutoff"], b["force_bandwidth"],
                     1.0, forward_euler=True), 1)]
        if spec in FIXED:
            wF, w = FIXED[spec]
            m = model.mass
            cases.append(("former fixed, 1 sample delay", PIDFamilyGains(
                3 * m * w * w, m * w ** 3, 3 * m * w, 60.0, wF, 1.0, forward_euler=True), 1))
        cases.append(("after (derived)", model.tuning.family(), model.delay))
        for label, fam, delay in cases:
            ev = evaluate(model, fam, delay)
            rows.append({"plant": spec, "case": label, **ev})
            mv, mp = ev["mid"]["valve"], ev["mid"]["position"]

            def f(x: float, spec_: str) -> str:
                return "inf" if not math.isfinite(x) else format(x, spec_)

            print(f"{spec:28s} {label:34s} mid: valve GM {f(mv['gain'], '.3g')} PM "
                  f"{f(mv['phase_deg'], '.1f')} Ms {f(mv['ms'], '.3g')}; position GM "
                  f"{f(mp['gain'], '.3g')} PM {f(mp['phase_deg'], '.1f')} Ms "
                  f"{f(mp['ms'], '.3g')} | {'meets' if ev['meets'] else 'FAILS'} | worst: "
                  f"{ev['worst']}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows}, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
