"""One colour rule for every result shown (issue 42, item 12): a diagnose report showed
"explained" in green beside "How sure: low" in red; a study sure that a claim is not
reproduced opened with a green "high"; compare said "high" where the diagnosis that made
the model said "low", and proposed adding an effect the model already had.

The rule (:func:`fcomp.conclusions.tone`): the colour of a result is the worse of what it
says and how sure it is.
"""

from __future__ import annotations

import itertools
import re

import pytest

from fcomp.conclusions import LEVELS, OUTCOMES, TONES, Conclusion, of_comparison, of_diagnosis, tone
from fcomp.report import Report


def test_the_rule_is_the_worse_of_the_two() -> None:
    """Green only for a favourable result held with high confidence; never better when the
    result or the confidence gets worse (monotone in both)."""
    assert tone("good", "high") == "ok"
    assert tone("good", "medium") == "warn"
    assert tone("good", "low") == "bad"
    assert tone("bad", "high") == "bad"
    assert tone("mixed", "high") == "warn"
    assert tone(None, "high") == "ok" and tone(None, "low") == "bad"
    rank = {t: i for i, t in enumerate(TONES)}
    for (o1, c1), (o2, c2) in itertools.product(itertools.product(OUTCOMES, LEVELS), repeat=2):
        if OUTCOMES.index(o1) <= OUTCOMES.index(o2) and LEVELS.index(c1) <= LEVELS.index(c2):
            assert rank[tone(o1, c1)] <= rank[tone(o2, c2)]


def _kind(html_text: str) -> str:
    m = re.search(r'<div class="note (ok|warn|bad) conclusion">', html_text)
    assert m, html_text
    return m.group(1)


@pytest.mark.parametrize(("outcome", "confidence", "kind"), [
    ("good", "high", "ok"), ("good", "low", "bad"), ("bad", "high", "bad"), (None, "medium", "warn")])
def test_a_reports_conclusion_takes_the_rule(outcome: str | None, confidence: str,
                                            kind: str) -> None:
    rep = Report("t").conclusion(Conclusion("found", confidence, outcome=outcome))
    assert _kind(rep.to_html()) == kind


def _diagnosis(**over: object) -> dict:
    doc = {"baseline": "lugre", "model": "lugre + stribeck", "added": ["stribeck"],
           "rms_baseline": 3.0, "rms_final": 1.0, "noise_floor": 1.0, "verdict": "explained",
           "warnings": [], "baseline_dependent": False}
    return {**doc, **over}


def test_an_explained_verdict_not_to_be_trusted_is_not_green() -> None:
    """The diagnose report's verdict note is coloured by the conclusion's rule: "explained"
    with a final fit at its bounds is red, as its "How sure: low" beside it."""
    sure = of_diagnosis(_diagnosis())
    unsure = of_diagnosis(_diagnosis(warnings=[
        {"code": "at-bound", "parameter": "Fs", "message": "final model lugre: Fs at a bound"}]))
    assert (sure.confidence, sure.tone) == ("high", "ok")
    assert (unsure.confidence, unsure.tone) == ("low", "bad")
    unexplained = of_diagnosis(_diagnosis(verdict="unexplained-structure"))
    assert unexplained.tone == "warn"  # structure left: never green
    import inspect

    import fcomp.diagnosis.report as report

    assert "of_diagnosis(d).tone" in inspect.getsource(report.build_report)


def test_a_study_sure_its_claim_fails_is_red() -> None:
    """A study's finding: its report's opening and its card on the index are coloured by the
    same rule -- "not reproduced" is red however sure, "reproduced" but unsure is not green."""
    from studies.all import finding_words, study_card
    from studies.base import Finding

    cases = [(Finding("not reproduced", "bad", "x", confidence="high"), "bad"),
             (Finding("reproduced", "ok", "x", confidence="high"), "ok"),
             (Finding("reproduced", "ok", "x", confidence="low"), "bad"),
             (Finding("reproduced", "ok", "x", flags=("a number",), confidence="high"), "warn"),
             (Finding("partly reproduced", "warn", "x", confidence="high"), "warn")]
    for finding, kind in cases:
        assert finding.shown_level == kind
        assert finding.conclusion().tone == kind
        run = {"status": "ok", "finding": finding.as_dict(), "report": "r.html",
               "summary": "s.json", "seconds": 1.0, "paper": "", "title": "t"}
        assert finding_words(run)[1] == kind
        assert study_card("s", run).startswith(f'<div class="note {kind}">')


def test_the_site_is_not_green_while_a_study_fails() -> None:
    from studies.all import STUDY as ALL
    from studies.base import Finding

    bad = Finding("not reproduced", "bad", "x", confidence="high").as_dict()
    good = Finding("reproduced", "ok", "x", confidence="high").as_dict()
    runs = {"a": {"status": "ok", "finding": good}, "b": {"status": "ok", "finding": bad}}
    found = ALL.finding({"studies": runs, "failed": []})
    assert found.level == "warn" and found.conclusion().tone == "warn"
    assert ALL.finding({"studies": {"a": runs["a"]}, "failed": []}).conclusion().tone == "ok"


def _comparison(**over: object) -> dict:
    doc = {"model": "coulomb-viscous", "description": "coulomb-viscous + position-dependence",
           "rms": 0.628, "rms_scored": 0.2471, "noise_floor": 0.1, "warnings": [],
           "regimes": {"all": {"rms": 0.2471, "n": 900}},
           "residual_features": [{"feature": "x", "strength": 0.4}]}
    return {**doc, **over}


def test_compare_trusts_a_model_as_little_as_its_own_fit_did() -> None:
    """A model file whose fit left parameters undetermined (their stderr null): compare says
    "low" as the diagnosis that made it did (it said "high")."""
    plain = of_comparison(_comparison())
    flagged = of_comparison(_comparison(warnings=[
        {"code": "not-identified", "parameter": "kx2,kx3",
         "message": "diag.json: kx2, kx3 not determined by the fit that made this model"}]))
    assert plain.confidence == "high"
    assert flagged.confidence == "low" and any("kx2, kx3" in r for r in flagged.reasons)


def test_compare_proposes_diagnosing_the_model_as_compared() -> None:
    """The next step starts the diagnosis from the model file compared (its effects kept), so
    it never proposes adding an effect the model already has; with a name, from the name."""
    by_file = of_comparison(_comparison(friction="diag.json"))
    assert any("fcomp diagnose DATA --friction diag.json" in s for s in by_file.next_steps)
    by_name = of_comparison(_comparison())
    assert any("--friction coulomb-viscous " in s for s in by_name.next_steps)


def test_the_compare_summary_says_which_rms_is_which() -> None:
    """The headline RMS (the whole record) and the table's (scored, per regime) differ by
    nature: the summary and the report say so instead of leaving 0.628 beside 0.2471."""
    from fcomp.cli.compare import summary

    doc = {**_comparison(), "fitted": False, "judged": 900, "rms_plain": 0.3, "plant": {},
           "params": {}}
    text = summary(doc)
    assert "RMS 0.628 N on the whole record, as fcomp fit measures it; scored 0.2471 N" in text
    assert "scored RMS per regime:" in text
    import inspect

    import fcomp.diagnosis.report as report

    assert "is another measure" in inspect.getsource(report.comparison_sections)
