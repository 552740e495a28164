"""``fcomp export CONTROLLER``: a controller's step as C, compiled, checked and timed.

On the built-in hydraulic plant every exported controller's compiled step
gives, in closed loop, the Python controller's commands at every sample
(relative 1e-9), and its step time is measured; the check is not a
tautology (a Python controller tuned differently fails it); without a C
compiler (``FCOMP_CC`` naming a missing program, the documented switch) the
files are still written with one warning line; an unknown controller and
``mpc`` are refused in one line, exit 2. Needs a C compiler (skipped without).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from controllers.export import find_compiler
from fcomp.cli.main import main

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="needs a C compiler")

FILES = ("fcomp_ctrl.h", "fcomp_ctrl.c", "fcomp_ctrl_bench.c", "example.c", "Makefile",
         "fcomp_ctrl_casadi.c", "fcomp_ctrl_casadi.h")


def _run(args: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("controller", ["pid", "pid-ff", "lugre-observer", "ekf"])
def test_export_is_equivalent_and_timed(controller: str, tmp_path: Path,
                                        capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "c"
    code, _, err = _run(["export", controller, "--plant", "hydraulic", "--friction", "nmlgm",
                         "-o", str(out), "--json", str(tmp_path / "r.json")], capsys)
    assert code == 0, err
    doc = json.loads((tmp_path / "r.json").read_text())
    assert {"controller", "files", "equivalent", "max_rel_diff", "step_time_median",
            "step_time_max"} <= set(doc)
    assert doc["controller"] == controller
    assert doc["equivalent"] is True
    assert doc["max_rel_diff"] <= 1e-9 and doc["max_state_rel_diff"] <= 1e-9
    if controller != "ekf":  # the EKF amplifies rounding (docs): the free run is only close
        assert doc["free_run_max_rel_diff"] == 0.0
    assert doc["steps_checked"] == 601
    assert doc["timed_steps"] >= 100_000
    assert 0 < doc["step_time_median"] <= doc["step_time_max"]
    assert doc["step_time_clock"] == "cpu"
    assert 0 < doc["step_time_wall_median"] <= doc["step_time_wall_max"]
    assert doc["rate"] == doc["plant_rate"] == 1000.0 and doc["sample_time"] == 1e-3
    fc = doc["fault_check"]
    assert fc["equivalent"] and fc["same_faults"] and fc["within_limits"]
    assert (fc["faults"], fc["latches"], fc["recoveries"]) == (33, 2, 2)
    assert doc["fail_safe"]["safe_output"] == "centre"
    assert doc["warnings"] == []
    for name in FILES:
        assert (out / name).is_file()
        assert str(out / name) in doc["files"]


def test_the_check_sees_a_different_controller(tmp_path: Path) -> None:
    """The compiled observer with gain 0.5 checked against a Python observer with gain 0.6."""
    from controllers import make_controller
    from controllers.export import (
        CompiledController,
        check_equivalence,
        guarded_step_function,
        write_c,
    )
    from controllers.plant_model import ControlModel
    from fcomp.models import make_model

    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))
    ctrl = make_controller("lugre-observer", model, observer_gain=0.5)
    step = guarded_step_function(ctrl)
    write_c(step, tmp_path / "c", controller="lugre-observer", plant=model.describe(),
            unit="A", u_max=model.u_max, dt=ctrl.dt, y_example=[0.1, 1e6, 1e6], r_example=0.1)
    cc = find_compiler()
    assert cc is not None
    lib = CompiledController(tmp_path / "c", cc, step.n_state, tmp_path)
    same = check_equivalence(ctrl, lib, model.plant, layout=step.layout, duration=0.3)
    assert same.max_rel_diff <= 1e-9 and same.free_max_rel_diff <= 1e-9
    other = make_controller("lugre-observer", model, observer_gain=0.6)
    diff = check_equivalence(other, lib, model.plant, layout=step.layout, duration=0.3)
    assert diff.max_rel_diff > 1e-6 and diff.max_state_rel_diff > 1e-6


def test_no_compiler_still_writes_the_code(tmp_path: Path, capsys: pytest.CaptureFixture,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("FCOMP_CC", str(tmp_path / "no-such-cc"))
    out = tmp_path / "c"
    code, stdout, err = _run(["export", "pid", "-o", str(out), "--json", "-"], capsys)
    assert code == 0
    doc = json.loads(stdout)
    assert doc["equivalent"] is None and doc["max_rel_diff"] is None
    assert doc["step_time_median"] is None
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fcomp: warning: no C compiler found")
    assert "FCOMP_CC" in lines[0]
    assert [w["code"] for w in doc["warnings"]] == ["export"]
    for name in FILES:
        assert (out / name).is_file()


@pytest.mark.parametrize("args, words", [(["nope"], "unknown controller"),
                                         (["pid", "--plant", "motion"], "--plant"),
                                         (["pid", "--option", "kp=-1"], "kp")])
def test_bad_input_is_one_line(args: list[str], words: str, tmp_path: Path,
                               capsys: pytest.CaptureFixture) -> None:
    code, _, err = _run(["export", *args, "-o", str(tmp_path / "c")], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and words in err, err
    assert not (tmp_path / "c").exists()


def test_mpc_fixed_iteration_form_is_equivalent(tmp_path: Path) -> None:
    """``mpc`` in its fixed-iteration form (the QP by ADMM): the compiled step equals the
    Python :class:`~controllers.mpc_fixed.FixedIterationMPC` step for step and free-running
    (the API, a short check and no timing: the MPC's C takes some 10 s to compile)."""
    from controllers.base import Reference
    from controllers.export import (
        CompiledController,
        check_equivalence,
        python_state,
        step_function,
        write_c,
    )
    from controllers.mpc_fixed import FixedIterationMPC
    from controllers.plant_model import ControlModel
    from fcomp.models import make_model

    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))
    ctrl = FixedIterationMPC(model, horizon=5, qp_iterations=10)
    step = step_function(ctrl)
    assert step.n_ref == 3 + 5
    y0 = np.array([0.5 * model.stroke, 2e6, 2e6])
    ctrl.reset(0.0, y0, Reference(float(y0[0]), 0.0, 0.0))
    step.state0 = python_state(ctrl)
    write_c(step, tmp_path / "c", controller="mpc", plant=model.describe(), unit="A",
            u_max=model.u_max, dt=ctrl.dt, y_example=y0, r_example=float(y0[0]))
    cc = find_compiler()
    assert cc is not None
    lib = CompiledController(tmp_path / "c", cc, step.n_state, tmp_path, n_ref=step.n_ref)
    chk = check_equivalence(ctrl, lib, model.plant, layout=step.layout, start_from_init=False,
                            duration=0.2)
    assert chk.u_step.size == 101
    assert chk.max_rel_diff <= 1e-9 and chk.max_state_rel_diff <= 1e-9
    assert chk.free_max_rel_diff <= 1e-9
    assert np.ptp(chk.u_python) > 0  # the loop moved
    # the fallback law: a warm start gone non-finite makes both take it, and reset to it
    ctrl.solver.U[:] = np.nan
    lib.set_state(python_state(ctrl))
    y, ref = chk.Y[-1], chk.REF[-1]
    u_c = lib.step(y, ref)
    u_py = ctrl.step(0.2, y, Reference(ref[0], ref[1], ref[2], tuple(ref[3:])))
    assert ctrl.fallback_active and np.isfinite(u_py)
    assert abs(u_c - u_py) <= 1e-9 * abs(u_py)
    assert np.allclose(lib.state()[-15:-10], u_py, rtol=1e-12, atol=0)  # U reset to u


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_the_example_builds_and_runs(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "c"
    code, _, err = _run(["export", "pid", "-o", str(out), "--duration", "0.05"], capsys)
    assert code == 0, err
    cc = find_compiler()
    subprocess.run(["make", "-s", f"CC={cc}"], cwd=out, check=True, capture_output=True)
    run = subprocess.run([str(out / "example")], capture_output=True, text=True, check=True)
    assert "step 4: u =" in run.stdout and "step time over 100000 steps" in run.stdout
    assert "after a dropout of 5 samples: faults 5, latched 1, cause 7, u = 0" in run.stdout
    assert "(CPU time of the step)" in run.stdout and "wall-clock worst" in run.stdout


def test_mpc_from_the_command_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A short-horizon MPC (counts given as numbers on the command line) exports, is
    equivalent to its fixed-iteration Python form, and says which form that is; its rate
    (250 Hz here, the plant's 1 kHz) is said on the console and in the JSON (issue 42,
    item 16)."""
    code, out, err = _run(["export", "mpc", "--option", "horizon=4", "--option", "rate=250",
                           "--option", "qp_iterations=8", "--duration", "0.2", "-o",
                           str(tmp_path / "c"), "--json", "-"], capsys)
    assert code == 0, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "mpc runs at 250 Hz (a step every 4 ms), the plant's [control] " \
        "rate is 1000 Hz" in lines[0], err
    doc = json.loads(out)
    assert (doc["rate"], doc["plant_rate"], doc["sample_time"]) == (250.0, 1000.0, 0.004)
    assert [w["code"] for w in doc["warnings"]] == ["export"]
    assert doc["fault_check"]["equivalent"] is True
    assert doc["equivalent"] is True and doc["max_rel_diff"] <= 1e-9
    assert doc["python_reference"] == "controllers.mpc_fixed.FixedIterationMPC"
    assert "8 ADMM iterations" in doc["step"]
    assert doc["steps_checked"] == 51 and doc["step_time_median"] > 0
    assert "#define FCOMP_CTRL_NREF 7" in (tmp_path / "c" / "fcomp_ctrl.h").read_text()


def test_a_failing_compiler_still_leaves_the_code(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    false = shutil.which("false")
    if false is None:
        pytest.skip("needs the false program")
    monkeypatch.setenv("FCOMP_CC", false)
    code, stdout, err = _run(["export", "pid", "-o", str(tmp_path / "c"), "--json", "-"], capsys)
    assert code == 0
    assert json.loads(stdout)["equivalent"] is None
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "failed on the generated code" in lines[0]
    assert (tmp_path / "c" / "fcomp_ctrl_casadi.c").is_file()


def test_the_console_tells_the_rate_the_layer_and_the_times(tmp_path: Path,
                                                             capsys: pytest.CaptureFixture
                                                             ) -> None:
    """Issue 42 item 16: the console says the rate, the fail-safe layer, the hostile check,
    and the step time as the step's own CPU time beside the wall-clock worst, named so."""
    code, out, err = _run(["export", "pid", "-o", str(tmp_path / "c"), "--duration", "0.2"],
                          capsys)
    assert code == 0 and err == ""
    assert "runs at 1000 Hz: call it every 1 ms" in out
    assert "fail-safe layer: safe output centre after 5 faulty samples in a row" in out
    assert "on hostile input 0 over" in out and "2 latches, 2 recoveries" in out
    assert "compiled step time (CPU time of the step): median" in out
    assert "wall-clock worst" in out and "other processes" in out


def test_a_check_that_is_not_a_number_is_refused(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 42 item 10: a check whose difference is NaN is never a result ("equivalent: NO
    (nan)", exit 0, before): one line, and nothing claimed."""
    import controllers.export.pipeline as pipeline
    from controllers.plant_model import ControlModel
    from fcomp.errors import FcompError
    from fcomp.models import make_model

    real = pipeline.check_equivalence

    def poisoned(*args, **kwargs):  # type: ignore[no-untyped-def]
        res = real(*args, **kwargs)
        res.u_step[3] = float("nan")
        return res

    monkeypatch.setattr(pipeline, "check_equivalence", poisoned)
    model = ControlModel("hydraulic", make_model("nmlgm", params="seed002-type1"))
    with pytest.raises(FcompError, match="gave no number"):
        pipeline.export_controller("pid", model, tmp_path / "c", duration=0.05)
