"""The open questions of a diagnosis (its ``--json`` document), each with the models it opposes.

* ``tie``: effects the record fits equally well (``ties``); the final model against each
  rival the diagnosis fitted (``model_file.source.diagnosis.rivals``) -- the rival
  effect put in place of the tied one in the final model, its fitted values kept.
* ``untested``: an effect the diagnosis skipped because the record could not test it
  (``skipped``, a reason other than "already part of" the model); the final model
  against the final model with that effect at a size worth finding (:func:`alternative`).
* ``parameter``: a value at a bound, not identified, or with an interval through zero
  (``warnings`` with codes :data:`UNDETERMINED`); its interval before (the diagnosis's
  standard error) and after the programme (Fisher information, :mod:`.criteria`).

A field missing from the document is a question not asked (older diagnoses, other
versions); a document that is not a diagnosis is refused with one line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from fcomp.errors import FcompError
from fcomp.models.base import FrictionModel
from fcomp.planning.rig import MAXIMA

#: The warning codes that make a parameter an open question.
UNDETERMINED = ("at-bound", "not-identified", "interval-crosses-zero")
#: Skip reasons that are no question (the effect is in the model already).
NOT_A_QUESTION = ("already part of", "not applicable", "measured directly", "no area enters")
#: Keys every diagnose JSON has.
REQUIRED = ("verdict", "noise_floor", "model_file", "added")
#: The largest force noise (N) a diagnosis may give: the force of a large press.
NOISE_MAX = MAXIMA["noise"]


@dataclass
class Question:
    """One open question: ``kind`` (``tie`` / ``untested`` / ``parameter``), a label, the
    models it opposes (name -> model; the first is the diagnosis's answer) or the parameter."""

    kind: str
    label: str
    models: dict[str, FrictionModel] = field(default_factory=dict)
    parameter: str | None = None
    reason: str = ""
    stderr_before: float | None = None
    value: float | None = None
    notes: list[str] = field(default_factory=list)


@dataclass
class Diagnosed:
    """What the design reads from a diagnosis: the final model, the noise floor, the
    record's files, the questions."""

    model: FrictionModel
    noise_floor: float
    data: list[str]
    kind: str
    source: str
    questions: list[Question]
    skipped_notes: list[str]
    stderr: dict[str, float] = field(default_factory=dict)
    #: Lines for the effects named that fcomp does not know (left out; :func:`_unknown`).
    ignored: list[str] = field(default_factory=list)


def _check(doc: Any, label: str) -> Mapping[str, Any]:
    if not isinstance(doc, Mapping) or any(k not in doc for k in REQUIRED):
        missing = [k for k in REQUIRED if not isinstance(doc, Mapping) or k not in doc]
        raise FcompError(f"{label}: not a diagnosis (no {', '.join(missing)}); give the "
                         "--json output of fcomp diagnose")
    nf = doc["noise_floor"]
    if isinstance(nf, bool) or not isinstance(nf, (int, float)) or not (
            math.isfinite(nf) and 0 < nf <= NOISE_MAX):
        raise FcompError(f"{label}: noise_floor must be a positive force of at most "
                         f"{NOISE_MAX:g} N, got {nf!r}")
    if not isinstance(doc["model_file"], Mapping):
        raise FcompError(f"{label}: model_file is not a model document")
    shapes = (("ties", "a list of lists of effect names", lambda v: isinstance(v, list) and all(
                  isinstance(t, list) and all(isinstance(e, str) for e in t) for t in v)),
              ("skipped", "an object of effect name: reason", lambda v: isinstance(v, Mapping)
               and all(isinstance(r, str) for r in v.values())),
              ("added", "a list of effect names", lambda v: isinstance(v, list)
               and all(isinstance(e, str) for e in v)),
              ("warnings", "a list of objects", lambda v: isinstance(v, list)),
              ("tie_models", "a list of objects", lambda v: isinstance(v, list)),
              ("signals", "an object", lambda v: isinstance(v, Mapping)))
    for key, shape, ok in shapes:
        if doc.get(key) is not None and not ok(doc[key]):
            raise FcompError(f"{label}: {key} must be {shape}, as fcomp diagnose writes it; "
                             f"got {type(doc[key]).__name__}")
    return doc


def _unknown(doc: Mapping[str, Any]) -> list[str]:
    """Lines for the effects the diagnosis names (``ties``, ``skipped``) that fcomp does not
    know -- an effects file's, run without it: they are left out of the design."""
    from fcomp.effects import EFFECTS

    out = []
    for tie in doc.get("ties") or []:
        odd = [e for e in tie if e not in EFFECTS]
        if odd:
            out.append(f"tie {' vs '.join(tie)}: {', '.join(odd)} is no effect fcomp knows "
                       "(an effects file's?): the tie is not designed for")
    odd = [e for e in doc.get("skipped") or {} if e not in EFFECTS]
    if odd:
        out.append(f"untested {', '.join(odd)}: no effect fcomp knows (an effects file's?): "
                   "not designed for")
    return out


def _model(doc: Mapping[str, Any], label: str) -> FrictionModel:
    from fcomp.modelfile import read_model

    try:
        return read_model(dict(doc)).measured_model()
    except FcompError as exc:
        raise FcompError(f"{label}: its model is not usable ({exc})") from None


def _swapped(final: FrictionModel, tied: str, rival: FrictionModel, effect: str
             ) -> FrictionModel | None:
    """``final`` with the effect ``tied`` replaced by ``rival``'s ``effect`` (its fitted
    values); None when either is a structural term of the model (no swap by parts)."""
    mine = [e for e in final.effects if e.name == tied]
    theirs = [e for e in rival.effects if e.name == effect]
    if len(mine) != 1 or len(theirs) != 1:
        return None
    kept = tuple(e for e in final.effects if e.name != tied)
    return final._rebuild(final.params, (*kept, theirs[0]))


def _step_ties(doc: Mapping[str, Any], label: str) -> list[Question]:
    """The ties with every tied effect's model as fitted at its step (``tie_models``)."""
    out = []
    for t in doc.get("tie_models") or []:
        if not isinstance(t, Mapping) or not isinstance(t.get("effects"), Mapping):
            continue
        eff = t["effects"]
        chosen = str(t.get("chosen") or next(iter(eff)))
        order = [chosen, *[e for e in eff if e != chosen]]
        q = Question("tie", " vs ".join(order),
                     {e: _model(eff[e], label) for e in order if isinstance(eff[e], Mapping)},
                     reason=f"{chosen} was added at step {t.get('step')}; "
                            f"{', '.join(order[1:])} fit as well")
        q.notes.append("each rival as the diagnosis fitted it at that step (the same effects "
                       "before it)")
        if len(q.models) > 1:
            out.append(q)
    return out


def ties(doc: Mapping[str, Any], final: FrictionModel, label: str) -> list[Question]:
    """One question per tie: the tied effects' models as fitted at their step when the
    diagnosis wrote them (``tie_models``), else the final model and each rival."""
    if doc.get("tie_models"):
        return _step_ties(doc, label)
    rivals = ((doc["model_file"].get("source") or {}).get("diagnosis") or {}).get("rivals") or []
    out = []
    from fcomp.effects import EFFECTS

    for tie in doc.get("ties") or []:
        if len(tie) < 2 or any(e not in EFFECTS for e in tie):
            continue
        first = str(tie[0])
        q = Question("tie", " vs ".join(map(str, tie)), {first: final},
                     reason=f"{first} was added; {', '.join(map(str, tie[1:]))} fit as well")
        for r in rivals:
            if not isinstance(r, Mapping) or not str(r.get("why", "")).startswith(
                    f"tied with {first}"):
                continue
            rival = _model(r.get("model_file") or {}, label)
            names = {e.name for e in rival.effects}
            for eff in tie[1:]:
                if eff in names and eff not in q.models:
                    swapped = _swapped(final, first, rival, eff)
                    if swapped is None:  # a structural term: the rival, with the effects
                        later = [e for e in final.effects  # the final model added beside
                                 if e.name not in names and e.name != first]
                        swapped = rival.with_effects(*later) if later else rival
                        q.notes.append(f"{eff}: the rival as the diagnosis fitted it"
                                       + (f", with {', '.join(e.name for e in later)} as "
                                          "in the final model" if later else ""))
                    q.models[eff] = swapped
        missing = [e for e in tie[1:] if e not in q.models]
        if missing:
            q.notes.append(f"no fitted rival for {', '.join(map(str, missing))} in the "
                           "diagnosis: tested as an untested effect instead")
        out.append(q)
    return out


def untested(doc: Mapping[str, Any], final: FrictionModel) -> list[Question]:
    """One question per effect the record could not test (its reason kept)."""
    from fcomp.effects import EFFECTS

    out = []
    skipped = doc.get("skipped") or {}
    have = {e.name for e in final.effects} | set(getattr(final, "features", ()) or ())
    for effect, reason in skipped.items() if isinstance(skipped, Mapping) else ():
        if any(s in str(reason) for s in NOT_A_QUESTION) or effect in have:
            continue
        if effect not in EFFECTS:
            continue
        out.append(Question("untested", effect, {"without": final}, reason=str(reason)))
    return out


def parameters(doc: Mapping[str, Any], final: FrictionModel) -> list[Question]:
    """One question per parameter the diagnosis flagged undetermined."""
    stderr = doc["model_file"].get("stderr") or {}
    params = {**(doc.get("params") or {}), **final.flat_params()}
    seen: dict[str, Question] = {}
    for w in doc.get("warnings") or []:
        if not isinstance(w, Mapping) or w.get("code") not in UNDETERMINED:
            continue
        name = w.get("parameter")
        if not isinstance(name, str) or "," in name:
            continue
        if name in seen:
            seen[name].reason += f"; {w['code']}"
            continue
        se = stderr.get(name)
        val = params.get(name)
        seen[name] = Question("parameter", name, {}, parameter=name, reason=str(w["code"]),
                              stderr_before=float(se) if isinstance(se, (int, float)) else None,
                              value=float(val) if isinstance(val, (int, float)) else None)
    return list(seen.values())


def read_diagnosis(doc: Any, label: str = "diagnosis") -> Diagnosed:
    """The design's view of a diagnose JSON document (checked; one line if not one)."""
    doc = _check(doc, label)
    final = _model(doc["model_file"], label)
    source = (doc["model_file"].get("source") or {})
    data = [str(p) for p in source.get("data") or [] if isinstance(p, str)]
    sig = doc.get("signals") or {}
    qs = [*ties(doc, final, label), *untested(doc, final), *parameters(doc, final)]
    notes = [f"{e}: {r}" for e, r in (doc.get("skipped") or {}).items()
             if any(s in str(r) for s in NOT_A_QUESTION)]
    return Diagnosed(model=final, noise_floor=float(doc["noise_floor"]), data=data,
                     kind=str(doc.get("kind") or "pneumatic-cylinder"),
                     source=str(sig.get("force") or "F"), questions=qs, skipped_notes=notes,
                     stderr={k: float(v) for k, v in
                             (doc["model_file"].get("stderr") or {}).items()
                             if isinstance(v, (int, float)) and math.isfinite(v) and v > 0},
                     ignored=_unknown(doc))
