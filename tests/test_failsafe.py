"""The fail-safe layer (controllers.safety) in Python: validation, hold, latch, recovery,
anti-windup, range and rate limit, for every controller; in closed loop with sensor dropouts.

The checks are made against independent computations written here, not against the
layer's own functions: the held inputs are rebuilt sample by sample from the documented
rules and fed to the bare controller (its law alone), whose command, clipped and
rate-limited by hand, must equal the layer's; fault counts are counted from the injected
values; the bumpless re-entry is checked on the force balance it promises (demand equal
to the actuator force of the measured pressures); closed-loop runs with a sensor dropout
are compared with the same run without it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from controllers import CONTROLLERS, make_controller
from controllers.base import Reference
from controllers.harness import LoopConfig, SensorFault, run_closed_loop
from controllers.plant_model import ControlModel, equilibrium
from controllers.safety import FailSafe, Limits, unwrap
from controllers.tasks import get_task
from fcomp.errors import FcompError
from fcomp.models import make_model
from plants.planfile import PlantFileError, builtin_path, parse_plant, read_plant_file

NAMES = ["pid", "pid-ff", "lugre-observer", "ekf", "mpc"]
#: Small MPC (the layer is the same for every horizon).
OPTIONS = {"mpc": {"horizon": 5}}


@pytest.fixture(scope="module")
def model() -> ControlModel:
    return ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))


def _pair(name: str, model: ControlModel) -> tuple[FailSafe, object]:
    """The controller behind the layer, and the same controller's law alone."""
    opts = OPTIONS.get(name, {})
    ctrl = make_controller(name, model, **opts)
    assert isinstance(ctrl, FailSafe)
    return ctrl, CONTROLLERS.get(name)(model, **opts)


def _record(model: ControlModel, n: int, dt: float, preview: int, seed: int = 0
            ) -> tuple[np.ndarray, np.ndarray]:
    """Plausible measurements and references (seed002-sine about mid-stroke): ``Y (n, 3)``,
    ``REF (n, 3 + preview)``."""
    rng = np.random.default_rng(seed)
    x_mid = 0.5 * model.stroke
    x_eq, _ = equilibrium(model.plant, x_mid)
    names = model.plant.state_names
    t = np.arange(n + preview) * dt
    r, dr, ddr = get_task("seed002-sine").sample(t)
    r = r + x_mid
    Y = np.empty((n, 3))
    Y[:, 0] = r[:n] + 2e-5 * rng.standard_normal(n)
    Y[:, 1] = x_eq[names.index("p1")] + 2e4 * rng.standard_normal(n)
    Y[:, 2] = x_eq[names.index("p2")] + 2e4 * rng.standard_normal(n)
    REF = np.empty((n, 3 + preview))
    REF[:, 0], REF[:, 1], REF[:, 2] = r[:n], dr[:n], ddr[:n]
    for j in range(preview):
        REF[:, 3 + j] = r[1 + j:n + 1 + j]
    return Y, REF


def _ref(row: np.ndarray) -> Reference:
    return Reference(float(row[0]), float(row[1]), float(row[2]), tuple(float(v) for v in row[3:]))


def _expected_limits(model: ControlModel, dt: float) -> dict[str, float]:
    """The documented numbers of the rules (controllers.safety, module docstring)."""
    L = model.stroke
    sp = math.hypot(model.sensors.p_noise, model.sensors.p_quantum / math.sqrt(12))
    return {"x_lo": -0.05 * L, "x_hi": 1.05 * L, "p_lo": -6 * sp,
            "p_hi": 2 * float(model.params["ps"]), "v_max": L / dt,
            "a_max": (model.force_max - model.force_min) / model.mass,
            "du": model.du_max * dt, "u_max": model.u_max}


def _clean(Y: np.ndarray, REF: np.ndarray, lim: dict[str, float], y0: np.ndarray,
           r0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The inputs the rules promise the controller steps on (held and clipped), written
    out independently: ``(Y_used, REF_used, faulty)``."""
    Yc, Rc = Y.copy(), REF.copy()
    faulty = np.zeros(len(Y), dtype=bool)
    hold_y, hold_r = np.array(y0, dtype=float), r0
    bounds = [(lim["x_lo"], lim["x_hi"]), (lim["p_lo"], lim["p_hi"]), (lim["p_lo"], lim["p_hi"])]
    for k in range(len(Y)):
        for i, (lo, hi) in enumerate(bounds):
            v = Y[k, i]
            if not (lo <= v <= hi):
                Yc[k, i] = hold_y[i]
                faulty[k] = True
        hold_y = Yc[k].copy()
        positions = np.concatenate([[REF[k, 0]], REF[k, 3:]])
        ok = (bool(np.all((positions >= lim["x_lo"]) & (positions <= lim["x_hi"])))
              and math.isfinite(REF[k, 1]) and math.isfinite(REF[k, 2]))
        stroke = lim["x_hi"] + lim["x_lo"]  # (1.05 L) + (-0.05 L)
        if ok:
            Rc[k, 0] = min(max(REF[k, 0], 0.0), stroke)
            Rc[k, 1] = min(max(REF[k, 1], -lim["v_max"]), lim["v_max"])
            Rc[k, 2] = min(max(REF[k, 2], -lim["a_max"]), lim["a_max"])
            Rc[k, 3:] = np.clip(REF[k, 3:], 0.0, stroke)
        else:
            Rc[k, 0], Rc[k, 1], Rc[k, 2] = hold_r, 0.0, 0.0
            Rc[k, 3:] = hold_r
            faulty[k] = True
        hold_r = Rc[k, 0]
    return Yc, Rc, faulty


def _corrupt_sparse(Y: np.ndarray, REF: np.ndarray, stroke: float, gap: int, seed: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Isolated hostile values, ``gap`` samples apart (never two faulty samples in a row:
    no latch): NaN, +-inf, 1e300, positions beyond the stroke, pressures beyond any supply."""
    rng = np.random.default_rng(seed)
    Y, REF = Y.copy(), REF.copy()
    kinds = [("y", 0, math.nan), ("y", 0, math.inf), ("y", 0, stroke + 1.0), ("y", 0, -1.0),
             ("y", 1, math.nan), ("y", 1, 1e12), ("y", 2, -math.inf), ("y", 2, -5e5),
             ("r", 0, 1e300), ("r", 0, -1e300), ("r", 0, math.nan), ("r", 1, math.nan),
             ("r", 2, math.inf), ("r", -1, math.nan)]
    for j, k in enumerate(range(10, len(Y), gap)):
        where, i, v = kinds[(j + int(rng.integers(len(kinds)))) % len(kinds)]
        (Y if where == "y" else REF)[k, i] = v
    return Y, REF


# ----------------------------------------------------------------------- rules
def test_the_limits_are_the_documented_ones(model: ControlModel) -> None:
    ctrl = make_controller("pid", model)
    lim = ctrl.limits
    want = _expected_limits(model, ctrl.dt)
    for k, v in want.items():
        assert getattr(lim, k) == pytest.approx(v, rel=1e-12), k
    assert lim.r_hi == model.stroke
    assert (lim.n_latch, lim.n_recover, lim.hold, lim.safe_value) == (5, 50, False, 0.0)


@pytest.mark.parametrize("name", NAMES)
def test_isolated_faults_hold_the_last_good_value(name: str, model: ControlModel) -> None:
    """Isolated hostile samples of every kind: the layer's command equals the bare law's on
    the inputs held and clipped by hand, then clipped to +-u_max and rate-limited by hand;
    the faults counted are the hostile samples."""
    ctrl, law = _pair(name, model)
    n = 160
    Y, REF = _record(model, n, ctrl.dt, ctrl.preview)
    Yb, Rb = _corrupt_sparse(Y, REF, model.stroke, gap=7, seed=1)
    lim = _expected_limits(model, ctrl.dt)
    Yc, Rc, faulty = _clean(Yb, Rb, lim, Y[0], float(np.clip(REF[0, 0], 0, model.stroke)))
    assert faulty.sum() >= 20
    ctrl.reset(0.0, Yb[0], _ref(Rb[0]))
    law.reset(0.0, Yc[0], _ref(Rc[0]))
    u_prev = 0.0
    for k in range(n):
        u = ctrl.step(k * ctrl.dt, Yb[k], _ref(Rb[k]))
        raw = law.step(k * ctrl.dt, Yc[k], _ref(Rc[k]))
        want = min(max(min(max(raw, -lim["u_max"]), lim["u_max"]), u_prev - lim["du"]),
                   u_prev + lim["du"])
        law.applied(want)
        assert u == want, (k, u, want)
        u_prev = u
        assert ctrl.faults == int(faulty[:k + 1].sum())
        assert not ctrl.latched
    assert ctrl.last_fault is not None


@pytest.mark.parametrize("name", NAMES)
def test_a_dropout_latches_the_safe_output_and_good_samples_resume(name: str,
                                                                   model: ControlModel) -> None:
    """N - 1 faulty samples in a row hold; the N-th latches the closed centre (reached at
    the rate limit, then held at 0 while the controller is not stepped); M good samples in a
    row resume, the M-th one already the controller's. Never NaN, within the range, within
    the rate limit."""
    ctrl, _ = _pair(name, model)
    N, M = 5, 50
    du = model.du_max * ctrl.dt
    n = 300
    Y, REF = _record(model, n, ctrl.dt, ctrl.preview, seed=2)
    a = 30
    Y[a:a + N - 1] = math.nan          # below the latch
    b = a + N - 1 + 20
    Y[b:b + N + 20] = math.nan         # a dropout: latch at b + N - 1
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    U = np.zeros(n)
    lat = np.zeros(n, dtype=bool)
    for k in range(n):
        U[k] = ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k]))
        lat[k] = ctrl.latched
        fs = ctrl.fault_state
        assert fs.latched == ctrl.latched and fs.faults == ctrl.faults
    assert np.all(np.isfinite(U)) and np.all(np.abs(U) <= model.u_max)
    assert np.all(np.abs(np.diff(np.concatenate([[0.0], U]))) <= du * (1 + 1e-12))
    assert not lat[:b + N - 1].any()
    first = b + N - 1
    assert lat[first]
    end = b + N + 20  # first good sample
    assert lat[first:end + M - 1].all() and not lat[end + M - 1:].any()
    # while latched, the command slews to the closed centre and stays there
    k0 = first + int(math.ceil(abs(U[first - 1]) / du)) + 1
    assert np.all(U[k0:end + M - 1] == 0.0)
    assert ctrl.faults == (N - 1) + (N + 20)
    assert ctrl.last_fault == "position, pressure p1, pressure p2"


@pytest.mark.parametrize("name", ["pid", "pid-ff", "lugre-observer", "ekf"])
def test_reentry_is_bumpless_in_force(name: str, model: ControlModel) -> None:
    """At re-entry the PID's integral is set so that its force demand equals the actuator
    force of the measured pressures (Astrom & Hagglund's bumpless transfer); a plain reset
    would demand kp*e more."""
    ctrl, _ = _pair(name, model)
    n = 120
    Y, REF = _record(model, n, ctrl.dt, 0, seed=3)
    Y[10:10 + 5] = math.nan
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    k_back = 10 + 5 + 50 - 1  # the M-th good sample
    inner = unwrap(ctrl)
    for k in range(k_back):
        ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k]))
    assert ctrl.latched
    ctrl.step(k_back * ctrl.dt, Y[k_back], _ref(REF[k_back]))
    assert not ctrl.latched
    F_a = model.actuator_force(Y[k_back])
    assert inner.F_demand == pytest.approx(F_a, rel=1e-9, abs=1e-6)
    lo, hi = inner.integral_bounds
    assert lo <= inner.law.integral <= hi


def test_a_huge_reference_never_winds_the_integral(model: ControlModel) -> None:
    """The issue's case: a reference step to 1e300. The bare law's integral stays within
    its force bound (it reached -8.8e296 before); behind the layer a short one (below the
    latch) is held, so the integral equals that of the same run with the reference held --
    it never wound, nothing to unwind."""
    law = CONTROLLERS.get("pid")(model)
    y = np.array([0.15, *equilibrium(model.plant, 0.15)[0][[2, 3]]])
    law.reset(0.0, y, Reference(0.15, 0.0, 0.0))
    for k in range(50):
        law.step(k * law.dt, y, Reference(1e300, 0.0, 0.0))
    bound = max(abs(model.force_min), abs(model.force_max))
    assert abs(law.gains.ki * law.law.integral) <= bound * (1 + 1e-12)
    ctrl, ref_run = make_controller("pid", model), make_controller("pid", model)
    n = 60
    Y, REF = _record(model, n, ctrl.dt, 0, seed=4)
    bad, held = REF.copy(), REF.copy()
    bad[20:23, 0] = 1e300
    held[20:23] = [REF[19, 0], 0.0, 0.0]
    ctrl.reset(0.0, Y[0], _ref(bad[0]))
    ref_run.reset(0.0, Y[0], _ref(held[0]))
    for k in range(n):
        assert ctrl.step(k * ctrl.dt, Y[k], _ref(bad[k])) == \
            ref_run.step(k * ctrl.dt, Y[k], _ref(held[k]))
        assert unwrap(ctrl).law.integral == unwrap(ref_run).law.integral
    assert ctrl.faults == 3 and ref_run.faults == 0


@pytest.mark.parametrize("name", NAMES)
def test_random_hostile_input_never_gives_nan(name: str, model: ControlModel) -> None:
    """A fifth of the samples hostile at random (NaN, inf, 1e300, out of range, runs of
    them): every command finite, within +-u_max and the rate limit; the fault count is the
    count of hostile samples."""
    ctrl, _ = _pair(name, model)
    n = 400
    Y, REF = _record(model, n, ctrl.dt, ctrl.preview, seed=5)
    rng = np.random.default_rng(6)
    values = [math.nan, math.inf, -math.inf, 1e300, -1e300, 1e9, -1e9]
    hostile = rng.random(n) < 0.2
    hostile[0] = False
    hostile[200:240] = True  # a long run: latched
    for k in np.flatnonzero(hostile):
        if rng.random() < 0.6:
            Y[k, rng.integers(3)] = values[rng.integers(len(values))]
        else:
            REF[k, rng.integers(REF.shape[1])] = values[rng.integers(len(values))]
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    U = np.array([ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k])) for k in range(n)])
    du = model.du_max * ctrl.dt
    assert np.all(np.isfinite(U)) and np.all(np.abs(U) <= model.u_max)
    assert np.all(np.abs(np.diff(U)) <= du * (1 + 1e-12))
    # a dr or ddr of 1e9 (finite) is clipped, not a fault: count what the rules call faulty
    lim = _expected_limits(model, ctrl.dt)
    _, _, faulty = _clean(Y, REF, lim, Y[0], float(REF[0, 0]))
    assert ctrl.faults == int(faulty.sum())


def test_a_bad_first_sample_waits_for_a_good_one(model: ControlModel) -> None:
    """Reset on a NaN measurement: the safe output until the first good sample, which
    starts the controller as a reset from it would."""
    ctrl, law = _pair("pid", model)
    Y, REF = _record(model, 20, ctrl.dt, 0, seed=7)
    Y[0:3, 0] = math.nan
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    assert not ctrl.started
    u = [ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k])) for k in range(3)]
    assert u == [0.0, 0.0, 0.0] and ctrl.faults == 3
    law.reset(3 * ctrl.dt, Y[3], _ref(REF[3]))
    raw = law.step(3 * ctrl.dt, Y[3], _ref(REF[3]))
    du = model.du_max * ctrl.dt
    assert ctrl.step(3 * ctrl.dt, Y[3], _ref(REF[3])) == min(max(raw, -du), du)
    assert ctrl.started


def test_a_controller_fault_reseeds_it(model: ControlModel,
                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """The law's own state gone non-finite (the integral set to NaN): a fault of cause
    controller, and the controller re-enters at once from the measurement. A step that
    raises FloatingPointError (as the EKF's prediction does): the last command held, and
    re-entry at the next sample."""
    ctrl = make_controller("pid", model)
    Y, REF = _record(model, 30, ctrl.dt, 0, seed=8)
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    u = [ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k])) for k in range(10)]
    inner = unwrap(ctrl)
    inner.law.integral = math.nan
    assert math.isfinite(ctrl.step(10 * ctrl.dt, Y[10], _ref(REF[10])))
    assert ctrl.last_fault == "controller" and ctrl.faults == 1
    assert math.isfinite(inner.law.integral) and ctrl.consecutive_faults == 0
    u11 = ctrl.step(11 * ctrl.dt, Y[11], _ref(REF[11]))

    def broken(*args: object) -> float:
        raise FloatingPointError("prediction is not finite")

    monkeypatch.setattr(inner, "step", broken)
    assert ctrl.step(12 * ctrl.dt, Y[12], _ref(REF[12])) == u11
    assert ctrl.faults == 2 and ctrl.consecutive_faults == 1
    monkeypatch.undo()
    calls: list[float] = []
    monkeypatch.setattr(inner, "reenter", lambda t, y, r, uh: calls.append(uh))
    ctrl.step(13 * ctrl.dt, Y[13], _ref(REF[13]))
    assert calls == [u11] and ctrl.consecutive_faults == 0 and not ctrl.latched
    assert len(u) == 10


@pytest.mark.parametrize(("spec", "expect"), [("hold", None), (0.004, 0.004), (-0.002, -0.002)])
def test_the_safe_output_the_plant_names(spec: str | float, expect: float | None) -> None:
    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"),
                         safe_output=spec, fault_latch=2, fault_recover=3)
    ctrl = make_controller("pid", model)
    Y, REF = _record(model, 40, ctrl.dt, 0, seed=9)
    Y[20:35, 0] = math.nan
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    U = [ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k])) for k in range(40)]
    held = U[20] if expect is None else expect  # latched at the 2nd faulty sample (21)
    assert all(u == pytest.approx(held, abs=0) for u in U[23:35])


def test_settings_are_checked(model: ControlModel) -> None:
    friction = make_model("nmlgm", params="seed002-type1")
    for bad, words in [({"safe_output": "open"}, "safe_output must be"),
                       ({"safe_output": 0.5}, "outside the valve's range"),
                       ({"fault_latch": 0}, "fault_latch must be a whole number"),
                       ({"fault_recover": 2.5}, "fault_recover must be a whole number"),
                       ({"position_margin": -1.0}, "position_margin must be a positive number"),
                       ({"pressure_max": math.nan}, "pressure_max must be a positive number")]:
        with pytest.raises(FcompError, match=words):
            ControlModel("hydraulic", friction, **bad)


def test_plant_file_keys(tmp_path) -> None:  # type: ignore[no-untyped-def]
    text = builtin_path("hydraulic").read_text()
    good = text.replace("rate = 1000.0 ", 'safe_output = "hold"\nfault_latch = 3\n'
                        "fault_recover = 20\nposition_margin = 0.01\npressure_max = 2.0e7\n"
                        "rate = 1000.0 ")
    (tmp_path / "p.toml").write_text(good)
    pf = read_plant_file(tmp_path / "p.toml")
    assert pf.control["safe_output"] == "hold" and pf.control["fault_latch"] == 3
    model = ControlModel(pf, make_model("nmlgm", params="seed002-type1"))
    lim = make_controller("pid", model).limits
    assert (lim.hold, lim.n_latch, lim.n_recover, lim.x_lo, lim.p_hi) == \
        (True, 3, 20, -0.01, 2.0e7)
    import tomllib

    doc = tomllib.loads(text)
    for key, value, words in [("safe_output", "open", "safe_output = 'open' must be one of"),
                              ("safe_output", 0.02, "outside the valve's range"),
                              ("safe_output", True, "is not a finite number"),
                              ("fault_latch", 2.5, "whole number of samples"),
                              ("fault_recover", 0, "must be > 0"),
                              ("pressure_max", -1.0, "must be > 0")]:
        d = {k: dict(v) if isinstance(v, dict) else v for k, v in doc.items()}
        d["control"][key] = value
        with pytest.raises(PlantFileError) as err:
            parse_plant(d, "p.toml")
        assert len(err.value.problems) == 1 and words in err.value.problems[0], \
            err.value.problems
    assert make_controller("pid", ControlModel(
        "hydraulic", make_model("nmlgm", params="seed002-type1"))).limits.safe_value == 0.0


def test_the_layer_keeps_the_law_reachable(model: ControlModel) -> None:
    """make_controller wraps once; the law's attributes read through; the exported step of
    the wrapped controller (the linearisation helpers' step_function) is the law's."""
    from controllers.export import step_function

    ctrl = make_controller("pid-ff", model)
    assert isinstance(ctrl, FailSafe) and not isinstance(unwrap(ctrl), FailSafe)
    assert ctrl.gains is unwrap(ctrl).gains and ctrl.name == "pid-ff" and ctrl.preview == 0
    with pytest.raises(FcompError, match="once"):
        FailSafe(ctrl)
    a, b = step_function(ctrl), step_function(unwrap(ctrl))
    assert a.n_state == b.n_state and a.layout == b.layout
    s = np.array([1.0, 0.3, 0.01, 0.15])
    args = (s, [0.1501, 3e6, 2e6], [0.15, 0.01, 0.0])
    assert float(a.fn(*args)[0]) == float(b.fn(*args)[0])
    assert isinstance(Limits.of(model, 1e-3), Limits)


# ----------------------------------------------------------------- closed loop
@pytest.mark.parametrize("name", NAMES)
def test_a_sensor_dropout_mid_run_and_the_loop_recovers(name: str) -> None:
    """Closed loop on the built-in hydraulic servo, steps task: every sensor reads NaN for
    30 ms at 0.5 s. The layer latches the closed centre (the load sags on its oil column),
    resumes after its good samples, and the run ends tracking as the run without the
    dropout does; the metrics count what happened."""
    opts = OPTIONS.get(name)
    clean = run_closed_loop(name, "steps", LoopConfig(fast=True), opts)
    hit = run_closed_loop(name, "steps", LoopConfig(
        fast=True, sensor_faults=(SensorFault(0.4999, 0.03),)), opts)
    m = hit.metrics
    dt = hit.t[1] - hit.t[0]
    n_bad = int(round(0.03 / dt))
    assert m.faults == n_bad and m.max_consecutive_faults == n_bad
    assert m.latches == 1 and m.latched_steps == n_bad - 5 + 1 + 50 - 1
    assert m.last_fault == "position, pressure p1, pressure p2"
    assert clean.metrics.faults == 0 and clean.metrics.latches == 0
    assert hit.faults[-1] == n_bad and hit.latched.sum() == m.latched_steps
    assert np.all(np.isfinite(hit.u))
    assert np.all(np.abs(np.diff(hit.u)) <= hit_du(hit) * (1 + 1e-12))
    # recovered: over the last 0.3 s the error is the fault-free run's, within 20 um
    tail = hit.t > hit.t[-1] - 0.3
    e_hit = np.sqrt(np.mean((hit.r - hit.x)[tail] ** 2))
    e_clean = np.sqrt(np.mean((clean.r - clean.x)[tail] ** 2))
    assert e_hit < e_clean + 20e-6, (e_hit, e_clean)


def hit_du(res) -> float:  # type: ignore[no-untyped-def]
    from plants.planfile import builtin_plant_file

    dt = res.t[1] - res.t[0]
    return builtin_plant_file("hydraulic").control["du_max"] * dt


def test_a_short_glitch_does_not_latch() -> None:
    """Two samples of a wild position reading: held, counted, no latch, the run as good."""
    clean = run_closed_loop("pid", "steps", LoopConfig(fast=True))
    hit = run_closed_loop("pid", "steps", LoopConfig(
        fast=True, sensor_faults=(SensorFault(0.4999, 0.002, ("x",), 5.0),)))
    assert hit.metrics.faults == 2 and hit.metrics.latches == 0
    assert hit.metrics.last_fault == "position"
    assert hit.metrics.rms_error == pytest.approx(clean.metrics.rms_error, rel=0.05)


def test_sensor_faults_are_checked() -> None:
    with pytest.raises(FcompError, match="channels are x, p1, p2"):
        SensorFault(0.1, 0.01, ("v",))
    with pytest.raises(FcompError, match="positive duration"):
        SensorFault(0.1, 0.0)
