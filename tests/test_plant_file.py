"""Your plant as a file (docs/plants.md, "Plant files").

The shipped files are the built-in plants, bit for bit (plant parameters and
controller settings); the printed templates load; a hand-written file with
the rating of a valve gives the flow gain of the orifice law; bad values get
one line each and exit status 2; ``plant check`` gives the natural frequency
of the hand formulas; simulate and the closed-loop harness take a plant file.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers.plant_files import edited as _edit

from controllers.harness import LoopConfig, build_loop
from controllers.plant_model import ControlModel, plant_settings
from fcomp.cli.main import main
from fcomp.errors import FileFormatError
from fcomp.measurement import Measurement
from fcomp.models import make_model
from plants import make_plant
from plants.check import check_plant, frictionless
from plants.planfile import (
    PlantFileError,
    builtin_path,
    builtin_plant_file,
    read_plant_file,
    template,
)

KINDS = ("hydraulic", "pneumatic")


@pytest.mark.parametrize("kind", KINDS)
def test_the_shipped_files_are_the_built_in_plants_bit_for_bit(kind: str) -> None:
    pf = builtin_plant_file(kind)
    friction = make_model("lugre", params=pf.friction_set)
    from_file = pf.make_plant(friction).plant_params.flat()
    built_in = make_plant(kind, friction).plant_params.flat()
    assert list(from_file) == list(built_in)
    for k, v in built_in.items():  # bitwise: the same floats, not close ones
        assert from_file[k] == v and math.copysign(1, from_file[k]) == math.copysign(1, v), k
    assert plant_settings(pf) == plant_settings(kind)  # a name's settings are its file's
    assert plant_settings(pf).given_tuning() == {}  # the tuning is derived (controllers.tuning)
    assert pf.rig["orientation"] == ("vertical-up" if kind == "hydraulic" else "horizontal")


@pytest.mark.parametrize("kind", KINDS)
def test_the_printed_template_loads(kind: str, tmp_path: Path, capsys) -> None:
    assert main(["plant", "template", kind]) == 0
    text = capsys.readouterr().out
    assert text == template(kind) and "[rig]" in text and "bore" in text
    path = tmp_path / "mine.toml"
    path.write_text(text)
    assert read_plant_file(path).values == builtin_plant_file(kind).values


def test_a_valve_rating_gives_the_orifice_flow_gain(tmp_path: Path) -> None:
    """Q_n at full command and total drop dp_n (dp_n/2 per edge) through the orifice law
    Q = cd*w*x*sqrt(2/rho*dp): cd*w = Q_n/(kv*u_max*sqrt(dp_n/rho))."""
    path = _edit("hydraulic", tmp_path, ("w = 0.0228 ", "rated_flow = 4.0e-4\nrated_dp = 7.0e6\n#"))
    pf = read_plant_file(path)
    v = pf.values
    q = v["cd"] * v["w"] * v["kv"] * 0.010 * math.sqrt(2.0 / 862.0 * 3.5e6)
    assert q == pytest.approx(4.0e-4, rel=1e-12)


def test_a_sonic_conductance_gives_the_edge_area(tmp_path: Path) -> None:
    """ISO 6358: choked mass flow C*rho0*p*sqrt(T0/T) equals the nozzle's
    A*psi_c*p/sqrt(R*T), psi_c = sqrt(gamma*(2/(gamma+1))^((gamma+1)/(gamma-1)))."""
    path = _edit("pneumatic", tmp_path, ("A_valve = 6.0e-6 ", "sonic_conductance = 2.4e-8 #"))
    v = read_plant_file(path).values
    psi_c = math.sqrt(1.4 * (2 / 2.4) ** (2.4 / 0.4))
    p, T = 6e5, 293.15
    nozzle = v["A_valve"] * psi_c * p / math.sqrt(287.05 * T)
    assert nozzle == pytest.approx(2.4e-8 * 1.185 * p, rel=1e-12)


def test_bad_values_get_one_line_each_and_exit_2(tmp_path: Path, capsys) -> None:
    path = _edit("hydraulic", tmp_path, ("rod = 0.016 ", "rod = 0.040 "),
                 ("V10 = 5.0e-6 ", "V10 = -1.0e-6 "), ("mass = 118.0 ", "mass = -3.0 "),
                 ("rate = 1000.0 ", "rate = 50.0 "), ("zeta_v = 0.75 ", "zeta_v = 0.75\nkvv = 1 "))
    with pytest.raises(PlantFileError) as err:
        read_plant_file(path)
    problems = err.value.problems
    assert len(problems) == 5, problems
    for words in ("[rig] rod = 0.04 m must be smaller than bore", "[lines] V10 = -1e-06",
                  "[rig] mass = -3", "below the valve bandwidth 70", "unknown key [valve] kvv"):
        assert sum(words in p for p in problems) == 1, words
    assert all(p.startswith(str(path)) for p in problems)
    assert main(["plant", "check", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 5 and all(ln.startswith("fcomp: error: ") for ln in lines)
    out = tmp_path / "run.csv"
    code = main(["simulate", "hydraulic", "--plant-params", str(path), "--friction", "lugre",
                 "--input", "step:amplitude=0.001", "--duration", "0.1", "-o", str(out)])
    assert code == 2 and len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.parametrize("text, words", [
    ("kind = 'hydraulik'\n", "kind must be one of hydraulic, pneumatic"),
    ("kind = 'hydraulic'\n[rig\n", "not valid TOML"),
])
def test_a_file_that_is_no_plant_file(text: str, words: str, tmp_path: Path) -> None:
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=words):
        read_plant_file(path)


def _hand_wn(pf, p1: float, p2: float) -> float:
    v = pf.values
    A1 = math.pi / 4 * v["bore"] ** 2
    A2 = math.pi / 4 * (v["bore"] ** 2 - v["rod"] ** 2)
    x = 0.5 * v["stroke"]
    V1, V2 = v["V10"] + A1 * x, v["V20"] + A2 * (v["stroke"] - x)
    if pf.kind == "hydraulic":
        return math.sqrt(v["beta"] * A1**2 / (v["mass"] * V1)
                         + v["beta"] * A2**2 / (v["mass"] * V2))
    k = v["k_poly"]
    return math.sqrt(k * p1 * A1**2 / (v["mass"] * V1) + k * p2 * A2**2 / (v["mass"] * V2))


@pytest.mark.parametrize("kind", KINDS)
def test_plant_check_natural_frequency_is_the_hand_formula(kind: str) -> None:
    pf = builtin_plant_file(kind)
    doc = check_plant(pf)
    eq = doc["equilibrium"]
    # the equilibrium holds the load: (p1 - p_atm)*A1 - (p2 - p_atm)*A2 = m*g*orient
    v = pf.values
    A1 = math.pi / 4 * v["bore"] ** 2
    A2 = math.pi / 4 * (v["bore"] ** 2 - v["rod"] ** 2)
    force = (eq["p1"] - v["p_atm"]) * A1 - (eq["p2"] - v["p_atm"]) * A2
    assert force == pytest.approx(doc["weight"], abs=1e-6 * v["ps"] * A1)
    hand = _hand_wn(pf, eq["p1"], eq["p2"])
    assert doc["natural_frequency"] == pytest.approx(hand, rel=0.05)
    assert 0.0 < doc["damping"] < 1.0
    assert doc["valve_limited_speed"]["extend"] > 0 > doc["valve_limited_speed"]["retract"]


def test_valve_limited_speed_is_the_flow_balance() -> None:
    """Hydraulic, extending at full command: the open edges pass Q = cd*w*(U + kv*u)*
    sqrt(2/rho*dp); into the cap side A1*v at ps - p1, out of the rod side A2*v at p2 - pt."""
    pf = builtin_plant_file("hydraulic")
    doc = check_plant(pf)
    v = pf.values
    speed = doc["valve_limited_speed"]["extend"]
    from plants.equilibrium import steady_motion

    plant = pf.make_plant(frictionless())
    state = steady_motion(plant, 0.15, 0.010, speed)
    names = list(plant.state_names)
    p1, p2 = state[names.index("p1")], state[names.index("p2")]
    k = v["cd"] * v["w"] * (v["underlap"] + v["kv"] * 0.010)
    A1 = math.pi / 4 * v["bore"] ** 2
    A2 = math.pi / 4 * (v["bore"] ** 2 - v["rod"] ** 2)
    assert k * math.sqrt(2 / v["rho"] * (v["ps"] - p1)) == pytest.approx(A1 * speed, rel=1e-3)
    assert k * math.sqrt(2 / v["rho"] * (p2 - v["pt"])) == pytest.approx(A2 * speed, rel=1e-3)


def test_plant_check_of_another_cylinder(tmp_path: Path, capsys) -> None:
    """A 50 mm bore, 80 kg horizontal axis at 21 MPa: the linearisation follows the file."""
    path = _edit("hydraulic", tmp_path, ("bore = 0.030 ", "bore = 0.050 "),
                 ("rod = 0.016 ", "rod = 0.028 "), ("mass = 118.0 ", "mass = 80.0 "),
                 ('orientation = "vertical-up"', 'orientation = "horizontal"'),
                 ("ps = 6.5e6 ", "ps = 21.0e6 "))
    pf = read_plant_file(path)
    assert main(["plant", "check", str(path), "--json", "-"]) == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    hand = _hand_wn(pf, 0.0, 0.0)
    assert doc["natural_frequency"] == pytest.approx(hand, rel=0.05)
    A1 = math.pi / 4 * 0.05**2
    A2 = math.pi / 4 * (0.05**2 - 0.028**2)
    assert doc["force_range"]["max"] == pytest.approx((21e6 - 101325) * A1
                                                      - (1e5 - 101325) * A2, rel=1e-12)
    assert doc["weight"] == 0.0


def test_simulate_with_a_plant_file_is_the_built_in_run(tmp_path: Path) -> None:
    runs = []
    for extra in ([], ["--plant-params", str(builtin_path("pneumatic"))]):
        out = tmp_path / f"run{len(runs)}.csv"
        assert main(["simulate", "pneumatic", "--friction", "lugre", "--input",
                     "sine:amplitude=0.3,frequency=2", "--duration", "0.3", "-o", str(out),
                     *extra]) == 0
        runs.append(Measurement.read(out))
    for col in ("x", "p1", "p2", "F"):
        assert np.array_equal(runs[0][col], runs[1][col])


def test_the_closed_loop_takes_a_plant_file() -> None:
    pf = builtin_plant_file("pneumatic")
    friction = make_model("lugre", params=pf.friction_set)
    model = ControlModel(pf, friction)
    assert model.plant_name == "pneumatic" and model.settings == plant_settings("pneumatic")
    assert model.plant.flat_params() == ControlModel("pneumatic", friction).plant.flat_params()
    plant, cmodel, ctrl = build_loop("pid", LoopConfig(plant_file=pf, friction="lugre",
                                                       controller_friction=friction))
    assert plant.name == "pneumatic" and cmodel.u_max == 1.0


def test_sweep_on_a_plant_file_is_the_sweep_on_the_built_in_plant(tmp_path: Path,
                                                                   capsys) -> None:
    import json

    friction = tmp_path / "nmlgm.json"
    make_model("nmlgm", params="seed000-servo").save(friction)
    docs = []
    for extra in (["--plant", "pneumatic", "--friction", "nmlgm"],
                  ["--plant-params", str(builtin_path("pneumatic")), "--friction", str(friction)]):
        assert main(["sweep", *extra, "--controllers", "pid", "--samples", "1",
                     "--jobs", "1", "--no-progress", "--json", "-"]) == 0
        docs.append(json.loads(capsys.readouterr().out))
    assert docs[0]["plant"] == docs[1]["plant"] == "pneumatic"
    assert docs[0]["runs"][0]["metrics"] == docs[1]["runs"][0]["metrics"]


def test_compare_in_the_plant_domain_with_a_plant_file(tmp_path: Path, capsys) -> None:
    import json

    rec = tmp_path / "rec.csv"
    assert main(["simulate", "pneumatic", "--friction", "lugre", "--input",
                 "sine:amplitude=0.3,frequency=1", "--duration", "3", "--rate", "200",
                 "-o", str(rec)]) == 0
    capsys.readouterr()
    docs = []
    for extra in (["--plant", "pneumatic"], ["--plant-params", str(builtin_path("pneumatic"))]):
        assert main(["compare", str(rec), "--friction", "lugre", "--params", "seed000-servo",
                     *extra, "--json", "-"]) == 0
        docs.append(json.loads(capsys.readouterr().out))
    assert docs[0]["plant"] and docs[0]["plant"] == docs[1]["plant"]
