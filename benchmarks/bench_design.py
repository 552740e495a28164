"""Time ``fcomp.design`` (goal: a programme in under a minute on the 2-core machine).

    python benchmarks/bench_design.py --repeats 3

Diagnoses the shipped Circle files (2, 4, 6 bar; from ``coulomb``) once, then designs for
their open questions ``--repeats`` times with the rig as the files show it; prints the
median and range. The diagnosis itself is not timed (``benchmarks/bench_diagnose.py``).
There is no baseline: ``fcomp design`` is new (issue 40).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import fcomp
from fcomp import datasets
from fcomp.importers import import_file

RIG = {"rig": {"bore": 0.025, "mass": 0.5, "orientation": "horizontal"},
       "limits": {"stroke": 0.045, "speed_max": 0.02, "accel_max": 0.5, "pressure_min": 1e5,
                  "pressure_max": 7e5, "duration_max": 110.0, "rate": 100.0}}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        recs = []
        for name in ("Circle_2bar", "Circle_4bar", "Circle_6bar"):
            src = datasets.shipped("zillen", name)
            assert src is not None, name
            out = Path(d) / f"{name}.csv"
            import_file("zillen", src).write(out)
            recs.append(fcomp.read(out))
        diag = fcomp.diagnose(recs, "coulomb", progress=False)
        doc = {**diag.to_dict(), "model_file": diag.model_file({"data": []})}
    times = []
    for _ in range(a.repeats):
        t0 = time.perf_counter()
        res = fcomp.design(doc, RIG)
        times.append(time.perf_counter() - t0)
    print(f"fcomp.design on the Circle diagnosis ({len(res.questions_)} questions, "
          f"{len(res.experiments_)} experiments): median {statistics.median(times):.2f} s, "
          f"range {min(times):.2f}-{max(times):.2f} s over {a.repeats}")


if __name__ == "__main__":
    main()
