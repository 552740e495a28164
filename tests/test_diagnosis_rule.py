"""The diagnosis as small values (issue 26): the acceptance rule, the configuration checked
before any work, the words written apart from the figures, the result frozen."""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

from fcomp.diagnosis import AcceptanceRule, Diagnosis, DiagnosisResult, VerdictRule
from fcomp.diagnosis.rule import Failure, Judgement
from fcomp.diagnosis.wording import failure_text, judgement_text
from fcomp.errors import FcompError
from fcomp.synthetic import generate


@pytest.fixture(scope="module")
def record():
    return generate(["direction-asymmetry"], base="stribeck", duration=9.0, seed=21).measurement


@pytest.mark.parametrize("kwargs", [
    {"check_baseline": "sometimes"}, {"split": "random"}, {"max_steps": -1},
    {"max_steps": 2.5}, {"n_jobs": 0}, {"max_nfev": 0}, {"cutoff_hz": -3.0},
    {"candidates": ["no-such-effect"]}, {"add": ["no-such-effect"]}, {"rule": 0.05},
    {"verdict_rule": {"structure_min": 0.2}},
])
def test_every_argument_is_checked_before_any_work(kwargs) -> None:
    """A bad option fails at once, naming itself, before the data are even looked at (the
    data here are not a record at all: reaching them would fail otherwise)."""
    with pytest.raises(FcompError) as err:
        Diagnosis("stribeck", **kwargs).fit(object())  # type: ignore[arg-type]
    name = next(iter(kwargs))
    assert name in str(err.value) or "no-such-effect" in str(err.value)


@pytest.mark.parametrize("kwargs", [{"accept_p": 0.0}, {"accept_p": 1.5}, {"tie_share": -0.1},
                                    {"fall_noise": float("nan")}, {"at_floor": 0.5}])
def test_a_rule_outside_its_range_is_refused(kwargs) -> None:
    with pytest.raises(FcompError, match=next(iter(kwargs))):
        AcceptanceRule(**kwargs)
    with pytest.raises(FcompError, match="structure_min"):
        VerdictRule(structure_min=-1.0)


def test_every_failure_of_the_rule_has_its_words() -> None:
    """The rule returns codes and figures; :mod:`.wording` writes each one with its numbers."""
    figures = {"no-fall": {"before": 2.0, "after": 2.5},
               "small-fall": {"fall": 0.01, "need": 0.2},
               "small-share": {"share": 0.3, "least": 0.5},
               "not-significant": {"z": 1.1, "p": 0.14, "most": 0.05},
               "outside-signature": {"share": 0.4, "where": "reversal", "least": 2 / 3},
               "confounded-with-time": {"drift": 0.9, "fall": 1.0},
               "bic": {"delta_bic": 3.5}}
    texts = {code: failure_text(Failure(code, f)) for code, f in figures.items()}
    assert texts["no-fall"] == "held-out RMS does not fall (2 -> 2.5 N)"
    assert texts["not-significant"] == "fall not significant (z = 1.1, p = 0.14 > 0.05)"
    assert "40 %" in texts["outside-signature"] and "67 %" in texts["outside-signature"]
    judged = Judgement(0.1, 1.1, 0.14, 3.5, (Failure("not-significant", figures["not-significant"]),
                                             Failure("bic", figures["bic"])), AcceptanceRule())
    assert not judged.qualifies
    assert judgement_text(judged) == texts["not-significant"] + "; " + texts["bic"]


def test_the_rule_is_an_argument_and_decides(record) -> None:
    """The default rule finds the hidden asymmetry; a rule asking every fall to take 99 % of
    the error where the candidate acts accepts nothing, and says so for every candidate (the
    same refits, judged by another rule)."""
    found = Diagnosis("stribeck", n_jobs=1, check_baseline=False).fit(record)
    assert found.added_ == ["direction-asymmetry"]
    strict = AcceptanceRule(fall_relative=0.99)
    none = Diagnosis("stribeck", n_jobs=1, check_baseline=False, rule=strict).fit(record)
    assert none.added_ == [] and none.steps_ and not none.steps_[0].accepted
    first = {c.effect: c for c in found.candidates_}
    for c in none.candidates_:
        if c.judgement is not None:
            assert c.judgement.rule is strict and not c.qualifies
        if not first[c.effect].qualifies:  # refitted once from the same baseline fit
            assert c.rms_heldout == first[c.effect].rms_heldout or (
                np.isnan(c.rms_heldout) and np.isnan(first[c.effect].rms_heldout))
        if c.judgement is not None and c.fall > 0:
            assert "small-fall" in [f.code for f in c.judgement.failures], c.reason
    # the words come from the figures: the JSON's reason is the judgement's text
    js = none.to_dict()["candidates"]
    assert [c["reason"] for c in js] == [c.reason or "qualifies by the acceptance rule"
                                         for c in none.candidates_]


def test_the_result_is_one_frozen_value_and_the_baseline_check_reuses_the_config(record) -> None:
    """``result_`` is frozen; the ``*_`` attributes read it; the baseline check's second run
    is the same configuration with another baseline (the same rule object); the fitted
    diagnosis pickles."""
    rule = AcceptanceRule(tie_share=0.12)
    d = Diagnosis("stribeck", n_jobs=1, check_baseline=True, rule=rule).fit(record)
    res = d.result_
    assert isinstance(res, DiagnosisResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.added = ()  # type: ignore[misc]
    assert d.added_ == list(res.added) and d.verdict_ == res.verdict.verdict
    assert d.baseline_check_["ran"] and d.other_ is not None
    assert d.other_.baseline_name_ == "lugre"
    other_rules = {c.judgement.rule for s in d.other_.steps_ for c in s.candidates
                   if c.judgement is not None}
    assert other_rules == {rule}
    back = pickle.loads(pickle.dumps(d))
    assert back.to_dict()["added"] == d.to_dict()["added"]
    np.testing.assert_array_equal(back.fit_.residual, d.fit_.residual)


def test_an_unfitted_diagnosis_says_to_fit_it_first() -> None:
    d = Diagnosis("stribeck")
    assert not hasattr(d, "verdict_")
    with pytest.raises(AttributeError, match="fit"):
        _ = d.added_
    with pytest.raises(FcompError, match="fit"):
        d.to_dict()
    with pytest.raises(FcompError, match="fit"):
        d.add_effect("viscous")
