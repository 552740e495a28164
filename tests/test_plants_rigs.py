"""The pre-sliding rig (seed 000) and the force-driven rig (seed 001): plants/presliding_rig.py,
plants/force_rig.py, the Karnopp band and the end stops of plants/mechanics.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import independent_plants as ip

from fcomp.inputs import parse_input
from fcomp.models import make_model
from plants import PLANTS

P_ATM = 101325.0


@pytest.fixture(scope="module")
def rig():
    return PLANTS.get("presliding-rig")(make_model("nmlgm", params="seed000-cylinder1"))


def test_presliding_rig_agrees_with_independent_integration(rig) -> None:
    t = np.arange(0, 501) / 1000.0
    u = 0.6 * np.sin(2 * np.pi * 2 * t)
    U = rig.scalar_input(u)
    ref_rig = ip.PreslidingRig.seed000()
    u1, u2 = ip.held_input(t, U[:, 0]), ip.held_input(t, U[:, 1])
    scale = np.array([0.3, 1, 5e5, 5e5, 1e-3, 0.5])
    R = ip.reference(lambda tt, y: ref_rig.rhs(tt, y, lambda q: (u1(q), u2(q))), ref_rig.x0(), t,
                     rtol=1e-10, atol=1e-12 * scale, method="LSODA")
    run = rig.simulate(U, 0.5, 1000.0, rtol=1e-8, atol=1e-8)
    got = np.column_stack([run["x"], run["v"], run["p1"] + P_ATM, run["p2"] + P_ATM,
                           run["z"], run["h"]])
    rel = np.max(np.abs(got - R), axis=0) / np.ptp(R, axis=0)
    assert np.all(rel < 5e-6), rel
    assert np.ptp(R[:, 0]) > 1e-3  # the piston slides (film state h develops)
    np.testing.assert_allclose(run["u1"], U[:, 0])


def test_presliding_rig_scalar_command_and_default_state(rig) -> None:
    """The default state balances the free piston (p1*A1 = p2*A2 gauge, p2 = half the supply)
    and u = 0 holds it: nothing moves."""
    p = rig.plant_params.flat()
    A1 = math.pi / 4 * p["bore"] ** 2
    A2 = math.pi / 4 * (p["bore"] ** 2 - p["rod"] ** 2)
    run = rig.simulate(parse_input("step:amplitude=0"), 0.5, 1000.0)
    np.testing.assert_allclose(run["p2"], 0.5 * p["ps_g"], rtol=1e-12)
    np.testing.assert_allclose(run["p1"] * A1, run["p2"] * A2, rtol=1e-12)
    assert np.max(np.abs(run["x"] - p["stroke"] / 2)) < 1e-12
    assert np.max(np.abs(run["F"])) < 1e-9
    u1, u2 = rig.commands_at_rest()
    np.testing.assert_allclose(run["u1"], u1)
    assert u2 == pytest.approx(1.0)  # 5 V * 0.2 MPa / 1 MPa


def test_presliding_regime_is_quasi_static(rig) -> None:
    """Below break-away the free piston barely moves and the friction carries the pressure
    force: F = p1*A1 - p2*A2 - m*a (seed 000 Eq. 1, gauge), displacement ~ F/sigma0."""
    run = rig.simulate(parse_input("sine:amplitude=0.04,frequency=0.5"), 2.0, 1000.0)
    p = rig.plant_params.flat()
    A1 = math.pi / 4 * p["bore"] ** 2
    A2 = math.pi / 4 * (p["bore"] ** 2 - p["rod"] ** 2)
    F_eq1 = run["p1"] * A1 - run["p2"] * A2 - p["mass"] * run["a"]
    np.testing.assert_allclose(run["F"], F_eq1, atol=1e-9 * np.abs(F_eq1).max())
    Fs = 22.5
    assert np.abs(F_eq1).max() < Fs  # pre-sliding only
    disp = run["x"] - run["x"][0]
    sigma0 = rig.friction.flat_params()["sigma0"]
    assert 0 < np.abs(disp).max() < 1.5 * np.abs(F_eq1).max() / sigma0


@pytest.fixture(scope="module")
def force_rig_lugre():
    return PLANTS.get("force-rig")(make_model("lugre", params="seed000-cylinder1"))


def _friction_from_toml(sec: dict) -> ip.Friction:
    return ip.Friction.from_toml(sec, film=False)


def test_force_rig_agrees_with_independent_integration(force_rig_lugre) -> None:
    from fcomp.paramsets import get

    raw = get("seed000-cylinder1").raw
    fr = _friction_from_toml(raw["friction"]["1"])
    cyl = raw["cylinder"]["1"]
    ref = ip.ForceRig(fr, cyl["mass"], cyl["stroke"])
    t = np.arange(0, 1001) / 1000.0
    U = 12.0 * np.sin(2 * np.pi * 2.0 * t)
    u = ip.held_input(t, U)
    R = ip.reference(lambda tt, y: ref.rhs(tt, y, u), ref.x0(), t, rtol=1e-10,
                     atol=np.array([1e-13, 1e-12, 1e-15]), method="LSODA")
    run = force_rig_lugre.simulate(U, 1.0, 1000.0, rtol=1e-8, atol=1e-8)
    got = np.column_stack([run["x"], run["v"], run["z"]])
    rel = np.max(np.abs(got - R), axis=0) / np.ptp(R, axis=0)
    assert np.all(rel < 2e-6), rel
    # seed 001 Eq. 5 bookkeeping: friction = F_ext - m*a (chambers open, horizontal)
    assert run["x"].min() > 0.0 and run["x"].max() < cyl["stroke"]  # clear of the end stops
    np.testing.assert_allclose(run["F"], run["F_ext"] - cyl["mass"] * run["a"], atol=1e-9)
    assert "p1" not in run and run.meta["kind"] == "friction-rig"


def test_karnopp_stick_then_slide_matches_analytic_solution() -> None:
    """Coulomb-viscous friction in a plant: stuck (no motion) while |F_ext| < Fc; above it,
    v(t) = (F - Fc)/B*(1 - exp(-B*t/m)) exactly (seed 001 Eq. 5 with a constant force)."""
    model = make_model("coulomb-viscous", params={"Fc": 5.5, "B": 25.0})
    rig = PLANTS.get("force-rig")(model, "seed000-cylinder1")
    m = rig.plant_params.flat()["mass"]
    held = rig.simulate(5.4, 2.0, 200.0)
    assert np.max(np.abs(held["x"] - held["x"][0])) < 1e-12
    np.testing.assert_allclose(held["F"], 5.4)
    np.testing.assert_allclose(held["a"], 0.0, atol=1e-12)
    held_neg = rig.simulate(-5.4, 0.5, 200.0)
    assert np.max(np.abs(held_neg["x"] - held_neg["x"][0])) < 1e-12
    slide = rig.simulate(8.0, 0.3, 1000.0, rtol=1e-9, atol=1e-9)
    t = slide["t"]
    v_exact = (8.0 - 5.5) / 25.0 * (1 - np.exp(-25.0 * t / m))
    moving = t > 0.01
    np.testing.assert_allclose(slide["v"][moving], v_exact[moving], rtol=1e-5)
    x_exact = (8.0 - 5.5) / 25.0 * (t - m / 25.0 * (1 - np.exp(-25.0 * t / m)))
    assert np.max(np.abs(slide["x"] - slide["x"][0] - x_exact)) < 1e-6


def test_karnopp_stops_a_coasting_piston() -> None:
    """Given an initial speed and no force, Coulomb friction stops the piston at
    x0 + m*v0^2/(2*Fc) (B = 0) and it stays there."""
    model = make_model("coulomb", params={"Fc": 5.5})
    rig = PLANTS.get("force-rig")(model, "seed000-cylinder1")
    m = rig.plant_params.flat()["mass"]
    run = rig.simulate(0.0, 0.3, 1000.0, x0={"v": 0.2}, rtol=1e-9, atol=1e-9)
    stop = run["x"][0] + m * 0.2 ** 2 / (2 * 5.5)
    assert run["x"][-1] == pytest.approx(stop, abs=1e-7)
    assert abs(run["v"][-1]) < 1e-9  # stuck: the residual band velocity decays (tau_stick)
    assert np.ptp(run["x"][-200:]) < 1e-9  # no creep


def test_end_stop_is_a_stiff_contact(force_rig_lugre) -> None:
    """Pushed into the end stop, the piston settles at stroke + (F_ext - friction)/k_stop,
    with no rebound beyond the stroke after the impact."""
    p = force_rig_lugre.plant_params.flat()
    run = force_rig_lugre.simulate(40.0, 1.5, 1000.0, x0={"x": 0.28})
    friction_end = run["F"][-1]
    pen = (40.0 - friction_end) / p["k_stop"]
    assert run["x"][-1] == pytest.approx(p["stroke"] + pen, abs=1e-9)
    assert abs(run["v"][-1]) < 1e-6
    assert run["x"].max() < p["stroke"] + 1e-4
    back = force_rig_lugre.simulate(-40.0, 1.5, 1000.0, x0={"x": 0.02})
    assert back["x"][-1] == pytest.approx(-(40.0 + back["F"][-1]) / p["k_stop"], abs=1e-9)
