"""Regenerate the figures and numbers of docs/your-cylinder.md: the whole chain on two axes.

    python docs/make_your_cylinder_figures.py      # writes docs/figures/your_cylinder_*

For the 50 mm hydraulic axis (``docs/examples/axis50.toml``) and the 40 mm
pneumatic one (``docs/examples/axis40.toml``), in a temporary folder:

1. a friction-rig record of the rig scale of that kind (``fcomp.synthetic.generate``)
   with a hidden direction asymmetry the LuGre baseline lacks (retracting friction
   1.5 times the extending one);
2. ``fcomp fit REC.csv --friction lugre --save-model base.json`` and the *full*
   ``fcomp diagnose REC.csv --friction lugre --save-model diag.json`` (no candidate
   list, no step limit);
3. the generator's truth as a model file (``fcomp.make_model`` + effect, ``model.save``);
4. ``fcomp compensate`` on the axis (all five controllers, fast tasks, 4 draws): under
   every candidate truth (the honest default: no true friction given) and under the
   generator's truth;
5. ``fcomp export lugre-observer`` with the diagnosed model (equivalence check);
6. ``fcomp plant check`` of the axis: the tuning derived from the plant, with its margins.

Every number the page quotes is in ``docs/figures/your_cylinder_results.json``.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
FIG = DOCS / "figures"
sys.path.insert(0, str(ROOT))

from controllers.compensate import compensate  # noqa: E402
from controllers.compensate_report import (  # noqa: E402
    figure_across,
    figure_ratios,
    figure_robustness,
    figure_tracking,
)
from fcomp.cli.main import main  # noqa: E402
from fcomp.models import make_model  # noqa: E402
from fcomp.synthetic import generate  # noqa: E402
from fcomp.synthetic.scales import get_scale  # noqa: E402

#: Axis -> (plant file, synthetic rig scale, retracting excess dF_neg of the hidden
#: asymmetry (N): half the Coulomb level, r_neg = 1.5).
AXES = {"axis50": (DOCS / "examples" / "axis50.toml", "hydraulic", 150.0),
        "axis40": (DOCS / "examples" / "axis40.toml", "pneumatic", 15.0)}
SEED = 1
DURATION = 12.0


def true_model(scale: str, dF_neg: float):
    """The generator's truth as an fcomp model: its LuGre base (exponential Stribeck,
    n = 2) with the direction asymmetry ``r_neg = 1 + dF_neg/Fc``."""
    P = get_scale(scale).params
    return (make_model("lugre").with_params(Fc=P.Fc, Fs=P.Fs, vs=P.vs, n=2.0,
                                            sigma0=P.sigma0, sigma1=P.sigma1,
                                            sigma2=P.sigma2)
            .with_effects("direction-asymmetry").with_params(r_neg=1.0 + dF_neg / P.Fc))


def run(cmd: list[str]) -> None:
    print("  fcomp " + " ".join(cmd), flush=True)
    code = main(cmd)
    if code != 0:
        raise SystemExit(f"fcomp {' '.join(cmd)} exited {code}")


def chain(name: str, plant: Path, scale: str, dF_neg: float) -> dict:
    rec = generate({"direction-asymmetry": {"dF_neg": dF_neg}}, scale=scale,
                   style="pressures", duration=DURATION, seed=SEED, name=f"{name}-rig")
    rec.measurement.write("rig.csv")
    run(["fit", "rig.csv", "--friction", "lugre", "--save-model", "base.json"])
    t0 = time.perf_counter()
    run(["diagnose", "rig.csv", "--friction", "lugre", "--save-model", "diag.json",
         "--json", "diagnosis.json", "--no-progress"])
    diagnose_time = time.perf_counter() - t0
    true_model(scale, dF_neg).save("true.json")
    cand = compensate(plant, None, ["base.json", "diag.json"], fast=True)
    res = compensate(plant, "true.json", ["base.json", "diag.json"], fast=True,
                     keep_signals=True)
    for fig, stem in ((figure_ratios(res), "ratios"), (figure_robustness(res), "robustness"),
                      (figure_across(cand), "across_truths"),
                      (figure_tracking(res, "steps"), "tracking_steps"),
                      (figure_tracking(res, "slow-sine"), "tracking_slow_sine")):
        fig.savefig(FIG / f"your_cylinder_{name}_{stem}.png", dpi=100)
    run(["export", "lugre-observer", "--plant-params", str(plant), "--friction", "diag.json",
         "-o", "ctrl", "--json", "export.json"])
    export = json.loads(Path("export.json").read_text())
    run(["plant", "check", str(plant), "--json", "check.json"])
    check = json.loads(Path("check.json").read_text())
    diag = json.loads(Path("diagnosis.json").read_text())
    doc = res.as_dict()
    return {
        "plant": str(plant.relative_to(ROOT)), "scale": scale, "dF_neg": dF_neg,
        "record_seconds": DURATION, "diagnose_seconds": round(diagnose_time, 1),
        "diagnosis_added": diag.get("added"), "diagnosis_verdict": diag.get("verdict"),
        "models": {k: json.loads(Path(f"{k}.json").read_text())["params"]
                   for k in ("true", "base", "diag")},
        "compensate": {k: doc[k] for k in ("truths", "runs", "ratios", "across_truths",
                                           "robustness", "warnings")},
        "candidates": {k: cand.as_dict()[k] for k in ("truths", "runs", "ratios",
                                                      "across_truths", "robustness",
                                                      "warnings")},
        "export": {k: export[k] for k in ("equivalent", "max_rel_diff", "step_time_median",
                                          "step_time_max")},
        "tuning": check["tuning"],
    }


def main_() -> None:
    FIG.mkdir(exist_ok=True)
    out: dict = {}
    cwd = Path.cwd()
    for name, (plant, scale, dF_neg) in AXES.items():
        print(name, flush=True)
        with tempfile.TemporaryDirectory() as tmp:
            os.chdir(tmp)
            try:
                out[name] = chain(name, plant, scale, dF_neg)
            finally:
                os.chdir(cwd)
    (FIG / "your_cylinder_results.json").write_text(json.dumps(out, indent=1) + "\n")
    for name, r in out.items():
        print(name, "diagnosis added", r["diagnosis_added"], r["diagnosis_verdict"])
        for c, by_task in r["compensate"]["ratios"]["true"].items():
            cells = ", ".join(f"{t} {v['diag']['rms_error']:.3g}" if v["diag"]["rms_error"]
                              is not None else f"{t} not ranked" for t, v in by_task.items())
            rob = r["compensate"]["robustness"]["controllers"][c]["ratio"]["diag"]
            med = "none" if rob["median"] is None else f"{rob['median']:.3g}"
            print(f"  {c:15s} {cells}; draws median {med}")
        for c, per in r["candidates"]["across_truths"].items():
            a = per["diag"]
            cells = ", ".join(f"{t} {'-' if v is None else f'{v:.3g}'}"
                              for t, v in a["per_truth"].items())
            print(f"  {c:15s} under each candidate truth: {cells} -> {a['holds']}")


if __name__ == "__main__":
    main_()
