"""Importers of the real data sets, the generic .mat reader, ``fcomp import`` and bad input.

Expected values are computed here from the raw files with numpy/scipy
directly, not through the package.
"""

from __future__ import annotations

import hashlib
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from fcomp import datasets
from fcomp.cli.main import main
from fcomp.errors import FcompError, UnknownNameError
from fcomp.importers import IMPORTERS, import_file
from fcomp.matfile import parse_mapping, read_mat
from fcomp.measurement import Measurement


def _raw_mat(name: str) -> dict:
    return scipy.io.loadmat(datasets.path("emps", name))


# ------------------------------------------------------------------ datasets
def test_shipped_datasets_have_sources_and_files() -> None:
    assert datasets.names() == ["emps", "mataveid", "seed001", "zillen"]
    for name in datasets.names():
        folder = datasets.root() / name
        text = (folder / "SOURCE.md").read_text()
        assert "Source" in text or "Citation" in text
        assert datasets.files(name)
    assert "CC0" in (datasets.root() / "zillen" / "SOURCE.md").read_text()
    assert (datasets.root() / "mataveid" / "LICENSE.MataveID").is_file()
    assert (datasets.root() / "emps" / "README.txt").is_file()
    size = sum(p.stat().st_size for p in (datasets.root() / "zillen").iterdir())
    assert size < 6.5e6


def test_dataset_errors() -> None:
    with pytest.raises(UnknownNameError, match="unknown data set 'nope'"):
        datasets.path("nope", "x.csv")
    with pytest.raises(FcompError, match="has no file 'x.mat'"):
        datasets.path("emps", "x.mat")
    with pytest.raises(FcompError, match="holds tables, not time series"):
        datasets.load("seed001", "c2_b.csv")


# ---------------------------------------------------------------------- EMPS
@pytest.mark.parametrize("name", ["DATA_EMPS.mat", "DATA_EMPS_PULSES.mat"])
def test_emps_columns_units_and_provenance(name: str) -> None:
    raw = _raw_mat(name)
    meas = datasets.load("emps", name)
    np.testing.assert_array_equal(meas.t, raw["t"].ravel())
    np.testing.assert_array_equal(meas["x"], raw["qm"].ravel())
    np.testing.assert_array_equal(meas["x_ref"], raw["qg"].ravel())
    np.testing.assert_array_equal(meas["u"], raw["vir"].ravel())
    np.testing.assert_allclose(meas["F_ext"], raw["gtau"].item() * raw["vir"].ravel(), rtol=1e-15)
    assert ("pulses_N" in meas) == ("pulses_N" in raw)
    assert meas.meta["kind"] == "electromechanical-axis"
    assert "mass" not in meas.rig  # to be estimated
    assert meas.meta["signals"]["u_unit"] == "V"
    src = meas.meta["source"]
    assert src["file"] == name
    assert src["sha256"] == hashlib.sha256(datasets.path("emps", name).read_bytes()).hexdigest()
    assert "Janot" in src["citation"]
    assert src["gtau"] == pytest.approx(35.15065188)


def test_emps_pulses_are_already_in_the_drive_signal() -> None:
    """The documented reason F_ext does not add pulses_N: F_ext jumps by gtau*5 V at a pulse."""
    meas = datasets.load("emps", "DATA_EMPS_PULSES.mat")
    p = meas["pulses_N"]
    rises = np.flatnonzero(np.diff(p) > 0)
    assert len(rises) > 5
    jumps = meas["F_ext"][rises + 1] - meas["F_ext"][rises]
    gtau = meas.meta["source"]["gtau"]
    np.testing.assert_allclose(jumps, gtau * np.diff(p)[rises], rtol=0.05)


# -------------------------------------------------------------------- Zillen
@pytest.mark.parametrize("name", ["O-ring_3bar.csv", "rerun_1_O-ring257_3bar.csv"])
def test_zillen_si_conversion_and_signs(name: str) -> None:
    raw = np.loadtxt(datasets.path("zillen", name))
    meas = datasets.load("zillen", name)
    np.testing.assert_allclose(meas.t, raw[:, 0] / 1000.0, rtol=1e-15)
    np.testing.assert_allclose(meas["x"], -raw[:, 4] / 1000.0, rtol=1e-15)
    np.testing.assert_allclose(meas["p1"], raw[:, 5] * 1e5, rtol=1e-15)
    np.testing.assert_array_equal(meas["F_ext"], -raw[:, 6])
    np.testing.assert_array_equal(meas["laser_V"], raw[:, 1])
    bore = 0.0257 if "257" in name else 0.025
    assert meas.rig == {"bore": bore}
    assert "p2" not in meas and "rod" not in meas.rig
    # F = p1*A1 + F_ext is minus the authors' friction Force - p*A
    A = math.pi * (bore / 2) ** 2
    authors = raw[:, 6] - raw[:, 5] * 1e5 * A
    np.testing.assert_allclose(meas["p1"] * A + meas["F_ext"], -authors, atol=1e-9)
    assert meas.meta["pressure"] == "gauge"
    assert meas.meta["source"]["licence"] == "CC0-1.0"


def test_zillen_duplicate_time_stamps_and_bad_files(tmp_path: Path) -> None:
    rows = [
        [0.0, 3.5, 1.5, 3.2, 0.00, 2.99, 149.4],
        [10.0, 3.5, 1.5, 3.2, 0.01, 2.99, 149.5],
        [10.0, 3.5, 1.5, 3.2, 0.01, 2.99, 149.5],   # identical duplicate
        [10.0, 3.5, 1.5, 3.2, 0.02, 2.99, 149.6],   # same time, different values
        [20.0, 3.5, 1.5, 3.2, 0.03, 2.99, 149.7],
    ]
    src = tmp_path / "Seal_257_3bar.csv"
    src.write_text("\n".join("\t".join(f"{v:.3f}" for v in r) for r in rows) + "\n")
    meas = import_file("zillen", src)
    assert meas.t.tolist() == [0.0, 0.01, 0.02]
    assert meas["F_ext"].tolist() == [-149.4, -149.5, -149.7]
    assert meas.meta["source"]["duplicate_rows_dropped"] == 1
    assert meas.meta["source"]["repeated_times_dropped"] == 1
    assert meas.rig["bore"] == 0.0257
    assert import_file("zillen", src, bore=0.03).rig["bore"] == 0.03

    back = tmp_path / "back.csv"
    back.write_text("0 1 2 3 4 5 6\n10 1 2 3 4 5 6\n5 1 2 3 4 5 6\n")
    with pytest.raises(FcompError, match=r"back.csv: time goes backwards at line 3"):
        import_file("zillen", back)
    six = tmp_path / "six.csv"
    six.write_text("0 1 2 3 4 5\n10 1 2 3 4 5\n")
    with pytest.raises(FcompError, match=r"six.csv: expected 7 whitespace-separated columns"):
        import_file("zillen", six)
    nan = tmp_path / "nan.csv"
    nan.write_text("0 1 2 3 4 5 6\n10 1 2 nan 4 5 6\n")
    with pytest.raises(FcompError, match=r"nan.csv: non-finite value \(nan\) at line 2, column 4"):
        import_file("zillen", nan)


# ------------------------------------------------------------------ MataveID
def test_mataveid_raw_volts_and_optional_calibration() -> None:
    raw = np.loadtxt(datasets.path("mataveid", "HangingLoad.csv"), delimiter=",")
    meas = datasets.load("mataveid", "HangingLoad.csv")
    assert list(meas.columns) == ["t", "u", "r_raw", "y_raw"]
    np.testing.assert_array_equal(meas["y_raw"], raw[:, 2])
    assert "x" not in meas  # no calibration exists: no metres
    assert meas.meta["signals"]["u_unit"] == "V"
    scaled = import_file("mataveid", datasets.path("mataveid", "HangingLoad.csv"),
                         position_scale=0.02)
    np.testing.assert_allclose(scaled["x"], 0.02 * raw[:, 2])
    np.testing.assert_allclose(scaled["x_ref"], 0.02 * raw[:, 1])
    assert scaled.meta["source"]["position_scale_m_per_V"] == 0.02


# ------------------------------------------------------------------ generic
def _write_mat(path: Path, n: int = 50) -> dict:
    t = np.linspace(0.0, 0.49, n)
    data = {"time": t[:, None], "pos_mm": 1000 * np.sin(t)[None, :], "gain": np.array([[2.5]]),
            "volts": np.cos(t), "rig": {"p": 3e5 + t}, "short": np.arange(3.0),
            "label": "text", "matrix": np.ones((n, 2))}
    scipy.io.savemat(path, data)
    return {"t": t}


def test_generic_mat_mapping_products_structs_and_sidecar(tmp_path: Path) -> None:
    src = tmp_path / "rig.mat"
    t = _write_mat(src)["t"]
    side = tmp_path / "rig.toml"
    side.write_text('kind = "pneumatic-cylinder"\n[rig]\nbore = 0.032\nmass = 0.4\n')
    meas = import_file("mat", src, mapping="t=time,x=pos_mm*1e-3,F_ext=-gain*volts,p1=rig.p",
                       sidecar=side)
    np.testing.assert_allclose(meas["x"], np.sin(t), rtol=1e-12)
    np.testing.assert_allclose(meas["F_ext"], -2.5 * np.cos(t), rtol=1e-12)
    np.testing.assert_allclose(meas["p1"], 3e5 + t)
    assert meas.rig == {"bore": 0.032, "mass": 0.4}
    assert meas.meta["kind"] == "pneumatic-cylinder"
    assert meas.meta["source"]["mapping"]["x"] == "pos_mm*1e-3"
    assert meas.meta["source"]["sidecar"] == "rig.toml"
    direct = read_mat(src, {"t": "time", "g": "gain"})
    assert direct["g"].tolist() == [2.5] * len(t)


@pytest.mark.parametrize(
    ("mapping", "message"),
    [
        ("t=time,x=qm", r"no variable 'qm' in the file \(variables: gain, label"),
        ("t=time,x=short", r"different lengths \(t: 50, x: 3\)"),
        ("t=time,x=label", r"variable 'label' \(for column 'x'\) is not a real numeric array"),
        ("t=time,x=matrix", r"variable 'matrix' \(for column 'x'\) has shape \(50, 2\)"),
        ("t=gain", r"is a scalar, not a vector of sample times"),
        ("t=time,x=pos_mm", r"column 'x' spans .* not millimetres"),
        ("t=-time", r"time is not strictly increasing"),
        ("t=time,x=a+b", r"'a\+b' is neither a variable nor a number"),
    ],
)
def test_generic_mat_bad_mappings(tmp_path: Path, mapping: str, message: str) -> None:
    src = tmp_path / "rig.mat"
    _write_mat(src)
    with pytest.raises(FcompError, match=message) as info:
        import_file("mat", src, mapping=mapping)
    assert str(info.value).startswith(str(src))


def test_mapping_syntax_errors() -> None:
    assert parse_mapping("t=a, x = b*2 ,") == {"t": "a", "x": "b*2"}
    for spec, msg in [("x=a", "'t' must be mapped"), ("t", "expected COLUMN=VARIABLE"),
                      ("t=a,t=b", "mapped twice"), ("t=a,1x=b", "not a valid column name"),
                      ("t=", "no variable given")]:
        with pytest.raises(FcompError, match=msg):
            parse_mapping(spec)


def test_unreadable_mat_files(tmp_path: Path) -> None:
    h5 = tmp_path / "v73.mat"
    h5.write_bytes(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 ." + b"\0" * 200)
    with pytest.raises(FcompError, match=r"v73.mat: MATLAB v7.3 \(HDF5\) files are not supported"):
        import_file("mat", h5, mapping="t=t")
    junk = tmp_path / "junk.mat"
    junk.write_bytes(b"this is not a mat file at all" * 10)
    with pytest.raises(FcompError, match=r"junk.mat: cannot read as a MATLAB .mat file"):
        import_file("mat", junk, mapping="t=t")
    with pytest.raises(FcompError, match=r"not an EMPS file, variable\(s\) t, qm, qg, vir, gtau"):
        scipy.io.savemat(tmp_path / "other.mat", {"x": np.arange(3.0)})
        import_file("emps", tmp_path / "other.mat")


def test_registry_and_options() -> None:
    assert IMPORTERS.names() == ["csv", "emps", "mat", "mataveid", "zillen"]
    with pytest.raises(UnknownNameError, match="unknown import kind .parquet."):
        import_file("parquet", "x")
    with pytest.raises(FcompError, match="option\\(s\\) bore do not apply"):
        import_file("emps", datasets.path("emps", "DATA_EMPS.mat"), bore=0.02)


# ----------------------------------------------------------------------- CLI
def test_cli_import_round_trips(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "sub" / "emps.csv"
    src = datasets.path("emps", "DATA_EMPS_PULSES.mat")
    assert main(["import", "emps", str(src), "-o", str(out)]) == 0
    assert "24841 samples" in capsys.readouterr().out
    back = Measurement.read(out)
    ref = import_file("emps", src)
    for k in ref.columns:
        np.testing.assert_array_equal(back[k], ref[k])
    assert back.meta["source"] == ref.meta["source"]
    zout = tmp_path / "z.csv"
    assert main(["import", "zillen", str(datasets.path("zillen", "NAPN_1bar.csv")),
                 "-o", str(zout)]) == 0
    assert Measurement.read(zout).meta["source"]["file"] == "NAPN_1bar.csv"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["import", "emps", "{d}/missing.mat"], "missing.mat: file not found"),
        (["import", "mat", "{emps}"], "--map COLUMN=EXPR,... is required"),
        (["import", "mat", "{emps}", "--map", "t=t,x=nope"], "no variable 'nope'"),
        (["import", "zillen", "{emps}"], "cannot read as whitespace-separated numbers"),
        (["import", "emps", "{zillen}"], "cannot read as a MATLAB .mat file"),
        (["import", "emps", "{emps}", "--bore", "0.02"], "bore do not apply"),
        (["import", "gizmo", "{emps}"], "unknown import kind 'gizmo'"),
        (["import", "mat", "{emps}", "--map", "t=t", "--sidecar", "{d}/bad.toml"],
         "bad.toml: not valid TOML"),
        (["import", "mat", "{emps}", "--map", "t=t,x=qm", "--sidecar", "{d}/mm.toml"],
         "rig.bore = 25.0 m is implausible"),
    ],
)
def test_cli_bad_input_one_line_exit_2_nothing_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    (tmp_path / "bad.toml").write_text("[rig\n")
    (tmp_path / "mm.toml").write_text("[rig]\nbore = 25.0\n")
    subs = {"d": str(tmp_path), "emps": str(datasets.path("emps", "DATA_EMPS.mat")),
            "zillen": str(datasets.path("zillen", "O-ring_1bar.csv"))}
    out = tmp_path / "out" / "result.csv"
    code = main([a.format(**subs) for a in argv] + ["-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_cli_subprocess_has_no_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "run.csv"
    bad.write_text("not,a,mat\n")
    proc = subprocess.run([sys.executable, "-m", "fcomp.cli.main", "import", "emps", str(bad),
                           "-o", str(tmp_path / "o.csv")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.startswith("fcomp: error: ") and proc.stderr.count("\n") == 1
    assert str(bad) in proc.stderr
    assert not (tmp_path / "o.csv").exists()
