"""The LuGre family of friction models (issue 2): equations, invariants, bad input.

* numeric (NUMPY) and symbolic (CasADi) forms agree at random states and
  signals, for every model with every catalogue effect; the CasADi
  Jacobians are finite at ``v = 0`` and equal finite differences elsewhere;
* static maps equal a hand-written formula of models.md 1.1; every dynamic
  model driven long enough at constant velocity settles on its
  ``steady_state`` map, which equals the hand-written formula too;
* NMLGM along a reversing motion agrees with an independent integration;
* Olsson's bound ``|z| <= Fs/sigma0`` holds under random motions;
* the passivity condition ``sigma1*|v| <= 4*g(v)`` of :meth:`LuGreFamily.passivity`:
  dissipation is non-negative within ``v_max`` and a motion beyond it makes
  it negative, which ``passivity()`` flags;
* bad names and parameters raise a ``ValueError`` naming them.

SI units: m, m/s, m/s^2, Pa, N, N/m, Ns/m, s.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import casadi as ca
import numpy as np
import pytest
from helpers import reference_lugre as ref

from fcomp.backend import NUMPY
from fcomp.effects import make_effect
from fcomp.effects.structural import StructuralEffect
from fcomp.errors import UnknownNameError
from fcomp.models import MODELS, FrictionModel, Signals, make_model
from fcomp.models.lugre_family import PRESETS, LuGreFamily
from fcomp.parameters import Directional
from fcomp.trajectory import friction_along_motion

FAMILY = tuple(PRESETS)  # coulomb ... nmlgm
DYNAMIC = ("dahl", "lugre", "modified-lugre", "nmlgm")

#: non-default effect parameters, so that every effect acts
EFFECT_PARAMS: dict[str, dict[str, float]] = {
    "viscous": {"sigma2": 3.0},
    "stribeck": {"Fs_excess": 2.0, "vs": 0.01, "n": 1.5},
    "presliding": {"sigma0": 2e4, "sigma1": 5.0},
    "frictional-lag": {"vb": 0.03, "tau_hp": 0.02, "tau_hn": 0.1, "tau_h0": 5.0},
    "dwell-time": {"dFs": 3.0, "tau_dwell": 0.5, "L_dwell": 1e-3},
    "direction-asymmetry": {"r_neg": 1.3},
    "pressure-dependence": {"kp": 1e-6, "p_ref": 2e5},
    "position-dependence": {"kx1": 0.1, "kx2": -0.05, "kx3": 0.02},
    "viscous-lead": {"T": 0.01},
    "inertia-error": {"dm": 0.3},
    "force-offset": {"offset": 1.5},
}
ADD_ONS = ("dwell-time", "direction-asymmetry", "pressure-dependence", "position-dependence",
           "inertia-error", "force-offset")


def attachable(effect: str, model: FrictionModel) -> bool:
    """Whether ``effect`` applies to ``model`` and the terms it needs are there."""
    eff = make_effect(effect)
    if not eff.applies_to(model):
        return False
    if isinstance(eff, StructuralEffect):
        needs = set(eff.requires) | ({"stribeck"} if effect == "frictional-lag" else set())
        return needs <= set(model.features)  # type: ignore[attr-defined]
    return True


def _variants() -> list[tuple[str, FrictionModel]]:
    """Every family model (directional seed 000 parameters), alone, with each effect, with all add-ons."""
    out = []
    for name in FAMILY:
        base = make_model(name, params="seed000-cylinder1")
        out.append((name, base))
        for eff in EFFECT_PARAMS:
            if attachable(eff, base):
                out.append((f"{name}+{eff}", base.with_effects(make_effect(eff, EFFECT_PARAMS[eff]))))
        out.append((f"{name}+add-ons", base.with_effects(
            *[make_effect(e, EFFECT_PARAMS[e]) for e in ADD_ONS])))
    return out


VARIANTS = _variants()
VARIANT_IDS = [n for n, _ in VARIANTS]


def _fs_max(model: FrictionModel) -> float:
    flat = model.flat_params()
    return max(v for k, v in flat.items() if k.split("_")[0] in ("Fs", "Fc"))


def _random_states(model: FrictionModel, rng: np.random.Generator, n: int) -> np.ndarray:
    cols = []
    for name in model.state_names:
        if name == "z":
            cols.append(rng.uniform(-1.2, 1.2, n) * _fs_max(model) / model.flat_params()["sigma0"])
        else:  # film h, dwell age w: fractions
            cols.append(rng.uniform(0.0, 1.0, n))
    return np.array(cols).reshape(model.n_states, n)


def _random_signals(rng: np.random.Generator, n: int) -> np.ndarray:
    """Rows v, a, x, p1, p2, s: speeds from 0 to 0.3 m/s incl. exact zero and thresholds."""
    special = [0.0, 1e-12, -1e-12, 1e-5, -1e-5, 0.037, -0.025, 0.01, -0.055]
    mags = 10 ** rng.uniform(-7, -0.5, n - len(special))
    v = np.concatenate([special, mags * rng.choice([-1.0, 1.0], mags.size)])
    return np.vstack([
        v,
        rng.normal(0.0, 2.0, n),
        rng.uniform(0.0, 0.3, n),
        rng.uniform(0.0, 6e5, n),
        rng.uniform(0.0, 6e5, n),
        rng.choice([-1.0, 1.0], n),  # side: both parameter sets at every speed
    ])


def _numeric(model: FrictionModel, X: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(dx/dt (nx, n), F (n,))`` from the NUMPY backend, vectorised over samples."""
    P = model.param_values(NUMPY)
    sig = Signals(*S)
    n = S.shape[1]
    xs = [X[i] for i in range(model.n_states)]
    dx = model.rhs(NUMPY, xs, sig, P)
    D = np.array([np.broadcast_to(np.asarray(d, dtype=float), (n,)) for d in dx]).reshape(-1, n)
    F = np.broadcast_to(np.asarray(model.force(NUMPY, xs, sig, P), dtype=float), (n,))
    return D, F


# ---------------------------------------------------------- numeric = symbolic
@pytest.mark.parametrize(("label", "model"), VARIANTS, ids=VARIANT_IDS)
def test_numeric_and_symbolic_forms_agree(label: str, model: FrictionModel) -> None:
    rng = np.random.default_rng(abs(hash(label)) % 2**32)
    n = 300
    X, S = _random_states(model, rng, n), _random_signals(rng, n)
    D, F = _numeric(model, X, S)
    fns = model.casadi_functions()
    F_sym = np.asarray(fns["force"].map(n)(X, S)).ravel()
    np.testing.assert_allclose(F, F_sym, rtol=1e-12, atol=1e-12)
    if model.n_states:
        D_sym = np.asarray(fns["rhs"].map(n)(X, S))
        np.testing.assert_allclose(D, D_sym, rtol=1e-12, atol=1e-15)
    parts = np.asarray(fns["force_parts"].map(n)(X, S))
    np.testing.assert_allclose(parts[0] + parts[1] * S[1], F, rtol=1e-12, atol=1e-12)


def test_symbolic_parameters_give_the_same_functions() -> None:
    model = make_model("nmlgm", params="seed000-cylinder1").with_effects(
        make_effect("pressure-dependence", EFFECT_PARAMS["pressure-dependence"]))
    rng = np.random.default_rng(3)
    X, S = _random_states(model, rng, 50), _random_signals(rng, 50)
    p = np.array(list(model.flat_params().values()))
    fixed, free = model.casadi_functions(), model.casadi_functions(symbolic_params=True)
    for k in ("rhs", "force"):
        a = np.asarray(fixed[k].map(50)(X, S))
        b = np.asarray(free[k].map(50)(X, S, np.repeat(p[:, None], 50, axis=1)))
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-16)


def _jacobian_function(model: FrictionModel) -> ca.Function:
    """``(x, [v, a, x, p1, p2], s) -> d[dx/dt; F]/d[x; v, a, x, p1, p2]``."""
    fns = model.casadi_functions()
    xs, u, s = ca.SX.sym("x", model.n_states), ca.SX.sym("u", 5), ca.SX.sym("s")
    sig = ca.vertcat(u, s)
    out = ca.vertcat(fns["rhs"](xs, sig), fns["force"](xs, sig))
    return ca.Function("J", [xs, u, s], [ca.jacobian(out, ca.vertcat(xs, u))])


@pytest.mark.parametrize(("label", "model"), VARIANTS, ids=VARIANT_IDS)
def test_jacobians_finite_at_rest(label: str, model: FrictionModel) -> None:
    rng = np.random.default_rng(7)
    J = _jacobian_function(model)
    for s in (1.0, -1.0):
        for X in _random_states(model, rng, 5).T:
            u = [0.0, rng.normal(), 0.1, 2e5, 1e5]
            val = np.asarray(J(X, u, s))
            assert np.all(np.isfinite(val)), f"{label}: Jacobian at v = 0 not finite"


@pytest.mark.parametrize(("label", "model"), VARIANTS, ids=VARIANT_IDS)
def test_jacobians_match_finite_differences(label: str, model: FrictionModel) -> None:
    """Central differences of the NUMPY form, away from the kinks (v = 0, vb, h = h_ss)."""
    rng = np.random.default_rng(11)
    J = _jacobian_function(model)
    nx = model.n_states
    flat = model.flat_params()
    kinks = [flat[k] for k in flat if k.startswith("vb")]
    P = model.param_values(NUMPY)
    scales = [(_fs_max(model) / flat["sigma0"]) if n == "z" else 1.0 for n in model.state_names]
    scales += [1e-2, 1.0, 0.1, 1e5, 1e5]
    checked = 0
    while checked < 12:
        v = rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-2.7, -0.5)
        if any(abs(abs(v) - k) < 2e-3 for k in kinks):
            continue
        X = _random_states(model, rng, 1)[:, 0]
        s = 1.0 if v > 0 else -1.0
        u = np.array([v, rng.normal(), rng.uniform(0, 0.3), rng.uniform(0, 6e5),
                      rng.uniform(0, 6e5)])
        if "h" in model.state_names and isinstance(model, LuGreFamily):
            sig = Signals(v=u[0], a=u[1], x=u[2], p1=u[3], p2=u[4], s=s)
            L = model.levels(NUMPY, list(X), sig, P)
            hss = float(model.h_ss(NUMPY, v, P, L, s))
            if abs(X[model.state_names.index("h")] - hss) < 1e-3:
                continue
        point = np.concatenate([X, u])

        def f(pt: np.ndarray, s: float = s) -> np.ndarray:
            D, F = _numeric(model, pt[:nx, None], np.concatenate([pt[nx:], [s]])[:, None])
            return np.concatenate([D[:, 0], F])

        fd = np.empty((nx + 1, nx + 5))
        steps = 1e-6 * np.asarray(scales)
        for j in range(nx + 5):
            e = np.zeros(nx + 5)
            e[j] = steps[j]
            fd[:, j] = (f(point + e) - f(point - e)) / (2 * steps[j])
        exact = np.asarray(J(X, u, s))
        # rounding of a central difference: about eps*|f|/step (allow 20x); and entries far
        # below their row's largest scaled sensitivity are swamped by rounding of the
        # intermediate terms, so they are checked to 1e-7 of that
        rounding = 20 * np.finfo(float).eps * np.abs(f(point))[:, None] / steps[None, :]
        sc = np.asarray(scales)
        row = 1e-7 * (np.abs(exact) * sc[None, :]).max(axis=1, keepdims=True) / sc[None, :]
        assert np.all(np.abs(fd - exact) <= 1e-5 * np.abs(exact) + rounding + row + 1e-12), (
            f"{label} at v = {v:g}:\nFD {fd}\nexact {exact}")
        checked += 1


# --------------------------------------------------------------- static maps
def _side(v: float) -> str:
    return "pos" if v > 0 else "neg"


SPEEDS = (-0.3, -0.06, -0.03, -0.012, -3e-3, -2e-4, -2e-5, 2e-5, 2e-4, 3e-3, 0.012, 0.03, 0.06, 0.3)


@pytest.mark.parametrize("params", ["seed000-cylinder1", "seed002-type1"])
def test_static_maps_equal_models_md_formulas(params: str) -> None:
    """models.md 1.1 written out by hand in reference_lugre, for |v| > v_eps."""
    v = np.array(SPEEDS)
    for name in ("coulomb", "coulomb-viscous", "stribeck"):
        model = make_model(name, params=params)
        flat = model.flat_params()

        def p(key: str, side: str, flat: dict = flat) -> float:
            return flat.get(key, flat.get(f"{key}_{side}", math.nan))

        F = model.steady_state(v)
        for vi, Fi in zip(v, F, strict=True):
            sd = _side(vi)
            if name == "coulomb":
                want = ref.coulomb(vi, p("Fc", sd))
            elif name == "coulomb-viscous":
                want = ref.coulomb_viscous(vi, p("Fc", sd), p("B", sd))
            else:
                want = ref.stribeck_map(vi, p("Fc", sd), p("Fs", sd), p("vs", sd), p("n", sd),
                                        p("sigma2", sd), p("vb", sd))
            assert Fi == pytest.approx(want, rel=1e-13, abs=1e-13), (name, vi)


def test_stribeck_without_film_is_the_classical_curve() -> None:
    model = make_model("stribeck", params="canudas1995").with_params(vb=math.inf)
    for v in SPEEDS:
        want = ref.stribeck_map(v, 1.0, 1.5, 1e-3, 2.0, 0.4)
        assert float(model.steady_state(v)) == pytest.approx(want, rel=1e-13)


def test_static_map_regularisation_below_v_eps() -> None:
    """Documented regularisation: ``F = (v/v_eps)*g(v) + sigma2*v`` for ``|v| < v_eps``."""
    model = make_model("stribeck", params="canudas1995").with_params(vb=math.inf)
    v_eps = model.flat_params()["v_eps"]
    for v in (-0.9e-5, -3e-6, 0.0, 1e-7, 5e-6):
        g = 1.0 + 0.5 * math.exp(-((abs(v) / 1e-3) ** 2))
        assert float(model.steady_state(v)) == pytest.approx(v / v_eps * g + 0.4 * v, abs=1e-14)


# -------------------------------------------------------------- steady state
STEADY_CASES = [
    ("dahl", "seed000-cylinder1", ()),
    ("lugre", "canudas1995", ()),
    ("lugre", "seed000-cylinder1", ()),
    ("modified-lugre", "seed000-cylinder1", ()),
    ("nmlgm", "seed000-cylinder1", ()),
    ("nmlgm", "seed002-type1", ()),
    ("lugre", "canudas1995", ("dwell-time", "pressure-dependence", "position-dependence")),
]


@pytest.mark.parametrize(("name", "params", "effects"), STEADY_CASES,
                         ids=[f"{n}-{p}-{'+'.join(e) or 'plain'}" for n, p, e in STEADY_CASES])
def test_long_run_force_equals_steady_state_map(name: str, params: str, effects: tuple) -> None:
    model = make_model(name, params=params).with_effects(
        *[make_effect(e, EFFECT_PARAMS[e]) for e in effects])
    flat = model.flat_params()
    p1, p2, x = 3e5, 1e5, 0.12
    for v in (-0.2, -0.03, -0.005, -0.001, 0.001, 0.005, 0.03, 0.2):
        # slowest state: the bristles, time constant g/(sigma0*|v|) <= Fs/(sigma0*|v|)
        tau = max(_fs_max(model) * 2 / (flat["sigma0"] * abs(v)), 0.2, flat.get("tau_dwell", 0))
        t = np.linspace(0.0, 60 * tau, 6001)
        run = friction_along_motion(model, t, np.full_like(t, v), x=np.full_like(t, x),
                                    p1=p1, p2=p2)
        want = float(model.steady_state(v, x=x, p1=p1, p2=p2))
        assert run.F[-1] == pytest.approx(want, rel=1e-9, abs=1e-9), (name, v)


def _reference_of(model: FrictionModel) -> ref.LuGreRef | ref.FilmLuGreRef:
    if model.name == "lugre" and not model.params.is_directional():
        flat = model.flat_params()
        return ref.LuGreRef(**{k: flat[k] for k in
                               ("Fc", "Fs", "vs", "n", "sigma0", "sigma1", "sigma2")})
    params: dict[str, float | tuple[float, float]] = {}
    for s in type(model.params).SPECS:
        val = getattr(model.params, s.name)
        params[s.name] = val.values() if isinstance(val, Directional) else float(val)
    return ref.FilmLuGreRef(params)


@pytest.mark.parametrize(("name", "params"), [("lugre", "canudas1995"),
                                              ("modified-lugre", "seed000-cylinder1"),
                                              ("nmlgm", "seed000-cylinder1"),
                                              ("nmlgm", "seed002-type1")])
def test_steady_state_map_equals_hand_formula(name: str, params: str) -> None:
    """``F_ss = sign(v)*g(v, h_ss(v)) + sigma2*v`` (models.md 1.3-1.5), written independently."""
    model = make_model(name, params=params)
    r = _reference_of(model)
    for v in SPEEDS:
        assert float(model.steady_state(v)) == pytest.approx(r.steady(v), rel=1e-13), v


def test_dahl_steady_state_is_coulomb_viscous() -> None:
    model = make_model("dahl", params="seed000-cylinder1")
    for v in SPEEDS:
        want = ref.coulomb_viscous(v, 5.5 if v > 0 else 5.8, 25.0)
        assert float(model.steady_state(v)) == pytest.approx(want, rel=1e-13)


def test_nmlgm_along_reversing_motion_matches_independent_integration() -> None:
    """Film state, its three time constants, directional sides and the lead term ``T``.

    ``v = 0.08*sin(pi*t) + 0.01`` m/s over one period (two reversals), 20 kHz.
    The sampled scheme is first order where the film time constant switches
    (``|v| < v_eps`` for an instant at each reversal): 1.3e-3 N at 20 kHz on
    forces of 8 N; a wrong term gives errors of order newtons.
    """
    model = make_model("nmlgm", params="seed000-cylinder1").with_params(T=0.01)
    r = _reference_of(model)
    assert isinstance(r, ref.FilmLuGreRef)
    w = math.pi
    t = np.linspace(0.0, 2.0, 40001)
    v, a = 0.08 * np.sin(w * t) + 0.01, 0.08 * w * np.cos(w * t)
    run = friction_along_motion(model, t, v, a=a)
    tr = ref.along_velocity(r, lambda tt: 0.08 * math.sin(w * tt) + 0.01, t)
    s = np.where(v >= 0, 1.0, -1.0)
    F_ref = np.array([r.friction(z, h, vv, aa, ss)
                      for z, h, vv, aa, ss in zip(*tr.y, v, a, s, strict=True)])
    assert np.abs(run.states[:, 0] - tr.y[0]).max() < 2e-7  # m, z up to 1.7e-3
    assert np.abs(run.states[:, 1] - tr.y[1]).max() < 2e-4  # film h in [0, 0.78]
    assert np.abs(run.F - F_ref).max() < 3e-3


# ----------------------------------------------------------- Olsson's bound
def _random_profile(rng: np.random.Generator, n: int = 20_000) -> tuple[np.ndarray, np.ndarray]:
    """Non-uniform sample times; steps, creeps, reversals and a sine, up to 0.5 m/s."""
    dt = rng.uniform(1e-5, 2e-3, n - 1)
    t = np.concatenate([[0.0], np.cumsum(dt)])
    levels = rng.choice([-1.0, 1.0], 40) * 10 ** rng.uniform(-7, np.log10(0.5), 40)
    v = levels[np.minimum((t / t[-1] * 40).astype(int), 39)]
    v = v + 0.05 * np.sin(2 * np.pi * rng.uniform(0.5, 20) * t) * rng.choice([0.0, 1.0])
    return t, v


@pytest.mark.parametrize(("name", "params"), [("lugre", "canudas1995"), ("lugre", "seed002-type1"),
                                              ("modified-lugre", "seed000-cylinder1"),
                                              ("nmlgm", "seed000-cylinder1")])
def test_bristle_deflection_stays_within_olsson_bound(name: str, params: str) -> None:
    """``|z(0)| <= Fs/sigma0`` implies ``|z(t)| <= Fs/sigma0`` (Olsson; g <= Fs since h >= 0)."""
    model = make_model(name, params=params)
    flat = model.flat_params()
    bound = max(v for k, v in flat.items() if k.startswith("Fs")) / flat["sigma0"]
    rng = np.random.default_rng(2024)
    for z0 in (bound, -bound, 0.0, rng.uniform(-bound, bound)):
        t, v = _random_profile(rng)
        x0 = model.initial_state()
        x0[0] = z0
        run = friction_along_motion(model, t, v, state0=x0)
        assert np.abs(run.states[:, 0]).max() <= bound * (1 + 1e-12)


def test_olsson_bound_in_continuous_time_and_tight() -> None:
    """Radau on the package's numeric equations, random smooth motion from ``z = Fs/sigma0``."""
    model = make_model("lugre", params="canudas1995")
    P = model.param_values(NUMPY)
    bound = 1.5 / 1e5
    rng = np.random.default_rng(5)
    amp, freq, phase = rng.uniform(0, 0.02, 4), rng.uniform(2, 20, 4), rng.uniform(0, 6.3, 4)

    def v_of(t: float) -> float:
        return float(np.sum(amp * np.sin(2 * np.pi * freq * t + phase)))

    def fun(t: float, y: np.ndarray) -> list[float]:
        v = v_of(t)
        return model.rhs(NUMPY, [y[0]], Signals(v=v, s=1.0 if v >= 0 else -1.0), P)

    t = np.linspace(0.0, 0.25, 5001)
    tr = ref.solve_radau(fun, (0.0, 0.25), [bound], t, atol=(1e-19,))
    assert np.abs(tr.y[0]).max() <= bound * (1 + 1e-9)
    # tight: creeping at 1 um/s (time constant 15 s) the deflection approaches Fs/sigma0
    tc = np.linspace(0.0, 600.0, 601)
    run = friction_along_motion(model, tc, np.full_like(tc, 1e-6))
    assert run.states[-1, 0] == pytest.approx(bound, rel=1e-6)


# --------------------------------------------------------------- passivity
def _dissipation(model: FrictionModel, velocities: Sequence[float] | np.ndarray,
                 durations: Sequence[float] | np.ndarray, samples: int = 4000) -> np.ndarray:
    """``D(t) = int v*(sigma0*z + sigma1*dz/dt) dt - sigma0*z^2/2`` (J) along piecewise-constant v.

    Integrated with Radau on the package's numeric equations, from ``z = 0``.
    The bristle force is the model's force minus its viscous term.
    """
    P = model.param_values(NUMPY)
    sigma0 = model.flat_params()["sigma0"]
    visc = model.flat_params().get("sigma2", 0.0)

    def piece(v: float) -> Callable[[float, np.ndarray], list[float]]:
        sig = Signals(v=v, s=1.0 if v >= 0 else -1.0)

        def fun(t: float, y: np.ndarray) -> list[float]:
            dz = model.rhs(NUMPY, [y[0]], sig, P)[0]
            Fb = model.force(NUMPY, [y[0]], sig, P) - visc * v
            return [dz, v * Fb - sigma0 * y[0] * dz]

        return fun

    edges = np.concatenate([[0.0], np.cumsum(durations)])
    t = np.unique(np.concatenate([np.linspace(0.0, edges[-1], samples), edges]))
    tr = ref.solve_radau([piece(v) for v in velocities], (0.0, float(edges[-1])), [0.0, 0.0], t,
                         atol=(1e-19, 1e-16), breaks=list(edges[1:-1]))
    return tr.y[1]


def test_passivity_identity_of_the_docstring() -> None:
    """``v*(sigma0 z + sigma1 dz) - sigma0 z dz = sigma1 dz^2 + sigma1 a z dz + sigma0 a z^2``."""
    model = make_model("lugre", params="canudas1995").with_params(sigma2=0.0)
    P = model.param_values(NUMPY)
    rng = np.random.default_rng(1)
    S = _random_signals(rng, 400)
    S[5] = np.where(S[0] >= 0, 1.0, -1.0)
    z = rng.uniform(-1.5e-5, 1.5e-5, 400)
    sig = Signals(*S)
    dz = model.rhs(NUMPY, [z], sig, P)[0]
    lhs = S[0] * model.force(NUMPY, [z], sig, P) - 1e5 * z * dz
    g = 1.0 + 0.5 * np.exp(-((S[0] / 1e-3) ** 2))
    alpha = 1e5 * np.abs(S[0]) / g
    s1 = model.flat_params()["sigma1"]  # the set's 316.2277660 (sqrt(1e5) to 10 digits)
    rhs = s1 * dz**2 + s1 * alpha * z * dz + 1e5 * alpha * z**2
    terms = (np.abs(S[0] * 1e5 * z) + np.abs(S[0] * s1 * dz) + np.abs(1e5 * z * dz)
             + s1 * dz**2 + np.abs(s1 * alpha * z * dz) + 1e5 * alpha * z**2)
    assert np.all(np.abs(lhs - rhs) <= 1e-12 * terms + 1e-20)


def test_lugre_dissipates_within_v_max() -> None:
    """Random piecewise-constant motions (jumps included) with ``|v| <= v_max``: D(t) >= 0, rising."""
    model = make_model("lugre", params="canudas1995")
    info = model.passivity()
    assert info["applies"] and info["passive"] is None
    vmax = info["v_max"]
    assert vmax == pytest.approx(4 * 1.0 / math.sqrt(1e5))
    rng = np.random.default_rng(8)
    for _ in range(2):
        vs = rng.choice([-1.0, 1.0], 8) * rng.uniform(0.0, 1.0, 8) ** 3 * vmax
        vs[rng.integers(0, 8, 3)] = vmax * rng.choice([-1.0, 1.0], 3)  # the edge itself
        D = _dissipation(model, vs, rng.uniform(1e-4, 5e-3, 8), samples=2000)
        assert D.min() >= -1e-15
        assert np.all(np.diff(D) >= -1e-15), "bristle power must be non-negative pointwise"


def test_lugre_beyond_v_max_returns_energy_and_is_flagged() -> None:
    """Creep to load the bristles, then jump to 0.1 m/s (8 v_max): D(t) goes negative.

    After the jump ``z`` exceeds its new steady value ``g/sigma0`` and falls
    at nearly ``-v``: with ``r = sigma0*z/g > 1`` the bristle power is
    ``sigma1*v^2*(1 - r) + g*v*r^2 < 0`` once ``sigma1*v > g*r^2/(r - 1)``.
    """
    model = make_model("lugre", params="canudas1995")
    D = _dissipation(model, [1e-4, 0.1], [0.3, 2e-3], samples=20000)
    assert D.min() < -1e-5  # J (about -3.7e-5 J)
    info = model.passivity()
    assert info["passive"] is None and info["v_max"] < 0.1
    assert "flag" in info["reason"]


def test_v_max_is_sufficient_but_conservative() -> None:
    """Within Olsson's set ``|z| <= Fs/sigma0`` the power is non-negative up to
    ``min_{1 < r <= Fs/g} g*r^2/((r - 1)*sigma1)`` = 4.5*Fc/sigma1 here, above
    ``v_max = 4*Fc/sigma1``: between the two no reachable state returns energy."""
    p = ref.CANUDAS
    for v in np.linspace(1e-4, 4.45 / p.sigma1, 300):
        for z in np.linspace(-p.Fs / p.sigma0, p.Fs / p.sigma0, 301):
            dz = p.zdot(z, v)
            assert v * (p.sigma0 * z + p.sigma1 * dz) - p.sigma0 * z * dz >= -1e-15


def test_dahl_is_passive_at_any_speed() -> None:
    model = make_model("dahl", params="seed000-cylinder1")
    info = model.passivity()
    assert info["passive"] is True and math.isinf(info["v_max"])
    D = _dissipation(model, [1e-4, 1.0, -0.5], [0.3, 2e-3, 2e-3])
    assert D.min() >= -1e-15 and np.all(np.diff(D) >= -1e-15)


@pytest.mark.parametrize("name", ["coulomb", "coulomb-viscous", "stribeck"])
def test_static_maps_are_passive(name: str) -> None:
    model = make_model(name, params="seed000-cylinder1")
    assert model.passivity()["passive"] is True
    v = np.linspace(-0.3, 0.3, 601)
    assert np.all(v * model.steady_state(v) >= 0.0)


# ---------------------------------------------------------------- bad input
def test_every_family_model_is_registered() -> None:
    assert set(FAMILY) <= set(MODELS.names())
    assert FAMILY == ("coulomb", "coulomb-viscous", "stribeck", "dahl", "lugre",
                      "modified-lugre", "nmlgm")


def test_unknown_model_is_a_clear_error() -> None:
    with pytest.raises(UnknownNameError, match=r"unknown friction model 'lugr'.*lugre"):
        make_model("lugr")


def test_unknown_parameter_set_is_a_clear_error() -> None:
    with pytest.raises(UnknownNameError, match=r"unknown parameter set 'canudas'.*canudas1995"):
        make_model("lugre", params="canudas")


@pytest.mark.parametrize(("values", "name"), [
    ({"sigma0": -1e5}, "sigma0"),
    ({"sigma0": 0.0}, "sigma0"),
    ({"sigma1": -1.0}, "sigma1"),
    ({"Fc": -1.0}, "Fc"),
    ({"Fc": 2.0, "Fs": 1.5}, "Fc"),
    ({"vs": 0.0}, "vs"),
    ({"n": 12.0}, "n"),
    ({"sigma2": math.nan}, "sigma2"),
])
def test_out_of_bounds_parameter_raises_value_error_naming_it(values: dict, name: str) -> None:
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        make_model("lugre", params=values)
    base = make_model("lugre", params="canudas1995")
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        base.with_params(**values)


def test_fs_below_fc_on_one_side_names_the_side() -> None:
    base = make_model("nmlgm", params="seed000-cylinder1")
    with pytest.raises(ValueError, match=r"Fc = 6 must not exceed Fs = 5.*v < 0"):
        base.with_params(Fs_neg=5.0, Fc_neg=6.0)


def test_film_time_constants_must_be_positive() -> None:
    with pytest.raises(ValueError, match="tau_hn"):
        make_model("nmlgm", params={"tau_hn": 0.0})


def test_unknown_parameter_name_is_a_clear_error() -> None:
    with pytest.raises(ValueError, match=r"unknown parameter\(s\) sigma3"):
        make_model("lugre", params="canudas1995").with_params(sigma3=1.0)
    with pytest.raises(ValueError, match=r"unknown parameter\(s\) B"):
        make_model("lugre", params={"B": 1.0})


@pytest.mark.parametrize("i_pre", [0.25, 0.5, 0.8, 2.0])
def test_stiff_bristle_with_dahl_exponent_agrees_with_exact_solution(i_pre: float) -> None:
    """A hydraulic bristle (``sigma0 = 3.7e7 N/m``) with Dahl's exponent, sampled at 1 kHz.

    Below ``i = 1`` the tangent rate of ``dz/dt = v*|u|^i*sign(u)`` is ``i`` times the
    secant one, and the sampled step overshot ``z_ss`` (at ``i = 1/4`` the force
    chattered by +-1 kN on a 500 N level). The reference is the closed-form
    solution at the held interval-mean velocity: in the slid distance
    ``xi = |v|*t``, ``d|u|/dxi = -(sigma0/g)*|u|^i``, so ``|u|^(1-i)`` changes
    linearly (reaching 0 in finite slip for ``i < 1``) and ``u`` keeps its sign.
    Olsson's bound holds and the force agrees to round-off (before: by up to 1 kN).
    """
    sigma0, Fc, Fs, vs, visc = 3.7e7, 350.0, 500.0, 0.01, 1000.0
    model = make_model("stribeck").with_effects(make_effect("presliding", {
        "sigma0": sigma0, "sigma1": 0.0, "i_pre": i_pre}))
    model = model.with_params(Fc=Fc, Fs=Fs, vs=vs, n=2.0, sigma2=visc, vb=100.0)
    t = np.arange(0.0, 0.6, 1e-3)
    v = 0.05 * np.sin(2 * np.pi * 2.0 * t + 0.3)
    run = friction_along_motion(model, t, v)
    assert np.abs(run.states[:, 0]).max() * sigma0 <= Fs * (1 + 1e-9)

    z = np.zeros(t.size)
    for k in range(t.size - 1):
        vm = 0.5 * (v[k] + v[k + 1])
        s = 1.0 if vm >= 0 else -1.0
        h_ss = (1.0 - Fc / Fs) * min(abs(vm) / 100.0, 1.0) ** (2.0 / 3.0)  # film, vb = 100 m/s
        g = Fc + ((1.0 - h_ss) * Fs - Fc) * math.exp(-((abs(vm) / vs) ** 2))
        u0 = 1.0 - sigma0 * s * z[k] / g
        q = abs(u0) ** (1.0 - i_pre) - (1.0 - i_pre) * sigma0 / g * abs(vm) * (t[k + 1] - t[k])
        u = math.copysign(max(q, 0.0) ** (1.0 / (1.0 - i_pre)), u0) if i_pre < 1 else \
            math.copysign(q ** (1.0 / (1.0 - i_pre)), u0)
        z[k + 1] = s * g * (1.0 - u) / sigma0
    err = run.F - (sigma0 * z + visc * v)
    assert np.abs(err).max() < 1e-6 * Fs  # exact: both solve the same held-velocity steps


@pytest.mark.parametrize("ba", [0.0, 0.5, 0.8])
def test_elasto_plastic_bristle_agrees_with_the_independent_generator_law(ba: float) -> None:
    """The break-away deflection ``ba_pre`` (Dupont et al. 2002's elasto-plastic bristle)
    against :func:`fcomp.synthetic.dynamics.elasto_plastic`, written separately (phase by
    phase in the slid distance), along slow reversing motions of a hydraulic bristle
    (``sigma0 = 3.7e7 N/m``, 350 N) at 1 kHz: purely elastic below the break, the
    transition above, and elastic again whenever ``z`` and ``v`` have opposite signs."""
    from fcomp.synthetic.dynamics import elasto_plastic

    Fc, k = 350.0, 3.7e7
    model = make_model("coulomb").with_effects(make_effect("presliding", {
        "sigma0": k, "sigma1": 0.0, "ba_pre": ba}, form="elasto-plastic")).with_params(Fc=Fc)
    t = np.arange(0.0, 1.0, 1e-3)
    v = 2e-4 * np.sin(2 * np.pi * 1.5 * t) + 3e-4 * np.sin(2 * np.pi * 0.4 * t)
    run = friction_along_motion(model, t, v)
    vm = 0.5 * (v[1:] + v[:-1])  # the interval means both hold
    F_ref = elasto_plastic(vm, np.full(t.size, Fc), k, ba, 1e-3)
    assert np.abs(run.F[:-1] - F_ref).max() < 1e-9 * Fc
    assert np.abs(run.F).max() <= Fc * (1 + 1e-12)


def test_effects_by_name_go_through_with_effects() -> None:
    """The constructor takes effect instances; names are resolved by ``with_effects`` alone."""
    cls = type(make_model("lugre"))
    with pytest.raises(ValueError, match="with_effects"):
        cls(effects=["dwell-time"])  # type: ignore[list-item]
    by_name = make_model("lugre").with_effects("dwell-time")
    assert cls(effects=by_name.effects).describe() == by_name.describe() == "lugre + dwell-time"
