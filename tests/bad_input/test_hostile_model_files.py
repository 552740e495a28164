"""Hostile model files and JSON inputs (issue 42, items 5, 8 and 10): one line naming the
file and the key, exit status 2 -- a 400-digit parameter, ``x_min == x_max``, a file nested
100 000 deep, an integer of 5000 digits, duplicate keys, an unknown configuration key, a
negative fitted mass -- and the API raises what docs/model-file.md promises.

The model-file variants are those of ``benchmarks/hostile_cases.py`` (``MODELS``).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers.cli_cases import Case, check_case
from helpers.hostile import runner, write_lab

from fcomp.effects import make_effect
from fcomp.errors import FileFormatError
from fcomp.modelfile import load_model, read_model
from fcomp.textdata import parse_json

RUNNER = runner()
SIM = RUNNER.SIM


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    yield write_lab(tmp_path_factory.mktemp("models"))


@pytest.mark.parametrize("stem", [s for s, v in RUNNER.MODELS.items() if v[0] == "refuse"])
def test_a_bad_model_file_is_one_line_naming_it(lab: Path, stem: str,
                                               capsys: pytest.CaptureFixture[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    _, match, _ = RUNNER.MODELS[stem]
    check_case(lab, Case(f"{SIM} --friction {stem}.json", match=(f"{stem}.json", *match)),
               capsys, monkeypatch)


@pytest.mark.parametrize("stem", [s for s, v in RUNNER.MODELS.items() if v[0] == "ok"])
def test_a_valid_model_file_is_read(lab: Path, stem: str, capsys: pytest.CaptureFixture[str],
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """``features`` in another order (item 8: refused while listing the same names), a BOM,
    UTF-16, a simple model extended by effects."""
    check_case(lab, Case(f"{SIM} --friction {stem}.json", code=0, outputs=("o.csv", "o.toml")),
               capsys, monkeypatch)


@pytest.mark.parametrize("command", ["compare rec.csv --friction {f}",
                                     "sweep --controllers pid --samples 2 --friction {f}",
                                     "compensate --plant hydraulic --friction lugre "
                                     "--controller-friction lugre,{f} --controllers pid "
                                     "--task steps --fast --samples 0",
                                     "export pid --plant hydraulic -o ctrl --friction {f}",
                                     "fit rec.csv --friction {f}"])
@pytest.mark.parametrize("stem", ["m_deep_list", "m_hugeint", "m_bigint", "m_dup_top",
                                  "m_xmin_eq", "m_config_typo", "m_mass_negative"])
def test_every_command_reads_model_files_alike(lab: Path, command: str, stem: str,
                                              capsys: pytest.CaptureFixture[str],
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    _, match, _ = RUNNER.MODELS[stem]
    check_case(lab, Case(command.format(f=f"{stem}.json") + " --no-progress"
                         if not command.startswith("fit") else command.format(f=f"{stem}.json"),
                         match=(f"{stem}.json", *match)), capsys, monkeypatch)


@pytest.mark.parametrize(("option", "file", "match"), [
    ("--params", "fit_dup.json", "'Fc' is given twice"),
    ("--params", "m_deep_dict.json", "nested too deep"),
    ("--params", "m_hugeint.json", "an integer of 5001 digits"),
    ("--params", "m_notjson.json", "not valid JSON"),
])
def test_any_json_input_is_strict(lab: Path, option: str, file: str, match: str,
                                  capsys: pytest.CaptureFixture[str],
                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """Every JSON fcomp reads goes through one strict reader (item 10: a key given twice was
    kept silently, the last one winning)."""
    check_case(lab, Case(f"compare rec.csv --friction lugre {option} {file}",
                         match=(f"--params {file}", match)), capsys, monkeypatch)


def test_the_strict_reader_against_pythons_own() -> None:
    """What the strict reader accepts it reads as ``json.loads`` does (the same objects);
    what it refuses, it names."""
    for text in ('{"a": 1, "b": [1, 2.5, "inf"], "c": {"d": null}}', "[]", '"x"', "1e400"):
        assert parse_json(text, "t.json") == json.loads(text)
    for text, why in (('{"a": 1, "a": 1}', "given twice"), ('{"a": NaN}', "NaN"),
                      ("[" * 50000, "too deep"), ("{", "not valid JSON")):
        with pytest.raises(FileFormatError, match=why):
            parse_json(text, "t.json")
    huge = parse_json('{"a": -' + "9" * 4400 + "}", "t.json")["a"]  # beyond Python's 4300
    assert huge == float("-inf") and repr(huge) == "<an integer of 4400 digits>"


def test_unknown_configuration_keys_are_refused() -> None:
    """A typo in an effect's configuration was dropped silently (item 10); now refused, for
    fcomp's effects and for a user's effect that declares its keys -- not for one that
    declares none (its own business)."""
    from fcomp.effects import Effect
    from fcomp.parameters import make_params_class

    with pytest.raises(ValueError, match="unknown configuration key 'x_mni'.*x_min, x_max"):
        make_effect("position-dependence", x_mni=0.0)
    with pytest.raises(ValueError, match="unknown configuration key 'v_rfe'"):
        make_effect("viscous", v_rfe=1.0)
    assert make_effect("viscous", v_ref=0.05).config == {"v_ref": 0.05}
    params = make_params_class("FreeParams", [], owner="effect free")

    class Free(Effect):  # a user's effect reading its configuration freely
        name = "free-config-test"
        Params = params

    class Declared(Effect):
        name = "declared-config-test"
        Params = params
        CONFIG = ("period",)

    assert Free(period=1.0, other=2).config == {"period": 1.0, "other": 2}
    Declared(period=1.0)
    with pytest.raises(ValueError, match="unknown configuration key 'perid'"):
        Declared(perid=1.0)


@pytest.mark.parametrize(("config", "why"), [
    ({"x_min": 0.1, "x_max": 0.1}, "must be below"), ({"x_min": 0.3, "x_max": 0.0}, "must be below"),
    ({"x_min": "a"}, "not a finite position"), ({"x_max": float("nan")}, "not a finite position"),
    ({"x_min": 10**400}, "not a finite position"), ({"x_min": True}, "not a finite position"),
])
def test_position_dependence_needs_an_interval(config: dict, why: str) -> None:
    """``x_min == x_max`` was a ZeroDivisionError inside a run (item 5), ``x_min > x_max`` a
    mirrored law accepted silently (item 10)."""
    with pytest.raises(ValueError, match=why):
        make_effect("position-dependence", **config)


def test_the_api_raises_file_format_errors(tmp_path: Path) -> None:
    """docs/model-file.md: every problem with a model file is a FileFormatError in Python
    (item 10: a missing file, a folder, a binary file raised the plain FcompError)."""
    (tmp_path / "bin.json").write_bytes(b"\x00\x01")
    (tmp_path / "dup.json").write_text('{"format": "fcomp-model", "version": 1, '
                                       '"model": "lugre", "model": "coulomb"}')
    for path in (tmp_path / "nope.json", tmp_path, tmp_path / "bin.json",
                 tmp_path / "dup.json"):
        with pytest.raises(FileFormatError):
            load_model(path)


def test_measurement_terms_within_what_a_fit_gives() -> None:
    """A negative fitted mass (item 10), a mass of 1e300 kg, a lag beyond the fit's bounds:
    refused with the key; a plausible one read."""
    base = {"format": "fcomp-model", "version": 1, "model": "lugre"}
    for params, key in (({"mass": -5.0}, "mass"), ({"mass": 1e300}, "mass"),
                        ({"lag": -5.0}, "lag"), ({"lag": 2.0}, "lag")):
        with pytest.raises(FileFormatError, match=f"measurement_terms.params.{key}"):
            read_model({**base, "measurement_terms": {"params": params}})
    assert read_model({**base, "measurement_terms": {"params": {"mass": 1.5, "lag": 0.002}}}
                      ).mass == 1.5
