"""``fcomp fit DATA.csv --friction NAME [--offset] [--json OUT]``: the public contract.

JSON ``{"model", "params", "stderr", "rms"}`` (plus more keys); the mass is estimated
when the sidecar has no ``rig.mass`` and the data hold ``F_ext``; ``--offset`` adds
``params.offset``; bad input and non-convergence give one line and exit status 2.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fcomp.cli.main import main
from fcomp.measurement import Measurement
from fcomp.models import make_model
from fcomp.trajectory import friction_along_motion

RNG = np.random.default_rng(7)


def _motion(n: int = 4001) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n) / 1000.0
    v = 0.05 * np.sin(np.pi * t) + 0.02 * np.sin(2.6 * np.pi * t)
    a = 0.05 * np.pi * np.cos(np.pi * t) + 0.02 * 2.6 * np.pi * np.cos(2.6 * np.pi * t)
    return t, v, a


@pytest.fixture(scope="module")
def lugre_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """LuGre friction (Canudas et al. 1995 values, sigma2 raised) with 0.01 N noise."""
    model = make_model("lugre", params="canudas1995").with_params(sigma2=20.0)
    t, v, a = _motion()
    F = friction_along_motion(model, t, v, a=a).F + 0.01 * RNG.standard_normal(t.size)
    path = tmp_path_factory.mktemp("fit") / "lugre.csv"
    Measurement({"t": t, "v": v, "a": a, "F": F}, {"name": "lugre"}).write(path)
    return path


@pytest.fixture(scope="module")
def rig_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Force-driven rig without rig.mass: F_ext = m*a + Fc*sign(v) + B*v + offset + noise."""
    t, v, a = _motion()
    F_ext = 2.5 * a + 3.0 * np.sign(v) + 40.0 * v + 0.4 + 0.02 * RNG.standard_normal(t.size)
    path = tmp_path_factory.mktemp("fit") / "rig.csv"
    Measurement({"t": t, "v": v, "a": a, "F_ext": F_ext},
                {"name": "rig", "kind": "friction-rig"}).write(path)
    return path


def run(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_help_exits_zero(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["fit", "--help"])
    assert exc.value.code == 0
    assert "--offset" in capsys.readouterr().out


def test_json_contract(lugre_csv: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "fit.json"
    code, text, err = run(["fit", str(lugre_csv), "--friction", "lugre", "--json", str(out)],
                          capsys)
    assert code == 0, err
    doc = json.loads(out.read_text())
    assert doc["model"] == "lugre"
    assert set(doc["params"]) == {"Fc", "Fs", "vs", "n", "sigma0", "sigma1", "sigma2"}
    assert set(doc["stderr"]) == set(doc["params"])
    assert all(isinstance(v, float) and v > 0 for v in doc["stderr"].values())
    assert isinstance(doc["rms"], float) and doc["rms"] == pytest.approx(0.01, rel=0.2)
    truth = {"Fc": 1.0, "Fs": 1.5, "vs": 1e-3, "sigma2": 20.0}
    for name, value in truth.items():
        assert abs(doc["params"][name] - value) < 3 * doc["stderr"][name], name
        lo, hi = doc["ci"][name]
        assert lo < doc["params"][name] < hi
    assert doc["units"]["sigma0"] == "N/m" and doc["converged"] is True
    assert "sigma0" in text and "rms force error" in text  # the human-readable table


def test_json_to_stdout(lugre_csv: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, text, _ = run(["fit", str(lugre_csv), "--friction", "coulomb-viscous", "--json", "-"],
                        capsys)
    assert code == 0
    doc = json.loads(text)  # nothing but the JSON on standard output
    assert set(doc["params"]) == {"Fc", "B"}


def test_mass_estimated_and_offset(rig_csv: Path, tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "rig.json"
    code, _, err = run(["fit", str(rig_csv), "--friction", "coulomb-viscous", "--offset",
                        "--json", str(out)], capsys)
    assert code == 0, err
    doc = json.loads(out.read_text())
    p, se = doc["params"], doc["stderr"]
    for name, value in {"mass": 2.5, "Fc": 3.0, "B": 40.0, "offset": 0.4}.items():
        assert abs(p[name] - value) < 3 * se[name], name
    # a known mass (option) is not estimated
    code, text, _ = run(["fit", str(rig_csv), "--friction", "coulomb-viscous", "--offset",
                         "--mass", "2.5", "--json", "-"], capsys)
    assert code == 0 and "mass" not in json.loads(text)["params"]


@pytest.mark.parametrize("args, message", [
    (["fit", "missing.csv", "--friction", "lugre"], "file not found"),
    (["fit", "DATA", "--friction", "no-such-model"], "no-such-model"),
    (["fit", "DATA", "--friction", "lugre", "--fix", "sigma0"], "expected NAME=VALUE"),
    (["fit", "DATA", "--friction", "lugre", "--free", "Fc,bogus"], "bogus"),
    (["fit", "DATA", "--friction", "lugre", "--json", "/dev/null/out.json"], "is a file"),
    (["fit", "DATA", "--friction", "lugre", "--max-nfev", "0"], "--max-nfev"),
    (["fit", "DATA", "--friction", "lugre", "--method", "samples"], "is dynamic"),
])
def test_bad_input_one_line_exit_2(args: list[str], message: str, lugre_csv: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    args = [str(lugre_csv) if a == "DATA" else a for a in args]
    code, _, err = run(args, capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("fcomp: error:") and message in err


def test_data_without_force(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    t, v, _ = _motion(200)
    path = tmp_path / "bare.csv"
    Measurement({"t": t, "v": v}, {"name": "bare"}).write(path)
    code, _, err = run(["fit", str(path), "--friction", "coulomb"], capsys)
    assert code == 2 and "no force to fit" in err and err.count("\n") == 1


def test_non_convergence_exits_2_without_output(lugre_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "never.json"
    proc = subprocess.run(
        [sys.executable, "-m", "fcomp.cli.main", "fit", str(lugre_csv), "--friction", "lugre",
         "--max-nfev", "2", "--json", str(out)],
        capture_output=True, text=True)
    assert proc.returncode == 2
    assert "did not converge" in proc.stderr and proc.stderr.count("\n") == 1
    assert "Traceback" not in proc.stderr
    assert not out.exists()
