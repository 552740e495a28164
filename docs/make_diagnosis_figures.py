"""Figures and numbers of docs/diagnosis.md: the diagnosis on synthetic and real records.

Runs :class:`fcomp.diagnosis.Diagnosis` on

* a synthetic rig record with the pressure dependence of the seal hidden
  (:func:`fcomp.synthetic.generate`, 12 s at 500 Hz, seed 1);
* the TU Delft pneumatic cylinders (Zillen, Vallery & Smit 2021, CC0): the
  O-ring and the NAPN seal, each at 1, 3, 5 and 7 bar diagnosed together
  (four files = experiments at four pressure levels);
* the seed 001 tables (Dağdelen & Sarıgeçili 2020) as steady-state points
  (see :func:`seed001_points` for the two assumptions this needs);

writes ``docs/figures/diagnosis_<case>_<figure>.png`` and prints every
number the page quotes (also saved to ``docs/figures/diagnosis_summary.json``).

Run ``python docs/make_diagnosis_figures.py`` (a few minutes on 2 cores).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

import fcomp.datasets as datasets
from fcomp.diagnosis import Diagnosis
from fcomp.diagnosis.figures import figures
from fcomp.measurement import Measurement
from fcomp.synthetic import generate

OUT = Path(__file__).resolve().parent / "figures"
KEEP = ("error_fall", "before_after", "residuals", "candidates", "loops")
#: C1 stroke (m) and the number of break-away positions along it (seed 001, Tables 2-3).
STROKE_C1, N_POSITIONS = 0.25, 12
#: Speed (m/s) assigned to a break-away point: the slowest the hand-pushed rod is
#: moving when it breaks away (assumption; the paper gives no speed).
BREAKAWAY_SPEED = 1e-3


def seed001_points() -> list[Measurement]:
    """Seed 001 cylinder C1 as steady-state points ``(v, x, F)``, one record per experiment.

    The paper repeated every test in 10 experiments; each experiment is a
    record here, so the diagnosis holds out whole experiments (the 2nd, 5th
    and 8th), never single points.

    * constant-speed rows (Tables 4-5): ``F = F_ext`` at ``v`` extending,
      ``F = -F_ext`` at ``-v`` retracting (friction positive opposing
      extension, data-format.md);
    * break-away rows (Tables 2-3): ``F = +-Fc`` at ``v = +-BREAKAWAY_SPEED``
      (assumption 1: the paper gives no speed) and at position
      ``x = (step - 1)/11*0.25 m`` (assumption 2: the 12 positions evenly
      spread over the 250 mm stroke). The constant-speed rows get the
      mid-stroke position (their position is not reported).
    """
    rows: list[tuple[int, float, float, float]] = []
    for side, sign in (("extension", 1.0), ("retraction", -1.0)):
        b = np.genfromtxt(datasets.path("seed001", f"b_{side}_c1.csv"), names=True,
                          delimiter=",")
        rows += [(int(e), sign * float(v), 0.5 * STROKE_C1, sign * float(f))
                 for e, v, f in zip(b["experiment"], b["v"], b["F_ext"], strict=True)]
        fc = np.genfromtxt(datasets.path("seed001", f"fc_{side}_c1.csv"), names=True,
                           delimiter=",")
        rows += [(int(e), sign * BREAKAWAY_SPEED,
                  (float(k) - 1) / (N_POSITIONS - 1) * STROKE_C1, sign * float(f))
                 for e, k, f in zip(fc["experiment"], fc["position_step"], fc["Fc"], strict=True)]
    arr = np.array(rows)
    out = []
    for e in sorted(set(arr[:, 0].astype(int))):
        sel = arr[arr[:, 0] == e]
        out.append(Measurement({"t": np.arange(len(sel), dtype=float), "v": sel[:, 1],
                                "x": sel[:, 2], "F": sel[:, 3]},
                               {"name": f"seed001-C1-experiment{e}",
                                "diagnosis": {"samples": "steady-state"}}))
    return out


def summary(d: Diagnosis, seconds: float) -> dict:
    doc = d.to_dict()
    keep = ("baseline", "rms_baseline", "added", "ties", "rms_final", "noise_floor", "verdict",
            "model", "params", "split", "noise_method")
    out = {k: doc[k] for k in keep}
    out["steps"] = [{**s, "reason": next((c.reason for c in st.candidates
                                           if c.effect == s["effect"]), "")}
                    for s, st in zip(doc["steps"], d.steps_, strict=True)]
    out["candidates"] = [(c["effect"], c["rms_heldout"], c["qualifies"])
                         for c in doc["candidates"]]
    out["residual_features"] = doc["residual_features"][:5]
    out["seconds"] = round(seconds, 1)
    return out


def run(case: str, baseline: str, data, **kw) -> dict:
    t0 = time.perf_counter()
    d = Diagnosis(baseline, **kw).fit(data)
    s = summary(d, time.perf_counter() - t0)
    for name, fig in figures(d).items():
        if name in KEEP:
            fig.savefig(OUT / f"diagnosis_{case}_{name}.png", dpi=90)
    print(f"\n== {case} (baseline {baseline}, {s['seconds']} s)")
    print(json.dumps(s, indent=1, default=float))
    return s


def hidden_table() -> list[dict]:
    """Every hidden-effect case of tests/test_diagnosis_hidden.py, as a table row."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_diagnosis_hidden import CASES  # the tests' own cases, not a copy

    rows = []
    print("\n| hidden | generator base / baseline | s | added | tie | verdict | held-out RMS "
          "baseline -> final, N | noise floor, N | time, s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for case, (hidden, base, baseline, duration) in CASES.items():
        rec = generate(list(hidden), base=base, duration=duration, seed=1)
        t0 = time.perf_counter()
        d = Diagnosis(baseline).fit(rec.measurement)
        sec = time.perf_counter() - t0
        row = {"case": case, "hidden": list(hidden), "base": base, "baseline": baseline,
               "duration": duration, "added": d.added_, "ties": d.ties_,
               "verdict": d.verdict_, "rms_baseline": d.rms_baseline_,
               "rms_final": d.rms_final_, "noise_floor": d.noise_floor_.value,
               "seconds": sec}
        rows.append(row)
        print(f"| {', '.join(hidden) or '(nothing)'} | {base} / {baseline} | {duration:.0f} | "
              f"{', '.join(d.added_) or '-'} | {'; '.join(', '.join(t) for t in d.ties_) or '-'} "
              f"| {d.verdict_} | {d.rms_baseline_:.3g} -> {d.rms_final_:.3g} | "
              f"{d.noise_floor_.value:.3g} | {sec:.1f} |", flush=True)
    return rows


def main() -> None:
    OUT.mkdir(exist_ok=True)
    results: dict = {"hidden": hidden_table()}
    rec = generate(["pressure-dependence"], duration=12.0, seed=1)
    results["synthetic"] = run("synthetic", "lugre", rec.measurement)
    for seal in ("O-ring", "NAPN"):
        files = [datasets.load("zillen", f"{seal}_{bar}bar.csv") for bar in (1, 3, 5, 7)]
        results[seal] = run(seal.lower().replace("-", ""), "coulomb", files)
    results["seed001"] = run("seed001", "coulomb", seed001_points())
    (OUT / "diagnosis_summary.json").write_text(json.dumps(results, indent=1, default=float))


if __name__ == "__main__":
    main()
