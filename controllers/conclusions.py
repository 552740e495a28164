"""The conclusion a sweep or a compensator comparison opens with (:class:`fcomp.conclusions.Conclusion`).

Built from the command's JSON document, like the conclusions of ``fit``,
``compare`` and ``diagnose``: what was found (which model or controller buys
what, in numbers), how sure (failed runs, draws that disagree, ranges that
overlap) and what to do next (export the winner to C, test it on the rig).
"""

from __future__ import annotations

from collections.abc import Mapping
from statistics import median
from typing import Any

from fcomp.conclusions import Conclusion

#: Draws in which a model must beat the baseline for its gain to count as sure.
SURE_SHARE = 0.8


def of_compensation(doc: Mapping[str, Any]) -> Conclusion:
    """The conclusion of ``fcomp compensate --json``: what the better friction model buys."""
    base = doc["baseline"]
    others = [m for m in doc["models"] if m != base]
    cells: list[tuple[float, str, str, str]] = []  # (ratio, controller, task, model)
    blind: list[str] = []
    for c in doc["controllers"]:
        ratios = [(r, c, t, m) for t in doc["tasks"] for m in others
                  if (r := ((doc["ratios"].get(c, {}).get(t, {}).get(m)) or {})
                      .get("rms_error")) is not None]
        if ratios and all(abs(r - 1.0) < 1e-12 for r, *_ in ratios):
            blind.append(c)  # its law does not use the friction model
        else:
            cells += ratios
    failed = sum(r.get("status") != "ok" for r in doc["runs"])
    if not cells:
        finding = (f"no controller here uses the friction model ({', '.join(blind)}): the "
                   "models cannot make a difference")
        return Conclusion(finding, "high", (), ("compare pid-ff, lugre-observer, ekf or mpc "
                                                "(--controllers)",))
    best = min(cells)
    typical = median(r for r, *_ in cells)
    better = sum(r < 1.0 for r, *_ in cells)
    verb = "lowers" if typical < 1.0 else "does not lower"
    finding = (f"{' and '.join(others)} instead of {base} {verb} the RMS tracking error: "
               f"median ratio {typical:.2f} over {len(cells)} controller-task pairs "
               f"({better} better); best {best[1]} on {best[2]} ({best[0]:.2f})"
               + (f"; {', '.join(blind)} {'uses' if len(blind) == 1 else 'use'} no friction "
                  "model" if blind else ""))
    reasons: list[str] = []
    level = "high"
    if failed:
        reasons.append(f"{failed} run(s) failed (see the runs table)")
        level = "medium"
    rob = (doc.get("robustness") or {}).get("controllers") or {}
    for c, per in rob.items():
        for m, r in (per.get("ratio") or {}).items():
            share = r.get("better")
            if c not in blind and share is not None and share < SURE_SHARE and typical < 1.0:
                reasons.append(f"{c} with {m} is better in only {share * 100:.0f} % of the "
                               "robustness draws")
                level = "medium"
    steps = ([f"deploy it: fcomp export {best[1]} --plant-params PLANT.toml --friction "
              f"{best[3]}.json -o DIR (C code, checked against Python and timed)"]
             if best[0] < 1.0 else [])
    steps.append("check it on the rig: the ratios hold for the plant file's model of it")
    return Conclusion(finding, level, tuple(reasons), tuple(steps))


def of_sweep(doc: Mapping[str, Any]) -> Conclusion:
    """The conclusion of ``fcomp sweep --json``: the most robust controller (Monte Carlo), or
    how the error grows across the grid."""
    failed = sum(r.get("status") != "ok" for r in doc["runs"])
    reasons = [f"{failed} of {len(doc['runs'])} runs failed (counted, not dropped; see the "
               "table)"] \
        if failed else []
    if doc["mode"] == "monte-carlo":
        dist = {c: d["rms_error"] for c, d in doc["distributions"].items()
                if d["rms_error"].get("median") is not None}
        if not dist:
            return Conclusion("every run failed", "low", tuple(reasons),
                              ("check the plant and the task (fcomp plant check)",))
        order = sorted(dist, key=lambda c: dist[c]["median"])
        b = dist[order[0]]
        finding = (f"{order[0]} tracks best over {doc['samples']} draws of friction mismatch: "
                   f"median RMS error {b['median'] * 1e6:.3g} um (10-90 %: "
                   f"{b['p10'] * 1e6:.3g}-{b['p90'] * 1e6:.3g} um)")
        if len(order) > 1:
            s = dist[order[1]]
            finding += f", then {order[1]} ({s['median'] * 1e6:.3g} um)"
            if s["p10"] <= b["p90"]:
                reasons.append(f"the 10-90 % ranges of {order[0]} and {order[1]} overlap: "
                               "more draws (--samples) would tell them apart")
        level = "medium" if reasons else "high"
        return Conclusion(finding, level, tuple(reasons),
                          (f"deploy it: fcomp export {order[0]} --plant-params PLANT.toml -o "
                           "DIR",))
    growth = []
    for c in doc["controllers"]:
        errs = [(p["rms_error"].get(c), p["label"]) for p in doc["points"]
                if p["rms_error"].get(c) is not None]
        if len(errs) > 1:
            lo, hi = min(errs), max(errs)
            growth.append((hi[0] / lo[0] if lo[0] > 0 else float("inf"), c, hi[1]))
    if not growth:
        return Conclusion("too few grid points ran to compare", "low", tuple(reasons), ())
    g = min(growth)
    w = max(growth)
    finding = (f"over the grid {g[1]} is the least sensitive to the mismatch (its RMS error "
               f"varies {g[0]:.2g}x); {w[1]} the most ({w[0]:.2g}x, worst at {w[2]})")
    return Conclusion(finding, "medium" if reasons else "high", tuple(reasons), ())
