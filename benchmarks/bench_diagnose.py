"""Benchmark: ``fcomp diagnose`` on a 60 s record at 1 kHz with the full catalogue.

Goal (issue 5): under 60 s wall time on a 2-core machine, with a progress bar.

What is timed
-------------
* **fcomp diagnose (cold)**: the console command in a *fresh process* with an
  *empty compile cache* (``FCOMP_CACHE`` pointed at a new folder): imports,
  CasADi code generation and C compilation of every candidate model's
  sensitivity step, the baseline fit, every step of the search over the full
  catalogue (each candidate refitted on the training samples and scored on the
  held-out ones, two processes in parallel), the verdict and the JSON.
* **fcomp diagnose (warm)**: the same command with the compile cache filled
  (a user's second run).
* **baseline: serial** (``--jobs 1``, warm): the same work in one process, the
  reference the parallel refits are measured against.

The record: :func:`fcomp.synthetic.generate` with the pressure dependence of
the seal hidden (LuGre truth, three experiments at different chamber
pressures, quantised position, coloured force noise), 60 s at 1 kHz =
60 001 samples. The figure reported is the median of ``--repeats`` runs, with
the ratio to the goal and to the serial run.

Run ``python benchmarks/bench_diagnose.py`` (``--quick`` for a 20 s record and
one repeat).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fcomp.synthetic import generate

GOAL_S = 60.0


def run(csv: Path, cache: Path, extra: list[str], out: Path) -> tuple[float, dict]:
    env = dict(os.environ, FCOMP_CACHE=str(cache))
    cmd = [sys.executable, "-m", "fcomp.cli.main", "diagnose", str(csv), "--baseline", "lugre",
           "--json", str(out), *extra]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"fcomp diagnose failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return wall, json.loads(out.read_text())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="20 s record, one repeat")
    args = ap.parse_args()
    duration = 20.0 if args.quick else 60.0
    repeats = 1 if args.quick else args.repeats
    with tempfile.TemporaryDirectory() as tmp:
        tmpd = Path(tmp)
        csv = tmpd / "record.csv"
        generate(["pressure-dependence"], duration=duration, rate=1000.0, seed=11
                 ).measurement.write(csv)
        out = tmpd / "out.json"
        cold, warm, serial = [], [], []
        doc: dict = {}
        for k in range(repeats):
            cache = tmpd / f"cache{k}"
            w, doc = run(csv, cache, [], out)
            cold.append(w)
            w, doc = run(csv, cache, [], out)
            warm.append(w)
            w, _ = run(csv, cache, ["--jobs", "1", "--no-progress"], out)
            serial.append(w)
            print(f"run {k + 1}: cold {cold[-1]:.1f} s, warm {warm[-1]:.1f} s, serial (warm) "
                  f"{serial[-1]:.1f} s", flush=True)
    med = {name: statistics.median(v) for name, v in
           (("cold", cold), ("warm", warm), ("serial", serial))}
    print(f"\nrecord: {duration:.0f} s at 1 kHz, hidden pressure-dependence; "
          f"{os.cpu_count()} CPUs; {repeats} repeat(s), medians:")
    print(f"  fcomp diagnose, cold cache : {med['cold']:7.1f} s  ({med['cold'] / GOAL_S:.2f} of "
          f"the {GOAL_S:.0f} s goal)")
    print(f"  fcomp diagnose, warm cache : {med['warm']:7.1f} s  ({med['warm'] / GOAL_S:.2f} of "
          "the goal)")
    print(f"  serial baseline (--jobs 1) : {med['serial']:7.1f} s  (parallel refits "
          f"{med['serial'] / med['warm']:.2f}x faster)")
    print(f"  result: added {doc['added']}, verdict {doc['verdict']}, held-out RMS "
          f"{doc['rms_baseline']:.3g} -> {doc['rms_final']:.3g} N (noise floor "
          f"{doc['noise_floor']:.3g} N), {len(doc['candidates'])} candidates")


if __name__ == "__main__":
    main()
