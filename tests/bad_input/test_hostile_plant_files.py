"""Hostile plant files (issue 42, items 5, 7, 8, 9 and 16): every edited plant file is one
line naming the file and the key (``plant check``: one line per bad value), exit status 2
-- never an internal error -- and what docs/plants.md promises holds.

The plant-file variants are those of ``benchmarks/hostile_cases.py`` (``PLANTS``): the
hostile-case runner counts them, this file checks them in the suite.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from helpers.cli_cases import Case, check_case, run_cli
from helpers.hostile import runner, write_lab

from fcomp.errors import ConvergenceError, FcompWarning, FileFormatError
from fcomp.measurement import G
from fcomp.piston import piston_areas
from plants.equilibrium import equilibrium, unreachable
from plants.planfile import NAME_MAX, PlantFileError, parse_plant, read_plant_file, template

RUNNER = runner()
#: The runner's plant variants this work answers for (all of them now: a valve that passes
#: no flow -- kv, cd, w, A_valve or sonic_conductance zero -- is the file's own refusal).
MINE = {stem: v for stem, v in RUNNER.PLANTS.items() if not v[5]}


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    yield write_lab(tmp_path_factory.mktemp("plants"))


@pytest.mark.parametrize("stem", [s for s, v in MINE.items() if v[2] == "refuse"])
def test_a_bad_plant_file_is_named_with_its_key(lab: Path, stem: str,
                                               capsys: pytest.CaptureFixture[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """``kind = ["hydraulic"]`` or a table, ``tau_v = 0``, ``gamma = 1`` with a sonic
    conductance, ``rated_flow`` with ``cd = 0``, ``p_noise = 1e308``, a 400-digit mass, a
    300-character name, a load beyond the force range, ...: one line each, the file and
    the key named (item 5: several were internal errors -- TypeError, ZeroDivisionError,
    OverflowError). Also the fail-safe layer's keys: a ``safe_output`` that is no name nor
    command, a ``fault_latch`` of 2.5 or 1e300, a ``position_margin`` of 1e308 or a
    ``pressure_max`` below the supply (each switched the layer off, or made it latch on
    every good reading)."""
    match = MINE[stem][3]
    check_case(lab, Case(f"plant check {stem}.toml", match=(f"{stem}.toml", *match),
                         lines=None), capsys, monkeypatch)


MISSING = [("hm", k) for _, k in RUNNER.H_REQUIRED] + [("pm", k) for _, k in RUNNER.P_REQUIRED]


@pytest.mark.parametrize(("prefix", "key"), MISSING, ids=[f"{p}-{k}" for p, k in MISSING])
def test_a_missing_key_is_named(lab: Path, prefix: str, key: str,
                                capsys: pytest.CaptureFixture[str],
                                monkeypatch: pytest.MonkeyPatch) -> None:
    check_case(lab, Case(f"plant check {prefix}_{key}.toml", match=(f"{prefix}_{key}.toml", key),
                         lines=None), capsys, monkeypatch)


@pytest.mark.parametrize("stem", ["h_kind_list", "h_rated_cd_zero", "p_tau_zero",
                                  "p_gamma_one_sonic", "h_pnoise_huge", "h_load_beyond",
                                  "h_mass_bigint", "h_name300", "h_w_zero", "p_sonic_zero"])
def test_every_command_refuses_the_bad_plant_file_first(lab: Path, stem: str,
                                                        capsys: pytest.CaptureFixture[str],
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """The same files through simulate, compensate, sweep and export: the file's line, before
    any run (item 3: a valve that passes no flow was accepted by compensate, export and
    sweep, and plant check tuned it)."""
    kind = "hydraulic" if stem.startswith("h_") else "pneumatic"
    for args in (f"simulate {kind} --plant-params {stem}.toml --friction coulomb --input "
                 "step:amplitude=0 --duration 0.01 -o o.csv",
                 f"compensate --plant-params {stem}.toml --friction lugre --controller-friction "
                 "lugre,coulomb --controllers pid --task steps --fast --samples 0 --no-progress",
                 f"sweep --plant-params {stem}.toml --controllers pid --samples 2 --no-progress",
                 f"export pid --plant-params {stem}.toml -o ctrl --no-progress"):
        check_case(lab, Case(args, match=(f"{stem}.toml",)), capsys, monkeypatch)


def test_orientation_defaults_to_horizontal(lab: Path, capsys: pytest.CaptureFixture[str],
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """docs/plants.md: ``orientation`` is optional, horizontal by default (item 7: it was
    required)."""
    pf = read_plant_file(lab / "h_no_orientation.toml")
    assert pf.rig["orientation"] == "horizontal" and pf.values["orient"] == 0.0
    docs = (Path(__file__).resolve().parents[2] / "docs" / "plants.md").read_text()
    assert "| `[rig]` | `orientation` | | `horizontal` (default)" in docs
    monkeypatch.chdir(lab)
    code, out, err = run_cli(["plant", "check", "h_no_orientation.toml", "--json", "-"], capsys)
    assert code == 0, err
    import json

    assert json.loads(out)["weight"] == 0.0  # horizontal: no weight to hold


def test_the_template_names_no_plant(tmp_path: Path) -> None:
    """A plant file made from the template is named after itself (item 16: every output
    named the built-in plant ``seed002-type1``); the template says how to name it."""
    for kind, builtin in (("hydraulic", "seed002-type1"), ("pneumatic", "seed000-servo")):
        text = template(kind)
        assert f'name = "{builtin}"' not in text
        assert any(line.startswith("# name = ") and "default: this file's name" in line
                   for line in text.splitlines())
        path = tmp_path / f"my-{kind}-axis.toml"
        path.write_text(text)
        assert read_plant_file(path).name == f"my-{kind}-axis"
        assert tomllib.loads(text)["kind"] == kind


def test_a_file_keeping_the_built_in_name_is_named_after_itself(tmp_path: Path) -> None:
    """An older template's copy keeps ``name = "seed002-type1"``: the plant is named after the
    file, with a warning saying why; the shipped file itself keeps its name."""
    from plants.planfile import builtin_path

    path = tmp_path / "axis.toml"
    path.write_text(builtin_path("hydraulic").read_text())
    with pytest.warns(FcompWarning, match="left from the template"):
        pf = read_plant_file(path)
    assert pf.name == "axis"
    assert read_plant_file(builtin_path("hydraulic")).name == "seed002-type1"


def test_a_name_becomes_no_overlong_file_name() -> None:
    """A plant name is part of file names (a study's figures): more than NAME_MAX characters,
    or one that is not text on one line, is refused up front (item 9: a 300-character name
    failed a study after 54 s)."""
    doc = tomllib.loads(template("hydraulic"))
    for name, ok in (("a" * NAME_MAX, True), ("a" * (NAME_MAX + 1), False), ("two\nlines", False),
                     (5, False), ("", False)):
        if ok:
            assert parse_plant({**doc, "name": name}, "p.toml").name == name
        else:
            with pytest.raises(PlantFileError, match="p.toml: name"):
                parse_plant({**doc, "name": name}, "p.toml")


def test_a_study_refuses_an_overlong_name_before_its_runs(lab: Path,
                                                          capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    import controllers.harness

    ran: list[int] = []
    monkeypatch.setattr(controllers.harness, "run_closed_loop",
                        lambda *a, **k: ran.append(1))  # the work: must not start
    check_case(lab, Case("study compensators --fast --plant-params h_name300.toml --out st "
                         "--no-progress", match=("h_name300.toml", "name")), capsys, monkeypatch)
    assert not ran


# ------------------------------------------------------- the cause, not "no progress"
def test_the_force_range_is_the_independent_formula() -> None:
    """The load check uses the force the pressures can give: each chamber between tank and
    supply, F = (ps - pa)*A1 - (pt - pa)*A2 at most (an independent computation here)."""
    from plants.mechanics import force_range

    doc = tomllib.loads(template("hydraulic"))
    pf = parse_plant(doc, "p.toml")
    v = pf.values
    A1 = math.pi / 4 * v["bore"] ** 2
    A2 = A1 - math.pi / 4 * v["rod"] ** 2
    assert np.allclose(piston_areas(v["bore"], v["rod"]), (A1, A2))
    low, high = force_range(v)
    assert high == pytest.approx((v["ps"] - v["p_atm"]) * A1 - (v["pt"] - v["p_atm"]) * A2)
    assert low == pytest.approx((v["pt"] - v["p_atm"]) * A1 - (v["ps"] - v["p_atm"]) * A2)


@pytest.mark.parametrize(("change", "cause"), [
    ({"kv": 0.0}, "flow does not follow the command"),
    ({"w": 0.0}, "flow does not follow the command"),
    ({"mass": 1e4}, "beyond the"),  # 98 kN of weight, vertical-up: more than 4.6 kN
])
def test_an_unreachable_equilibrium_says_why(change: dict[str, float], cause: str) -> None:
    """Before: every unreachable operating point was "no equilibrium ... the iteration is not
    making good progress" (item 8); the cause is now said before any iteration."""
    from plants import PLANTS
    from plants.check import frictionless

    plant = PLANTS.get("hydraulic")(frictionless(), "seed002-type1", overrides=change)
    with pytest.raises(ConvergenceError, match=cause):
        equilibrium(plant, 0.15)
    assert cause in (unreachable(plant) or "")


def test_a_reachable_equilibrium_holds_the_load() -> None:
    """The check lets a plant that can hold its load through, and the equilibrium found holds
    it: F_p = F_load + m*g*orient (an invariant, computed apart from the solver)."""
    from plants import PLANTS
    from plants.check import frictionless

    plant = PLANTS.get("hydraulic")(frictionless(), "seed002-type1")
    assert unreachable(plant) is None
    x0, _ = equilibrium(plant, 0.15)
    p = plant.plant_params.flat()
    names = list(plant.state_names)
    A1, A2 = piston_areas(p["bore"], p["rod"])
    Fp = x0[names.index("p1")] * A1 - x0[names.index("p2")] * A2 - p["p_atm"] * (A1 - A2)
    assert Fp == pytest.approx(p["F_load"] + p["mass"] * G * p["orient"], rel=1e-6)


def test_an_unreadable_plant_file_is_a_file_format_error(tmp_path: Path) -> None:
    """The API raises what the docs promise (item 10): FileFormatError, for a missing file,
    a folder, a binary file and bad TOML alike."""
    (tmp_path / "bin.toml").write_bytes(b"\x00\x01")
    (tmp_path / "bad.toml").write_text("[rig\n")
    for path in (tmp_path / "nope.toml", tmp_path, tmp_path / "bin.toml", tmp_path / "bad.toml"):
        with pytest.raises(FileFormatError):
            read_plant_file(path)
