"""The pneumatic servo (plants/pneumatic.py): orifice flow, mass, equilibrium, agreement."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import independent_plants as ip
from scipy.integrate import trapezoid

from fcomp.backend import NUMPY
from fcomp.measurement import G
from fcomp.models import make_model
from plants import PLANTS
from plants.pneumatic import iso6358_flow

P_ATM = 101325.0


@pytest.fixture(scope="module")
def plant():
    return PLANTS.get("pneumatic")(make_model("nmlgm", params="seed000-servo"))


def test_agrees_with_independent_tight_integration(plant) -> None:
    t = np.arange(0, 601) / 1000.0
    U = 0.3 * np.sin(2 * np.pi * 2 * t)
    ref_plant = ip.Pneumatic.seed000()
    u = ip.held_input(t, U)
    scale = np.array([0.3, 1, 6e5, 6e5, 1, 1e-3, 0.5])
    R = ip.reference(lambda tt, y: ref_plant.rhs(tt, y, u), ref_plant.x0(), t, rtol=1e-10,
                     atol=1e-12 * scale, method="LSODA")
    for tol, limit in ((1e-6, 2e-4), (1e-8, 2e-6)):  # defaults, then tight (docs/plants.md)
        run = plant.simulate(U, 0.6, 1000.0, rtol=tol, atol=tol)
        got = np.column_stack([run["x"], run["v"], run["p1"] + P_ATM, run["p2"] + P_ATM,
                               run["xs"], run["z"], run["h"]])
        rel = np.max(np.abs(got - R), axis=0) / np.ptp(R, axis=0)
        assert np.all(rel < limit), dict(zip(["x", "v", "p1", "p2", "xs", "z", "h"], rel,
                                             strict=True))
    m1 = np.array([ref_plant.flows(list(y))[0] for y in R])
    assert np.max(np.abs(run["mdot1"] - m1)) < 1e-4 * np.ptp(m1)


def test_iso6358_flow_sign_choking_and_magnitude(plant) -> None:
    """Flow goes from high to low pressure, is choked (independent of p_down) below the
    critical ratio, continuous at b and r_lam, and at choke equals isentropic nozzle theory."""
    P = plant.param_values(NUMPY)
    f = plant.plant_params.flat()
    A = 4e-6
    up = 6e5
    down = np.linspace(0.0, up, 2001)[1:]
    q = np.array([iso6358_flow(NUMPY, up, d, A, P) for d in down])
    back = np.array([iso6358_flow(NUMPY, d, up, A, P) for d in down])
    np.testing.assert_allclose(back, -q)
    assert np.all(q[down < up] > 0) and q[-1] == 0.0
    choked = down / up <= f["b_crit"]
    assert np.ptp(q[choked]) == 0.0
    assert np.all(np.diff(q) <= 1e-15)  # less flow as the back pressure rises
    gam, R, T = f["gamma_air"], f["R_air"], f["T_air"]
    nozzle = A * up * math.sqrt(gam / (R * T)) * (2 / (gam + 1)) ** ((gam + 1) / (2 * (gam - 1)))
    assert q[0] == pytest.approx(nozzle, rel=1e-12)
    for r0 in (f["b_crit"], f["r_lam"]):
        lo = iso6358_flow(NUMPY, up, up * r0 * (1 - 1e-9), A, P)
        hi = iso6358_flow(NUMPY, up, up * r0 * (1 + 1e-9), A, P)
        assert abs(lo - hi) < 1e-6 * nozzle
    # subsonic value against the ISO 6358 ellipse written out
    r = 0.8
    b = f["b_crit"]
    ell = math.sqrt(1 - ((r - b) / (1 - b)) ** 2)
    assert iso6358_flow(NUMPY, up, r * up, A, P) == pytest.approx(nozzle * ell, rel=1e-12)


def test_air_mass_conserved_isothermal(plant) -> None:
    """With k_poly = 1 the air mass p*V/(R*T) of each chamber changes exactly by the valve flow."""
    iso = plant.with_params(k_poly=1.0)
    run = iso.simulate(lambda t: 0.4 * np.sin(2 * np.pi * 3 * t), 0.4, 20000.0, rtol=1e-9,
                       atol=1e-9)
    p = iso.plant_params.flat()
    A1 = math.pi / 4 * p["bore"] ** 2
    A2 = math.pi / 4 * (p["bore"] ** 2 - p["rod"] ** 2)
    RT = p["R_air"] * p["T_air"]
    t, x = run["t"], run["x"]
    for mdot, V, pr in ((run["mdot1"], p["V10"] + A1 * x, run["p1"] + P_ATM),
                        (run["mdot2"], p["V20"] + A2 * (p["stroke"] - x), run["p2"] + P_ATM)):
        mass = pr * V / RT
        assert abs((mass[-1] - mass[0]) - trapezoid(mdot, t)) < 1e-4 * trapezoid(
            np.abs(mdot), t)
        assert np.ptp(mass) > 0.1 * mass[0]  # the run really exchanges air


def test_closed_chambers_polytropic_invariant(plant) -> None:
    """Valve shut (A_valve = 0): no mass crosses, p*V^k stays constant while the piston
    oscillates on the two air springs."""
    shut = plant.with_params(A_valve=0.0)
    run = shut.simulate(0.0, 0.5, 2000.0, x0={"p1": 3.5e5, "p2": 2.0e5}, rtol=1e-9, atol=1e-9)
    p = shut.plant_params.flat()
    k = p["k_poly"]
    A1 = math.pi / 4 * p["bore"] ** 2
    A2 = math.pi / 4 * (p["bore"] ** 2 - p["rod"] ** 2)
    x = run["x"]
    assert np.ptp(x) > 1e-3
    assert np.all(run["mdot1"] == 0.0) and np.all(run["mdot2"] == 0.0)
    for V, pr in ((p["V10"] + A1 * x, run["p1"] + P_ATM),
                  (p["V20"] + A2 * (p["stroke"] - x), run["p2"] + P_ATM)):
        inv = pr * V ** k
        assert np.ptp(inv) < 1e-6 * inv[0]


def test_vertical_load_held_by_pressure(plant) -> None:
    """A vertical cylinder with the valve shut holds its load where
    p1*A1 - p2*A2 - p_atm*(A1 - A2) = m*g; 2 % less pressure and it sinks."""
    vert = plant.with_params(orient=1.0, A_valve=0.0)
    p = vert.plant_params.flat()
    A1 = math.pi / 4 * p["bore"] ** 2
    A2 = math.pi / 4 * (p["bore"] ** 2 - p["rod"] ** 2)
    p2 = 2.0e5
    p1 = (p["mass"] * G + p2 * A2 + P_ATM * (A1 - A2)) / A1
    held = vert.simulate(0.0, 1.0, 200.0, x0={"p1": p1, "p2": p2})
    assert np.max(np.abs(held["x"] - held["x"][0])) < 1e-9
    assert np.max(np.abs(held["F"])) < 1e-6
    sinks = vert.simulate(0.0, 1.0, 200.0, x0={"p1": 0.98 * p1, "p2": p2})
    assert sinks["x"][-1] < sinks["x"][0] - 1e-4


def test_default_state_and_valve_direction(plant) -> None:
    p = plant.plant_params.flat()
    run = plant.simulate(0.5, 0.3, 1000.0)
    x0 = run.meta["simulation"]["x0"]
    assert x0["p1"] == x0["p2"] == pytest.approx((p["ps"] + P_ATM) / 2)
    assert x0["x"] == pytest.approx(p["stroke"] / 2) and x0["xs"] == 0.0
    assert p["mass"] == pytest.approx(1.6)  # cylinder 1 (0.6 kg) + servo load (1.0 kg)
    assert run["mdot1"][10] > 0 and run["mdot2"][10] < 0  # P->A and B->exhaust open
    assert run["x"][-1] > run["x"][0] + 0.01
    assert run.meta["kind"] == "pneumatic-cylinder" and run.meta["pressure"] == "gauge"
