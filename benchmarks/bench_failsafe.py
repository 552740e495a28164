"""Benchmark: what the fail-safe layer (controllers/safety.py) costs, in Python and in C.

1. The Python step of every controller with and without the layer, in one process: the same
   controller (``make_controller``) stepped through its layer and, on a second instance, its
   law alone (``controllers.safety.unwrap``), on the same inputs, step for step interleaved;
   CPU time of the thread per step (median, p99), and the ratio.
2. With ``--dropout``: every controller in closed loop (``steps``, fast) with every sensor
   reading NaN for 30 ms at 0.5 s, beside the same run without: faults, samples latched, the
   largest deviation between the two runs, the RMS errors (the table of
   docs/compensators.md, "The fail-safe layer").
3. With ``--baseline DIR`` (a checkout of the baseline, e.g. ``git worktree add --detach
   /tmp/base 2d5cfbf``): ``fcomp export CONTROLLER`` with the baseline's code and with this
   checkout's, one after the other in one run: the equivalence figures and the compiled
   step times of both (the baseline times wall clock only; this checkout CPU time and wall
   clock).

    python benchmarks/bench_failsafe.py [--steps 3000] [--dropout] [--baseline /tmp/base]
           [--controllers pid,pid-ff,lugre-observer,ekf,mpc] [--plant hydraulic] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def python_steps(name: str, plant: str, steps: int) -> dict[str, float]:
    """CPU time per step (s) of ``name`` through its layer and of its law alone."""
    from controllers import make_controller
    from controllers.base import Reference
    from controllers.plant_model import MEASURED, ControlModel, equilibrium
    from controllers.safety import unwrap
    from controllers.tasks import get_task
    from fcomp.models import make_model
    from plants import PLANTS

    model = ControlModel(plant, make_model("nmlgm", params=PLANTS.get(plant).default_params))
    guarded, bare = make_controller(name, model), unwrap(make_controller(name, model))
    x_eq, _ = equilibrium(model.plant, 0.5 * model.stroke)
    names = model.plant.state_names
    y0 = np.array([x_eq[names.index(k)] for k in MEASURED])
    dt = guarded.dt
    n = guarded.preview
    t = np.arange(steps + n) * dt
    r, dr, ddr = get_task("seed002-sine").sample(t)
    r = r + 0.5 * model.stroke
    rng = np.random.default_rng(0)
    pair = (("layer", guarded), ("law", bare))
    times = {label: np.empty(steps) for label, _ in pair}
    for _, ctrl in pair:
        ctrl.reset(0.0, y0, Reference(float(r[0]), 0.0, 0.0, tuple(r[1:1 + n])))
    for k in range(steps):  # interleaved: both see the same machine load
        y = y0 + np.array([r[k] - r[0], 0.0, 0.0]) + rng.standard_normal(3) * [1e-6, 1e3, 1e3]
        ref = Reference(float(r[k]), float(dr[k]), float(ddr[k]),
                        tuple(float(v) for v in r[k + 1:k + 1 + n]))
        for label, ctrl in pair:
            c0 = time.thread_time()
            ctrl.step(k * dt, y, ref)
            times[label][k] = time.thread_time() - c0
    out: dict[str, float] = {}
    for label, _ in pair:
        out[f"{label}_median"] = float(np.median(times[label]))
        out[f"{label}_p99"] = float(np.quantile(times[label], 0.99))
    out["ratio_median"] = out["layer_median"] / out["law_median"]
    return out


def dropout(name: str, plant: str) -> dict[str, float]:
    """A 30 ms dropout of every sensor at 0.5 s against the same run without it."""
    from controllers.harness import LoopConfig, SensorFault, run_closed_loop

    clean = run_closed_loop(name, "steps", LoopConfig(plant=plant, fast=True))
    hit = run_closed_loop(name, "steps", LoopConfig(
        plant=plant, fast=True, sensor_faults=(SensorFault(0.4999, 0.03),)))
    tail = hit.t > hit.t[-1] - 0.3
    return {"faults": hit.metrics.faults, "latched_steps": hit.metrics.latched_steps,
            "latches": hit.metrics.latches, "false_alarms": clean.metrics.faults,
            "max_deviation": float(np.max(np.abs(hit.x - clean.x))),
            "rms_clean": clean.metrics.rms_error, "rms_dropout": hit.metrics.rms_error,
            "tail_clean": float(np.sqrt(np.mean((clean.r - clean.x)[tail] ** 2))),
            "tail_dropout": float(np.sqrt(np.mean((hit.r - hit.x)[tail] ** 2)))}


def export(checkout: Path, name: str, plant: str, folder: Path) -> dict[str, object]:
    """``fcomp export`` run with the code of ``checkout``; its JSON."""
    env = dict(os.environ, PYTHONPATH=str(checkout))
    out = folder / f"{name}.json"
    proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", "export", name, "--plant",
                           plant, "-o", str(folder / name), "--json", str(out),
                           "--no-progress"], env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        return {"error": proc.stderr.strip()}
    return json.loads(out.read_text())


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=3000, help="Python steps timed (default 3000)")
    p.add_argument("--controllers", default="pid,pid-ff,lugre-observer,ekf,mpc")
    p.add_argument("--plant", default="hydraulic")
    p.add_argument("--dropout", action="store_true",
                   help="also the closed loops with a sensor dropout")
    p.add_argument("--baseline", default=None, metavar="DIR",
                   help="a checkout of the baseline: also export with it and with this one")
    p.add_argument("--json", default=None, metavar="OUT.json")
    args = p.parse_args(argv)
    names = args.controllers.split(",")
    res: dict[str, object] = {"plant": args.plant, "python": {}, "export": {}}
    print(f"Python step, {args.plant}, CPU time of the thread, {args.steps} steps")
    for name in names:
        d = python_steps(name, args.plant, args.steps)
        res["python"][name] = d  # type: ignore[index]
        print(f"  {name:15s} law {d['law_median'] * 1e6:7.1f} us   with the layer "
              f"{d['layer_median'] * 1e6:7.1f} us   ratio {d['ratio_median']:.2f}   "
              f"(p99 {d['law_p99'] * 1e6:.0f} / {d['layer_p99'] * 1e6:.0f} us)")
    if args.dropout:
        print(f"Sensor dropout (every sensor NaN for 30 ms at 0.5 s), steps, {args.plant}")
        res["dropout"] = {}
        for name in names:
            d = dropout(name, args.plant)
            res["dropout"][name] = d  # type: ignore[index]
            print(f"  {name:15s} faults {d['faults']}  latched {d['latched_steps']} samples  "
                  f"largest deviation {d['max_deviation'] * 1e6:.0f} um  RMS last 0.3 s "
                  f"{d['tail_clean'] * 1e6:.1f} / {d['tail_dropout'] * 1e6:.1f} um  RMS "
                  f"{d['rms_clean'] * 1e6:.1f} / {d['rms_dropout'] * 1e6:.1f} um  (false "
                  f"alarms without the dropout: {d['false_alarms']})")
    if args.baseline:
        print("fcomp export (max_rel_diff; compiled step: median / max)")
        with tempfile.TemporaryDirectory() as tmp:
            for name in names:
                row = {}
                for label, checkout in (("baseline", Path(args.baseline)), ("this", ROOT)):
                    folder = Path(tmp) / label
                    folder.mkdir(exist_ok=True)
                    row[label] = export(checkout, name, args.plant, folder)
                res["export"][name] = row  # type: ignore[index]
                b, n = row["baseline"], row["this"]
                if "error" in b or "error" in n:
                    print(f"  {name}: {b.get('error') or n.get('error')}")
                    continue
                fc = n["fault_check"]
                print(f"  {name:15s} baseline: {b['max_rel_diff']:.2g}, wall "
                      f"{b['step_time_median'] * 1e6:.2f} / {b['step_time_max'] * 1e6:.0f} us"
                      f" | this: {n['max_rel_diff']:.2g} (hostile {fc['max_rel_diff']:.2g}, "
                      f"{fc['faults']} faults, fault states "
                      f"{'same' if fc['same_faults'] else 'DIFFERENT'}), CPU "
                      f"{n['step_time_median'] * 1e6:.2f} / {n['step_time_max'] * 1e6:.0f} us,"
                      f" wall {n['step_time_wall_median'] * 1e6:.2f} / "
                      f"{n['step_time_wall_max'] * 1e6:.0f} us")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
