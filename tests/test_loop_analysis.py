"""Margins of the loop as it runs (controllers/loop_analysis), against independent computations.

* the sampled linear plant against finite differences of the nonlinear plant's own
  one-sample step (a fixed-step RODAS4 integration of the plant's equations);
* the closed loop's poles against the eigenvalues of a finite-difference Jacobian of the
  nonlinear sampled closed-loop map: the plant's step over one period, the *Python*
  controller's ``step`` (not the CasADi function the analysis differentiates) and the
  computation delay's buffer -- for pid, lugre-observer and ekf, both plant kinds, sliding
  and in pre-sliding, along the stroke;
* the margins against the closed loop's eigenvalues with the loop gain scaled by the
  gain margin (just stable below, just unstable above) and against python-control's
  ``stability_margins``;
* the PID family's closed form against the Jacobian of the exported step;
* the nonlinear loop's own critical gain (scaled until it rings) against the prediction;
* the plant file's ``[uncertainty]`` and ``[control] delay``, dead valves refused.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from helpers.plant_files import edited as _edit

from controllers import make_controller
from controllers.base import Reference
from controllers.loop_analysis.controller import StepLinearisation
from controllers.loop_analysis.loop import closed_loop_matrix, iosystems
from controllers.loop_analysis.margins import frequency_grid, refined_margins
from controllers.loop_analysis.pid_family import (
    PIDFamilyGains,
    pid_family_response,
    pid_family_ss,
)
from controllers.pid import PIDGains, PIDLaw, pid_transfer
from controllers.plant_model import ControlModel
from controllers.tuning import Tuning
from fcomp.cli.main import main
from fcomp.errors import FcompError
from fcomp.models import make_model
from plants.check import frictionless
from plants.equilibrium import equilibrium
from plants.linearise import Linearisation, linearise
from plants.planfile import PlantFileError, builtin_plant_file, read_plant_file
from plants.uncertainty import Uncertainty

KINDS = ("hydraulic", "pneumatic")
#: Gains of the tests' loops (a slow, stable PID family per kind: no design needed).
GAINS = {
    "hydraulic": PIDFamilyGains(3.0e5, 2.5e6, 2.0e3, 120.0, 60.0, 0.2),
    "pneumatic": PIDFamilyGains(2.0e3, 2.0e4, 40.0, 150.0, 40.0, 0.3),
}


def _model(kind: str) -> ControlModel:
    pf = builtin_plant_file(kind)
    model = ControlModel(pf, make_model("nmlgm", params=pf.friction_set))
    g = GAINS[kind]
    m = model.mass
    w = (g.ki / m) ** (1 / 3)
    nan = float("nan")
    from controllers.loop_analysis.margins import LoopMargins

    ok = LoopMargins(3.0, 3.0, 0.0, 45.0, 1.5, nan, nan, nan, 0.99)
    model.use_tuning(Tuning(
        column_frequency=80.0, valve_bandwidth=400.0, control_rate=1000.0,
        force_bandwidth=g.force_bandwidth, pid_bandwidth=w,
        pid_gains=PIDGains(g.kp, g.ki, g.kd, derivative_cutoff=g.derivative_cutoff),
        derivative_cutoff=g.derivative_cutoff, observer_gain=5.0,
        ekf_measurement_std=tuple(float(s) for s in model.sensors.std()),  # type: ignore[arg-type]
        mpc_horizon_time=0.04, mpc_velocity_ratio=100.0, margins=ok,
        velocity_compensation=g.velocity_compensation,
        observer_stiffness=0.4 * model.friction.flat_params()["sigma0"]))
    return model


def _seal(kind: str) -> object:
    """The plant held by a LuGre seal (the nmlgm friction's bristle and levels)."""
    pf = builtin_plant_file(kind)
    p = make_model("nmlgm", params=pf.friction_set).flat_params()
    def one(k: str) -> float:  # a directional parameter's extending side
        return float(p.get(k, p.get(f"{k}_pos", 0.0)))

    fr = make_model("lugre", {"sigma0": one("sigma0"), "sigma1": one("sigma1"),
                              "sigma2": one("sigma2"), "Fc": one("Fc"), "Fs": one("Fs"),
                              "vs": one("vs")})
    return pf.make_plant(fr)


def _fd(f, z0: np.ndarray, h: np.ndarray) -> np.ndarray:
    cols = []
    for i in range(z0.size):
        e = np.zeros(z0.size)
        e[i] = h[i]
        cols.append((f(z0 + e) - f(z0 - e)) / (2 * h[i]))
    return np.array(cols).T


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("regime", ["sliding", "presliding"])
def test_the_sampled_plant_is_the_nonlinear_step_differentiated(kind: str, regime: str) -> None:
    pf = builtin_plant_file(kind)
    plant = pf.make_plant(frictionless()) if regime == "sliding" else _seal(kind)
    dt = 1e-3
    lin = Linearisation(plant, dt)
    step = plant.discrete_step(dt, substeps=40)
    p = plant.param_vector()
    names = list(plant.state_names)
    for frac in (0.03, 0.5, 0.97):
        pos = frac * pf.values["stroke"]
        lp = lin.at(pos)
        x0, u0 = equilibrium(plant, pos)
        scale = np.asarray(plant.ode_model().scales, dtype=float)
        J = _fd(lambda z: np.asarray(step(z[:-1], z[-1], p)).ravel(),
                np.concatenate([x0, [u0]]),
                np.concatenate([scale * 1e-6, [1e-6 * pf.control["u_max"]]]))
        Ad, Bd = J[:, :-1], J[:, -1]
        if regime == "presliding":  # the bristle joins the position (z = x - x0)
            ix, iz = names.index("x"), names.index("z")
            keep = [i for i in range(len(names)) if i != iz]
            Ad = Ad.copy()
            Ad[:, ix] += Ad[:, iz]
            Ad, Bd = Ad[np.ix_(keep, keep)], Bd[keep]
            dz = (J[iz, :-1] - J[ix, :-1]) * scale / scale[iz]  # x - z conserved
            assert np.allclose(dz, (np.eye(len(names))[iz] - np.eye(len(names))[ix]) * scale
                               / scale[iz], atol=1e-4)
        sc = np.array([scale[names.index(n)] for n in lp.state_names])
        rel = (Ad - lp.Ad) * sc[None, :] / sc[:, None]
        assert np.max(np.abs(rel)) < 1e-4, (frac, np.max(np.abs(rel)))
        assert np.allclose(Bd, lp.Bd[:, 0], rtol=1e-4, atol=1e-6 * np.abs(Bd).max())


def _controller_state(ctrl) -> tuple[callable, callable]:
    """Get/set of a Python controller's own state (what its step reads and writes): the
    PID law's, the observer's estimate and side, the EKF's estimate and last command with its
    covariance held at the value it has when this is called, the friction estimate's last
    value (its lead); behind the fail-safe layer, the inner controller's)."""
    from controllers.safety import unwrap

    ctrl = unwrap(ctrl)
    law = ctrl.law
    parts: list[tuple[int, callable, callable]] = [
        (3, lambda: [law.integral, law.v_f, law.x_prev],
         lambda v: (setattr(law, "integral", v[0]), setattr(law, "v_f", v[1]),
                    setattr(law, "x_prev", v[2])))]
    if hasattr(ctrl, "x_hat"):
        n = len(ctrl.x_hat)

        def set_obs(v, n=n):
            ctrl.x_hat = np.array(v, dtype=float)
            ctrl._side = 1.0

        parts.append((n, lambda: list(ctrl.x_hat), set_obs))
    if hasattr(ctrl, "ekf"):
        kf = ctrl.ekf.kf
        n = kf.x.shape[0]
        P = kf.P.copy()

        def set_ekf(v, n=n):
            kf.x = np.array(v[:n], dtype=float).reshape(-1, 1)
            kf.P = P.copy()
            ctrl._u_prev = float(v[n])

        parts.append((n + 1, lambda: list(kf.x[:, 0]) + [ctrl._u_prev], set_ekf))
    if ctrl.uses_friction and ctrl.friction_lead:  # the estimate's lead: the previous one
        parts.append((1, lambda: [0.0 if ctrl._F_prev is None else ctrl._F_prev],
                      lambda v: setattr(ctrl, "_F_prev", float(v[0]))))

    def getter():
        return np.concatenate([np.asarray(g(), dtype=float) for _k, g, _s in parts])

    def setter(v):
        i = 0
        for k, _g, s_ in parts:
            s_(list(v[i:i + k]))
            i += k

    return getter, setter


def _nonlinear_poles(plant, make, pos: float, delay: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Eigenvalues of the finite-difference Jacobian of the nonlinear sampled closed-loop map
    ``[plant state, controller state, delay line] -> next`` (``make()`` builds the
    controller); also the fixed point's y, u."""
    ctrl = make()
    dt = ctrl.dt
    x0, u0 = equilibrium(plant, pos)
    names = list(plant.state_names)
    meas = [names.index(k) for k in ("x", "p1", "p2")]
    ref = Reference(pos, 0.0, 0.0)
    ctrl.reset(0.0, x0[meas], ref)
    # the controller's fixed point (its integral holding the load), from the analysis's own
    # search on the exported step -- the Python controller is then checked to sit still there
    lin = StepLinearisation(make())
    s = lin.fixed_point(x0[meas], u0)
    fixed = dict(zip(lin.names, s, strict=True))
    get, put = _controller_state(ctrl)
    c0 = get()
    c0[0], c0[1], c0[2] = fixed["integral"], fixed["v_f"], fixed["x_prev"]
    if hasattr(ctrl, "x_hat"):
        k = len(ctrl.x_hat)
        c0[3:3 + k] = [fixed[f"observer[{i}]"] if k > 1 else fixed["observer"]
                       for i in range(k)]
    if hasattr(ctrl, "ekf"):
        n = ctrl.ekf.kf.x.shape[0]
        c0[3:3 + n] = [fixed[f"ekf_x[{i}]"] for i in range(n)]
        c0[3 + n] = fixed["u_prev"]
        i0 = lin.names.index("ekf_P[0]")
        ctrl.ekf.kf.P = np.asarray(s[i0:i0 + n * n]).reshape(n, n, order="F")
        get, put = _controller_state(ctrl)
    if "F_prev" in fixed:
        c0[-1] = fixed["F_prev"]
    ncs = len(c0)
    step = plant.discrete_step(dt, substeps=40)
    p = plant.param_vector()
    nx = x0.size

    def F(z: np.ndarray) -> np.ndarray:
        X, cs, buf = z[:nx], z[nx:nx + ncs], z[nx + ncs:]
        put(cs)
        u = ctrl.step(0.0, X[meas], ref)
        Xn = np.asarray(step(X, buf[0] if delay else u, p)).ravel()
        return np.concatenate([Xn, get(), ([*buf[1:], u])[:delay] if delay else []])

    z0 = np.concatenate([x0, c0, [u0] * delay])
    h = np.concatenate([np.asarray(plant.ode_model().scales, dtype=float) * 1e-6,
                        np.maximum(np.abs(c0), 1e-6) * 1e-6,
                        [1e-6 * ctrl.model.u_max] * delay])
    resid = F(z0) - z0
    assert np.max(np.abs(resid[:nx]) / np.asarray(plant.ode_model().scales)) < 1e-9  # rests
    assert np.max(np.abs(resid[nx:]) / np.maximum(np.abs(z0[nx:]), 1e-6)) < 1e-4
    J = _fd(F, z0, h)
    return np.linalg.eigvals(J), x0[meas], u0


def _compare(ev_nl: np.ndarray, ev_lin: np.ndarray, floor: float = 0.5,
             slow_tol: float = 3e-4) -> None:
    """Every pole of magnitude above ``floor`` of the one set near one of the other: within
    ``slow_tol`` for the loop's own (|z| > 0.9), 1 % for the fast ones (the position's
    invariant x - z of a plant held by its seal, at z = 1, is not a pole of the loop)."""
    a = np.sort_complex(ev_nl[(np.abs(ev_nl) > floor) & (np.abs(ev_nl - 1) > 1e-5)])
    b = np.sort_complex(ev_lin[(np.abs(ev_lin) > floor) & (np.abs(ev_lin - 1) > 1e-5)])
    assert a.size == b.size, (a, b)
    # match each nonlinear pole to its nearest linear one
    for e in a:
        d = np.min(np.abs(b - e))
        tol = slow_tol if abs(e) > 0.9 else 1e-2 * abs(e)
        assert d < tol, (e, b[np.argmin(np.abs(b - e))], d)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("regime", ["sliding", "presliding"])
def test_closed_loop_poles_are_those_of_the_nonlinear_sampled_loop(kind: str, regime: str) -> None:
    model = _model(kind)
    pf = builtin_plant_file(kind)
    plant = pf.make_plant(frictionless()) if regime == "sliding" else _seal(kind)
    lin = Linearisation(plant, 1e-3)
    for frac in (0.04, 0.5, 0.96):
        pos = frac * pf.values["stroke"]
        ev_nl, y, u = _nonlinear_poles(plant, lambda: make_controller("pid", model), pos, 1)
        lp = lin.at(pos)
        lc = StepLinearisation(make_controller("pid", model)).at(y, u)
        M = closed_loop_matrix(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1)
        _compare(ev_nl, np.linalg.eigvals(M))


@pytest.mark.parametrize("name", ["lugre-observer", "ekf"])
def test_compensators_at_rest_are_linearised_as_they_run(name: str) -> None:
    model = _model("hydraulic")
    plant = _seal("hydraulic")
    pos = 0.12
    ev_nl, y, u = _nonlinear_poles(plant, lambda: make_controller(name, model), pos, 1)
    lp = Linearisation(plant, 1e-3).at(pos)
    lc = StepLinearisation(make_controller(name, model)).at(y, u)
    M = closed_loop_matrix(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1)
    # the EKF's bristle equation has a kink at v = 0 (|v|): the differences straddle it
    _compare(ev_nl, np.linalg.eigvals(M), floor=0.6, slow_tol=1e-3 if name == "ekf" else 3e-4)


@pytest.mark.parametrize("kind", KINDS)
def test_the_pid_family_closed_form_is_the_exported_step_differentiated(kind: str) -> None:
    model = _model(kind)
    pf = builtin_plant_file(kind)
    lin = Linearisation(pf.make_plant(frictionless()), 1e-3)
    ctrl = make_controller("pid", model)
    sl = StepLinearisation(ctrl)
    z = np.exp(1j * frequency_grid(1e-3, 50) * 1e-3)
    for frac in (0.02, 0.5, 0.98):
        lp = lin.at(frac * pf.values["stroke"], damping=500.0)
        lc = sl.at(lp.measurement, lp.command)
        s, Jy, Jv = ctrl.valve.slopes(lp.measurement, lp.command)
        A, B, C, D = pid_family_ss(ctrl.family(), np.array([s]), Jy[None], np.array([Jv]),
                                   model.A1, model.A2, 1e-3)
        assert np.allclose(A[0], lc.A, atol=1e-12)
        assert np.allclose(B[0], lc.B, rtol=1e-9, atol=1e-12)
        assert np.allclose(C[0], lc.C, rtol=1e-9, atol=1e-9 * np.abs(lc.C).max())
        assert np.allclose(D[0], lc.D, rtol=1e-9, atol=1e-9 * np.abs(lc.D).max())
        K = pid_family_response(ctrl.family(), np.array([s]), Jy[None], np.array([Jv]),
                                model.A1, model.A2, 1e-3, z)[0]
        K2 = np.array([(lc.C @ np.linalg.solve(zz * np.eye(3) - lc.A, lc.B) + lc.D)[0]
                       for zz in z])
        assert np.allclose(K, K2, rtol=1e-8)


@pytest.mark.parametrize("kind", KINDS)
def test_margins_agree_with_the_gain_scaled_closed_loop_and_python_control(kind: str) -> None:
    import control as ct

    model = _model(kind)
    pf = builtin_plant_file(kind)
    lp = linearise(pf.make_plant(frictionless()), 0.5 * pf.values["stroke"], 1e-3, 300.0)
    lc = StepLinearisation(make_controller("pid", model)).at(lp.measurement, lp.command)
    systems = iosystems(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1, 1e-3)
    pole = np.linalg.eigvals(closed_loop_matrix(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1))
    pole = pole[np.argmax(np.abs(pole))]
    w = frequency_grid(1e-3, 3000)
    for brk, L in systems.items():
        def resp(x, L=L):
            return np.asarray(L(np.exp(1j * np.asarray(x) * 1e-3)), dtype=complex).reshape(-1)

        m = refined_margins(resp, w, pole, 1e-3)
        assert m.stable and math.isfinite(m.gain_up)
        for k, stable in ((0.99 * m.gain_up, True), (1.01 * m.gain_up, False)):
            A = np.asarray(ct.feedback(k * L, 1).A)
            assert (np.max(np.abs(np.linalg.eigvals(A))) < 1.0) == stable, (brk, k)
        gm, pm, _sm, _wpc, _wgc, _wms = ct.stability_margins(ct.frd(resp(w), w),
                                                             returnall=True)
        gms = [g for g in np.atleast_1d(gm) if np.isfinite(g) and g > 1]
        assert min(gms) == pytest.approx(m.gain_up, rel=2e-3)
        pms = [180 - abs(((p + 180) % 360) - 180) for p in np.atleast_1d(pm)]
        assert min(180 - abs(180 - p) for p in np.atleast_1d(pm) % 360) == pytest.approx(
            m.phase, abs=0.2) or min(pms) == pytest.approx(m.phase, abs=0.2)
        dist = np.min(np.abs(1 + resp(np.logspace(-1, math.log10(math.pi / 1e-3), 40000))))
        assert m.ms == pytest.approx(1 / dist, rel=1e-3)


def test_the_nonlinear_loop_rings_where_the_gain_margin_says() -> None:
    """The fast slice of benchmarks/bench_gain_margin.py: the nonlinear sampled loop, its
    valve command's deviation scaled, decays below the predicted gain margin and rings
    above it (within 15 %)."""
    from controllers.loop_analysis.ringing import growth

    model = _model("hydraulic")
    pf = builtin_plant_file("hydraulic")
    plant = pf.make_plant(frictionless())
    pos = 0.5 * pf.values["stroke"]
    lp = linearise(plant, pos, 1e-3, 0.0)
    lc = StepLinearisation(make_controller("pid", model)).at(lp.measurement, lp.command)
    L = iosystems(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1, 1e-3)["valve"]
    pole = np.linalg.eigvals(closed_loop_matrix(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1))

    def resp(x):
        return np.asarray(L(np.exp(1j * np.asarray(x) * 1e-3)), dtype=complex).reshape(-1)

    gm = refined_margins(resp, frequency_grid(1e-3, 2000), pole[np.argmax(np.abs(pole))],
                         1e-3).gain_up
    below = growth(plant, make_controller("pid", model), pos, 0.85 * gm, duration=1.0)
    above = growth(plant, make_controller("pid", model), pos, 1.15 * gm, duration=1.0)
    assert below.rate < 0 < above.rate, (gm, below.rate, above.rate)


def test_the_pid_integral_is_backward_euler_as_the_tuning_assumes() -> None:
    """PIDLaw's response to an error impulse equals pid_transfer's ki*dt*z/(z - 1) (plus the
    proportional and derivative parts): the integral includes this sample's error."""
    import control as ct

    g = PIDGains(kp=2.0, ki=50.0, kd=0.1, derivative_cutoff=30.0, kt=0.0)
    dt = 1e-3
    law = PIDLaw(g, dt)
    e = np.zeros(40)
    e[0] = 1.0
    out = []
    for k in range(40):  # the error is r - x with x = -e
        law.velocity(-e[k])
        out.append(law.force(e[k], 0.0))
        law.integrate(e[k], out[-1], out[-1], 0)
    C = pid_transfer(g, dt)
    resp = ct.impulse_response(C, np.arange(40) * dt)
    ref = np.asarray(resp.outputs).ravel() * dt  # python-control scales a discrete impulse
    assert np.allclose(out, ref, rtol=1e-10, atol=1e-12)


def test_the_harness_applies_the_computation_delay() -> None:
    from controllers.harness import LoopConfig, build_loop, run_closed_loop

    cfg = LoopConfig(plant="hydraulic", fast=True, noise=0.0, friction="lugre",
                     controller_friction="lugre",
                     tuning=lambda m: _model("hydraulic").tuning)
    res = run_closed_loop("pid", "steps", cfg)
    plant, model, ctrl = build_loop("pid", cfg)
    x0, u_hold = equilibrium(plant, res.x[0])
    assert model.delay == 1 and res.u[0] == pytest.approx(u_hold, rel=1e-12)
    # replay the controller on the recorded measurements: its command at k acts at k + 1
    from controllers.tasks import get_task

    tk = get_task("steps")
    r, dr, ddr = tk.sample(res.t)
    ctrl.reset(0.0, res.y[0], Reference(float(res.r[0]), float(dr[0]), float(ddr[0])))
    for k in range(30):
        u = ctrl.step(float(res.t[k]), res.y[k],
                      Reference(float(res.r[k]), float(dr[k]), float(ddr[k])))
        assert res.u[k + 1] == pytest.approx(min(max(u, -model.u_max), model.u_max),
                                             rel=1e-12, abs=1e-15)


# ------------------------------------------------------------------ plant files
def test_uncertainty_and_delay_are_read_with_their_defaults(tmp_path: Path) -> None:
    pf = builtin_plant_file("hydraulic")
    assert pf.control["delay"] == 1 and pf.ranges == Uncertainty.default("hydraulic")
    path = _edit("hydraulic", tmp_path, ("rate = 1000.0 ", "delay = 0\nrate = 1000.0 "),
                 ("[sensors]", "[uncertainty]\nvalve_gain = 0.25\nbeta = [-0.4, 0.1]\n"
                  "positions = [0.1, 0.9]\npresliding = 0\n\n[sensors]"))
    pf = read_plant_file(path)
    assert pf.control["delay"] == 0
    r = pf.ranges.ranges
    assert r["valve_gain"] == (-0.25, 0.25) and r["beta"] == (-0.4, 0.1)
    assert r["mass"] == (-0.1, 0.1)  # a default
    assert pf.ranges.positions == (0.1, 0.9) and pf.ranges.presliding == (0.0, 0.0)
    scaled = pf.ranges.scaled(pf.values, {"ps": 0.1, "beta": -0.4})
    assert scaled["ps"] == pytest.approx(pf.values["pt"] + 1.1 * (pf.values["ps"]
                                                                  - pf.values["pt"]))
    assert scaled["beta"] == pytest.approx(0.6 * pf.values["beta"])


@pytest.mark.parametrize(("table", "needle"), [
    ("[uncertainty]\nvalve_gain = 1.5\n", "valve_gain = 1.5 must be a relative range"),
    ("[uncertainty]\nbeta = [0.1, 0.2]\n", "-1 < low <= 0 <= high"),
    ("[uncertainty]\nkappa = 0.1\n", "unknown key [uncertainty] kappa"),
    ("[uncertainty]\npositions = [0.0, 0.5]\n", "positions"),
    ("[uncertainty]\nmass = \"a lot\"\n", "must be a number r"),
    ("uncertainty = 3\n", "uncertainty must be a table"),
])
def test_bad_uncertainty_is_one_line_each(table: str, needle: str, tmp_path: Path) -> None:
    if table.startswith("["):
        path = _edit("hydraulic", tmp_path, ("[sensors]", f"{table}\n[sensors]"))
    else:  # a top-level key, before the first table
        path = _edit("hydraulic", tmp_path, ('name = "seed002-type1"',
                                             f'name = "seed002-type1"\n{table}'))
    with pytest.raises(PlantFileError) as exc:
        read_plant_file(path)
    assert any(needle in p for p in exc.value.problems), exc.value.problems


@pytest.mark.parametrize("value", ["-1", "1.5", "11", "true", "\"one\""])
def test_bad_delay_is_refused(value: str, tmp_path: Path) -> None:
    path = _edit("hydraulic", tmp_path, ("rate = 1000.0 ", f"delay = {value}\nrate = 1000.0 "))
    with pytest.raises(PlantFileError) as exc:
        read_plant_file(path)
    assert any("[control] delay" in p for p in exc.value.problems)


@pytest.mark.parametrize(("kind", "old", "new", "needle"), [
    ("hydraulic", "w = 0.0228 ", "w = 0.0 ", "w (area gradient"),
    ("hydraulic", "cd = 0.32 ", "cd = 0.0 ", "cd (discharge"),
    ("hydraulic", "kv = 0.0227 ", "kv = 0.0 ", "kv (spool"),
    ("pneumatic", "A_valve = 6.0e-6 ", "A_valve = 0.0 ", "A_valve (edge area"),
    ("pneumatic", "A_valve = 6.0e-6 ", "# A_valve\nsonic_conductance = 0.0 #",
     "A_valve (edge area"),
])  # the file names the key it was given; the tuning (values without a file) the model's
def test_a_dead_valve_is_refused_in_one_line(kind: str, old: str, new: str, needle: str,
                                              tmp_path: Path, capsys) -> None:
    path = _edit(kind, tmp_path, (old, new))
    assert main(["plant", "check", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    given = new.split("\n")[-1].split()[0]
    assert len(err) == 1 and "passes no flow" in err[0] and f"[valve] {given} = 0" in err[0], err
    with pytest.raises(FcompError, match="passes no flow"):  # the file refuses it itself
        read_plant_file(path)
    pf = builtin_plant_file(kind)  # the same dead valve given as values: tuning refuses it
    pf = replace(pf, values={**pf.values, needle.split()[0]: 0.0})
    model = ControlModel(pf, make_model("nmlgm", params=(
        "seed002-type1" if kind == "hydraulic" else "seed000-servo")))
    with pytest.raises(FcompError, match="passes no flow") as exc:
        _ = model.tuning
    assert needle in str(exc.value)


def test_a_zero_delay_and_a_wider_box_change_the_grid(tmp_path: Path) -> None:
    from controllers.loop_analysis.grid import parameter_combinations, plant_grid

    unc = replace(Uncertainty.default("hydraulic"), positions=(0.5,))
    combos = parameter_combinations(unc)
    assert len(combos) == 1 + 2 * 4 + 2 ** 4
    pf = builtin_plant_file("hydraulic")
    model = ControlModel(pf, make_model("nmlgm", params=pf.friction_set), uncertainty=unc,
                         delay=0)
    grid = plant_grid(model, n_frequencies=100)
    assert grid.delay == 0 and len(grid) == len(combos) * 4  # sliding + 3 pre-sliding
    i = next(i for i, p in enumerate(grid.points) if p.presliding is None
             and dict(p.changes)["beta"] == 0.2 and dict(p.changes)["mass"] == -0.1)
    j = next(i for i, p in enumerate(grid.points) if p.presliding is None
             and all(v == 0 for _k, v in p.changes))
    # the column: w_h^2 = beta*(A1^2/V1 + A2^2/V2)/m, so +20 % beta, -10 % mass: x1.2/0.9
    wi, wj = grid.plants[i].column_mode()[0], grid.plants[j].column_mode()[0]
    assert (wi / wj) ** 2 == pytest.approx(1.2 / 0.9, rel=0.02)


def test_the_observer_closed_form_is_the_exported_step_differentiated() -> None:
    """lugre-observer at rest: controllers.loop_analysis.observer (the tuning's route) equals
    the Jacobian of the exported step (the plant check's route)."""
    from controllers.loop_analysis.observer import ObserverPath, observer_ss

    model = _model("hydraulic")
    lin = Linearisation(_seal("hydraulic"), 1e-3)
    ctrl = make_controller("lugre-observer", model)
    sl = StepLinearisation(ctrl)
    assert ctrl.observer_stiffness == pytest.approx(
        0.4 * model.friction.flat_params()["sigma0"])  # the tuning's, not the model's
    path = ObserverPath(model, 1e-3, ctrl.observer_stiffness)
    for frac in (0.05, 0.5, 0.95):
        lp = lin.at(frac * 0.3)
        lc = sl.at(lp.measurement, lp.command)
        s, Jy, Jv = ctrl.valve.slopes(lp.measurement, lp.command)
        phi, fh = path.at(lp.measurement)
        A, B, C, D = observer_ss(ctrl.family(), ctrl.k, np.array([s]), Jy[None],
                                 np.array([Jv]), phi[None], fh[None], model.A1, model.A2, 1e-3)
        # the exported step's states: integral, v_f, x_prev, observer (z, h); the same order
        assert lc.states[:3] == ("integral", "v_f", "x_prev")
        assert np.allclose(A[0], lc.A, rtol=1e-8, atol=1e-10)
        assert np.allclose(B[0], lc.B, rtol=1e-8, atol=1e-10 * np.abs(lc.B).max())
        assert np.allclose(C[0], lc.C, rtol=1e-7, atol=1e-9 * np.abs(lc.C).max())
        assert np.allclose(D[0], lc.D, rtol=1e-7, atol=1e-9 * np.abs(lc.D).max())


def test_the_ekf_at_rest_near_the_end_is_linearised_as_it_runs() -> None:
    """Near the cap end the EKF's film state answers the pressures through a smoothed sign
    (``tanh(v/v_eps)``) at rest: its exact derivative there is that of the smoothing (an
    eigenvalue of 3.8, a 'mode growing 1e3/s' no nonlinear loop has); the analysis takes the
    symmetric difference there, and its poles are the nonlinear sampled loop's (the slow ones,
    |z| > 0.9, that set the margins: at a kink the fast ones depend on the amplitude, i.e. on
    the differences' step)."""
    model = _model("hydraulic")
    plant = _seal("hydraulic")
    for pos in (0.03, 0.285):
        ev_nl, y, u = _nonlinear_poles(plant, lambda: make_controller("ekf", model), pos, 1)
        assert np.max(np.abs(ev_nl)) < 1.0 + 1e-6
        lp = Linearisation(plant, 1e-3).at(pos)
        lc = StepLinearisation(make_controller("ekf", model)).at(y, u)
        ev = np.linalg.eigvals(closed_loop_matrix(lp.Ad, lp.Bd, lp.C, lc.A, lc.B, lc.C, lc.D, 1))
        assert np.max(np.abs(ev)) < 1.0 + 1e-6
        _compare(ev_nl, ev, floor=0.9, slow_tol=1e-2)  # within 1 %: the kink again


@pytest.mark.slow
def test_the_derived_observer_holds_a_seal_half_as_stiff() -> None:
    """The derived lugre-observer on the built-in hydraulic plant: its bristle stiffness at
    most the low end of the seal's range, the requirement met at every resting grid point,
    explicit gains up to the derived one accepted, and on the nonlinear loop -- a LuGre seal
    half as stiff as the friction model's, the piston at rest at 95 % of the stroke -- a
    disturbance decays (with the model's own stiffness it grew to a 0.25 mm limit cycle)."""
    from controllers.cli.plant_check import plant_model
    from controllers.loop_analysis.ringing import growth

    pf = builtin_plant_file("hydraulic")
    model = plant_model(pf)
    tu = model.tuning
    p = model.friction.flat_params()
    assert 0 < tu.observer_stiffness <= 0.5 * p["sigma0"]
    m = tu.observer_margins
    assert m.stable and m.gain >= 2 and m.phase >= 30 and m.ms <= 2
    for k in (0.2, 2.0, tu.observer_gain):
        make_controller("lugre-observer", model, observer_gain=k)
    with pytest.raises(FcompError, match="observer_gain given"):
        make_controller("lugre-observer", model, observer_gain=10 * tu.observer_gain)
    seal = pf.make_plant(make_model("lugre", {
        "sigma0": 0.5 * p["sigma0"], "sigma1": p["sigma1"], "sigma2": p["sigma2"],
        "Fc": p["Fc"], "Fs": p["Fs"], "vs": p["vs"]}))
    r = growth(seal, make_controller("lugre-observer", model), 0.95 * pf.values["stroke"], 1.0,
               duration=0.6, kick=1e-7)
    assert r.rate < 0, r.rate
    assert np.ptp(r.error[-100:]) < np.ptp(r.error[:100])
