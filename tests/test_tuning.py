"""The compensators' default tuning derived from the plant (controllers/tuning.py)."""

from __future__ import annotations

import math
from pathlib import Path

import control as ct
import numpy as np
import pytest

from controllers import make_controller
from controllers.harness import LoopConfig, control_model, run_closed_loop
from controllers.pid import PIDGains, position_loop
from controllers.plant_model import ControlModel
from controllers.tuning import (
    FORCE_PHASE_MARGIN,
    KD_FACTORS,
    KP_FACTORS,
    MIN_GAIN_MARGIN,
    MIN_PHASE_MARGIN,
    fixed_tuning,
    force_loop,
    loop_margins,
    observer_loop,
    quick_margins,
)
from fcomp.cli.main import main
from fcomp.errors import FcompError
from fcomp.models import make_model
from fcomp.piston import piston_areas
from plants.planfile import builtin_path, builtin_plant_file, read_plant_file

AXIS_50 = Path(__file__).parent / "data" / "hydraulic-50mm.toml"


def _model(pf) -> ControlModel:
    return ControlModel(pf, make_model("nmlgm", params=pf.friction_set))


def _hand_column_frequency(pf) -> float:
    """``w_h^2 = beta*A1^2/(m*V1) + beta*A2^2/(m*V2)`` at mid stroke (hydraulic)."""
    v = pf.values
    A1, A2 = piston_areas(v["bore"], v["rod"])
    V1 = v["V10"] + A1 * 0.5 * v["stroke"]
    V2 = v["V20"] + A2 * 0.5 * v["stroke"]
    return math.sqrt(v["beta"] * (A1**2 / V1 + A2**2 / V2) / v["mass"])


def _with(path: Path, tmp_path: Path, name: str, **edits: str) -> Path:
    """A copy of a plant file with lines replaced (``old line start -> new line``)."""
    text = path.read_text()
    for old, new in edits.items():
        lines = [new if ln.startswith(old) else ln for ln in text.splitlines()]
        assert lines != text.splitlines(), old
        text = "\n".join(lines) + "\n"
    out = tmp_path / name
    out.write_text(text)
    return out


def test_derived_bandwidths_obey_the_rules_on_the_builtin_hydraulic_plant() -> None:
    pf = builtin_plant_file("hydraulic")
    model = _model(pf)
    tu = model.tuning
    assert tu.given == ()
    assert tu.column_frequency == pytest.approx(_hand_column_frequency(pf), rel=1e-3)
    assert tu.column_frequency == pytest.approx(80.6, abs=0.1)
    # rule 1: the force loop at the 45 deg phase margin (the largest such bandwidth)
    valve, dt = model.valve_transfer(), 1.0 / model.control_rate
    assert tu.force_margins.phase == pytest.approx(FORCE_PHASE_MARGIN, abs=0.3)
    assert quick_margins(force_loop(1.02 * tu.force_bandwidth, valve, dt)).phase < \
        FORCE_PHASE_MARGIN
    # rule 2: the largest PID bandwidth with the minimum margins; w_F > w_h: no column cap
    assert tu.force_bandwidth > tu.column_frequency
    assert tu.margins.gain >= MIN_GAIN_MARGIN and tu.margins.phase >= MIN_PHASE_MARGIN
    assert tu.margins.radius < 1
    # the pole pattern is one of the rule's, and its bandwidth the largest with the margins
    g, w = tu.pid_gains, tu.pid_bandwidth
    assert g.ki == pytest.approx(model.mass * w**3)
    kp_factor, kd_factor = g.kp / (3 * model.mass * w**2), g.kd / (3 * model.mass * w)
    assert min(abs(kp_factor - f) for f in KP_FACTORS) < 1e-9
    assert min(abs(kd_factor - f) for f in KD_FACTORS) < 1e-9
    damping = model.viscous_damping()
    for factor, short in ((1.0, False), (1.03, True)):
        gains = PIDGains.placed(model.mass, factor * w, kp_factor, kd_factor,
                                derivative_cutoff=g.derivative_cutoff)
        loop = position_loop(gains, model.mass, damping, tu.force_bandwidth, valve, dt)
        assert (loop_margins(loop).shortfall() is not None) == short
    # rule 4: the largest observer gain (below w_P/2) whose loop keeps the margins
    assert 0 < tu.observer_gain < 0.5 * tu.pid_bandwidth
    assert tu.observer_margins is not None and tu.observer_margins.shortfall() is None
    over = loop_margins(observer_loop(g, model, 1.2 * tu.observer_gain, tu.force_bandwidth, dt))
    assert over.shortfall() is not None
    # rule 6
    assert tu.mpc_horizon_time == pytest.approx(math.pi / tu.column_frequency)
    assert tu.mpc_horizon(500.0) == 20
    assert tu.mpc_velocity_ratio == pytest.approx(0.5 * tu.force_bandwidth)
    assert tu.ekf_measurement_std == pytest.approx(tuple(model.sensors.std()))


def _numpy_margins(num: np.ndarray, den: np.ndarray, dt: float) -> tuple[float, float]:
    """Phase margin (deg) and gain margin by a dense numpy sweep of ``num(z)/den(z)``."""
    w = np.logspace(-2, math.log10(math.pi / dt) - 1e-6, 400_000)
    z = np.exp(1j * w * dt)
    L = np.polyval(num, z) / np.polyval(den, z)
    mag, ph = np.abs(L), np.degrees(np.unwrap(np.angle(L)))
    i = np.nonzero((mag[:-1] >= 1) & (mag[1:] < 1))[0][-1]  # the last gain crossover
    pm = 180.0 + ph[i]
    j = np.nonzero(np.diff(np.floor((ph + 180.0) / 360.0)) != 0)[0]
    j = j[w[j] > w[i]]  # the phase crossover above the gain crossover
    gm = 1.0 / mag[j[0]]
    return ((pm + 180.0) % 360.0) - 180.0, gm


def test_margins_agree_with_an_independent_frequency_sweep() -> None:
    dt = 1e-3
    s = ct.tf("s")
    simple = ct.tf(ct.c2d(ct.ss(40.0 / (s * (0.02 * s + 1) * (0.01 * s + 1))), dt, "zoh"))
    model = _model(builtin_plant_file("hydraulic"))
    pid = position_loop(PIDGains.placed(model.mass, 25.0), model.mass, 900.0, 200.0,
                        model.valve_transfer(), dt)
    for loop in (simple, pid):
        m = loop_margins(loop)
        num, den = (np.asarray(c[0][0], dtype=float) for c in (loop.num, loop.den))
        pm, gm = _numpy_margins(num, den, dt)
        assert m.phase == pytest.approx(pm, abs=0.2)
        assert m.gain == pytest.approx(gm, rel=5e-3)
    # the simple loop by hand: |L(jw_c)| = 1, PM = 180 - 90 - atan(0.02 w_c) - atan(0.01 w_c)
    #   - w_c*dt/2 (the hold's half-sample lag)
    m = loop_margins(simple)
    wc = m.crossover
    assert 40.0 / (wc * math.hypot(1, 0.02 * wc) * math.hypot(1, 0.01 * wc)) == \
        pytest.approx(1.0, rel=0.02)
    hand = 90 - math.degrees(math.atan(0.02 * wc) + math.atan(0.01 * wc) + wc * dt / 2)
    assert m.phase == pytest.approx(hand, abs=0.5)


def test_a_stiffer_lighter_axis_gets_its_own_tuning(tmp_path: Path) -> None:
    base = _model(builtin_plant_file("hydraulic")).tuning
    pf = read_plant_file(AXIS_50)
    tu = _model(pf).tuning
    assert tu.column_frequency == pytest.approx(_hand_column_frequency(pf), rel=1e-3)
    assert tu.column_frequency > 2 * base.column_frequency
    assert (tu.pid_bandwidth, tu.derivative_cutoff) != (base.pid_bandwidth,
                                                       base.derivative_cutoff)
    assert tu.mpc_horizon_time < 0.5 * base.mpc_horizon_time
    assert tu.margins.shortfall() is None and math.isfinite(tu.margins.phase)
    # a slower valve (omega_v 150 rad/s): the force loop is slower than the column, which it
    # cannot damp, and the position loop stays below w_h/3 (Merritt; Jelali & Kroll)
    slow = read_plant_file(_with(AXIS_50, tmp_path, "slow.toml",
                                 omega_v="omega_v = 150.0", rate="rate = 1000.0"))
    st = _model(slow).tuning
    assert st.force_bandwidth < st.column_frequency
    assert st.pid_bandwidth <= st.column_frequency / 3 * (1 + 1e-9)
    assert st.margins.shortfall() is None


def test_explicit_values_win_and_are_checked(tmp_path: Path, capsys) -> None:
    path = _with(builtin_path("hydraulic"), tmp_path, "given.toml",
                 **{"# pid_bandwidth": "pid_bandwidth = 20.0",
                    "# observer_gain": "observer_gain = 0.5"})
    tu = _model(read_plant_file(path)).tuning
    assert (tu.pid_bandwidth, tu.observer_gain) == (20.0, 0.5)
    assert tu.given == ("observer_gain", "pid_bandwidth")
    assert tu.margins.gain > MIN_GAIN_MARGIN
    bad = _with(builtin_path("hydraulic"), tmp_path, "bad.toml",
                **{"# pid_bandwidth": "pid_bandwidth = 60.0"})
    with pytest.raises(FcompError, match=r"^pid_bandwidth 60 rad/s .*refused: the closed loop "
                       r"is unstable .*lower pid_bandwidth"):
        _ = _model(read_plant_file(bad)).tuning
    capsys.readouterr()
    assert main(["plant", "check", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "refused" in err[0] and "pid_bandwidth" in err[0]
    assert main(["sweep", "--plant-params", str(bad), "--samples", "1", "--controllers", "pid",
                 "--task", "steps", "--no-progress", "--jobs", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "refused" in err[0]
    # the former fixed numbers, given as controller options, lack margins: refused in one line
    model = _model(builtin_plant_file("hydraulic"))
    with pytest.raises(FcompError, match=r"refused: gain margin 1\.\d+ \(0\.\d dB\) < 2 "
                       r"\(6 dB\)"):
        make_controller("pid", model, bandwidth=40.0, force_bandwidth=150.0,
                        derivative_cutoff=60.0)
    ok = make_controller("pid", model, bandwidth=20.0)
    assert ok.margins.gain > MIN_GAIN_MARGIN
    # the former observer gain (20/s) makes the loop at rest unstable: refused, a file's too
    with pytest.raises(FcompError, match=r"observer_gain given\) refused: the loop with the "
                       r"LuGre observer at rest: the closed loop is unstable"):
        make_controller("lugre-observer", model, observer_gain=20.0)
    loose = _with(builtin_path("hydraulic"), tmp_path, "loose.toml",
                  **{"# observer_gain": "observer_gain = 20.0"})
    capsys.readouterr()
    assert main(["plant", "check", str(loose)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "observer_gain 20 1/s refused" in err[0], err


def test_the_observer_loop_is_the_pid_with_an_integrator_of_the_error() -> None:
    """Rule 4's loop against an independent evaluation: at z = exp(jw dt) the controller is
    the PID plus ``sigma1 k + sigma0 k dt/(z - 1)`` (the bristle correction at rest)."""
    model = _model(builtin_plant_file("hydraulic"))
    tu = model.tuning
    g, dt, k = tu.pid_gains, 1.0 / model.control_rate, 3.0
    p = model.friction.flat_params()
    L = observer_loop(g, model, k, tu.force_bandwidth, dt)
    P = position_loop(g, model.mass, model.viscous_damping(), tu.force_bandwidth,
                      model.valve_transfer(), dt)
    Tf = 1.0 / (2 * math.pi * g.derivative_cutoff)
    for w in (0.5, 5.0, 50.0, 500.0):
        z = complex(math.cos(w * dt), math.sin(w * dt))
        C = g.kp + g.ki * dt * z / (z - 1) + g.kd * (z - 1) / ((Tf + dt) * z - Tf)
        plant = complex(P(z)) / C
        want = (C + p["sigma1"] * k + p["sigma0"] * k * dt / (z - 1)) * plant
        assert complex(L(z)) == pytest.approx(want, rel=1e-6)


def test_check_prints_the_tuning_and_its_margins(capsys) -> None:
    assert main(["plant", "check", str(AXIS_50)]) == 0
    out = capsys.readouterr().out
    assert "tuning: force loop" in out and "position loop: gain margin" in out
    assert "phase margin" in out and "MPC horizon" in out


def _former(model: ControlModel):
    """The former fixed hydraulic tuning (PLANT_SETTINGS before controllers/tuning.py)."""
    return fixed_tuning(model, force_bandwidth=150.0, pid_bandwidth=40.0,
                        derivative_cutoff=60.0, observer_gain=20.0, mpc_horizon_time=0.040,
                        mpc_velocity_ratio=100.0)


def test_derived_mpc_tracks_no_worse_than_the_former_numbers_on_the_hydraulic_plant() -> None:
    """The MPC (the tuning rule 6) against the former horizon and weights, fast steps. The
    PID family is *not* compared here: the former numbers had no margin (GM 1.02, PM 1 deg,
    see docs/compensators.md), and the derived, margin-respecting PID tracks worse."""
    runs = {}
    for name, tuning in (("former", _former), ("derived", None)):
        res = run_closed_loop("mpc", "steps", LoopConfig(plant="hydraulic", fast=True,
                                                         tuning=tuning))
        runs[name] = res.metrics
    assert runs["derived"].rms_error <= 1.02 * runs["former"].rms_error
    assert runs["derived"].max_error <= 1.02 * runs["former"].max_error
    former = _former(control_model(LoopConfig(plant="hydraulic")))
    assert former.margins.shortfall() is not None  # the reason the PID family differs
