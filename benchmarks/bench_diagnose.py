"""Benchmark: ``fcomp diagnose`` on a synthetic 60 s record and on the four O-ring files,
beside the code of a baseline revision, in one run.

Goals (issue 24, item 5): a 60 s record at 1 kHz with the full catalogue in at most
15 s warm on 2 cores; the four Zillen O-ring files (1, 3, 5, 7 bar, about 100 Hz with
irregular stamps) from ``lugre`` in at most 60 s.

What is timed
-------------
* **synthetic, warm**: the console command in a fresh process with the compile cache
  filled (``FCOMP_CACHE``, filled by one untimed run first): imports, the baseline fit,
  every step of the search over the full catalogue (two processes), the verdict, the
  JSON. The record: :func:`fcomp.synthetic.generate` with the pressure dependence of the
  seal hidden (LuGre truth, three experiments, quantised position, coloured force
  noise), 60 s at 1 kHz = 60 001 samples.
* **O-ring, warm**: ``fcomp diagnose O-ring_1bar.csv ... O-ring_7bar.csv --baseline
  lugre`` as a user types it (the baseline check as the default decides).

Each is timed for this checkout and, with ``--baseline-rev REV`` (default: the commit
before issue 24's work, ``c848ea1``), for that revision's code (``git archive`` into a
temporary folder, run with ``PYTHONPATH`` pointing there), alternately A B A B, so a
drift of the machine's speed hits both. Medians over ``--repeats`` runs and the ratio
of the medians are printed, with each side's answer (added effects, verdict, errors).

Run ``python benchmarks/bench_diagnose.py`` (``--quick``: a 20 s record, one repeat;
``--no-baseline``: this checkout only).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fcomp import datasets
from fcomp.synthetic import generate

REPO = Path(__file__).resolve().parents[1]
#: The goals (s).
GOALS = {"synthetic": 15.0, "o-ring": 60.0}
#: The last commit before issue 24's work.
BASELINE_REV = "c848ea1"


def checkout(rev: str, into: Path) -> Path:
    """The package of revision ``rev`` unpacked under ``into`` (its ``PYTHONPATH``)."""
    into.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(["git", "-C", str(REPO), "archive", rev, "fcomp"],
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into


#: CPU seconds of the last :func:`run` (the command and every process it waited for): on a
#: machine other work loads, the CPU time moves less than the wall time.
LAST_CPU = [0.0]


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run(args: list[str], out: Path, cache: Path, pythonpath: Path | None) -> tuple[float, dict]:
    env = dict(os.environ, FCOMP_CACHE=str(cache))
    env["PYTHONPATH"] = str(pythonpath if pythonpath is not None else REPO)
    cmd = [sys.executable, "-m", "fcomp.cli.main", "diagnose", *args, "--no-progress",
           "--json", str(out)]
    t0, c0 = time.perf_counter(), _children_cpu()
    # run away from the checkout: ``python -m`` puts the working directory first on
    # sys.path, before PYTHONPATH, so run from the repository the baseline side would
    # import this checkout's package (as it did until 2026-11-27: both sides ran this code)
    proc = subprocess.run(cmd, env=env, cwd=out.parent, capture_output=True, text=True,
                          check=False)
    wall = time.perf_counter() - t0
    LAST_CPU[0] = _children_cpu() - c0
    if proc.returncode != 0:
        raise SystemExit(f"fcomp diagnose failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return wall, json.loads(out.read_text())


def answer(doc: dict) -> str:
    return (f"added {doc['added']}, verdict {doc['verdict']}, held-out RMS "
            f"{doc['rms_baseline']:.3g} -> {doc['rms_final']:.3g} N (floor "
            f"{doc['noise_floor']:.3g} N)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="20 s record, one repeat")
    ap.add_argument("--baseline-rev", default=BASELINE_REV)
    ap.add_argument("--no-baseline", action="store_true")
    ap.add_argument("--cases", default="synthetic,o-ring")
    args = ap.parse_args()
    duration = 20.0 if args.quick else 60.0
    repeats = 1 if args.quick else args.repeats
    with tempfile.TemporaryDirectory() as tmp:
        tmpd = Path(tmp)
        csv = tmpd / "record.csv"
        generate(["pressure-dependence"], duration=duration, rate=1000.0, seed=11
                 ).measurement.write(csv)
        orings = []  # the shipped source files (tab-separated logs) as measurement files
        for k in (1, 3, 5, 7):
            orings.append(str(tmpd / f"O-ring_{k}bar.csv"))
            datasets.load("zillen", f"O-ring_{k}bar.csv").write(orings[-1])
        cases = {"synthetic": [str(csv), "--baseline", "lugre"],
                 "o-ring": [*orings, "--baseline", "lugre"]}
        sides: dict[str, Path | None] = {"this checkout": None}
        if not args.no_baseline:
            sides[f"baseline {args.baseline_rev}"] = checkout(args.baseline_rev,
                                                              tmpd / "baseline")
        out = tmpd / "out.json"
        for case in args.cases.split(","):
            times: dict[str, list[float]] = {s: [] for s in sides}
            cpus: dict[str, list[float]] = {s: [] for s in sides}
            docs: dict[str, dict] = {}
            for side, path in sides.items():  # fill each side's compile cache
                run(cases[case], out, tmpd / f"cache-{len(docs)}-{case}", path)
                docs[side] = {}
            for k in range(repeats):
                for i, (side, path) in enumerate(sides.items()):
                    w, docs[side] = run(cases[case], out, tmpd / f"cache-{i}-{case}", path)
                    times[side].append(w)
                    cpus[side].append(LAST_CPU[0])
                    print(f"{case} run {k + 1}, {side}: {w:.1f} s ({LAST_CPU[0]:.1f} s CPU; "
                          f"load {os.getloadavg()[0]:.1f})", flush=True)
            print(f"\n{case} ({'60' if case == 'synthetic' and not args.quick else ''}"
                  f"{' s at 1 kHz' if case == 'synthetic' else '4 files from lugre'}), "
                  f"{os.cpu_count()} CPUs, {repeats} repeat(s), warm, medians:")
            med = {s: statistics.median(v) for s, v in times.items()}
            for side in sides:
                print(f"  {side:22s}: {med[side]:7.1f} s  (goal {GOALS[case]:.0f} s: "
                      f"{med[side] / GOALS[case]:.2f}x; CPU "
                      f"{statistics.median(cpus[side]):.1f} s)  {answer(docs[side])}")
            if len(sides) == 2:
                a, b = list(med.values())
                ca, cb = (statistics.median(v) for v in cpus.values())
                print(f"  ratio this/baseline     : {a / b:.2f} wall, {ca / cb:.2f} CPU\n")


if __name__ == "__main__":
    main()
