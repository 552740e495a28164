"""One-line messages that name their file and cause, one rule for ``--params``, and the
shipped data sets by name (issue 42, items 7, 8 and 16)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers.cli_cases import Case, check_case, run_cli
from helpers.hostile import runner, write_lab

RUNNER = runner()


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    yield write_lab(tmp_path_factory.mktemp("messages"))


@pytest.mark.parametrize("command", [
    "simulate motion --friction lugre.json --params canudas1995 --input step:amplitude=0.01 "
    "--duration 0.1 -o o.csv",
    "simulate hydraulic --friction lugre.json --params seed002-type1 --input step:amplitude=0 "
    "--duration 0.01 -o o.csv",
    "export pid --plant hydraulic -o ctrl --friction lugre.json --params seed002-type1",
    "compare rec.csv --friction lugre.json --params canudas1995",
    "fit rec.csv --friction lugre.json --params canudas1995",
])
def test_params_beside_a_model_file_is_refused_everywhere(lab: Path, command: str,
                                                          capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/cli.md: with ``--friction MODEL.json`` the file gives the values and ``--params``
    is refused -- simulate and export accepted it (item 7); one rule everywhere now."""
    check_case(lab, Case(command, match=("--params", "the model file lugre.json gives the "
                                          "values")), capsys, monkeypatch)
    docs = (Path(__file__).resolve().parents[2] / "docs" / "cli.md").read_text()
    assert "`--params` is refused on every command" in docs


def test_simulate_takes_the_plants_values_from_plant_params(lab: Path,
                                                            capsys: pytest.CaptureFixture[str],
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """What ``--params SET`` gave simulate beside a model file -- the plant's values -- is
    ``--plant-params SET`` (as compare takes it): the same plant, the model file's friction."""
    check_case(lab, Case("simulate hydraulic --friction lugre.json --plant-params seed002-type1 "
                         "--input step:amplitude=0 --duration 0.01 -o o.csv", code=0,
                         outputs=("o.csv", "o.toml")), capsys, monkeypatch)
    meta = (lab / "o.toml").read_text()
    assert "mass = 118.0" in meta  # the set's vertical 118 kg axis


@pytest.mark.parametrize(("stem", "match"), [
    ("r_long", "lasts 1e+07 s, longer than the 3600 s"),
    ("r_text", "row 3, column 'x_ref'"),
    ("r_bigint", "r_bigint.csv"),
])
def test_a_reference_says_what_is_wrong_with_it(lab: Path, stem: str, match: str,
                                                capsys: pytest.CaptureFixture[str],
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """A 1e7 s reference was "out of memory; use fewer or shorter records" (item 8), a
    text cell "could not convert string to float: 'a'" without the file."""
    comp = RUNNER.COMP.replace("--task steps ", "")
    check_case(lab, Case(f"{comp} --reference {stem}.csv", match=(f"{stem}.csv", match)),
               capsys, monkeypatch)


def test_plant_check_names_the_file_and_the_cause(lab: Path,
                                                  capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """A plant that cannot hold its load: the cause, not "no equilibrium ... not making good
    progress" (item 8); its file named."""
    err = check_case(lab, Case("plant check h_load_beyond.toml", lines=None,
                               match=("h_load_beyond.toml", "F_load = 1e+07 N",
                                      "beyond the")), capsys, monkeypatch)
    assert "good progress" not in err


@pytest.mark.parametrize(("option", "value", "match"), [
    ("--samples", "0", "--samples must be a positive integer"),
    ("--samples", "100000000", "at most 1000 draws"),  # item 10: ran unbounded
    ("--spread", "-1", "--spread must be >= 0"),
    ("--noise", "3,0.5", "--noise range"),
    ("--grid", "Fc=", "--grid Fc: factors"),
])
def test_sweep_names_its_options(lab: Path, option: str, value: str, match: str,
                                 capsys: pytest.CaptureFixture[str],
                                 monkeypatch: pytest.MonkeyPatch) -> None:
    check_case(lab, Case(f"sweep --controllers pid {option} {value}", match=(match,)), capsys,
               monkeypatch)


def test_compensate_bounds_its_draws(lab: Path, capsys: pytest.CaptureFixture[str],
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """``compensate --samples 1e8`` ran unbounded (item 10): one line before any run."""
    check_case(lab, Case("compensate --plant hydraulic --friction lugre --controller-friction "
                         "lugre,coulomb --controllers pid --samples 100000000 --no-progress",
                         match=("--samples", "1000")), capsys, monkeypatch)


@pytest.mark.parametrize(("name", "stem"), [("O-ring_3bar", "O-ring_3bar"),
                                             ("O-ring_3bar.csv", "O-ring_3bar")])
def test_a_shipped_data_set_by_name_from_any_folder(tmp_path: Path, name: str, stem: str,
                                                    capsys: pytest.CaptureFixture[str],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``fcomp import zillen fcomp/data/...`` worked only from the repository root (item
    16): the shipped files are taken by name, from any folder, the same data as the file."""
    from fcomp import datasets
    from fcomp.importers import import_file

    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["import", "zillen", name, "-o", "z.csv"], capsys)
    assert code == 0, err
    ref = import_file("zillen", datasets.path("zillen", f"{stem}.csv"))
    got = (tmp_path / "z.csv").read_text().splitlines()
    assert len(got) == len(ref) + 1
    code, _, err = run_cli(["import", "zillen", "O-ring_9bar", "-o", "y.csv"], capsys)
    assert code == 2 and "O-ring_9bar: file not found, and no data set shipped" in err
    assert "O-ring_3bar" in err and "fcomp list data" in err


def test_list_data_names_every_shipped_file(capsys: pytest.CaptureFixture[str]) -> None:
    from fcomp import datasets

    code, out, _ = run_cli(["list", "data"], capsys)
    assert code == 0
    for ds in datasets.names():
        for f in datasets.files(ds):
            assert f.rsplit(".", 1)[0] in out
    assert "fcomp import zillen O-ring_3bar -o OUT.csv" in out


def test_the_duplicate_keys_of_a_fit_json_are_named(lab: Path,
                                                    capsys: pytest.CaptureFixture[str],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``{"Fc": 1.0, "Fc": 3.0}`` kept the last value silently (item 10); before, the
    comparison then failed on a later check that named neither the file nor the key."""
    check_case(lab, Case("compare rec.csv --friction lugre --params fit_dup.json",
                         match=("--params fit_dup.json", "'Fc' is given twice")), capsys,
               monkeypatch)
    assert json.loads((lab / "fit_dup.json").read_text())["params"]["Fc"] == 3.0
