"""``fcomp study compensators --plant-params PLANT.toml --friction NAME|MODEL.json``
(:attr:`studies.base.StudyConfig.plant_file`, :attr:`~studies.base.StudyConfig.friction`).

Short runs only: fast mode, the study's plan cut down (one task, one draw, some
controllers) by patching the module's tables as ``tests/test_distributed.py`` does.
The built-in plant ``hydraulic`` and its shipped file give the same numbers; an
edited plant (``docs/examples/axis50.toml``) runs end to end on the command line.
"""

from __future__ import annotations

import html
import json
import math
import re
from pathlib import Path

import pytest

import studies.compensators as comp
from controllers.harness import DEFAULT_MISMATCH, LoopConfig, control_model
from fcomp.cli.main import main
from fcomp.effects import make_effect
from fcomp.errors import FcompError
from fcomp.models import make_model
from studies import STUDIES
from studies.base import StudyConfig

ROOT = Path(__file__).resolve().parents[1]
HYDRAULIC = ROOT / "plants" / "data" / "hydraulic.toml"
AXIS = ROOT / "docs" / "examples" / "axis50.toml"
#: What a run's row holds that does not depend on the machine (solve times do).
STABLE = ("rms_error", "max_error", "steady_state_error", "hunting_amplitude",
          "reversal_error", "valve_activity", "fallbacks", "status")


@pytest.fixture
def short_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    """The study on one task with one robustness draw, no do-mpc benchmark."""
    monkeypatch.setattr(comp, "TASK_ORDER", ("steps",))
    monkeypatch.setattr(comp, "LOW_VELOCITY", ("steps",))
    monkeypatch.setattr(comp, "FAST_DRAWS", 1)
    monkeypatch.setattr(comp.CompensatorsStudy, "_do_mpc", staticmethod(lambda fast: {
        "available": False, "note": "left out in this test"}))


def _stable(summary: dict, plant: str) -> dict:
    rows = {(r["controller"], r["task"]): [r[k] for k in STABLE] for r in summary["results"]
            if r["plant"] == plant}
    rob = {c: {m: d[m]["values"] for m in ("rms_error", "max_error")} | {"failed": d["failed"]}
           for c, d in summary["robustness"][plant].items()}
    return {"rows": rows, "robustness": rob, "verdict": summary["verdict"][f"{plant}/steps"]}


def test_default_setup_is_the_study_as_before(tmp_path: Path) -> None:
    """No plant file, no friction: the built-in plants with the loop defaults (the runs of
    the study before the options existed), and nothing new in the record."""
    config = StudyConfig(out=tmp_path / "o")
    plants = comp.study_plants(config)
    assert [sp.label for sp in plants] == ["hydraulic", "pneumatic"]
    assert [sp.base for sp in plants] == [LoopConfig(plant=p) for p in ("hydraulic",
                                                                         "pneumatic")]
    assert config.as_dict() == {"out": str(tmp_path / "o"), "fast": False, "command": None}


def test_plant_file_of_the_builtin_plant_gives_the_same_numbers(
        tmp_path: Path, short_plan: None, monkeypatch: pytest.MonkeyPatch) -> None:
    """The shipped file of the built-in hydraulic plant is the same plant: every controller's
    errors and the robustness draws are those of the built-in plant, bit for bit."""
    from_file = comp.main(StudyConfig(out=tmp_path / "file", fast=True, progress=False,
                                      plant_file=str(HYDRAULIC)))
    monkeypatch.setattr(comp, "PLANTS", ("hydraulic",))
    builtin = comp.main(StudyConfig(out=tmp_path / "builtin", fast=True, progress=False))
    name = from_file["setup"]["plants"][0]["name"]
    assert name == "seed002-type1" and list(from_file["robustness"]) == [name]
    assert "setup" not in builtin
    got, want = _stable(from_file, name), _stable(builtin, "hydraulic")
    assert len(got["rows"]) == len(comp.CONTROLLER_ORDER)
    assert all(row[-1] == "ok" for row in got["rows"].values())
    assert got == want
    derived = control_model(LoopConfig(plant="hydraulic")).tuning  # same plant, same tuning
    settings = from_file["setup"]["plants"][0]["settings"]
    assert settings["pid_bandwidth"] == derived.pid_bandwidth
    assert settings["tuning"]["margins"]["gain"] >= 2.0
    assert from_file["setup"]["friction"] == from_file["setup"]["controller_friction"] == "nmlgm"


def test_edited_plant_file_on_the_command_line(tmp_path: Path, short_plan: None,
                                               monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture) -> None:
    """A 50 mm, 80 kg, 21 MPa axis with a friction model file: the study runs end to end,
    names the plant by the file's name, shows the file's values and drops the file's
    measurement term (with a warning)."""
    monkeypatch.setattr(comp, "CONTROLLER_ORDER", ("pid", "pid-ff", "lugre-observer"))
    model = make_model("lugre", params="seed002-type1").with_effects(
        make_effect("force-offset", {"offset": 3.0}))
    friction = model.save(tmp_path / "seal.json")
    out = tmp_path / "study"
    code = main(["study", "compensators", "--fast", "--no-progress", "--out", str(out),
                 "--plant-params", str(AXIS), "--friction", str(friction)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "measurement terms force-offset" in captured.err
    summary = json.loads((out / "summary.json").read_text())
    assert {r["plant"] for r in summary["results"]} == {"axis50"}
    assert [r["controller"] for r in summary["results"]] == list(comp.CONTROLLER_ORDER)
    assert all(r["status"] == "ok" and math.isfinite(r["rms_error"])
               for r in summary["results"])
    assert list(summary["robustness"]) == ["axis50"] and "axis50/steps" in summary["verdict"]
    setup = summary["setup"]
    assert setup["plants"][0]["name"] == "axis50" and setup["plants"][0]["kind"] == "hydraulic"
    assert setup["friction"] == setup["controller_friction"] == "lugre"
    assert setup["friction_source"] == str(friction)
    assert setup["mismatch"] == DEFAULT_MISMATCH
    assert len(setup["warnings"]) == 1 and "force-offset" in setup["warnings"][0]
    assert "--plant-params" in summary["meta"]["command"]
    assert "fig-tracking-axis50.png" in summary["meta"]["figures"]
    text = _text(out / "report.html")
    assert "The plant of the plant file" in text and "name axis50" in text
    for shown in ("bore [mm] 50 ", "moving mass [kg] 80 ", "supply [MPa abs] 21 ",
                  "orientation horizontal"):  # the file's values, not the built-in plant's
        assert shown in text, shown
    assert "Controller settings: the plant file's control rate" in text
    assert "the true friction lugre (model file" in text and f"model file {friction}" in text
    assert "*true*" not in text  # plain words: the report renders no markdown


def test_plant_file_settings_replace_the_builtin_table(tmp_path: Path) -> None:
    """The report's settings come from the file: a file with another rate, sensors, limit
    and tuning gives those values."""
    text = AXIS.read_text().replace("rate = 1000.0", "rate = 2000.0").replace(
        "# pid_bandwidth = 25.0", "pid_bandwidth = 25.0").replace(
        "x_noise = 0.5e-6", "x_noise = 2.0e-6").replace("u_max = 0.010", "u_max = 0.008")
    path = tmp_path / "edited.toml"
    path.write_text(text)
    (sp,) = comp.study_plants(StudyConfig(out=tmp_path / "o", plant_file=str(path)))
    assert sp.label == "axis50" and sp.source == str(path)
    s = sp.settings
    assert (s.control_rate, s.pid_bandwidth, s.sensors.x_noise, s.u_max) == (
        2000.0, 25.0, 2.0e-6, 0.008)
    assert sp.base.plant_file is not None and sp.base.plant_file.values["mass"] == 80.0
    assert comp._slug("my axis/50") == "my-axis-50"  # a name as figure files hold it


def _text(page: Path) -> str:
    """A report's text, tags dropped and white space collapsed."""
    text = re.sub(r"<[^>]+>", " ", page.read_text(encoding="utf-8"))
    return re.sub(r"\s+", " ", html.unescape(text))


def _one_line_exit_2(args: list[str], out: Path, capsys: pytest.CaptureFixture) -> str:
    code = main([*args, "--out", str(out), "--fast", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert not out.exists()
    return err


def test_bad_inputs_are_one_line_and_write_nothing(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    err = _one_line_exit_2(["study", "friction-models", "--plant-params", str(AXIS)], out,
                           capsys)
    assert "--plant-params applies to the compensators study" in err
    err = _one_line_exit_2(["study", "all", "--friction", "lugre"], out, capsys)
    assert "--friction applies to the compensators study" in err
    bad = tmp_path / "bad.toml"
    bad.write_text(AXIS.read_text().replace("rod = 0.028", "rod = 0.060"))
    err = _one_line_exit_2(["study", "compensators", "--plant-params", str(bad)], out, capsys)
    assert "rod" in err
    _one_line_exit_2(["study", "compensators", "--plant-params", str(tmp_path / "no.toml")],
                     out, capsys)
    err = _one_line_exit_2(["study", "compensators", "--plant-params", str(ROOT / "README.md")],
                           out, capsys)
    assert ".toml" in err
    err = _one_line_exit_2(["study", "compensators", "--friction",
                            str(tmp_path / "missing.json")], out, capsys)
    assert "missing.json" in err
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "fcomp-model", "version": 99}')
    _one_line_exit_2(["study", "compensators", "--plant-params", str(AXIS), "--friction",
                      str(broken)], out, capsys)
    err = _one_line_exit_2(["study", "compensators", "--friction", "no-such-model"], out,
                           capsys)
    assert "no-such-model" in err


def test_api_refuses_options_a_study_does_not_take(tmp_path: Path) -> None:
    with pytest.raises(FcompError, match="applies to the compensators study"):
        STUDIES.get("presliding").main(StudyConfig(out=tmp_path / "o", fast=True,
                                                   plant_file=str(AXIS)))
    assert not (tmp_path / "o").exists()
    config = StudyConfig.coerce({"out": tmp_path / "o", "plant_file": str(AXIS),
                                 "friction": "lugre"})
    assert config.as_dict()["plant_file"] == str(AXIS)
    assert config.as_dict()["friction"] == "lugre"
