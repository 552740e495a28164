"""``fcomp compensate`` honest (issue 39 item 3, issue 42 items 1, 2, 10, 13, 14): which
friction the plant runs, what is ranked and what is not, and what the conclusion may say.

The unit tests check the pieces against hand computations (the candidate truths'
draws within their bounds, the run checks' rules, the conclusion's confidence);
the command-line cases run short loops (fast ``steps``, one or two controllers).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fcomp.cli.main import main
from fcomp.models import make_model

ROOT = Path(__file__).resolve().parents[1]
AXIS = ROOT / "docs" / "examples" / "axis50.toml"


def _run(args: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


# ------------------------------------------------------------------ run checks
def _metrics(**kw: float) -> dict:
    base = {"reference_travel": 4e-3, "travel": 4e-3, "saturated_share": 0.0,
            "hunting_amplitude": 1e-6, "steps": 1000, "fallbacks": 0, "max_error": 1e-4}
    return {**base, **kw}


@pytest.mark.parametrize("metrics, words", [
    (_metrics(travel=1e-5, max_error=2e-3), "never moved"),
    (_metrics(saturated_share=0.95), "saturated throughout"),
    (_metrics(hunting_amplitude=1e-3), "limit cycle: +-1e+03 um"),  # the +-1000 um of issue 42
    (_metrics(reference_travel=2e-3, travel=2e-3, hunting_amplitude=5.25e-4), "limit cycle"),
    (_metrics(fallbacks=300), "solver failed"),
    (_metrics(max_error=9e-3), "lost the reference"),
])
def test_a_run_that_did_not_do_the_task_is_flagged(metrics: dict, words: str) -> None:
    from controllers.run_checks import run_flags, run_status

    flags = run_flags(metrics)
    assert len(flags) == 1 and words in flags[0], flags
    assert run_status("ok", metrics).startswith("flagged: ")
    assert run_status("ok", _metrics()) == "ok"
    assert run_status("failed: boom", None) == "failed: boom"


def test_stick_slip_a_compensator_should_remove_is_ranked() -> None:
    """+-350 um of stick-slip on the 2.7 mm of the fast ramp is the task's point, not a
    run to leave out."""
    from controllers.run_checks import run_flags

    assert run_flags(_metrics(reference_travel=2.7e-3, travel=2.7e-3,
                              hunting_amplitude=3.5e-4)) == []


def test_a_hold_is_judged_by_saturation_and_the_solver_alone() -> None:
    """A user's reference that holds still (travel 0) cannot 'never move'."""
    from controllers.run_checks import run_flags

    hold = _metrics(reference_travel=0.0, travel=0.0, hunting_amplitude=5e-6, max_error=1e-5)
    assert run_flags(hold) == []
    assert "saturated" in run_flags({**hold, "saturated_share": 1.0})[0]


# ------------------------------------------------------------------ truths
def test_uncertainty_draws_stay_within_the_bounds_and_the_constraints() -> None:
    """Draws from standard errors far larger than the values: every draw a valid model (Fc
    below Fs, every value within its bounds), the parameters without error untouched, and
    the spread of a well-determined parameter that of its standard error."""
    from controllers.truths import uncertainty_draws

    m = make_model("lugre", params="seed002-type1")
    se = {"Fc": 200.0, "Fs": 150.0, "sigma2": 50.0}
    draws = uncertainty_draws(m, se, 300, np.random.default_rng(1))
    specs = m.param_specs()
    for d in draws:
        f = d.flat_params()
        assert f["Fc"] <= f["Fs"]
        assert all(specs[k].lower <= v <= specs[k].upper for k, v in f.items())
        assert f["sigma0"] == m.flat_params()["sigma0"]
    s2 = np.array([d.flat_params()["sigma2"] for d in draws])
    assert abs(np.std(s2) - 50.0) < 8.0 and abs(np.mean(s2) - 900.0) < 10.0
    assert uncertainty_draws(m, {}, 3, np.random.default_rng(1)) == []


def test_candidate_truths_are_the_models_their_draws_and_rivals_once_each() -> None:
    from controllers.truths import Compared, candidate_truths, same_friction

    base = make_model("coulomb-viscous", params="seed002-type1")
    diag = make_model("lugre", params="seed002-type1")
    rival = diag.with_params(Fs=300.0)
    cast = candidate_truths({"base": Compared(base, {"Fc": 5.0}),
                             "diag": Compared(diag, rivals=(("lugre", rival, "tied"),
                                                            ("lugre", diag, "itself")))},
                            draws=2, seed=3, named={"same": base.with_params()})
    labels = [t.label for t in cast]
    assert labels == ["base", "diag", "base~1", "base~2", "diag:rival1"]
    assert [t.equals for t in cast] == ["base", "diag", None, None, None]
    assert same_friction(cast[0].model, base) and not same_friction(cast[2].model, base)
    assert {t.origin for t in cast} == {"compared", "uncertainty", "rival"}


def test_a_diagnosis_model_file_carries_its_rivals() -> None:
    """``source.diagnosis.rivals`` as ``fcomp diagnose`` writes it, read back as truths."""
    from controllers.truths import rivals_of
    from fcomp.models.document import model_document

    rival = make_model("lugre", params="seed002-type1").with_effects("force-offset")
    doc = {"source": {"diagnosis": {"rivals": [
        {"why": "tied", "model_file": model_document(rival)},
        {"why": "broken", "model_file": {"format": "nope"}}]}}}
    ((name, model, why),) = rivals_of(doc)
    assert why == "tied" and model.describe() == "lugre"  # the offset is the measurement's


# ------------------------------------------------------------------ outside the fit
def test_a_position_effect_run_far_outside_its_window_is_said() -> None:
    """The README's chain: a position dependence fitted over -37..2.7 mm run at 150 mm."""
    from controllers.model_range import Span, range_warnings

    m = (make_model("coulomb-viscous").with_params(Fc=3.6, B=350.0)
         .with_effects(make_position())
         .with_params(kx1=-0.019, kx2=-0.29, kx3=0.2))
    out = range_warnings("diag", m, Span(0.128, 0.172, 0.14), truth=True, free_force=4000.0)
    codes = [c for c, _ in out]
    assert codes[0] == "outside-fitted-range" and "-37.17..2.746 mm" in out[0][1]
    inside = range_warnings("diag", m, Span(-0.03, 0.0, 0.01), truth=True, free_force=4000.0)
    assert inside == []


def make_position():  # the window the diagnosis configured on the O-ring record
    from fcomp.effects import make_effect

    return make_effect("position-dependence", x_min=-0.0371696, x_max=0.0027456)


# ------------------------------------------------------------------ conclusions
def _doc(per_truth: dict[str, float], holds: str, mode: str = "candidates",
         equals: str | None = None, better: float = 1.0) -> dict:
    ranked = [v for v in per_truth.values()]
    truths = {t: {"equals": equals if i == 0 else None} for i, t in enumerate(per_truth)}
    return {"baseline": "base", "models": {"base": "", "diag": ""}, "mode": mode,
            "controllers": ["pid", "ekf"], "uses_friction": {"pid": False, "ekf": True},
            "tasks": ["steps"], "truths": truths,
            "runs": [{"status": "ok", "controller": "ekf", "model": "diag"}] * 4,
            "across_truths": {"ekf": {"diag": {"per_truth": per_truth, "holds": holds,
                                               "best": min(ranked), "worst": max(ranked)}}},
            "robustness": {"controllers": {"ekf": {"ratio": {"diag": {"better": better}}}}},
            "warnings": []}


def test_opposite_ratios_are_never_high_confidence() -> None:
    """Issue 42 item 14: 2.09 under one truth and 0.35 under another is no recommendation."""
    from controllers.conclusions import of_compensation

    c = of_compensation(_doc({"base": 2.09, "diag": 0.35}, "mixed"))
    assert c.confidence == "low"
    assert "no model wins under every truth" in c.finding
    assert "2.09" in c.finding and "0.35" in c.finding
    assert not any(s.startswith("deploy") for s in c.next_steps)


def test_a_model_better_under_every_truth_is_recommended() -> None:
    from controllers.conclusions import of_compensation

    c = of_compensation(_doc({"base": 0.5, "diag": 0.3, "base~1": 0.8}, "better"))
    assert c.confidence == "high" and "under every one of the 3 candidate truths" in c.finding
    assert "ekf: median-task ratio 0.30-0.80" in c.finding
    assert c.next_steps[0].startswith("deploy it: fcomp export ekf ")
    circular = of_compensation(_doc({"diag": 0.3}, "better", mode="given", equals="diag"))
    assert circular.confidence == "low" and circular.reasons[0].startswith("circular")


def test_every_run_failed_is_said_so() -> None:
    """Issue 42 item 2: not 'no controller here uses the friction model (): high'."""
    from controllers.conclusions import of_compensation

    doc = _doc({"base": 1.0}, "not ranked")
    doc["runs"] = [{"status": "failed: the plant integration did not converge",
                    "controller": "ekf", "model": m} for m in ("base", "diag")]
    c = of_compensation(doc)
    assert c.finding.startswith("every run failed") and c.confidence == "low"
    assert "ekf with base (failed: the plant integration did not converge; 1 run)" in c.reasons


# ------------------------------------------------------------------ the command
def _files(folder: Path) -> tuple[Path, Path]:
    """A Coulomb-viscous baseline and a LuGre 'diagnosis', each with standard errors."""
    base = make_model("coulomb-viscous", params="seed002-type1").with_stderr(
        {"Fc": 6.0, "B": 40.0})
    diag = make_model("lugre", params="seed002-type1").with_stderr(
        {"Fc": 5.0, "Fs": 8.0, "sigma2": 30.0})
    paths = folder / "base.json", folder / "diag.json"
    base.save(paths[0])
    diag.save(paths[1])
    return paths


@pytest.fixture(scope="module")
def candidates(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The honest default: no --friction; pid-ff and the LuGre observer on the fast steps,
    one uncertainty draw per model."""
    import contextlib
    import io

    folder = tmp_path_factory.mktemp("truths")
    base, diag = _files(folder)
    out = folder / "c.json"
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        code = main(["compensate", "--plant-params", str(AXIS), "--controller-friction",
                     f"{base},{diag}", "--controllers", "pid-ff,lugre-observer", "--task",
                     "steps", "--fast", "--samples", "2", "--truth-draws", "1", "--jobs",
                     "1", "--json", str(out), "--no-progress"])
    return {"code": code, "doc": json.loads(out.read_text()), "stdout": stdout.getvalue()}


def test_the_default_runs_every_candidate_truth(candidates: dict) -> None:
    doc = candidates["doc"]
    assert candidates["code"] == 0
    assert doc["mode"] == "candidates"
    assert list(doc["truths"]) == ["base", "diag", "base~1", "diag~1"]
    assert doc["truths"]["base"]["equals"] == "base" and doc["truths"]["base~1"]["equals"] is None
    assert {r["truth"] for r in doc["runs"]} == set(doc["truths"])
    assert len(doc["runs"]) == 4 * 2 * 2  # truths x controllers x models, one task
    assert any(w["code"] == "truth-is-compared" for w in doc["warnings"])
    # a draw differs from its model within a few standard errors
    f0, f1 = doc["truths"]["diag"]["params"], doc["truths"]["diag~1"]["params"]
    assert f1["Fc"] != f0["Fc"] and abs(f1["Fc"] - f0["Fc"]) < 6 * 5.0
    assert f1["sigma0"] == f0["sigma0"]  # no standard error: not drawn
    for truth, per in doc["ratios"].items():
        assert set(per) == {"pid-ff", "lugre-observer"} and truth in doc["truths"]
    across = doc["across_truths"]["pid-ff"]["diag"]
    assert set(across["per_truth"]) == set(doc["truths"])
    assert across["holds"] in ("better", "worse", "mixed", "same")
    assert [d["truth"] for d in doc["robustness"]["draws"]] == ["base", "diag"]


def test_a_pair_known_not_to_work_is_skipped_with_its_reason(candidates: dict) -> None:
    """Issue 42 item 14: the observer on the Coulomb-viscous baseline is refused before any
    run, each of its runs says why, the console says why, and nothing ranks it."""
    doc = candidates["doc"]
    skipped = [r for r in doc["runs"] if r["controller"] == "lugre-observer"
               and r["model"] == "base"]
    assert len(skipped) == 4
    assert all(r["status"].startswith("skipped: lugre-observer needs a friction model with "
                                      "a bristle state z") and r["rms_error"] is None
               for r in skipped)
    assert doc["across_truths"]["lugre-observer"]["diag"]["holds"] == "not ranked"
    out = candidates["stdout"]
    assert "needs a friction model with a bristle state z" in out
    assert out.index("Conclusion:") == 0


def test_the_console_gives_ratios_with_their_errors(candidates: dict) -> None:
    """Issue 42 item 14: every ratio beside both RMS errors."""
    import re

    cells = re.findall(r"steps ([0-9.e+-]+) \(([0-9.e+-]+) vs ([0-9.e+-]+) um\)",
                       candidates["stdout"])
    assert len(cells) == 4  # pid-ff under each of the 4 truths
    for ratio, mine, theirs in cells:
        assert float(ratio) == pytest.approx(float(mine) / float(theirs), rel=0.02)


def test_every_run_flagged_exits_2_with_the_result_written(tmp_path: Path,
                                                          capsys: pytest.CaptureFixture
                                                          ) -> None:
    """Issue 42 item 2: a plant whose true friction is beyond its force (the piston never
    moves): the JSON is written whole, the conclusion says every run was flagged, the one
    error line points to the JSON, exit 2."""
    base, diag = _files(tmp_path)
    stuck = make_model("coulomb-viscous").with_params(Fc=6e4, B=100.0)
    stuck.save(tmp_path / "stuck.json")
    out = tmp_path / "all.json"
    code, stdout, err = _run(["compensate", "--plant-params", str(AXIS), "--friction",
                              str(tmp_path / "stuck.json"), "--controller-friction",
                              f"{base},{diag}", "--controllers", "pid-ff", "--task", "steps",
                              "--fast", "--samples", "0", "--jobs", "1", "--json", str(out),
                              "--no-progress"], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fcomp: error: compensate: no run could "
                                                   "be ranked"), err
    assert str(out) in lines[0]
    assert stdout.startswith("Conclusion: every run failed, was flagged or skipped")
    doc = json.loads(out.read_text())
    assert all(r["status"].startswith("flagged: never moved") for r in doc["runs"])
    # without --json the line says where the reasons are instead of naming a file
    code, stdout, err = _run(["compensate", "--plant-params", str(AXIS), "--friction",
                              str(tmp_path / "stuck.json"), "--controller-friction",
                              f"{base},{diag}", "--controllers", "pid-ff", "--task", "steps",
                              "--fast", "--samples", "0", "--jobs", "1", "--no-progress"],
                             capsys)
    assert code == 2 and "--json" not in err and "the summary above lists why" in err


@pytest.mark.parametrize("case, words", [
    ("tuning", "the tuning given (pid_bandwidth 400) refused"),
    ("load", "beyond the"),
    ("no-pair", "no controller can be built on two of the models"),
    ("blind", "none uses a friction model"),
    ("not-symbolic", "no controller can be built on two of the models"),
])
def test_a_comparison_that_cannot_be_made_is_refused_before_any_run(
        case: str, words: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Issue 42 item 2: one line, exit 2, nothing written -- not 'exit 0, high'."""
    text = AXIS.read_text()
    plant = tmp_path / "p.toml"
    if case == "tuning":
        text = text.replace("# pid_bandwidth = 25.0 ", "pid_bandwidth = 400.0 ")
    elif case == "load":
        text = (text.replace("mass = 80.0 ", "mass = 80000.0 ")
                .replace('orientation = "horizontal"', 'orientation = "vertical-up"'))
    plant.write_text(text)
    models, controllers = "lugre,nmlgm", "pid-ff"
    if case == "no-pair":
        models, controllers = "coulomb-viscous,stribeck", "lugre-observer"
    elif case == "blind":
        controllers = "pid"
    elif case == "not-symbolic":
        models, controllers = "lugre,nmlgm-hysteresis", "ekf"
    code, out, err = _run(["compensate", "--plant-params", str(plant),
                           "--controller-friction", models, "--controllers", controllers,
                           "--task", "steps", "--fast", "--samples", "0", "--jobs", "1",
                           "--json", str(tmp_path / "o.json"), "--no-progress"], capsys)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], err
    assert not (tmp_path / "o.json").exists()


# ------------------------------------------------------------------ sweep
def test_sweep_names_a_model_file_in_its_json(tmp_path: Path,
                                              capsys: pytest.CaptureFixture) -> None:
    """Issue 42 item 1: ``--controller-friction lugre,MODEL.json`` ended in a TypeError
    (a model object where its name belongs)."""
    model = make_model("nmlgm", params="seed002-type1").with_measurement({"mass": 2.0})
    model.save(tmp_path / "mine.json")
    model.save(tmp_path / "other.json")
    out = tmp_path / "s.json"
    args = ["sweep", "--controllers", "pid-ff", "--grid", "Fc=1", "--controller-friction",
            f"lugre,{tmp_path / 'mine.json'},{tmp_path / 'other.json'}", "--task", "steps",
            "--jobs", "1", "--no-progress"]
    code, _, err = _run([*args, "--json", str(out)], capsys)
    assert code == 0, err
    doc = json.loads(out.read_text())
    assert doc["controller_frictions"] == ["lugre", str(tmp_path / "mine.json"),
                                           str(tmp_path / "other.json")]
    assert [p["controller_friction"] for p in doc["points"]] == doc["controller_frictions"]
    # issue 42 item 2: the grouped warning names the JSON written, or says none was
    assert f"each in full in the JSON ({out})" in err
    code, _, err = _run(args, capsys)
    assert code == 0 and "each in full in the JSON (give --json OUT to keep them)" in err


def test_sweep_draws_only_valid_models() -> None:
    """Issue 42 item 13: log-normal factors of spread 0.5 put Fc above Fs in a quarter of
    the draws; every draw is now a valid controller model, drawn again where not."""
    from controllers.harness import LoopConfig
    from controllers.plant_model import friction_with_mismatch
    from controllers.robustness import Sweep

    model = make_model("nmlgm", params="seed002-type1")
    sweep = Sweep(samples=200, spread=0.5, base=LoopConfig(controller_friction=model))
    draws = sweep.draws()
    assert len(draws) == 200 and draws == sweep.draws()  # reproducible
    for factors, noise in draws:
        friction_with_mismatch(model, factors)  # raises for an invalid model
        assert 0.5 <= noise <= 3.0
    ratio = np.array([f["Fc"] / f["Fs"] for f, _ in draws]) * 120.0 / 260.0
    assert ratio.max() <= 1.0 and ratio.max() > 0.8  # truncated at the constraint, not far
    assert math.isclose(np.median(np.log([f["vs"] for f, _ in draws])), 0.0, abs_tol=0.15)


# ------------------------------------------------------------------ from a diagnosis
def test_a_diagnosis_model_file_gives_its_uncertainty_and_rivals(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture
                                                                 ) -> None:
    """``fcomp diagnose --save-model``: the final fit's standard errors and the diagnosis's
    rivals are in the file; read back, the model carries its standard errors, and the
    candidate truths of ``compensate`` draw from them (the values within a few standard
    errors of the fit's) and run its rivals."""
    from controllers.compensate_inputs import resolve_compared, resolve_plant
    from controllers.truths import candidate_truths
    from fcomp.modelfile import read_model
    from fcomp.synthetic import generate

    rec = tmp_path / "press.csv"
    generate(["pressure-dependence"], duration=12.0, seed=1).measurement.write(rec)
    code, _, err = _run(["diagnose", str(rec), "--friction", "lugre", "--candidates",
                         "pressure-dependence,force-offset,direction-asymmetry",
                         "--save-model", str(tmp_path / "d.json"), "--no-progress"], capsys)
    assert code == 0, err
    doc = json.loads((tmp_path / "d.json").read_text())
    assert doc["description"] == "lugre + pressure-dependence"
    se = doc["stderr"]
    assert {"Fc", "Fs", "kp"} <= set(se) and all(v is None or v >= 0 for v in se.values())
    rivals = doc["source"]["diagnosis"]["rivals"]
    assert isinstance(rivals, list)
    for r in rivals:
        assert r["why"] and read_model(r["model_file"]).model.describe()
    mf = read_model(tmp_path / "d.json")
    assert mf.model.stderr == {k: v for k, v in se.items() if v is not None
                               and k in mf.model.flat_params()}
    warns: list = []
    c = resolve_compared(str(tmp_path / "d.json"), resolve_plant("hydraulic"), warns)
    cast = candidate_truths({"d": c}, draws=3, seed=1)
    assert [t.label for t in cast][:4] == ["d", "d~1", "d~2", "d~3"]
    assert len(cast) == 4 + min(len(rivals), 2)
    for t in cast[1:4]:
        f, f0 = t.model.flat_params(), mf.model.flat_params()
        assert all(abs(f[k] - f0[k]) <= 6 * se[k] for k in f if se.get(k))


def test_a_partly_failed_comparison_ranks_only_what_ran() -> None:
    """Issue 42 item 2: one run failed among ranked ones: its pair gets no ratio, under
    that truth the pair is not counted (not a ratio of a failure), the recommendation rests
    on the pairs that ran, and the conclusion says which runs were not ranked and why."""
    from controllers.compensate import across_truths, ratios
    from controllers.conclusions import of_compensation

    def run(truth: str, c: str, m: str, rms: float | None, status: str = "ok") -> dict:
        from controllers.compensate import RATIO_ERRORS

        return {"truth": truth, "controller": c, "model": m, "task": "steps",
                "status": status, **dict.fromkeys(RATIO_ERRORS, rms)}

    runs = {"base": [run("base", "ekf", "base", 2e-5), run("base", "ekf", "diag", 1e-5),
                     run("base", "pid-ff", "base", 4e-5),
                     run("base", "pid-ff", "diag", None, "failed: solver diverged")],
            "diag": [run("diag", "ekf", "base", 3e-5), run("diag", "ekf", "diag", 2.4e-5),
                     run("diag", "pid-ff", "base", 5e-5), run("diag", "pid-ff", "diag", 1e-5)]}
    per_truth = {t: ratios(rs, ["base", "diag"]) for t, rs in runs.items()}
    assert per_truth["base"]["pid-ff"]["steps"]["diag"]["rms_error"] is None
    assert per_truth["base"]["ekf"]["steps"]["diag"]["rms_error"] == pytest.approx(0.5)
    across = across_truths(per_truth, ["ekf", "pid-ff"], ["base", "diag"], ["steps"])
    assert across["ekf"]["diag"]["holds"] == "better"
    assert across["ekf"]["diag"]["best"] == pytest.approx(0.5)
    assert across["ekf"]["diag"]["worst"] == pytest.approx(0.8)
    ff = across["pid-ff"]["diag"]
    assert ff["holds"] == "partly ranked" and ff["per_truth"] == {"base": None, "diag": 0.2}
    doc = {"baseline": "base", "models": {"base": "", "diag": ""}, "mode": "candidates",
           "controllers": ["ekf", "pid-ff"], "uses_friction": {"ekf": True, "pid-ff": True},
           "tasks": ["steps"], "truths": {"base": {"equals": "base"},
                                          "diag": {"equals": "diag"}},
           "runs": runs["base"] + runs["diag"], "across_truths": across,
           "robustness": {"controllers": {}}, "warnings": []}
    c = of_compensation(doc)
    # pid-ff's 0.2 under one truth does not outrank ekf's 0.5-0.8 under both
    assert c.finding.startswith("under every one of the 2 candidate truths, diag instead of "
                                "base lowers the RMS tracking error of ekf: median-task "
                                "ratio 0.50-0.80"), c.finding
    assert c.confidence != "high"
    assert "pid-ff with diag (1 of 2)" in " ".join(c.reasons)
    assert ("1 of 8 runs not ranked: pid-ff with diag (failed: solver diverged; 1 run)"
            in c.reasons), c.reasons


def test_sweep_samples_are_bounded(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """Issue 42 item 10 (``--samples 1e8`` unbounded, as compensate's): one line, exit 2,
    before any run and nothing written."""
    from controllers.robustness import MAX_SAMPLES

    out = tmp_path / "s.json"
    code, stdout, err = _run(["sweep", "--plant", "hydraulic", "--controllers", "pid",
                              "--samples", str(10 * MAX_SAMPLES), "--json", str(out),
                              "--no-progress"], capsys)
    assert code == 2 and stdout == "" and not out.exists()
    lines = err.strip().splitlines()
    assert len(lines) == 1 and f"at most {MAX_SAMPLES}" in lines[0], err
