"""Plants with discrete-memory friction (plants/discrete_memory.py): nmlgm-hysteresis."""

from __future__ import annotations

import numpy as np
import pytest

from fcomp.inputs import parse_input
from fcomp.models import NotSymbolicError, make_model
from plants import PLANTS


def test_noop_memory_reproduces_the_nmlgm_plant() -> None:
    """With the no-op hysteresis parameters F(z) = sigma0*z: the coupled run is the NMLGM plant."""
    base = make_model("nmlgm", params="seed000-cylinder1")
    noop = base.with_effects("nonlocal-memory")
    assert not noop.symbolic
    u = parse_input("sine:amplitude=0.4,frequency=2")
    ref = PLANTS.get("presliding-rig")(base).simulate(u, 0.3, 1000.0, rtol=1e-10, atol=1e-10)
    got = PLANTS.get("presliding-rig")(noop).simulate(u, 0.3, 1000.0, rtol=1e-10, atol=1e-10)
    for c in ("x", "v", "p1", "p2", "F", "z", "h"):
        assert np.max(np.abs(got[c] - ref[c])) < 1e-6 * np.ptp(ref[c]), c
    np.testing.assert_allclose(got["Fz"], 1.5e4 * got["z"], rtol=1e-9, atol=1e-12)
    assert got.meta["simulation"]["coupling"] == pytest.approx(1e-4)


@pytest.fixture(scope="module")
def rig():
    return PLANTS.get("presliding-rig")(make_model("nmlgm-hysteresis", params="seed000-cylinder1"))


def test_presliding_hysteresis_run_converges_and_keeps_memory(rig) -> None:
    """Seed 000's new model on its own rig: pre-sliding loops (F against x), friction
    balancing the pressure force (Eq. 1), results converging as the coupling is refined."""
    u = parse_input("sine:amplitude=0.05,frequency=1")
    coarse = rig.simulate(u, 1.2, 1000.0, coupling=2e-4)
    fine = rig.simulate(u, 1.2, 1000.0, coupling=5e-5)
    disp = fine["x"] - fine["x"][0]
    assert 1e-5 < np.ptp(disp) < 1e-3  # pre-sliding: tenths of a millimetre
    assert np.max(np.abs(coarse["x"] - fine["x"])) < 1e-3 * np.ptp(disp)
    assert np.max(np.abs(coarse["F"] - fine["F"])) < 1e-2 * np.ptp(fine["F"])
    # a hysteresis loop: the same displacement with different forces going up and down
    t = fine["t"]
    cyc = (t > 0.2)
    x, F = disp[cyc], fine["F"][cyc]
    mid = np.abs(x - 0.5 * (x.max() + x.min())) < 0.05 * np.ptp(x)
    assert np.ptp(F[mid]) > 0.2 * np.ptp(F)
    # below break-away the friction carries the pressure force (seed 000 Eq. 1, gauge)
    p = rig.plant_params.flat()
    A1 = np.pi / 4 * p["bore"] ** 2
    A2 = np.pi / 4 * (p["bore"] ** 2 - p["rod"] ** 2)
    F_eq1 = fine["p1"] * A1 - fine["p2"] * A2 - p["mass"] * fine["a"]
    np.testing.assert_allclose(fine["F"], F_eq1, atol=1e-9 * np.abs(F_eq1).max())
    assert np.abs(fine["F"]).max() < 22.5


def test_memory_stepper_matches_simulate_with_held_input(rig) -> None:
    n, dt = 100, 1e-3
    u = 0.05 * np.sin(2 * np.pi * 2 * np.arange(n + 1) * dt)
    st = rig.stepper(dt)
    X = [st.reset()]
    for k in range(n):
        X.append(st.step(rig.scalar_input(u[k:k + 1])[0]))
    run = rig.simulate(rig.scalar_input(u), n * dt, 1 / dt, hold="zoh")
    cols = np.column_stack([run["x"], run["v"], run["z"], run["Fz"]])
    X = np.array(X)
    idx = [rig.state_names.index(c) for c in ("x", "v", "z", "Fz")]
    np.testing.assert_allclose(X[:, idx], cols, rtol=1e-9, atol=1e-12)
    # outputs of stepped states (closed-loop harness) = the simulation's columns
    y = rig.evaluate_outputs(X, rig.scalar_input(u))
    np.testing.assert_allclose(y["F"], run["F"], rtol=1e-9, atol=1e-9)


def test_symbolic_forms_refused_in_one_line(rig) -> None:
    with pytest.raises(NotSymbolicError, match="discrete"):
        rig.to_iosys()
    with pytest.raises(NotSymbolicError):
        rig.discrete_step(1e-3)


def test_sliding_switch_jump_is_not_taken_for_a_slope() -> None:
    """Seed 000's curves with seed 002's much stiffer bristles: F(z) jumps where the memory
    enters sliding; the coupling must step over the jump (slope kept in [0, K_max])."""
    plant = PLANTS.get("hydraulic")(make_model("nmlgm-hysteresis", params="seed002-type1"))
    run = plant.simulate(parse_input("sine:amplitude=0.0045,frequency=1"), 0.08, 1000.0)
    assert np.all(np.isfinite(run["F"])) and run["v"].max() > 0.02
    assert run["z"].max() > 1.3e-4  # the sliding threshold Fs/sigma0 was crossed
