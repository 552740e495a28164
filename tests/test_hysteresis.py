"""nmlgm-hysteresis (seed 000 Eqs. 10-13) and the nonlocal-memory effect.

Independent references used here:

* the seed's Eq. 13 chain written out directly in absolute coordinates
  (``f_i(z) = f_i(z_i) + c_i*(1 - exp(-k_i*(z - z_i)))`` over the Table 2
  segments, with ``c4..6 = -c1..3``, ``k4..6 = -k1..3``), not the package's
  relative-shape code;
* the Stribeck/film steady state of seed 000 Eq. 9 from the Table 4 numbers;
* the LuGre-family models themselves (compiled engine) for the no-op effect.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fcomp.effects import make_effect
from fcomp.models import MODELS, NotSymbolicError, make_model
from fcomp.models.hysteresis import (
    MAX_POINTS,
    HysteresisFamily,
    HysteresisFunction,
    NMLGMHysteresis,
)
from fcomp.trajectory import friction_along_motion

# seed 000 Table 2 (read as metres), Table 3, Table 4 (cylinder 1)
Z1, Z2, Z3, Z4, Z5 = 1.25e-4, 0.84e-4, 1.59e-4, 1.78e-4, 2.29e-4
C1, K1, C2, K2, C3, K3, C8, K8 = 2.0, 3e5, 1.7, 3e4, 1.8, 3.4e5, 4.05, 1.8e5
ZC, ZD = 2.46e-4, 2.65e-4
SIGMA0 = 1.5e4


@pytest.fixture(scope="module")
def model() -> HysteresisFamily:
    m = make_model("nmlgm-hysteresis", params="seed000-cylinder1")
    assert isinstance(m, HysteresisFamily)
    return m


def eq13(z: float, z_start: float, F_start: float,
         segments: list[tuple[float, float, float]]) -> float:
    """Seed 000 Eq. 13 chained over absolute segment ends ``(z_end, c_i, k_i)``."""
    F, zi = F_start, z_start
    for z_end, c, k in segments:
        lo, hi = min(zi, z_end), max(zi, z_end)
        if lo <= z <= hi:
            return F + c * (1.0 - math.exp(-k * (z - zi)))
        F, zi = F + c * (1.0 - math.exp(-k * (z_end - zi))), z_end
    raise ValueError("z outside the segments")


ASC = [(0.0, C1, K1), (Z3, C2, K2), (Z5, C3, K3)]          # from -z1 upwards
DESC = [(Z4, -C1, -K1), (Z2, -C2, -K2), (-Z1, -C3, -K3)]   # from z5 downwards


# ---------------------------------------------------------------- parameters
def test_parameter_set_gives_tables_2_to_4(model: HysteresisFamily) -> None:
    p = model.flat_params()
    expected = {"z1": Z1, "z2": Z2, "z3": Z3, "z4": Z4, "z5": Z5, "c1": C1, "k1": K1,
                "c2": C2, "k2": K2, "c3": C3, "k3": K3, "c8": C8, "k8": K8,
                "internal_zc": ZC, "internal_zd": ZD, "sigma0": SIGMA0, "Fs_pos": 22.5,
                "Fs_neg": 25.0, "Fc_pos": 5.5, "sigma1": 0.1, "tau_hn": 0.15}
    for name, value in expected.items():
        assert p[name] == pytest.approx(value, rel=1e-12), name
    assert model.state_names == ("z", "h", "Fz")
    assert MODELS.get("nmlgm-hysteresis") is NMLGMHysteresis


def test_bad_parameters_are_named() -> None:
    with pytest.raises(ValueError, match="z3"):
        make_model("nmlgm-hysteresis", params={"z3": 3e-4})  # z3 > z5
    with pytest.raises(ValueError, match="c1"):
        make_model("nmlgm-hysteresis", params={"c1": -1.0})
    with pytest.raises(ValueError, match="k8"):
        make_model("nmlgm-hysteresis", params={"k8": 0.0})


def test_no_symbolic_form(model: HysteresisFamily) -> None:
    assert model.symbolic is False
    with pytest.raises(NotSymbolicError, match="memory"):
        model.casadi_functions()
    with pytest.raises(NotSymbolicError, match="memory"):
        model.rhs(None, [0.0, 0.0, 0.0], None, None)  # type: ignore[arg-type]


# ------------------------------------------------------------ curve shapes
def test_external_curves_are_seed_eq13(model: HysteresisFamily) -> None:
    """Leaving sliding at -z1 (and at z5) the curves are the seed's raw Eq. 13 chains."""
    hf = model.hysteresis_function()
    hf.move_to(-Z1, zs=Z1)  # reaches the threshold: sliding, F = sigma0*z
    assert hf.sliding and pytest.approx(-SIGMA0 * Z1) == hf.F
    F0 = hf.F
    for z in np.linspace(-Z1, Z5, 41)[1:]:
        assert hf.move_to(z) == pytest.approx(eq13(z, -Z1, F0, ASC), abs=1e-12)
    # beyond the identified range the curve continues with the bristle stiffness sigma0
    F5 = hf.F
    assert hf.move_to(Z5 + 1e-4) - F5 == pytest.approx(SIGMA0 * 1e-4, rel=1e-6)

    hf = model.hysteresis_function()
    hf.move_to(Z5, zs=Z5)
    F0 = hf.F
    for z in np.linspace(Z5, -Z1, 41)[1:]:
        assert hf.move_to(z) == pytest.approx(eq13(z, Z5, F0, DESC), abs=1e-12)


def test_raw_branches_do_not_close_but_the_model_does(model: HysteresisFamily) -> None:
    """Table 3 rises 5.486 N but falls 5.399 N: the scaled curves still close exactly."""
    rise = eq13(Z5, -Z1, 0.0, ASC)
    fall = -eq13(-Z1, Z5, 0.0, DESC)
    assert rise == pytest.approx(5.4856, abs=1e-3)
    assert fall == pytest.approx(5.3987, abs=1e-3)
    hf = model.hysteresis_function()
    A = 1.7e-4
    hf.move_to(A)
    top = [hf.F]
    bottom = [hf.move_to(-A)]
    for _ in range(10):
        top.append(hf.move_to(A))
        bottom.append(hf.move_to(-A))
    assert np.ptp(top) == 0.0 and np.ptp(bottom) == 0.0


def test_virgin_curve_is_masing_half_of_the_external_curve(model: HysteresisFamily) -> None:
    """From the virgin state F(z) = Phi(2z)/2 (Masing); a +-A cycle has the external shapes."""
    hf = model.hysteresis_function()
    for z in np.linspace(0.0, 1.7e-4, 30)[1:]:
        assert hf.move_to(z) == pytest.approx(0.5 * eq13(2 * z - Z1, -Z1, 0.0, ASC), abs=1e-12)
    FA = hf.F
    A = 1.7e-4
    # the first reversal curve ends on the mirror point of the descending virgin curve
    FmA = 0.5 * (eq13(Z5 - 2 * A, Z5, 0.0, DESC))
    assert hf.move_to(-A) == pytest.approx(FmA, abs=1e-12)
    assert hf.depth == 1  # only the virgin root: the loop is wiped out at the mirror point
    # the next ascending branch is the external shape, scaled to end exactly at (A, FA)
    assert hf.move_to(A) == pytest.approx(FA, abs=1e-12)


def test_internal_loop_uses_c8_k8_shape(model: HysteresisFamily) -> None:
    """A reversal inside the memorised range starts a c8/k8 curve scaled to its target."""
    hf = model.hysteresis_function()
    for z in (2e-4, -2e-4, 1e-4, -1e-4):  # the last two reversals: global extremes (external)
        hf.move_to(z)
    zr, Fr = hf.z, hf.F
    zt, Ft = hf.reversal_points()[-1]  # the internal curve will target the last maximum
    assert zt == 1e-4
    span = zt - zr
    w = ZD - ZC
    raw = C8 * (1 - math.exp(-K8 * w)) + SIGMA0 * (span - w)  # Eq. 13 (c8, k8) + tail
    lam = (Ft - Fr) / raw
    for z in (-0.99e-4, -0.95e-4, -0.9e-4):
        expected = Fr + lam * C8 * (1 - math.exp(-K8 * (z - zr)))
        assert hf.move_to(z) == pytest.approx(expected, abs=1e-12)
    assert hf.move_to(zt) == pytest.approx(Ft, abs=1e-12)


# ------------------------------------------------------------ memory rules
def test_minor_loop_closes_and_is_wiped_out(model: HysteresisFamily) -> None:
    hf = model.hysteresis_function()
    for z in (2e-4, -2e-4, 0.5e-4):
        hf.move_to(z)
    before = hf.snapshot()
    depth = hf.depth
    F_rev = hf.F
    hf.move_to(0.1e-4)           # minor loop down ...
    assert hf.depth == depth + 1
    assert hf.move_to(0.5e-4) == pytest.approx(F_rev, abs=1e-12)   # ... closes at its start
    assert hf.depth == depth                                        # removed from memory
    after = [hf.move_to(z) for z in np.linspace(0.5e-4, 1.8e-4, 14)[1:]]
    hf.restore(before)
    clean = [hf.move_to(z) for z in np.linspace(0.5e-4, 1.8e-4, 14)[1:]]
    np.testing.assert_allclose(after, clean, rtol=0, atol=1e-12)   # no trace left


def test_return_point_memory_with_nested_loops(model: HysteresisFamily) -> None:
    hf = model.hysteresis_function()
    hf.move_to(2.2e-4)
    hf.move_to(-2.2e-4)
    path = [1.5e-4, -1.0e-4, 1.0e-4, -0.5e-4, 0.5e-4, 0.0, 0.3e-4]
    remembered = {}
    for z in path:
        hf.move_to(z)
        remembered[z] = hf.F
    depth = hf.depth
    assert depth == 1 + len(path)  # the virgin root and one point per reversal
    # unwind: each earlier reversal point is met again at exactly its force
    for z in (0.0, 0.5e-4, -0.5e-4, 1.0e-4, -1.0e-4, 1.5e-4):
        assert hf.move_to(z) == pytest.approx(remembered[z], abs=1e-12)
    # going past the outermost point wipes all inner loops
    hf.move_to(-2.2e-4)
    assert hf.depth == 1


def test_no_drift_over_50_closed_cycles(model: HysteresisFamily) -> None:
    """A closed deflection cycle with nested minor loops, 50 times: the force repeats."""
    hf = model.hysteresis_function()
    cycle = [1.9e-4, -0.4e-4, 1.2e-4, 0.2e-4, 0.9e-4, -1.6e-4, -0.2e-4, -1.1e-4, 0.0]
    start, depths = [], []
    for _ in range(50):
        for z in cycle:
            hf.move_to(z)
        start.append(hf.F)
        depths.append(hf.depth)
    assert max(abs(F - start[1]) for F in start[1:]) < 1e-9
    assert len(set(depths[1:])) == 1


def test_sliding_switch_jump_and_return(model: HysteresisFamily) -> None:
    """|z| = Fs/sigma0 switches to sigma0*z; the jump is the tail's offset from the line."""
    hf = model.hysteresis_function()
    zs = 1.5e-3
    hf.move_to(-zs, zs=zs)
    assert hf.sliding
    z_r = -1.6e-3
    hf.move_to(z_r, zs=zs)
    assert pytest.approx(SIGMA0 * z_r) == hf.F  # sliding law
    # reversal: raw external ascending curve from (z_r, sigma0*z_r)
    z_below = zs - 1e-9
    F_below = hf.move_to(z_below, zs=zs)
    rise = eq13(Z5, -Z1, 0.0, ASC)
    expected = SIGMA0 * z_r + rise + SIGMA0 * (z_below - z_r - (Z1 + Z5))
    assert F_below == pytest.approx(expected, abs=1e-8)
    hf.move_to(zs + 1e-5, zs=zs)
    assert hf.sliding and hf.depth == 0
    jump = SIGMA0 * zs - (F_below + SIGMA0 * 1e-9)
    assert jump == pytest.approx(-(rise - SIGMA0 * (Z1 + Z5)), abs=1e-6)  # -0.176 N
    assert jump == pytest.approx(-0.1756, abs=1e-3)
    # leave sliding, make a loop, pass the exit point again: back on the sliding law
    z_exit = hf.z
    hf.move_to(z_exit - 2e-4, zs=zs)
    assert not hf.sliding
    hf.move_to(z_exit + 1e-4, zs=zs)
    assert hf.sliding and pytest.approx(SIGMA0 * (z_exit + 1e-4)) == hf.F


def test_memory_is_bounded(model: HysteresisFamily) -> None:
    hf = model.hysteresis_function()
    amp = 2e-4
    previous = None
    for k in range(400):  # slowly decaying oscillation: deeper and deeper nesting
        z = amp * (0.995 ** k) * (1 if k % 2 == 0 else -1)
        F = hf.move_to(z)
        assert hf.depth <= MAX_POINTS
        if previous is not None:  # force stays bounded by the steepest stiffness
            assert abs(F - previous[1]) <= 1.01 * C1 * K1 * abs(z - previous[0]) + 1e-12
        previous = (z, F)
    assert hf.depth >= MAX_POINTS - 2


def test_hysteresis_function_rejects_bad_settings(model: HysteresisFamily) -> None:
    with pytest.raises(ValueError, match="sigma0"):
        HysteresisFunction(model.hysteresis_function().shapes, 0.0)


# ------------------------------------------------------------ full model
def _stribeck_eq9(v: float) -> float:
    """Seed 000 Eq. 9, cylinder 1, v > 0: g(v, h_ss) + sigma2*v."""
    Fs, Fc, vs, vb, n, s2 = 22.5, 5.5, 0.01, 0.037, 2.5, 25.0
    hss = (1 - Fc / Fs) * min(v / vb, 1.0) ** (2 / 3)
    return Fc + ((1 - hss) * Fs - Fc) * math.exp(-((v / vs) ** n)) + s2 * v


def test_steady_sliding_is_seed_eq9(model: HysteresisFamily) -> None:
    for v in (0.003, 0.01, 0.02, 0.05):
        assert float(model.steady_state(v)) == pytest.approx(_stribeck_eq9(v), rel=1e-12)
        t = np.linspace(0.0, 10.0, 5001)  # >= 20 bristle time constants g/(v*sigma0)
        run = friction_along_motion(model, t, np.full(t.size, v))
        assert run.F[-1] == pytest.approx(_stribeck_eq9(v), rel=1e-6)


def test_force_is_eq11_with_the_memory_of_each_sample(model: HysteresisFamily) -> None:
    t = np.linspace(0.0, 2.0, 2001)
    v = 0.004 * np.sin(2 * np.pi * 1.5 * t) + 0.002 * np.sin(2 * np.pi * 4.0 * t)
    run = friction_along_motion(model, t, v)
    z, h, Fz = run.states.T
    s = np.where(run.s > 0, 1, 0)
    Fs, Fc = np.where(s, 22.5, 25.0), np.where(s, 5.5, 5.8)
    vs, n = np.where(s, 0.01, 0.055), np.where(s, 2.5, 1.2)
    g = Fc + ((1 - h) * Fs - Fc) * np.exp(-((np.abs(v) / vs) ** n))
    dz = v - Fz * np.abs(v) / g
    np.testing.assert_allclose(run.F, Fz + 0.1 * dz + 25.0 * v, rtol=0, atol=1e-9)
    assert np.all(np.isfinite(run.F)) and np.max(np.abs(Fz)) < 25.0
    # z follows Eq. 10: the change of z over each interval matches dz/dt (midpoint rule)
    zdot = np.diff(z) / np.diff(t)
    mid = 0.5 * (dz[1:] + dz[:-1])
    assert np.median(np.abs(zdot - mid)) < 0.05 * np.median(np.abs(mid))


def test_repeated_displacement_cycles_stay_bounded_and_dissipate(
        model: HysteresisFamily) -> None:
    """Repeated x cycles: bounded force and memory, and every cycle dissipates energy.

    (The force loop in F(z) closes exactly, see the no-drift test; in x the loop
    moves slowly because Eq. 10 re-centres z, so no exact repetition is claimed.)
    """
    f, A, N = 0.5, 0.15e-3, 200
    st = model.stepper()
    t = np.arange(50 * N + 1) / (N * f)
    v = A * 2 * np.pi * f * np.cos(2 * np.pi * f * t)
    run = friction_along_motion(model, t, v)
    assert np.max(np.abs(run.F)) < 4.0   # well inside the sliding level Fs = 22.5 N
    for c in range(50):
        cyc = slice(c * N, (c + 1) * N + 1)
        assert np.trapezoid(run.F[cyc], run.x[cyc]) > 0.0  # clockwise loop: dissipative
    vm = 0.5 * (v[1:] + v[:-1])
    for k in range(10 * N):  # the memory stays shallow (loops are closed and removed)
        st.step(t[k + 1] - t[k], vm[k])
        assert st.function.depth <= 6


def test_stepper_matches_friction_along_motion(model: HysteresisFamily) -> None:
    t = np.linspace(0.0, 0.5, 501)
    v = 0.01 * np.sin(2 * np.pi * 3 * t)
    run = friction_along_motion(model, t, v, a=np.zeros_like(t))
    st = model.stepper()
    vm = 0.5 * (v[1:] + v[:-1])
    F = [st.force(v[0])]
    for k in range(t.size - 1):
        st.step(t[k + 1] - t[k], vm[k])
        F.append(st.force(v[k + 1]))
    np.testing.assert_allclose(F, run.F, rtol=0, atol=1e-9)
    st.reset()
    np.testing.assert_array_equal(st.state, model.initial_state())
    with pytest.raises(ValueError, match="state"):
        st.reset([0.0])


def test_substeps_refine_consistently(model: HysteresisFamily) -> None:
    t = np.linspace(0.0, 2.0, 4001)
    v = 0.02 * np.sin(2 * np.pi * 0.7 * t)
    F1 = friction_along_motion(model, t, v).F
    F3 = friction_along_motion(model, t, v, substeps=3).F
    assert np.max(np.abs(F1 - F3)) < 0.01 * np.max(np.abs(F1))


def test_long_run(model: HysteresisFamily) -> None:
    t = np.linspace(0.0, 10.0, 100_001)
    rng = np.random.default_rng(3)
    v = 0.02 * np.sin(2 * np.pi * 0.7 * t) + 1e-4 * rng.standard_normal(t.size)
    run = friction_along_motion(model, t, v)
    assert np.all(np.isfinite(run.F)) and np.max(np.abs(run.F)) < 30.0


# ------------------------------------------------------------ the effect
@pytest.mark.parametrize("base, params", [("lugre", "canudas1995"),
                                          ("nmlgm", "seed000-cylinder1"), ("dahl", None)])
def test_nonlocal_memory_defaults_are_a_no_op(base: str, params: str | None) -> None:
    m = make_model(base, params=params)
    h = m.with_effects("nonlocal-memory")
    assert isinstance(h, HysteresisFamily) and h.describe() == f"{base} + nonlocal-memory"
    t = np.linspace(0.0, 2.0, 2001)
    v = 0.01 * np.sin(2 * np.pi * 1.3 * t) + 0.004 * np.sin(2 * np.pi * 7 * t)
    F0 = friction_along_motion(m, t, v).F
    F1 = friction_along_motion(h, t, v).F
    np.testing.assert_allclose(F1, F0, rtol=0, atol=1e-9 * np.max(np.abs(F0)))


def test_nonlocal_memory_with_seed_curves_is_nmlgm_hysteresis(model: HysteresisFamily) -> None:
    seed = {k: v for k, v in model.flat_params().items() if k in model.hysteresis_values()}
    h = make_model("nmlgm", params="seed000-cylinder1").with_effects(
        make_effect("nonlocal-memory", seed))
    assert type(h) is NMLGMHysteresis
    assert h.flat_params() == model.flat_params()
    t = np.linspace(0.0, 1.0, 1001)
    v = 0.005 * np.sin(2 * np.pi * 2 * t)
    np.testing.assert_array_equal(friction_along_motion(h, t, v).F,
                                  friction_along_motion(model, t, v).F)


def test_nonlocal_memory_with_other_effects() -> None:
    base = make_model("lugre", params="canudas1995",
                      effects=["pressure-dependence", "dwell-time"]).with_params(kp=1e-6, dFs=0.3)
    h = base.with_effects("nonlocal-memory")
    assert h.state_names == ("z", "Fz", "w")
    t = np.linspace(0.0, 2.0, 2001)
    v = 0.01 * np.sin(2 * np.pi * 1.3 * t)
    p1 = 2e5 + 1e5 * np.sin(t)
    F0 = friction_along_motion(base, t, v, p1=p1).F
    F1 = friction_along_motion(h, t, v, p1=p1).F
    np.testing.assert_allclose(F1, F0, rtol=0, atol=1e-9 * np.max(np.abs(F0)))
    # adding the film lag keeps the hysteresis function
    lagged = h.with_effects("frictional-lag")
    assert isinstance(lagged, HysteresisFamily) and "film-lag" in lagged.features


def test_nonlocal_memory_applicability() -> None:
    eff = make_effect("nonlocal-memory")
    assert eff.signature and eff.experiment
    assert eff.applies_to(make_model("lugre"))
    assert not eff.applies_to(make_model("coulomb"))
    assert not eff.applies_to(make_model("nmlgm-hysteresis"))
    assert not eff.applies_to(make_model("gms"))
    with pytest.raises(ValueError, match="presliding"):
        make_model("coulomb").with_effects("nonlocal-memory")
    with pytest.raises(ValueError, match="already has"):
        make_model("nmlgm-hysteresis").with_effects("nonlocal-memory")
    with pytest.raises(ValueError, match="does not apply"):
        make_model("gms").with_effects("nonlocal-memory")
