"""The conclusion a sweep or a compensator comparison opens with (:class:`fcomp.conclusions.Conclusion`).

Built from the command's JSON document, like the conclusions of ``fit``,
``compare`` and ``diagnose``: what was found (which model or controller buys
what, in numbers), how sure (failed runs, draws that disagree, ranges that
overlap) and what to do next (export the winner to C, test it on the rig).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from fcomp.conclusions import Conclusion

#: Draws in which a model must beat the baseline for its gain to count as sure.
SURE_SHARE = 0.8


def _not_ranked(runs: Sequence[Mapping[str, Any]]) -> list[str]:
    """The runs not ranked, grouped by what they are and why: ``"4 runs: lugre-observer with
    diag (skipped: ...)"``."""
    groups: dict[tuple[str, str, str], int] = {}
    for r in runs:
        if r.get("status") != "ok":
            kind, _, why = str(r.get("status")).partition(": ")
            key = (f"{r.get('controller')} with {r.get('model')}", kind, why.split(":")[0])
            groups[key] = groups.get(key, 0) + 1
    return [f"{who} ({kind}: {why}; {n} run{'s' if n > 1 else ''})"
            for (who, kind, why), n in sorted(groups.items(), key=lambda kv: -kv[1])]


def _span(a: Mapping[str, Any]) -> str:
    lo, hi = a.get("best"), a.get("worst")
    return f"{lo:.2f}" if lo == hi else f"{lo:.2f}-{hi:.2f}"


def of_compensation(doc: Mapping[str, Any]) -> Conclusion:
    """The conclusion of ``fcomp compensate --json``: what the better friction model buys,
    recommended only where it holds under every truth the plant ran
    (:mod:`controllers.compensate`)."""
    base = doc["baseline"]
    runs = doc["runs"]
    truths = list(doc.get("truths") or {})
    n_truths = max(len(truths), 1)
    under = ("under the true friction given" if doc.get("mode") == "given"
             else f"under every one of the {n_truths} candidate truths")
    across = doc.get("across_truths") or {}
    uses = doc.get("uses_friction") or {}
    users = [c for c in doc["controllers"] if uses.get(c, True)]
    not_ranked = _not_ranked(runs)
    ranked = sum(r.get("status") == "ok" for r in runs)
    reasons: list[str] = []
    if not ranked:
        return Conclusion(
            f"every run failed, was flagged or skipped ({len(runs)} runs): nothing to rank",
            "low", tuple(not_ranked),
            ("read each run's status (the runs table, or the JSON's runs)",
             "check the plant and the models: fcomp plant check PLANT.toml"))
    pairs = [(c, m, a) for c in users for m, a in (across.get(c) or {}).items()]
    better = sorted((p for p in pairs if p[2]["holds"] == "better"),
                    key=lambda p: p[2]["worst"])
    mixed = [p for p in pairs if p[2]["holds"] == "mixed"]
    partly = [p for p in pairs if p[2]["holds"] == "partly ranked"]
    worse = [p for p in pairs if p[2]["holds"] == "worse"]
    level = "high"
    blind = [c for c in doc["controllers"] if not uses.get(c, True)]
    tail = (f"; {', '.join(blind)} {'uses' if len(blind) == 1 else 'use'} no friction model"
            if blind else "")
    if better:
        c, m, a = better[0]
        finding = (f"{under}, {m} instead of {base} lowers the RMS tracking error of {c}: "
                   f"median-task ratio {_span(a)}"
                   + (f"; also {', '.join(f'{cc} ({_span(aa)})' for cc, _, aa in better[1:4])}"
                      if len(better) > 1 else ""))
    elif mixed:
        c, m, a = max(mixed, key=lambda p: p[2]["worst"] / p[2]["best"])
        per = a["per_truth"]
        lo = min((t for t in per if per[t] is not None), key=lambda t: per[t])
        hi = max((t for t in per if per[t] is not None), key=lambda t: per[t])
        finding = (f"no model wins under every truth the plant may have: {c} with {m} has "
                   f"the ratio {per[lo]:.2f} when the truth is {lo} but {per[hi]:.2f} when it "
                   f"is {hi}")
        level = "low"
        reasons.append("the truths disagree: the answer depends on which friction the plant "
                       "really has")
    elif partly:
        c, m, a = min(partly, key=lambda p: p[2]["worst"])
        finding = (f"{c} with {m}: median-task ratio {_span(a)} under the "
                   f"{a['ranked_truths']} of {a['truths']} truths where its runs could be "
                   "ranked, none under the others")
        level = "low"
    elif worse:
        names = sorted({m for _, m, _ in worse})
        finding = (f"{under}, {' and '.join(names)} instead of {base} does not lower the RMS "
                   f"tracking error of {', '.join(sorted({c for c, _, _ in worse}))}")
    elif any(p[2]["holds"] == "same" for p in pairs):
        finding = (f"{under}, the models make no difference here: every ranked run tracks "
                   f"alike with {base} and with {', '.join(m for m in doc['models'] if m != base)}")
    else:
        finding = "no compared model could be ranked against the baseline"
        level = "low"
    finding += tail
    if partly and (better or mixed):
        reasons.append("ranked under only some truths: " + ", ".join(
            f"{c} with {m} ({a['ranked_truths']} of {a['truths']})" for c, m, a in partly[:3]))
    if mixed and better:
        level = "medium"
        reasons.append("the truths disagree for " + ", ".join(
            f"{c} with {m} ({_span(a)})" for c, m, a in mixed[:3]))
    if doc.get("mode") == "given" and any((t or {}).get("equals")
                                          for t in (doc.get("truths") or {}).values()):
        level = "low"
        reasons.insert(0, "circular: the plant's true friction is one of the compared models, "
                          "which is exact there and wins by construction")
    for w in doc.get("warnings") or []:
        if w.get("code") in ("outside-fitted-range", "friction-beyond-force"):
            level = "low"
            reasons.append(w["message"].split(":")[0] + (
                ": run outside what it was fitted on" if w["code"] == "outside-fitted-range"
                else ": the plant can hardly move its friction"))
    rob = (doc.get("robustness") or {}).get("controllers") or {}
    for c, m, _a in better:
        share = (((rob.get(c) or {}).get("ratio") or {}).get(m) or {}).get("better")
        if share is not None and share < SURE_SHARE:
            reasons.append(f"{c} with {m} is better in only {share * 100:.0f} % of the "
                           "robustness draws")
            level = "medium" if level == "high" else level
    if not_ranked:
        reasons.append(f"{len(runs) - ranked} of {len(runs)} runs not ranked: "
                       + "; ".join(not_ranked[:3]) + (" ..." if len(not_ranked) > 3 else ""))
        level = "medium" if level == "high" else level
    steps: list[str] = []
    if better:
        c, m, _ = better[0]
        steps.append(f"deploy it: fcomp export {c} --plant-params PLANT.toml --friction "
                     f"{m}.json -o DIR (C code, checked against Python and timed)")
    if mixed:
        steps.append("tell the truths apart: compare the models on a second record (fcomp "
                     "compare REC2 --friction MODEL.json) before choosing")
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
