"""The add / refit / score loop: which catalogue effect is missing, if any.

:class:`Diagnosis` (sklearn style: options in the constructor, :meth:`fit`
returns ``self``, results in ``*_`` attributes) is the configuration; its
:meth:`~Diagnosis.fit` runs a small pipeline of values:

1. **Data** (:func:`diagnose`). The records are cut into experiments
   (:mod:`.data`), segmented into regimes (:mod:`.regimes`), split into
   training and held-out samples (:mod:`.split`); the noise floor is estimated
   from them (:mod:`.noise`). What the rule judges on is one value
   (:class:`.rule.Ground`).
2. **Baseline and search** (:class:`.search.Search`). The baseline is fitted on
   the training samples (:mod:`.refit`); each applicable candidate is added,
   the whole model refitted and judged by the acceptance rule
   (:class:`.rule.AcceptanceRule`, ``rule=``); the best qualifying one is added,
   equals tie. After the search each effect is taken out again and its
   confounded partners tried in its place (:mod:`.revision`).
3. **Verdict** (:mod:`.verdict`): is structure left in the final held-out
   residual? The result is one frozen value (:class:`.result.DiagnosisResult`);
   the JSON and the report are written from it (:mod:`.writers`, :mod:`.report`),
   the words by :mod:`.wording`.
4. **Baseline check**: the same configuration from a baseline of the other kind
   (``dataclasses.replace(config, baseline=...)``), on the same workers.

The candidate refits run on an executor and report to a progress callback,
both handed to the search (:mod:`.workers`).

:meth:`Diagnosis.add_effect` is the one call that adds an effect (from the
catalogue or registered by the user) to the current model, refits it and
records the step, so the error-fall chart shows it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import fcomp.diagnosis.revision as revision
from fcomp.diagnosis.beside import CheckBeside, check_beside
from fcomp.diagnosis.confounding import design_ties
from fcomp.diagnosis.data import DiagnosisData, prepare
from fcomp.diagnosis.design import held_by_design, record_design
from fcomp.diagnosis.features import FeatureStrength, trimmed_rms
from fcomp.diagnosis.forms import refine
from fcomp.diagnosis.noise import NoiseFloor, noise_floor
from fcomp.diagnosis.refit import Refit
from fcomp.diagnosis.regimes import Segmentation, segment
from fcomp.diagnosis.result import DiagnosisResult, FittedAttributes, other_baseline
from fcomp.diagnosis.rule import AcceptanceRule, Ground
from fcomp.diagnosis.search import Candidate, Search, Step
from fcomp.diagnosis.split import STRATEGIES, Split, make_split
from fcomp.diagnosis.verdict import VERDICTS, VerdictRule
from fcomp.diagnosis.workers import worker_pool
from fcomp.diagnosis.writers import model_file, signals, to_dict
from fcomp.effects import EFFECTS, Effect
from fcomp.errors import FcompError, deprecated
from fcomp.measurement import Measurement
from fcomp.models import MODELS, FrictionModel, make_model
from fcomp.progress import Tick, counter, quiet


@dataclass(frozen=True)
class DiagnosisConfig:
    """Everything a diagnosis is asked to do, validated before any work (see :class:`Diagnosis`)."""

    baseline: str | FrictionModel
    effects: tuple[str, ...] | None = None
    add: tuple[str | Effect, ...] = ()
    search: bool = True
    split: str = "auto"
    cutoff_hz: float | None = None
    max_steps: int = 6
    n_jobs: int | None = None
    scheduler: str | None = None
    max_nfev: int = 60
    max_samples: int = 40_000
    check_baseline: bool | str = "auto"
    rule: AcceptanceRule = AcceptanceRule()
    verdict_rule: VerdictRule = VerdictRule()

    def __post_init__(self) -> None:
        if self.check_baseline not in (True, False, "auto"):
            raise FcompError(f"check_baseline must be True, False or 'auto', got "
                             f"{self.check_baseline!r}")
        if self.split not in STRATEGIES:
            raise FcompError(f"split {self.split!r}: choose one of {', '.join(STRATEGIES)}")
        for name, least in (("max_steps", 0), ("max_nfev", 1), ("max_samples", 100)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise FcompError(f"{name} must be an integer >= {least}, got {value!r}")
        if self.n_jobs is not None and (isinstance(self.n_jobs, bool)
                                        or not isinstance(self.n_jobs, int) or self.n_jobs < 1):
            raise FcompError(f"n_jobs must be a positive integer or None, got {self.n_jobs!r}")
        if self.cutoff_hz is not None and not (isinstance(self.cutoff_hz, (int, float))
                                               and math.isfinite(self.cutoff_hz)
                                               and self.cutoff_hz > 0):
            raise FcompError(f"cutoff_hz must be a positive frequency (Hz) or None, got "
                             f"{self.cutoff_hz!r}")
        if not isinstance(self.rule, AcceptanceRule):
            raise FcompError(f"rule must be an AcceptanceRule, got {self.rule!r}")
        if not isinstance(self.verdict_rule, VerdictRule):
            raise FcompError(f"verdict_rule must be a VerdictRule, got {self.verdict_rule!r}")
        for n in [*self.names, *self.add]:
            EFFECTS.get(n if isinstance(n, str) else n.name)  # unknown names fail here
        if isinstance(self.baseline, str):
            MODELS.get(self.baseline)  # an unknown name fails here, with the known ones
        elif not isinstance(self.baseline, FrictionModel):
            raise FcompError(f"baseline must be a model name or a FrictionModel, got "
                             f"{self.baseline!r}")

    @property
    def model(self) -> FrictionModel:
        """The baseline model (built from its name on each call); a fitted model's
        measurement terms are left out: the diagnosis estimates the record's own."""
        return (make_model(self.baseline) if isinstance(self.baseline, str)
                else self.baseline.with_measurement(None))

    @property
    def names(self) -> list[str]:
        """The candidate effects (default: every registered effect now)."""
        return list(self.effects) if self.effects is not None else EFFECTS.names()


def diagnose(config: DiagnosisConfig, data: Measurement | Sequence[Measurement] | DiagnosisData,
             pool: Executor | None, tick: Tick) -> tuple[DiagnosisResult, Search]:
    """One diagnosis of ``data`` as ``config`` asks, without its baseline check.

    Returns the result and the search (kept to add or remove effects afterwards).
    """
    model, names = config.model, config.names
    name = config.baseline if isinstance(config.baseline, str) else model.describe()
    data = data if isinstance(data, DiagnosisData) else prepare(data, cutoff_hz=config.cutoff_hz)
    seg = segment(data)
    check_support(model, data, seg)
    split = make_split(data, seg.valid, config.split)
    floor = noise_floor(data, seg)
    refit = Refit(data, split, seg.d_pre, max_nfev=config.max_nfev,
                  max_samples=config.max_samples, noise=floor.value)
    design = record_design(data, seg)
    search = Search(refit, Ground.of(data, seg, split, floor.value), floor, config.rule, pool,
                    tick, config.max_nfev, config.max_samples, design=design,
                    design_held=held_by_design(design))
    refit.keep(list(search.design_held))  # what the design cannot determine, from the start
    search.fit_baseline(model)
    for effect in config.add:
        search.force(effect if isinstance(effect, str) else effect.name,
                     effect if isinstance(effect, Effect) else None)
    if config.search:
        search.run(names, config.max_steps)
    for effect in list(search.added):  # each effect's richer forms, in the model as it ended
        refine(search, effect)
    if config.search:
        revision.drop_no_ops(search)
        revision.backward(search)
        revision.swaps(search, names)
        revision.partners_in_model(search)
        assert search.design is not None
        design_ties(search, search.design)
    search.late_disturbances()
    return DiagnosisResult.of(search, name, config.verdict_rule), search


def check_support(model: FrictionModel, data: DiagnosisData, seg: Segmentation) -> None:
    """Refuse a baseline the data cannot support, saying why."""
    v = data.signal("v")
    moving = int(np.sum(np.abs(v) > max(seg.v_rest, 1e-12)))
    label = ", ".join(data.labels[:3]) + (" ..." if len(data.labels) > 3 else "")
    if moving < 20:
        raise FcompError(f"{label}: the piston hardly moves ({moving} samples faster than "
                         f"{seg.v_rest:.3g} m/s): there is no friction to compare "
                         f"{model.describe()!r} with")
    if model.n_states and data.steady_state:
        raise FcompError(f"baseline {model.describe()!r} is a dynamic model (states "
                         f"{', '.join(model.state_names)}) but the data are steady-state "
                         "points without a motion history: use a static baseline "
                         "(coulomb, coulomb-viscous, stribeck)")
    if model.n_states and not seg.starts:
        raise FcompError(f"{label}: the record has no start or reversal, so the states of "
                         f"the dynamic baseline {model.describe()!r} are not determined; "
                         "use a static baseline or record through reversals")
    n_par = len(model.flat_params())
    usable = int(seg.valid.sum())
    if usable < 10 * n_par:
        raise FcompError(f"{label}: only {usable} usable samples for the {n_par} "
                         f"parameters of {model.describe()!r}; record longer")


def baseline_check(config: DiagnosisConfig, result: DiagnosisResult, pool: Executor | None,
                   tick: Tick, beside: CheckBeside | None = None) -> DiagnosisResult:
    """``result`` with the baseline check ``config.check_baseline`` asks for.

    ``True`` always, ``False`` never, ``"auto"`` when the first answer is doubtful
    (:attr:`.result.DiagnosisResult.doubts`): the same configuration from a baseline
    of the other kind (:func:`.result.other_baseline`), its fits counted by ``tick`` as
    the first answer's were (one bar for the whole diagnosis). ``beside`` is that check
    started beside the first diagnosis (:mod:`.beside`): its answer is taken when the
    check is needed; else the check runs now, on the same workers.
    """
    doubts = result.doubts
    if config.check_baseline is False:
        return dataclasses.replace(result, check={"ran": False, "why": "not asked for"})
    if config.check_baseline == "auto" and not doubts:
        return dataclasses.replace(result, check={
            "ran": False, "why": "a clean answer: final fit not flagged, no tie, explained to "
                                 "the noise"})
    why = "asked for" if config.check_baseline is True else "; ".join(doubts)
    other_name = other_baseline(result.baseline_fit.model, result.ground)
    other = None  # none applies, or it does not fit these data
    if beside is not None and other_name == beside.baseline:
        other = beside.result()
    elif other_name is not None:
        second = dataclasses.replace(config, baseline=other_name, add=(), check_baseline=False)
        tick(f"baseline check: {other_name}")
        with contextlib.suppress(FcompError):
            other = dataclasses.replace(diagnose(second, result.ground.data, pool, tick)[0],
                                        check={"ran": False, "why": "not asked for"})
    return dataclasses.replace(result, other=other, check={
        "ran": other is not None,
        "why": why if other is not None else "no baseline of the other kind fits these data"})


class Diagnosis(FittedAttributes):
    """Compare a model with measurements, find the missing effect, add it, watch the error fall.

    Parameters
    ----------
    baseline
        Model name (``coulomb`` ... ``gms``) or a :class:`~fcomp.models.base.FrictionModel`.
    candidates
        Candidate effect names (default: every registered effect at :meth:`fit` time;
        the command line's ``--candidates``). ``effects=`` is its deprecated spelling
        (a DeprecationWarning; it works for one release).
    add
        Effects to add first, in order, whatever the rule says (one step each).
    search
        Search the candidates after the forced additions.
    split
        ``"auto"``, ``"experiment"`` or ``"segment"`` (:mod:`.split`).
    cutoff_hz
        Cutoff of the filter deriving ``v``, ``a`` from ``x`` (default from the rate).
    max_steps
        Most effects the search adds.
    n_jobs
        Processes refitting candidates in parallel (default: the CPU count, at most 4).
    scheduler
        Address of a Dask distributed scheduler: the candidate refits run on its
        workers instead (:mod:`fcomp.parallel`; the results are the same).
    max_nfev
        Evaluation budget of each refit.
    max_samples
        Largest record a refit runs on (longer ones are block-averaged for fitting).
    progress
        Show a progress bar on stderr.
    check_baseline
        After the search, diagnose the record again from a baseline of the other
        kind (static <-> dynamic, :func:`.result.other_baseline`) and say whether
        the answer depends on the baseline (``baseline_dependent_``): ``True``
        always, ``False`` never, ``"auto"`` (default) when the first answer is
        doubtful (:meth:`doubts`: the final fit flagged, a tie, or structure left).
    rule
        The acceptance rule (:class:`.rule.AcceptanceRule`; default its thresholds).
    verdict_rule
        The verdict's thresholds (:class:`.verdict.VerdictRule`).

    Attributes
    ----------
    result_ : DiagnosisResult
        Everything found, as one frozen value; the attributes below read it.
    data_, segmentation_, split_, noise_floor_
        The prepared data, regimes, held-out split and noise floor.
    baseline_fit_, fit_ : FitResult
        The baseline and the final model fitted on the training samples.
    steps_ : list of Step
    candidates_ : list of Candidate
        First-step candidates, best first.
    ties_ : list of list of str
    added_ : list of str
        Effects in the final model, in the order they were added.
    removed_ : list of str
        Effects the backward check (or :meth:`remove_effect`) took out again.
    skipped_ : dict
        Effect -> why it was not a candidate (at the last step it was considered).
    rms_baseline_, rms_final_ : N
        Held-out RMS of the baseline and the final model.
    verdict_ : str
        ``"explained"`` or ``"unexplained-structure"``.
    reason_ : str
        The rule that decided the verdict, with its numbers.
    baseline_dependent_ : bool
        Whether a baseline of the other kind finds other effects (``check_baseline``).
    other_ : Diagnosis or None
        That other diagnosis.
    baseline_check_ : dict
        ``{"ran": bool, "why": str}``: whether the check ran, and why (or why not).
    warnings_ : list of FitWarning
        The plausibility of the baseline's and the final model's fits
        (:mod:`fcomp.identification.plausibility`) and what the held-out data
        cannot judge (``heldout-coverage``).
    residual_features_ : list of FeatureStrength
        Features of the final held-out residual, strongest first.
    """

    def __init__(
        self,
        baseline: str | FrictionModel,
        *,
        candidates: Sequence[str] | None = None,
        add: Sequence[str | Effect] = (),
        search: bool = True,
        split: str = "auto",
        cutoff_hz: float | None = None,
        max_steps: int = 6,
        n_jobs: int | None = None,
        scheduler: str | None = None,
        max_nfev: int = 60,
        max_samples: int = 40_000,
        progress: bool = False,
        check_baseline: bool | str = "auto",
        rule: AcceptanceRule | None = None,
        verdict_rule: VerdictRule | None = None,
        **deprecated_names: Any,
    ) -> None:
        if "effects" in deprecated_names:
            if candidates is not None:
                raise TypeError("Diagnosis() got both candidates= and its deprecated spelling "
                                "effects=; give candidates=")
            deprecated("Diagnosis(effects=...)", "Diagnosis(candidates=...)")
            candidates = deprecated_names.pop("effects")
        if deprecated_names:
            raise TypeError(f"Diagnosis() got an unexpected keyword argument "
                            f"{next(iter(deprecated_names))!r}")
        self.baseline = baseline
        self.candidates = candidates
        self.add = add
        self.search = search
        self.split = split
        self.cutoff_hz = cutoff_hz
        self.max_steps = max_steps
        self.n_jobs = n_jobs
        self.scheduler = scheduler
        self.max_nfev = max_nfev
        self.max_samples = max_samples
        self.progress = progress
        self.check_baseline = check_baseline
        self.rule = rule
        self.verdict_rule = verdict_rule

    @property
    def config(self) -> DiagnosisConfig:
        """The constructor's arguments as one validated value."""
        return DiagnosisConfig(
            self.baseline, None if self.candidates is None else tuple(self.candidates),
            tuple(self.add), self.search, self.split, self.cutoff_hz, self.max_steps,
            self.n_jobs, self.scheduler, self.max_nfev, self.max_samples, self.check_baseline,
            self.rule or AcceptanceRule(), self.verdict_rule or VerdictRule())

    @classmethod
    def of(cls, result: DiagnosisResult) -> Diagnosis:
        """A fitted diagnosis holding ``result`` (the baseline check's other diagnosis)."""
        d = cls(result.baseline_name)
        d.result_ = result
        return d

    @property
    def other_(self) -> Diagnosis | None:
        """The baseline check's other diagnosis (None when it did not run)."""
        other = self._result.other
        return None if other is None else Diagnosis.of(other)

    def __getstate__(self) -> dict[str, Any]:
        return {k: v for k, v in self.__dict__.items() if k != "_search"}

    def __setstate__(self, state: dict[str, Any]) -> None:
        if "effects" in state and "candidates" not in state:  # pickled before the rename
            state = {("candidates" if k == "effects" else k): v for k, v in state.items()}
        self.__dict__.update(state)

    # ------------------------------------------------------------------ fit
    def fit(self, data: Measurement | Sequence[Measurement] | DiagnosisData) -> Diagnosis:
        """Run the diagnosis on ``data`` (one or several measurements); returns ``self``."""
        config = self.config
        self.__dict__.pop("result_", None)
        with (worker_pool(config.n_jobs, config.scheduler,
                          len(config.names) if config.search else 0) as pool,
              counter("diagnose", enabled=self.progress, unit="fit") as tick):
            if not isinstance(data, DiagnosisData):
                data = prepare(data, cutoff_hz=config.cutoff_hz)
            with check_beside(diagnose, config, data, tick) as beside:
                result, search = diagnose(config, data, pool,
                                          tick if beside is None else beside.tick)
                result = baseline_check(config, result, pool, tick, beside)
        search.pool, search.tick = None, quiet
        self._search = search
        self.result_ = result
        return self

    def _fitted(self) -> DiagnosisResult:
        result = self.__dict__.get("result_")
        if result is None:
            raise FcompError("this Diagnosis is not fitted yet: call fit(data) first")
        return result

    def _conclude(self) -> None:
        """The result again after the search's model changed (its baseline check kept)."""
        old = self._fitted()
        new = DiagnosisResult.of(self._search, old.baseline_name, old.verdict.rule)
        self.result_ = dataclasses.replace(new, check=old.check, other=old.other)

    def add_effect(self, effect: str | Effect) -> Diagnosis:
        """Add ``effect`` to the current model, refit, score and record the step (forced).

        Works after :meth:`fit`; the effect may be a catalogue entry or one the user
        registered (:func:`fcomp.effects.register_effect`), by name or as a
        configured instance (``make_effect("cogging", period=0.01)``: its
        configuration is kept, its parameter values are the start of the refit).
        """
        if "_search" not in self.__dict__:
            raise FcompError("call fit(data) before add_effect")
        name = effect.name if isinstance(effect, Effect) else effect
        EFFECTS.get(name)
        self._search.force(name, effect if isinstance(effect, Effect) else None)
        self._conclude()
        return self

    def remove_effect(self, effect: str) -> Diagnosis:
        """Take ``effect`` out of the current model again and refit the rest (after :meth:`fit`).

        The step that added it is marked not accepted and the effect is listed in
        ``removed_`` (the error-fall chart shows the removal); the verdict is
        judged again.
        """
        if "_search" not in self.__dict__:
            raise FcompError("call fit(data) before remove_effect")
        revision.remove(self._search, effect)
        self._conclude()
        return self

    # ------------------------------------------------------------- display
    def doubts(self) -> list[str]:
        """Why the answer might depend on the baseline (empty: a clean answer;
        :attr:`.result.DiagnosisResult.doubts`)."""
        return self._fitted().doubts

    def baseline_dependence(self) -> dict[str, Any] | None:
        """Whether the effects found depend on the baseline, and the other baseline's answer
        (:attr:`.result.DiagnosisResult.dependence`; ``None`` without a check)."""
        return self._fitted().dependence

    def __repr__(self) -> str:
        name = self.baseline if isinstance(self.baseline, str) else self.baseline.describe()
        if "result_" not in self.__dict__:
            return f"<Diagnosis from {name}: not fitted>"
        return (f"<Diagnosis from {name}: added {', '.join(self.added_) or 'nothing'}; "
                f"held-out RMS {self.rms_baseline_:.4g} -> {self.rms_final_:.4g} N; "
                f"{self.verdict_}>")

    def _repr_html_(self) -> str:
        from fcomp.diagnosis.report import diagnosis_html

        return diagnosis_html(self)

    def write_report(self, directory: str | Path, *, command: str | None = None) -> Path:
        """Write the self-contained ``DIRECTORY/report.html`` (:func:`.report.write_report`)."""
        from fcomp.diagnosis.report import write_report

        return write_report(self, directory, command=command)

    def signals(self) -> dict[str, Any]:
        """Which velocity drove the friction states, from which force, and why
        (:func:`.writers.signals`)."""
        return signals(self._fitted())

    def model_file(self, source: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The final model as a model file's document (:func:`.writers.model_file`)."""
        return model_file(self._fitted(), source)

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``fcomp diagnose`` (public contract, plus extra keys;
        :func:`.writers.to_dict`)."""
        return to_dict(self._fitted())


__all__ = ["VERDICTS", "AcceptanceRule", "Candidate", "Diagnosis", "DiagnosisConfig",
           "DiagnosisResult", "FeatureStrength", "NoiseFloor", "Segmentation", "Split", "Step",
           "DiagnosisData", "VerdictRule", "trimmed_rms"]
