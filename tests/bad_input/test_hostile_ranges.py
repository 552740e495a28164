"""A model run far outside what it was fitted on (issue 42, item 11).

The README's chain fitted ``position-dependence`` on a 25 mm O-ring record (x in
[-37, 2.7] mm) and simulated it on a hydraulic axis at x = 150 mm without a word: the
polynomial factor reached 140-434. A model file now carries the ranges it was fitted on
(``fitted_range``), and every command warns beyond them -- or refuses where the law is
meaningless (:func:`fcomp.modelfile.check_range`).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from helpers.cli_cases import Case, check_case, run_cli
from helpers.hostile import runner, write_lab
from numpy.polynomial import legendre

from fcomp.modelfile import OutOfRangeError, check_range, load_model, read_model
from fcomp.models import make_model

RUNNER = runner()


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    yield write_lab(tmp_path_factory.mktemp("ranges"))


def test_a_polynomial_law_far_outside_its_stroke_is_refused() -> None:
    """The factor at 150 mm of the runner's model (kx1..kx3 over x = -37.5..3.2 mm),
    computed here with numpy's Legendre series, is what the refusal says, and far beyond
    anything the law takes on its own stroke."""
    model = read_model(RUNNER.POSDEP).model
    x_min, x_max = -0.0375, 0.0032
    xi = 2 * (0.15 - x_min) / (x_max - x_min) - 1
    factor = legendre.legval(xi, [1.0, 0.6, 0.5, 0.4])
    inside = legendre.legval(np.linspace(-1, 1, 401), [1.0, 0.6, 0.5, 0.4])
    assert factor > 100 * inside.max()
    with pytest.raises(OutOfRangeError, match=f"scales the friction by {factor:.3g}"):
        check_range(model, x=[0.15], label="m.json")
    assert check_range(model, x=[-0.03, 0.0], label="m.json") == []  # on its own stroke


def test_beyond_the_fitted_range_is_a_warning_naming_each_signal() -> None:
    model = make_model("lugre").with_effects("pressure-dependence").with_fitted_range(
        {"x": [0.0, 0.05], "v": [-0.02, 0.02], "p": [2e5, 7e5]})
    assert check_range(model, x=[0.01, 0.04], v=[-0.021, 0.019], p=[2.5e5, 6e5]) == []
    [line] = check_range(model, x=[0.0, 0.05], v=[-0.2, 0.2], p=[0.0, 6.4e6], label="m.json")
    assert line.startswith("m.json was fitted on speeds -20 to 20 mm/s; chamber pressures "
                           "(gauge) 2 to 7 bar, and this use reaches speeds -200 to 200 mm/s; "
                           "chamber pressures 0 to 64 bar")
    plain = make_model("lugre").with_fitted_range({"x": [0.0, 0.05], "p": [2e5, 7e5]})
    assert check_range(plain, x=[0.2, 0.3], p=[0, 6e6]) == []  # it reads neither x nor p


def test_fit_and_save_carry_the_record_ranges(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    """``fit --save-model`` and ``model.save()`` write the ranges of the record (measured
    here from the record's own columns); the version stays 1, and a file without them
    reads as before."""
    rec = write_lab(tmp_path / "lab") / "rec.csv"
    data = np.genfromtxt(rec, delimiter=",", names=True)
    code, _, err = run_cli(["fit", str(rec), "--friction", "coulomb-viscous", "--save-model",
                            str(tmp_path / "m.json")], capsys)
    assert code == 0, err
    doc = json.loads((tmp_path / "m.json").read_text())
    assert doc["version"] == 1
    assert doc["fitted_range"]["x"] == pytest.approx([data["x"].min(), data["x"].max()])
    assert doc["fitted_range"]["v"] == pytest.approx([data["v"].min(), data["v"].max()])
    assert "p" not in doc["fitted_range"]  # the record has no pressures
    model = load_model(tmp_path / "m.json")
    assert model.fitted_range == {k: tuple(v) for k, v in doc["fitted_range"].items()}
    model.save(tmp_path / "again.json")
    assert json.loads((tmp_path / "again.json").read_text())["fitted_range"] == \
        doc["fitted_range"]
    old = {k: v for k, v in doc.items() if k != "fitted_range"}
    assert read_model(old).model.fitted_range == {}


@pytest.mark.parametrize("command", [
    "simulate hydraulic --friction ranged.json --input step:amplitude=0 --duration 0.01 "
    "-o o.csv",
    "compensate --plant hydraulic --friction lugre --controller-friction lugre,ranged.json "
    "--controllers pid --task steps --fast --samples 0 --no-progress",
    "compensate --plant hydraulic --friction ranged.json --controller-friction lugre,coulomb "
    "--controllers pid --task steps --fast --samples 0 --no-progress",
    "sweep --controllers pid --samples 2 --friction ranged.json --no-progress",
    "sweep --controllers pid --controller-friction lugre,ranged.json --no-progress",
    "export pid --plant hydraulic -o ctrl --friction ranged.json --no-progress",
])
def test_every_command_refuses_the_law_where_it_is_meaningless(
        lab: Path, command: str, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The README's case on every command that runs a model on a plant: refused before any
    run, the file named (the hydraulic axis starts at mid stroke, 150 mm)."""
    check_case(lab, Case(command, match=("ranged.json", "meaningless there")), capsys,
               monkeypatch)


def test_compare_and_simulate_warn_beyond_the_range(lab: Path,
                                                   capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """A model without a position law, fitted on slow speeds, on a record or a plant beyond
    them: a warning naming the file and what was exceeded, and the result as before."""
    slow = make_model("lugre").with_fitted_range({"v": [-0.001, 0.001]})
    slow.save(lab / "slow.json")
    err = check_case(lab, Case("compare rec.csv --friction slow.json", code=0,
                               match=("slow.json was fitted on speeds -1 to 1 mm/s",)),
                     capsys, monkeypatch)
    assert "this use reaches speeds" in err
    check_case(lab, Case("simulate motion --friction slow.json --input "
                         "sine:amplitude=0.05,frequency=1 --duration 0.5 -o o.csv", code=0,
                         match=("slow.json was fitted on speeds",), outputs=("o.csv", "o.toml")),
               capsys, monkeypatch)
    sidecar = (lab / "o.toml").read_text()
    assert "fitted-range" in sidecar  # written into the output's warnings too


def test_the_loop_use_of_a_task(lab: Path) -> None:
    """What a closed loop asks of a model (controllers.model_range): the tasks' absolute
    positions and speeds on the plant, the pressures between return and supply."""
    from controllers.model_range import loop_use
    from controllers.tasks import TASKS
    from plants.planfile import builtin_plant_file

    pf = builtin_plant_file("hydraulic")
    task = TASKS.get("steps")
    use = loop_use(pf, [task], fast=True)
    t = np.linspace(0, task.run_duration(True), 5001)
    r, dr, _ = task.sample(t)
    assert use["x"][0] == pytest.approx(0.15 + r.min(), abs=1e-4)
    assert use["x"][1] == pytest.approx(0.15 + r.max(), abs=1e-4)
    assert use["v"][1] == pytest.approx(dr.max(), rel=1e-2)
    v = pf.values
    assert use["p"] == pytest.approx((v["pt"] - v["p_atm"], v["ps"] - v["p_atm"]))
