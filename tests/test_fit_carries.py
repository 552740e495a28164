"""A fit carries what its model needs, and every command prints one RMS (issue 27, item 2).

* A fitted model carries the terms of its record the fit estimated beside the friction
  (``model_.measurement``: ``mass``, ``offset``, ``lag``, the model file's
  ``measurement_terms.params``), so ``fcomp.compare(record, fit.model_)`` works on a
  record with a driving force and no ``rig.mass`` (it raised "... no rig.mass").
* ``fit``'s RMS is the comparison's (:func:`fcomp.diagnosis.compare.model_rms`):
  ``fcomp fit`` and ``fcomp compare --params FIT.json`` print the same number (they
  printed 0.749 N and 0.840 N on the O-ring record); a diagnosis's held-out RMS says
  in words what it is.
"""

from __future__ import annotations

import json
import pickle
import warnings
from pathlib import Path

import numpy as np
import pytest

import fcomp
from fcomp.cli.main import main
from fcomp.diagnosis.compare import model_from_fit
from fcomp.errors import FcompError, FcompWarning
from fcomp.measurement import Measurement
from fcomp.modelfile import load_model, split_measurement
from fcomp.models import make_model
from fcomp.trajectory import friction_along_motion

ROOT = Path(__file__).resolve().parents[1]
ORING = ROOT / "fcomp" / "data" / "datasets" / "zillen" / "O-ring_3bar.csv"


@pytest.fixture(scope="module")
def oring(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped O-ring record at 3 bar (a driving force, no rig.mass), imported."""
    out = tmp_path_factory.mktemp("oring") / "oring3.csv"
    assert main(["import", "zillen", str(ORING), "-o", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def oring_fit(oring: Path) -> tuple[Measurement, fcomp.FrictionFit]:
    rec = fcomp.read(oring)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FcompWarning)
        return rec, fcomp.fit(rec, "lugre")


def _driving_force_record(path: Path, mass: float = 2.0, offset: float = 3.0) -> Path:
    """Coulomb-viscous friction seen through a driving force ``F_ext = F + m*a - offset``
    (no ``F`` column, no ``rig.mass``), 4 s at 500 Hz, 0.05 N noise."""
    t = np.arange(2000) / 500.0
    w = 2 * np.pi * 0.5
    x = 0.05 * np.sin(w * t) + 0.01 * np.sin(3.1 * w * t)
    v = 0.05 * w * np.cos(w * t) + 0.031 * w * np.cos(3.1 * w * t)
    a = -0.05 * w**2 * np.sin(w * t) - 0.0961 * w**2 * np.sin(3.1 * w * t)
    F = friction_along_motion(make_model("coulomb-viscous").with_params(Fc=15.0, B=200.0),
                              t, v, a=a).F
    noise = 0.05 * np.random.default_rng(5).standard_normal(t.size)
    Measurement({"t": t, "x": x, "v": v, "a": a, "F_ext": F + mass * a + offset + noise},
                {"name": path.stem, "kind": "friction-rig"}).write(path)
    return path


# ------------------------------------------------------------------ a. the fit carries it
def test_the_readme_block_works_on_the_real_oring_record(oring_fit) -> None:
    rec, fit = oring_fit
    assert set(fit.model_.measurement) == {"mass"}
    assert fit.model_.measurement["mass"] == pytest.approx(fit.params_["mass"])
    comp = fcomp.compare(rec, fit.model_)  # raised "... gives a driving force and no rig.mass"
    assert comp.rms == fit.rms_  # one RMS of a model on a record
    assert comp.values["mass"] == pytest.approx(fit.params_["mass"])


def test_measurement_terms_ride_along_pickles_effects_and_model_files(oring_fit,
                                                                      tmp_path: Path) -> None:
    _, fit = oring_fit
    model = fit.model_
    assert pickle.loads(pickle.dumps(model)).measurement == model.measurement
    assert model.with_effects("dwell-time").measurement == model.measurement
    assert model.with_params(Fc=1.0).measurement == model.measurement
    assert "measurement mass" in repr(model)
    # the model file: the one representation, measurement_terms.params
    path = model.save(tmp_path / "m.json")
    doc = json.loads(path.read_text())
    assert doc["version"] == 1
    assert doc["measurement_terms"]["params"] == pytest.approx(model.measurement)
    with pytest.warns(FcompWarning, match="measurement terms mass dropped"):
        seal = load_model(path)
    assert seal.measurement == {}
    assert load_model(path, measurement_terms=True).measurement == pytest.approx(
        model.measurement)
    # a model file of an older release (no terms) reads as before
    del doc["measurement_terms"]
    path.write_text(json.dumps(doc))
    assert load_model(path).measurement == {}


def test_split_measurement_puts_the_offset_into_its_effect() -> None:
    model = make_model("coulomb-viscous").with_measurement({"mass": 2.0, "offset": 1.5,
                                                            "lag": 0.002})
    friction, record = split_measurement(model)
    assert friction.measurement == {}
    assert [e.name for e in friction.effects] == ["force-offset"]
    assert friction.flat_params()["offset"] == 1.5
    assert record == {"mass": 2.0, "lag": 0.002}
    with pytest.raises(ValueError, match="not a measurement term"):
        model.with_measurement({"Fc": 1.0})


def test_a_fit_json_gives_its_mass_and_lag_to_the_model() -> None:
    model, mass = model_from_fit({"model": "coulomb-viscous",
                                  "params": {"Fc": 10.0, "B": 50.0, "mass": 2.5, "lag": 0.001}})
    assert mass == 2.5
    assert model.measurement == {"mass": 2.5, "lag": 0.001}


def test_simulate_drops_a_fitted_models_measurement_terms_with_a_warning(oring_fit) -> None:
    _, fit = oring_fit
    with pytest.warns(FcompWarning, match="the plant's moving mass is its own"):
        run = fcomp.simulate("motion", fit.model_, "sine:amplitude=0.01,frequency=0.5",
                             duration=0.5, rate=200.0)
    seal = fcomp.simulate("motion", fit.model_.with_measurement(None),
                          "sine:amplitude=0.01,frequency=0.5", duration=0.5, rate=200.0)
    assert np.array_equal(run["F"], seal["F"])


def test_the_missing_mass_message_says_what_to_do(oring: Path, capsys) -> None:
    assert main(["compare", str(oring), "--friction", "lugre", "--set", "Fc=1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fcomp: error: ") and err.count("\n") == 1
    for what in ("--mass KG", "--params FIT.json", "rig.mass"):
        assert what in err
    with pytest.raises(FcompError, match="give mass KG"):
        fcomp.compare(fcomp.read(oring), make_model("lugre"))


# ------------------------------------------------------------------ b. one RMS
@pytest.mark.parametrize("offset", [False, True])
def test_fit_and_compare_print_the_same_rms_on_a_synthetic_record(
        tmp_path: Path, capsys, offset: bool) -> None:
    rec = _driving_force_record(tmp_path / "rec.csv")
    fit_json, model_json = tmp_path / "fit.json", tmp_path / "model.json"
    assert main(["fit", str(rec), "--friction", "coulomb-viscous", "--json", str(fit_json),
                 "--save-model", str(model_json), *(["--offset"] if offset else [])]) == 0
    fitted = json.loads(fit_json.read_text())
    assert fitted["params"]["mass"] == pytest.approx(2.0, rel=0.05)
    assert "fcomp compare" in fitted["rms_measured"] and fitted["rms_fit"] > 0
    capsys.readouterr()
    for how in (["--friction", "coulomb-viscous", "--params", str(fit_json)],
                ["--friction", str(model_json)]):
        assert main(["compare", str(rec), *how, "--json", "-"]) == 0
        doc = json.loads(capsys.readouterr().out)
        assert doc["rms"] == fitted["rms"]
        assert doc["params"]["mass"] == pytest.approx(fitted["params"]["mass"])
    fit = fcomp.fit(rec, "coulomb-viscous", offset=offset)
    assert fcomp.compare(rec, fit.model_).rms == fit.rms_ == fitted["rms"]


@pytest.mark.parametrize("cutoff", [[], ["--cutoff", "20"]])
def test_fit_and_compare_print_the_same_rms_on_the_oring_record(oring: Path, tmp_path: Path,
                                                                 capsys, cutoff) -> None:
    """The issue's case: 0.749 N from fit, 0.840 N from compare --params fit.json; a fit
    with its own cut-off gives it to the comparison through its JSON."""
    out = tmp_path / "fit.json"
    assert main(["fit", str(oring), "--friction", "lugre", "--json", str(out), *cutoff]) == 0
    printed = capsys.readouterr().out
    fitted = json.loads(out.read_text())
    assert f"rms force error {fitted['rms']:.4g} N" in printed
    assert fitted["cutoff_hz"] == (20.0 if cutoff else 10.0)
    assert main(["compare", str(oring), "--friction", "lugre", "--params", str(out), "--json",
                 str(tmp_path / "cmp.json")]) == 0
    assert f"RMS {fitted['rms']:.4g} N on the whole record" in capsys.readouterr().out
    assert json.loads((tmp_path / "cmp.json").read_text())["rms"] == fitted["rms"]


def test_held_out_rms_says_what_it_is(tmp_path: Path) -> None:
    rec = fcomp.read(_driving_force_record(tmp_path / "rec.csv"))
    given = fcomp.compare(rec, make_model("coulomb-viscous").with_measurement({"mass": 2.0}))
    assert given.to_dict()["rms_measured"].startswith("the model's RMS error on the whole record")
    fitted = fcomp.compare(rec, "coulomb-viscous", fit=True).to_dict()
    assert fitted["rms_measured"].startswith("held-out RMS")
    assert "refitted on the training part" in fitted["rms_measured"]


def test_a_diagnosis_json_says_its_rms_is_held_out(tmp_path: Path) -> None:
    rec = fcomp.read(_driving_force_record(tmp_path / "rec.csv"))
    doc = fcomp.diagnose(rec, "coulomb-viscous", candidates=["stribeck"], max_steps=1, n_jobs=1,
                         check_baseline=False).to_dict()
    assert doc["rms_measured"].startswith("held-out RMS")
    assert "refitted on the training part" in doc["rms_measured"]
