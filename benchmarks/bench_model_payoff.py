"""Does a better model pay off? Each model-based compensator on the true friction vs on wrong ones.

The matrix of :mod:`controllers.payoff`: for every plant (the built-in
hydraulic and pneumatic servos and the plant file ``docs/examples/axis50.toml``)
and every true friction -- LuGre with the plant's values; LuGre with a strong
pressure dependence; LuGre with another Stribeck curve (exponent 2, twice the
Stribeck speed); NMLGM -- the plant runs that friction, and each of ``pid-ff``,
``lugre-observer``, ``ekf`` and ``mpc`` is built once on the true model and
once on each wrong one (the LuGre a third off, Coulomb-viscous, plain LuGre),
on the four fast tasks and on ``--samples`` robustness draws (every parameter
of the truth and the mass times 1 +- 0.2, :func:`controllers.compensate.compensate`
with the true friction given). Per controller and wrong model it prints

* the *median-task ratio* ``RMS(true)/RMS(wrong)`` over the tasks (below 1: the true
  model pays off), and the ratio on each task;
* the share of robustness draws in which the true model tracks better;
* ``ok`` where both hold (median ratio <= 1, better in at least half of the draws).

Before/after in one run: ``--tree DIR`` runs the same matrix on another source tree
too (a git worktree of ``main`` at 2d5cfbf), each tree in its own process::

    git worktree add /tmp/main-2d5cfbf 2d5cfbf
    PYTHONPATH=. python3 benchmarks/bench_model_payoff.py --tree /tmp/main-2d5cfbf \\
        [--plants hydraulic,pneumatic,axis50] [--truths lugre,...] [--controllers pid-ff,...]
        [--samples 4] [--jobs 2] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def _payoff() -> Any:
    """:mod:`controllers.payoff` of *this* tree, whatever tree ``controllers`` is imported
    from (it uses only the public API of ``compensate``, which earlier trees have)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("payoff_matrix",
                                                  ROOT / "controllers" / "payoff.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def matrix(plants: list[str], controllers: tuple[str, ...], samples: int,
           jobs: int | None, truths: list[str] | None = None) -> list[dict[str, Any]]:
    """Every row of the matrix on the code importable here (the truths named, or all)."""
    rows = []
    for plant in plants:
        rows += _payoff().payoff_rows(plant, truths, controllers=controllers,
                                      samples=samples, workers=jobs)
        print(f"  {plant} done", file=sys.stderr, flush=True)
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
                     f"{med} | {tasks} | {share} | "
                     f"{'ok' if r['ok'] else 'NO' if r['ok'] is False else 'n/a'} |")
    good = sum(r["ok"] is True for r in rows)
    lines += ["", f"{good} of {sum(r['ok'] is not None for r in rows)} ok (n/a: the "
              "controller cannot be built on the wrong model)"]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--plants", default="hydraulic,pneumatic,axis50")
    ap.add_argument("--controllers", default="pid-ff,lugre-observer,ekf,mpc")
    ap.add_argument("--truths", default=None, help="the truths to run (default all)")
    ap.add_argument("--samples", type=int, default=4)
    ap.add_argument("--jobs", type=int, default=None)
    ap.add_argument("--tree", default=None, help="another source tree to run beside this one")
    ap.add_argument("--json", default=None)
    ap.add_argument("--rows-only", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    plants = args.plants.split(",")
    controllers = tuple(args.controllers.split(","))
    if args.rows_only:  # a child process on its tree: the rows as JSON on stdout
        json.dump(matrix(plants, controllers, args.samples, args.jobs,
                         args.truths.split(",") if args.truths else None), sys.stdout)
        return
    out: dict[str, Any] = {}
    for label, tree in (("before", args.tree), ("after", str(ROOT))):
        if tree is None:
            continue
        cmd = [sys.executable, str(Path(__file__).resolve()), "--rows-only", "--plants",
               args.plants, "--controllers", args.controllers, "--samples", str(args.samples)]
        if args.jobs:
            cmd += ["--jobs", str(args.jobs)]
        if args.truths:
            cmd += ["--truths", args.truths]
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
