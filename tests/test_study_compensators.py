"""Study ``compensators``: the summary contract, the verdict, the report (shared fast run)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from helpers.browser import study_summary

from studies import STUDIES

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("site")]  # builds the study site or runs long diagnoses

FIELDS = ("plant", "controller", "task", "rms_error", "max_error", "steady_state_error",
          "solve_time_median", "solve_time_max")


@pytest.fixture(scope="module")
def summary() -> dict:
    return study_summary("compensators")


def test_registered() -> None:
    assert "compensators" in STUDIES


def test_summary_has_every_plant_controller_task(summary: dict) -> None:
    rows = summary["results"]
    combos = {(r["plant"], r["controller"], r["task"]) for r in rows}
    assert len(rows) == len(combos) == 2 * 5 * 4
    for r in rows:
        for k in FIELDS:
            assert k in r, k
        assert r["status"] == "ok", r
        # errors in metres: a servo tracking within millimetres
        assert 0 < r["rms_error"] <= r["max_error"] < 0.01
        assert 0 <= r["steady_state_error"] < 0.01
        # step times in seconds
        assert 0 < r["solve_time_median"] <= r["solve_time_max"] < 5.0
        assert r["fallbacks"] == 0


def test_best_compensator_halves_pid_error_at_low_velocity(summary: dict) -> None:
    v = summary["verdict"]
    assert set(v) == {f"{p}/{t}" for p in ("hydraulic", "pneumatic")
                      for t in ("slow-sine", "low-velocity-ramp")}
    for key, d in v.items():
        assert d["halved"] and d["ratio"] <= 0.5, key
        rows = {r["controller"]: r["rms_error"] for r in summary["results"]
                if f"{r['plant']}/{r['task']}" == key}
        assert rows[d["best"]] == min(v for c, v in rows.items() if c != "pid")
        assert math.isclose(d["ratio"], rows[d["best"]] / rows["pid"], rel_tol=1e-12)


def test_robustness_distributions_per_compensator(summary: dict) -> None:
    for plant in ("hydraulic", "pneumatic"):
        dist = summary["robustness"][plant]
        assert set(dist) == {"pid", "pid-ff", "lugre-observer", "ekf", "mpc"}
        for d in dist.values():
            vals = d["rms_error"]["values"]
            assert len(vals) + d["failed"] == d["runs"] >= 3
            if vals:
                assert min(vals) <= d["rms_error"]["median"] <= max(vals)


def test_report_has_tables_figures_and_timing(summary: dict, site: Path) -> None:
    html = (site / "compensators" / "report.html").read_text(encoding="utf-8")
    for text in ("Ranked results", "Friction estimate against the true friction",
                 "Robustness", "Compute time"):
        assert text in html
    figs = summary["meta"]["figures"]
    assert {"fig-tracking-hydraulic.png", "fig-friction-pneumatic.png",
            "fig-robustness.png"} <= set(figs)
    t = summary["mpc_timing"]
    assert {"hydraulic/mpc", "pneumatic/mpc", "hydraulic/ekf"} <= set(t)


def test_each_configuration_is_tuned_once_with_the_same_runs(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The study's runs carry their configuration's tuning, derived once per configuration
    (:func:`controllers.robustness.with_tunings`; every worker used to derive it again, most
    of a fast run's time); the closed loop is the same as with the tuning derived where it
    runs."""
    from controllers import robustness
    from controllers.harness import LoopConfig
    from controllers.robustness import GivenTuning, Job, run_job, with_tunings

    calls: list[LoopConfig] = []
    derive = robustness.derived_tuning
    monkeypatch.setattr(robustness, "derived_tuning",
                        lambda cfg: calls.append(cfg) or derive(cfg))
    a = LoopConfig(plant="hydraulic", fast=True)
    b = LoopConfig(plant="hydraulic", fast=True, noise=2.0)
    jobs = [Job("pid", "steps", a), Job("pid-ff", "steps", a), Job("pid", "steps", b)]
    tuned = with_tunings(jobs, workers=1)
    assert calls == [a, b]
    assert [j.controller for j in tuned] == ["pid", "pid-ff", "pid"]
    assert all(isinstance(j.config.tuning, GivenTuning) for j in tuned)
    assert tuned[0].config.tuning.tuning is tuned[1].config.tuning.tuning  # type: ignore[union-attr]
    for plain, given in zip(jobs, tuned, strict=True):
        m0, m1 = run_job(plain)["metrics"], run_job(given)["metrics"]
        for k in ("rms_error", "max_error", "steady_state_error"):
            assert m0[k] == m1[k], k


def test_the_feedback_tuning_is_shared_by_friction_draws() -> None:
    """Rules 1-3 of the tuning (the PID part, seconds to derive) do not depend on the
    controller's friction levels: their cache key leaves them out, so the Monte Carlo draws
    (the controllers' friction times random factors) derive it once per plant -- and the
    tuning is the one derived afresh."""
    import controllers.plant_model as pm
    import controllers.tuning as tu
    from controllers.harness import LoopConfig, control_model

    a = LoopConfig(plant="hydraulic", fast=True)
    b = LoopConfig(plant="hydraulic", fast=True, mismatch={"Fc": 1.7, "sigma0": 0.6})
    assert control_model(a).plant_key() == control_model(b).plant_key()
    fresh = []
    for cfg in (a, b):
        tu._PID_PARTS.clear()
        pm._TUNINGS.clear()
        fresh.append(control_model(cfg).tuning)
    tu._PID_PARTS.clear()
    pm._TUNINGS.clear()
    assert [control_model(cfg).tuning for cfg in (a, b)] == fresh
    assert len(tu._PID_PARTS) == 1
