"""The design loop end to end on synthetic truths: diagnose a record that cannot tell,
design the next experiment, record the programme with a law that has the hidden effect
(:mod:`fcomp.synthetic`, written apart from :mod:`fcomp.effects`), diagnose again.

    python benchmarks/design_chain.py --seeds 31 32 --out /tmp/chain.json

Per case and question: whether the re-diagnosis answered it (a tie broken towards the
truth, an untested effect added when it is the truth, a parameter's standard error shrunk
by half or more), the predicted and achieved separation of the tie's rivals along the
recorded programme (:func:`fcomp.planning.criteria.achieved_separation`), the predicted and
achieved standard errors, and the design time.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import fcomp
from fcomp.measurement import Measurement
from fcomp.planning.criteria import achieved_separation, force
from fcomp.planning.programme import measurement
from fcomp.planning.rig import rig_from
from fcomp.synthetic import generate
from fcomp.synthetic.motion import along

RIG = {"rig": {"bore": 0.032, "rod": 0.012, "mass": 1.2, "orientation": "horizontal"},
       "limits": {"stroke": 0.2, "speed_max": 0.2, "accel_max": 4.0, "pressure_min": 1.5e5,
                  "pressure_max": 2.5e5, "duration_max": 30.0, "rate": 500.0}}
#: The truths: the hidden law (effect:shape) and the record's pressure levels (p1 + p2).
CASES = {"pressure-dependence:lip-seal": [3e5], "pressure-dependence:saturating": [3e5],
         "direction-asymmetry:levels": None, "direction-asymmetry:ratio": None}


def diagnose(paths: list[Path]) -> dict:
    d = fcomp.diagnose([Measurement.read(p) for p in paths], "lugre", check_baseline=False)
    doc = d.to_dict()
    doc["model_file"] = d.model_file({"data": [str(p) for p in paths]})
    return doc


def case(law: str, seed: int, work: Path, noise: float, rate: float) -> dict:
    levels = CASES.get(law)
    effect = law.split(":")[0]
    rig_doc = json.loads(json.dumps(RIG))
    rig_doc["limits"]["rate"] = rate
    old = generate([law], base="lugre", experiments=2, duration=16.0, pressures=levels,
                   seed=seed, noise_std=noise, rate=rate).measurement
    old.write(work / "old.csv")
    doc0 = diagnose([work / "old.csv"])
    t0 = time.perf_counter()
    res = fcomp.design(doc0, rig_doc)
    t_design = time.perf_counter() - t0
    rig = rig_from(rig_doc)
    if not res.experiments_:  # the record left no question: nothing to record
        return {"law": law, "seed": seed, "noise": noise, "rate": rate, "design_s": t_design,
                "programme_s": 0.0, "added_before": doc0["added"], "ties_before": doc0["ties"],
                "added_after": doc0["added"], "ties_after": doc0["ties"], "questions": []}
    progs = []
    for k, e in enumerate(res.experiments_, 1):
        p = work / f"experiment_{k}.csv"
        measurement(e, rig, f"experiment_{k}", "pneumatic-cylinder").write(p)
        progs.append(Measurement.read(p).columns)
    fine = 10
    plan = along([p["t"] for p in progs], [p["x"] for p in progs],
                 [p["p1"] + p["p2"] for p in progs], 1.0 / rate / fine)
    new = generate([law], base="lugre", pressures=levels or [1.5e5, 3e5, 5e5], seed=seed + 1000,
                   plan=plan, rate=rate, noise_std=noise).measurement
    new.write(work / "new.csv")
    doc1 = diagnose([work / "old.csv", work / "new.csv"])
    (work / "before.json").write_text(json.dumps(doc0, default=str))
    (work / "after.json").write_text(json.dumps(doc1, default=str))
    y = new.columns["F"]
    ex = new.columns["experiment"]
    out = {"law": law, "seed": seed, "noise": noise, "rate": rate, "design_s": t_design,
           "programme_s": sum(e.duration for e in res.experiments_),
           "added_before": doc0["added"], "ties_before": doc0["ties"],
           "added_after": doc1["added"], "ties_after": doc1["ties"], "questions": []}
    stderr1 = doc1["model_file"].get("stderr") or {}
    for q, qq in zip(res.questions_, res_questions(res), strict=True):
        row = {"kind": q["kind"], "label": q.get("label") or q.get("parameter")}
        if q["kind"] == "parameter":
            p = q["parameter"]
            row.update(before=q["stderr_before"], predicted=q["stderr_after"],
                       achieved=stderr1.get(p))
            row["resolved"] = bool(row["achieved"] is not None and q["stderr_before"]
                                   and row["achieved"] * 2 <= q["stderr_before"])
        else:
            names = list(qq.models)
            fa = np.concatenate([force(qq.models[names[0]], e.signals)
                                 for e in res.experiments_])
            fb = np.concatenate([force(qq.models[names[1]], e.signals)
                                 for e in res.experiments_])
            n = min(fa.size, y.size)
            ach, favours = achieved_separation(y[:n], fa[:n], fb[:n], res.noise_)
            truth_is = names[0] if names[0] == effect or (names[0] == "without" and
                                                           names[1] != effect) else names[1]
            row.update(rivals=names, predicted=q["predicted_separation"], achieved=ach,
                       favours=names[0] if favours == "a" else names[1], truth=truth_is)
            if q["kind"] == "tie":
                row["resolved"] = (effect in doc1["added"] and not any(
                    effect in t and len(t) > 1 for t in doc1["ties"]))
                # the re-diagnosis's own evidence: each tied effect's held-out RMS at the
                # step that added one of them (the tie rule aside)
                step = next((st for st in doc1["steps"] if st["effect"] in names), None)
                held = {c["effect"]: c["rms_heldout"] for c in (step or {}).get("candidates", [])
                        if c["effect"] in names}
                row["heldout_rms"] = held
                row["heldout_favours_truth"] = bool(held) and min(held, key=held.get) == effect
            else:
                added = names[1] in doc1["added"]
                row["resolved"] = added == (names[1] == effect)
        out["questions"].append(row)
        _ = ex
    return out


def res_questions(res: object) -> list:
    """The design's questions with their models (in the JSON's order)."""
    return getattr(res, "_questions", [])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[31, 32])
    ap.add_argument("--laws", nargs="+", default=list(CASES))
    ap.add_argument("--noise", type=float, nargs="+", default=[0.4, 0.8])
    ap.add_argument("--rate", type=float, nargs="+", default=[500.0, 1000.0])
    ap.add_argument("--out", default=None)
    ap.add_argument("--keep", default=None, help="keep each case's files under this folder")
    a = ap.parse_args()
    rows = []
    k = 0
    for law in a.laws:
        for s in a.seeds:
            noise, rate = a.noise[k % len(a.noise)], a.rate[(k // 2) % len(a.rate)]
            k += 1
            with tempfile.TemporaryDirectory() as d:
                work = Path(a.keep) / f"{law.replace(':', '_')}_{s}" if a.keep else Path(d)
                work.mkdir(parents=True, exist_ok=True)
                try:
                    r = case(law, s, work, noise, rate)
                except Exception as exc:  # noqa: BLE001  (a benchmark reports, never stops)
                    r = {"law": law, "seed": s, "error": repr(exc)}
            print(json.dumps(r), flush=True)
            rows.append(r)
    qs = [q for r in rows for q in r.get("questions", [])]
    for kind in ("tie", "untested", "parameter"):
        mine = [q for q in qs if q["kind"] == kind]
        print(f"{kind}: resolved {sum(q['resolved'] for q in mine)}/{len(mine)}")
    ties = [q for q in qs if q["kind"] == "tie"]
    if ties:
        print(f"tie: the truth's held-out RMS the lowest at its step in "
              f"{sum(q['heldout_favours_truth'] for q in ties)}/{len(ties)}")
    ratios = [q["achieved"] / q["predicted"] for q in qs if q["kind"] != "parameter"
              and q["predicted"] and q["achieved"] is not None]
    if ratios:
        print(f"achieved/predicted separation: median {np.median(ratios):.3g}, range "
              f"{min(ratios):.3g}-{max(ratios):.3g}, within x2: "
              f"{sum(0.5 <= r <= 2 for r in ratios)}/{len(ratios)}")
    print(f"design time median {np.median([r['design_s'] for r in rows if 'design_s' in r]):.2f} s")
    if a.out:
        Path(a.out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
