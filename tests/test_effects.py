"""Effects (models.md 1.8): no-ops at their defaults, documented changes otherwise, user effects.

Each catalogue effect is checked along a rich prescribed motion (reversals,
a dwell, varying position and chamber pressures) with
:func:`fcomp.trajectory.friction_along_motion`, against the same model
without the effect. SI units: m, m/s, m/s^2, Pa, N, s.
"""

from __future__ import annotations

import math
import uuid
from pathlib import Path

import numpy as np
import pytest
from helpers import reference_lugre as ref
from test_models import attachable

from fcomp.backend import NUMPY, Backend
from fcomp.effects import EFFECTS, Effect, load_effects_module, make_effect, register_effect
from fcomp.errors import FcompError, UnknownNameError
from fcomp.models import FrictionModel, Signals, make_model
from fcomp.models.lugre_family import PRESETS
from fcomp.parameters import ParamValues, make_params_class, spec
from fcomp.trajectory import FrictionRun, friction_along_motion

CATALOGUE = ("viscous", "stribeck", "presliding", "frictional-lag", "dwell-time",
             "direction-asymmetry", "pressure-dependence", "position-dependence",
             "viscous-lead", "inertia-error", "force-offset")
# nonlocal-memory (the hysteresis function) is tested with nmlgm-hysteresis, elsewhere


@pytest.fixture(scope="module")
def motion() -> dict[str, np.ndarray]:
    """4 s at 2 kHz: two sine strokes, a 0.6 s dwell, creep, reversals; p1, p2 and x vary."""
    t = np.linspace(0.0, 4.0, 8001)
    v = 0.06 * np.sin(2 * np.pi * 0.8 * t) * (t < 2.5) + 0.004 * (t > 3.1)
    v = v + 0.0 * t
    a = np.gradient(v, t)
    x = 0.15 + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    p1 = 3e5 + 1.5e5 * np.sin(2 * np.pi * 0.5 * t)
    p2 = 2e5 - 1e5 * np.cos(2 * np.pi * 0.3 * t)
    return {"t": t, "v": v, "a": a, "x": x, "p1": p1, "p2": p2}


def _run(model: FrictionModel, m: dict[str, np.ndarray]) -> FrictionRun:
    return friction_along_motion(model, m["t"], m["v"], a=m["a"], x=m["x"], p1=m["p1"],
                                 p2=m["p2"])


CASES = [(name, eff) for name in PRESETS for eff in CATALOGUE
         if attachable(eff, make_model(name, params="seed000-cylinder1"))]


#: (model, effect) pairs where ``applies_to`` holds but the defaults are not a no-op:
#: ``frictional-lag`` on the ``stribeck`` map keeps the map's
#: static film (its vb) and makes it lag, which changes the force while the speed changes.
NOT_A_NO_OP = {("stribeck", "frictional-lag")}


NO_OP_CASES = [c for c in CASES if c not in NOT_A_NO_OP]


def test_catalogue_is_the_public_contract() -> None:
    assert set(CATALOGUE) | {"nonlocal-memory"} <= set(EFFECTS.names())
    for name in CATALOGUE:
        cls = EFFECTS.get(name)
        assert cls.__doc__ and cls.signature and cls.experiment, name


def test_every_effect_has_somewhere_to_go() -> None:
    attached = {eff for _, eff in NO_OP_CASES}
    assert attached == set(CATALOGUE)
    assert set(CASES) >= NOT_A_NO_OP


@pytest.mark.parametrize(("name", "effect"), NO_OP_CASES,
                         ids=[f"{n}+{e}" for n, e in NO_OP_CASES])
def test_effect_at_defaults_leaves_the_force_unchanged(name: str, effect: str,
                                                       motion: dict) -> None:
    base = make_model(name, params="seed000-cylinder1")
    with_effect = base.with_effects(effect)
    F0, F1 = _run(base, motion).F, _run(with_effect, motion).F
    np.testing.assert_allclose(F1, F0, rtol=1e-12, atol=1e-12 * np.abs(F0).max())


def test_presliding_on_dahl_adds_only_the_bristle_damping() -> None:
    dahl = make_model("dahl")
    model = dahl.with_effects(make_effect("presliding", {"sigma0": 2e4, "sigma1": 3.0}))
    assert "damping" in model.features  # type: ignore[attr-defined]
    assert model.flat_params()["sigma1"] == 3.0
    assert model.flat_params()["sigma0"] == dahl.flat_params()["sigma0"]  # Dahl's own kept


def test_frictional_lag_default_on_the_stribeck_map_changes_only_transients(
        motion: dict) -> None:
    base = make_model("stribeck", params="seed000-cylinder1")
    lagged = base.with_effects("frictional-lag")
    v = np.array([-0.1, -0.01, 0.01, 0.1])
    np.testing.assert_allclose(lagged.steady_state(v), base.steady_state(v), rtol=1e-13)
    F0, F1 = _run(base, motion).F, _run(lagged, motion).F
    assert np.abs(F1 - F0).max() > 0.1  # N: the film now lags the speed


# ----------------------------------------------------------- documented effects
def test_pressure_dependence_scales_the_levels(motion: dict) -> None:
    """``(Fc, Fs) -> (Fc, Fs)*(1 + kp*(p1 + p2 - p_ref))``: exact for a Coulomb map."""
    kp, p_ref = 8e-7, 4e5
    base = make_model("coulomb", params="seed000-cylinder1")
    model = base.with_effects(make_effect("pressure-dependence", {"kp": kp, "p_ref": p_ref}))
    factor = 1 + kp * (motion["p1"] + motion["p2"] - p_ref)
    np.testing.assert_allclose(_run(model, motion).F, _run(base, motion).F * factor, rtol=1e-13)


def test_pressure_dependence_scales_the_stribeck_curve_not_the_viscous_term() -> None:
    kp, p_ref = 8e-7, 4e5
    base = make_model("lugre", params="canudas1995")
    model = base.with_effects(make_effect("pressure-dependence", {"kp": kp, "p_ref": p_ref}))
    v = np.array([-0.05, -2e-3, -3e-4, 3e-4, 2e-3, 0.05])
    for p1, p2 in [(0.0, 0.0), (6e5, 1e5), (2e5, 2e5)]:
        factor = 1 + kp * (p1 + p2 - p_ref)
        got = model.steady_state(v, p1=p1, p2=p2) - 0.4 * v
        np.testing.assert_allclose(got, factor * (base.steady_state(v) - 0.4 * v), rtol=1e-13)


def test_force_offset_adds_a_constant(motion: dict) -> None:
    base = make_model("nmlgm", params="seed000-cylinder1")
    model = base.with_effects(make_effect("force-offset", {"offset": -2.5}))
    np.testing.assert_allclose(_run(model, motion).F - _run(base, motion).F, -2.5, atol=1e-12)


def test_a_fits_offset_becomes_the_effect_that_holds_it() -> None:
    """The effect a fit's ``offset`` becomes is the effect's own data (``fit_extra``), not a
    name the comparison knows."""
    from fcomp.diagnosis.compare import model_from_fit
    from fcomp.effects import effect_holding

    holder = effect_holding("offset")
    assert holder is EFFECTS.get("force-offset") and "offset" in holder.Params.names()
    doc = {"model": "coulomb-viscous", "effects": [holder.name],
           "params": {"Fc": 10.0, "B": 50.0, "offset": 2.5, "mass": 3.0}}
    model, mass = model_from_fit(doc)
    assert mass == 3.0 and [e.name for e in model.effects] == [holder.name]
    assert model.flat_params()["offset"] == 2.5
    with pytest.raises(UnknownNameError):
        effect_holding("no-such-extra")


def test_inertia_error_adds_mass_times_acceleration(motion: dict) -> None:
    base = make_model("lugre", params="seed000-cylinder1")
    model = base.with_effects(make_effect("inertia-error", {"dm": 0.35}))
    np.testing.assert_allclose(_run(model, motion).F - _run(base, motion).F,
                               0.35 * motion["a"], atol=1e-12)
    # and it is the c_a part of the force split that plants move to the mass side
    F0, c_a = model.force_parts(NUMPY, [0.0], Signals(v=0.01, a=3.0), model.param_values(NUMPY))
    assert c_a == pytest.approx(0.35)


def test_direction_asymmetry_scales_retracting_levels(motion: dict) -> None:
    base = make_model("coulomb", params="canudas1995")
    model = base.with_effects(make_effect("direction-asymmetry", {"r_neg": 1.4}))
    F0, F1 = _run(base, motion).F, _run(model, motion).F
    ext, ret = motion["v"] > 1e-4, motion["v"] < -1e-4
    np.testing.assert_allclose(F1[ext], F0[ext], rtol=1e-14)
    np.testing.assert_allclose(F1[ret], 1.4 * F0[ret], rtol=1e-14)


def test_position_dependence_is_a_legendre_scale_of_the_levels(motion: dict) -> None:
    k1, k2, k3 = 0.1, -0.05, 0.03
    base = make_model("coulomb", params="canudas1995")
    model = base.with_effects(make_effect("position-dependence", {"kx1": k1, "kx2": k2, "kx3": k3}))
    xi = 2 * motion["x"] / 0.3 - 1  # default stroke 0 .. 0.3 m
    scale = 1 + k1 * xi + k2 * (3 * xi**2 - 1) / 2 + k3 * (5 * xi**3 - 3 * xi) / 2
    np.testing.assert_allclose(_run(model, motion).F, _run(base, motion).F * scale, rtol=1e-13)


def test_position_dependence_local_box_is_a_soft_step_pair(motion: dict) -> None:
    """``kb*box(x)``: ``(tanh((x - xb + wb)/eb) - tanh((x - xb - wb)/eb))/2`` scales the levels."""
    base = make_model("coulomb", params="canudas1995")
    kb, xb, wb, eb = 0.6, 0.16, 0.01, 0.001
    model = base.with_effects(make_effect("position-dependence",
                                          {"kb": kb, "xb": xb, "wb": wb, "eb": eb}))
    x = motion["x"]
    box = 0.5 * (np.tanh((x - xb + wb) / eb) - np.tanh((x - xb - wb) / eb))
    np.testing.assert_allclose(_run(model, motion).F, _run(base, motion).F * (1 + kb * box),
                               rtol=1e-13)
    inside = np.abs(x - xb) < wb - 4 * eb
    assert inside.any() and np.all(box[inside] > 0.99)  # a plateau of height kb inside


def test_viscous_lead_adds_sigma2_T_a(motion: dict) -> None:
    base = make_model("lugre", params="canudas1995")
    model = base.with_effects(make_effect("viscous-lead", {"T": 0.02}))
    assert model.describe() == "lugre + viscous-lead"
    np.testing.assert_allclose(_run(model, motion).F - _run(base, motion).F,
                               0.4 * 0.02 * motion["a"], atol=1e-12)


def test_viscous_adds_a_linear_term(motion: dict) -> None:
    base = make_model("coulomb", params="canudas1995")
    model = base.with_effects(make_effect("viscous", {"sigma2": 7.0}))
    np.testing.assert_allclose(_run(model, motion).F - _run(base, motion).F,
                               7.0 * motion["v"], atol=1e-12)


def test_stribeck_on_coulomb_is_the_stribeck_curve() -> None:
    model = make_model("coulomb", params="canudas1995").with_effects(
        make_effect("stribeck", {"Fs_excess": 0.5, "vs": 2e-3, "n": 1.5}))
    for v in (-0.05, -3e-3, -5e-4, 5e-4, 3e-3, 0.05):
        assert float(model.steady_state(v)) == pytest.approx(
            ref.stribeck_map(v, 1.0, 1.5, 2e-3, 1.5, 0.0), rel=1e-13)


def test_presliding_turns_a_static_map_into_lugre(motion: dict) -> None:
    stat = make_model("stribeck", params="canudas1995").with_params(vb=math.inf)
    model = stat.with_effects(make_effect("presliding", {"sigma0": 1e5, "sigma1": 316.2277660}))
    assert model.dynamic and "z" in model.state_names
    lugre = make_model("lugre", params="canudas1995")
    # the bristle exponent i_pre = 1 is LuGre's bristle; Dahl's form of it rounds differently
    np.testing.assert_allclose(_run(model, motion).F, _run(lugre, motion).F, rtol=1e-9,
                               atol=1e-9)


def test_frictional_lag_turns_lugre_into_modified_lugre(motion: dict) -> None:
    values = {"vb": 0.037, "tau_hp": 0.02, "tau_hn": 0.15, "tau_h0": 20.0}
    model = make_model("lugre", params="seed000-cylinder1").with_effects(
        make_effect("frictional-lag", values))
    assert isinstance(model, PRESETS["modified-lugre"])
    assert model.describe() == "lugre + frictional-lag"
    target = make_model("modified-lugre", params="seed000-cylinder1").with_params(
        vb_pos=0.037, vb_neg=0.037)
    np.testing.assert_allclose(_run(model, motion).F, _run(target, motion).F, rtol=1e-13)
    assert np.abs(_run(model, motion).F - _run(make_model("lugre", params="seed000-cylinder1"),
                                                motion).F).max() > 1.0


def _dwell_peak(model: FrictionModel, dwell: float) -> tuple[float, float]:
    """Slide 0.3 s at 10 mm/s, rest ``dwell`` s, restart at 1 mm/s: (age at restart, peak F).

    Each speed change happens within 1 ns, so the sampled motion is the
    piecewise-constant one.
    """
    t, v = [], []
    start = 0.0
    for duration, speed in [(0.3, 0.01), (dwell, 0.0), (0.2, 1e-3)]:
        t.append(start + np.linspace(0.0, duration, 3001))
        v.append(np.full(3001, speed))
        start += duration + 1e-9
    run = friction_along_motion(model, np.concatenate(t), np.concatenate(v),
                                a=np.zeros(3 * 3001))
    restart = 2 * 3001 - 1  # last sample of the dwell
    return float(run.states[restart, 1]), float(run.F[restart:].max())


def test_dwell_time_raises_break_away_with_dwell() -> None:
    """Age ``w -> 1 - (1 - w0)*exp(-T/tau_dwell)`` at rest; break-away ``Fs + dFs*w`` grows."""
    dFs, tau = 0.5, 1.0
    model = make_model("lugre", params="canudas1995").with_effects(
        make_effect("dwell-time", {"dFs": dFs, "tau_dwell": tau, "L_dwell": 1e-4}))
    w0 = 0.0  # no ageing while sliding (10 mm/s = 1000 v_rest)
    dwells = (0.05, 0.5, 2.0, 8.0)
    ages, peaks = zip(*[_dwell_peak(model, d) for d in dwells], strict=True)
    for d, w in zip(dwells, ages, strict=True):
        assert w == pytest.approx(1 - (1 - w0) * math.exp(-d / tau), rel=1e-6)
    assert np.all(np.diff(peaks) > 0), peaks
    # without the effect the peak does not depend on the dwell
    plain = [_dwell_peak(make_model("lugre", params="canudas1995").with_effects("dwell-time"),
                         d)[1] for d in (0.05, 8.0)]
    assert plain[0] == pytest.approx(plain[1], abs=1e-9)
    # bounded by the aged level: F <= Fs + dFs*w + (sigma1 + sigma2)*v
    assert peaks[-1] < 1.5 + dFs * ages[-1] + (316.23 + 0.4) * 1e-3
    # and a sizeable part of dFs*(w(8 s) - w(0.05 s)) reaches the peak (0.23 of it here:
    # at 1 mm/s = vs the Stribeck factor exp(-1) weighs the static level, and sliding
    # erases the age over L_dwell while the bristles load)
    gain = peaks[-1] - peaks[0]
    assert 0.2 * dFs * (ages[-1] - ages[0]) < gain < dFs * (ages[-1] - ages[0])


def test_dwell_time_log_ageing_follows_its_closed_form() -> None:
    """``dw/dt = (1 - w)^(1 + k)/tau`` at rest: ``w = 1 - (1 + k*t/tau)^(-1/k)`` (Dieterich-like)."""
    k, tau = 1.5, 0.4
    model = make_model("lugre", params="canudas1995").with_effects(
        make_effect("dwell-time", {"dFs": 0.5, "tau_dwell": tau, "L_dwell": 1e-4, "k_dwell": k}))
    t = np.linspace(0.0, 6.0, 60001)
    run = friction_along_motion(model, t, np.zeros_like(t))
    w = run.states[:, model.state_names.index("w")]
    closed = 1 - (1 + k * t / tau) ** (-1 / k)
    np.testing.assert_allclose(w, closed, atol=2e-4)  # exponential-Euler steps of 0.1 ms
    # unlike Kato's exponential (1 - exp(-15) at 15 tau) it still ages long after tau
    assert w[30000] < 0.9 and w[-1] - w[30000] > 0.05


def test_dwell_time_adds_nothing_while_sliding() -> None:
    """Ageing is restricted to rest: at a steady 1 mm/s the age is nil, the force unchanged."""
    base = make_model("lugre", params="canudas1995")
    model = base.with_effects(make_effect("dwell-time", {"dFs": 0.5, "tau_dwell": 0.2}))
    t = np.linspace(0.0, 2.0, 20001)
    v = np.full_like(t, 1e-3)
    run = friction_along_motion(model, t, v)
    assert run.states[-1, model.state_names.index("w")] < 1e-6
    np.testing.assert_allclose(run.F[-1], friction_along_motion(base, t, v).F[-1], rtol=1e-9)


def test_dwell_time_level_form_shifts_the_whole_curve() -> None:
    """Form ``level``: the age raises ``Fc`` and ``Fs`` alike, so the excess ``dFs*w``
    is there at any speed until slip erases it; form ``static`` raises the hump only,
    which fades above the Stribeck speed (a stribeck map, ``vs`` = 1 mm/s here)."""
    base = make_model("stribeck", params="canudas1995")
    dFs, L = 0.5, 0.05  # a long erasure length: the age is nearly intact after 0.1 s at 20 mm/s
    t = np.concatenate([np.linspace(0.0, 2.0, 20001), 2.0 + 1e-9 + np.linspace(0.0, 0.1, 1001)])
    v = np.concatenate([np.zeros(20001), np.full(1001, 0.02)])
    plain = friction_along_motion(base, t, v).F
    for form in ("level", "static"):
        model = base.with_effects(make_effect(
            "dwell-time", {"dFs": dFs, "tau_dwell": 0.5, "L_dwell": L}, form=form))
        run = friction_along_motion(model, t, v)
        w = run.states[:, model.state_names.index("w")]
        k = 20001 + 500  # 50 ms at 20 mm/s = 20 Stribeck speeds: the hump is gone
        excess = run.F[k] - plain[k]
        if form == "level":
            assert excess == pytest.approx(dFs * w[k], rel=1e-6)
            assert w[k] > 0.9
        else:
            assert abs(excess) < 1e-9


def test_dwell_time_forms_are_one_law_without_a_static_level() -> None:
    """A model without ``Fs`` gets the one law (not refitted twice); with it, both forms."""
    from fcomp.effects import EFFECTS

    cls = EFFECTS.get("dwell-time")
    one = cls.forms_for(make_model("coulomb-viscous", params="canudas1995"))
    both = cls.forms_for(make_model("stribeck", params="canudas1995"))
    assert [f.name for f in one] == ["static"]
    assert [f.name for f in both] == ["static", "level"]
    # on the model without Fs the two forms give the same force
    t = np.linspace(0.0, 1.2, 12001)
    v = np.where(t < 1.0, 0.0, 0.02)
    base = make_model("coulomb-viscous", params="canudas1995")
    F = [friction_along_motion(base.with_effects(make_effect(
        "dwell-time", {"dFs": 0.5, "tau_dwell": 0.3, "L_dwell": 0.01}, form=f)), t, v).F
        for f in ("static", "level")]
    np.testing.assert_array_equal(F[0], F[1])


def test_position_box_is_never_narrower_than_a_seal_band() -> None:
    """A box narrower than a seal's contact band is not a property of the bore."""
    from fcomp.effects.position_dependence import SEAL_BAND, PositionDependenceParams

    specs = {n: PositionDependenceParams.spec_of(n) for n in ("wb", "eb")}
    assert specs["wb"].lower == 0.5 * SEAL_BAND and specs["eb"].lower == 0.2 * SEAL_BAND
    with pytest.raises(ValueError):
        make_effect("position-dependence", {"kb": 0.3, "xb": 0.15, "wb": 5e-5, "eb": 1e-3})


def _maxwell_slip_reference(x: np.ndarray, shares: np.ndarray, slips: np.ndarray,
                            level: float) -> np.ndarray:
    """Classical Maxwell-slip, written out: spring ``k_i = level*share_i/slip_i``, deflection
    clipped to ``+-slip_i`` (Lampaert, Al-Bender & Swevers 2002)."""
    delta = np.zeros(slips.size)
    out = np.empty(x.size)
    for i in range(x.size):
        if i:
            delta = np.clip(delta + (x[i] - x[i - 1]), -slips, slips)
        out[i] = float(np.sum(level * shares / slips * delta))
    return out


def test_maxwell_slip_elements_are_classical_maxwell_slip() -> None:
    """Form ``maxwell-slip`` with the whole level on the elements equals Maxwell-slip, exactly."""
    base = make_model("dahl", params="canudas1995").with_params(sigma2=0.0)
    Fc = base.flat_params()["Fc"]
    dmax, rho, beta = 2e-4, 20.0, 0.7
    model = base.with_effects(make_effect(
        "nonlocal-memory", {"ms_share": 1.0, "ms_dmax": dmax, "ms_spread": rho,
                            "ms_shape": beta}, form="maxwell-slip"))
    assert model.describe() == "dahl + nonlocal-memory" and model.symbolic
    from fcomp.models.lugre_family import ELEMENTS

    u = np.linspace(0.0, 1.0, ELEMENTS)
    shares = rho ** (beta * u) / np.sum(rho ** (beta * u))
    slips = dmax * rho ** (u - 1.0)
    # nested displacement loops (seed 000 Fig. 10): out, back, a minor loop, on again
    knots = np.array([0.0, 4e-4, -1e-4, 2e-4, 0.5e-4, 3e-4, -3e-4])
    x = np.concatenate([np.linspace(a, b, 400, endpoint=False)
                        for a, b in zip(knots[:-1], knots[1:], strict=True)] + [knots[-1:]])
    t = np.arange(x.size) * 1e-3
    v = np.gradient(x, t)
    xs = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    F = friction_along_motion(model, t, v, x=xs).F
    ref = _maxwell_slip_reference(xs, shares, slips, Fc)
    np.testing.assert_allclose(F, ref, atol=1e-9 * Fc)
    # return-point memory: after the minor loop 2e-4 -> 0.5e-4, back at 2e-4 the force is
    # the force of the reversal there
    i1 = 3 * 400
    i2 = 4 * 400 + int(np.argmin(np.abs(xs[1600:2000] - xs[i1])))
    assert abs(F[i2] - F[i1]) < 1e-2 * Fc
    assert abs(F[i2 - 1] - F[i1]) > abs(F[i2] - F[i1])


def test_maxwell_slip_elements_at_zero_share_are_a_no_op(motion: dict) -> None:
    base = make_model("lugre", params="seed000-cylinder1")
    model = base.with_effects(make_effect("nonlocal-memory", form="maxwell-slip"))
    np.testing.assert_array_equal(_run(model, motion).F, _run(base, motion).F)
    with pytest.raises(ValueError, match="form"):
        make_effect("nonlocal-memory", form="spline")


# ----------------------------------------------------------------- user effects
def _level_scale_effect(name: str) -> type[Effect]:
    class LevelScale(Effect):
        """Test effect: all levels times ``1 + k``."""

        Params = make_params_class("LevelScaleParams", [spec("k", "-", 0.0, -0.5, 1.0, "gain")],
                                   owner=f"effect {name}")
        signature = "levels off by a constant factor"
        experiment = "none"

        def modify_levels(self, be: Backend, L: dict, w: list, sig: Signals,
                          P: ParamValues) -> dict:
            return {k: v * (1.0 + P("k")) for k, v in L.items()}

    LevelScale.name = name
    return LevelScale


def test_register_a_user_effect() -> None:
    name = f"test-scale-{uuid.uuid4().hex[:8]}"
    cls = register_effect(_level_scale_effect(name))
    assert name in EFFECTS.names()
    base = make_model("lugre", params="canudas1995")
    model = base.with_effects(make_effect(name, {"k": 0.2}))
    v = np.array([-0.01, 2e-3, 0.05])
    np.testing.assert_allclose(model.steady_state(v) - 0.4 * v, 1.2 * (base.steady_state(v) - 0.4 * v),
                               rtol=1e-13)
    # at its default it is a no-op; its symbolic form works like the catalogue's
    np.testing.assert_allclose(base.with_effects(name).steady_state(v), base.steady_state(v))
    fns = model.casadi_functions()
    sig = [0.02, 0.0, 0.1, 0.0, 0.0, 1.0]
    F_num = model.force(NUMPY, [1e-5], Signals(*sig), model.param_values(NUMPY))
    assert float(fns["force"]([1e-5], sig)) == pytest.approx(float(F_num), rel=1e-14)
    with pytest.raises(ValueError, match="already registered"):
        register_effect(cls)
    register_effect(cls, replace=True)


def test_register_rejects_what_is_not_an_effect() -> None:
    with pytest.raises(ValueError, match="not an Effect subclass"):
        register_effect(dict)  # type: ignore[arg-type]
    nameless = _level_scale_effect("")
    with pytest.raises(ValueError, match="has no name"):
        register_effect(nameless)


USER_MODULE = '''
"""A user's effects module: a constant load on the rod (N)."""
from fcomp.effects import Effect, register_effect
from fcomp.parameters import make_params_class, spec


@register_effect
class ConstantLoad(Effect):
    """A constant external load."""

    name = "{name}"
    Params = make_params_class("ConstantLoadParams", [spec("load", "N", 0.0, -1e3, 1e3, "load")],
                               owner="effect {name}")
    signature = "constant offset"
    experiment = "none"

    def extra_force(self, be, sig, P):
        return P("load"), 0.0
'''


def test_load_effects_module(tmp_path: Path) -> None:
    name = f"user-load-{uuid.uuid4().hex[:8]}"
    path = tmp_path / f"my_effects_{uuid.uuid4().hex[:6]}.py"
    path.write_text(USER_MODULE.format(name=name))
    assert load_effects_module(path) == [name]
    model = make_model("coulomb", params="canudas1995").with_effects(make_effect(name, {"load": 3.0}))
    assert float(model.steady_state(0.01)) == pytest.approx(4.0)


def test_load_effects_module_errors_are_one_line(tmp_path: Path) -> None:
    with pytest.raises(FcompError, match="effects module not found"):
        load_effects_module(tmp_path / "missing.py")
    broken = tmp_path / "broken_effects.py"
    broken.write_text("import nonexistent_package_xyz\n")
    with pytest.raises(FcompError, match="importing the effects module failed") as info:
        load_effects_module(broken)
    assert "\n" not in str(info.value)


# ------------------------------------------------------------------ bad input
def test_unknown_effect_is_a_clear_error() -> None:
    with pytest.raises(UnknownNameError, match=r"unknown effect 'presure-dependence'.*pressure"):
        make_model("lugre", params="canudas1995").with_effects("presure-dependence")


def test_effect_parameter_out_of_bounds_names_it() -> None:
    with pytest.raises(ValueError, match=r"\bkp\b"):
        make_effect("pressure-dependence", {"kp": 1.0})
    with pytest.raises(ValueError, match=r"\bL_dwell\b"):
        make_effect("dwell-time", {"L_dwell": 0.0})
    model = make_model("lugre", params="canudas1995").with_effects("dwell-time")
    with pytest.raises(ValueError, match=r"\btau_dwell\b"):
        model.with_params(tau_dwell=-1.0)


def test_effect_cannot_be_added_twice() -> None:
    model = make_model("lugre", params="canudas1995").with_effects("force-offset")
    with pytest.raises(ValueError, match="already has effect 'force-offset'"):
        model.with_effects("force-offset")
    with pytest.raises(ValueError, match="already has effect 'stribeck'"):
        make_model("lugre").with_effects("stribeck")


def test_structural_effect_needs_its_base_term() -> None:
    with pytest.raises(ValueError, match="needs the Stribeck term"):
        make_model("coulomb").with_effects("frictional-lag")
    with pytest.raises(ValueError, match="needs viscous"):
        make_model("coulomb").with_effects("viscous-lead")


@pytest.mark.parametrize(("B_pos", "B_neg", "B_start"), [
    (1000.0, 1000.0, 1000.0), (1000.0, 1000.0, 600.0), (1000.0, 2000.0, 1000.0),
    (2000.0, 800.0, 1000.0)])
def test_stribeck_start_reads_the_hump_not_a_viscous_mismatch(B_pos: float, B_neg: float,
                                                              B_start: float) -> None:
    """A small Gaussian Stribeck hump under a viscous term the start does not know exactly.

    ``F = s*(Fc + (Fs - Fc)*exp(-(|v|/vs)^2)) + B_s*v``, both directions, log-spaced
    speeds 0.5 mm/s - 0.3 m/s, a 60 N hump on 350 N, noise 1 % of ``Fc``. The start
    is given ``B_start``: low (a linear fit whose level took up the hump) or the
    mean of coefficients that differ by side. The level left after ``B_start*|v|``
    then rises with speed by more than the hump, and the largest bin was read as
    the hump (``vs`` 0.24 m/s, 20 times too high). The hump is now fitted with its
    own slope: ``vs`` within a factor of two, ``Fs - Fc`` within 30 %.
    """
    from fcomp.effects.record import stribeck_hump_start

    Fc, Fs, vs = 350.0, 410.0, 0.011
    rng = np.random.default_rng(7)
    speed = np.geomspace(5e-4, 0.3, 4000)
    v = np.concatenate([speed, -speed])
    B = np.where(v > 0, B_pos, B_neg)
    F = np.sign(v) * (Fc + (Fs - Fc) * np.exp(-((np.abs(v) / vs) ** 2))) + B * v
    F = F + rng.normal(0.0, 0.01 * Fc, v.size)
    Fs_hat, vs_hat = stribeck_hump_start(v, F, Fc, B_start, 2e-4)
    assert 0.5 * vs <= vs_hat <= 2.0 * vs
    assert Fs_hat - Fc == pytest.approx(Fs - Fc, rel=0.3)


def test_presliding_forms_and_the_elastic_unloading_of_the_elasto_plastic_bristle() -> None:
    """Both forms on a static map, one on Dahl (it has its bristle). After a reversal the
    elasto-plastic bristle unloads as a spring, ``dF/dx = sigma0``, down to ``-ba*Fc``,
    whatever its break; LuGre's bristle (the ``bristle`` form) unloads faster than that."""
    from fcomp.effects import EFFECTS

    cls = EFFECTS.get("presliding")
    assert [f.name for f in cls.forms_for(make_model("stribeck"))] == ["bristle",
                                                                        "elasto-plastic"]
    assert [f.name for f in cls.forms_for(make_model("dahl"))] == ["bristle"]
    k, Fc, dt = 1e6, 50.0, 1e-4
    t = np.arange(0.0, 0.12, dt)
    v = np.where(t < 0.1, 5e-3, -1e-3)  # 0.5 mm forward (sliding), then back at 1 mm/s
    back = t >= 0.1
    for ba in (0.3, 0.6):
        ep = make_model("coulomb").with_params(Fc=Fc).with_effects(make_effect(
            "presliding", {"sigma0": k, "ba_pre": ba}, form="elasto-plastic"))
        F = friction_along_motion(ep, t, v).F
        assert F[np.flatnonzero(back)[0] - 1] == pytest.approx(Fc)
        # elastic while F > -ba*Fc: the force falls by k*|dx| per step exactly
        elastic = back & (-ba * Fc + k * 1e-3 * dt < F)
        steps = np.diff(F)[elastic[1:] & elastic[:-1]]
        np.testing.assert_allclose(steps, -k * 1e-3 * dt, rtol=1e-9)
    lugre = make_model("coulomb").with_params(Fc=Fc).with_effects(make_effect(
        "presliding", {"sigma0": k}))
    F = friction_along_motion(lugre, t, v).F
    i = np.flatnonzero(back)[0]
    assert F[i + 1] - F[i] < -1.5 * k * 1e-3 * dt  # LuGre: dz/dx = 1 + |u| > 1 at first


def test_stribeck_hump_start_weighs_bins_by_their_samples() -> None:
    """A long creep at the full hump, a few samples crossing the low speeds during
    accelerations (below the hump: the inertia estimate lags there), and thousands on
    a long-tailed (Lorentzian, Hess & Soom 1990) hump at the stroke speeds. Unweighted,
    the median of a hundred transit samples weighs as much as that of thousands, and
    the hump was read as a spike at the creep speed (``vs`` 50 times too low)."""
    from fcomp.effects.record import stribeck_hump_start

    Fc, dF, vs, B = 350.0, 180.0, 0.012, 900.0
    rng = np.random.default_rng(3)
    creep = np.full(1200, 2e-4)
    transit = np.geomspace(3e-4, 2.5e-3, 150)
    stroke = np.geomspace(3e-3, 0.13, 20000)
    speed = np.concatenate([creep, transit, stroke])
    F = Fc + dF / (1.0 + (speed / vs) ** 2) + B * speed
    F[creep.size:creep.size + transit.size] = Fc - 50.0
    F = F + rng.normal(0.0, 3.0, speed.size)
    Fs_hat, vs_hat = stribeck_hump_start(speed, F, Fc, B, 1.5e-4)
    assert 0.5 * vs <= vs_hat <= 2.0 * vs
    assert Fs_hat - Fc == pytest.approx(dF, rel=0.3)
