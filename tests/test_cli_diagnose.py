"""``fcomp diagnose``: the public contract, the report, user effects, bad input."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fcomp.cli.main import main
from fcomp.measurement import Measurement
from fcomp.synthetic import generate

CONTRACT = {"baseline", "rms_baseline", "added", "steps", "candidates", "ties", "rms_final",
            "noise_floor", "verdict", "residual_features"}


@pytest.fixture(scope="module")
def pressure_csv(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("diag") / "press.csv"
    generate(["pressure-dependence"], duration=12.0, seed=1).measurement.write(path)
    return path


def test_contract_json_and_report(pressure_csv: Path, tmp_path: Path, capsys) -> None:
    out, rep = tmp_path / "d.json", tmp_path / "rep"
    code = main(["diagnose", str(pressure_csv), "--friction", "lugre", "--json", str(out),
                 "--report", str(rep), "--no-progress"])
    assert code == 0
    doc = json.loads(out.read_text())
    assert set(doc) >= CONTRACT
    assert doc["baseline"] == "lugre"
    assert doc["added"] == ["pressure-dependence"]
    assert doc["verdict"] == "explained"
    assert doc["rms_final"] < 0.3 * doc["rms_baseline"]
    want = {"effect": "pressure-dependence", "rms_before": doc["rms_baseline"],
            "rms_after": doc["rms_final"], "accepted": True, "forced": False, "removed": False}
    assert {k: doc["steps"][0][k] for k in want} == want
    assert isinstance(doc["steps"][0]["warnings"], list)
    assert {"effect", "rms_heldout"} <= set(doc["candidates"][0])
    heldout = [c["rms_heldout"] for c in doc["candidates"] if c["rms_heldout"] is not None]
    assert heldout == sorted(heldout)  # best first
    for f in doc["residual_features"]:  # the contract's two keys, extended (issues 41, 43)
        assert {"feature", "strength"} <= set(f) <= {"feature", "strength", "rms", "same_as"}
        # the RMS a feature carries: its share of the final held-out mean square
        assert f["rms"] == pytest.approx(doc["rms_final"] * f["strength"] ** 0.5, rel=1e-3,
                                         abs=0.01 * doc["rms_final"])
    assert 0.2 < doc["noise_floor"] < 0.8  # the generator's noise is 0.4 N
    html = (rep / "report.html").read_text()
    assert html.count('<img src="data:image/png;base64,') >= 7
    assert not re.search(r'(src|href)="https?://', html)  # self-contained
    assert "Chamber pressure energises lip seals" in html  # the physics of the added effect
    opening = html.index('conclusion"><p><strong>Conclusion:</strong> lugre misses '
                         "pressure-dependence")
    assert opening < html.index("<h2")  # the report opens with it
    captured = capsys.readouterr()
    printed = captured.out
    assert "verdict: explained" in printed and "pressure-dependence" in printed
    # the conclusion first; warnings only on stderr, in the one form
    assert printed.startswith("Conclusion: lugre misses pressure-dependence; with them the "
                              "held-out RMS falls")
    assert printed.splitlines()[1].startswith("How sure: ")
    assert "warning" not in printed
    assert all(ln.startswith("fcomp: warning: ") for ln in captured.err.splitlines())


def test_json_to_stdout(pressure_csv: Path, capsys) -> None:
    code = main(["diagnose", str(pressure_csv), "--friction", "lugre", "--json", "-",
                 "--candidates", "pressure-dependence,force-offset", "--no-progress"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["added"] == ["pressure-dependence"]
    assert {c["effect"] for c in doc["candidates"]} == {"pressure-dependence", "force-offset"}


def test_several_files_are_several_experiments(tmp_path: Path, capsys) -> None:
    rec = generate(["force-offset"], duration=12.0, experiments=2, seed=1)
    paths = []
    for i, m in enumerate(rec.experiments()):
        p = tmp_path / f"run{i}.csv"
        Measurement({k: v for k, v in m.columns.items() if k != "experiment"}, m.meta).write(p)
        paths.append(str(p))
    code = main(["diagnose", *paths, "--friction", "lugre", "--json", "-", "--no-progress",
                 "--candidates", "force-offset,direction-asymmetry"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["added"][0] in ("force-offset", "direction-asymmetry")
    assert "force-offset" in [doc["added"][0], *sum(doc["ties"], [])]


USER_EFFECT = '''
from fcomp.effects import Effect, register_effect
from fcomp.parameters import make_params_class, spec


@register_effect
class Bias(Effect):
    """A constant bias of the load cell (the user's own effect)."""

    name = "load-cell-bias"
    Params = make_params_class("BiasParams", [spec("bias", "N", 0.0, -1e3, 1e3, "bias",
                                                   directional=False)], owner="bias")
    signature = "constant residual"
    experiment = "zero reading"

    def extra_force(self, be, sig, P):
        return P("bias"), 0.0
'''


def test_add_a_users_own_effect(tmp_path: Path, capsys) -> None:
    mod = tmp_path / "my_effects.py"
    mod.write_text(USER_EFFECT)
    data = tmp_path / "off.csv"
    generate(["force-offset"], duration=12.0, seed=1).measurement.write(data)
    code = main(["diagnose", str(data), "--friction", "lugre", "--effects", str(mod),
                 "--add-effect", "load-cell-bias", "--no-search", "--json", "-", "--no-progress"])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["added"] == ["load-cell-bias"]
    step = doc["steps"][0]
    assert step["forced"] and step["accepted"]
    assert doc["rms_final"] < 0.2 * doc["rms_baseline"]
    assert doc["params"]["bias"] == pytest.approx(6.0, abs=0.5)  # the hidden offset


def _one_line_error(capsys, argv: list[str], match: str) -> None:
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse usage errors leave through SystemExit(2)
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert re.search(match, err), err


def test_bad_input_one_line_exit_2(pressure_csv: Path, tmp_path: Path, capsys) -> None:
    base = ["diagnose", str(pressure_csv), "--no-progress"]
    _one_line_error(capsys, ["diagnose", str(tmp_path / "nope.csv"), "--friction", "lugre"],
                    "not found")
    _one_line_error(capsys, [*base, "--friction", "lugrex"], "unknown friction model 'lugrex'")
    _one_line_error(capsys, [*base, "--friction", "lugre", "--add-effect", "magic"],
                    "unknown effect 'magic'")
    (tmp_path / "afile").write_text("x")
    _one_line_error(capsys, [*base, "--friction", "lugre", "--json",
                             str(tmp_path / "afile" / "o.json")], "is a file")
    _one_line_error(capsys, [*base, "--friction", "lugre", "--report", str(tmp_path / "afile")],
                    "not a directory")
    _one_line_error(capsys, [*base, "--friction", "lugre", "--effects",
                             str(tmp_path / "none.py")], "not found")
    _one_line_error(capsys, ["diagnose", "--friction", "lugre"], "required")


def test_unsupported_baselines_say_why(tmp_path: Path, capsys) -> None:
    t = np.arange(2000) / 500.0
    still = tmp_path / "still.csv"
    Measurement({"t": t, "x": np.full(t.size, 0.1), "F": np.random.default_rng(0).normal(
        5.0, 0.3, t.size)}, {"name": "still"}).write(still)
    out = tmp_path / "o.json"
    _one_line_error(capsys, ["diagnose", str(still), "--friction", "lugre", "--json", str(out),
                             "--no-progress"], "hardly moves")
    assert not out.exists()  # no half-written output
    v = np.array([0.01, 0.05, 0.1, -0.01, -0.05, -0.1] * 4)
    table = tmp_path / "table.csv"
    Measurement({"t": np.arange(v.size, dtype=float), "v": v, "F": 20 * np.sign(v) + 50 * v},
                {"name": "table", "diagnosis": {"samples": "steady-state"}}).write(table)
    _one_line_error(capsys, ["diagnose", str(table), "--friction", "lugre", "--no-progress"],
                    "dynamic model .* steady-state points")


def test_console_script_help() -> None:
    proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", "diagnose", "--help"],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0
    assert "--friction" in proc.stdout and "--report" in proc.stdout
