"""Generalized Maxwell-slip (continuous-state GMS, models.md 1.7).

Independent references: the closed-form solution of each element at constant
``g`` (``z_i -> s*alpha_i*g/k_i`` exponentially in the travelled distance),
the Stribeck curve written out, and an ideal Maxwell-slip model
(elasto-perfectly-plastic elements, exact return-point memory).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

from fcomp.backend import CASADI, NUMPY
from fcomp.models import MODELS, Signals, make_model
from fcomp.models.gms import GMS, GMSModel, gms_class
from fcomp.trajectory import friction_along_motion

K = np.array([4e4, 3e4, 2e4, 1e4])
ALPHA = np.array([0.1, 0.2, 0.3, 0.4])
RATE_INDEPENDENT = {"Fc": 1.0, "Fs": 1.0, "sigma1": 0.0, "sigma2": 0.0}  # g = 1 N


def stribeck(v: np.ndarray, Fc: float, Fs: float, vs: float, n: float) -> np.ndarray:
    return Fc + (Fs - Fc) * np.exp(-((np.abs(v) / vs) ** n))


def legs(model: GMSModel, points: list[float], speed: float = 1e-4, n: int = 100) -> list[float]:
    """Force at the end of each monotone leg (constant speed, state carried over)."""
    x0 = model.initial_state()
    out = []
    for a, b in zip(points[:-1], points[1:], strict=True):
        t = np.linspace(0.0, abs(b - a) / speed, n + 1)
        run = friction_along_motion(model, t, np.full(t.size, math.copysign(speed, b - a)),
                                    state0=x0)
        x0 = run.states[-1]
        out.append(float(run.F[-1]))
    return out


def closed_form(points: list[float], k: np.ndarray = K, alpha: np.ndarray = ALPHA,
                g: float = 1.0) -> list[float]:
    """Elements at constant g: z_i(x) = s*a_i*g/k_i + (z_i0 - s*a_i*g/k_i)*exp(-k_i|dx|/(a_i*g))."""
    z = np.zeros_like(k)
    out = []
    for a, b in zip(points[:-1], points[1:], strict=True):
        zs = math.copysign(1.0, b - a) * alpha * g / k
        z = zs + (z - zs) * np.exp(-k * abs(b - a) / (alpha * g))
        out.append(float(k @ z))
    return out


def test_registered_with_defaults() -> None:
    m = make_model("gms")
    assert MODELS.get("gms") is GMS and isinstance(m, GMSModel)
    p = m.flat_params()
    np.testing.assert_allclose([p[f"k{i}"] for i in range(1, 5)], K)
    np.testing.assert_allclose([p[f"alpha{i}"] for i in range(1, 5)], ALPHA)
    assert m.state_names == ("z1", "z2", "z3", "z4")
    assert m.symbolic


def test_bad_parameters_are_named() -> None:
    with pytest.raises(ValueError, match=r"alpha1\.\.alpha4 must sum to 1"):
        make_model("gms", params={"alpha1": 0.5})
    with pytest.raises(ValueError, match="k2"):
        make_model("gms", params={"k2": 0.0})
    with pytest.raises(ValueError, match="alpha3"):
        make_model("gms", params={"alpha3": 1.5})
    with pytest.raises(ValueError, match="number of elements"):
        gms_class(0)


def test_steady_state_is_the_stribeck_curve() -> None:
    params = {"Fc_pos": 1.0, "Fc_neg": 1.2, "Fs_pos": 1.6, "Fs_neg": 1.5, "vs": 2e-3,
              "n": 1.5, "sigma2": 3.0}
    m = make_model("gms", params=params)
    v = np.array([-0.05, -3e-3, -1e-4, 1e-4, 1e-3, 0.02])
    expected = np.where(v > 0, stribeck(v, 1.0, 1.6, 2e-3, 1.5),
                        -stribeck(v, 1.2, 1.5, 2e-3, 1.5)) + 3.0 * v
    np.testing.assert_allclose(m.steady_state(v), expected, rtol=1e-13)
    for vi, Fi in zip(v, expected, strict=True):
        t = np.linspace(0.0, 5e-3 / abs(vi), 2001)  # 5 mm: ~80 slip lengths alpha_i*g/k_i
        run = friction_along_motion(m, t, np.full(t.size, vi))
        assert run.F[-1] == pytest.approx(Fi, rel=1e-8)


def test_numeric_and_symbolic_forms_agree() -> None:
    m = make_model("gms", params={"Fc_pos": 1.0, "Fc_neg": 0.8, "Fs": 1.5})
    rng = np.random.default_rng(0)
    for symbolic_params in (False, True):
        fns = m.casadi_functions(symbolic_params=symbolic_params)
        pv = list(m.flat_params().values())
        P = m.param_values(NUMPY)
        for _ in range(20):
            x = rng.normal(0.0, 2e-5, 4)
            v = rng.normal(0.0, 0.01)
            sig = [v, rng.normal(), 0.1, 1e5, 2e5, 1.0 if v > 0 else -1.0]
            args = [x, sig, pv] if symbolic_params else [x, sig]
            dx_sym = np.asarray(fns["rhs"](*args)).ravel()
            F_sym = float(fns["force"](*args))
            s = Signals(*sig)
            np.testing.assert_allclose(dx_sym, m.rhs(NUMPY, list(x), s, P), rtol=1e-12,
                                       atol=1e-15)
            assert F_sym == pytest.approx(float(m.force(NUMPY, list(x), s, P)), rel=1e-12)
    # the force is linear in the states: its Jacobian is k_i + sigma1*d(dz_i/dt)/dz_i
    xs = ca.SX.sym("x", 4)
    sig, sigv = Signals.symbolic()
    F = m.force(CASADI, [xs[i] for i in range(4)], sig, m.param_values(CASADI))
    J = ca.Function("J", [xs, sigv], [ca.jacobian(F, xs)])
    np.testing.assert_allclose(np.asarray(J(np.zeros(4), [0.0, 0, 0, 0, 0, 1])).ravel(), K)


def test_exact_along_monotone_legs() -> None:
    """The engine reproduces the element closed form (piecewise-constant velocity)."""
    m = make_model("gms", params=RATE_INDEPENDENT)
    path = [0.0, 60e-6, 20e-6, 35e-6, 20e-6, -60e-6]
    np.testing.assert_allclose(legs(m, path), closed_form(path), rtol=1e-9, atol=1e-12)


def test_nonlocal_memory() -> None:
    """Equal force now, different past extremes: GMS remembers them, LuGre cannot.

    History 1 goes up to 100 um, history 2 to 15 um; each then comes down to
    where the force is zero. Going on down by 10 um, the GMS forces differ,
    while for LuGre (one state, F = sigma0*z) equal force means equal state.
    """
    m = make_model("gms", params=RATE_INDEPENDENT)
    lugre = make_model("lugre", params={"Fc": 1.0, "Fs": 1.0, "sigma0": 1e5, "sigma1": 0.0,
                                        "sigma2": 0.0})

    def zero_crossing(top: float, k: np.ndarray, alpha: np.ndarray) -> float:
        return brentq(lambda xb: closed_form([0.0, top, xb], k, alpha)[-1], -top, top,
                      xtol=1e-16)

    futures = {}
    for name, model, k, alpha in (("gms", m, K, ALPHA),
                                  ("lugre", lugre, np.array([1e5]), np.array([1.0]))):
        out = []
        for top in (100e-6, 15e-6):
            xb = zero_crossing(top, k, alpha)
            F = legs(model, [0.0, top, xb, xb - 10e-6], n=200)
            assert F[1] == pytest.approx(0.0, abs=1e-9)
            out.append(F[2])
        futures[name] = out
    assert abs(futures["gms"][0] - futures["gms"][1]) > 0.05
    assert futures["lugre"][0] == pytest.approx(futures["lugre"][1], abs=1e-9)


def test_approximates_maxwell_slip_better_than_lugre() -> None:
    """Nested loops: GMS follows the ideal Maxwell-slip model (exact return-point memory)
    much more closely than a one-state LuGre with the same stiffness and level."""
    path = [0.0, 60e-6, -60e-6, 30e-6, -10e-6, 20e-6, 0.0, 40e-6, -60e-6, 60e-6]
    n = 60

    def ideal(k: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        Fi = np.zeros_like(k)
        out, x_prev = [], path[0]
        for a, b in zip(path[:-1], path[1:], strict=True):
            for x in np.linspace(a, b, n + 1)[1:]:
                Fi = np.clip(Fi + k * (x - x_prev), -alpha, alpha)
                x_prev = x
                out.append(Fi.sum())
        return np.array(out)

    def model_curve(model: object) -> np.ndarray:
        x0 = model.initial_state()  # type: ignore[attr-defined]
        out = []
        for a, b in zip(path[:-1], path[1:], strict=True):
            t = np.linspace(0.0, abs(b - a) / 1e-4, n + 1)
            run = friction_along_motion(model, t, np.full(t.size, math.copysign(1e-4, b - a)),
                                        state0=x0)
            x0 = run.states[-1]
            out += list(run.F[1:])
        return np.array(out)

    ms = ideal(K, ALPHA)
    gms = model_curve(make_model("gms", params=RATE_INDEPENDENT))
    lugre = model_curve(make_model("lugre", params={"Fc": 1.0, "Fs": 1.0, "sigma0": 1e5,
                                                    "sigma1": 0.0, "sigma2": 0.0}))
    rms_gms = np.sqrt(np.mean((gms - ms) ** 2))
    rms_lugre = np.sqrt(np.mean((lugre - ms) ** 2))
    assert rms_gms < 0.7 * rms_lugre
    assert rms_gms < 0.2  # N, with Fs = 1 N


def test_other_element_counts_and_effects() -> None:
    cls = gms_class(2)
    m = cls({"k1": 5e4, "k2": 5e4, "alpha1": 0.25, "alpha2": 0.75})
    assert m.state_names == ("z1", "z2")
    assert float(m.steady_state(0.01)) == pytest.approx(
        float(stribeck(np.array(0.01), 1.0, 1.5, 1e-3, 2.0)) + 0.4 * 0.01, rel=1e-12)
    g = make_model("gms", effects=["pressure-dependence"]).with_params(kp=1e-6)
    t = np.linspace(0.0, 1.0, 1001)
    run = friction_along_motion(g, t, np.full(t.size, 0.05), p1=2e5)
    assert run.F[-1] == pytest.approx((1.0 * 1.2) + 0.4 * 0.05, rel=1e-6)  # Fc*(1 + kp*p1)
    with pytest.raises(ValueError, match="does not apply"):
        make_model("gms").with_effects("frictional-lag")


def test_passivity_bound() -> None:
    info = make_model("gms").passivity()
    assert info["applies"] and info["v_max"] == pytest.approx(4 * 0.1 * 1.0 / 316.227766)
    assert make_model("gms", params={"sigma1": 0.0}).passivity()["passive"] is True
