"""``fcomp compensate`` and :func:`controllers.compensate.compensate`: every controller built
with each friction model on a plant file with the true friction.

Short runs only (fast tasks, one or two controllers, one task, few draws).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from fcomp.cli.main import main
from fcomp.models import make_model

ROOT = Path(__file__).resolve().parents[1]
AXIS = ROOT / "docs" / "examples" / "axis50.toml"


def _models(folder: Path) -> tuple[Path, Path, Path]:
    """True friction (LuGre of the hydraulic set, 1.5 times as strong retracting), a plain
    LuGre baseline with the same values and the true model as the "diagnosed" one."""
    lugre = make_model("lugre", params="seed002-type1")
    true = lugre.with_effects("direction-asymmetry").with_params(r_neg=1.5)
    paths = folder / "true.json", folder / "base.json", folder / "diag.json"
    true.save(paths[0])
    lugre.save(paths[1])
    true.save(paths[2])
    return paths


def _run(args: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """One command-line run: pid-ff on the fast steps, one robustness draw."""
    folder = tmp_path_factory.mktemp("compensate")
    true, base, diag = _models(folder)
    out = folder / "out.json"
    code = main(["compensate", "--plant-params", str(AXIS), "--friction", str(true),
                 "--controller-friction", f"{base},{diag}", "--controllers", "pid-ff", "--task", "steps",
                 "--fast", "--samples", "1", "--jobs", "1", "--json", str(out),
                 "--report", str(folder / "report"), "--no-progress"])
    assert code == 0
    return {"doc": json.loads(out.read_text()), "folder": folder,
            "files": (true, base, diag)}


def test_json_contract(cli_run: dict) -> None:
    doc = cli_run["doc"]
    assert {"runs", "ratios", "robustness", "warnings", "models", "baseline", "plant",
            "controllers", "tasks", "truths", "mode", "across_truths"} <= set(doc)
    assert list(doc["models"]) == ["base", "diag"] and doc["baseline"] == "base"
    assert doc["tasks"] == ["steps"] and doc["controllers"] == ["pid-ff"]
    assert doc["mode"] == "given" and list(doc["truths"]) == ["true"]
    assert len(doc["runs"]) == 2
    for r in doc["runs"]:
        assert {"truth", "controller", "model", "task", "status", "rms_error", "max_error",
                "reversal_error", "hunting"} <= set(r)
        assert r["status"] == "ok" and r["model"] in ("base", "diag") and r["truth"] == "true"
    rob = doc["robustness"]
    assert rob["task"] == "steps" and rob["samples"] == 1 and len(rob["draws"]) == 1
    draw = dict(rob["draws"][0])
    assert draw.pop("truth") == "true"
    assert set(draw) >= {"Fc", "Fs", "r_neg", "mass"}
    assert all(0.8 <= f <= 1.2 for f in draw.values())
    assert rob["controllers"]["pid-ff"]["ratio"]["diag"]["paired_draws"] == 1


def test_a_true_friction_that_is_a_compared_model_is_said(cli_run: dict) -> None:
    """The contract's warning: the given true friction (true.json) is the compared model
    diag (the same friction): circular, said once, and the conclusion is not sure."""
    doc = cli_run["doc"]
    assert doc["truths"]["true"]["equals"] == "diag"
    said = [w for w in doc["warnings"] if w["code"] == "truth-is-compared"]
    assert len(said) == 1 and "circular" in said[0]["message"]
    assert "diag" in said[0]["message"]
    from controllers.conclusions import of_compensation

    assert of_compensation(doc).confidence == "low"


def test_the_report_draws_the_ratios_the_errors_and_the_draws(cli_run: dict) -> None:
    html = (cli_run["folder"] / "report" / "report.html").read_text()
    for heading in ("What the plant ran", "Across the truths", "Ratios under each truth",
                    "Not ranked", "Tracking errors", "Robustness", "Runs"):
        assert heading in html
    assert html.count("<img") + html.count("<svg") >= 4


def test_ratios_follow_from_the_runs(cli_run: dict) -> None:
    doc = cli_run["doc"]
    runs = {(r["truth"], r["controller"], r["task"], r["model"]): r for r in doc["runs"]}
    for truth, by_controller in doc["ratios"].items():
        for c, by_task in by_controller.items():
            for t, by_model in by_task.items():
                for m, ratios in by_model.items():
                    assert m != doc["baseline"]
                    for e, value in ratios.items():
                        num = runs[(truth, c, t, m)][e]
                        den = runs[(truth, c, t, doc["baseline"])][e]
                        if num is None or den is None or den == 0:
                            assert value is None
                        else:
                            assert value == pytest.approx(num / den, rel=1e-12)
    assert doc["ratios"]["true"]["pid-ff"]["steps"]["diag"]["rms_error"] is not None


def test_the_python_api_gives_the_same_numbers(cli_run: dict) -> None:
    from controllers.compensate import compensate

    true, base, diag = cli_run["files"]
    res = compensate(AXIS, true, [base, diag], controllers=("pid-ff",), task="steps",
                     fast=True, samples=1, workers=1)
    doc = res.as_dict()
    cli = cli_run["doc"]
    assert doc["runs"] == cli["runs"]
    assert doc["ratios"] == cli["ratios"]
    assert doc["robustness"] == cli["robustness"]


def test_the_true_model_helps_the_model_based_compensator() -> None:
    """Physics: on a plant with strong LuGre friction, the LuGre observer built on the true
    model tracks the slow ramp better than built on a wrong one (a LuGre with a third of
    the levels; a Coulomb-only model has no bristle state for the observer)."""
    from controllers.compensate import compensate

    true = make_model("lugre", params="seed002-type1").with_params(Fc=400.0, Fs=700.0)
    weak = true.with_params(Fc=130.0, Fs=230.0)
    res = compensate("hydraulic", true, {"wrong": weak, "true": true},
                     controllers=("lugre-observer",), task="low-velocity-ramp", fast=True,
                     samples=0, workers=1)
    rms = {r["model"]: r["rms_error"] for r in res.runs}
    assert rms["true"] < rms["wrong"], rms
    truth = next(iter(res.truths))
    # the derived observer is built on the seal's soft end (its bristle stiffness a quarter of
    # the model's: the loop at rest must hold a seal half as stiff), so the model's levels act
    # through its sliding estimate: the true model still wins clearly (0.80 here)
    assert res.ratios[truth]["lugre-observer"]["low-velocity-ramp"]["true"]["rms_error"] < 0.9


def test_a_reference_file_is_tracked(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """``--reference``: the run follows the file's positions (from its first one) and the
    errors are those against it."""
    from controllers.compensate import compensate

    true, base, diag = _models(tmp_path)
    t = np.linspace(0.0, 1.2, 121)
    x = 0.12 + 0.004 * np.clip((t - 0.1) / 0.3, 0, 1)  # 4 mm move from 120 mm, then a hold
    ref = tmp_path / "move.csv"
    ref.write_text("t,x_ref\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(t, x, strict=True)))
    out = tmp_path / "ref.json"
    code, _, err = _run(["compensate", "--plant-params", str(AXIS), "--friction", str(true),
                         "--controller-friction", f"{base},{diag}", "--controllers", "pid-ff",
                         "--reference", str(ref), "--samples", "0", "--jobs", "1",
                         "--json", str(out), "--no-progress"], capsys)
    assert code == 0, err
    doc = json.loads(out.read_text())
    assert doc["tasks"] == ["move"] and {r["task"] for r in doc["runs"]} == {"move"}
    res = compensate(AXIS, true, [base, diag], controllers=("pid-ff",), reference=ref,
                     samples=0, workers=1, keep_signals=True)
    sig = res.signals[("true", "pid-ff", "diag", "move")]
    assert sig["t"][-1] == pytest.approx(1.2)
    assert np.allclose(sig["r"], np.interp(sig["t"], t, x), atol=1e-12)
    assert abs(sig["x"][0] - x[0]) < 1e-5  # starts at the reference's first position
    run = next(r for r in doc["runs"] if r["model"] == "diag")
    assert run["rms_error"] == pytest.approx(math.sqrt(np.mean((sig["r"] - sig["x"]) ** 2)))
    assert run["hunting"] is not None  # the hold is a settle window


@pytest.mark.parametrize("case, words", [
    ("controller", "unknown controller"),
    ("missing", "not found"),
    ("effect", "effect"),
    ("both", "--task and --reference"),
    ("backwards", "times must increase"),
    ("outside", "outside the stroke"),
    ("one-model", "at least two models"),
    ("spread", "--spread"),
    ("samples", "at most 1000"),
    ("truth-draws", "at most 50"),
    ("truths-and-friction", "no --truths or --truth-draws"),
])
def test_bad_input_is_one_line_and_writes_nothing(case: str, words: str, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture) -> None:
    true, base, diag = _models(tmp_path)
    ref = tmp_path / "ref.csv"
    ref.write_text("t,x_ref\n0,0.1\n0.5,0.11\n1.0,0.1\n")
    args = ["compensate", "--plant-params", str(AXIS), "--friction", str(true),
            "--controller-friction", f"{base},{diag}", "--controllers", "pid", "--task", "steps",
            "--fast", "--samples", "0", "--json", str(tmp_path / "out.json"),
            "--report", str(tmp_path / "rep"), "--no-progress"]
    if case == "controller":
        args[args.index("pid")] = "pid,bang-bang"
    elif case == "missing":
        args[args.index(f"{base},{diag}")] = f"{base},{tmp_path / 'nothere.json'}"
    elif case == "effect":
        doc = json.loads(diag.read_text())
        doc["effects"][0]["name"] = "warp-drive"
        diag.write_text(json.dumps(doc))
    elif case == "both":
        args += ["--reference", str(ref)]
    elif case in ("backwards", "outside"):
        ref.write_text("t,x_ref\n0,0.1\n0.5,0.11\n0.4,0.1\n" if case == "backwards"
                       else "t,x_ref\n0,0.1\n0.5,0.299\n1.0,0.1\n")
        i = args.index("--task")
        args[i:i + 2] = ["--reference", str(ref)]
    elif case == "one-model":
        args[args.index(f"{base},{diag}")] = str(base)
    elif case == "spread":
        args += ["--spread", "1.5"]
    elif case == "samples":
        args[args.index("--samples") + 1] = "100000000"
    elif case == "truth-draws":
        i = args.index("--friction")
        del args[i:i + 2]
        args += ["--truth-draws", "51"]
    elif case == "truths-and-friction":
        args += ["--truths", str(base)]
    code, out, err = _run(args, capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fcomp: error:"), err
    assert words in lines[0], lines[0]
    assert not (tmp_path / "out.json").exists() and not (tmp_path / "rep").exists()


def test_the_example_plant_files_are_the_axes_of_the_docs() -> None:
    """docs/examples: the 50 mm, 80 kg hydraulic axis at 21 MPa and the 40 mm pneumatic one
    (docs/your-cylinder.md), edited from the templates."""
    from plants.planfile import read_plant_file

    hyd = read_plant_file(AXIS)
    assert hyd.kind == "hydraulic"
    assert (hyd.values["bore"], hyd.values["rod"], hyd.values["mass"]) == (0.05, 0.028, 80.0)
    assert hyd.values["ps"] == 21.0e6
    pn = read_plant_file(ROOT / "docs" / "examples" / "axis40.toml")
    assert pn.kind == "pneumatic" and pn.values["bore"] == 0.04 and pn.values["mass"] == 4.0
