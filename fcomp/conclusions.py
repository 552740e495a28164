"""What a result means, first: the engineer-level conclusion every command and report opens with.

A :class:`Conclusion` says what was found (one sentence), how sure it is
(``high``, ``medium`` or ``low``, with the reasons: the flags where a number
should not be trusted) and what to do next. It is built from a result's
JSON document (the ``--json`` output of ``fcomp fit``, ``compare``,
``diagnose``), so the console, the report and a script reading the JSON
all draw the same conclusion::

    c = of_diagnosis(diag.to_dict())
    print("\\n".join(c.lines()))      # Conclusion / How sure / Next
    report.conclusion(c)              # the report's opening (fcomp.report.Report)

Flags come from the result's warnings (codes of
:mod:`fcomp.identification.plausibility`) and from comparisons that hold
whatever the model: a held-out RMS below the noise floor (over-fitting, or a
floor estimate that is off), an "explained" model whose parameters the record
does not determine, an answer that depends on the baseline.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

#: The confidence levels, worst first.
LEVELS = ("low", "medium", "high")

#: What a result says, worst first: the claim fails or the model leaves structure
#: (``bad``), holds in part (``mixed``), holds (``good``).
OUTCOMES = ("bad", "mixed", "good")

#: The colours of a report (its note kinds), worst first: red, amber, green.
TONES = ("bad", "warn", "ok")


def tone(outcome: str | None, confidence: str) -> str:
    """The one colour rule of every report and page: the colour of a result is the worse
    of what it says and how sure it is -- green (``ok``) only for a favourable result held
    with high confidence; amber (``warn``) for one that holds in part or is only medium
    sure; red (``bad``) for a result that fails, or one held with low confidence. An
    "explained" verdict whose fit is not to be trusted is therefore not green beside a red
    "How sure: low", and a study sure that a claim is not reproduced is red, not green.

    ``outcome``: one of :data:`OUTCOMES`, or ``None`` (only the confidence colours)."""
    by_confidence = TONES[LEVELS.index(confidence)] if confidence in LEVELS else "bad"
    if outcome is None:
        return by_confidence
    return TONES[min(OUTCOMES.index(outcome), TONES.index(by_confidence))]

#: A held-out RMS below this fraction of the noise floor is suspect: a model that is right
#: leaves the noise (RMS about the floor); well below it, it fits noise, or the floor
#: estimate is off.
BELOW_FLOOR = 0.8

def below_floor(rms: float | None, floor: float | None) -> bool:
    """Whether ``rms`` is well below the noise floor ``floor`` (:data:`BELOW_FLOOR`; a
    floor under 1 uN is a noise-free record, where nothing is below it)."""
    return (rms is not None and floor is not None and floor > 1e-6
            and rms < BELOW_FLOOR * floor)


#: Codes whose parameters the record does not determine (the number is not to be trusted).
UNDETERMINED = ("at-bound", "not-identified", "interval-crosses-zero")

_CONTEXT = re.compile(r"^(baseline|final model) [^:]*: ")
_EXPERIMENT = re.compile(r"to determine (?:it|them): ([^;]+)")


@dataclass(frozen=True)
class Conclusion:
    """The opening of a result: what was found, how sure, what next.

    Parameters
    ----------
    finding
        One sentence: what was found, with the number that says it.
    confidence
        ``"high"``, ``"medium"`` or ``"low"``.
    reasons
        Why not ``high`` (each a short clause naming the number not to trust);
        empty when ``high``.
    next_steps
        What to do next, most useful first.
    outcome
        What the finding says (:data:`OUTCOMES`: ``"good"``, ``"mixed"``, ``"bad"``), or
        ``None``: it only reports numbers. With the confidence it decides the colour
        (:func:`tone`, :attr:`tone`).
    """

    finding: str
    confidence: str
    reasons: tuple[str, ...] = ()
    next_steps: tuple[str, ...] = ()
    outcome: str | None = None

    @property
    def tone(self) -> str:
        """The colour of this conclusion wherever it is shown (:func:`tone`)."""
        return tone(self.outcome, self.confidence)

    def lines(self) -> list[str]:
        """The console form: ``Conclusion:``, ``How sure:`` (with its reasons) and ``Next:``,
        the lists as indented ``- `` items (at most :data:`SHOWN` each)."""
        out = [f"Conclusion: {self.finding}",
               f"How sure: {self.confidence}" + (", because" if self.reasons else "")]
        out += _items(self.reasons)
        if self.next_steps:
            out += ["Next:", *_items(self.next_steps)]
        return out


#: Most reasons and next steps a console conclusion lists (a report lists them all).
SHOWN = 4


def _items(texts: Sequence[str]) -> list[str]:
    out = [f"  - {t}" for t in texts[:SHOWN]]
    if len(texts) > SHOWN:
        out.append(f"  - and {len(texts) - SHOWN} more (the report lists them)")
    return out


def _num(x: Any, unit: str = "N") -> str:
    return "-" if x is None else f"{x:.3g} {unit}"


def _lowest(*levels: str) -> str:
    return min(levels, key=LEVELS.index)


def context(message: str) -> str | None:
    """``"baseline"`` or ``"final model"`` for a diagnosis warning about that fit, else None."""
    m = _CONTEXT.match(message)
    return m.group(1) if m else None


def _params(items: Iterable[Mapping[str, Any]]) -> list[str]:
    out: list[str] = []
    for w in items:
        for p in str(w.get("parameter") or "").split(","):
            if p and p not in out:
                out.append(p)
    return out


def _experiments(items: Iterable[Mapping[str, Any]]) -> list[str]:
    """The experiments the warnings name ("to determine it: ..."), each once, with the
    parameters it would determine."""
    found: dict[str, list[str]] = {}
    for w in items:
        m = _EXPERIMENT.search(str(w.get("message", "")))
        if m:
            names = found.setdefault(m.group(1).strip().rstrip("."), [])
            names += [p for p in str(w.get("parameter") or "").split(",") if p and p not in names]
    return [f"record {exp} (it would determine {', '.join(ps)})" if ps else f"record {exp}"
            for exp, ps in found.items()]


def fit_flags(warnings: Sequence[Mapping[str, Any]], mass_option: str | None = "--mass"
              ) -> tuple[str, list[str], list[str]]:
    """``(confidence, reasons, next steps)`` of a fit from its warnings; ``mass_option`` is
    the command's option that gives the moving mass (None: it has none, the sidecar's
    ``rig.mass`` alone)."""
    by = {c: [w for w in warnings if w.get("code") == c] for c in
          ("not-converged", *UNDETERMINED, "mass-implausible")}
    reasons: list[str] = []
    level = "high"
    if by["not-converged"]:
        reasons.append("the fit did not converge (the values are where the solver stopped)")
        level = "low"
    if by["at-bound"]:
        reasons.append(f"{', '.join(_params(by['at-bound']))} at a bound of the allowed range "
                       "(no error bar)")
        level = _lowest(level, "low")
    if by["not-identified"]:
        reasons.append(f"{', '.join(_params(by['not-identified']))} not determined by the "
                       "record")
        level = _lowest(level, "low")
    if by["interval-crosses-zero"]:
        reasons.append(f"{', '.join(_params(by['interval-crosses-zero']))} not established "
                       "(the interval reaches zero)")
        level = _lowest(level, "medium")
    if by["mass-implausible"]:
        reasons.append("the fitted mass is implausible for the rig")
        level = _lowest(level, "medium")
    steps = _experiments(w for c in UNDETERMINED for w in by[c])
    if by["mass-implausible"]:
        steps.append("give the moving mass (rig.mass in the sidecar"
                     + (f", or {mass_option})" if mass_option else ")"))
    return level, reasons, steps


def of_fit(doc: Mapping[str, Any]) -> Conclusion:
    """The conclusion of a fit's JSON (``fcomp fit --json``; one record)."""
    params = doc.get("params") or {}
    undetermined = set(_params(w for w in doc.get("warnings", [])
                               if w.get("code") in UNDETERMINED))
    held = len(doc.get("not_identifiable") or [])
    known = len([p for p in params if p not in undetermined])
    finding = (f"{doc.get('model')} fitted over {doc.get('n_samples', '?')} samples: RMS force "
               f"error {_num(doc.get('rms'))}; {known} of {len(params) + held} parameters "
               "determined" + (f" ({held} held: the record does not determine them)"
                               if held else ""))
    level, reasons, steps = fit_flags(doc.get("warnings", []))
    steps.append("see where the model fails: fcomp compare DATA --friction "
                 f"{doc.get('model')} --params FIT.json --report DIR; what is missing: "
                 "fcomp diagnose")
    return Conclusion(finding, level, tuple(reasons), tuple(steps))


def of_comparison(doc: Mapping[str, Any]) -> Conclusion:
    """The conclusion of a comparison's JSON (``fcomp compare --json``)."""
    rms, floor = doc.get("rms"), doc.get("noise_floor")
    regimes = {k: v for k, v in (doc.get("regimes") or {}).items()
               if k != "all" and v.get("rms") is not None and v.get("n", 0) >= 10}
    worst = max(regimes, key=lambda k: regimes[k]["rms"]) if regimes else None
    ratio = rms / floor if rms is not None and floor else None
    at_noise = ratio is not None and ratio <= 1.5
    what = ("at the noise: nothing left to explain" if at_noise else
            f"{ratio:.1f} times the noise floor {_num(floor)}" if ratio is not None else
            "no noise floor to judge it by")
    finding = (f"{doc.get('description', doc.get('model'))} on these records: RMS "
               f"{_num(rms)}, {what}"
               + (f"; worst where it matters most: {worst} ({_num(regimes[worst]['rms'])})"
                  if worst and not at_noise else ""))
    reasons: list[str] = []
    level = "high"
    codes = {w.get("code") for w in doc.get("warnings", [])}
    if "default-params" in codes:
        reasons.append("the model's default values, not fitted to these records")
        level = "low"
    flagged, flags, experiments = fit_flags([w for w in doc.get("warnings", [])
                                             if w.get("code") in UNDETERMINED])
    if flags:  # as the fit or diagnosis that made the model said (the model file's stderr)
        reasons += flags
        level = _lowest(level, flagged)
    if below_floor(rms, floor):
        reasons.append(f"RMS below the noise floor {_num(floor)} (the floor estimate is off, "
                       "or the model was fitted to these very samples)")
        level = _lowest(level, "medium")
    if "heldout-coverage" in codes:
        reasons.append("part of the motion too short to judge")
        level = _lowest(level, "medium")
    steps: list[str] = list(experiments)
    top = (doc.get("residual_features") or [{}])[0]
    if not at_noise:  # from the model as compared (a file keeps its effects): nothing re-added
        steps.append(f"find the missing effect: fcomp diagnose DATA --friction "
                     f"{doc.get('friction') or doc.get('model')}"
                     + (f" (the residual follows {top['feature']}, strength "
                        f"{top['strength']:.2f})" if top.get("feature") else ""))
    if "default-params" in codes:
        steps.insert(0, "fit it first (fcomp fit ... --json FIT.json, then --params FIT.json)")
    return Conclusion(finding, level, tuple(reasons), tuple(steps),
                      outcome="good" if at_noise else "mixed")


def structure_words(follows: Sequence[Mapping[str, Any]]) -> str:
    """What the structure left follows (a diagnosis JSON's ``structure_left.follows``), the
    first two in words with their size: ``"time (strength 0.62, 1.3 N RMS; +0.18 N per s,
    7.2 N over the record)"``."""
    parts = []
    for f in follows[:2]:
        size = f"strength {f['strength']:.2f}, {_num(f.get('rms'))} RMS"
        if f.get("slope") is not None:
            size += (f"; {f['slope']:+.3g} N per {f['slope_per']}, {_num(f.get('change'))} "
                     "over the record")
        elif f.get("note"):
            size += f"; {f['note']}"
        elif f.get("change") is not None:
            size += f"; {_num(f.get('change'))} peak to peak"
        parts.append(f"{f['words']} ({size})")
    return " and ".join(parts)


def of_diagnosis(doc: Mapping[str, Any]) -> Conclusion:
    """The conclusion of a diagnosis's JSON (``fcomp diagnose --json``)."""
    added, base, final = doc.get("added") or [], doc.get("baseline"), doc.get("model")
    rb, rf, floor = doc.get("rms_baseline"), doc.get("rms_final"), doc.get("noise_floor")
    explained = doc.get("verdict") == "explained"
    if explained and added:
        finding = (f"{base} misses {', '.join(added)}; with them the held-out RMS falls "
                   f"{_num(rb)} -> {_num(rf)}, at the noise (floor {_num(floor)})")
    elif explained:
        finding = (f"{base} already explains the records: held-out RMS {_num(rf)}, at the "
                   f"noise (floor {_num(floor)}); no missing effect found")
    else:
        top = (doc.get("residual_features") or [{}])[0]
        same = (f" (one with {', '.join(top['same_as'])} on this record's fixed stroke)"
                if top.get("same_as") else "")
        named = [st["name"] for st in doc.get("structures") or []]
        follows = (doc.get("structure_left") or {}).get("follows") or []
        finding = (f"{final} leaves structure no catalogue effect explains: held-out RMS "
                   f"{_num(rf)} against a noise floor of {_num(floor)}"
                   + (f" (after adding {', '.join(added)})" if added else "")
                   + (f"; it follows {structure_words(follows)}" if follows else
                      f"; the residual follows {top['feature']}{same}" if top.get("feature")
                      else "")
                   + (f"; named: {', '.join(dict.fromkeys(named))}" if named else ""))
    final_warnings = [w for w in doc.get("warnings", []) if context(w.get("message", ""))
                      == "final model"]
    level, flags, steps = fit_flags(final_warnings, mass_option=None)  # diagnose: no --mass
    reasons: list[str] = []
    if doc.get("baseline_dependent"):
        other = doc.get("other_baseline") or {}
        reasons.append(f"the answer depends on the baseline (from {other.get('baseline')}: "
                       f"{', '.join(other.get('added') or []) or 'nothing'})")
        level = "low"
        steps.insert(0, "compare both models on a second record (fcomp compare REC2 "
                     "--friction MODEL.json) before trusting either")
    if below_floor(rf, floor):
        reasons.append(f"held-out RMS {_num(rf)} below the noise floor {_num(floor)}: "
                       "over-fitting, or the floor estimate is off")
        level = _lowest(level, "medium")
    if flags:
        reasons.append(("called explained, but the final fit is not to be trusted: "
                        if explained else "the final fit: ") + "; ".join(flags))
    for tie in doc.get("ties") or []:
        reasons.append(f"{' / '.join(tie)} fit equally well (confounded)")
        level = _lowest(level, "medium")
        # where the record's design confounds them, the experiment that separates the factors
        design = [c for c in doc.get("confounding") or [] if set(c["effects"]) <= set(tie)]
        exps = (doc.get("tie_experiments") or {}).get(tie[0], {})
        for c in design:
            steps.append(f"to tell {' from '.join(c['effects'])} (the record varies "
                         f"{' and '.join(c['factors'])} together): record {c['separates']}")
        covered = {e for c in design for e in c["effects"]}
        if exps and not set(tie) <= covered:
            steps.append(f"to tell {' from '.join(tie)}: record "
                         + "; ".join(f"{e}: {x}" for e, x in exps.items()))
    if level != "low" and explained:
        steps.append("use the final model: --save-model MODEL.json, then fcomp simulate / "
                     "fcomp compensate --controller-friction MODEL.json")
    if not explained:
        for exp in ((doc.get("structure_left") or {}).get("next_experiments") or [])[:2]:
            steps.append(f"to tell more ({exp['because'].replace('_', ' ')}): "
                         f"{exp['experiment']}")
        steps.append("look at the residual against each feature (--report DIR) and write the "
                     "effect (docs/effects.md)")
    return Conclusion(finding, level, tuple(reasons), tuple(steps),
                      outcome="good" if explained else "mixed")


#: What a warning code means, said once for a group of several warnings of that code.
MEANING: dict[str, str] = {
    "at-bound": "at a bound of the allowed range: the data push them beyond it (a missing "
                "effect, or a record that does not determine them); their error bars mean "
                "nothing",
    "interval-crosses-zero": "must be positive, but their intervals reach zero: the record "
                             "does not establish them (the term may be absent)",
    "not-identified": "not determined by the record (standard errors far above the values, or "
                      "parameters that trade off)",
    "mass-implausible": "fitted masses implausible for the rig: give rig.mass in the sidecar "
                        "(fcomp fit and fcomp compare also take --mass)",
    "not-converged": "fits that did not converge: the values are where the solver stopped",
    "heldout-coverage": "parts of the motion with too few held-out samples to be judged",
    "unknown-key": "sidecar keys the format does not read: they are kept but not used",
}


def _subject(message: str) -> str:
    """What a warning without a parameter concerns: its message's lead-in, after any
    baseline/final-model context (``"speed slow: 28 held-out ..."`` -> ``"speed slow"``)."""
    m = _CONTEXT.match(message)
    head = message[m.end():] if m else message
    lead = head.split(":", 1)[0].strip()
    return lead if lead and len(lead) <= 40 and lead != head else "the fit"


def grouped_warnings(items: Sequence[Mapping[str, Any]],
                     place: str = "in the JSON (--json OUT)") -> list[str]:
    """The warnings ``items`` (``{"code", "parameter", "message"}``) as lines to print: a code
    met once keeps its message; several of one code become one counted line naming what
    they concern; a last line says where (``place``) each is in full when any were grouped (the
    command line says which file, or that ``--json OUT`` would write them:
    :func:`fcomp.cli.app.run`)."""
    groups: dict[str, list[Mapping[str, Any]]] = {}
    for w in items:
        groups.setdefault(str(w.get("code")), []).append(w)
    out: list[str] = []
    for code, ws in groups.items():
        if len(ws) == 1:
            out.append(str(ws[0].get("message", "")))
            continue
        where: dict[str, list[str]] = {}
        for w in ws:
            message, parameter = str(w.get("message", "")), w.get("parameter")
            ctx = context(message)
            names = where.setdefault((ctx or "") if parameter else "", [])
            name = str(parameter or ctx or _subject(message))
            if name not in names:
                names.append(name)
        subjects = "; ".join(", ".join(n) + (f" ({c})" if c else "") for c, n in where.items())
        out.append(f"{len(ws)} x {code}: {subjects} -- "
                   f"{MEANING.get(code, f'each in full {place}')}")
    if len(out) < len(items):
        out.append(f"{len(items)} warnings in all, each in full in the JSON's \"warnings\" "
                   f"{place.removeprefix('in the JSON ')}")
    return out
