"""The diagnosis matrix: is `fcomp diagnose` right on records it was not built on? (issue 10)

Every catalogue effect hidden alone, nothing hidden, two effects at once and
effects outside the catalogue, x every measurement style x both rig scales x
static and dynamic baselines x seeds, on records of :mod:`fcomp.synthetic`
(its laws written independently of :mod:`fcomp.effects`; shapes rotate with
the case so every shape of every effect is met; nuisance parameters drawn
per seed). Each case runs the diagnosis as a user would and is judged through
the public JSON contract (:mod:`fcomp.synthetic.matrix`): the added set right
(in order where it matters), the verdict right, and the held-out error at
most 0.6 of the baseline's where something was to be found.

Conditions (``--conditions``, :data:`fcomp.synthetic.matrix.CONDITIONS`) cross
the cases with loggers, sensors and rigs the diagnosis was not built on:
irregular or gapped stamps, pink force noise, a vertical rig, a pump's
pulsation (which must be reported as a disturbance, the record then not
explained), a presliding-dominated motion on a soft seal. The default is
``plain``, the original records; ``--rows all`` adds the rows outside the
default selection (two effects hidden with the dynamic baseline too).

Prints the confusion matrix (hidden effect vs added effects), the share
right per row, style, scale, baseline kind and condition, the rows that fall
short and why, and the time per case.

    python benchmarks/bench_diagnosis_matrix.py                 # the whole matrix
    python benchmarks/bench_diagnosis_matrix.py --seeds 1 --rows dwell-time,nothing
    python benchmarks/bench_diagnosis_matrix.py --json matrix.json
    python benchmarks/bench_diagnosis_matrix.py --seed-list 4,5 --sample 120   # a seeded draw
    python benchmarks/bench_diagnosis_matrix.py --seed-list 4 --sample 60 \
        --conditions pulsation,vertical,pink-noise --rows all       # other rigs and loggers
    python benchmarks/bench_diagnosis_matrix.py --conditions soft-presliding --list
    python benchmarks/bench_diagnosis_matrix.py --cases-from old1.json,old2.json --json new.json
    python benchmarks/bench_diagnosis_matrix.py --seed-list 301 --per-row 4 --rows all \
        --conditions plain,gapped-stamps --code /tmp/main-checkout     # another revision

``--per-row K`` draws ``K`` cases of every row (seeded), so each row's share rests on
the same number of cases. ``--code DIR`` diagnoses with the package of another checkout
(``DIR/fcomp``): each record is written to a CSV file and ``fcomp diagnose`` runs on it in
a fresh process with ``PYTHONPATH=DIR`` (``--jobs 1 --no-baseline-check``), so one
generator and one judge -- this checkout's -- score two revisions on the same records.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

import numpy as np

from fcomp.synthetic.matrix import CASE_FIELDS, CONDITIONS, Case, cases, judge, record


def _diagnose_in(code: str, rec: Any, baseline: str) -> tuple[dict, float]:
    """``fcomp diagnose`` of the package under ``code`` on ``rec`` in a fresh process: the
    JSON (or ``{"error": ...}``) and the CPU seconds (user + system) it took."""
    with tempfile.TemporaryDirectory() as tmp:
        csv, out = os.path.join(tmp, "case.csv"), os.path.join(tmp, "out.json")
        rec.measurement.write(csv)
        env = dict(os.environ, PYTHONPATH=os.path.abspath(code))
        before = os.times()
        proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", "diagnose", csv,
                               "--friction", baseline, "--jobs", "1", "--no-baseline-check",
                               "--no-progress", "--json", out], env=env, cwd=tmp,
                              capture_output=True, text=True, check=False)
        after = os.times()
        cpu = (after.children_user - before.children_user
               + after.children_system - before.children_system)
        if proc.returncode != 0:
            return {"error": (proc.stderr.strip().splitlines() or ["exit status "
                                                                   f"{proc.returncode}"])[-1]}, cpu
        with open(out) as fh:
            return json.load(fh), cpu


def run_case(case: Case, code: str | None = None) -> dict:
    """Generate the record of ``case``, diagnose it, judge it (a worker process).

    ``code``: diagnose with the package of that checkout, in a fresh process
    (:func:`_diagnose_in`); ``None``: with this one, here.
    """
    from fcomp.diagnosis import Diagnosis

    t0 = time.perf_counter()
    rec = record(case)
    t1 = time.perf_counter()
    out: dict[str, Any] = {"case": case.as_dict()}
    c0 = time.process_time()
    cpu = None
    if code is not None:
        doc, cpu = _diagnose_in(code, rec, case.baseline)
    else:
        try:
            # the matrix judges the added effects and the verdict; the baseline check
            # (a second diagnosis from the other kind of baseline) changes neither
            d = Diagnosis(case.baseline, n_jobs=1, check_baseline=False).fit(rec.measurement)
            doc = d.to_dict()
        except Exception as exc:  # a failure is a wrong answer, with its reason
            doc = {"error": f"{type(exc).__name__}: {exc}"}
        cpu = time.process_time() - c0
    t2 = time.perf_counter()
    right, why = judge(case, doc, rec.truth.noise_std)
    out.update(right=right, why=why, generate_s=t1 - t0, diagnose_s=t2 - t1, cpu_s=cpu,
               added=doc.get("added"), verdict=doc.get("verdict"), reason=doc.get("reason"),
               rms_baseline=doc.get("rms_baseline"), rms_final=doc.get("rms_final"),
               noise_floor=doc.get("noise_floor"), ties=doc.get("ties"),
               features=(doc.get("residual_features") or [])[:4],
               regimes=(doc.get("regimes") or {}).get("final"),
               candidates=[(c["effect"], c["rms_heldout"], c["reason"][:160])
                           for c in doc.get("candidates") or []],
               steps=[(s["effect"], s["rms_after"], s["accepted"]) for s in doc.get("steps") or []],
               velocity=(doc.get("signals") or {}).get("velocity"),
               disturbances=[(d.get("frequency_hz"), d.get("amplitude"))
                             for d in doc.get("disturbances") or []],
               error=doc.get("error"))
    return out


def _share(results: list[dict], key) -> dict[str, tuple[int, int]]:
    acc: dict[str, list[int]] = defaultdict(lambda: [0, 0])
    for r in results:
        k = key(r)
        acc[k][0] += bool(r["right"])
        acc[k][1] += 1
    return {k: (v[0], v[1]) for k, v in sorted(acc.items())}


def report(results: list[dict]) -> str:
    lines = []
    n = len(results)
    right = sum(bool(r["right"]) for r in results)
    lines.append(f"overall: {right}/{n} right ({100 * right / max(n, 1):.1f} %)")
    for title, key in (("row", lambda r: r["case"]["row"]), ("style", lambda r: r["case"]["style"]),
                       ("scale", lambda r: r["case"]["scale"]),
                       ("baseline kind", lambda r: r["case"]["kind"]),
                       ("condition", lambda r: r["case"].get("condition", "plain"))):
        lines.append(f"\nshare right per {title}:")
        for k, (a, b) in _share(results, key).items():
            flag = "   <-- below 2/3" if title == "row" and a < 2 * b / 3 else ""
            lines.append(f"  {k:32s} {a:4d}/{b:<4d} {100 * a / b:5.1f} %{flag}")
    # confusion: hidden row vs effects added
    lines.append("\nconfusion (row: how often each effect was added; '-' nothing added; "
                 "verdict counts):")
    by_row: dict[str, Counter] = defaultdict(Counter)
    for r in results:
        c = by_row[r["case"]["row"]]
        added = r["added"] or []
        if r.get("error"):
            c["ERROR"] += 1
        elif not added:
            c["-"] += 1
        for e in added:
            c[e] += 1
        c[f"[{r['verdict']}]"] += 1
    for row, c in sorted(by_row.items()):
        lines.append(f"  {row:32s} " + ", ".join(f"{k} {v}" for k, v in c.most_common()))
    wrong = [r for r in results if not r["right"]]
    if wrong:
        lines.append("\nwrong cases (row / kind / style / scale / seed [shape] condition: why):")
        for r in wrong:
            c = r["case"]
            lines.append(f"  {c['row']} / {c['kind']} / {c['style']} / {c['scale']} / "
                         f"{c['seed']} [{c['shape']}] {c.get('condition', 'plain')}: {r['why']}")
    ts = np.array([r["diagnose_s"] for r in results])
    gs = np.array([r["generate_s"] for r in results])
    cs = np.array([r.get("cpu_s") or np.nan for r in results])
    lines.append(f"\ntime per case: diagnose median {np.median(ts):.1f} s wall, "
                 f"{np.nanmedian(cs) if np.isfinite(cs).any() else np.nan:.1f} s CPU, max "
                 f"{ts.max():.1f} s wall; generate median {np.median(gs):.2f} s")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=3, help="seeds 1..N")
    ap.add_argument("--seed-list", default=None, help="comma-separated seeds (instead of --seeds)")
    ap.add_argument("--jobs", type=int, default=min(os.cpu_count() or 1, 2))
    for f in ("rows", "styles", "scales", "kinds"):
        ap.add_argument(f"--{f}", default=None, help=f"comma-separated subset of {f}"
                        + (" ('all': the rows outside the default selection too)"
                           if f == "rows" else ""))
    ap.add_argument("--conditions", default=None,
                    help=f"comma-separated conditions (default plain): {', '.join(CONDITIONS)}")
    ap.add_argument("--duration", type=float, default=40.0)
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--json", default=None, help="write every case's result here")
    ap.add_argument("--sample", type=int, default=None,
                    help="run this many cases drawn at random (seeded) from the selection")
    ap.add_argument("--per-row", type=int, default=None,
                    help="run this many cases of every row, drawn at random (seeded)")
    ap.add_argument("--code", default=None,
                    help="diagnose with the package of this checkout (its directory holding "
                         "fcomp/), in a fresh process per case")
    ap.add_argument("--list", action="store_true", help="list the cases and stop")
    ap.add_argument("--cases-from", default=None,
                    help="comma-separated JSON files of earlier runs (--json): run their "
                         "cases again instead of a selection, and name the answers that changed")
    args = ap.parse_args(argv)
    pick = {f: (getattr(args, f).split(",") if getattr(args, f) else None)
            for f in ("rows", "styles", "scales", "kinds", "conditions")}
    seeds = ([int(x) for x in args.seed_list.split(",")] if args.seed_list
             else list(range(1, args.seeds + 1)))
    todo = cases(seeds=seeds, duration=args.duration, rate=args.rate, **pick)
    earlier: dict[str, bool] = {}
    if args.cases_from:
        todo = []
        for path in args.cases_from.split(","):
            with open(path) as fh:
                for r in json.load(fh):
                    key = json.dumps(r["case"], sort_keys=True)
                    if key not in earlier:
                        todo.append(Case(**r["case"]))
                    earlier[key] = bool(r["right"])
    elif args.per_row is not None:
        rng = np.random.default_rng(sum(seeds))
        by_row: dict[str, list[int]] = defaultdict(list)
        for i, c in enumerate(todo):
            by_row[c.row].append(i)
        keep = sorted(int(i) for row in sorted(by_row) for i in rng.choice(
            by_row[row], min(args.per_row, len(by_row[row])), replace=False))
        todo = [todo[i] for i in keep]
    elif args.sample is not None and args.sample < len(todo):
        keep = np.random.default_rng(sum(seeds)).choice(len(todo), args.sample, replace=False)
        todo = [todo[i] for i in sorted(keep)]
    if args.list:
        for c in todo:
            print(" ".join(str(getattr(c, f)) for f in CASE_FIELDS))
        print(f"{len(todo)} cases")
        return 0
    print(f"{len(todo)} cases on {args.jobs} processes", file=sys.stderr)
    results = []
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        futs = [pool.submit(run_case, c, args.code) for c in todo]
        for k, fut in enumerate(as_completed(futs), 1):
            r = fut.result()
            results.append(r)
            c = r["case"]
            print(f"[{k}/{len(todo)}] {'ok ' if r['right'] else 'BAD'} {c['row']} / {c['kind']} / "
                  f"{c['style']} / {c['scale']} / {c['seed']} / {c['condition']}: {r['why']} "
                  f"({r['diagnose_s']:.1f} s)", file=sys.stderr, flush=True)
    wall = time.perf_counter() - t0
    print(report(results))
    if earlier:
        now = {json.dumps(r["case"], sort_keys=True): bool(r["right"]) for r in results}
        fixed = sorted(k for k in now if now[k] and not earlier[k])
        worse = sorted(k for k in now if earlier[k] and not now[k])
        print(f"\nagainst the earlier runs: {sum(earlier.values())} -> {sum(now.values())} "
              f"right of {len(now)}; fixed {len(fixed)}, worse {len(worse)}")
        for tag, keys in (("fixed", fixed), ("worse", worse)):
            for k in keys:
                print(f"  {tag}: {k}")
    print(f"wall time {wall / 60:.1f} min for {len(results)} cases")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
