"""Fits of the real records shipped in ``fcomp/data/datasets`` say what a careful engineer
would question: values at bounds, intervals through zero, an impossible mass, parameters the
record does not determine (with the experiment that would, worded for the rig)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from fcomp import datasets
from fcomp.cli.main import main
from fcomp.diagnosis import Diagnosis
from fcomp.effects import experiment_for
from fcomp.identification import FrictionFit
from fcomp.measurement import Measurement


@pytest.fixture(scope="module")
def oring3() -> Measurement:
    return datasets.load("zillen", "O-ring_3bar.csv")


@pytest.fixture(scope="module")
def emps() -> Measurement:
    return datasets.load("emps", "DATA_EMPS.mat")


def by_code(fit: FrictionFit) -> dict[str, list[str | None]]:
    out: dict[str, list[str | None]] = {}
    for w in fit.warnings_:
        out.setdefault(w.code, []).append(w.parameter)
    return out


def test_zillen_lugre_flags_fc_interval_and_n_at_bound(oring3: Measurement) -> None:
    fit = FrictionFit("lugre").fit(oring3)
    lo, hi = fit.ci_["Fc"]
    assert lo <= 0.0 < fit.params_["Fc"] < hi  # what was printed without comment
    found = by_code(fit)
    assert "Fc" in found["interval-crosses-zero"]
    assert "n" in found["at-bound"]
    (n_warning,) = [w for w in fit.warnings_ if w.code == "at-bound" and w.parameter == "n"]
    assert "upper bound 10" in n_warning.message
    assert fit.to_dict()["warnings"] == [w.to_dict() for w in fit.warnings_]


def test_zillen_coulomb_viscous_flags_the_impossible_mass(oring3: Measurement) -> None:
    fit = FrictionFit("coulomb-viscous").fit(oring3)
    assert "mass" in fit.params_ and fit.params_["mass"] < 1e-3  # estimated, ~0 kg
    (w,) = [w for w in fit.warnings_ if w.code == "mass-implausible"]
    assert w.parameter == "mass" and "25 mm bore" in w.message and "rig.mass" in w.message
    # with the mass known there is nothing to say about it
    known = FrictionFit("coulomb-viscous", mass=0.5).fit(oring3)
    assert "mass-implausible" not in by_code(known)


def test_emps_advice_names_no_chambers(emps: Measurement) -> None:
    assert emps.meta["kind"] == "electromechanical-axis"
    diag = Diagnosis("coulomb-viscous", candidates=["direction-asymmetry", "force-offset"],
                     max_steps=1, n_jobs=1).fit(emps)
    assert diag.data_.kind == "electromechanical-axis"
    doc = diag.to_dict()
    # whether the two tie on this record or not, the advice for them is the axis's
    advice = " ".join([*(a for t in doc["tie_experiments"].values() for a in t.values()),
                       *(experiment_for(e, diag.data_.kind)
                         for e in ("force-offset", "direction-asymmetry"))]).lower()
    assert "drive disabled" in advice
    assert "chamber" not in advice and "vent" not in advice and "retract" not in advice


def test_emps_nmlgm_converges_and_says_what_the_record_does_not_determine(
        emps: Measurement) -> None:
    fit = FrictionFit("nmlgm").fit(emps)  # strict: raises if it does not converge
    assert fit.converged_
    held = fit.not_identifiable_
    assert held and set(held) <= set(fit.fixed_)
    not_identified = {w.parameter: w.message for w in fit.warnings_
                      if w.code == "not-identified"}
    for name in held:  # each held parameter: a warning naming the experiment that would fit it
        assert "to determine it:" in not_identified[name], name
    # the parameters the full solve could not settle were held and the rest refitted
    assert not fit.stages_[0]["converged"] and fit.stages_[-1]["converged"]
    assert fit.rms_ <= fit.stages_[0]["rms"] + 1e-9


def test_cli_prints_warnings_and_json_carries_them(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    src = datasets.path("zillen", "O-ring_3bar.csv")
    rec, out = tmp_path / "oring3.csv", tmp_path / "fit.json"
    assert main(["import", "zillen", str(src), "-o", str(rec)]) == 0
    capsys.readouterr()
    assert main(["fit", str(rec), "--friction", "lugre", "--json", str(out)]) == 0
    printed = capsys.readouterr()
    doc = json.loads(out.read_text())
    assert {"model", "params", "stderr", "rms", "warnings"} <= set(doc)
    codes = {(w["code"], w["parameter"]) for w in doc["warnings"]}
    assert {("interval-crosses-zero", "Fc"), ("at-bound", "n")} <= codes
    lines = [ln for ln in printed.err.splitlines() if ln.startswith("fcomp: warning: ")]
    assert len(lines) == len(doc["warnings"])
    assert any(ln.startswith("fcomp: warning: Fc = 0.4") for ln in lines)
    assert "Fc " in printed.out  # the table itself


def test_a_clean_fit_has_an_empty_warning_list(emps: Measurement) -> None:
    fit = FrictionFit("coulomb-viscous", offset=True).fit(emps)
    assert fit.warnings_ == [] and fit.to_dict()["warnings"] == []
