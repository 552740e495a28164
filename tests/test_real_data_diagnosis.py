"""The diagnosis on the shipped real records: held-out data that can judge, and no silent
dependence on the baseline (issue 11, items 2 and 3)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fcomp import datasets
from fcomp.cli.main import main
from fcomp.diagnosis.data import prepare
from fcomp.diagnosis.regimes import segment
from fcomp.diagnosis.split import make_split


def test_zillen_split_judges_every_pressure_level_and_no_warm_up() -> None:
    """O-ring at 1, 3, 5, 7 bar: before, "2 of 6 held out" with the 7 bar piece all warm-up,
    so every held-out number came from one 3 bar fragment. Now every experiment and every
    pressure band has held-out samples, and none of them is warm-up."""
    recs = [datasets.load("zillen", f"O-ring_{k}bar.csv") for k in (1, 3, 5, 7)]
    data = prepare(recs)
    seg = segment(data)
    split = make_split(data, seg.valid)
    assert not (split.test & ~seg.valid).any()  # nothing held out outside the usable samples
    for e in data.experiments:
        assert split.test[e.start:e.stop].any(), e
    psum = data.signal("p1") + data.signal("p2")
    held = psum[split.test]
    for level in (1e5, 3e5, 5e5, 7e5):  # gauge p1 (p2 vented) of each file, within 0.5 bar
        assert np.any(np.abs(held - level) < 0.5e5), level
    bands = split.coverage["pressure"]
    assert len(bands) >= 3 and all(b["heldout"] > 0 for b in bands.values())
    assert not [w for w in split.warnings if w.code == "heldout-coverage"]


@pytest.mark.slow
def test_emps_diagnosis_reports_the_baseline_check(tmp_path: Path) -> None:
    """The JSON says whether the answer depends on the baseline, with the other one's answer,
    and the rule that decided the verdict."""
    rec = tmp_path / "emps.csv"
    assert main(["import", "emps", str(datasets.path("emps", "DATA_EMPS.mat")), "-o",
                 str(rec)]) == 0
    out = tmp_path / "d.json"
    assert main(["diagnose", str(rec), "--friction", "coulomb-viscous", "--no-progress",
                 "--baseline-check", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert isinstance(doc["baseline_dependent"], bool)
    assert doc["baseline_check"] == {"ran": True, "why": "asked for"}
    other = doc["other_baseline"]
    assert other["baseline"] == "lugre" and isinstance(other["added"], list)
    assert other["rms_final"] <= other["rms_baseline"] + 1e-12
    assert doc["reason"] and doc["verdict"] in ("explained", "unexplained-structure")
    if doc["baseline_dependent"]:
        assert "baseline" in doc["reason"]
    assert doc["signals"]  # which velocity drove the friction states, and why
