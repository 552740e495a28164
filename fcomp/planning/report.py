"""The HTML report of ``fcomp design`` (:class:`fcomp.report.Report`, the one figure style):
the conclusion first, then per experiment its motion and pressures with the rivals'
predicted forces along it, the separation per question in noise floors, and the values'
intervals before and after."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from fcomp.planning.criteria import force
from fcomp.planning.programme import described


def conclusion(doc: dict[str, Any]) -> Any:
    """What the design found, how sure, what next (:class:`fcomp.conclusions.Conclusion`)."""
    from fcomp.conclusions import Conclusion

    qs = doc["questions"]
    blocked = [w["message"] for w in doc["warnings"] if w["code"] == "limits-block"]
    n = len(doc["experiments"])
    finding = (f"{n} experiment(s), {sum(e['duration'] for e in doc['programme']):.0f} s in all, "
               f"for {len(qs)} open question(s)")
    seps = [q["predicted_separation"] for q in qs if q["kind"] != "parameter"]
    if seps:
        finding += f"; the rivals separate by {min(seps):.3g} noise floors or more"
    reasons = tuple(blocked) + ("predictions from the diagnosis's models: a rival fitted "
                                "to the record may move once the new record is in",)
    return Conclusion(finding, "medium" if blocked else "high" if not seps else "medium",
                      reasons, ("run each file on the rig (x: the position to follow, p1/p2: "
                                "the pressures to hold), log the force, then fcomp diagnose "
                                "the old records with the new ones",),
                      outcome="mixed" if blocked else "good")


def write_report(result: Any, folder: str | Path, command: str | None = None) -> Path:
    """``folder/report.html`` for a :class:`fcomp.planning.design.DesignResult`."""
    from fcomp import figstyle
    from fcomp.report import Report

    doc = result.as_dict()
    rep = Report("Next experiment: fcomp design", command=command)
    rep.conclusion(conclusion(doc))
    rep.section("Questions")
    rows = []
    for q in doc["questions"]:
        if q["kind"] == "parameter":
            rows.append([q["kind"], q["parameter"], q["reason"], "-",
                         q.get("interval_before"), q.get("interval_after")])
        else:
            rows.append([q["kind"], q["label"], q["reason"], q["predicted_separation"],
                         None, None])
    rep.table(["kind", "question", "why open", "separation (noise floors)",
               "95 % half-interval before", "after"], rows,
              caption="Each open question of the diagnosis and what the programme predicts: "
                      "the rivals' RMS force difference in noise floors; a value's interval "
                      "before and after (Fisher information along the programme).", digits=3)
    if doc["warnings"]:
        rep.note("; ".join(w["message"] for w in doc["warnings"]), kind="warn")
    qs = [q for q in getattr(result, "_questions", []) if q.kind != "parameter"]
    for k, (exp, name) in enumerate(zip(result.experiments_, doc["experiments"], strict=True), 1):
        rep.section(f"Experiment {k}: {Path(name).name}")
        s = exp.signals
        with figstyle.style():
            fig, axes = figstyle.new_figure(6.0 if qs else 3.6, nrows=3 if qs else 2,
                                            sharex=True)
            ax = np.atleast_1d(axes)
            ax[0].plot(s["t"], s["x"] * 1e3)
            ax[0].set_ylabel("x (mm)")
            ax[1].plot(s["t"], s["p1"] / 1e5, label="p1")
            if np.any(s["p2"]):
                ax[1].plot(s["t"], s["p2"] / 1e5, "--", label="p2")
            ax[1].set_ylabel("pressure (bar)")
            if qs:
                for q in qs:
                    for n_, m in q.models.items():
                        ax[2].plot(s["t"], force(m, s), lw=0.8, label=f"{q.label}: {n_}")
                ax[2].set_ylabel("predicted F (N)")
                figstyle.legend_above(ax[2], ncol=2)
            ax[-1].set_xlabel("t (s)")
        rep.figure(fig, f"Experiment {k} at {exp.level / 1e5:.3g} bar: the position to follow, "
                   "the pressures to hold, and each question's models' predicted friction "
                   "along it. " + "; ".join(described(exp.blocks)))
    path = Path(folder) / "report.html"
    rep.write(path)
    return path
