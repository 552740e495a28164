"""The fail-safe layer in the exported C, against the Python controller, on hostile input.

Every exported controller (``pid``, ``pid-ff``, ``lugre-observer``, ``ekf``, ``mpc`` in
its fixed-iteration form) is compiled once behind its layer; then NaN, +-inf, references
of 1e300, positions beyond the stroke, pressures beyond any supply, runs of them (sensor
dropouts, a reference gone wild until latched) and a NULL input pointer go through the
compiled step and the Python controller alike. Checked at every sample: the same command
(step by step from the Python state, and free-running from ``fcomp_ctrl_init``), the same
fault state (``fcomp_ctrl_fault`` against the Python layer's), the same next state, no
NaN, every command within +-u_max and the rate limit. Then the closed loop with the
hostile script, and a controller whose own state went non-finite. Needs a C compiler.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from controllers import make_controller
from controllers.base import Reference
from controllers.export import (
    CompiledController,
    block_deviations,
    check_equivalence,
    find_compiler,
    guarded_step_function,
    hostile_script,
    python_state,
    relative_difference,
    write_c,
)
from controllers.mpc_fixed import FixedIterationMPC
from controllers.plant_model import MEASURED, ControlModel, equilibrium
from controllers.safety import CAUSES, FailSafe
from fcomp.models import make_model

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="needs a C compiler")

NAMES = ["pid", "pid-ff", "lugre-observer", "ekf", "mpc"]
#: The EKF's free run amplifies rounding (docs/compensators.md): judged looser, its step not.
FREE_RTOL = {"ekf": 1e-6, "mpc": 1e-6}


class Built:
    """A controller behind its layer, its guarded export compiled."""

    def __init__(self, name: str, model: ControlModel, folder: Path) -> None:
        self.name = name
        self.model = model
        x_eq, _ = equilibrium(model.plant, 0.5 * model.stroke)
        names = model.plant.state_names
        self.y_ex = np.array([x_eq[names.index(k)] for k in MEASURED])
        self.ctrl = self.fresh()
        self.step = guarded_step_function(self.ctrl)
        if name == "mpc":
            self.ctrl.reset(0.0, self.y_ex, Reference(float(self.y_ex[0]), 0.0, 0.0))
            self.step.state0 = python_state(self.ctrl)
        write_c(self.step, folder, controller=name, plant=model.describe(), unit="A",
                u_max=model.u_max, dt=self.ctrl.dt, y_example=self.y_ex,
                r_example=float(self.y_ex[0]), limits=self.ctrl.limits)
        cc = find_compiler()
        assert cc is not None
        self.lib = CompiledController(folder, cc, self.step.n_state, folder,
                                      n_ref=self.step.n_ref)

    def fresh(self) -> FailSafe:
        if self.name == "mpc":
            return FailSafe(FixedIterationMPC(self.model, horizon=4, qp_iterations=8))
        return make_controller(self.name, self.model)  # type: ignore[return-value]


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Built]:
    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))
    return {n: Built(n, model, tmp_path_factory.mktemp(n)) for n in NAMES}


def _record(b: Built, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Measurements about the rest state and a moving reference (open loop)."""
    rng = np.random.default_rng(seed)
    dt = b.ctrl.dt
    preview = b.step.n_ref - 3
    t = np.arange(n + preview) * dt
    r = b.y_ex[0] + 0.002 * np.sin(2 * np.pi * 2 * t)
    dr = 0.002 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t)
    ddr = -0.002 * (2 * np.pi * 2) ** 2 * np.sin(2 * np.pi * 2 * t)
    Y = b.y_ex + np.column_stack([1e-5 * rng.standard_normal(n), 1e4 * rng.standard_normal(n),
                                  1e4 * rng.standard_normal(n)])
    REF = np.column_stack([r[:n], dr[:n], ddr[:n]] + [r[1 + j:n + 1 + j] for j in range(preview)])
    return Y, REF


def _hostile(b: Built, Y: np.ndarray, REF: np.ndarray, seed: int
             ) -> tuple[np.ndarray, np.ndarray]:
    """The export's scripted events, then random hostile samples beyond them."""
    lim = b.ctrl.limits
    corrupt = hostile_script(len(Y), b.model.stroke, int(lim.n_latch), int(lim.n_recover))
    Y, REF = Y.copy(), REF.copy()
    for k in range(len(Y)):
        Y[k], REF[k] = corrupt(k, Y[k], REF[k])
    rng = np.random.default_rng(seed)
    values = [math.nan, math.inf, -math.inf, 1e300, -1e300, 1e9, -1e9, b.model.stroke + 1.0]
    for k in range(260, len(Y)):
        if rng.random() < 0.25:
            if rng.random() < 0.5:
                Y[k, rng.integers(3)] = values[rng.integers(len(values))]
            else:
                REF[k, rng.integers(REF.shape[1])] = values[rng.integers(len(values))]
    return Y, REF


def _ref(row: np.ndarray) -> Reference:
    return Reference(float(row[0]), float(row[1]), float(row[2]), tuple(float(v) for v in row[3:]))


def _fault(ctrl: FailSafe) -> dict[str, int]:
    fs = ctrl.fault_state
    mask = sum(bit for bit, name in CAUSES.items() if fs.cause and name in fs.cause.split(", "))
    return {"faults": fs.faults, "consecutive": fs.consecutive, "good_run": fs.good_run,
            "latched": int(fs.latched), "cause": mask}


def _drive(b: Built, Y: np.ndarray, REF: np.ndarray, y0: np.ndarray | None = None
           ) -> dict[str, Any]:
    """Python and compiled (synced and free) on the same inputs; the differences."""
    ctrl, lib = b.fresh(), b.lib
    free, synced = lib.instance(), lib.instance()
    y0 = Y[0] if y0 is None else y0
    ctrl.reset(0.0, y0, _ref(REF[0]))
    lib.init(free)
    if b.name == "mpc":  # its init state is a Python reset's (docs)
        lib.set_state(python_state(ctrl), free)
    n = len(Y)
    out: dict[str, Any] = {k: np.zeros(n) for k in ("u_py", "u_step", "u_free", "state")}
    out["latched"] = np.zeros(n, dtype=bool)
    same_faults = True
    devs = []
    for k in range(n):
        lib.set_state(python_state(ctrl), synced)
        out["u_step"][k] = lib.step(Y[k], REF[k], synced)
        out["u_py"][k] = ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k]))
        devs.append(block_deviations(lib.state(synced), python_state(ctrl), b.step.layout))
        out["u_free"][k] = lib.step(Y[k], REF[k], free)
        out["latched"][k] = ctrl.latched
        same_faults = same_faults and lib.fault(free) == _fault(ctrl) == lib.fault(synced)
    dev, scale = (np.array([d[i] for d in devs]) for i in (0, 1))
    out["state"] = np.max(dev / np.maximum(scale.max(axis=0), 1e-300), axis=1)  # per block
    out["same_faults"] = same_faults
    out["faults"] = ctrl.faults
    out["ctrl"] = ctrl
    return out


def _assert_safe(b: Built, u: np.ndarray) -> None:
    du = b.model.du_max * b.ctrl.dt
    assert np.all(np.isfinite(u))
    assert np.all(np.abs(u) <= b.model.u_max)
    assert np.all(np.abs(np.diff(u)) <= du * (1 + 1e-12))


@pytest.mark.parametrize("name", NAMES)
def test_hostile_input_python_and_c_agree(name: str, built: dict[str, Built]) -> None:
    b = built[name]
    n = 400 if name != "mpc" else 330
    Y, REF = _hostile(b, *_record(b, n, seed=1), seed=2)
    res = _drive(b, Y, REF)
    u_max = b.model.u_max
    lat = res["latched"]
    assert int(np.sum(lat[1:] & ~lat[:-1])) >= 2  # the script's two latches, at least
    assert np.max(relative_difference(res["u_step"], res["u_py"], u_max)) <= 1e-9
    assert np.max(res["state"]) <= 1e-9
    assert np.max(relative_difference(res["u_free"], res["u_py"], u_max)) <= \
        FREE_RTOL.get(name, 1e-12)
    assert res["same_faults"]
    for u in (res["u_py"], res["u_free"]):
        _assert_safe(b, u)
    assert res["faults"] >= 40


@pytest.mark.parametrize("name", ["pid", "pid-ff", "lugre-observer", "ekf"])
def test_a_bad_first_sample_python_and_c_agree(name: str, built: dict[str, Built]) -> None:
    """Reset on a NaN measurement (Python) and init (C): the safe output until the first good
    sample, then the same start."""
    b = built[name]
    Y, REF = _record(b, 40, seed=3)
    Y[0:3] = math.nan
    res = _drive(b, Y, REF)
    assert np.all(res["u_py"][:3] == 0.0) and res["faults"] == 3
    assert np.max(relative_difference(res["u_free"], res["u_py"], b.model.u_max)) <= \
        FREE_RTOL.get(name, 1e-12)
    assert res["same_faults"] and np.max(res["state"]) <= 1e-9


@pytest.mark.parametrize("name", NAMES)
def test_closed_loop_on_the_hostile_script(name: str, built: dict[str, Built]) -> None:
    """The export's own check on hostile input: the compiled controller drives the plant, the
    Python one steps beside it: the same commands and fault states, two latches and two
    recoveries, every command within the limits."""
    b = built[name]
    lim = b.ctrl.limits
    dur = 0.6 if name != "mpc" else 0.7
    n = int(round(dur / b.ctrl.dt)) + 1
    chk = check_equivalence(b.fresh(), b.lib, b.model.plant, layout=b.step.layout,
                            start_from_init=name != "mpc", duration=dur,
                            corrupt=hostile_script(n, b.model.stroke, int(lim.n_latch),
                                                   int(lim.n_recover)))
    assert chk.max_rel_diff <= 1e-9 and chk.max_state_rel_diff <= 1e-9
    assert chk.same_faults and chk.within_limits
    assert (chk.latches, chk.recoveries) == (2, 2)
    # x, p1, p2, 3 x r, 2 x x, dr, ddr, (mpc: a future position), a dropout of N + 10,
    # a reference of 1e300 for N + 3 samples
    assert chk.faults == 33 + (name == "mpc")


def test_a_null_pointer_is_a_missing_sample(built: dict[str, Built]) -> None:
    """``fcomp_ctrl_step_ref(c, NULL, ref)``: every measured value missing, a fault, as a NaN
    sample is for the Python layer."""
    b = built["pid"]
    Y, REF = _record(b, 12, seed=4)
    ctrl, lib = b.fresh(), b.lib
    mem = lib.instance()
    lib.init(mem)
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    for k in range(10):
        assert lib.step(Y[k], REF[k], mem) == ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k]))
    u_c = lib.step_raw(None, REF[10], mem)
    u_py = ctrl.step(10 * ctrl.dt, np.full(3, math.nan), _ref(REF[10]))
    assert u_c == u_py and lib.fault(mem) == _fault(ctrl)
    assert lib.fault(mem)["cause"] == 7 and lib.fault(mem)["faults"] == 1
    assert math.isfinite(lib.step_raw(Y[11], None, mem))
    assert lib.fault(mem)["cause"] == 8


@pytest.mark.parametrize("name", ["pid", "lugre-observer"])
def test_a_non_finite_law_state_is_a_controller_fault(name: str,
                                                      built: dict[str, Built]) -> None:
    """The law's integral gone NaN in both: a fault of cause ``controller``, and the
    controller re-enters at once from the measurement -- in C as in Python."""
    b = built[name]
    Y, REF = _record(b, 30, seed=5)
    ctrl, lib = b.fresh(), b.lib
    mem = lib.instance()
    ctrl.reset(0.0, Y[0], _ref(REF[0]))
    for k in range(10):
        ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k]))
    ctrl.inner.law.integral = math.nan
    lib.set_state(python_state(ctrl), mem)
    for k in range(10, 30):
        u_c = lib.step(Y[k], REF[k], mem)
        u_py = ctrl.step(k * ctrl.dt, Y[k], _ref(REF[k]))
        assert u_c == u_py and lib.fault(mem) == _fault(ctrl), k
    assert ctrl.faults == 1 and lib.fault(mem)["cause"] == 16
    assert math.isfinite(ctrl.inner.law.integral)


def test_the_header_tells_the_layer(built: dict[str, Built]) -> None:
    b = built["pid"]
    folder = Path(b.lib.dll._name).parent
    h = (folder / "fcomp_ctrl.h").read_text()
    nl = b.step.n_state - 12
    assert f"#define FCOMP_CTRL_FS {nl}" in h
    assert "#define FCOMP_CTRL_FAULT_LATCH 5" in h and "#define FCOMP_CTRL_FAULT_RECOVER 50" in h
    assert "fcomp_ctrl_fault_t fcomp_ctrl_fault(const fcomp_ctrl_t* c);" in h
    assert "closed centre, u = 0" in h
