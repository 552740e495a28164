"""fcomp design: the rig file, the diagnosis read, the programme physical, refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers.design_inputs import RIG

from fcomp.cli.main import main
from fcomp.errors import FcompError
from fcomp.planning import TEMPLATE, design
from fcomp.planning.rig import rig_from


def _diagnosis() -> dict:
    """A diagnosis by hand (the JSON's fields): lugre, pressure untested at one level."""
    import fcomp

    m = fcomp.make_model("lugre", params="canudas1995")
    doc = m.save  # noqa: F841  (the model document below)
    from fcomp.models.document import model_document

    return {"verdict": "explained", "noise_floor": 0.05, "added": [], "ties": [],
            "skipped": {"pressure-dependence": "needs p1: p1 + p2 hardly varies",
                        "stribeck": "already part of lugre"},
            "warnings": [], "signals": {"force": "F"},
            "model_file": model_document(m, source={"data": []})}


def _recorded_plan(res, rig, folder: Path):
    """The programme's experiments written as the rig's files and read back, as the motion
    plan a synthetic rig runs them along (fcomp.synthetic.motion.along, 10 fine steps)."""
    from fcomp.measurement import Measurement
    from fcomp.planning.programme import measurement
    from fcomp.synthetic.motion import along

    progs = []
    for k, e in enumerate(res.experiments_, 1):
        measurement(e, rig, f"e{k}", "pneumatic-cylinder").write(folder / f"e{k}.csv")
        progs.append(Measurement.read(folder / f"e{k}.csv").columns)
    return along([p["t"] for p in progs], [p["x"] for p in progs],
                 [p["p1"] + p["p2"] for p in progs], 1.0 / rig.rate / 10)


@pytest.fixture(scope="module")
def result():
    return design(_diagnosis(), rig_from(__import__("tomllib").loads(RIG)))


def test_programme_is_physical(result):
    rig = result.rig_
    assert result.experiments_
    for e in result.experiments_:
        s = e.signals
        dt = np.diff(s["t"])
        assert np.allclose(dt, 1 / rig.rate)
        assert s["x"].min() >= 0 and s["x"].max() <= rig.stroke
        v = np.diff(s["x"]) / dt
        assert np.max(np.abs(v)) <= rig.speed_max * 1.02
        a = np.diff(v) / dt[1:]
        assert np.max(np.abs(a)) <= rig.accel_max * 1.1
        assert e.duration <= rig.duration_max
        assert abs(v[0]) < 1e-9 and abs(v[-1]) < 1e-3  # starts and ends at rest
        assert set(np.unique(s["p1"])) <= set(rig.levels())


def test_untested_pressure_is_designed_for(result):
    q = [q for q in result.questions_ if q["kind"] == "untested"]
    assert [x["label"] for x in q] == ["pressure-dependence"]
    assert q[0]["predicted_separation"] > 1.0
    # the separation needs a level other than the record's: the programme leaves it
    levels = {e.level for e in result.experiments_}
    assert levels - {1.5e5}


def test_one_level_blocks_pressure_and_says_so():
    rig = RIG.replace("pressure_max = 2.5e5", "pressure_max = 1.5e5")
    doc = _diagnosis()
    r = design(doc, rig_from(__import__("tomllib").loads(rig)))
    msgs = [w["message"] for w in r.warnings_ if w["code"] == "limits-block"]
    assert msgs and "pressure" in msgs[0]


def test_template_is_a_valid_rig():
    import tomllib

    rig_from(tomllib.loads(TEMPLATE))


@pytest.mark.parametrize("edit, what", [
    (("stroke = 0.2", "stroke = 0"), "stroke"),
    (("speed_max = 0.2", "speed_max = 0"), "speed_max"),
    (("accel_max = 4.0", "accel_max = -4.0"), "accel_max"),
    (("rate = 500.0", "rate = 20.0"), "rate"),
    (("rate = 500.0", "rate = nan"), "rate"),
    (("duration_max = 20.0\n", ""), "duration_max"),
    (("rate = 500.0", "rate = 500.0\nspeed = 3"), "unknown"),
    (("stroke = 0.2", "stroke = 0.2\nstroke = 0.3"), "TOML"),
])
def test_bad_rig_files_exit_2(tmp_path: Path, capsys, edit, what):
    (tmp_path / "d.json").write_text(json.dumps(_diagnosis()))
    (tmp_path / "rig.toml").write_text(RIG.replace(*edit))
    code = main([ "design", str(tmp_path / "d.json"), "--rig", str(tmp_path / "rig.toml"),
                 "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and what in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("text", ['{"a": 1}', "[1, 2]", "not json",
                                  '{"verdict": "x", "verdict": "y"}'])
def test_bad_diagnoses_exit_2(tmp_path: Path, capsys, text):
    (tmp_path / "d.json").write_text(text)
    (tmp_path / "rig.toml").write_text(RIG)
    code = main(["design", str(tmp_path / "d.json"), "--rig", str(tmp_path / "rig.toml"),
                 "-o", str(tmp_path / "out")])
    assert code == 2 and not (tmp_path / "out").exists()
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.parametrize("target", ["json-on-diag", "json-on-rig", "dir-holding-rig"])
def test_output_onto_input_refused(tmp_path: Path, capsys, target):
    (tmp_path / "d.json").write_text(json.dumps(_diagnosis()))
    (tmp_path / "rig.toml").write_text(RIG)
    extra = {"json-on-diag": ["-o", str(tmp_path / "out"), "--json", str(tmp_path / "d.json")],
             "json-on-rig": ["-o", str(tmp_path / "out"), "--json", str(tmp_path / "rig.toml")],
             "dir-holding-rig": ["-o", str(tmp_path)]}[target]
    code = main(["design", str(tmp_path / "d.json"), "--rig", str(tmp_path / "rig.toml"),
                 *extra])
    assert code == 2
    assert json.loads((tmp_path / "d.json").read_text())["verdict"] == "explained"
    assert (tmp_path / "rig.toml").read_text() == RIG
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_cli_writes_programme_files(tmp_path: Path):
    from fcomp.measurement import Measurement

    (tmp_path / "d.json").write_text(json.dumps(_diagnosis()))
    (tmp_path / "rig.toml").write_text(RIG)
    code = main(["design", str(tmp_path / "d.json"), "--rig", str(tmp_path / "rig.toml"),
                 "-o", str(tmp_path / "out"), "--json", str(tmp_path / "des.json"),
                 "--report", str(tmp_path / "rep")])
    assert code == 0
    html = (tmp_path / "rep" / "report.html").read_text()
    assert html.index("Conclusion:") < html.index("<img")
    doc = json.loads((tmp_path / "des.json").read_text())
    assert doc["experiments"] and doc["questions"][0]["kind"] == "untested"
    m = Measurement.read(doc["experiments"][0])
    assert list(m.columns)[:4] == ["t", "x", "p1", "p2"]
    assert m.meta["rig"]["bore"] == 0.032


def test_template_cli(capsys):
    assert main(["design", "--template"]) == 0
    assert "[limits]" in capsys.readouterr().out


def test_fcomp_design_is_public():
    import fcomp

    assert fcomp.design is design
    with pytest.raises(FcompError):
        design({"nope": 1}, rig_from(__import__("tomllib").loads(RIG)))


@pytest.mark.slow
def test_recorded_programme_tests_the_untested_effect(tmp_path: Path):
    """End to end: a one-level record (pressure-dependence untested), the design, the
    programme recorded with a lip-seal pressure law of fcomp.synthetic (written apart from
    fcomp.effects; another seed, another noise), the re-diagnosis adds the effect."""
    import fcomp
    from fcomp.synthetic import generate

    law, rate = "pressure-dependence:lip-seal", 250.0
    old = generate([law], base="lugre", experiments=2, duration=10.0, pressures=[3e5],
                   seed=5, noise_std=0.3, rate=rate).measurement
    cands = ["pressure-dependence", "direction-asymmetry"]
    d0 = fcomp.diagnose([old], "lugre", candidates=cands, check_baseline=False, progress=False)
    doc = {**d0.to_dict(), "model_file": d0.model_file({"data": []})}
    assert "pressure-dependence" in doc["skipped"] and not doc["added"]
    rig = rig_from(__import__("tomllib").loads(
        RIG.replace("rate = 500.0", f"rate = {rate}").replace("duration_max = 20.0",
                                                               "duration_max = 12.0")))
    res = design(doc, rig)
    q = next(x for x in res.questions_ if x.get("label") == "pressure-dependence")
    assert q["predicted_separation"] > 1
    plan = _recorded_plan(res, rig, tmp_path)
    new = generate([law], base="lugre", pressures=[3e5], seed=105, plan=plan, rate=rate,
                   noise_std=0.5).measurement
    d1 = fcomp.diagnose([old, new], "lugre", candidates=cands, check_baseline=False,
                        progress=False)
    assert "pressure-dependence" in d1.to_dict()["added"]


def test_tie_opposes_the_models_fitted_at_the_step():
    """A tie written with its step's models: the design opposes them, and a pair that
    differs only with pressure is separated only by levels other than the record's."""
    import tomllib

    import fcomp
    from fcomp.models.document import model_document

    base = fcomp.make_model("lugre", params="canudas1995")
    a = base.with_effects(fcomp.make_effect("direction-asymmetry").with_params(r_neg=1.1))
    b = base.with_effects(fcomp.make_effect("pressure-dependence").with_params(
        kp=2e-6, p_ref=3e5))
    doc = {**_diagnosis(), "ties": [["direction-asymmetry", "pressure-dependence"]],
           "skipped": {},
           "tie_models": [{"step": 1, "chosen": "direction-asymmetry",
                           "effects": {"direction-asymmetry": model_document(a),
                                       "pressure-dependence": model_document(b)}}]}
    r = design(doc, rig_from(tomllib.loads(RIG)))
    q = r.questions_[0]
    assert q["kind"] == "tie" and q["rivals"] == ["direction-asymmetry", "pressure-dependence"]
    assert q["predicted_separation"] > 1
    # by hand: along a run both ways at one level, the two differ by the asymmetry and the
    # pressure factor; the predicted T is the sum of squares of that difference
    from fcomp.planning.criteria import force, t_criterion

    total = sum(t_criterion(force(a, e.signals), force(b, e.signals), r.noise_)
                for e in r.experiments_)
    assert total == pytest.approx(q["predicted_T"], rel=1e-9)


# ------------------------------------------------------------------ hostile inputs
def _run(folder: Path, diagnosis: str, rig: str, *extra: str) -> tuple[int, str]:
    """``fcomp design d.json --rig rig.toml -o out EXTRA`` on these texts in ``folder``: its
    exit status and standard error."""
    import contextlib
    import io

    (folder / "d.json").write_text(diagnosis)
    (folder / "rig.toml").write_text(rig)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(["design", str(folder / "d.json"), "--rig", str(folder / "rig.toml"),
                     "-o", str(folder / "out"), *extra])
    return code, err.getvalue()


@pytest.mark.parametrize("edit, what", [
    (("stroke = 0.2", "stroke = 1e308"), "stroke"),  # beyond any rig: a slip of unit
    (("stroke = 0.2", "stroke = 1" + "0" * 400), "stroke"),  # an integer no float holds
    (("speed_max = 0.2", "speed_max = 1e300"), "speed_max"),
    (("accel_max = 4.0", "accel_max = 1e300"), "accel_max"),
    (("rate = 500.0", "rate = 1e12"), "rate"),
    (("duration_max = 20.0", "duration_max = 1e12"), "duration_max"),
    (("rate = 500.0", "rate = 9e5"), "samples"),  # each within bounds, their product not
    (("pressure_min = 1.5e5\npressure_max = 2.5e5", 'pressure_levels = ["high"]'),
     "pressure_levels"),
    (("rate = 500.0", "rate = 500.0\nnoise = 1e300"), "noise"),
])
def test_rig_values_beyond_any_rig_exit_2(tmp_path: Path, edit, what):
    """Values no rig has (found by the hostile-case runner: a 1e12 s experiment hung, a
    1e12 Hz logger ran out of memory, 1e308 m and a 400-digit integer were internal
    errors): one line naming the key, nothing written."""
    assert edit[0] in RIG
    code, err = _run(tmp_path, json.dumps(_diagnosis()), RIG.replace(*edit))
    assert code == 2 and what in err and "rig.toml" in err, err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def _edited(**changes) -> str:
    return json.dumps({**_diagnosis(), **changes})


@pytest.mark.parametrize("text, what", [
    ("[" * 100000 + "]" * 100000, "nested too deep"),
    (json.dumps(_diagnosis()).replace('"noise_floor": 0.05', '"noise_floor": 1' + "0" * 5000),
     "5001 digits"),
    (_edited(noise_floor=1e308), "noise_floor"),
    (_edited(skipped=["pressure-dependence"]), "skipped"),
    (_edited(ties="area-error"), "ties"),
    (_edited(added={"a": 1}), "added"),
], ids=["deep", "bigint", "noise-huge", "skipped-list", "ties-text", "added-object"])
def test_diagnoses_of_the_wrong_shape_exit_2(tmp_path: Path, text, what):
    """A diagnosis JSON edited by hand into shapes fcomp diagnose never writes: one line
    naming the file and what is wrong (they were internal errors, or accepted)."""
    code, err = _run(tmp_path, text, RIG)
    assert code == 2 and what in err and "d.json" in err, err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_an_effect_fcomp_does_not_know_is_left_out_and_said(tmp_path: Path):
    """A tie naming an effect of an effects file the design runs without: the tie is left
    out with a warning naming it, the rest designed; alone, nothing to design (exit 2,
    naming the file and the effect)."""
    code, err = _run(tmp_path, _edited(ties=[["my-seal-law", "area-error"]]), RIG)
    assert code == 0 and "my-seal-law" in err and "warning" in err
    assert list((tmp_path / "out").glob("experiment_*.csv"))
    alone = tmp_path / "alone"
    alone.mkdir()
    code, err = _run(alone, _edited(skipped={"my-seal-law": "one level only"}), RIG)
    assert code == 2 and "d.json" in err and "my-seal-law" in err
    assert not (alone / "out").exists()


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")
def test_a_json_that_cannot_be_written_leaves_no_programme(tmp_path: Path):
    """Every output or none: the JSON on a full disk used to fail after the programme
    folder was in place (a programme without its design)."""
    code, err = _run(tmp_path, json.dumps(_diagnosis()), RIG, "--report",
                     str(tmp_path / "rep"), "--json", "/dev/full")
    assert code == 2 and "/dev/full" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.json", "rig.toml"]


def test_recorded_programme_breaks_a_tie_the_old_closeness_would_keep(tmp_path: Path):
    """End to end for a tie: a record whose pressure and direction move together
    (direction-asymmetry of the levels law, noise 0.5 N, a 250 Hz logger: off the chain's
    defaults) fits a pressure law and the asymmetry equally well -- a tie, the paired test
    finding no difference. The design opposes the two; the programme, recorded with the law of
    fcomp.synthetic (written apart from fcomp.effects; another seed), is diagnosed with the
    record: the asymmetry is chosen and the tie is gone, although the pressure law's held-out
    RMS stays within the fall's share of it -- the held-out data tell them apart (p < 0.05),
    which the closeness alone did not see."""
    import tomllib

    import fcomp
    from fcomp.synthetic import generate

    law, rate, noise = "direction-asymmetry:levels", 250.0, 0.5
    cands = ["direction-asymmetry", "pressure-dependence"]
    old = generate([law], base="lugre", experiments=2, duration=12.0, seed=32, noise_std=noise,
                   rate=rate).measurement
    d0 = fcomp.diagnose([old], "lugre", candidates=cands, check_baseline=False, progress=False)
    doc = {**d0.to_dict(), "model_file": d0.model_file({"data": []})}
    assert sorted(map(sorted, doc["ties"])) == [sorted(cands)], doc["ties"]
    before = [t for s in doc["steps"] for t in s["tie_tests"]]
    assert before and all(t["close"] and not t["separated"] for t in before), before
    rig = rig_from(tomllib.loads(RIG.replace("rate = 500.0", f"rate = {rate}")
                                 .replace("pressure_max = 2.5e5", "pressure_max = 4e5")
                                 .replace("duration_max = 20.0", "duration_max = 12.0")))
    res = design(doc, rig)
    q = next(x for x in res.questions_ if x["kind"] == "tie")
    assert sorted(q["rivals"]) == sorted(cands) and q["pairs"][0]["answered"]
    plan = _recorded_plan(res, rig, tmp_path)
    new = generate([law], base="lugre", seed=1032, plan=plan, rate=rate,
                   noise_std=noise).measurement
    d1 = fcomp.diagnose([old, new], "lugre", candidates=cands, check_baseline=False,
                        progress=False).to_dict()
    assert d1["added"] == ["direction-asymmetry"] and d1["ties"] == [], (d1["added"], d1["ties"])
    (after,) = [t for s in d1["steps"] for t in s["tie_tests"]]
    assert after["effect"] == "pressure-dependence" and after["separated"] and not after["tie"]
    assert after["p"] < 0.05 and after["difference"] >= after["need"]


def test_information_at_a_parameter_bound_is_one_sided():
    """A parameter fitted to its bound (a LuGre bristle damping at 0) has no value below it:
    its column of the Jacobian is the one-sided difference, equal to the central one of a
    parameter entering the force linearly (sigma1 enters as sigma1*dz/dt: checked against
    the central difference about an inner value)."""
    import fcomp
    from fcomp.planning.criteria import jacobian

    t = np.arange(0.0, 2.0, 1e-3)
    x = 0.05 * (1 - np.cos(2 * np.pi * 0.5 * t))
    v = np.gradient(x, t)
    sig = {"t": t, "x": x, "v": v, "a": np.gradient(v, t), "p1": np.full(t.size, 3e5),
           "p2": np.full(t.size, 1e5)}
    m = fcomp.make_model("lugre", params="canudas1995")
    at_bound = jacobian(m.with_params(sigma1=0.0), sig, ["sigma1"], False)
    inner = jacobian(m.with_params(sigma1=1e-6), sig, ["sigma1"], False)
    assert np.all(np.isfinite(at_bound)) and np.max(np.abs(at_bound)) > 0
    # the step at 0 is 1e-9 Ns/m: rounding of the force leaves about 1e-7 of the column
    np.testing.assert_allclose(at_bound, inner, rtol=1e-3, atol=1e-4 * np.max(np.abs(inner)))
