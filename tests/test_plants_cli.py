"""``fcomp simulate`` for every plant: files in the data format, defaults, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from fcomp.cli.main import main
from fcomp.measurement import Measurement

RUNS = {
    "hydraulic": ("nmlgm", "sine:amplitude=0.0045,frequency=1"),
    "pneumatic": ("nmlgm", "sine:amplitude=0.3,frequency=1"),
    "presliding-rig": ("nmlgm", "step:amplitude=0.2,time=0.05"),
    "force-rig": ("coulomb-viscous", "sine:amplitude=10,frequency=2"),
}


def simulate(argv: list[str], out, capsys) -> Measurement:
    """Run ``fcomp simulate ARGV -o OUT`` in-process; it must succeed; read the result."""
    rc = main(["simulate", *argv, "-o", str(out)])
    assert rc == 0, capsys.readouterr().err
    return Measurement.read(out)


@pytest.mark.parametrize("plant", sorted(RUNS))
def test_simulate_every_plant_writes_a_measurement(plant, tmp_path, capsys) -> None:
    friction, spec = RUNS[plant]
    m = simulate([plant, "--friction", friction, "--input", spec, "--duration", "0.2",
                  "--rate", "500"], tmp_path / f"{plant}.csv", capsys)
    assert len(m) == 101 and m.t[-1] == pytest.approx(0.2)
    for col in ("t", "x", "v", "a", "F"):
        assert col in m
    assert m.meta["simulation"]["plant"] == plant
    assert m.meta["simulation"]["input"] == spec
    assert m.meta["rig"]["stroke"] > 0 and m.meta["rig"]["bore"] > m.meta["rig"]["rod"]
    x0 = m.meta["simulation"]["x0"]
    assert x0["x"] == pytest.approx(m.meta["rig"]["stroke"] / 2) and x0["v"] == 0.0
    if plant != "force-rig":
        assert m.meta["pressure"] == "gauge" and "p1" in m and "p2" in m
    else:
        assert "F_ext" in m
        np.testing.assert_allclose(m["F_ext"], 10 * np.sin(2 * np.pi * 2 * m.t), atol=1e-12)


def test_initial_state_and_plant_parameters_from_the_command_line(tmp_path, capsys) -> None:
    m = simulate(["hydraulic", "--friction", "lugre", "--input", "step:amplitude=0",
                  "--duration", "0.05", "--x0", "x=0.1", "--x0", "p1=4e6", "--set", "mass=20",
                  "--set", "sigma1=100", "--rtol", "1e-8"], tmp_path / "h.csv", capsys)
    sim = m.meta["simulation"]
    assert m["x"][0] == pytest.approx(0.1) and sim["x0"]["p1"] == pytest.approx(4e6)
    assert m.meta["rig"]["mass"] == 20.0 and sim["plant_params"]["mass"] == 20.0
    assert sim["friction_params"]["sigma1"] == 100.0 and sim["rtol"] == 1e-8


def test_hysteresis_model_runs_through_the_cli(tmp_path, capsys) -> None:
    m = simulate(["presliding-rig", "--friction", "nmlgm-hysteresis", "--input",
                  "sine:amplitude=0.05,frequency=2", "--duration", "0.1", "--coupling", "2e-4"],
                 tmp_path / "r.csv", capsys)
    assert "Fz" in m and m.meta["simulation"]["coupling"] == 2e-4


BAD = [
    (["simulate", "crane", "--friction", "nmlgm", "--input", "sine:amplitude=1,frequency=1"],
     "unknown plant 'crane'"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "saw:amplitude=1"],
     "unknown input kind 'saw'"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "sine:amplitude=1"],
     "missing frequency"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "sine:amplitude=x,frequency=1"],
     "not a number"),
    (["simulate", "pneumatic", "--friction", "nmlgm", "--input", "step:amplitude=1",
      "--set", "rod=0.03"], "rod diameter 0.03 m must be smaller than the bore"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "step:amplitude=0",
      "--set", "V10=-1e-6"], "V10"),
    (["simulate", "force-rig", "--friction", "lugre", "--input", "step:amplitude=1",
      "--set", "mass=-2"], "mass"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "step:amplitude=0.004",
      "--max-steps", "20"], "did not converge"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--params", "canudas1995", "--input",
      "step:amplitude=0"], "no [servo_valve] section"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "step:amplitude=0",
      "--x0", "q=1"], "unknown state 'q'"),
    (["simulate", "motion", "--friction", "nmlgm", "--input", "step:amplitude=0.01",
      "--rtol", "1e-8"], "applies to the ODE plants"),
    (["simulate", "hydraulic", "--friction", "nmlgm", "--input", "step:amplitude=0",
      "--coupling", "1e-4"], "discrete memory"),
]


@pytest.mark.parametrize(("argv", "message"), BAD, ids=[b[1][:24] for b in BAD])
def test_bad_input_is_one_line_exit_2_nothing_written(argv, message, tmp_path, capsys) -> None:
    out = tmp_path / "bad.csv"
    rc = main([*argv, "--duration", "0.5", "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []
