"""The shipped real records diagnosed as a user runs them, and the 7 bar levels predicted.

Two parts (issue 43, "done when"):

**The table.** ``fcomp diagnose`` on each data set as a user types it (a fresh
process, ``--no-progress --json``), one row each: data set, files, baseline,
effects added (ties and pairs), verdict, held-out RMS baseline -> final (noise
floor), wall time. The cases:

* ``emps``: the EMPS benchmark from ``coulomb-viscous``;
* ``oring``: the TU Delft O-ring at 1, 3, 5, 7 bar from ``lugre`` (and, with
  ``--baselines``, others);
* ``circle`` and ``circle-reversed``: the Circle files at 2, 4, 6 bar, in that order
  and in the order 6, 4, 2;
* ``kdn``, ``napn``: the KDN and NAPN seals at 1, 3, 5, 7 bar;
* ``oring-circle``: O-ring and Circle together, 1 to 7 bar, and ``oring-circle-1-6``
  the same without the 7 bar file;
* ``oring-renamed``: the O-ring files copied under other names (``run_a`` .. ``run_d``)
  and given in the order 7, 5, 3, 1 bar; ``oring-mass``: the O-ring files with an
  irrelevant ``rig.mass = 0.1`` kg written in their sidecars. Both must answer as
  ``oring`` does.

**The prediction** (``--predict``). For each seal, the diagnosis of 1, 3 and 5 bar
alone (``--save-model``), its final model (with its measurement terms, as fitted)
run along the 7 bar record's motion, and the friction levels there: the median of
the measured and of the predicted force over the steady sliding samples of each
direction (extending, retracting), and their difference.

Run ``python benchmarks/bench_real_seals.py`` (``--cases oring,kdn``, ``--predict``,
``--json OUT``; ``--baseline-rev REV`` runs the table on that revision's code too, A B
per case, as ``benchmarks/bench_diagnose.py`` does).
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

REPO = Path(__file__).resolve().parents[1]
ZILLEN = {"oring": [f"O-ring_{k}bar.csv" for k in (1, 3, 5, 7)],
          "circle": [f"Circle_{k}bar.csv" for k in (2, 4, 6)],
          "circle-reversed": [f"Circle_{k}bar.csv" for k in (6, 4, 2)],
          "kdn": [f"KDN_{k}bar.csv" for k in (1, 3, 5, 7)],
          "napn": [f"NAPN_{k}bar.csv" for k in (1, 3, 5, 7)],
          "oring-circle": ["O-ring_1bar.csv", "Circle_2bar.csv", "O-ring_3bar.csv",
                           "Circle_4bar.csv", "O-ring_5bar.csv", "Circle_6bar.csv",
                           "O-ring_7bar.csv"],
          "oring-circle-1-6": ["O-ring_1bar.csv", "Circle_2bar.csv", "O-ring_3bar.csv",
                               "Circle_4bar.csv", "O-ring_5bar.csv", "Circle_6bar.csv"],
          "oring-renamed": [f"O-ring_{k}bar.csv" for k in (7, 5, 3, 1)],
          "oring-mass": [f"O-ring_{k}bar.csv" for k in (1, 3, 5, 7)]}
BASELINE = {"emps": "coulomb-viscous", "oring": "lugre", "circle": "coulomb-viscous",
            "circle-reversed": "coulomb-viscous", "kdn": "coulomb-viscous",
            "napn": "coulomb-viscous", "oring-circle": "lugre", "oring-circle-1-6": "lugre",
            "oring-renamed": "lugre", "oring-mass": "lugre"}
#: The seals whose 7 bar level is predicted from 1, 3 and 5 bar.
PREDICTED = {"O-ring": "O-ring_{}bar.csv", "KDN": "KDN_{}bar.csv", "NAPN": "NAPN_{}bar.csv"}


def imported(folder: Path) -> dict[str, Path]:
    """Every shipped record the cases use, imported into ``folder`` (name -> CSV)."""
    from fcomp import datasets

    out = {}
    names = {n for v in ZILLEN.values() for n in v} | {
        p.format(k) for p in PREDICTED.values() for k in (1, 3, 5, 7)}
    for name in sorted(names):
        dst = folder / name
        if not dst.exists():  # a kept folder (--keep) is imported once
            _cli(["import", "zillen", str(datasets.path("zillen", name)), "-o", str(dst)],
                 folder, None)
        out[name] = dst
    emps = folder / "emps.csv"
    if not emps.exists():
        _cli(["import", "emps", str(datasets.path("emps", "DATA_EMPS.mat")), "-o", str(emps)],
             folder, None)
    out["emps"] = emps
    return out


def variant(case: str, files: list[Path], folder: Path) -> list[Path]:
    """The case's files as it gives them: ``oring-renamed`` copies them under other names
    (the sidecar's ``name`` too), ``oring-mass`` writes ``rig.mass = 0.1`` kg in copies of
    their sidecars; every other case its files unchanged."""
    if case not in ("oring-renamed", "oring-mass"):
        return files
    out = []
    for k, f in enumerate(files):
        stem = f"run_{'abcd'[k]}" if case == "oring-renamed" else f"{f.stem}_mass"
        dst = folder / case / f"{stem}.csv"
        dst.parent.mkdir(exist_ok=True)
        dst.write_bytes(f.read_bytes())
        side = f.with_suffix(".toml").read_text()
        if case == "oring-renamed":
            side = side.replace(f'name = "{f.stem}"', f'name = "{stem}"', 1)
        else:
            side = side.replace("[rig]\n", "[rig]\nmass = 0.1\n", 1)
        dst.with_suffix(".toml").write_text(side)
        out.append(dst)
    return out


def _cli(args: list[str], cwd: Path, pythonpath: Path | None) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(pythonpath if pythonpath is not None else REPO)
    proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise SystemExit(f"fcomp {' '.join(args[:2])} failed: {proc.stderr[-1500:]}")
    return proc


def diagnose(files: list[Path], baseline: str, out: Path, jobs: int,
             pythonpath: Path | None = None, extra: tuple[str, ...] = ()
             ) -> tuple[float, dict]:
    t0 = time.perf_counter()
    _cli(["diagnose", *map(str, files), "--friction", baseline, "--no-progress", "--jobs",
          str(jobs), "--json", str(out), *extra], out.parent, pythonpath)
    return time.perf_counter() - t0, json.loads(out.read_text())


def row(case: str, files: list[str], baseline: str, doc: dict, wall: float) -> dict:
    pairs = [p["effects"] for p in doc.get("pairs") or [] if p.get("accepted")]
    forms = [f"{f['effect']}: {f['form']}" for f in doc.get("forms") or [] if f.get("kept")]
    return {"case": case, "files": files, "baseline": baseline, "added": doc["added"],
            "ties": doc["ties"], "pairs": pairs, "forms": forms, "verdict": doc["verdict"],
            "rms_baseline": doc["rms_baseline"], "rms_final": doc["rms_final"],
            "noise_floor": doc["noise_floor"], "time_s": wall,
            "baseline_dependent": doc.get("baseline_dependent"),
            "structures": [s["text"] for s in doc.get("structures") or []],
            "confounding": [" / ".join(c["effects"]) for c in doc.get("confounding") or []]}


def levels(model_file: Path, record: Path) -> dict[str, dict[str, float]]:
    """The measured and predicted friction levels (N) of ``record``'s steady sliding, per
    direction: medians over the samples sliding at a steady speed."""
    from fcomp.diagnosis.data import prepare
    from fcomp.diagnosis.regimes import SLIDING, segment
    from fcomp.measurement import Measurement
    from fcomp.modelfile import read_model
    from fcomp.trajectory import friction_along_motion

    mf = read_model(model_file)
    model = mf.measured_model()
    data = prepare([Measurement.read(record)])
    seg = segment(data)
    out: dict[str, dict[str, float]] = {}
    pred = []
    for e in data.experiments:
        s = e.data.sig
        F = friction_along_motion(model.with_measurement(None), s["t"], s["v"], a=s["a"],
                                  x=s["x"], p1=s["p1"], p2=s["p2"]).F
        mass = model.measurement.get("mass")
        if mass and e.data.inertia is not None:
            F = F + mass * e.data.inertia
        pred.append(e.data.band_limited(F))
    F_hat = np.concatenate(pred)
    v, y = data.signal("v"), data.y
    steady = (seg.regime == SLIDING) & seg.valid
    for name, side in (("extending", v > 0), ("retracting", v < 0)):
        m = steady & side
        out[name] = {"measured": float(np.median(y[m])), "predicted": float(np.median(F_hat[m]))}
    return out


def predict(paths: dict[str, Path], folder: Path, jobs: int,
            seals: tuple[str, ...] = tuple(PREDICTED)) -> list[dict]:
    rows = []
    for seal in seals:
        pattern = PREDICTED[seal]
        files = [paths[pattern.format(k)] for k in (1, 3, 5)]
        model = folder / f"{seal}_135.json"
        wall, doc = diagnose(files, "lugre", folder / f"{seal}_135_diag.json", jobs,
                             extra=("--save-model", str(model)))
        lv = levels(model, paths[pattern.format(7)])
        rows.append({"seal": seal, "added": doc["added"], "verdict": doc["verdict"],
                     "forms": [f"{f['effect']}: {f['form']}" for f in doc.get("forms") or []
                               if f.get("kept")],
                     "levels": lv, "time_s": wall})
    return rows


def table(rows: list[dict]) -> str:
    out = ["| data set | files | baseline | added (ties; pairs; forms) | verdict | held-out "
           "RMS, N (floor) | time, s |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        extra = []
        if r["ties"]:
            extra.append("tie " + "; ".join(" / ".join(t) for t in r["ties"]))
        if r["pairs"]:
            extra.append("pair " + "; ".join(" + ".join(p) for p in r["pairs"]))
        if r["forms"]:
            extra.append("form " + "; ".join(r["forms"]))
        added = ", ".join(r["added"]) or "nothing"
        out.append(f"| {r['case']} | {len(r['files'])} | {r['baseline']} | {added}"
                   + (f" ({'; '.join(extra)})" if extra else "")
                   + f" | {r['verdict']} | {r['rms_baseline']:.3g} -> {r['rms_final']:.3g} "
                   f"({r['noise_floor']:.3g}) | {r['time_s']:.0f} |")
    return "\n".join(out)


def prediction_table(rows: list[dict]) -> str:
    out = ["| seal (from 1, 3, 5 bar) | added | 7 bar extending: measured / predicted, N | "
           "retracting: measured / predicted, N |", "|---|---|---|---|"]
    for r in rows:
        e, t = r["levels"]["extending"], r["levels"]["retracting"]
        out.append(f"| {r['seal']} | {', '.join(r['added']) or 'nothing'}"
                   + (f" ({'; '.join(r['forms'])})" if r["forms"] else "")
                   + f" | {e['measured']:.3g} / {e['predicted']:.3g} | {t['measured']:.3g} / "
                   f"{t['predicted']:.3g} |")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cases", default=",".join(["emps", *ZILLEN]),
                   help="comma-separated cases (default all)")
    p.add_argument("--baselines", default=None,
                   help="comma-separated baselines for every Zillen case (default: each "
                   "case's own)")
    p.add_argument("--predict", action="store_true", help="also predict 7 bar from 1-5 bar")
    p.add_argument("--no-table", action="store_true", help="only the prediction")
    p.add_argument("--seals", default=",".join(PREDICTED),
                   help="comma-separated seals whose 7 bar level is predicted (default all)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--json", default=None, metavar="OUT")
    p.add_argument("--keep", default=None, metavar="DIR", help="work in DIR and keep it")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.keep or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        paths = imported(folder)
        rows: list[dict] = []
        if not args.no_table:
            for case in args.cases.split(","):
                files = ([paths["emps"]] if case == "emps" else
                         variant(case, [paths[n] for n in ZILLEN[case]], folder))
                bases = ([BASELINE.get(case, "lugre")] if case == "emps" or not args.baselines
                         else args.baselines.split(","))
                for base in bases:
                    wall, doc = diagnose(files, base, folder / f"{case}_{base}.json", args.jobs)
                    rows.append(row(case, [f.name for f in files], base, doc, wall))
                    print(table(rows[-1:]).splitlines()[-1], flush=True)
            print(table(rows))
        preds = (predict(paths, folder, args.jobs, tuple(args.seals.split(",")))
                 if args.predict else [])
        if preds:
            print(prediction_table(preds))
        if args.json:
            Path(args.json).write_text(json.dumps({"table": rows, "prediction": preds},
                                                  indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
