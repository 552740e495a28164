"""The diagnosis's sentences: the rule's and the verdict's data put into words.

:class:`.rule.Judgement` and :class:`.verdict.Verdict` carry codes and figures;
this module alone writes them as the English of the JSON's ``reason`` fields,
the report and the console.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

from fcomp.diagnosis.features import TRIM
from fcomp.diagnosis.rule import Failure, Judgement
from fcomp.diagnosis.verdict import Verdict

QUALIFIES = "qualifies by the acceptance rule"

_FAILURES: dict[str, Callable[[Mapping[str, Any]], str]] = {
    "no-fall": lambda f: (f"held-out RMS does not fall ({f['before']:.4g} -> "
                          f"{f['after']:.4g} N)"),
    "small-fall": lambda f: (f"where it changes the prediction the held-out RMS falls by "
                             f"{f['fall']:.3g} N < {f['need']:.3g} N"),
    "small-share": lambda f: (f"explains only {100 * f['share']:.0f} % of the excess over the "
                              f"noise floor where it acts (< {100 * f['least']:.0f} %)"),
    "not-significant": lambda f: (f"fall not significant (z = {f['z']:.2g}, p = {f['p']:.2g} "
                                  f"> {f['most']:g})"),
    "outside-signature": lambda f: (f"its fall lies outside its signature: "
                                    f"{100 * f['share']:.0f} % of the held-out fall where it "
                                    f"acts ({f['where']}; < {100 * f['least']:.0f} %)"),
    "confounded-with-time": lambda f: (f"confounded with time: a slow drift of the friction "
                                       f"level alone takes {f['drift']:.3g} N off the held-out "
                                       f"RMS (this effect {f['fall']:.3g} N)"),
    "bic": lambda f: f"BIC does not agree (dBIC = {f['delta_bic']:.3g})",
}


def failure_text(failure: Failure) -> str:
    """One failed test of the acceptance rule, in words with its numbers."""
    return _FAILURES[failure.code](failure.figures)


def judgement_text(judgement: Judgement) -> str:
    """Why a candidate does not qualify (empty when it does)."""
    return "; ".join(failure_text(f) for f in judgement.failures)


def verdict_text(v: Verdict) -> str:
    """The verdict's reason: the rule that decided it, with its numbers."""
    r, nf, ev, ring = v.rule, v.noise, v.event, v.ring
    after = ("" if ev is None else f"structure after events: within "
             f"{1e3 * ev.window:.0f} ms of every start and reversal the held-out residual ")
    floor_words = (f"{nf:.3g} N" if v.noise_timing <= 1.0005 * nf else
                   f"{v.noise_timing:.3g} N: {nf:.3g} N of noise and what the right model "
                   "scores within the events' timing windows")
    if v.cause == "event-repeats":
        assert ev is not None
        text = (f"{after}repeats (strength {ev.strength:.2f} >= {r.structure_min:g} of the time "
                f"since the event; it carries {ev.rms:.3g} N RMS >= {v.least:.3g} N there)")
    elif v.cause == "event-excess":
        assert ev is not None
        text = (f"{after}(without its largest {100 * TRIM:g} %) is {ev.local:.3g} N RMS, above "
                f"{r.event_excess:g} noise floors of {nf:.3g} N, with {v.event_excess:.3g} N RMS "
                f"above the noise >= {v.least:.3g} N (it does not repeat in phase: strength "
                f"{ev.strength:.2f})")
    elif v.cause == "ring":
        assert ring is not None
        text = (f"structure after events: a ring at {ring.frequency:.3g} Hz after every start "
                f"and reversal ({ring.events} held-out windows; "
                f"{100 * ring.concentration:.0f} % of the excess power within three bins) "
                f"carries {ring.rms:.3g} N RMS there, >= "
                f"{max(r.ring_noise * nf, r.ring_level * v.force_scale):.3g} N "
                f"({r.ring_noise:g} noise floor, {100 * r.ring_level:g} % of the friction "
                "level): a rig mode no friction law explains")
    elif v.cause == "structure":
        top = v.features[0]
        text = (f"structure: the held-out residual still follows {top.feature} (strength "
                f"{top.strength:.2f} >= {r.structure_min:g}; it carries "
                f"{v.rms_final * math.sqrt(top.strength):.3g} N RMS >= {v.least:.3g} N, a noise "
                f"floor and {100 * r.structure_level:g} % of the friction level)")
    elif v.cause == "excess":
        text = (f"excess: the held-out RMS without its largest {100 * TRIM:g} % "
                f"({v.trimmed:.3g} N) is above {v.limit:.3g} N ({r.excess_max:g} noise floors "
                f"of {floor_words}, and the floor plus {100 * r.structure_level:g} % of the "
                "friction level), though no single feature explains it")
    else:
        text = (f"at the noise: held-out RMS without its largest {100 * TRIM:g} % "
                f"{v.trimmed:.3g} N within {v.limit:.3g} N (noise floor {floor_words}), and no "
                f"structure carries {v.least:.3g} N")
    if v.lines:
        what = ", ".join(f"{d.frequency_hz:.4g} Hz ({d.amplitude:.3g} N amplitude)"
                         for d in v.lines)
        text = (f"periodic disturbance: a narrow line in the residual that follows no motion "
                f"feature at {what}, taken off the force before the diagnosis (no friction law "
                f"explains it: look for a pump, a fan, mains hum, a valve dither); the rest: "
                f"{text}")
    if v.edge:
        text += (f"; the final fit sits at a bound of its box for {', '.join(v.edge)} (after "
                 "the boxes the record's scale set were widened): the error may be the box's, "
                 "not the model's")
    return text


def dependence_text(dependence: Mapping[str, Any] | None) -> str:
    """What the baseline check adds to the reason: the other baseline's answer, if it differs."""
    if not dependence or not dependence["dependent"]:
        return ""
    return (f"; the effects found depend on the baseline: from {dependence['baseline']} the "
            f"diagnosis adds {', '.join(dependence['added']) or 'nothing'} "
            f"({dependence['verdict']})")
