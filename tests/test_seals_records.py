"""The shipped TU Delft seal records diagnosed whole (issue 43): answers that do not hang on
names, order or irrelevant sidecar values, and what a diagnosed seal model may be used for.

The parts are checked fast in ``tests/test_seals.py``; these run diagnoses of real records
(about a minute each on a quiet 2-core machine), so they are marked slow.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from fcomp import datasets
from fcomp.diagnosis import Diagnosis
from fcomp.errors import FcompWarning
from fcomp.measurement import Measurement
from fcomp.modelfile import load_model

pytestmark = pytest.mark.slow

#: Candidates of the quick diagnoses: the effects these records are known to show and their
#: confounded partners (the full catalogue is the benchmark's: benchmarks/bench_real_seals.py).
SEAL_CANDIDATES = ("pressure-dependence", "direction-asymmetry", "area-error", "force-offset")


def _diagnose(recs: list[Measurement], baseline: str = "coulomb-viscous") -> dict:
    d = Diagnosis(baseline, candidates=SEAL_CANDIDATES, n_jobs=1, check_baseline=False,
                  max_steps=3).fit(recs)
    return d.to_dict()


def _found(doc: dict) -> set[frozenset[str]]:
    """The findings: each added effect as its tie group."""
    return {frozenset(next((t for t in doc["ties"] if e in t), [e])) for e in doc["added"]}


def _copy(meas: Measurement, name: str) -> Measurement:
    out = meas.with_columns()
    out.meta["name"] = name
    return out


def test_names_order_and_an_irrelevant_mass_do_not_change_the_answer() -> None:
    """O-ring at 3 and 7 bar: renamed and given the other way round the answer is the same
    to the bit; with ``rig.mass = 0.1`` kg in the sidecars (a milligram-force at these
    accelerations) and with a near-duplicate of the 7 bar record added (its force 0.1 %
    higher), the same effects are found."""
    recs = [datasets.load("zillen", f"O-ring_{k}bar.csv") for k in (3, 7)]
    base = _diagnose(recs)
    renamed = _diagnose([_copy(recs[1], "a_first"), _copy(recs[0], "z_last")])
    for key in ("added", "ties", "rms_baseline", "rms_final", "noise_floor", "params"):
        assert renamed[key] == base[key], key
    heavy = []
    for r in recs:
        h = r.with_columns()
        h.meta["rig"] = {**h.meta.get("rig", {}), "mass": 0.1}
        heavy.append(h)
    assert _found(_diagnose(heavy)) == _found(base)
    near = recs[1].with_columns(F_ext=recs[1]["F_ext"] * 1.001)
    near.meta["name"] = "O-ring_7bar_again"
    # the same effects, up to the force offset: its third step sits at the rule's edge (43 %
    # of the excess where it acts against the 50 % asked with the near-duplicate: refused;
    # accepted without it, and then tied as the asymmetry's partner in the model). Refused,
    # its place of the area error is told apart by the held-out data -- behind by 0.13 N
    # (1.1 noise floors) where they differ, behind in each record on average, both paired
    # tests significant -- so it no longer joins that tie as the fall's share alone let it
    # (issue 40: a tie must be one the data cannot break)
    assert {g - {"force-offset"} for g in _found(_diagnose([*recs, near]))} == {
        g - {"force-offset"} for g in _found(base)}
    assert any("pressure-dependence" in g for g in _found(base))


def test_the_oring_model_is_a_seal_model_with_its_uncertainty(tmp_path: Path) -> None:
    """O-ring at 1-7 bar from LuGre: the pressure dependence is found; what the vented
    chamber cannot determine is never fitted; the model file carries the standard errors,
    flags what the record does not determine, and its friction at 5 bar in the rod chamber
    is the seal's (an area error is a measurement term); the advice names no experiment the
    record holds and no option diagnose lacks."""
    recs = [datasets.load("zillen", f"O-ring_{k}bar.csv") for k in (1, 3, 5, 7)]
    d = Diagnosis("lugre", candidates=SEAL_CANDIDATES, n_jobs=1, check_baseline=False,
                  max_steps=3).fit(recs)
    doc = d.to_dict()
    assert any("pressure-dependence" in g for g in _found(doc)), doc["added"]
    assert "kd" not in doc["params"] and "dA2" not in doc["params"]
    for name in ("kd", "dA2"):
        assert doc["model_params"].get(name, 0.0) == 0.0
    assert doc["stderr"] and all(k in doc["params"] for k in doc["stderr"])
    design = doc["design"]
    assert design["one_speed_per_direction"]
    assert {("speed", "pressure"), ("speed", "direction")} <= {
        tuple(c["factors"]) for c in design["confounded"]}
    assert "n" in doc["held_by_design"] and "n" not in doc["params"]
    path = tmp_path / "oring.json"
    path.write_text(json.dumps(doc["model_file"]))
    mf = doc["model_file"]
    assert "n" in mf["undetermined"]
    assert all(e["name"] != "area-error" for e in mf["effects"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FcompWarning)
        friction = load_model(path)
    F = friction.steady_state(np.array([-0.008, 0.012]), p1=0.0, p2=5e5)
    assert np.all(np.abs(F) < 25.0), F  # N: the seal's level, no dA2*p2
    text = " ".join(w["message"] for w in doc["warnings"])
    assert "two or more chamber pressure levels" not in text
    assert "--mass" not in text


def test_two_effects_missing_at_once_are_found_as_a_pair() -> None:
    """O-ring and Circle at 1-7 bar from LuGre: no single candidate takes half the excess
    where it acts (each acts where the other's excess is too), but the pressure law with its
    partner qualifies as a pair, each member against the other alone -- the search says so
    (JSON ``pairs``, both steps marked ``pair``)."""
    names = ["O-ring_1bar.csv", "Circle_2bar.csv", "O-ring_3bar.csv", "Circle_4bar.csv",
             "O-ring_5bar.csv", "Circle_6bar.csv", "O-ring_7bar.csv"]
    recs = [datasets.load("zillen", n) for n in names]
    doc = Diagnosis("lugre", candidates=SEAL_CANDIDATES, n_jobs=1, check_baseline=False,
                    max_steps=3).fit(recs).to_dict()
    first = doc["steps"][0]
    assert not any(c["qualifies"] for c in first["candidates"]), first["candidates"]
    accepted = [p for p in doc["pairs"] if p["accepted"]]
    assert accepted and "pressure-dependence" in accepted[0]["effects"], doc["pairs"]
    assert first["pair"] == accepted[0]["effects"] and doc["steps"][1]["pair"]
    assert set(accepted[0]["effects"]) <= set(doc["added"])
    assert doc["rms_final"] < 0.7 * doc["rms_baseline"]
