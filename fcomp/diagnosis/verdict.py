"""The verdict: is structure left in the final model's held-out residual?

:func:`conclude` returns a :class:`Verdict` -- the rule that decided and its
figures, as data; :mod:`.wording` writes the sentence. The final model's
residual is ``unexplained-structure`` when

* some feature (:mod:`.features`) explains at least ``structure_min`` of its
  held-out mean square *and* the part it explains is at least
  ``max(structure_rms*noise_floor, structure_level*force_scale)`` (RMS);
* the residual near starts and reversals (weighted as the fits weigh it:
  :func:`.scoring.sample_weights`) repeats as a function of the time since the
  event (:func:`.features.event_structure`), or, not in phase, lifts the RMS
  there above ``event_excess`` noise floors, or rings there (a narrow band of
  power quiet stretches lack, :func:`.features.event_ring`);
* the held-out RMS without its largest 1 % of samples
  (:func:`.features.trimmed_rms`) is above ``excess_max`` noise floors (the
  floor counting what the right model scores within the events' timing windows);
* or a periodic disturbance was taken off the force (:mod:`.disturbance`);

else ``explained``. The tool never accepts an effect that does not qualify
just because structure remains: it says so instead.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fcomp.diagnosis.disturbance import Disturbance
from fcomp.diagnosis.features import (
    EventRing,
    EventStructure,
    FeatureStrength,
    event_ring,
    event_structure,
    residual_structure,
    trimmed_rms,
)
from fcomp.diagnosis.refit import FitResult
from fcomp.diagnosis.rule import Ground
from fcomp.diagnosis.scoring import sample_weights
from fcomp.errors import FcompError
from fcomp.identification.plausibility import FitWarning

VERDICTS = ("explained", "unexplained-structure")


@dataclass(frozen=True)
class VerdictRule:
    """The thresholds of the verdict (module docstring).

    Parameters
    ----------
    structure_min
        Feature strength above which the residual "still follows" a feature.
    structure_rms
        Structure must carry at least this RMS, in noise floors, to count ...
    structure_level
        ... and this share of the friction level (the record's force scale).
    event_excess
        Trimmed RMS after events above this many noise floors is structure after
        events even where it does not repeat in phase.
    ring_concentration
        A ring after events counts when this share of its excess power lies in
        three adjacent bins ...
    ring_noise
        ... it carries this many noise floors (RMS in the windows after events) ...
    ring_level
        ... and this share of the friction level.
    excess_max
        Trimmed held-out RMS above this many noise floors is unexplained structure
        whatever the features say.
    """

    structure_min: float = 0.15
    structure_rms: float = 1.0
    structure_level: float = 0.015
    event_excess: float = 3.0
    ring_concentration: float = 0.6
    ring_noise: float = 0.5
    ring_level: float = 0.005
    excess_max: float = 2.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not (math.isfinite(value) and value >= 0.0):
                raise FcompError(f"VerdictRule: {name} must be finite and >= 0, got {value!r}")


@dataclass(frozen=True)
class Verdict:
    """The verdict and the figures of the rule that decided it (N unless said).

    ``cause`` is ``event-repeats``, ``event-excess``, ``ring``, ``structure``,
    ``excess`` or ``at-noise`` (the structure found, if any, else the size of the
    error); ``lines`` are periodic disturbances taken off the force (they make the
    verdict ``unexplained-structure`` whatever the cause); ``edge`` the final fit's
    parameters at a bound of their box.
    """

    verdict: str
    cause: str
    rule: VerdictRule
    noise: float
    noise_timing: float
    least: float
    trimmed: float
    limit: float
    rms_final: float
    force_scale: float
    features: tuple[FeatureStrength, ...]
    event: EventStructure | None
    event_excess: float
    ring: EventRing | None
    lines: tuple[Disturbance, ...]
    edge: tuple[str, ...]


def conclude(fit: FitResult, ground: Ground, lines: Sequence[Disturbance],
             final_warnings: Sequence[FitWarning], rule: VerdictRule) -> Verdict:
    """The verdict on the final ``fit`` (module docstring)."""
    data, seg, split, nf = ground.data, ground.segmentation, ground.split, ground.noise
    rms_final = fit.rms_test
    # where structure is left: the tolerant residual (a shape the model could place);
    # how large the error is: the scored residual (:func:`.scoring.scored_residual`)
    located = fit.located
    features = residual_structure(located, data, seg, split.train, split.test)
    # what counts: a structure as large as the noise and as a small share of the
    # friction level (a filtered, reconstructed force has a floor far below that)
    least = max(rule.structure_rms * nf, rule.structure_level * data.scales.force)
    top = features[0] if features else None
    structured = (top is not None and top.strength >= rule.structure_min
                  and rms_final * math.sqrt(top.strength) >= least)
    # after starts and reversals, where a jump of the law within the timing uncertainty
    # of the event leaves spikes no model could place, the residual counts as the fits
    # weigh it (a static map's full-level step one sample early is not a structure)
    r_events = located
    if fit.spread is not None:
        r_events = r_events * np.sqrt(sample_weights(fit.spread, nf))
    ev = event_structure(r_events, data, seg, split.train, split.test)
    event = ev is not None and ev.strength >= rule.structure_min and ev.rms >= least
    # a structure after events whose phase wanders from event to event lifts the
    # window's RMS (trimmed, weighted) well above the noise all the same
    ev_excess = 0.0 if ev is None else math.sqrt(max(ev.local**2 - nf**2, 0.0))
    event_excess = (ev is not None and not event and ev.local > rule.event_excess * nf
                    and ev_excess >= least)
    ring = event_ring(r_events, data, seg, split.test)
    ringing = (ring is not None and not (event or event_excess)
               and ring.concentration >= rule.ring_concentration
               and ring.rms >= max(rule.ring_noise * nf, rule.ring_level * data.scales.force))
    trimmed = trimmed_rms(fit.residual[split.test])
    # the right model's score within the timing windows of the events (a static law's
    # jump is placed only within them): the floor the scored error is held against
    nf_t = nf * math.sqrt(ground.timing_share(fit, np.flatnonzero(split.test)))
    limit = max(rule.excess_max * nf_t, nf_t + rule.structure_level * data.scales.force)
    excess = trimmed > limit
    if event and not structured:
        cause = "event-repeats"
    elif event_excess and not structured:
        cause = "event-excess"
    elif ringing and not structured:
        cause = "ring"
    elif structured:
        cause = "structure"
    else:
        cause = "excess" if excess else "at-noise"
    verdict = ("unexplained-structure" if cause != "at-noise" or lines else "explained")
    edge = tuple(sorted({w.parameter for w in final_warnings
                         if w.code == "at-bound" and w.parameter}))
    return Verdict(verdict, cause, rule, nf, nf_t, least, trimmed, limit, rms_final,
                   data.scales.force, tuple(features), ev, ev_excess, ring, tuple(lines), edge)
