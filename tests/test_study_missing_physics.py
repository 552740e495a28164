"""Study ``missing-physics``: the diagnose loop on a generated case and on real data."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers.browser import study_summary

from studies import missing_physics as mp

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("site")]  # builds the study site or runs long diagnoses


@pytest.fixture(scope="module")
def summary() -> dict:
    return study_summary("missing-physics")


def test_recovered_rule() -> None:
    res = {"added": ["force-offset"], "ties": [["force-offset", "direction-asymmetry"]],
           "verdict": "explained"}
    assert mp.recovered("force-offset", res)
    assert mp.recovered("direction-asymmetry", res)  # tied with the added effect
    assert not mp.recovered("stribeck", res)
    assert not mp.recovered("ripple", res)  # outside the catalogue: must say unexplained
    assert mp.recovered("ripple", {**res, "verdict": "unexplained-structure"})


def test_generated_case_hidden_effect_found(summary: dict) -> None:
    (g,) = summary["generated"]
    d = g["diagnosis"]
    assert g["hidden"] == "pressure-dependence"
    assert g["recovered"] and "pressure-dependence" in d["added"]
    assert d["rms_final"] < 0.6 * d["rms_baseline"]
    # the noise floor estimated from the data against the noise that was added
    assert d["noise_floor"] == pytest.approx(g["true_noise_std"], rel=0.3)
    assert d["verdict"] in ("explained", "unexplained-structure")


def test_real_data_error_falls(summary: dict) -> None:
    (r,) = summary["real"]
    d = r["diagnosis"]
    assert r["file"] == "O-ring_3bar.csv" and d["baseline"] == "coulomb-viscous"
    assert d["rms_final"] <= d["rms_baseline"]
    assert r["fall"] == pytest.approx(1 - d["rms_final"] / d["rms_baseline"])
    for key in ("baseline", "rms_baseline", "added", "steps", "candidates", "ties",
                "rms_final", "noise_floor", "verdict", "residual_features"):
        assert key in d, key
    assert all(s["rms_after"] is None or s["rms_after"] >= 0 for s in d["steps"])


def test_full_diagnosis_reports_written(site: Path) -> None:
    folder = site / "missing-physics"
    subs = sorted(folder.glob("diagnosis-*/report.html"))
    assert len(subs) == 2
    text = (folder / "report.html").read_text(encoding="utf-8")
    for sub in subs:
        assert f'href="{sub.parent.name}/report.html"' in text


def test_fast_mode_says_the_baseline_check_was_not_run(summary: dict, site: Path) -> None:
    """The fast mode leaves out the baseline check (half of each diagnosis's time); its
    JSON and each diagnosis report say so rather than "not asked for"."""
    assert summary["settings"]["options"]["check_baseline"] is False
    for case in summary["generated"] + summary["real"]:
        assert case["diagnosis"]["baseline_check"] == {"ran": False,
                                                       "why": mp.FAST_NO_CHECK}
    for sub in (site / "missing-physics").glob("diagnosis-*/report.html"):
        assert f"Baseline check not run: {mp.FAST_NO_CHECK}" in sub.read_text(encoding="utf-8")
