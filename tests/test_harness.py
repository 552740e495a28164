"""Closed-loop harness and robustness sweep: sampling, sensors, mismatch, replay, parallel runs.

The harness's recorded trajectory is replayed with an independent
integrator (``scipy.integrate.solve_ivp``, Radau, tight tolerance) under
the recorded piecewise-constant valve commands; the process pool and a
Dask ``LocalCluster`` must give exactly the sequential results.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from controllers.harness import DEFAULT_MISMATCH, LoopConfig, build_loop, run_closed_loop
from controllers.plant_model import equilibrium
from controllers.robustness import (
    Job,
    StoppingRule,
    Sweep,
    distributions,
    median_interval,
    run_jobs,
    run_sequential,
)
from fcomp.errors import FcompError, UnknownNameError

CFG = LoopConfig(plant="hydraulic", fast=True)


@pytest.fixture(scope="module")
def pid_run():
    return run_closed_loop("pid", "low-velocity-ramp", CFG)


def test_controller_model_is_its_own_object_with_the_mismatch() -> None:
    plant, model, ctrl = build_loop("lugre-observer", CFG)
    assert ctrl.model is model and model.plant is not plant
    assert model.friction is not plant.friction
    true, mine = plant.friction.flat_params(), model.friction.flat_params()
    for name, factor in DEFAULT_MISMATCH.items():
        if name in true:
            assert mine[name] == pytest.approx(true[name] * factor)


def test_run_records_every_sample_at_the_controller_rate(pid_run) -> None:
    r = pid_run
    assert np.allclose(np.diff(r.t), 1e-3)                  # 1 kHz hydraulic loop
    assert r.t[-1] == pytest.approx(1.5)
    assert r.x.shape == r.u.shape == r.F_true.shape == r.t.shape
    q = 1e-6                                                 # position quantum (m)
    assert np.allclose(np.round(r.y[:, 0] / q) * q, r.y[:, 0], atol=1e-12)
    assert np.abs(r.y[:, 0] - r.x).max() < 1e-5              # noise + quantisation only
    m = r.metrics
    assert 0 < m.rms_error < m.max_error < 1e-3
    assert m.steps == r.t.size and m.fallbacks == 0
    assert np.all(np.abs(r.u) <= 0.010 + 1e-15)
    assert r.solve_cpu.shape == r.solve_times.shape and np.all(r.solve_cpu >= 0)
    assert 0 < m.solve_time_cpu_median <= m.solve_time_cpu_max


def test_recorded_trajectory_replays_with_an_independent_integrator(pid_run) -> None:
    r = pid_run
    plant, _, _ = build_loop("pid", CFG)
    f = plant.casadi_functions()["rhs"]
    x0, _ = equilibrium(plant, 0.15)
    sc = plant.ode_model().scales
    x = x0.copy()
    n = 300                                                  # the first 0.3 s
    xs = [x[0]]
    for k in range(n):
        u = r.u[k]
        sol = solve_ivp(lambda _t, s, u=u: np.asarray(f(s, u)).ravel(), (0, 1e-3), x,
                        method="Radau", rtol=1e-9, atol=1e-10 * sc)
        x = sol.y[:, -1]
        xs.append(x[0])
    assert np.max(np.abs(np.array(xs) - r.x[: n + 1])) < 2e-7   # m


def test_noise_is_seeded() -> None:
    a = run_closed_loop("pid", "steps", LoopConfig(fast=True, seed=3))
    b = run_closed_loop("pid", "steps", LoopConfig(fast=True, seed=3))
    c = run_closed_loop("pid", "steps", LoopConfig(fast=True, seed=4))
    assert np.array_equal(a.y, b.y) and np.array_equal(a.x, b.x)
    assert not np.array_equal(a.y, c.y)


def test_bad_names_are_one_line_errors() -> None:
    with pytest.raises(UnknownNameError, match="unknown controller"):
        run_closed_loop("pi", "steps", CFG)
    with pytest.raises(UnknownNameError, match="unknown task"):
        run_closed_loop("pid", "stairs", CFG)
    with pytest.raises(FcompError, match="closed-loop control is set up for plants"):
        run_closed_loop("pid", "steps", LoopConfig(plant="motion"))


# ----------------------------------------------------------------- robustness
def test_sweep_draws_are_reproducible_and_shared_by_the_controllers() -> None:
    sw = Sweep(samples=4, controllers=("pid", "ekf"), spread=0.3, noise=(0.5, 2.0))
    assert sw.draws() == Sweep(samples=4, controllers=("pid",), noise=(0.5, 2.0)).draws()
    jobs = sw.jobs()
    assert len(jobs) == 8
    assert jobs[0].config == jobs[1].config                  # common random numbers
    factors = np.array([list(m.values()) for m, _ in sw.draws()])
    assert np.all(factors > 0) and all(0.5 <= n <= 2.0 for _, n in sw.draws())
    with pytest.raises(FcompError, match="samples"):
        Sweep(samples=0)


def test_median_interval_is_the_binomial_order_statistic_interval() -> None:
    v = np.arange(1.0, 21.0)                    # n = 20: (x_(6), x_(15)) covers 95.9 %
    assert median_interval(v[::-1], 0.95) == (6.0, 15.0)
    assert median_interval(v[:6], 0.95) == (1.0, 6.0)      # 1 - 2/64 = 96.9 %
    assert median_interval(v[:5], 0.95) is None            # 1 - 2/32 = 93.8 % < 95 %


def _fake_runs(effects: dict[str, float]):
    """A ``run`` for :func:`run_sequential` without simulations: RMS error of controller ``c``
    on draw ``i`` is pid's (1 + i % 3) times ``effects[c]`` times a draw-dependent wobble."""
    calls: list[list[Job]] = []

    def run(jobs: list[Job]) -> list[dict]:
        calls.append(jobs)
        out = []
        for j in jobs:
            i = j.sample
            base = 1.0 + i % 3
            wobble = 1.0 if j.controller == "pid" else 1.0 + 0.8 * np.sin(1.7 * i + len(j.controller))
            out.append({"controller": j.controller, "sample": i, "status": "ok",
                        "metrics": {"rms_error": base * effects[j.controller] * wobble,
                                    "max_error": 1.0, "steady_state_error": 0.0}})
        return out

    return run, calls


def test_sequential_sweep_stops_each_compensator_once_decided() -> None:
    effects = {"pid": 1.0, "ekf": 0.2, "pid-ff": 1.0}   # ekf clearly better; pid-ff a toss-up
    sw = Sweep(plant="hydraulic", controllers=("pid", "ekf", "pid-ff"), samples=99)
    rule = StoppingRule(min_draws=8, max_draws=16, batch=4)
    assert rule.looks == 3 and rule.level == pytest.approx(1 - 0.05 / 3)
    run, calls = _fake_runs(effects)
    res = run_sequential({"h": sw}, rule, run)["h"]
    assert [len(c) for c in calls] == [24, 8, 8]          # ekf decided at the first look
    assert {j.controller for j in calls[1]} == {"pid", "pid-ff"}
    assert res["draws"] == 16 and res["stopped"] == "max-draws"
    d = res["decisions"]
    assert d["ekf"]["verdict"] == "better" and d["ekf"]["paired_draws"] == 8
    assert d["ekf"]["interval"][1] < 1.0
    assert d["pid-ff"]["verdict"] == "undecided" and d["pid-ff"]["paired_draws"] == 16
    lo, hi = d["pid-ff"]["interval"]
    assert lo < 1.0 < hi
    # the draws are those of the fixed-count sweep: common random numbers, reproducible
    assert [j.config for j in calls[0][::3]] == [j.config for j in sw.jobs(range(8), ["pid"])]
    dist = distributions(res["results"])
    assert dist["pid"]["runs"] == 16 and dist["ekf"]["runs"] == 8


def test_stopping_rule_refuses_nonsense() -> None:
    with pytest.raises(FcompError, match="confidence"):
        StoppingRule(confidence=1.0)
    with pytest.raises(FcompError, match="min_draws"):
        StoppingRule(min_draws=30, max_draws=20)
    with pytest.raises(FcompError, match="reference"):
        run_sequential({"h": Sweep(controllers=("ekf",))}, StoppingRule(), lambda jobs: [])


def _physics(results: list[dict]) -> list[dict]:
    """The metrics without the wall-clock step times (which differ from run to run)."""
    return [{k: v for k, v in r["metrics"].items() if not k.startswith("solve_time")}
            for r in results]


JOBS = [Job("pid", "low-velocity-ramp", LoopConfig(fast=True, seed=s)) for s in (1, 2)]


@pytest.fixture(scope="module")
def sequential():
    return run_jobs(JOBS, workers=1)


def test_process_pool_gives_the_sequential_results(sequential) -> None:
    pooled = run_jobs(JOBS, workers=2)
    assert _physics(pooled) == _physics(sequential)
    assert all(r["status"] == "ok" for r in pooled)
    d = distributions(pooled)
    assert d["pid"]["runs"] == 2 and d["pid"]["failed"] == 0
    vals = d["pid"]["rms_error"]["values"]
    assert d["pid"]["rms_error"]["median"] == pytest.approx(np.median(vals))


@pytest.mark.slow
def test_dask_local_cluster_gives_the_sequential_results(sequential) -> None:
    import distributed  # part of the test extra: a missing package fails, never skips
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:
        res = run_jobs(JOBS, scheduler=cluster.scheduler_address)
    assert _physics(res) == _physics(sequential)


@pytest.mark.slow
def test_unreachable_scheduler_is_a_clear_error() -> None:
    with pytest.raises(FcompError, match="cannot connect to the Dask scheduler"):
        run_jobs(JOBS[:1], scheduler="tcp://127.0.0.1:9")
