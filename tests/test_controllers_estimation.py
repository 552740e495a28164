"""EKF, MPC, the prediction model and native calls: against independent computations.

* the linearly implicit Euler prediction converges to a tight ``solve_ivp``
  (Radau) integration of the same equations at first order;
* the EKF's Jacobian equals finite differences of its own step, and with an
  exact model its friction estimate follows the plant's true friction;
* the MPC respects the valve and rate limits, refuses infeasible set-ups in
  one line, and falls back (counted) when its QP fails at run time.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from controllers import make_controller
from controllers.base import Reference
from controllers.ekf import make_ekf
from controllers.native import native
from controllers.plant_model import ControlModel, equilibrium
from fcomp.errors import FcompError
from fcomp.models import make_model


@pytest.fixture(scope="module")
def hyd() -> ControlModel:
    return ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))


def test_native_call_equals_casadi() -> None:
    x = ca.SX.sym("x", 3)
    M = ca.SX.sym("M", 2, 2)
    f = ca.Function("native_test_fn", [x, M], [ca.sin(x) * ca.trace(M), ca.jacobian(x**3, x), M.T])
    args = (np.array([0.1, -2.0, 3.0]), np.array([[1.0, 2.0], [3.0, 4.0]]))
    ref = [np.asarray(r) for r in f(*args)]
    for compiled in (True, False):
        got = native(f, compiled=compiled)(*args)
        assert np.allclose(got[0], ref[0].ravel()) and np.allclose(got[1], ref[1])
        assert np.allclose(got[2], ref[2])


def test_prediction_step_converges_to_an_accurate_integration(hyd: ControlModel) -> None:
    pm = hyd.prediction
    x0, u0 = equilibrium(hyd.plant, 0.15)
    u = u0 + 2e-3                                       # open the valve: the load rises
    T = 0.02

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        return np.asarray(pm.f(x, u, pm.p)).ravel()

    ref = solve_ivp(rhs, (0, T), x0, method="Radau", rtol=1e-10,
                    atol=1e-12 * pm.scales).y[:, -1]
    errs = []
    for n in (20, 40, 80):
        step = pm.step(T / n)  # the plant's discrete step, linearly implicit Euler
        x = x0.copy()
        for _ in range(n):
            x = np.asarray(step(x, u, pm.p)).ravel()
        errs.append(np.max(np.abs(x - ref) / pm.scales))
    assert errs[0] < 0.05                                 # 1 ms steps: a few % of a scale (film h)
    assert errs[1] < 0.6 * errs[0] and errs[2] < 0.6 * errs[1]   # first order: halves


def test_prediction_step_with_scales_as_input_is_the_same_step(hyd: ControlModel) -> None:
    pm = hyd.prediction
    x0, u0 = equilibrium(hyd.plant, 0.15)
    x0[1] = 0.01                                          # moving: the friction terms active
    for sens in (False, True):
        fixed = pm.step(2e-3, 2, sensitivities=sens)
        free = pm.step(2e-3, 2, sensitivities=sens, scale_input=True)
        for a, b in zip(fixed.call([x0, u0, pm.p]), free.call([x0, u0, pm.p, pm.scales]),
                        strict=True):
            assert np.allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=0)


def test_one_compiled_kernel_serves_every_parameter_draw() -> None:
    """The EKF's and the MPC's functions do not depend on the friction parameters (scales
    follow them, and are inputs too): a Monte Carlo draw compiles nothing new."""
    from controllers.harness import LoopConfig, build_loop

    fns = []
    for factor in (0.5, 2.0):
        cfg = LoopConfig(plant="hydraulic", mismatch={"sigma0": factor, "Fc": factor})
        _plant, model, ctrl = build_loop("mpc", cfg)
        assert model.prediction.scales[model.prediction.index("z")] > 0
        fns.append([ctrl.solver._lin.fn, ctrl.ekf._predict.fn, ctrl.ekf._friction.fn])
    for a, b in zip(*fns, strict=True):
        assert a.serialize() == b.serialize(), a.name()


def test_ekf_jacobian_is_the_derivative_of_its_step(hyd: ControlModel) -> None:
    ekf = make_ekf(hyd, 1e-3, {})
    x0, u0 = equilibrium(hyd.plant, 0.15)
    xi = x0 / ekf.scale
    xi[1] = 0.01 / ekf.scale[1]                          # moving: the friction terms active
    xn, A = ekf._predict(xi, u0, ekf.p, ekf.scale)
    for j in range(xi.size):
        h = 1e-6 * max(1.0, abs(xi[j]))
        d = np.zeros_like(xi)
        d[j] = h
        fd = (ekf._predict(xi + d, u0, ekf.p, ekf.scale)[0]
              - ekf._predict(xi - d, u0, ekf.p, ekf.scale)[0]) / (2 * h)
        assert np.allclose(A[:, j], fd, rtol=1e-4, atol=1e-6), hyd.prediction.state_names[j]


def test_ekf_tracks_the_true_friction_with_an_exact_model(hyd: ControlModel) -> None:
    dt = 1e-3
    x0, u0 = equilibrium(hyd.plant, 0.15)
    ekf = make_ekf(hyd, dt, {})
    idx = list(hyd.prediction.measured)
    ekf.reset(*hyd.estimator_initial(x0[idx]))
    stepper = hyd.plant.stepper(dt, x0=x0)
    x = stepper.reset()
    rng = np.random.default_rng(1)
    F_true, F_hat = [], []
    fric = hyd.prediction.friction
    for k in range(600):
        u = u0 + 1.5e-3 * np.sin(2 * np.pi * 2.0 * k * dt)
        x = stepper.step(u)
        y = x[idx] + hyd.sensor_std() * rng.standard_normal(3)
        ekf.step(y, u)
        F_true.append(float(fric(x, u, hyd.prediction.p)))
        F_hat.append(ekf.friction(u))
    F_true, F_hat = np.array(F_true[200:]), np.array(F_hat[200:])
    assert np.sqrt(np.mean((F_hat - F_true) ** 2)) < 0.1 * np.max(np.abs(F_true))


def _mpc_loop(model: ControlModel, ctrl, steps: int, ref_pos: float):
    x0, _ = equilibrium(model.plant, 0.15)
    stepper = model.plant.stepper(ctrl.dt, x0=x0)
    x = stepper.reset()
    ctrl.reset(0.0, x[[0, 2, 3]], Reference(0.15, 0.0, 0.0))
    us = []
    for _ in range(steps):
        ref = Reference(ref_pos, 0.0, 0.0, tuple([ref_pos] * ctrl.preview))
        u = ctrl.step(0.0, x[[0, 2, 3]], ref)
        us.append(u)
        x = stepper.step(u)
    return np.array(us), x


def test_mpc_respects_valve_and_rate_limits(hyd: ControlModel) -> None:
    ctrl = make_controller("mpc", hyd, du_max=0.5, u_max=0.004)
    us, x = _mpc_loop(hyd, ctrl, 60, 0.152)             # a 2 mm step
    assert np.all(np.abs(us) <= 0.004 + 1e-9)
    assert np.max(np.abs(np.diff(us))) <= 0.5 * ctrl.dt + 1e-9
    assert ctrl.fallbacks == 0
    assert abs(x[0] - 0.152) < abs(0.15 - 0.152)         # it moved toward the target


def test_mpc_infeasible_set_ups_are_one_line_errors(hyd: ControlModel) -> None:
    with pytest.raises(FcompError, match="infeasible MPC set-up: horizon"):
        make_controller("mpc", hyd, horizon=1)
    with pytest.raises(FcompError, match="infeasible MPC set-up: u_max .* exceeds"):
        make_controller("mpc", hyd, u_max=1.0)
    with pytest.raises(FcompError, match="infeasible MPC set-up: holding the load"):
        make_controller("mpc", hyd, u_max=1e-5)
    with pytest.raises(FcompError, match="infeasible MPC set-up: du_max"):
        make_controller("mpc", hyd, du_max=0.0)


def test_mpc_falls_back_and_counts_when_the_qp_fails(hyd: ControlModel, monkeypatch) -> None:
    import controllers.mpc as mpc_mod

    ctrl = make_controller("mpc", hyd)
    real = mpc_mod.daqp.solve
    calls = {"n": 0}

    def flaky(*args, **kwargs):
        calls["n"] += 1
        x, f, flag, info = real(*args, **kwargs)
        return (x, f, -1, info) if 10 <= calls["n"] < 15 else (x, f, flag, info)

    monkeypatch.setattr(mpc_mod.daqp, "solve", flaky)
    us, _ = _mpc_loop(hyd, ctrl, 30, 0.151)
    assert ctrl.fallbacks == 5                           # every failed solve counted
    assert np.all(np.isfinite(us))
    assert np.max(np.abs(np.diff(us))) <= hyd.du_max * ctrl.dt + 1e-12   # fallback rate-limited
