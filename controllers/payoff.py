"""Does a better friction model pay off? Each model-based compensator on the true friction and on wrong ones.

The property a friction compensator must have to be worth a diagnosis: built
on the model that *is* the plant's friction it tracks at least as well as
built on a wrong model. :func:`payoff_rows` measures it: the plant runs a true
friction (:func:`truths`), each model-based controller (:data:`CONTROLLERS`)
is built once on the true model and once on each wrong one, on the fast tasks
and on robustness draws (:func:`controllers.compensate.compensate` with that
true friction given), and per controller and wrong model a row gives

* ``median``: the median over the tasks of ``RMS(true)/RMS(wrong)`` (below 1:
  the true model pays off), and ``per_task``;
* ``true_better_in``: the share of the robustness draws (every parameter of
  the truth and the mass times ``1 +- 0.2``) in which the true model tracks
  better;
* ``ok``: ``median <= 1`` and the true model better in at least half the draws;
  ``None`` where the controller cannot be built on the wrong model (the LuGre
  observer on a static map: ``note`` says why).

The truths (on each plant, the values of its friction set): LuGre (wrong: a
LuGre a third off, Coulomb-viscous); LuGre with a pressure dependence whose
levels double over the supply pressure, in the chambers' sum and across the
piston (wrong: plain LuGre); LuGre with another Stribeck curve (exponent 2, twice the
Stribeck speed; wrong: the set's curve); NMLGM (wrong: LuGre).
``benchmarks/bench_model_payoff.py`` runs the whole matrix (before and after a
change); ``tests/test_model_payoff.py`` fast slices of it. The module uses only
the public API of :func:`~controllers.compensate.compensate`, so the benchmark
runs it on earlier trees too.
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from pathlib import Path
from typing import Any

#: The plants: the built-in servos and a plant file.
PLANTS = {"hydraulic": "hydraulic", "pneumatic": "pneumatic",
          "axis50": str(Path(__file__).resolve().parents[1] / "docs" / "examples" /
                        "axis50.toml")}
#: The controllers that use their friction model.
CONTROLLERS = ("pid-ff", "lugre-observer", "ekf", "mpc")


def truths(plant: str) -> dict[str, tuple[Any, dict[str, Any]]]:
    """Truth name -> ``(true friction, {wrong name: wrong model})`` on ``plant`` (a key of
    :data:`PLANTS`; module docstring)."""
    from controllers.compensate import resolve_plant
    from controllers.plant_model import equilibrium, friction_with_mismatch
    from fcomp.effects import EFFECTS
    from fcomp.models import make_model

    pf = resolve_plant(PLANTS.get(plant, plant))
    lug = make_model("lugre", params=pf.friction_set)
    p = pf.make_plant(lug)
    x0, _ = equilibrium(p, 0.5 * float(pf.values["stroke"]))
    n = p.state_names
    pa = float(p.flat_params()["p_atm"])
    S = float(x0[n.index("p1")] + x0[n.index("p2")] - 2 * pa)
    D = float(x0[n.index("p1")] - x0[n.index("p2")])
    ps = float(pf.values["ps"]) - pa
    # the levels double over the supply pressure, in the sum and across the piston
    pd = EFFECTS.get("pressure-dependence")
    strong = pd(pd.Params.from_flat({"kp": 1.0 / ps, "kd": 1.0 / ps, "p_ref": S, "d_ref": D}))
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


def payoff_rows(plant: str, names: Sequence[str] | None = None,
                controllers: Sequence[str] = CONTROLLERS, tasks: Sequence[str] | None = None,
                samples: int = 4, workers: int | None = None) -> list[dict[str, Any]]:
    """The rows of the matrix (module docstring) on ``plant`` for the truths ``names``
    (default all), on ``tasks`` (default every fast task)."""
    from controllers.compensate import compensate

    rows = []
    for tname, (true, wrongs) in truths(plant).items():
        if names is not None and tname not in names:
            continue
        runs: dict[tuple[str, str, str], dict[str, Any]] = {}
        draws: dict[tuple[str, str], list[float]] = {}
        for i, task in enumerate(tasks or [None]):
            res = compensate(PLANTS.get(plant, plant), true, {"true": true, **wrongs},
                             controllers=tuple(controllers), task=task, fast=True,
                             samples=samples if i == 0 else 0, workers=workers)
            runs.update({(r["controller"], r["model"], r["task"]): r for r in res.runs})
            if i == 0:
                for c in controllers:
                    for w in wrongs:
                        rob = res.robustness["controllers"][c]["ratio"].get(w) or {}
                        draws[(c, w)] = list(rob.get("values") or [])  # wrong/true
            task_names = sorted({t for (_, _, t) in runs})
        for c in controllers:
            for w in wrongs:
                per = {}
                for t in task_names:
                    a, b = runs.get((c, "true", t)), runs.get((c, w, t))
                    ok = a and b and a["status"] == b["status"] == "ok"
                    per[t] = (a["rms_error"] / b["rms_error"]
                              if ok and b["rms_error"] > 0 else None)  # type: ignore[index]
                vals = [v for v in per.values() if v is not None]
                d = draws[(c, w)]
                share = sum(v > 1.0 for v in d) / len(d) if d else None
                med = statistics.median(vals) if vals else None
                note = next((str(r["status"]) for t in task_names for m in ("true", w)
                             if (r := runs.get((c, m, t))) and r["status"] != "ok"), "")
                skipped = note.startswith("skipped") and not vals
                rows.append({"plant": plant, "truth": tname, "controller": c, "wrong": w,
                             "per_task": per, "median": med, "true_better_in": share,
                             "draws": len(d), "note": note,
                             "ok": None if skipped else bool(
                                 med is not None and med <= 1.0
                                 and (share is None or share >= 0.5))})
    return rows


__all__ = ["CONTROLLERS", "PLANTS", "payoff_rows", "truths"]
