"""The model file (docs/model-file.md): a friction model that travels.

Saved and loaded models give the same forces bit for bit (along a motion and
in a plant); a hand-written file gives the forces of the hand formulas; fit
and diagnose write it; simulate and compare read it; bad files get one line
and exit status 2; measurement terms stay in the file and are dropped (with a
warning) from plant friction.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

import fcomp
from fcomp.cli.main import main
from fcomp.effects import EFFECTS, make_effect
from fcomp.errors import FcompWarning, FileFormatError
from fcomp.measurement import Measurement
from fcomp.modelfile import read_model
from fcomp.models import make_model
from fcomp.trajectory import friction_along_motion

T = np.arange(3001) / 1000.0
V = 0.05 * np.sin(2 * np.pi * T) + 0.01 * np.sin(7 * np.pi * T)
A = 0.1 * np.pi * np.cos(2 * np.pi * T) + 0.07 * np.pi * np.cos(7 * np.pi * T)
X = 0.15 + np.cumsum(V) / 1000.0
P1 = 3e5 + 1e5 * np.sin(np.pi * T)
P2 = 2e5 - 0.5e5 * np.cos(np.pi * T)


def _models() -> dict[str, fcomp.FrictionModel]:
    """Models of every kind: family presets, effects with configuration and direction-
    dependent values, a chain of structural effects with their forms, discrete memory."""
    lugre = make_model("lugre", params="canudas1995").with_effects(
        make_effect("pressure-dependence", {"kp_pos": 2e-7, "kp_neg": 1e-7}),
        make_effect("position-dependence", x_min=0.0, x_max=0.25))
    chain = make_model("coulomb-viscous", params="seed002-type1").with_effects(
        make_effect("stribeck", {"Fs_excess": 80.0, "vs": 0.01}),
        make_effect("presliding", {"sigma0": 2e6, "sigma1": 300.0, "ba_pre": 0.3},
                    form="elasto-plastic"),
        make_effect("frictional-lag", {"tau_L": 0.05, "w_L": 0.5}, form="speed-lag"),
        make_effect("nonlocal-memory", {"ms_share": 0.5, "ms_spread": 10.0},
                    form="maxwell-slip"),
        "dwell-time")
    return {"lugre-effects": lugre, "structural-chain": chain,
            "nmlgm": make_model("nmlgm", params="seed000-cylinder1"),
            "nmlgm-hysteresis": make_model("nmlgm-hysteresis", params="seed000-cylinder1"),
            "gms": make_model("gms")}


def _forces(model: fcomp.FrictionModel) -> np.ndarray:
    return friction_along_motion(model, T, V, a=A, x=X, p1=P1, p2=P2).F


@pytest.mark.parametrize("name", list(_models()))
def test_saved_and_loaded_models_give_the_same_forces_bit_for_bit(name: str,
                                                                  tmp_path: Path) -> None:
    model = _models()[name]
    path = model.save(tmp_path / f"{name}.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == "fcomp-model" and doc["version"] == 1
    back = fcomp.load_model(path)
    assert type(back) is type(model)
    assert back.describe() == model.describe()
    assert back.flat_params() == model.flat_params()
    assert [(e.name, e.config) for e in back.effects] == [(e.name, e.config)
                                                          for e in model.effects]
    assert np.array_equal(_forces(back), _forces(model))


def test_a_plant_with_the_loaded_model_runs_the_same_bit_for_bit(tmp_path: Path) -> None:
    model = make_model("lugre", params="seed002-type1").with_effects(
        make_effect("pressure-dependence", {"kp": 1e-8}))
    path = model.save(tmp_path / "m.json")
    back = fcomp.load_model(path)
    runs = [fcomp.simulate("hydraulic", m, "sine:amplitude=0.004,frequency=2", 0.2)
            for m in (model, back, str(path))]  # a model, the one read back, the file
    for col in ("x", "p1", "p2", "F"):
        assert np.array_equal(runs[0][col], runs[1][col])
        assert np.array_equal(runs[0][col], runs[2][col])


def test_a_hand_written_file_gives_the_hand_formula(tmp_path: Path) -> None:
    """Coulomb-viscous, direction-dependent levels: F = Fc(side)*sign(v) + B*v."""
    path = tmp_path / "cv.json"
    path.write_text(json.dumps({
        "format": "fcomp-model", "version": 1, "model": "coulomb-viscous", "effects": [],
        "params": {"Fc_pos": 10.0, "Fc_neg": 12.0, "B": 50.0}}))
    model = fcomp.load_model(path)
    v = np.array([-0.2, -0.05, 0.05, 0.3])
    expected = np.where(v > 0, 10.0, -12.0) + 50.0 * v
    assert np.allclose(model.steady_state(v), expected, rtol=1e-12, atol=0.0)


def test_hand_written_structural_effects_rebuild_the_richer_model(tmp_path: Path) -> None:
    """coulomb + stribeck + viscous by effects is the stribeck map of models.md 1.1:
    F = sign(v)*(Fc + (Fs - Fc)*exp(-(|v|/vs)^n)) + sigma2*v."""
    path = tmp_path / "s.json"
    path.write_text(json.dumps({
        "format": "fcomp-model", "version": 1, "model": "coulomb",
        "effects": [{"name": "stribeck"}, {"name": "viscous"}],
        "params": {"Fc": 20.0, "Fs": 35.0, "vs": 0.01, "n": 2.0, "sigma2": 100.0}}))
    model = fcomp.load_model(path)
    v = np.array([-0.05, -0.01, 0.004, 0.02, 0.1])
    g = 20.0 + 15.0 * np.exp(-(np.abs(v) / 0.01) ** 2)
    assert np.allclose(model.steady_state(v), np.sign(v) * g + 100.0 * v, rtol=1e-9)
    assert model.describe() == "coulomb + stribeck + viscous"


def test_measurement_terms_stay_in_the_file_and_leave_plant_friction(tmp_path: Path,
                                                                      capsys) -> None:
    model = make_model("lugre", params="canudas1995").with_effects(
        make_effect("force-offset", {"offset": 2.5}))
    path = model.save(tmp_path / "m.json", measurement={"mass": 3.0, "lag": 0.002})
    doc = json.loads(path.read_text())
    assert "force-offset" not in [e["name"] for e in doc["effects"]]
    assert doc["measurement_terms"]["effects"][0]["params"] == {"offset": 2.5}
    assert doc["measurement_terms"]["params"] == {"mass": 3.0, "lag": 0.002}
    assert "offset" not in doc["params"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        seal = fcomp.load_model(path)
    assert [w.message.code for w in caught if isinstance(w.message, FcompWarning)] == [
        "measurement-terms"]
    assert seal.describe() == "lugre"
    mf = read_model(path)
    assert mf.mass == 3.0
    measured = mf.measured_model()
    assert np.array_equal(_forces(measured), _forces(model))
    assert np.allclose(_forces(measured) - _forces(seal), 2.5, rtol=0, atol=1e-12)
    out = tmp_path / "run.csv"
    code = main(["simulate", "motion", "--friction", str(path), "--input",
                 "sine:amplitude=0.01,frequency=1", "--duration", "0.5", "-o", str(out)])
    assert code == 0
    err = capsys.readouterr().err
    assert "measurement terms force-offset, mass, lag dropped" in err


USER_EFFECT = '''
from fcomp.effects import Effect, register_effect
from fcomp.parameters import make_params_class, spec


@register_effect
class Bias(Effect):
    """A constant bias of the load cell (the user's own effect)."""

    name = "my-bias"
    Params = make_params_class("BiasParams", [spec("bias", "N", 0.0, -1e3, 1e3, "bias",
                                                   directional=False)], owner="bias")

    def extra_force(self, be, sig, P):
        return P("bias"), 0.0
'''


def _bad(path: Path, capsys, *extra: str) -> str:
    code = main(["simulate", "motion", "--friction", str(path), "--input",
                 "sine:amplitude=0.01,frequency=1", "--duration", "0.2",
                 "-o", str(path.with_name("out.csv")), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert str(path) in err[0]
    return err[0]


def test_a_users_effect_needs_its_module(tmp_path: Path, capsys) -> None:
    from fcomp.effects import load_effects_module
    from fcomp.usercode import USER_FILES

    mod = tmp_path / "my_effects.py"
    mod.write_text(USER_EFFECT)
    load_effects_module(mod)
    model = make_model("coulomb").with_effects(make_effect("my-bias", {"bias": 4.0}))
    path = model.save(tmp_path / "user.json")
    assert json.loads(path.read_text())["effects"][0]["module"] == str(mod)
    EFFECTS._items.pop("my-bias")  # a fresh process: the effect is not registered
    USER_FILES.clear()
    line = _bad(path, capsys)
    assert "'my-bias' is a user effect" in line and "--effects" in line
    back = fcomp.load_model(path, effects_module=mod)
    assert np.allclose(back.steady_state(np.array([0.1])), 1.0 + 4.0)


@pytest.mark.parametrize("text, words", [
    ('{"format": "fcomp-model", "version": 1, "model": "lugre", '
     '"effects": [{"name": "no-such-effect"}], "params": {}}', "unknown effect 'no-such-effect'"),
    ('{"format": "fcomp-model", "version": 2, "model": "lugre", "params": {}}',
     "model file version 2 is newer"),
    ('{"format": "fcomp-model", "version": 1, "model": "lugre", "params": {"Fc": 1,}}',
     "not valid JSON"),
    ('{"model": "lugre", "params": {}}', "not an fcomp model file"),
    ('{"format": "fcomp-model", "version": 1, "model": "no-model", "params": {}}',
     "unknown friction model 'no-model'"),
    ('{"format": "fcomp-model", "version": 1, "model": "lugre", "params": {"Fc": -1}}',
     "Fc"),
    ('{"format": "fcomp-model", "version": 1, "model": "lugre", "params": {"zz": 1}}',
     "params.zz is not a parameter"),
    ('{"format": "fcomp-model", "version": 1, "model": "lugre", "parms": {}}',
     "unknown key 'parms'"),
])
def test_a_bad_model_file_gets_one_line_and_exit_2(text: str, words: str, tmp_path: Path,
                                                   capsys) -> None:
    path = tmp_path / "bad.json"
    path.write_text(text)
    assert words in _bad(path, capsys)
    with pytest.raises(FileFormatError):
        read_model(path)


def _record(tmp_path: Path) -> Path:
    """Coulomb-viscous friction along a motion with a driving force and no mass: the fit
    estimates the mass (a measurement term)."""
    model = make_model("coulomb-viscous").with_params(Fc=15.0, B=200.0)
    F = friction_along_motion(model, T, V, a=A).F
    rng = np.random.default_rng(3)
    F_ext = F + 2.0 * A + 0.05 * rng.standard_normal(T.size)  # F = F_ext - m*a
    path = tmp_path / "rec.csv"
    Measurement({"t": T, "v": V, "a": A, "F_ext": F_ext}, {"name": "rec"}).write(path)
    return path


def test_fit_writes_the_model_file_and_compare_reads_it(tmp_path: Path, capsys) -> None:
    rec = _record(tmp_path)
    saved, out = tmp_path / "fit.json", tmp_path / "out.json"
    assert main(["fit", str(rec), "--friction", "coulomb-viscous", "--save-model", str(saved),
                 "--json", str(out), "--no-progress"]) == 0
    doc, result = json.loads(saved.read_text()), json.loads(out.read_text())
    assert result["model_file"] == doc
    assert doc["measurement_terms"]["params"]["mass"] == pytest.approx(2.0, rel=0.05)
    assert doc["params"]["Fc"] == pytest.approx(15.0, rel=0.02)
    assert doc["params"]["B"] == pytest.approx(200.0, rel=0.02)
    fit = fcomp.fit(rec, "coulomb-viscous")
    seal = read_model(saved).model  # the friction, without the fitted mass
    assert np.array_equal(_forces(seal), _forces(fit.model_))
    capsys.readouterr()
    assert main(["compare", str(rec), "--friction", str(saved), "--json", "-"]) == 0
    by_file = json.loads(capsys.readouterr().out)
    # the same comparison as with the fit's JSON (its values and fitted mass)
    assert main(["compare", str(rec), "--friction", "coulomb-viscous", "--params", str(out),
                 "--json", "-"]) == 0
    by_fit = json.loads(capsys.readouterr().out)
    assert by_file["rms_plain"] == by_fit["rms_plain"]
    assert by_file["rms"] == by_fit["rms"]
    assert main(["compare", str(rec), "--friction", str(saved), "--params", "canudas1995"]) == 2
    assert "gives the values" in capsys.readouterr().err
    # a fit started from the file: the same model, the same optimum
    assert main(["fit", str(rec), "--friction", str(saved), "--json", "-", "--no-progress"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert again["model"] == "coulomb-viscous"
    assert again["params"]["B"] == pytest.approx(result["params"]["B"], rel=1e-6)


def test_save_model_refuses_a_name_that_is_not_json(tmp_path: Path, capsys) -> None:
    rec = _record(tmp_path)
    assert main(["fit", str(rec), "--friction", "coulomb", "--save-model",
                 str(tmp_path / "m.txt")]) == 2
    assert "ends in .json" in capsys.readouterr().err


def test_diagnose_writes_its_final_model(tmp_path: Path, capsys) -> None:
    """The diagnosis's final model with a force offset: the offset is a measurement term."""
    from fcomp.synthetic import generate

    data = tmp_path / "off.csv"
    generate(["force-offset"], duration=12.0, seed=1).measurement.write(data)
    saved = tmp_path / "diag.json"
    assert main(["diagnose", str(data), "--friction", "coulomb-viscous", "--add-effect",
                 "force-offset", "--no-search", "--no-baseline-check", "--no-progress",
                 "--jobs", "1", "--save-model", str(saved), "--json", "-"]) == 0
    result = json.loads(capsys.readouterr().out)
    doc = json.loads(saved.read_text())
    assert result["model_file"] == doc
    assert doc["description"] == "coulomb-viscous + force-offset"
    terms = doc["measurement_terms"]
    assert [e["name"] for e in terms["effects"]] == ["force-offset"]
    assert "offset" not in terms["params"] and "offset" not in doc["params"]
    mf = read_model(saved)
    assert mf.model.describe() == "coulomb-viscous"
    assert mf.measured_model().flat_params()["offset"] == pytest.approx(
        result["model_params"]["offset"], rel=1e-12)
    assert doc["params"]["B"] == result["model_params"]["B"]
    # the final model as the baseline of another diagnosis (its offset left out, said so)
    assert main(["diagnose", str(data), "--friction", str(saved), "--no-search",
                 "--no-baseline-check", "--no-progress", "--jobs", "1", "--json", "-"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["baseline"] == "coulomb-viscous"
    assert "measurement terms force-offset dropped" in captured.err


def _users_model_file(tmp_path: Path) -> tuple[Path, Path]:
    """A user's effects module (:data:`USER_EFFECT`) and a model file naming its effect,
    the effect then unregistered as in a fresh process: ``(module, model file)``."""
    from fcomp.effects import load_effects_module
    from fcomp.usercode import USER_FILES

    mod = tmp_path / "my_effects.py"
    mod.write_text(USER_EFFECT)
    load_effects_module(mod)
    model = make_model("lugre", params="seed002-type1").with_effects(
        make_effect("my-bias", {"bias": 40.0}))
    path = model.save(tmp_path / "user.json")
    EFFECTS._items.pop("my-bias")  # a fresh process: the effect is not registered
    USER_FILES.clear()
    return mod, path


def test_study_compensators_reads_a_model_file_with_a_users_effect_given_its_module(
        tmp_path: Path, capsys) -> None:
    """``study compensators --friction FILE.json`` with a user's effect: refused in one line
    without ``--effects`` (nothing written); with it, the study's plants carry the user's
    effect as the true friction and in the controllers' mismatched copy; ``--effects`` for a
    study that takes no friction is refused."""
    from studies.base import StudyConfig
    from studies.compensators import study_plants

    mod, path = _users_model_file(tmp_path)
    out = tmp_path / "study"
    args = ["study", "compensators", "--fast", "--no-progress", "--friction", str(path),
            "--out", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--effects" in err[0] and "my-bias" in err[0], err
    assert not out.exists()
    assert main(["study", "presliding", "--fast", "--effects", str(mod), "--out",
                 str(tmp_path / "other")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["fcomp: error: --effects applies to the compensators study"], err
    plants = study_plants(StudyConfig(out=out, friction=str(path), effects=str(mod)))
    assert [p.label for p in plants] == ["hydraulic", "pneumatic"]
    for p in plants:
        for friction in (p.base.friction, p.base.controller_friction):
            assert "my-bias" in friction.describe(), friction.describe()
            assert friction.flat_params()["bias"] == pytest.approx(40.0)
    assert StudyConfig.coerce({"out": out, "effects": str(mod)}).effects == str(mod)


def test_sweep_reads_a_model_file_with_a_users_effect_given_its_module(
        tmp_path: Path, capsys) -> None:
    """``sweep --friction FILE.json`` with a user's effect: refused in one line without
    ``--effects``, run (in a worker process too) with it."""
    mod, path = _users_model_file(tmp_path)
    args = ["sweep", "--plant", "hydraulic", "--controllers", "pid", "--samples", "1",
            "--friction", str(path), "--no-progress"]
    assert main([*args, "--json", str(tmp_path / "no.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--effects" in err[0], err
    assert not (tmp_path / "no.json").exists()
    out = tmp_path / "sweep.json"
    assert main([*args, "--effects", str(mod), "--jobs", "2", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["runs"] and all(r["status"] == "ok" for r in doc["runs"]), doc["runs"]
