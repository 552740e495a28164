"""Identification (fcomp.identification): exact sensitivities, honest standard errors, and
recovery of known parameters from data simulated *independently* of the package.

The records are generated with the plain equations of ``tests/helpers/reference_lugre.py``
(written from models.md, importing nothing from fcomp) integrated by SciPy's LSODA
at rtol 1e-8 along a smooth velocity; the package then fits its own models to them.
Recovery is checked against the stated uncertainty (|estimate - true| < 3 stderr)
and a relative error bound. SI units throughout.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.reference_lugre import FilmLuGreRef, LuGreRef, coulomb_viscous, stribeck_map
from scipy.integrate import solve_ivp

from fcomp.effects import make_effect
from fcomp.errors import ConvergenceError, FcompError
from fcomp.identification import FrictionFit, fit_data, steady_state_points
from fcomp.identification.problem import compressed
from fcomp.identification.sensitivity import SensitivityLoop
from fcomp.identification.uncertainty import determined_mask, estimate
from fcomp.measurement import Measurement
from fcomp.models import make_model
from fcomp.trajectory import friction_along_motion, prepare_signals

RNG = np.random.default_rng(20240611)


def velocity(t: np.ndarray | float) -> np.ndarray | float:
    """A rich two-tone velocity (m/s): reversals at varying speed and acceleration."""
    return 0.05 * np.sin(2 * np.pi * 0.5 * t) + 0.02 * np.sin(2 * np.pi * 1.3 * t)


def acceleration(t: np.ndarray) -> np.ndarray:
    return (0.05 * 2 * np.pi * 0.5 * np.cos(2 * np.pi * 0.5 * t)
            + 0.02 * 2 * np.pi * 1.3 * np.cos(2 * np.pi * 1.3 * t))


def reference_record(p: LuGreRef | FilmLuGreRef, duration: float, noise: float,
                     rate: float = 1000.0) -> tuple[Measurement, np.ndarray]:
    """Friction of the reference model along :func:`velocity` (LSODA), plus white noise."""
    t = np.arange(int(round(duration * rate)) + 1) / rate
    v, a = velocity(t), acceleration(t)
    vf = lambda tt: float(velocity(tt))  # noqa: E731
    if isinstance(p, LuGreRef):
        sol = solve_ivp(lambda tt, y: [p.zdot(y[0], vf(tt))], (0, t[-1]), [0.0],
                        method="LSODA", t_eval=t, rtol=1e-8, atol=1e-13)
        F = np.array([p.friction(z, vk) for z, vk in zip(sol.y[0], v, strict=True)])
    else:
        side = lambda tt: 1.0 if vf(tt) >= 0 else -1.0  # noqa: E731
        sol = solve_ivp(lambda tt, y: list(p.rates(y[0], y[1], vf(tt), side(tt))), (0, t[-1]),
                        [0.0, 0.0], method="LSODA", t_eval=t, rtol=1e-8, atol=[1e-13, 1e-10])
        F = np.array([p.friction(z, h, vk, ak, 1.0 if vk >= 0 else -1.0)
                      for z, h, vk, ak in zip(sol.y[0], sol.y[1], v, a, strict=True)])
    assert sol.success
    x = 0.05 / (2 * np.pi * 0.5) * (1 - np.cos(2 * np.pi * 0.5 * t)) + 0.02 / (
        2 * np.pi * 1.3) * (1 - np.cos(2 * np.pi * 1.3 * t))
    y = F + noise * RNG.standard_normal(t.size)
    return Measurement({"t": t, "x": x, "v": v, "a": a, "F": y}, {"name": "reference"}), F


def assert_recovered(fit: FrictionFit, truth: dict[str, float], rel: float,
                     weak: tuple[str, ...] = ()) -> None:
    """Every estimate within 3 standard errors of the truth; within ``rel`` of it, except
    the ``weak`` ones (weakly determined by the record), which need only be determined to
    better than 50 %."""
    for name, true in truth.items():
        est, se = fit.params_[name], fit.stderr_[name]
        assert math.isfinite(se) and se > 0, name
        assert abs(est - true) < 3 * se + 1e-12, (name, est, true, se)
        bound = 0.5 if name in weak else rel
        assert abs(est - true) <= bound * abs(true), (name, est, true)
        assert name not in weak or se < 0.5 * abs(true), (name, se)
        lo, hi = fit.ci_[name]
        assert lo < est < hi


# ------------------------------------------------------------------- machinery
def test_sensitivities_equal_central_differences_of_the_simulation() -> None:
    model = make_model("nmlgm", params="seed000-cylinder1").with_params(T=0.01)
    t = np.arange(3001) / 1000.0
    v = velocity(t)
    free = [n for n in model.flat_params() if n != "v_eps"]
    F, G = SensitivityLoop(model, free)(prepare_signals(t, v), {})
    base = friction_along_motion(model, t, v).F
    np.testing.assert_allclose(F, base, rtol=0, atol=1e-12)
    flat = model.flat_params()
    for j, name in enumerate(free):
        h = 1e-6 * abs(flat[name]) if flat[name] else 1e-8
        up = friction_along_motion(model, t, v, values={name: flat[name] + h}).F
        down = friction_along_motion(model, t, v, values={name: flat[name] - h}).F
        fd = (up - down) / (2 * h)
        scale = max(np.abs(fd).max(), 1e-9)
        assert np.abs(G[:, j] - fd).max() <= 1e-4 * scale, name


def test_kept_sensitivities_stay_within_their_byte_budget(monkeypatch) -> None:
    """The reuse store of :class:`SensitivityLoop` results keeps a running byte count
    that equals the bytes it holds and never exceeds its budget."""
    from fcomp.identification import sensitivity as sens

    monkeypatch.setattr(sens, "_KEPT", {})
    monkeypatch.setattr(sens, "_KEPT_BYTES", [0])
    monkeypatch.setattr(sens, "KEEP_BYTES", 10 * 8 * 101)
    record = (object(),)
    for k in range(25):
        sens._keep((k,), record, np.zeros(100), np.zeros((100, 1 + k % 3)))
        held = sum(e[1].nbytes + e[2].nbytes for e in sens._KEPT.values())
        assert sens._KEPT_BYTES[0] == held <= sens.KEEP_BYTES
    assert sens._kept((24,), record) is not None and sens._kept((0,), record) is None
    sens._keep((24,), record, np.ones(100), np.ones((100, 1)))  # the same key again: replaced
    assert sens._kept((24,), record)[0][0] == 1.0
    assert sens._KEPT_BYTES[0] == sum(e[1].nbytes + e[2].nbytes for e in sens._KEPT.values())


def test_successive_halving_races_the_starts_and_keeps_the_best_valley() -> None:
    """best_start with ``resume``: every start a third of the budget, the better half (at
    least two) the rest from where they stopped; the deepest valley wins; fewer
    evaluations than every start's full budget. A toy solver: each evaluation halves
    the distance to the start's valley floor (valleys at -2, 1 and 4, depths 3, 0, 1)."""
    from fcomp.identification.problem import Solution
    from fcomp.identification.records import best_start

    floors = {-2.0: 3.0, 1.0: 0.0, 4.0: 1.0}

    def solve(st: dict[str, float], k: int) -> tuple[Solution, int]:
        x = st["x"]
        m = min(floors, key=lambda c: abs(c - x))
        x = m + (x - m) * 0.5**k
        cost = floors[m] + (x - m) ** 2
        return Solution(np.array([x]), np.array([math.sqrt(cost)]), np.zeros((1, 1)), True,
                        "", k, (False,)), k

    def resume(st: dict[str, float], sol: Solution) -> dict[str, float]:
        return {"x": float(sol.theta[0])}

    # the start in the deepest valley begins farthest from its floor
    starts = [{"x": -2.4}, {"x": 2.4}, {"x": 4.3}, {"x": -1.7}, {"x": 3.8}]
    budget = 20
    cost, sol, st, nfev = best_start(starts, solve, budget, "toy", resume=resume)
    assert abs(sol.theta[0] - 1.0) < 1e-4 and cost < 1e-8
    assert st["x"] == pytest.approx(1.0 + 1.4 * 0.5 ** (budget // 3))  # where it resumed
    assert nfev == 5 * (budget // 3) + 3 * (budget - budget // 3) < 5 * budget
    # two starts: no race, each gets the whole budget
    cost2, sol2, st2, nfev2 = best_start(starts[:2], solve, budget, "toy", resume=resume)
    assert nfev2 == 2 * budget and st2 is starts[1] and cost2 < 1e-8


def test_maxwell_slip_sensitivities_equal_central_differences() -> None:
    """The clipped element deflections are differentiated exactly (piecewise, away from kinks)."""
    model = make_model("lugre", params="seed000-cylinder1").with_effects(make_effect(
        "nonlocal-memory", {"ms_share": 0.7, "ms_dmax": 3e-4, "ms_spread": 8.0,
                            "ms_shape": 0.4}, form="maxwell-slip"))
    t = np.arange(3001) / 1000.0
    v = velocity(t)
    free = ["Fc_pos", "Fs_neg", "sigma0", "ms_share", "ms_dmax", "ms_spread", "ms_shape"]
    F, G = SensitivityLoop(model, free)(prepare_signals(t, v), {})
    np.testing.assert_allclose(F, friction_along_motion(model, t, v).F, rtol=0, atol=1e-12)
    flat = model.flat_params()
    for j, name in enumerate(free):
        h = 1e-7 * abs(flat[name])
        up = friction_along_motion(model, t, v, values={name: flat[name] + h}).F
        down = friction_along_motion(model, t, v, values={name: flat[name] - h}).F
        fd = (up - down) / (2 * h)
        scale = max(np.abs(fd).max(), 1e-9)
        assert np.abs(G[:, j] - fd).max() <= 1e-3 * scale, name


def test_compressed_problem_keeps_every_step_cost() -> None:
    J = RNG.standard_normal((5000, 6)) * np.array([1, 1e3, 1e-3, 1, 5, 1])
    r = RNG.standard_normal(5000)
    rt, Jt = compressed(J, r)
    assert Jt.shape == (7, 6)
    for _ in range(5):
        d = RNG.standard_normal(6)
        assert np.linalg.norm(rt + Jt @ d) == pytest.approx(np.linalg.norm(r + J @ d), rel=1e-9)


def test_collinear_parameters_are_reported_undetermined() -> None:
    a = RNG.standard_normal(400)
    J = np.column_stack([a, 2.0 * a, RNG.standard_normal(400)])
    assert determined_mask(J).tolist() == [True, False, True]


def test_hac_standard_errors_match_the_spread_under_autocorrelated_noise() -> None:
    """Linear regression with AR(1) noise (phi = 0.9): the sandwich standard error agrees with
    the Monte-Carlo spread of the estimate; the i.i.d. formula is ~4x too small."""
    n, reps, phi = 2000, 300, 0.9
    t = np.linspace(0.0, 1.0, n)
    J = np.column_stack([np.ones(n), np.sin(2 * np.pi * 3 * t)])
    e = RNG.standard_normal((reps, n))
    noise = np.empty_like(e)
    noise[:, 0] = e[:, 0] / math.sqrt(1 - phi**2)
    for k in range(1, n):
        noise[:, k] = phi * noise[:, k - 1] + e[:, k]
    est, se_hac, se_iid = [], [], []
    for i in range(reps):
        coef, *_ = np.linalg.lstsq(J, noise[i], rcond=None)
        r = noise[i] - J @ coef
        est.append(coef[1])
        se_hac.append(estimate(J, r, coef).stderr[1])
        se_iid.append(estimate(J, r, coef, autocorrelated=False).stderr[1])
    spread = float(np.std(est))
    assert np.median(se_hac) == pytest.approx(spread, rel=0.25)
    assert np.median(se_iid) < 0.4 * spread


# ------------------------------------------------------------------- recovery
def test_lugre_recovered_from_an_independent_simulation() -> None:
    truth = {"Fc": 5.0, "Fs": 8.0, "vs": 0.01, "n": 2.0, "sigma0": 1e5, "sigma1": 50.0,
             "sigma2": 30.0}
    meas, _ = reference_record(LuGreRef(**truth), duration=6.0, noise=0.02)
    fit = FrictionFit("lugre").fit(meas)
    assert fit.converged_ and fit.method_ == "trajectory"
    assert_recovered(fit, truth, rel=0.05)
    assert fit.rms_ == pytest.approx(0.02, rel=0.1)  # down to the noise


def test_nmlgm_recovered_and_the_missing_dwell_reported() -> None:
    truth = {"Fc": 5.5, "Fs": 22.5, "vs": 0.01, "n": 2.5, "sigma2": 25.0, "sigma0": 1.5e4,
             "vb": 0.037, "tau_hp": 0.02, "tau_hn": 0.15, "T": 0.01}
    p = FilmLuGreRef({**truth, "sigma1": 0.1, "tau_h0": 20.0, "v_eps": 1e-5})
    meas, _ = reference_record(p, duration=6.0, noise=0.05)
    fit = FrictionFit("nmlgm").fit(meas)
    assert fit.converged_
    # the record never rests, so the dwell time constant cannot be determined
    assert "tau_h0" in fit.not_identifiable_ and "tau_h0" not in fit.params_
    assert_recovered(fit, truth, rel=0.1, weak=("tau_hp",))


def test_static_maps_on_the_steady_state_characteristic() -> None:
    """Seed 002's procedure: constant-speed runs, binned points, weighted least squares."""
    speeds = np.array([0.002, 0.004, 0.007, 0.012, 0.02, 0.035, 0.06, 0.1])
    seq = np.concatenate([[s, 0.0, -s, 0.0] for s in speeds])
    t = np.arange(seq.size * 500) / 1000.0
    v = np.repeat(seq, 500)
    truth = {"Fc": 5.0, "Fs": 8.0, "vs": 0.01, "n": 2.0, "sigma2": 30.0}
    F = np.array([stribeck_map(vk, **truth) for vk in v]) + 0.05 * RNG.standard_normal(t.size)
    meas = Measurement({"t": t, "v": v, "a": np.zeros_like(t), "F": F}, {"name": "steps"})
    pts = steady_state_points(t, v, np.zeros_like(t), F, v_min=1e-3)
    assert len(pts) == 2 * speeds.size  # one point per run and direction
    fit = FrictionFit("stribeck", fixed={"vb": math.inf}).fit(meas)
    assert fit.method_ == "steady-state"
    assert_recovered(fit, truth, rel=0.05)
    cv = FrictionFit("coulomb-viscous").fit(meas)
    assert cv.method_ == "steady-state" and set(cv.params_) == {"Fc", "B"}


def test_mass_and_offset_estimated_from_the_driving_force() -> None:
    """Force-driven rig: F_ext = m*a + Fc*sign(v) + B*v + offset (models.md 3.5)."""
    t = np.arange(8001) / 1000.0
    v, a = velocity(t), acceleration(t)
    m, Fc, B, off = 3.0, 4.0, 60.0, -0.7
    F_ext = m * a + np.array([coulomb_viscous(vk, Fc, B) for vk in v]) + off
    F_ext = F_ext + 0.05 * RNG.standard_normal(t.size)
    meas = Measurement({"t": t, "v": v, "a": a, "F_ext": F_ext}, {"name": "rig"})
    fit = FrictionFit("coulomb-viscous", offset=True).fit(meas)
    assert fit.target_ == "driving-force"
    assert_recovered(fit, {"mass": m, "Fc": Fc, "B": B, "offset": off}, rel=0.02)
    # the same record as positions only: v, a and the force pass the same zero-phase filter
    x = 0.05 / np.pi * (1 - np.cos(np.pi * t)) + 0.02 / (2.6 * np.pi) * (1 - np.cos(2.6 * np.pi * t))
    pos = Measurement({"t": t, "x": x, "F_ext": F_ext}, {"name": "rig-x"})
    fx = FrictionFit("coulomb-viscous", offset=True).fit(pos)
    assert fx.params_["mass"] == pytest.approx(m, rel=0.03)
    # filtering smooths the Coulomb steps at reversals: a few per cent of bias on Fc
    assert fx.params_["Fc"] == pytest.approx(Fc, rel=0.1)
    assert fx.params_["B"] == pytest.approx(B, rel=0.1)


def test_direction_dependent_levels() -> None:
    t = np.arange(6001) / 1000.0
    v = velocity(t)
    F = np.where(v > 0, 3.0 + 40.0 * v, -5.0 + 70.0 * v) + 0.02 * RNG.standard_normal(t.size)
    meas = Measurement({"t": t, "v": v, "a": acceleration(t), "F": F}, {"name": "asym"})
    fit = FrictionFit("coulomb-viscous", directional=True, method="samples").fit(meas)
    assert_recovered(fit, {"Fc_pos": 3.0, "Fc_neg": 5.0, "B_pos": 40.0, "B_neg": 70.0}, 0.02)
    with pytest.raises(FcompError, match="confounded"):
        FrictionFit("coulomb-viscous", directional=True, offset=True).fit(meas)


def test_hysteresis_segments_from_transition_curves() -> None:
    """Seed 000's new model: c_i, k_i recovered from pre-sliding loops with internal loops."""
    model = make_model("nmlgm-hysteresis", params="seed000-cylinder1")
    t = np.arange(3001) / 1000.0
    x = 0.17e-3 * np.sin(2 * np.pi * 0.5 * t) + 0.03e-3 * np.sin(2 * np.pi * 2.1 * t)
    v = np.gradient(x, t)
    F = friction_along_motion(model, t, v, x=x).F + 0.02 * RNG.standard_normal(t.size)
    meas = Measurement({"t": t, "x": x, "v": v, "a": np.gradient(v, t), "F": F}, {"name": "pre"})
    seg = ["c1", "k1", "c2", "k2", "c3", "k3", "c8", "k8"]
    fit = FrictionFit(model, free=seg).fit(meas)
    assert [s["stage"] for s in fit.stages_] == ["transition-curves", "hysteresis-trajectory"]
    truth = {n: model.flat_params()[n] for n in seg}
    assert_recovered(fit, truth, rel=0.05)


def test_gms_keeps_the_slip_fractions_summing_to_one() -> None:
    model = make_model("gms")
    t = np.arange(6001) / 1000.0
    x = 2e-3 * np.sin(2 * np.pi * 0.25 * t) + 3e-5 * np.sin(6 * np.pi * t) * (
        1 + np.sin(np.pi * t))
    v = np.gradient(x, t)
    F = friction_along_motion(model, t, v, x=x).F + 0.01 * RNG.standard_normal(t.size)
    meas = Measurement({"t": t, "x": x, "v": v, "a": np.gradient(v, t), "F": F}, {"name": "gms"})
    free = ["Fc", "Fs", "vs", "k1", "k2", "k3", "k4", "alpha1", "alpha2", "alpha3", "alpha4"]
    fit = FrictionFit("gms", free=free).fit(meas)
    alphas = [fit.params_[f"alpha{i}"] for i in range(1, 5)]
    assert sum(alphas) == pytest.approx(1.0, abs=1e-12)
    assert fit.stderr_["alpha4"] > 0  # propagated through the equality
    assert_recovered(fit, {k: model.flat_params()[k] for k in free}, rel=0.05,
                     weak=("k1", "k2", "k3", "k4", "alpha1", "alpha2", "alpha3", "alpha4"))


# ------------------------------------------------------------- failure modes
def test_non_convergence_is_reported() -> None:
    meas, _ = reference_record(LuGreRef(5.0, 8.0, 0.01, 2.0, 1e5, 50.0, 30.0), 2.0, 0.02)
    with pytest.raises(ConvergenceError, match="did not converge"):
        FrictionFit("lugre", max_nfev=2).fit(meas)
    fit = FrictionFit("lugre", max_nfev=2, strict=False).fit(meas)
    assert fit.converged_ is False


def test_bad_requests_are_one_line_errors() -> None:
    meas, _ = reference_record(LuGreRef(5.0, 8.0, 0.01, 2.0, 1e5, 50.0, 30.0), 1.0, 0.02)
    with pytest.raises(FcompError, match="no parameter 'sigma9'"):
        FrictionFit("lugre", free=["sigma9"]).fit(meas)
    with pytest.raises(FcompError, match="cannot be estimated from an 'F' column"):
        FrictionFit("lugre", estimate_mass=True).fit(meas)
    only_motion = Measurement({"t": meas.t, "v": meas["v"]}, {"name": "bare"})
    with pytest.raises(FcompError, match="no force to fit"):
        fit_data(only_motion)
    with pytest.raises(FcompError, match="not fitted"):
        FrictionFit("lugre").predict(meas)


# ------------------------------------------------------------------ real data
def test_emps_against_the_benchmark_reference_values() -> None:
    """EMPS (Janot et al. 2019): IDIM-LS values M = 95.1089 kg, Fv = 203.5034 Ns/m,
    Fc = 20.3935 N, offset = -3.1648 N (as quoted by meco-group/nlgreyfast)."""
    from fcomp import datasets

    est = datasets.load("emps", "DATA_EMPS.mat")
    fit = FrictionFit("coulomb-viscous", offset=True).fit(est)
    assert fit.params_["mass"] == pytest.approx(95.1089, rel=0.01)
    assert fit.params_["Fc"] == pytest.approx(20.3935, rel=0.05)
    assert fit.params_["B"] == pytest.approx(203.5034, rel=0.05)
    assert fit.params_["offset"] == pytest.approx(-3.1648, abs=0.3)
    for k, ref in (("mass", 95.1089), ("Fc", 20.3935), ("B", 203.5034)):
        lo, hi = fit.ci_[k]
        assert lo - 0.01 * abs(ref) < ref < hi + 0.01 * abs(ref), k
    # the validation record (force pulses added) is predicted about as well as the fit
    val = datasets.load("emps", "DATA_EMPS_PULSES.mat")
    assert fit.score(val) < 1.5 * fit.rms_


def test_zillen_friction_level_grows_with_chamber_pressure() -> None:
    from fcomp import datasets

    levels = []
    for bar in (1, 3, 5, 7):
        fit = FrictionFit("coulomb", offset=True).fit(datasets.load("zillen", f"O-ring_{bar}bar.csv"))
        levels.append((fit.params_["Fc"], fit.ci_["Fc"]))
    values = [v for v, _ in levels]
    assert values == sorted(values)
    assert levels[0][1][1] < levels[-1][1][0]  # 1 bar and 7 bar intervals do not overlap


# ------------------------------------------------------- several records, one vector
def test_fit_records_recovers_one_vector_from_masked_samples_of_two_records() -> None:
    """The engine's public multi-record entry point: two records of the same LuGre pushed
    by a driving force (the mass estimated), part of each masked out, one parameter vector."""
    from fcomp.identification import Record, fit_records

    truth = LuGreRef(5.0, 8.0, 0.01, 2.0, 1e5, 50.0, 30.0)
    mass = 2.5

    def driven(duration: float, name: str) -> Measurement:
        meas, _ = reference_record(truth, duration, 0.02)
        return Measurement({k: meas[k] for k in ("t", "x", "v", "a")}
                           | {"F_ext": meas["F"] + mass * meas["a"]}, {"name": name})

    d1, d2 = fit_data(driven(3.0, "one")), fit_data(driven(2.0, "two"))
    assert d1.inertia is not None and d2.inertia is not None
    m1 = np.arange(d1.n) % 2 == 0
    m2 = d2.sig["t"] < 1.5
    model = make_model("lugre", params={"Fc": 4.0, "Fs": 7.0, "vs": 0.01, "n": 2.0,
                                        "sigma0": 1e5, "sigma1": 50.0, "sigma2": 20.0})
    names = ["Fc", "Fs", "sigma2", "mass"]
    res = fit_records(model, [Record(d1, m1), Record(d2, m2)], names,
                      starts=[{"sigma2": 10.0}, {"sigma2": 40.0, "mass": 1.0}], probe_nfev=5,
                      bounds={"mass": (0.0, 10.0)}, max_nfev=50)
    assert res.converged and not res.probed_only
    want = {"Fc": 5.0, "Fs": 8.0, "sigma2": 30.0, "mass": mass}
    for n, v in want.items():
        assert res.values[n] == pytest.approx(v, rel=0.02), n
    assert res.model.flat_params()["Fs"] == pytest.approx(res.values["Fs"])
    assert "mass" not in res.model.flat_params()
    assert res.solution.residuals.size == int(m1.sum() + m2.sum())
    assert res.cost == pytest.approx(float(res.solution.residuals @ res.solution.residuals))
    # a caller's stopping rule after the probes
    stopped = fit_records(model, [Record(d1, m1)], ["Fc", "mass"], starts=[{}, {"Fc": 3.0}],
                          probe_nfev=2, keep_going=lambda cost: False)
    assert stopped.probed_only and not stopped.converged
    with pytest.raises(FcompError, match="no parameter"):
        fit_records(model, [Record(d1)], ["Fq"])


def test_records_carry_weights_held_extras_and_block_averages() -> None:
    """A record's weights scale its residual and Jacobian rows by ``sqrt(w)``; holding the
    mass takes its term out of the target; a block-averaged record keeps the blocks whose
    samples are all masked; ``fit_records`` with staged names and probes on a coarse copy
    still recovers the vector."""
    from fcomp.identification import Record, fit_records
    from fcomp.identification.problem import ParameterVector
    from fcomp.identification.records import RecordsProblem, fit_specs

    truth = LuGreRef(5.0, 8.0, 0.01, 2.0, 1e5, 50.0, 30.0)
    meas, _ = reference_record(truth, 3.0, 0.02)
    d = fit_data(Measurement({k: meas[k] for k in ("t", "x", "v", "a")}
                             | {"F_ext": meas["F"] + 2.5 * meas["a"]}, {"name": "one"}))
    model = make_model("lugre", params={"Fc": 4.0, "Fs": 7.0, "vs": 0.01, "n": 2.0,
                                        "sigma0": 1e5, "sigma1": 50.0, "sigma2": 20.0})
    mask = np.arange(d.n) % 3 != 0
    w = np.linspace(0.1, 1.0, d.n)
    names = ["Fc", "sigma2", "mass"]
    start = {**model.flat_params(), "mass": 1.0}
    pv = ParameterVector.build(names, start, fit_specs(model, names))
    theta = pv.start
    r0, G0 = RecordsProblem(model, [Record(d, mask)], pv)(theta, True)
    r1, G1 = RecordsProblem(model, [Record(d, mask, w)], pv)(theta, True)
    assert G0 is not None and G1 is not None
    np.testing.assert_allclose(r1, r0 * np.sqrt(w[mask]), rtol=1e-12)
    np.testing.assert_allclose(G1, G0 * np.sqrt(w[mask])[:, None], rtol=1e-12)
    held = Record(d, mask).holding({"mass": 2.5})
    assert held.data.inertia is None and d.inertia is not None
    np.testing.assert_allclose(held.data.y, d.y - 2.5 * d.inertia)
    first = d.sig["t"] < 1.5
    coarse = Record(d, first, w).averaged(4)
    assert coarse.data.n == math.ceil(d.n / 4) and coarse.weights is not None
    assert coarse.mask is not None and coarse.mask.sum() == first.sum() // 4
    whole = Record(d, mask)
    assert whole.averaged(1) is whole
    res = fit_records(model, [Record(d)], ["Fc", "Fs", "n", "sigma2", "mass"],
                      starts=[{"sigma2": 10.0}, {"sigma2": 40.0}, {"sigma2": 20.0, "Fc": 3.0}],
                      probe_nfev=6, probe_records=[Record(d).averaged(2)], staged=["n"],
                      bounds={"mass": (0.0, 10.0), "n": (0.5, 4.0)}, max_nfev=60)
    want = {"Fc": 5.0, "Fs": 8.0, "n": 2.0, "sigma2": 30.0, "mass": 2.5}
    for n, v in want.items():
        assert res.values[n] == pytest.approx(v, rel=0.03), n


def test_strategies_are_chosen_by_capability_and_pluggable() -> None:
    from fcomp.identification import (
        DiscreteMemoryStrategy,
        StaticStrategy,
        TrajectoryStrategy,
        strategy_for,
    )

    assert isinstance(strategy_for(make_model("coulomb-viscous")), StaticStrategy)
    assert isinstance(strategy_for(make_model("lugre", effects=["dwell-time"])),
                      TrajectoryStrategy)
    assert isinstance(strategy_for(make_model("nmlgm-hysteresis")), DiscreteMemoryStrategy)
    meas, _ = reference_record(LuGreRef(5.0, 8.0, 0.01, 2.0, 1e5, 50.0, 30.0), 2.0, 0.02)
    fit = FrictionFit("lugre", free=["Fc", "Fs", "sigma2"],
                      strategy=TrajectoryStrategy()).fit(meas)
    assert fit.strategy_.name == "trajectory" and fit.method_ == "trajectory"
    with pytest.raises(FcompError, match="no discrete memory"):
        FrictionFit("lugre", strategy=DiscreteMemoryStrategy()).fit(meas)
