"""Does a better model pay off? Each model-based compensator on the true friction vs on wrong ones.

For every plant (the built-in hydraulic and pneumatic servos and the plant
file ``docs/examples/axis50.toml``) and every true friction of :func:`truths`
-- LuGre with the plant's values; LuGre with a strong pressure dependence;
LuGre with another Stribeck curve (exponent 2, twice the Stribeck speed);
NMLGM -- the plant runs that friction, and each of ``pid-ff``,
``lugre-observer``, ``ekf`` and ``mpc`` is built once on the true model and
once on each wrong one (:func:`truths` names them: the LuGre a third off,
Coulomb-viscous, plain LuGre), on the four fast tasks and on ``--samples``
robustness draws (every parameter of the truth and the mass times 1 +- 0.2,
:func:`controllers.compensate.compensate` with the true friction given). Per
controller and wrong model it prints

* the *median-task ratio* ``RMS(true)/RMS(wrong)`` over the tasks (below 1: the true
  model pays off), and the ratio on each task;
* the share of robustness draws in which the true model tracks better;
* ``ok`` where both hold (median ratio <= 1, better in at least half of the draws).

Before/after in one run: ``--tree DIR`` runs the same matrix on another source tree
too (a git worktree of ``main`` at 2d5cfbf), each tree in its own process::

    git worktree add /tmp/main-2d5cfbf 2d5cfbf
    PYTHONPATH=. python3 benchmarks/bench_model_payoff.py --tree /tmp/main-2d5cfbf \\
        [--plants hydraulic,pneumatic,axis50] [--controllers pid-ff,...] [--samples 4]
        [--jobs 2] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
PLANTS = {"hydraulic": "hydraulic", "pneumatic": "pneumatic",
          "axis50": str(ROOT / "docs" / "examples" / "axis50.toml")}
CONTROLLERS = ("pid-ff", "lugre-observer", "ekf", "mpc")


def truths(plant: str) -> dict[str, tuple[Any, dict[str, Any]]]:
    """Truth name -> (true friction, {wrong name: wrong model}) on ``plant`` (the values of
    the plant's friction set)."""
    from controllers.compensate import resolve_plant
    from controllers.plant_model import equilibrium, friction_with_mismatch
    from fcomp.effects import EFFECTS
    from fcomp.models import make_model

    pf = resolve_plant(PLANTS[plant])
    lug = make_model("lugre", params=pf.friction_set)
    p = pf.make_plant(lug)
    x0, _ = equilibrium(p, 0.5 * float(pf.values["stroke"]))
    n = p.state_names
    pa = float(p.flat_params()["p_atm"])
    S = float(x0[n.index("p1")] + x0[n.index("p2")] - 2 * pa)
    D = float(x0[n.index("p1")] - x0[n.index("p2")])
    ps = float(pf.values["ps"]) - pa
    # levels x2 at twice the equilibrium pressure sum, +-50 % per tenth of the supply across
    pd = EFFECTS.get("pressure-dependence")
    strong = pd(pd.Params.from_flat({"kp": 1.0 / max(abs(S), 1e4), "kd": 5.0 / ps,
                                     "p_ref": S, "d_ref": D}))
    flat = lug.flat_params()
    vs = {k: 2.0 * v for k, v in flat.items() if k.startswith("vs")}
    nn = {k: 2.0 for k in flat if k == "n" or k.startswith("n_")}
    return {
        "lugre": (lug, {"lugre-30%": friction_with_mismatch(lug, {
            "Fc": 1.3, "Fs": 0.8, "sigma0": 0.5, "sigma1": 1.5, "sigma2": 1.2}),
            "coulomb-viscous": make_model("coulomb-viscous", params=pf.friction_set)}),
        "lugre+pressure": (lug.with_effects(strong), {"lugre": lug}),
        "lugre-stribeck2": (lug.with_params(**vs, **nn), {"lugre": lug}),
        "nmlgm": (make_model("nmlgm", params=pf.friction_set), {"lugre": lug}),
    }


def matrix(plants: list[str], controllers: tuple[str, ...], samples: int,
           jobs: int | None) -> list[dict[str, Any]]:
    """Every row of the matrix on the code importable here."""
    from controllers.compensate import compensate

    rows = []
    for plant in plants:
        for tname, (true, wrongs) in truths(plant).items():
            res = compensate(PLANTS[plant], true, {"true": true, **wrongs},
                             controllers=controllers, fast=True, samples=samples,
                             workers=jobs)
            runs = {(r["controller"], r["model"], r["task"]): r for r in res.runs}
            for c in controllers:
                for w in wrongs:
                    per = {}
                    for t in res.tasks:
                        a, b = runs.get((c, "true", t)), runs.get((c, w, t))
                        ok = a and b and a["status"] == b["status"] == "ok"
                        per[t] = (a["rms_error"] / b["rms_error"]
                                  if ok and b["rms_error"] > 0 else None)
                    vals = [v for v in per.values() if v is not None]
                    rob = res.robustness["controllers"][c]["ratio"].get(w) or {}
                    draws = [v for v in rob.get("values") or []]  # wrong/true
                    share = (sum(v > 1.0 for v in draws) / len(draws)) if draws else None
                    med = statistics.median(vals) if vals else None
                    rows.append({"plant": plant, "truth": tname, "controller": c,
                                 "wrong": w, "per_task": per, "median": med,
                                 "true_better_in": share, "draws": len(draws),
                                 "ok": bool(med is not None and med <= 1.0
                                            and (share is None or share >= 0.5))})
            print(f"  {plant} {tname} done", file=sys.stderr, flush=True)
    return rows


def table(rows: list[dict[str, Any]], title: str) -> str:
    lines = [f"### {title}", "",
             "| plant | truth | controller | wrong model | median-task ratio | tasks "
             "(ramp, sine, slow, steps) | true better in draws | ok |",
             "|---|---|---|---|---:|---|---:|---|"]
    for r in rows:
        tasks = ", ".join("-" if v is None else f"{v:.2f}" for v in r["per_task"].values())
        med = "-" if r["median"] is None else f"{r['median']:.2f}"
        share = ("-" if r["true_better_in"] is None
                 else f"{r['true_better_in'] * 100:.0f} % of {r['draws']}")
        lines.append(f"| {r['plant']} | {r['truth']} | {r['controller']} | {r['wrong']} | "
                     f"{med} | {tasks} | {share} | {'ok' if r['ok'] else 'NO'} |")
    good = sum(r["ok"] for r in rows)
    lines += ["", f"{good} of {len(rows)} ok"]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--plants", default=",".join(PLANTS))
    ap.add_argument("--controllers", default=",".join(CONTROLLERS))
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=None)
    ap.add_argument("--tree", default=None, help="another source tree to run beside this one")
    ap.add_argument("--json", default=None)
    ap.add_argument("--rows-only", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    plants = args.plants.split(",")
    controllers = tuple(args.controllers.split(","))
    if args.rows_only:  # a child process on its tree: the rows as JSON on stdout
        json.dump(matrix(plants, controllers, args.samples, args.jobs), sys.stdout)
        return
    out: dict[str, Any] = {}
    for label, tree in (("before", args.tree), ("after", str(ROOT))):
        if tree is None:
            continue
        cmd = [sys.executable, str(Path(__file__).resolve()), "--rows-only", "--plants",
               args.plants, "--controllers", args.controllers, "--samples", str(args.samples)]
        if args.jobs:
            cmd += ["--jobs", str(args.jobs)]
        env = {**os.environ, "PYTHONPATH": tree}
        print(f"{label}: {tree}", file=sys.stderr, flush=True)
        done = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True,
                              check=True)
        out[label] = json.loads(done.stdout)
        print(table(out[label], f"{label} ({tree})"))
        print()
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
