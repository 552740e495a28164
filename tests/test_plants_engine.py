"""The simulation engine (fcomp/simulation.py): order, error control, drivers, failures."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.linalg import expm

from fcomp.errors import ConvergenceError, FcompError
from fcomp.models import make_model
from fcomp.simulation import (
    METHODS,
    OdeModel,
    Rodas4,
    Tolerances,
    input_rates,
    integrate,
    rosenbrock_step,
)
from plants import PLANTS


def linear_model(A: np.ndarray, B: np.ndarray, name: str) -> OdeModel:
    """``dx/dt = A x + B u`` as an engine model (``p`` unused)."""
    n, m = B.shape
    x, u, p = ca.SX.sym("x", n), ca.SX.sym("u", m), ca.SX.sym("p", 1)
    f = ca.mtimes(ca.DM(A), x) + ca.mtimes(ca.DM(B), u)
    return OdeModel(name, ca.Function("f", [x, u, p], [f]), tuple(f"x{i}" for i in range(n)),
                    tuple(f"u{i}" for i in range(m)), np.ones(n), key=(name,))


def exact_linear(A: np.ndarray, B: np.ndarray, x0: np.ndarray, t: np.ndarray,
                 U: np.ndarray) -> np.ndarray:
    """Exact solution for an input linear between samples (augmented matrix exponential)."""
    n, m = B.shape
    X = [x0]
    for k in range(t.size - 1):
        h = t[k + 1] - t[k]
        du = (U[k + 1] - U[k]) / h
        # state [x, u, du]: x' = A x + B u, u' = du, du' = 0
        Aa = np.zeros((n + 2 * m, n + 2 * m))
        Aa[:n, :n], Aa[:n, n:n + m] = A, B
        Aa[n:n + m, n + m:] = np.eye(m)
        z = expm(Aa * h) @ np.concatenate([X[-1], U[k], du])
        X.append(z[:n])
    return np.array(X)


# a stiff, oscillatory linear test system: eigenvalues -1e4, -1 +- 30i
A_TEST = np.array([[-1e4, 0.0, 0.0], [0.0, -1.0, 30.0], [1.0, -30.0, -1.0]])
B_TEST = np.array([[1e4], [0.0], [1.0]])


def test_rodas4_step_is_fourth_order() -> None:
    """The CasADi RODAS4 step (discrete model) converges with order 4 on a linear system."""
    model = linear_model(A_TEST, B_TEST, "lin_order")
    x0 = np.array([1.0, 0.5, -0.2])
    exact = expm(A_TEST * 0.2) @ x0 + np.linalg.solve(A_TEST, (expm(A_TEST * 0.2) - np.eye(3))
                                                      @ B_TEST[:, 0] * 0.7)
    errs = []
    for n in (20, 40, 80):
        step = model.discrete_step(0.2 / n)
        x = x0
        for _ in range(n):
            x = np.asarray(step(x, 0.7, 0.0)).ravel()
        errs.append(np.max(np.abs(x - exact)))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((orders > 3.6) & (orders < 4.6)), orders


def test_adaptive_error_follows_tolerance() -> None:
    """Global error of the adaptive loop shrinks with rtol and stays near it (stiff system)."""
    model = linear_model(A_TEST, B_TEST, "lin_adaptive")
    t = np.linspace(0.0, 1.0, 201)
    U = np.sin(7.0 * t)[:, None]
    x0 = np.array([0.0, 1.0, 0.0])
    exact = exact_linear(A_TEST, B_TEST, x0, t, U)
    errors = []
    for tol in (1e-4, 1e-7, 1e-10):
        tr = integrate(model, x0, t, U, [0.0], tolerances=Tolerances(rtol=tol, atol=tol))
        errors.append(np.max(np.abs(tr.X - exact)))
    assert errors[0] < 1e-2 and errors[1] < 1e-5 and errors[2] < 1e-8, errors
    assert errors[2] < errors[1] < errors[0]


def test_radau_reference_method_agrees_on_linear_system() -> None:
    model = linear_model(A_TEST, B_TEST, "lin_radau")
    t = np.linspace(0.0, 0.2, 21)
    U = np.cos(5.0 * t)[:, None]
    x0 = np.array([0.3, 0.0, 1.0])
    exact = exact_linear(A_TEST, B_TEST, x0, t, U)
    tr = integrate(model, x0, t, U, [0.0], method="radau",
                   tolerances=Tolerances(rtol=1e-7, atol=1e-7))
    assert np.max(np.abs(tr.X - exact)) < 1e-4  # dense output of Radau between its steps


def test_rosenbrock_step_handles_badly_scaled_states() -> None:
    """With the scaling, a step of a system whose states span 1e-6 .. 1e7 is the same step as
    on the well-scaled system (Rosenbrock steps are scaling-invariant; the solves stay exact)."""
    D = np.diag([1e-6, 1.0, 1e7])
    x, u = ca.SX.sym("x", 3), ca.SX.sym("u", 1)

    def step(A: np.ndarray, B: np.ndarray, scale: object) -> ca.Function:
        def f(a, b):
            return ca.mtimes(ca.DM(A), a) + ca.mtimes(ca.DM(B), b)

        xn, err = rosenbrock_step(f, x, u, ca.SX(0.0), ca.SX(2e-3), scale)
        return ca.Function("s", [x, u], [xn, err])

    x0 = np.array([1.0, 0.5, -0.2])
    good = step(A_TEST, B_TEST, None)
    bad = step(D @ A_TEST @ np.linalg.inv(D), D @ B_TEST, ca.DM([1e-6, 1.0, 1e7]))
    xg, eg = (np.asarray(a).ravel() for a in good(x0, 0.3))
    xb, eb = (np.linalg.inv(D) @ np.asarray(a).ravel() for a in bad(D @ x0, 0.3))
    np.testing.assert_allclose(xb, xg, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(eb, eg, rtol=1e-8, atol=1e-13)


@pytest.fixture(scope="module")
def force_rig():
    return PLANTS.get("force-rig")(make_model("lugre", params="seed000-cylinder1"))


def test_python_loop_matches_compiled_loop(force_rig) -> None:
    """Without a compiler the same decisions are taken in Python: identical results."""
    model = force_rig.ode_model()
    t = np.linspace(0.0, 0.05, 51)
    U = (20.0 * np.sin(2 * np.pi * 10 * t))[:, None]
    x0 = force_rig.initial_state()
    p = force_rig.param_vector()
    dU = input_rates(t, U, "linear")
    tol = Tolerances()
    comp = Rodas4(model)
    assert comp.compiled
    Xc, sc, _ = comp.run(x0, U[:-1], dU, np.diff(t), p, tol, tol.h0)
    Xp, sp, _ = Rodas4(model, compiled=False).run(x0, U[:-1], dU, np.diff(t), p, tol, tol.h0)
    assert sc.steps == sp.steps and sc.rejected == sp.rejected
    np.testing.assert_allclose(Xp, Xc, rtol=1e-9, atol=1e-12)


def test_stepper_is_the_zero_order_hold_run(force_rig) -> None:
    """Closed-loop stepping (input held per sample) equals the whole run with hold="zoh"."""
    dt = 1e-3
    n = 200
    u = 15.0 * np.sign(np.sin(2 * np.pi * 5 * np.arange(n + 1) * dt))
    st = force_rig.stepper(dt)
    assert np.allclose(st.reset(), force_rig.initial_state())
    X = [st.x]
    for k in range(n):
        X.append(st.step(u[k]))
    assert st.t == pytest.approx(n * dt)
    tr = integrate(force_rig.ode_model(), force_rig.initial_state(), np.arange(n + 1) * dt,
                   u[:, None], force_rig.param_vector(), hold="zoh")
    np.testing.assert_allclose(np.array(X), tr.X, rtol=1e-6, atol=1e-9)
    st.reset()
    assert st.t == 0.0 and np.allclose(st.x, force_rig.initial_state())


def test_discrete_step_agrees_with_adaptive_engine(force_rig) -> None:
    """The CasADi discrete-time model (MPC/EKF) advances like the engine, input held."""
    step = force_rig.discrete_step(2e-3, substeps=20)
    x0 = force_rig.initial_state({"v": 0.05})
    st = force_rig.stepper(2e-3, x0=x0, rtol=1e-10, atol=1e-10)
    got = np.asarray(step(x0, 12.0, force_rig.param_vector())).ravel()
    ref = st.step(12.0)
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-10)
    xs = ca.SX.sym("x", force_rig.nx)
    jac = ca.Function("jac_x", [xs], [ca.jacobian(step(xs, 12.0, force_rig.param_vector()), xs)])
    assert np.all(np.isfinite(np.asarray(jac(x0))))


def test_convergence_failure_names_the_time(force_rig) -> None:
    with pytest.raises(ConvergenceError, match=r"did not converge at t = .* max_steps"):
        force_rig.simulate(20.0, 0.5, 100.0, max_steps=5)


def test_bad_options_are_one_line_errors(force_rig) -> None:
    with pytest.raises(FcompError, match="rtol"):
        force_rig.simulate(1.0, 0.1, 100.0, rtol=0.0)
    with pytest.raises(FcompError, match="unknown integration method"):
        force_rig.simulate(1.0, 0.1, 100.0, method="euler")
    with pytest.raises(FcompError, match="hold"):
        force_rig.simulate(1.0, 0.1, 100.0, hold="cubic")
    with pytest.raises(FcompError, match="unknown state"):
        force_rig.simulate(1.0, 0.1, 100.0, x0={"q": 1.0})
    assert set(METHODS.names()) == {"rodas4", "radau", "bdf", "lsoda"}


def test_compiled_driver_is_the_template_filled_from_the_tableau() -> None:
    """The C loop is the shipped template with the tableau's own numbers (written once)."""
    from importlib import resources

    from fcomp.compiled import c_source
    from fcomp.rosenbrock import RODAS4, STEP_CONTROL, c_coefficients

    template = resources.files("fcomp").joinpath("csrc", "rosenbrock_step.c").read_text()
    assert "@RA@" in template and "1.544" not in template  # no coefficient typed in C
    values = {"F": "f", "J": "j", "NX": "2", "NU": "1", **c_coefficients(RODAS4, STEP_CONTROL)}
    code = c_source("rosenbrock_step.c", values)
    assert "@" not in code
    assert f"GAM = {RODAS4.gamma!r};" in code and repr(RODAS4.a[1][0]) in code
    assert f"{STEP_CONTROL.safety!r} * pow(en, -1.0 / {RODAS4.order})" in code
    with pytest.raises(ValueError, match="placeholders"):
        c_source("rosenbrock_step.c", {k: v for k, v in values.items() if k != "RA"})
    with pytest.raises(ValueError, match="placeholders"):
        c_source("rosenbrock_step.c", {**values, "EXTRA": "1"})
    loop = c_source("stepping_loop.c", {"STEP": "step", "NX": "2", "NU": "1"})
    assert "@" not in loop and "step(arg, res, iw, w, 0)" in loop


def test_kernel_cache_is_bounded_and_shared_by_structure() -> None:
    """Models of one structure share their kernels; the cache keeps a bounded number."""
    from fcomp.simulation import KERNEL_CACHE_SIZE, _model_functions, clear_kernel_cache

    clear_kernel_cache()
    first = Rodas4(linear_model(A_TEST, B_TEST, "lin_cache"))
    again = Rodas4(linear_model(A_TEST, B_TEST, "lin_cache"))
    assert again.F is first.F and again.c_fn is first.c_fn
    assert _model_functions.cache_info().maxsize == KERNEL_CACHE_SIZE
    for i in range(KERNEL_CACHE_SIZE + 3):
        Rodas4(linear_model(A_TEST, B_TEST, f"lin_cache_{i}"), compiled=False)
    assert _model_functions.cache_info().currsize == KERNEL_CACHE_SIZE
    clear_kernel_cache()
    assert _model_functions.cache_info().currsize == 0


def test_the_three_steppers_share_one_contract(force_rig) -> None:
    """Engine, discrete-memory plant and hysteresis model: one base, one reset/advance."""
    from fcomp.simulation import Stepper
    from fcomp.stepper import SampledStepper
    from plants.discrete_memory import MemoryStepper

    rig = PLANTS.get("presliding-rig")(make_model("nmlgm-hysteresis", params="seed000-cylinder1"))
    hyst = make_model("nmlgm-hysteresis", params="seed000-cylinder1").stepper()
    steppers = [force_rig.stepper(1e-3), rig.stepper(1e-3), hyst]
    assert [type(s) for s in steppers[:2]] == [Stepper, MemoryStepper]
    inputs = ([5.0], rig.scalar_input(np.array([0.01]))[0], [0.01, 0.0, 0.0, 0.0, 0.0])
    for st, u in zip(steppers, inputs, strict=True):
        assert isinstance(st, SampledStepper)
        x0 = st.reset()
        assert st.t == 0.0 and x0.shape == (len(st.state_names),)
        x1 = st.advance(u, 2e-3)
        assert st.t == 2e-3 and np.all(np.isfinite(x1)) and not np.array_equal(x1, x0)
        with pytest.raises(FcompError, match="initial state"):
            st.reset(np.zeros(len(st.state_names) + 1))
        with pytest.raises(FcompError, match="values"):
            st.advance([*u, 0.0], 1e-3)
        with pytest.raises(FcompError, match="not finite"):
            st.advance([np.nan] * len(st.input_names), 1e-3)
        with pytest.raises(FcompError, match="positive"):
            st.advance(u, 0.0)
    # the shorter forms are advance over the sample time / with named signals
    a, b = force_rig.stepper(1e-3), force_rig.stepper(1e-3)
    np.testing.assert_array_equal(a.step(np.array([3.0])), b.advance([3.0], 1e-3))
    h2 = make_model("nmlgm-hysteresis", params="seed000-cylinder1").stepper()
    hyst.reset()
    np.testing.assert_array_equal(hyst.step(1e-3, 0.01, 0.2), h2.advance([0.01, 0.2, 0, 0, 0], 1e-3))
