"""The JSON of ``fcomp diagnose`` and the model file, written from a :class:`.result.DiagnosisResult`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.result import DiagnosisResult
from fcomp.diagnosis.search import Candidate
from fcomp.diagnosis.wording import QUALIFIES
from fcomp.effects import EFFECTS

#: What ``rms_*`` measure (the JSON's ``error_measure``).
ERROR_MEASURE = ("held-out RMS of the scored residual: the logarithmic score of the model's "
                 "prediction band with the noise floor, in N (equal to the plain residual where "
                 "the motion fixes the prediction; a wider band costs); rms_plain: y - F_hat")


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r**2))) if r.size else math.nan


def _candidate(c: Candidate) -> dict[str, Any]:
    return {"effect": c.effect, "form": c.form, "rms_heldout": _num(c.rms_heldout),
            "qualifies": c.qualifies, "z": _num(c.z), "p": _num(c.p),
            "delta_bic": _num(c.delta_bic), "reason": c.reason or QUALIFIES}


def signals(result: DiagnosisResult) -> dict[str, Any]:
    """Which velocity drove the friction states, from which force, and why (JSON ``signals``).

    ``velocity`` (``"x"``, ``"v"``, ``"fused"``, or ``"mixed"`` when records
    differ), ``force`` and ``reason`` summarise; ``unresolved_samples``
    counts the samples left out because the position missed motion there
    (:func:`fcomp.diagnosis.regimes.unresolved_rests`); ``force_lag_s`` is the
    lag of a driving force's channel, fitted with the first (unweighted) baseline
    fit, held in the weighted fits and estimated again (alone, unweighted) for
    every model accepted (s; None for a load cell): pressure transducers and their
    lines lag, and a force reconstructed from them misses ``lag*dD/dt`` where ``D``
    changes fast; ``records`` holds the full conditioning of every file
    (:class:`fcomp.conditioning.Conditioning`).
    """
    data = result.ground.data
    recs = [c.to_dict() for c in data.signals]
    if not recs:
        return {"velocity": "v", "force": data.source, "records": [],
                "reason": "steady-state points: the velocity of each point as given"}
    kinds = {r["velocity"] for r in recs}
    lag = result.fit.values.get("lag")
    return {"velocity": kinds.pop() if len(kinds) == 1 else "mixed",
            "force": data.source,
            "force_lag_s": None if lag is None else float(lag),
            "unresolved_samples": result.ground.segmentation.unresolved,
            "reason": "; ".join(dict.fromkeys(f"{r['label']}: {r['reason']}" for r in recs)),
            "records": recs}


#: What the RMS errors of a diagnosis (``rms_baseline``, ``rms_final``, ``rms_before``,
#: ``rms_after``, ``rms_heldout``) are, in words (the JSON's ``rms_measured``).
HELD_OUT = ("held-out RMS (N): each model refitted on the training part of the records and "
            "scored on the held-out part; not the RMS of a given model on the whole record "
            "that fcomp fit and fcomp compare print")


def model_file(result: DiagnosisResult, source: Mapping[str, Any] | None = None
               ) -> dict[str, Any]:
    """The final model as a model file's document (:mod:`fcomp.modelfile`): the friction
    with every effect accepted and its fitted values, the measurement terms (a fitted
    ``mass``, the channel ``lag``, ...) as such. ``source`` (``command``, ``data``) says
    where it comes from."""
    from fcomp.models.document import model_document
    from fcomp.models.fitted_range import signal_ranges

    data = result.ground.data
    seen = signal_ranges([e.data.sig for e in data.experiments], data.available)
    return model_document(result.fit.model.with_fitted_range(seen), measurement=result.fit.values,
                          stderr=dict(result.stderr), undetermined=undetermined(result),
                          source={"diagnosis": {"baseline": result.baseline_name,
                                                "added": list(result.added),
                                                "verdict": result.verdict.verdict,
                                                "rivals": rivals(result)},
                                  **dict(source or {})})


#: The other baseline's final model is a rival if its held-out RMS is within this factor of
#: the final model's.
RIVAL_RMS = 1.5


def rivals(result: DiagnosisResult) -> list[dict[str, Any]]:
    """The models the record could not tell from the final one, as model documents with why:
    the other baseline's final model (when the baseline check ran and its held-out RMS is
    within :data:`RIVAL_RMS` of the final one's), then each tied candidate of an accepted
    step, refitted at that step (without the effects added after it). ``fcomp compensate``
    runs them as candidate truths."""
    from fcomp.models.document import model_document

    out: list[dict[str, Any]] = []
    other = result.other
    if other is not None and other.fit.rms_test <= RIVAL_RMS * result.fit.rms_test:
        out.append({"why": f"the diagnosis from {other.baseline_name} ends there (held-out "
                           f"RMS {other.fit.rms_test:.4g} N)",
                    "rms_heldout": _num(other.fit.rms_test),
                    "model_file": model_document(other.fit.model,
                                                 measurement=other.fit.values)})
    for i, st in enumerate(result.steps, start=1):
        if not (st.accepted and st.tie):
            continue
        for cand in st.candidates:
            if cand.effect == st.effect or cand.effect not in st.tie or cand.fit is None:
                continue
            out.append({"why": f"tied with {st.effect} at step {i} (held-out RMS "
                               f"{cand.rms_heldout:.4g} N)",
                        "rms_heldout": _num(cand.rms_heldout),
                        "model_file": model_document(cand.fit.model,
                                                     measurement=cand.fit.values)})
    return out


#: Features that are one on a fixed stroke (every run reverses at the stroke's ends): the
#: position and the displacement since the reversal follow each other in each direction.
ONE_ON_A_FIXED_STROKE = ("x", "displacement_since_reversal")


def merged_features(result: DiagnosisResult) -> list[dict[str, Any]]:
    """The JSON's ``residual_features``: each feature with its strength and the RMS it carries
    (N), strongest first; on a fixed stroke (:attr:`.design.Design.fixed_stroke`) the
    position and the displacement since the reversal are one finding, listed once under
    the stronger with ``same_as``."""
    feats: list[dict[str, Any]] = [
        {"feature": f.feature, "strength": round(f.strength, 4),
         "rms": _num(result.verdict.rms_final * math.sqrt(f.strength))}
        for f in result.verdict.features]
    if result.design is None or not result.design.fixed_stroke:
        return feats
    pair = [f for f in feats if f["feature"] in ONE_ON_A_FIXED_STROKE]
    if len(pair) < 2:
        return feats
    keep, drop = pair[0], pair[1]  # strongest first
    keep["same_as"] = [drop["feature"]]
    return [f for f in feats if f is not drop]


#: Plausibility codes of a value the record does not determine.
UNDETERMINED = ("at-bound", "not-identified", "interval-crosses-zero")


def undetermined(result: DiagnosisResult) -> dict[str, str]:
    """The final model's parameters the record did not determine -> why (the final fit's
    ``at-bound``, ``not-identified`` and ``interval-crosses-zero`` warnings), for the model
    file's ``undetermined``."""
    flat = result.fit.model.flat_params()
    out: dict[str, str] = {k: f"{why} (value {flat[k]:.4g})"
                           for k, why in result.design_held.items() if k in flat}
    for w in result.final_warnings:
        if w.code not in UNDETERMINED or not w.parameter:
            continue
        why = w.message.split(": ", 1)[-1]
        for name in w.parameter.split(","):
            out.setdefault(name.strip(), f"{w.code}: {why}")
    return out


def tie_models(result: DiagnosisResult) -> list[dict[str, Any]]:
    """Every tie of an accepted step with each tied effect's model as fitted at that step
    (the same earlier effects under each; ``fcomp design`` opposes them): ``[{"step",
    "effects": {effect: model document}}]``."""
    from fcomp.models.document import model_document

    out: list[dict[str, Any]] = []
    for i, st in enumerate(result.steps, start=1):
        if not (st.accepted and st.tie):
            continue
        models = {c.effect: model_document(c.fit.model, measurement=c.fit.values)
                  for c in st.candidates
                  if c.fit is not None and (c.effect == st.effect or c.effect in st.tie)}
        if len(models) > 1:
            out.append({"step": i, "chosen": st.effect, "effects": models})
    return out


def to_dict(result: DiagnosisResult) -> dict[str, Any]:
    """The JSON of ``fcomp diagnose`` (public contract, plus extra keys)."""
    test = result.ground.split.test
    data = result.ground.data

    def plain(fit: FitResult) -> float | None:
        return _num(_rms(fit.plain_residual[test]))

    return {
        "baseline": result.baseline_name,
        "rms_baseline": result.baseline_fit.rms_test,
        "rms_measured": HELD_OUT,
        "added": list(result.added),
        "steps": [{"effect": s.effect, "rms_before": s.rms_before, "rms_after":
                   _num(s.rms_after), "accepted": bool(s.accepted), "forced": s.forced,
                   "removed": bool(s.removed),
                   "removed_because": s.removed or None,
                   "pair": list(s.pair) or None,
                   "form": s.form,
                   "candidates": [_candidate(c) for c in s.candidates],
                   "tie_tests": [{"effect": name, **{k: _num(v) if isinstance(v, float) else v
                                                     for k, v in t.to_dict().items()}}
                                 for name, t in s.tie_tests],
                   "warnings": [w.to_dict() for w in s.warnings]}
                  for s in result.steps],
        "candidates": [_candidate(c) for c in result.candidates],
        "ties": [list(t) for t in result.ties],
        "removed": list(result.removed),
        "rms_final": result.fit.rms_test,
        "rms_plain": {"baseline": plain(result.baseline_fit), "final": plain(result.fit)},
        "error_measure": ERROR_MEASURE,
        "noise_floor": result.noise_floor.value,
        "verdict": result.verdict.verdict,
        "reason": result.reason,
        "signals": signals(result),
        "baseline_dependent": bool(result.dependence and result.dependence["dependent"]),
        "baseline_check": dict(result.check or {}),
        "other_baseline": result.dependence,
        "residual_features": merged_features(result),
        "structure_left": None if result.structure is None else result.structure.to_dict(),
        "model": result.fit.model.describe(),
        "params": {k: _num(v) for k, v in result.fit.values.items()},
        "stderr": {k: _num(v) for k, v in result.stderr.items()},
        "held_by_design": dict(result.design_held),
        "model_params": {k: _num(float(v)) for k, v in result.fit.model.flat_params().items()},
        "regimes": dict(result.regimes),
        "tie_experiments": {t[0]: {e: EFFECTS.get(e).experiment_for(data.kind) for e in t}
                            for t in result.ties},
        "design": None if result.design is None else result.design.to_dict(),
        "confounding": [dict(c) for c in result.confounding],
        "pairs": [dict(p) for p in result.pairs],
        "forms": [dict(f) for f in result.refined],
        "structures": [st.to_dict() for st in result.structures],
        "skipped": dict(result.skipped),
        "split": result.ground.split.description,
        "noise_method": result.noise_floor.method,
        "disturbances": [d.to_dict() for d in result.disturbances],
        "units": "N",
        "warnings": [w.to_dict() for w in result.warnings],
        "model_file": model_file(result),
        "tie_models": tie_models(result),
    }
