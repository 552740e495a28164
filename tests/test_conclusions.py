"""The conclusion every result opens with (fcomp.conclusions), judged on hand-made documents.

Each flag of issue 27 is a case: an "explained" model whose parameters the
record does not determine, a held-out RMS below the noise floor, an answer
that depends on the baseline, a fit at a bound; a clean result is sure and says
what to do with it. The grouped warning lines count and name what they group.
"""

from __future__ import annotations

from fcomp.conclusions import grouped_warnings, of_comparison, of_diagnosis, of_fit


def _w(code: str, parameter: str | None, message: str) -> dict:
    return {"code": code, "parameter": parameter, "message": message}


CLEAN = {"baseline": "lugre", "model": "lugre + pressure-dependence",
         "added": ["pressure-dependence"], "rms_baseline": 1.2, "rms_final": 0.41,
         "noise_floor": 0.40, "verdict": "explained", "ties": [], "warnings": [],
         "baseline_dependent": False, "other_baseline": None, "residual_features": []}


def test_a_clean_diagnosis_is_sure_and_says_how_to_use_the_model() -> None:
    c = of_diagnosis(CLEAN)
    assert c.confidence == "high" and not c.reasons
    assert c.finding.startswith("lugre misses pressure-dependence; with them the held-out RMS "
                                "falls 1.2 N -> 0.41 N")
    assert any("--save-model" in s for s in c.next_steps)
    assert c.lines()[:2] == [f"Conclusion: {c.finding}", "How sure: high"]


def test_explained_with_undetermined_parameters_is_flagged() -> None:
    doc = {**CLEAN, "warnings": [
        _w("interval-crosses-zero", "Fc", "final model lugre: Fc = 1 N must be positive, but "
           "its 95 % interval [-10.2, 14.6] reaches zero; to determine it: slow runs"),
        _w("at-bound", "B", "baseline lugre: B = 0 is at its lower bound")]}
    c = of_diagnosis(doc)
    assert c.confidence == "medium"
    assert any(r.startswith("called explained, but the final fit is not to be trusted") and
               "Fc not established" in r for r in c.reasons)
    assert not any("B " in r for r in c.reasons)  # the baseline's flags do not count
    assert c.next_steps[0] == "record slow runs (it would determine Fc)"
    assert not any("--save-model" in s for s in c.next_steps[:1])


def test_heldout_rms_below_the_noise_floor_is_flagged() -> None:
    c = of_diagnosis({**CLEAN, "rms_final": 0.23, "noise_floor": 0.417})
    assert c.confidence == "medium"
    assert any("below the noise floor 0.417 N" in r and "over-fitting" in r for r in c.reasons)
    assert of_diagnosis({**CLEAN, "rms_final": 0.38, "noise_floor": 0.417}).confidence == "high"


def test_an_answer_that_depends_on_the_baseline_is_low() -> None:
    c = of_diagnosis({**CLEAN, "baseline_dependent": True,
                      "other_baseline": {"baseline": "coulomb-viscous", "added": ["stribeck"]}})
    assert c.confidence == "low"
    assert c.reasons[0] == "the answer depends on the baseline (from coulomb-viscous: stribeck)"


def test_unexplained_structure_says_what_the_residual_follows() -> None:
    c = of_diagnosis({**CLEAN, "verdict": "unexplained-structure", "rms_final": 1.1,
                      "residual_features": [{"feature": "x", "strength": 0.8}]})
    assert "leaves structure no catalogue effect explains" in c.finding
    assert c.finding.endswith("the residual follows x")
    assert any("docs/effects.md" in s for s in c.next_steps)


def test_fit_at_a_bound_is_low_and_names_the_experiment() -> None:
    doc = {"model": "lugre", "n_samples": 7834, "rms": 0.749,
           "params": {"Fc": 0.44, "n": 10.0, "mass": 1.87}, "not_identifiable": [],
           "warnings": [_w("at-bound", "n", "n = 10 is at its upper bound 10: ...; to "
                           "determine it: slow constant-speed runs (0.1-10 vs) in both "
                           "directions"),
                        _w("mass-implausible", "mass", "the fitted mass 1.87 kg ...")]}
    c = of_fit(doc)
    assert c.finding == ("lugre fitted over 7834 samples: RMS force error 0.749 N; 2 of 3 "
                         "parameters determined")
    assert c.confidence == "low"
    assert c.next_steps[:2] == ("record slow constant-speed runs (0.1-10 vs) in both directions "
                                "(it would determine n)",
                                "give the moving mass (rig.mass in the sidecar, or --mass)")


def test_comparison_with_default_values_is_not_trusted() -> None:
    doc = {"model": "lugre", "description": "lugre", "rms": 3.0, "noise_floor": 0.4,
           "regimes": {"sliding": {"rms": 1.0, "n": 900}, "reversal": {"rms": 5.0, "n": 40},
                       "all": {"rms": 3.0, "n": 940}},
           "residual_features": [{"feature": "v", "strength": 0.7}],
           "warnings": [_w("default-params", "params", "defaults")]}
    c = of_comparison(doc)
    assert c.confidence == "low"
    assert "7.5 times the noise floor 0.4 N" in c.finding and "reversal (5 N)" in c.finding
    assert c.next_steps[0].startswith("fit it first")
    at_noise = of_comparison({**doc, "rms": 0.42, "warnings": []})
    assert at_noise.confidence == "high" and "at the noise" in at_noise.finding
    assert not at_noise.next_steps


def test_warnings_grouped_and_counted() -> None:
    items = [_w("at-bound", "B", "baseline cv: B = 5e-13 Ns/m is at its lower bound"),
             _w("at-bound", "mass", "baseline cv: mass = 5e-13 kg is at its lower bound"),
             _w("at-bound", "mass", "final model cv + force-offset: mass = 0 kg at bound"),
             _w("not-converged", None, "final model cv: the fit did not converge")]
    lines = grouped_warnings(items)
    assert lines[0].startswith("3 x at-bound: B, mass (baseline); mass (final model) -- ")
    assert lines[1] == "final model cv: the fit did not converge"  # alone: in full
    assert lines[2] == ('4 warnings in all, each in full in the JSON\'s "warnings" '
                        "(--json OUT)")
    assert grouped_warnings(items[3:]) == ["final model cv: the fit did not converge"]


def test_compensation_says_what_the_better_model_buys() -> None:
    """A model better under every truth: recommended, with the range of its median-task
    ratios; the robustness draws that disagree lower the confidence."""
    from controllers.conclusions import of_compensation

    across = {"lugre-observer": {"diag": {"per_truth": {"base": 0.4, "diag": 0.7},
                                          "holds": "better", "best": 0.4, "worst": 0.7}},
              "pid": {"diag": {"per_truth": {"base": 1.0, "diag": 1.0}, "holds": "same",
                               "best": 1.0, "worst": 1.0}}}
    doc = {"baseline": "base", "models": {"base": "b.json", "diag": "d.json"},
           "mode": "candidates", "truths": {"base": {"equals": "base"},
                                            "diag": {"equals": "diag"}},
           "controllers": ["pid", "lugre-observer"],
           "uses_friction": {"pid": False, "lugre-observer": True},
           "tasks": ["slow-sine", "steps"], "across_truths": across,
           "runs": [{"status": "ok"}] * 8,
           "robustness": {"controllers": {"lugre-observer": {"ratio": {"diag": {
               "better": 0.5}}}}}, "warnings": []}
    c = of_compensation(doc)
    assert c.finding == ("under every one of the 2 candidate truths, diag instead of base "
                         "lowers the RMS tracking error of lugre-observer: median-task ratio "
                         "0.40-0.70; pid uses no friction model")
    assert c.confidence == "medium"
    assert c.reasons == ("lugre-observer with diag is better in only 50 % of the robustness "
                         "draws",)
    assert c.next_steps[0].startswith("deploy it: fcomp export lugre-observer ")


def test_sweep_names_the_most_robust_controller_and_overlaps() -> None:
    from controllers.conclusions import of_sweep

    def dist(med: float, p10: float, p90: float) -> dict:
        return {"rms_error": {"median": med, "p10": p10, "p90": p90}}

    doc = {"mode": "monte-carlo", "samples": 20, "runs": [{"status": "ok"}] * 40,
           "distributions": {"pid": dist(3e-5, 2e-5, 5e-5), "mpc": dist(2e-5, 1e-5, 2.5e-5)}}
    c = of_sweep(doc)
    assert c.finding.startswith("mpc tracks best over 20 draws of friction mismatch: median "
                                "RMS error 20 um (10-90 %: 10-25 um), then pid (30 um)")
    assert c.confidence == "medium" and "overlap" in c.reasons[0]
    apart = {**doc, "distributions": {"pid": dist(3e-5, 2.8e-5, 5e-5),
                                      "mpc": dist(2e-5, 1e-5, 2.5e-5)}}
    assert of_sweep(apart).confidence == "high"


def test_reprs_summarise_and_never_dump_arrays() -> None:
    import numpy as np

    from fcomp import make_model
    from fcomp.synthetic import generate
    from fcomp.trajectory import friction_along_motion

    rec = generate(["force-offset"], duration=2.0, seed=1)
    text = repr(rec)
    assert text.startswith("<SyntheticRecord 'synthetic-force-offset': 1000 samples, base ")
    assert "array" not in text and len(text) < 200
    t = np.linspace(0.0, 1.0, 5000)
    run = friction_along_motion(make_model("lugre"), t, 0.01 * np.sin(6 * t))
    assert repr(run).startswith("<FrictionRun 5000 samples, t 0..1 s, states z, |F| up to ")
    assert len(repr(run)) < 120
    page = rec.measurement._repr_html_()
    assert "<table>" in page and "data:image/png;base64," in page
    assert "<td style='text-align:left'>F</td><td style='text-align:right'>N</td>" in page


def test_a_noise_free_record_has_nothing_below_its_floor() -> None:
    c = of_diagnosis({**CLEAN, "rms_final": 0.0, "noise_floor": 4e-9})
    assert c.confidence == "high"


def test_the_verdicts_reasons_are_split_at_top_level_only() -> None:
    from fcomp.cli.diagnose import _clauses

    assert _clauses("structure: x (strength 0.30 >= 0.15; it carries 0.28 N); at a bound") == [
        "structure: x (strength 0.30 >= 0.15; it carries 0.28 N)", "at a bound"]


def test_grouped_warnings_without_a_parameter_name_what_they_concern() -> None:
    items = [_w("heldout-coverage", None, "speed slow: 28 held-out of 57 usable samples"),
             _w("heldout-coverage", None, "reversal: 3 held-out of 9 usable samples"),
             _w("not-converged", None, "final model cv: the fit did not converge: ..."),
             _w("not-converged", None, "baseline cv: the fit did not converge: ...")]
    lines = grouped_warnings(items)
    assert lines[0].startswith("2 x heldout-coverage: speed slow, reversal -- ")
    assert lines[1].startswith("2 x not-converged: final model, baseline -- ")
