"""The derived tuning against the former fixed one, side by side, on the two built-in plants.

Runs the closed loops of the compensator study (``fcomp study compensators
--fast``: every controller on every task, the default friction mismatch and
sensor noise, :mod:`controllers.harness`) once with the tuning derived from the
plant (:mod:`controllers.tuning`) and once with the former per-name table
(hydraulic: PID 40 rad/s, force loop 150 rad/s; pneumatic: 30 and 120 rad/s;
derivative filter 60 Hz, observer gain 20 1/s, MPC horizon 40 ms and
``e_v/e_x = 100`` 1/s), and prints RMS and max tracking error per controller
and plant (mean over the tasks, and per task with ``--per-task``), with the
margins of both tunings::

    PYTHONPATH=. python3 benchmarks/bench_tuning.py [--full] [--workers 2] [--per-task]
        [--plants hydraulic,pneumatic] [--controllers pid,...] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from controllers.harness import LoopConfig, control_model, run_closed_loop
from controllers.plant_model import ControlModel
from controllers.tuning import Tuning, fixed_tuning

CONTROLLERS = ("pid", "pid-ff", "lugre-observer", "ekf", "mpc")
TASKS = ("slow-sine", "steps", "low-velocity-ramp", "seed002-sine")
#: The former fixed tuning (PLANT_SETTINGS, pid.py, lugre_observer.py, mpc.py DEFAULTS).
FORMER = {
    "hydraulic": {"force_bandwidth": 150.0, "pid_bandwidth": 40.0},
    "pneumatic": {"force_bandwidth": 120.0, "pid_bandwidth": 30.0},
}


def former_tuning(model: ControlModel) -> Tuning:
    """The former fixed tuning of the model's plant (margins computed, not checked)."""
    return fixed_tuning(model, derivative_cutoff=60.0, observer_gain=20.0,
                        mpc_horizon_time=0.040, mpc_velocity_ratio=100.0,
                        **FORMER[model.plant_name])


def run_one(job: tuple[str, str, str, str, bool]) -> dict[str, Any]:
    """One closed loop: ``(tuning, plant, controller, task, fast)`` -> errors (m)."""
    which, plant, controller, task, fast = job
    config = LoopConfig(plant=plant, fast=fast,
                        tuning=former_tuning if which == "former" else None)
    row: dict[str, Any] = {"tuning": which, "plant": plant, "controller": controller,
                           "task": task}
    try:
        res = run_closed_loop(controller, task, config)
        row.update(rms_error=res.metrics.rms_error, max_error=res.metrics.max_error,
                   status="ok")
    except Exception as exc:  # noqa: BLE001 -- a failed loop is a row of the table
        row.update(rms_error=math.nan, max_error=math.nan, status=str(exc).splitlines()[0])
    return row


def tunings(plant: str) -> dict[str, Tuning]:
    model = control_model(LoopConfig(plant=plant))
    return {"former": former_tuning(model), "derived": model.tuning}


def table(rows: list[dict[str, Any]], plants: list[str], controllers: list[str],
          tasks: list[str], per_task: bool) -> str:
    """The side-by-side table (um)."""
    def pick(which: str, p: str, c: str, t: str | None) -> tuple[float, float]:
        sel = [r for r in rows if r["tuning"] == which and r["plant"] == p
               and r["controller"] == c and (t is None or r["task"] == t)]
        if not sel or any(r["status"] != "ok" for r in sel):
            return math.nan, math.nan
        return (sum(r["rms_error"] for r in sel) / len(sel) * 1e6,
                max(r["max_error"] for r in sel) * 1e6)

    out = ["| plant | controller | task | RMS former [um] | RMS derived [um] | ratio | "
           "max former [um] | max derived [um] |", "|---|---|---|---:|---:|---:|---:|---:|"]
    for p in plants:
        for c in controllers:
            for t in ([*tasks, None] if per_task else [None]):
                (r0, m0), (r1, m1) = pick("former", p, c, t), pick("derived", p, c, t)
                out.append(f"| {p} | {c} | {t or 'mean (max) of tasks'} | {r0:.1f} | {r1:.1f} | "
                           f"{r1 / r0:.2f} | {m0:.1f} | {m1:.1f} |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--full", action="store_true", help="full-length tasks (default: fast)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--per-task", action="store_true")
    ap.add_argument("--plants", default="hydraulic,pneumatic")
    ap.add_argument("--controllers", default=",".join(CONTROLLERS))
    ap.add_argument("--tasks", default=",".join(TASKS))
    ap.add_argument("--json", default=None, metavar="OUT")
    args = ap.parse_args(argv)
    plants, ctrls, tasks = (args.plants.split(","), args.controllers.split(","),
                            args.tasks.split(","))
    for p in plants:
        for which, tu in tunings(p).items():
            print(f"{p}, {which}:")
            print("\n".join(f"  {line}" for line in tu.lines()))
    jobs = [(w, p, c, t, not args.full) for w in ("former", "derived") for p in plants
            for c in ctrls for t in tasks]
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        rows = list(pool.map(run_one, jobs))
    for r in rows:
        if r["status"] != "ok":
            print(f"failed: {r['tuning']} {r['plant']} {r['controller']} {r['task']}: "
                  f"{r['status']}", file=sys.stderr)
    print(table(rows, plants, ctrls, tasks, args.per_task))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"runs": rows, "tunings": {p: {k: v.as_dict() for k, v in
                                                     tunings(p).items()} for p in plants}},
                      fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
