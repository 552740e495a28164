"""The design loop end to end on synthetic truths: diagnose a record that cannot tell,
design the next experiment, record the programme with a law that has the hidden effect
(fcomp.synthetic, written apart from fcomp.effects), diagnose again.

    python benchmarks/design_chain.py --seeds 11 12 13 --out /tmp/chain.json

Prints, per case, whether the re-diagnosis added the hidden effect, and the design time.
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
from fcomp.synthetic import generate
from fcomp.synthetic.motion import along

RIG = {"rig": {"bore": 0.032, "rod": 0.012, "mass": 1.2, "orientation": "horizontal"},
       "limits": {"stroke": 0.2, "speed_max": 0.2, "accel_max": 4.0, "pressure_min": 1.5e5,
                  "pressure_max": 2.5e5, "duration_max": 30.0, "rate": 500.0}}


def record(files: list[str], hidden: dict, seed: int, level: float, noise: float) -> Measurement:
    """The programme ``files`` as the rig would record it, with the truth ``hidden``."""
    progs = [Measurement.read(f).columns for f in files]
    rate, fine = 500.0, 10
    plan = along([p["t"] for p in progs], [p["x"] for p in progs],
                 [p["p1"] + p.get("p2", 0 * p["p1"]) for p in progs], 1.0 / rate / fine)
    return generate(hidden, base="lugre", pressures=[level], seed=seed, plan=plan,
                    rate=rate, noise_std=noise).measurement


def case(effect: str, seed: int, work: Path, noise: float) -> dict:
    level = 3e5
    old = generate([effect], base="lugre", experiments=2, duration=16.0, pressures=[level],
                   seed=seed, noise_std=noise).measurement
    old.write(work / "old.csv")
    d0 = fcomp.diagnose([Measurement.read(work / "old.csv")], "lugre", check_baseline=False)
    doc0 = d0.to_dict()
    doc0["model_file"] = d0.model_file({"data": [str(work / "old.csv")]})
    t0 = time.perf_counter()
    res = fcomp.design(doc0, RIG)
    t_design = time.perf_counter() - t0
    files = []
    from fcomp.planning.programme import measurement
    from fcomp.planning.rig import rig_from
    rig = rig_from(RIG)
    for k, e in enumerate(res.experiments_, 1):
        p = work / f"experiment_{k}.csv"
        measurement(e, rig, f"experiment_{k}", "pneumatic-cylinder").write(p)
        files.append(str(p))
    rec = record(files, [effect], seed + 1000, level, noise)
    rec.write(work / "new.csv")
    d1 = fcomp.diagnose([Measurement.read(work / "old.csv"), Measurement.read(work / "new.csv")],
                        "lugre", check_baseline=False)
    q = [x for x in res.questions_ if x.get("label") == effect]
    return {"effect": effect, "seed": seed, "skipped_before": effect in doc0["skipped"],
            "added_before": list(doc0["added"]), "added_after": list(d1.to_dict()["added"]),
            "resolved": effect in d1.to_dict()["added"],
            "predicted_separation": q[0]["predicted_separation"] if q else None,
            "design_s": t_design, "programme_s": sum(e.duration for e in res.experiments_)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, nargs="+", default=[11, 12])
    ap.add_argument("--effects", nargs="+", default=["pressure-dependence"])
    ap.add_argument("--noise", type=float, default=0.4)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    rows = []
    for eff in a.effects:
        for s in a.seeds:
            with tempfile.TemporaryDirectory() as d:
                r = case(eff, s, Path(d), a.noise)
            print(json.dumps(r))
            rows.append(r)
    print(f"resolved {sum(r['resolved'] for r in rows)}/{len(rows)}; design time median "
          f"{np.median([r['design_s'] for r in rows]):.2f} s")
    if a.out:
        Path(a.out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
