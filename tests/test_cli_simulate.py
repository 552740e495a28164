"""``fcomp simulate motion --friction NAME --params SET --input SPEC --duration S --rate HZ -o OUT``.

Every LuGre-family model runs through the installed console script in a
subprocess (the public contract) and writes a measurement that
:meth:`Measurement.read` reads back and that equals the same simulation done
in-process. Bad input exits with status 2, exactly one line on stderr, no
traceback and no output file left behind: checked through the script for a
few cases and, to keep the suite fast, through the script's ``main`` in-process
for the rest (the same code path after the interpreter starts).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_effects import USER_MODULE

from fcomp.inputs import parse_input
from fcomp.measurement import Measurement
from fcomp.models import make_model
from fcomp.models.lugre_family import PRESETS
from plants import make_plant

_SCRIPT = Path(sys.executable).parent / "fcomp"
FCOMP = [str(_SCRIPT)] if _SCRIPT.exists() else (
    [shutil.which("fcomp")] if shutil.which("fcomp") else [sys.executable, "-m", "fcomp.cli.main"])

FAMILY = list(PRESETS)
INPUT = "sine:amplitude=0.02,frequency=2"  # m/s: two reversals per period
DURATION, RATE = 0.5, 2000.0  # s, Hz
PARAMS = {name: ("canudas1995" if name == "lugre" else "seed000-cylinder1") for name in FAMILY}


def _in_process(args: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    from fcomp.cli.main import main

    try:
        code = main(args[len(FCOMP):])
    except SystemExit as exc:  # argparse
        code = int(exc.code or 0)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _args(name: str, params: str, out: Path, *extra: str) -> list[str]:
    return [*FCOMP, "simulate", "motion", "--friction", name, "--params", params,
            "--input", INPUT, "--duration", str(DURATION), "--rate", str(RATE), "-o", str(out),
            *extra]


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("FCOMP_DEBUG", None)
    return env


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[subprocess.CompletedProcess,
                                                                       Path]]:
    """One subprocess per model, started together."""
    folder = tmp_path_factory.mktemp("simulate")
    procs = {}
    for name in FAMILY:
        out = folder / f"{name}.csv"
        procs[name] = (subprocess.Popen(_args(name, PARAMS[name], out), stdout=subprocess.PIPE,
                                        stderr=subprocess.PIPE, text=True, env=_env()), out)
    done = {}
    for name, (proc, out) in procs.items():
        stdout, stderr = proc.communicate(timeout=300)
        done[name] = (subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr), out)
    return done


@pytest.mark.parametrize("name", FAMILY)
def test_simulate_motion_writes_a_readable_measurement(name: str, runs: dict) -> None:
    proc, out = runs[name]
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    assert "wrote" in proc.stdout and str(out) in proc.stdout
    assert out.with_suffix(".toml").is_file()
    m = Measurement.read(out)
    assert len(m) == int(DURATION * RATE) + 1
    assert {"t", "x", "v", "F"} <= set(m.columns)
    assert m.meta["simulation"]["friction"] == name
    assert m.meta["simulation"]["params"] == PARAMS[name]
    np.testing.assert_allclose(m["t"], np.arange(len(m)) / RATE, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m["v"], 0.02 * np.sin(2 * np.pi * 2 * m["t"]), atol=1e-15)
    # the same simulation in-process gives the same force, to the last digit written
    plant = make_plant("motion", make_model(name, params=PARAMS[name]), PARAMS[name])
    want = plant.simulate(parse_input(INPUT), DURATION, RATE)
    np.testing.assert_allclose(m["F"], want["F"], rtol=1e-15, atol=0)
    # bounded by the levels: |sigma0*z| <= Fs, |dz/dt| <= |v|*(1 + Fs/Fc) (Olsson)
    flat = make_model(name, params=PARAMS[name]).flat_params()
    top = {k: max(v for n, v in flat.items() if n.split("_")[0] == k)
           for k in ("Fc", "Fs", "sigma2", "B", "sigma1") if any(n.split("_")[0] == k for n in flat)}
    vmax = 0.02
    bound = (top.get("Fs", top["Fc"]) + (top.get("sigma2", 0) + top.get("B", 0)) * vmax
             + top.get("sigma1", 0) * vmax * (1 + top.get("Fs", top["Fc"]) / top["Fc"]))
    assert np.abs(m["F"]).max() <= bound
    assert np.abs(m["F"]).max() > 0.5 * top["Fc"]


def test_every_family_model_name_is_accepted() -> None:
    assert FAMILY == ["coulomb", "coulomb-viscous", "stribeck", "dahl", "lugre",
                      "modified-lugre", "nmlgm"]


def test_user_effect_from_a_module_via_effects_option(tmp_path: Path, runs: dict) -> None:
    module = tmp_path / "my_effects.py"
    module.write_text(USER_MODULE.format(name="rod-load"))
    out = tmp_path / "loaded.csv"
    proc = subprocess.run(_args("lugre", "canudas1995", out, "--effects", str(module),
                                "--add-effect", "rod-load", "--set", "load=2.5"),
                          capture_output=True, text=True, env=_env(), timeout=300)
    assert proc.returncode == 0, proc.stderr
    m = Measurement.read(out)
    plain = Measurement.read(runs["lugre"][1])
    np.testing.assert_allclose(m["F"] - plain["F"], 2.5, atol=1e-12)
    assert m.meta["simulation"]["friction"] == "lugre + rod-load"


def test_catalogue_effect_and_parameter_override(tmp_path: Path, runs: dict,
                                                 capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "offset.csv"
    code, _, err = _in_process(_args("lugre", "canudas1995", out, "--add-effect", "force-offset",
                                     "--set", "offset=-0.7"), capsys)
    assert code == 0, err
    plain = Measurement.read(runs["lugre"][1])
    np.testing.assert_allclose(Measurement.read(out)["F"] - plain["F"], -0.7, atol=1e-12)


BAD = {
    "unknown-model": (["--friction", "lugr"], "unknown friction model 'lugr'"),
    "unknown-params": (["--params", "canudas"], "unknown parameter set 'canudas'"),
    "unknown-effect": (["--add-effect", "presure-dependence"], "unknown effect"),
    "negative-stiffness": (["--set", "sigma0=-1e5"], "sigma0"),
    "zero-stiffness": (["--set", "sigma0=0"], "sigma0"),
    "fs-below-fc": (["--set", "Fs=0.5"], "Fc = 1 must not exceed Fs = 0.5"),
    "negative-fc": (["--set", "Fc=-1"], "Fc"),
    "unknown-parameter": (["--set", "sigma3=1"], "sigma3"),
    "not-a-number": (["--set", "sigma0=stiff"], "not a number"),
    "effect-out-of-bounds": (["--add-effect", "pressure-dependence", "--set", "kp=1"], "kp"),
    "bad-input-spec": (["--input", "sine:amplitude=big,frequency=1"], "amplitude"),
    "unknown-input-kind": (["--input", "ramp:amplitude=1"], "unknown input kind"),
    "negative-duration": (["--duration", "-1"], "--duration"),
    "zero-rate": (["--rate", "0"], "--rate"),
    "missing-effects-module": (["--effects", "/nonexistent/effects.py"], "not found"),
    "output-not-csv": (["-o", "OUT.txt"], "must end in .csv"),
}


def _bad_args(tmp_path: Path, extra: list[str]) -> tuple[list[str], Path]:
    out = tmp_path / "out.csv"
    base = {"--friction": "lugre", "--params": "canudas1995", "--input": INPUT,
            "--duration": str(DURATION), "--rate": str(RATE), "-o": str(out)}
    rest = []
    i = 0
    while i < len(extra):
        key, val = extra[i], extra[i + 1]
        if key in base and key not in ("--set", "--add-effect"):
            base[key] = val if key != "-o" else str(tmp_path / val)
        else:
            rest += [key, val]
        i += 2
    args = [*FCOMP, "simulate", "motion"]
    for k, v in base.items():
        args += [k, v]
    return args + rest, Path(base["-o"])


#: the cases also run through the console script (the others call its ``main`` in-process)
VIA_SCRIPT = ("unknown-model", "fs-below-fc")


@pytest.mark.parametrize("case", list(BAD))
def test_bad_input_one_line_exit_2_no_file(case: str, tmp_path: Path,
                                           capsys: pytest.CaptureFixture) -> None:
    extra, fragment = BAD[case]
    args, out = _bad_args(tmp_path, extra)
    if case in VIA_SCRIPT:
        proc = subprocess.run(args, capture_output=True, text=True, env=_env(), timeout=300)
        code, stdout, stderr = proc.returncode, proc.stdout, proc.stderr
    else:
        code, stdout, stderr = _in_process(args, capsys)
    assert code == 2, (code, stderr)
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr
    assert fragment in lines[0], lines[0]
    assert stdout == ""
    assert not out.exists() and not out.with_suffix(".toml").exists()
    assert list(tmp_path.iterdir()) == []


def test_missing_required_option_is_one_line(tmp_path: Path,
                                             capsys: pytest.CaptureFixture) -> None:
    code, _, err = _in_process([*FCOMP, "simulate", "motion", "--friction", "lugre", "-o",
                                str(tmp_path / "x.csv")], capsys)
    assert code == 2
    assert len(err.splitlines()) == 1 and "--input" in err
    assert list(tmp_path.iterdir()) == []
