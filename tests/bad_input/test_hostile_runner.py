"""A fast slice of the hostile-case runner (``benchmarks/hostile_cases.py``): a few of its
cases through real processes, classified as the runner classifies them -- so the runner
itself stays working, and its classification is checked on known outcomes."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers.hostile import ROOT, runner, write_lab

RUNNER = runner()
SLICE = ["plant-check-p_tau_zero", "simulate-model-m_deep_list", "template-stdout-closed",
         "list-data", "import-zillen-by-name", "signal-term-at-handler", "save-model-name-250",
         "compensate-reference-r_long"]


def test_the_runner_lists_a_few_hundred_cases() -> None:
    cases = RUNNER.cases()
    ids = [c.id for c in cases]
    assert len(cases) >= 300 and len(set(ids)) == len(ids)
    assert set(SLICE) <= set(ids)
    assert {c.expect for c in cases} <= {"refuse", "warn", "ok", "refuse-or-warn", "quiet",
                                          "signal"}


@pytest.mark.slow
@pytest.mark.parametrize("case_id", SLICE)
def test_a_slice_of_the_runner_is_clean(tmp_path: Path, case_id: str) -> None:
    case = next(c for c in RUNNER.cases() if c.id == case_id)
    lab = write_lab(tmp_path / "lab")
    result = RUNNER.run_case(case, lab, ROOT, 300.0)
    assert result.outcome == "clean", (result.reason, result.stderr)


def test_the_classification() -> None:
    """The runner's verdicts on made-up outcomes: a traceback, an internal error, an exit
    0 where a refusal is due, a refusal not naming its file, two lines, a changed input."""
    c = RUNNER.Case("x", "fit a.csv", "refuse", ("a.csv",))
    ok = "fcomp: error: a.csv: bad\n"
    assert RUNNER._classify(c, 2, "", ok, [], [])[0] == "clean"
    assert RUNNER._classify(c, 2, "", "fcomp: error: bad\n", [], [])[0] == "wrong"
    assert RUNNER._classify(c, 2, "", ok + ok, [], [])[0] == "wrong"
    assert RUNNER._classify(c, 0, "", "", [], [])[0] == "wrong"
    assert RUNNER._classify(c, 1, "", "fcomp: internal error: X\n", [], [])[0] == "internal"
    assert RUNNER._classify(c, 2, "", "Traceback (most recent call last):\n", [], [])[0] == \
        "traceback"
    assert RUNNER._classify(c, None, "", "", [], [])[0] == "hang"
    assert RUNNER._classify(c, 2, "", ok, ["a.csv"], [])[0] == "wrong"
    assert RUNNER._classify(c, 2, "", ok, [], ["out.json"])[0] == "wrong"
    w = RUNNER.Case("y", "sim", "warn", ("fitted",))
    assert RUNNER._classify(w, 0, "", "fcomp: warning: m.json was fitted on ...\n", [], [])[0] \
        == "clean"
