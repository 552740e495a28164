"""What a diagnosis found, as one frozen value, and the baseline check's comparison.

:class:`DiagnosisResult` is built once the search has stopped
(:meth:`DiagnosisResult.of`): the steps, the fits, the verdict (data,
:class:`.verdict.Verdict`), the plausibility warnings, the regimes' errors;
the JSON and the report are written from it (:mod:`.writers`, :mod:`.report`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from fcomp.diagnosis.advice import reword
from fcomp.diagnosis.data import DiagnosisData
from fcomp.diagnosis.design import Design
from fcomp.diagnosis.disturbance import Disturbance
from fcomp.diagnosis.features import EventRing, EventStructure, FeatureStrength
from fcomp.diagnosis.noise import NoiseFloor
from fcomp.diagnosis.refit import FitResult, Refit
from fcomp.diagnosis.regimes import Segmentation
from fcomp.diagnosis.residuals import regime_errors
from fcomp.diagnosis.rule import Ground
from fcomp.diagnosis.seal_structures import SealStructure, seal_structures
from fcomp.diagnosis.search import Candidate, Search, Step
from fcomp.diagnosis.split import Split
from fcomp.diagnosis.structure_left import StructureLeft, structure_left
from fcomp.diagnosis.verdict import Verdict, VerdictRule, conclude
from fcomp.diagnosis.wording import dependence_text, verdict_text
from fcomp.effects import EFFECTS
from fcomp.errors import FcompError
from fcomp.identification.plausibility import FitWarning
from fcomp.models import FrictionModel


@dataclass(frozen=True)
class DiagnosisResult:
    """One diagnosis's findings (attributes as :class:`.loop.Diagnosis`'s ``*_`` ones).

    ``check`` is ``{"ran": bool, "why": str}`` (the baseline check) and ``other``
    the other baseline's result when it ran; ``design`` the record's design
    (:mod:`.design`) and ``confounding`` the ties it makes (:mod:`.confounding`);
    ``pairs`` the pairs judged (:mod:`.pairs`), ``refined`` the refined forms tried
    (:mod:`.forms`); ``stderr`` the final fit's standard errors; ``structures`` the seal
    structures named in its residual (:mod:`.seal_structures`); ``structure`` says what
    the structure left in the final residual follows (:mod:`.structure_left`).
    """

    baseline_name: str
    ground: Ground
    noise_floor: NoiseFloor
    baseline_fit: FitResult
    fit: FitResult
    steps: tuple[Step, ...]
    candidates: tuple[Candidate, ...]
    ties: tuple[tuple[str, ...], ...]
    added: tuple[str, ...]
    removed: tuple[str, ...]
    skipped: Mapping[str, str]
    disturbances: tuple[Disturbance, ...]
    verdict: Verdict
    regimes: Mapping[str, Any]
    warnings: tuple[FitWarning, ...]
    final_warnings: tuple[FitWarning, ...]
    check: Mapping[str, Any] | None = None
    other: DiagnosisResult | None = None
    design: Design | None = None
    confounding: tuple[Mapping[str, Any], ...] = ()
    pairs: tuple[Mapping[str, Any], ...] = ()
    refined: tuple[Mapping[str, Any], ...] = ()
    stderr: Mapping[str, float] = dataclasses.field(default_factory=dict)
    structures: tuple[SealStructure, ...] = ()
    design_held: Mapping[str, str] = dataclasses.field(default_factory=dict)
    structure: StructureLeft | None = None

    @classmethod
    def of(cls, search: Search, baseline_name: str, rule: VerdictRule) -> DiagnosisResult:
        """The result of a search that has stopped (no baseline check yet)."""
        assert search.baseline_fit is not None
        g, fit, base = search.ground, search.current, search.baseline_fit
        refit = search.refit
        # nothing added: the baseline is the final model, and its flags are the final fit's
        first = _fit_warnings(refit, g, base, f"baseline {baseline_name}" if fit is not base
                              else f"final model {baseline_name} (the baseline, nothing "
                              "added)", search.design)
        final = first
        steps = list(search.steps)
        for i, st in enumerate(steps):
            if st.accepted and st.fit is not None and st.fit is not fit:
                steps[i] = dataclasses.replace(
                    st, warnings=tuple(_fit_warnings(refit, g, st.fit, f"after + {st.effect}",
                                                     search.design)))
        if fit is not base:
            final = _fit_warnings(refit, g, fit, f"final model {fit.model.describe()}",
                                  search.design)
            steps = [dataclasses.replace(st, warnings=tuple(final)) if st.fit is fit else st
                     for st in steps]
        warnings = (first + final if fit is not base else first) + list(g.split.warnings)
        verdict = conclude(fit, g, search.disturbances, final, rule)
        test = g.split.test
        left = structure_left(fit, g.data, g.segmentation, g.split.train, test, verdict,
                              search.disturbances)
        return cls(baseline_name, g, search.noise_floor, base, fit, tuple(steps),
                   tuple(search.candidates), tuple(tuple(t) for t in search.ties),
                   tuple(search.added), tuple(search.removed), dict(search.skipped),
                   tuple(search.disturbances), verdict,
                   {"baseline": regime_errors(base.residual, g.segmentation, test),
                    "final": regime_errors(fit.residual, g.segmentation, test)},
                   tuple(warnings), tuple(final), design=search.design,
                   confounding=tuple(dict(c) for c in search.confounding),
                   pairs=tuple(dict(p) for p in search.pairs),
                   refined=tuple(dict(f) for f in search.refined),
                   stderr=_stderr(refit, fit, final),
                   structures=tuple(seal_structures(fit.plain_residual, fit.F_hat, g.data,
                                                    g.segmentation, verdict.least)),
                   design_held=dict(search.design_held), structure=left)

    @property
    def doubts(self) -> list[str]:
        """Why the answer might depend on the baseline (empty: a clean answer).

        The final model's fit flagged (a parameter at a bound, an interval
        through zero, an implausible mass, ...), a tie, or a verdict of
        ``unexplained-structure``. The baseline's own flags do not count when
        effects were added: a baseline that misses an effect is expected to
        bend its parameters.
        """
        out = []
        if self.verdict.verdict != "explained":
            out.append(f"the verdict is {self.verdict.verdict}")
        fits = sorted({w.code for w in self.final_warnings})
        if fits:
            out.append(f"the final fit is flagged ({', '.join(fits)})")
        if self.ties:
            out.append("effects tie")
        return out

    @property
    def dependence(self) -> dict[str, Any] | None:
        """Whether the effects found depend on the baseline, and the other baseline's answer.

        The added effects are compared after leaving out, on each side, the
        effects the *other* baseline already holds (``presliding`` added to a
        static map is part of LuGre) and counting the members of a reported tie
        as one. ``None`` without a check.
        """
        other = self.other
        if other is None:
            return None
        mine = comparable(self.added, self.ties, other.baseline_fit.model)
        theirs = comparable(other.added, other.ties, self.baseline_fit.model)
        return {"dependent": not same_findings(mine, theirs), "baseline": other.baseline_name,
                "added": list(other.added), "verdict": other.verdict.verdict,
                "rms_baseline": other.baseline_fit.rms_test,
                "rms_final": other.fit.rms_test}

    @property
    def reason(self) -> str:
        """The rule that decided the verdict, with its numbers, in words."""
        return verdict_text(self.verdict) + dependence_text(self.dependence)


def _stderr(refit: Refit, fit: FitResult, warnings: Sequence[FitWarning]
            ) -> dict[str, float]:
    """The standard errors of ``fit``'s fitted parameters (:meth:`.Refit.uncertainty`; NaN
    where the record does not determine one; empty when they cannot be computed).

    A value at a bound of its box (an ``at-bound`` warning of ``fit``, ``warnings``) has no
    standard error: the Jacobian's column there says nothing of the data (1.3e38 N for an
    O-ring's ``Fs`` at its bound), so it is NaN -- null in the JSON and the model file, "-"
    in the report -- and the flag says why."""
    try:
        stderr = dict(refit.uncertainty(fit).stderr)
    except (FcompError, ValueError, ArithmeticError, np.linalg.LinAlgError):
        return {}
    for w in warnings:
        if w.code == "at-bound" and w.parameter:
            for name in w.parameter.split(","):
                if name.strip() in stderr:
                    stderr[name.strip()] = math.nan
    return stderr


def _fit_warnings(refit: Refit, ground: Ground, fit: FitResult, what: str,
                  design: Design | None = None) -> list[FitWarning]:
    """The plausibility warnings of one fit of the diagnosis, each naming the fit, their
    advice matched to the record's design and the diagnosis's options (:mod:`.advice`)."""
    try:
        found = refit.plausibility(fit, ground.data.rig)
    except (FcompError, ValueError, ArithmeticError, np.linalg.LinAlgError):
        return []
    found = reword(found, design, ground.data.kind)
    return [FitWarning(w.code, w.parameter, f"{what}: {w.message}") for w in found]


#: The baseline of the other kind the baseline check uses (static <-> dynamic).
OTHER_BASELINE = {"static": "lugre", "dynamic": "stribeck"}


def other_baseline(model: FrictionModel, ground: Ground) -> str | None:
    """The baseline of the other kind for the check, or None if the data cannot take it.

    A static map's check is ``lugre`` (not on steady-state points or records
    without a start); a dynamic model's is the ``stribeck`` map.
    """
    if model.n_states:
        return OTHER_BASELINE["dynamic"]
    if ground.data.steady_state or not ground.segmentation.starts:
        return None
    return OTHER_BASELINE["static"]


def comparable(added: Sequence[str], ties: Sequence[Sequence[str]],
               other: FrictionModel) -> frozenset[frozenset[str]]:
    """The added effects the ``other`` baseline does not already hold, each as its tie group."""
    out = set()
    for name in added:
        try:
            if not EFFECTS.get(name)().applies_to(other):
                continue  # part of the other baseline (presliding in LuGre)
        except (TypeError, ValueError):
            pass
        group = next((t for t in ties if name in t), [name])
        out.add(frozenset(group))
    return frozenset(out)


def same_findings(mine: frozenset[frozenset[str]], theirs: frozenset[frozenset[str]]) -> bool:
    """Whether two diagnoses found the same effects, a tie on either side matching any member.

    Each finding is its tie group (one name when there is no tie); a finding of
    one side is matched by a finding of the other that shares a member, and the
    two agree when every finding on each side is matched (a tie reported on one
    side only is no disagreement).
    """
    def covered(a: frozenset[frozenset[str]], b: frozenset[frozenset[str]]) -> bool:
        return all(any(g & h for h in b) for g in a)

    return covered(mine, theirs) and covered(theirs, mine)


class FittedAttributes:
    """The ``*_`` attributes of a fitted diagnosis, read off its ``result_`` (sklearn style)."""

    @property
    def _result(self) -> DiagnosisResult:
        result = vars(self).get("result_")
        if result is None:
            raise AttributeError("this Diagnosis is not fitted yet: call fit(data) first")
        return result

    @property
    def data_(self) -> DiagnosisData:
        return self._result.ground.data

    @property
    def segmentation_(self) -> Segmentation:
        return self._result.ground.segmentation

    @property
    def split_(self) -> Split:
        return self._result.ground.split

    @property
    def noise_floor_(self) -> NoiseFloor:
        return self._result.noise_floor

    @property
    def baseline_fit_(self) -> FitResult:
        return self._result.baseline_fit

    @property
    def fit_(self) -> FitResult:
        return self._result.fit

    @property
    def steps_(self) -> list[Step]:
        return list(self._result.steps)

    @property
    def candidates_(self) -> list[Candidate]:
        return list(self._result.candidates)

    @property
    def ties_(self) -> list[list[str]]:
        return [list(t) for t in self._result.ties]

    @property
    def added_(self) -> list[str]:
        return list(self._result.added)

    @property
    def removed_(self) -> list[str]:
        return list(self._result.removed)

    @property
    def skipped_(self) -> dict[str, str]:
        return dict(self._result.skipped)

    @property
    def disturbances_(self) -> list[Disturbance]:
        return list(self._result.disturbances)

    @property
    def rms_baseline_(self) -> float:
        return self._result.baseline_fit.rms_test

    @property
    def rms_final_(self) -> float:
        return self._result.fit.rms_test

    @property
    def verdict_(self) -> str:
        return self._result.verdict.verdict

    @property
    def reason_(self) -> str:
        return self._result.reason

    @property
    def residual_features_(self) -> list[FeatureStrength]:
        return list(self._result.verdict.features)

    @property
    def structure_left_(self) -> StructureLeft | None:
        """What the structure left in the final residual follows (:mod:`.structure_left`)."""
        return self._result.structure

    @property
    def event_structure_(self) -> EventStructure | None:
        return self._result.verdict.event

    @property
    def event_ring_(self) -> EventRing | None:
        return self._result.verdict.ring

    @property
    def regimes_(self) -> dict[str, Any]:
        return dict(self._result.regimes)

    @property
    def warnings_(self) -> list[FitWarning]:
        return list(self._result.warnings)

    @property
    def baseline_name_(self) -> str:
        return self._result.baseline_name

    @property
    def baseline_check_(self) -> dict[str, Any]:
        return dict(self._result.check or {})

    @property
    def baseline_dependent_(self) -> bool:
        dep = self._result.dependence
        return bool(dep and dep["dependent"])
