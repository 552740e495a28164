"""``fcomp.design``: from a diagnosis and a rig, the next experiment.

Reads the diagnosis's open questions (:mod:`.questions`), builds the alternatives of the
untested effects (:mod:`.alternatives`), scores the rig's candidate primitives
(:mod:`.optimiser`), chooses and packs them (:mod:`.programme`), then predicts along the
assembled programme what each question will show: the separation of every rival pair and
every parameter's standard error before and after. When the rig's limits cannot separate a
pair, it says which limit blocks it and what a wider one would give (a warning, not an
error).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fcomp.errors import FcompError
from fcomp.planning.alternatives import alternative
from fcomp.planning.criteria import force, jacobian, predicted_stderr, separation, t_criterion
from fcomp.planning.optimiser import (
    T_BLOCKED,
    T_TARGET,
    bound,
    choose,
    free_names,
    refit_T,
    refitted,
    score,
)
from fcomp.planning.primitives import candidates, signals
from fcomp.planning.programme import Experiment, described, pack
from fcomp.planning.questions import Diagnosed, Question, read_diagnosis
from fcomp.planning.rig import MAXIMA, Rig, read_rig, rig_from
from fcomp.textdata import read_json


@dataclass
class DesignResult:
    """The designed programme (trailing-underscore attributes, :meth:`as_dict`).

    Attributes
    ----------
    experiments_ : list of Experiment
        The programme, one experiment per file.
    questions_ : list of dict
        Per question: ``kind``, ``rivals`` (or ``parameter``), ``predicted_separation``
        (noise floors, RMS over the programme), ``predicted_T`` (the non-centrality), the
        standard error before and after for a parameter, ``blocked`` with why.
    warnings_ : list of dict
        ``{"code", "message"}``: limits that block a question, questions left out.
    rig_, noise_ : the rig, the noise floor used (N).
    """

    experiments_: list[Experiment]
    questions_: list[dict[str, Any]]
    warnings_: list[dict[str, str]]
    rig_: Rig
    noise_: float
    models_: dict[str, dict[str, Any]] = field(default_factory=dict, repr=False)
    files_: list[str] = field(default_factory=list)
    _questions: list[Question] = field(default_factory=list, repr=False)

    def as_dict(self) -> dict[str, Any]:
        """The JSON of ``fcomp design`` (``experiments``, ``questions``, ``warnings``)."""
        return {"experiments": list(self.files_) or
                [f"experiment_{k + 1}.csv" for k in range(len(self.experiments_))],
                "programme": [{"level": e.level, "duration": e.duration,
                               "primitives": described(e.blocks)}
                              for e in self.experiments_],
                "questions": self.questions_, "warnings": self.warnings_,
                "noise_floor": self.noise_, "rig": self.rig_.as_dict(),
                "criterion": "T-optimal (Atkinson & Fedorov 1975) for rivals; the "
                             "parameter's standard error (Fisher information) for values"}


def _reference_pressure(dx: Diagnosed) -> float | None:
    """The pressure sum the record was taken at (its files' mean p1 + p2), if readable."""
    from fcomp.measurement import Measurement

    sums = []
    for p in dx.data:
        try:
            m = Measurement.read(p)
        except (FcompError, OSError):
            continue
        c = m.columns
        if "p1" in c:
            sums.append(float(np.mean(c["p1"] + c.get("p2", 0.0))))
    return float(np.mean(sums)) if sums else None


def _prepare(dx: Diagnosed, rig: Rig, sigma: float, warnings: list[dict[str, str]]
             ) -> list[Question]:
    qs = [q for q in dx.questions]
    probes = [signals(b, rig) for b in candidates(rig)
              if b.kind != "run" or b.speed == rig.speed_max]
    base = [force(dx.model, s) for s in probes]
    p_ref = _reference_pressure(dx)
    for q in qs:
        if q.kind == "untested":
            alt = alternative(dx.model, q.label, probes, base, sigma,
                              p_ref if p_ref is not None else
                              rig.levels()[0] * (2 if rig.double_acting else 1))
            if alt is None:
                warnings.append(_untestable(dx, rig, q.label, sigma, p_ref))
                continue
            q.models[q.label] = alt[0]
            q.notes.append(f"designed against {q.label} at {alt[1]}")
        elif q.kind == "parameter":
            q.models = {"final": dx.model}
    return [q for q in qs if q.kind == "parameter" or len(q.models) > 1]


def _untestable(dx: Diagnosed, rig: Rig, effect: str, sigma: float, p_ref: float | None
                ) -> dict[str, str]:
    """Why an untested effect cannot be designed for: the limit that blocks it and what a
    wider one would do (a ``limits-block`` warning), or that no limit tried helps."""
    lv = rig.levels()
    wider = {"pressure levels": rig.relaxed(levels_given=(), pressure_min=0.5 * min(lv),
                                            pressure_max=max(2 * max(lv), min(lv) + 2e5)),
             "speed_max": rig.relaxed(speed_max=3 * rig.speed_max, accel_max=3 * rig.accel_max),
             "stroke": rig.relaxed(stroke=2 * rig.stroke)}
    for what, r in wider.items():
        probes = [signals(b, r) for b in candidates(r) if b.kind != "run" or b.speed == r.speed_max]
        base = [force(dx.model, s) for s in probes]
        ref = p_ref if p_ref is not None else lv[0] * (2 if rig.double_acting else 1)
        if alternative(dx.model, effect, probes, base, sigma, ref) is not None:
            now = (f"{len(lv)} level(s) {', '.join(f'{p / 1e5:.3g}' for p in lv)} bar"
                   if what == "pressure levels" else f"{getattr(rig, what)}")
            then = (f"{r.pressure_min / 1e5:.3g}-{r.pressure_max / 1e5:.3g} bar"
                    if what == "pressure levels" else f"{getattr(r, what)}")
            return {"code": "limits-block", "message":
                    f"{effect}: the rig's {what} block it ({now}: no motion the rig can run "
                    f"moves its force); with {what} {then} the programme could test it"}
    return {"code": "not-designable", "message": f"{effect}: no motion within the rig's "
            "limits, nor with wider pressures, speeds or stroke, moves its force; left out"}


def _blocked(sc: Any, rig: Rig, dx: Diagnosed, q: Question, i: int, other: str,
             sigma: float, mass: bool) -> str:
    """Which limit blocks the pair, and what a wider one would give."""
    tries = []
    lv = rig.levels()
    wider = {"pressure levels": rig.relaxed(levels_given=(), pressure_min=0.5 * min(lv),
                                            pressure_max=max(2 * max(lv), min(lv) + 2e5)),
             "speed_max": rig.relaxed(speed_max=3 * rig.speed_max,
                                      accel_max=3 * rig.accel_max),
             "stroke": rig.relaxed(stroke=2 * rig.stroke),
             "duration_max": rig.relaxed(duration_max=3 * rig.duration_max)}
    names = [next(iter(q.models)), other]
    for what, r in wider.items():
        qq = Question(q.kind, q.label, {n: q.models[n] for n in names})
        s2 = score(r, [qq], sigma, mass)
        t = bound(s2, r, (0, other))
        tries.append((t, what, r))
    t, what, r = max(tries, key=lambda x: x[0])
    if t < T_BLOCKED:
        return (f"{names[0]} vs {other}: no limit tried (wider pressure range, 3x speed, "
                "2x stroke, 3x duration) separates them: they predict the same force on "
                "every motion this rig can run")
    desc = {"pressure levels": f"pressures {r.pressure_min / 1e5:.3g}-{r.pressure_max / 1e5:.3g}"
            " bar", "speed_max": f"speed_max {r.speed_max:g} m/s",
            "stroke": f"stroke {r.stroke:g} m", "duration_max": f"duration_max "
            f"{r.duration_max:g} s"}[what]
    return (f"{names[0]} vs {other}: the rig's {what} block it (T = {bound(sc, rig, (i, other)):.3g}"
            f" at most, {T_BLOCKED:g} needed); with {desc} the programme would reach "
            f"T = {t:.3g}")


def design(diagnosis: Mapping[str, Any] | str | Path, rig: Rig | Mapping[str, Any] | str | Path,
           *, noise: float | None = None) -> DesignResult:
    """Design the next experiment for a diagnosis's open questions within a rig's limits.

    Parameters
    ----------
    diagnosis
        A ``fcomp diagnose --json`` document, or its path.
    rig
        A :class:`Rig`, a rig file's tables, or its path (:mod:`fcomp.planning.rig`).
    noise
        The force noise (N); default the rig file's ``noise``, else the diagnosis's floor.
    """
    if isinstance(diagnosis, (str, Path)):
        doc = read_json(diagnosis, "diagnosis", hint=" (give the --json output of fcomp "
                        "diagnose)")
        label = str(diagnosis)
    else:
        doc, label = diagnosis, "diagnosis"
    r = rig if isinstance(rig, Rig) else read_rig(rig) if isinstance(rig, (str, Path)) \
        else rig_from(rig)
    dx = read_diagnosis(doc, label)
    sigma = float(noise or r.noise or dx.noise_floor)
    if not (math.isfinite(sigma) and 0 < sigma <= MAXIMA["noise"]):
        raise FcompError(f"noise must be a positive force of at most {MAXIMA['noise']:g} N, "
                         f"got {sigma!r}")
    warnings: list[dict[str, str]] = [{"code": "unknown-effect", "message": m}
                                      for m in dx.ignored]
    mass = dx.source != "F"
    qs = _prepare(dx, r, sigma, warnings)
    if not qs:
        warnings.append({"code": "nothing-to-design", "message": "the diagnosis leaves no "
                         "open question (no tie, no untested effect, no undetermined value)"})
        return DesignResult([], [], warnings, r, sigma)
    sc = score(r, qs, sigma, mass, stderr=dx.stderr)
    chosen = choose(sc, r, qs)
    exps = pack([sc.blocks[j] for j in chosen], r)
    se_after = np.zeros(0)
    if sc.joint:
        model = next(q.models["final"] for q in qs if q.kind == "parameter")
        info = sum((lambda J: J.T @ J)(jacobian(model, e.signals, sc.joint, mass))
                   for e in exps) / sigma**2
        se_after = predicted_stderr(np.asarray(info), sc.prior)
    out = []
    for i, q in enumerate(qs):
        entry: dict[str, Any] = {"kind": q.kind, "reason": q.reason, "notes": list(q.notes)}
        if q.kind == "parameter":
            k = sc.asked[i]
            after = float(se_after[k]) if se_after.size else math.inf
            entry.update({"parameter": q.parameter, "value": q.value,
                          "stderr_before": q.stderr_before,
                          "stderr_after": after if math.isfinite(after) else None,
                          "interval_before": None if q.stderr_before is None
                          else 1.96 * q.stderr_before,
                          "interval_after": 1.96 * after if math.isfinite(after) else None,
                          "predicted_shrink": (q.stderr_before / after
                                               if q.stderr_before and math.isfinite(after)
                                               else None),
                          "estimated_with": list(sc.joint)})
            if not math.isfinite(after) or not (q.stderr_before is None
                                                or after < q.stderr_before * 0.99):
                warnings.append({"code": "limits-block", "message":
                                 f"{q.parameter}: no motion within the rig's limits carries "
                                 "information on it beyond the record's"})
            out.append(entry)
            continue
        names = list(q.models)
        ref = [force(q.models[names[0]], e.signals) for e in exps]
        rivals: list[dict[str, Any]] = []
        for other in names[1:]:
            fo = [force(q.models[other], e.signals) for e in exps]
            a, b = np.concatenate(ref or [np.zeros(0)]), np.concatenate(fo or [np.zeros(0)])
            T = t_criterion(a, b, sigma)
            _, rival = refitted(q, other)
            free = free_names(rival)
            Js = [jacobian(rival, e.signals, free, False) for e in exps]  # type: ignore[arg-type]
            J = np.vstack(Js) if Js else np.zeros((0, len(free)))
            Tr = refit_T(T, J.T @ (a - b) / sigma**2, J.T @ J / sigma**2)
            item = {"rival": other, "predicted_separation": separation(a, b, sigma),
                    "predicted_T": T, "predicted_T_refit": Tr,
                    "predicted_separation_refit": float(np.sqrt(Tr / max(a.size, 1))),
                    "refitted": refitted(q, other)[0], "answered": Tr >= T_TARGET}
            if bound(sc, r, (i, other)) < T_BLOCKED:
                why = _blocked(sc, r, dx, q, i, other, sigma, mass)
                item["blocked"] = why
                warnings.append({"code": "limits-block", "message": why})
            rivals.append(item)
        entry.update({"rivals": names, "label": q.label, "pairs": rivals,
                      "predicted_separation": min(float(p["predicted_separation"]) for p in rivals),
                      "predicted_T": min(float(p["predicted_T"]) for p in rivals),
                      "predicted_separation_refit": min(float(p["predicted_separation_refit"])
                                                        for p in rivals)})
        out.append(entry)
    from fcomp.models.document import model_document

    models = {f"{q.label}:{n}": model_document(m) for q in qs if q.kind != "parameter"
              for n, m in q.models.items()}
    res = DesignResult(exps, out, warnings, r, sigma, models_=models)
    res._questions = qs  # the questions with their models, in the order of questions_
    return res
