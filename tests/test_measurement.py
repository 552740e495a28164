"""The measurement format (data-format.md): lossless round trip, validation, errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from fcomp.errors import FcompError
from fcomp.measurement import Measurement, checked, sidecar_paths


def _awkward_floats(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    vals = rng.standard_normal(n) * 10.0 ** rng.integers(-300, 300, n)
    vals[:6] = [0.0, -0.0, 1e-310, -5e-324, 1.7976931348623157e308, 0.1 + 0.2]
    return vals


def _meta() -> dict:
    return {
        "name": "run-07 ünïcode \"quoted\" \\ back",
        "kind": "hydraulic-cylinder",
        "pressure": "absolute",
        "p_atm": 101300.0,
        "rig": {"bore": 0.05, "rod": 0.025, "stroke": 0.3, "mass": 12.5,
                "orientation": "vertical-up"},
        "signals": {"u_unit": "A"},
        "user": {"flag": True, "count": 3, "tags": ["a", "b"], "nested": {"deep": 1.5e-9}},
    }


def test_round_trip_is_lossless(tmp_path: Path) -> None:
    n = 500
    t = np.cumsum(np.random.default_rng(1).uniform(1e-4, 2e-3, n))
    cols = {"t": t, "x": np.random.default_rng(2).uniform(-0.1, 0.2, n),
            "p1": 1e5 + np.abs(_awkward_floats(n, 3)) % 1e7, "p2": np.full(n, 2e5),
            "my_signal": _awkward_floats(n, 4), "F": np.random.default_rng(5).standard_normal(n)}
    meas = Measurement(cols, _meta())
    csv, toml = meas.write(tmp_path / "run.csv")
    assert (csv, toml) == (tmp_path / "run.csv", tmp_path / "run.toml")
    back = Measurement.read(csv)
    assert list(back.columns) == list(cols)
    for k, v in cols.items():
        # bitwise equality, including the sign of zero and subnormals
        assert np.array_equal(back[k].view(np.int64), np.asarray(v, float).view(np.int64)), k
    meta = {k: v for k, v in back.meta.items() if not k.startswith("_")}
    assert meta == _meta()
    # writing the read-back file again gives the same bytes
    back.write(tmp_path / "again.csv")
    assert (tmp_path / "again.csv").read_bytes() == csv.read_bytes()
    assert (tmp_path / "again.toml").read_bytes() == toml.read_bytes()


def test_missing_sidecar_is_allowed_and_named_from_the_file(tmp_path: Path) -> None:
    (tmp_path / "plain.csv").write_text("t,v,F\n0,0.1,2\n0.5,0.2,3\n")
    meas = Measurement.read(tmp_path / "plain")
    assert meas.label == "plain"
    assert meas["F"].tolist() == [2.0, 3.0]
    with pytest.raises(FcompError, match=r"plain: sidecar key rig.mass is missing"):
        meas.rig_value("mass")


def test_gauge_pressure_converts_absolute(tmp_path: Path) -> None:
    t = np.arange(3.0)
    meas = Measurement({"t": t, "p1": [2e5, 3e5, 4e5], "p2": [1.5e5, 1.5e5, 1.5e5]},
                       {"pressure": "absolute", "p_atm": 1e5})
    np.testing.assert_array_equal(meas.gauge_pressure("p1"), [1e5, 2e5, 3e5])
    p1, p2 = meas.gauge_pressures()
    np.testing.assert_array_equal(p1, [1e5, 2e5, 3e5])
    np.testing.assert_array_equal(p2, [5e4] * 3)
    with pytest.raises(FcompError, match="rig.bore is missing"):
        meas.areas()
    m2 = Measurement({"t": t}, {"rig": {"bore": 0.04, "rod": 0.02}})
    area1, area2 = m2.areas()
    assert area1 == pytest.approx(math.pi / 4 * 0.04**2)
    assert area2 == pytest.approx(math.pi / 4 * (0.04**2 - 0.02**2))


# ------------------------------------------------------------ bad CSV files
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("t,x\n0,0\n1,nan\n2,0\n", r"column 'x' has a non-finite value \(nan\) at row 3"),
        ("t,x\n0,0\n1,0.1\n1,0.2\n", r"time is not strictly increasing at row 4"),
        ("t,x\n0,0\n2,0.1\n1,0.2\n", r"time is not strictly increasing at row 4"),
        ("x,v\n0,0\n1,0\n", r"column 't' \(time, s\) is required"),
        ("t,x\n0,0\n1,0,5\n", r"cannot read as CSV numbers"),
        ("t,x\n0,abc\n1,0\n", r"cannot read as CSV numbers"),
        ("t,x,x\n0,0,0\n1,0,0\n", r"duplicate column names"),
        ("", r"the first line must be comma-separated column names"),
        ("t,x\n", r"no data rows after the header"),
        ("t,x\n0,0\n", r"needs at least two samples"),
        ("t,,x\n0,0,0\n1,0,0\n", r"the first line must be comma-separated column names"),
        ("t,x,p1\n0,0,1.5\n1,0,2.0\n", r"column 'p1' peaks at 2, which looks like bar"),
        ("t,x\n0,0\n1,150.0\n", r"column 'x' spans 150 m, .*not millimetres"),
    ],
)
def test_bad_csv_names_file_and_problem(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "run.csv"
    path.write_text(text)
    with pytest.raises(FcompError, match=message) as info:
        Measurement.read(path)
    msg = str(info.value)
    assert msg.startswith(str(path)), msg
    assert "\n" not in msg


def test_binary_and_missing_files(tmp_path: Path) -> None:
    path = tmp_path / "bin.csv"
    path.write_bytes(b"t,x\n\x00\xff\xfe\x9c\x80\n")
    with pytest.raises(FcompError, match=f"{path}: cannot read"):
        Measurement.read(path)
    with pytest.raises(FcompError, match="nope.csv: file not found"):
        Measurement.read(tmp_path / "nope.csv")


def test_drop_nan_drops_only_incomplete_rows(tmp_path: Path) -> None:
    (tmp_path / "r.csv").write_text("t,x\n0,0\n1,nan\n2,0.2\n")
    meas = Measurement.read(tmp_path / "r.csv", drop_nan=True)
    assert meas.t.tolist() == [0.0, 2.0]


# ---------------------------------------------------------- bad sidecars
@pytest.mark.parametrize(
    ("toml", "message"),
    [
        ("[rig]\nbore = 25.0\n", r"rig.bore = 25.0 m is implausible.*not millimetres"),
        ("[rig]\nrod = 10\n", r"rig.rod = 10 m is implausible"),
        ("[rig]\nstroke = 300\n", r"rig.stroke = 300 m is implausible"),
        ("[rig]\nbore = 0.02\nrod = 0.03\n", r"rig.rod \(0.03 m\) must be smaller than rig.bore"),
        ("[rig]\nmass = -1\n", r"rig.mass must be a non-negative number"),
        ("[rig]\nmass = \"heavy\"\n", r"rig.mass must be a non-negative number"),
        ("[rig]\norientation = \"sideways\"\n", r"rig.orientation must be one of"),
        ("pressure = \"psi\"\n", r"'pressure' must be 'gauge' or 'absolute'"),
        ("[signals]\nu_unit = \"mA\"\n", r"signals.u_unit must be 'A' or 'V'"),
        ("pressure = \"absolute\"\n", r"column 'p1' has a negative absolute pressure"),
        ("[rig]\nstroke = 0.01\n", r"column 'x' spans 0.1 m"),
        ("rig = 3\n", r"\[rig\] must be a table"),
        ("[rig\nbore = 0.02\n", r"not valid TOML"),
    ],
)
def test_bad_sidecar_names_file_and_problem(tmp_path: Path, toml: str, message: str) -> None:
    csv = tmp_path / "run.csv"
    csv.write_text("t,x,p1\n0,0,-1000\n1,0.1,200000\n")
    (tmp_path / "run.toml").write_text(toml)
    with pytest.raises(FcompError, match=message) as info:
        Measurement.read(csv)
    assert str(info.value).startswith(str(tmp_path / "run.")), str(info.value)


def test_pressure_all_zero_is_a_vented_chamber_not_bar() -> None:
    t = np.arange(4.0)
    meas = Measurement({"t": t, "p2": np.zeros(4), "p1": np.full(4, 3e5)}, {})
    assert meas["p2"].max() == 0.0


# ------------------------------------------------------------- writing
def test_invalid_measurement_writes_nothing(tmp_path: Path) -> None:
    meas = Measurement({"t": [0.0, 1.0, 2.0], "x": [0.0, 0.1, 0.2]}, {"name": "ok"})
    meas.columns["x"][1] = np.nan  # corrupted after construction
    with pytest.raises(FcompError, match="non-finite"):
        meas.write(tmp_path / "out.csv")
    assert list(tmp_path.iterdir()) == []


def test_write_into_a_directory_writes_nothing(tmp_path: Path) -> None:
    (tmp_path / "out.toml").mkdir()
    meas = Measurement({"t": [0.0, 1.0], "x": [0.0, 0.1]}, {})
    with pytest.raises(FcompError, match="is a directory"):
        meas.write(tmp_path / "out.csv")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.toml"]


def test_write_replaces_previous_files_whole(tmp_path: Path) -> None:
    path = tmp_path / "out.csv"
    Measurement({"t": np.arange(100.0), "x": np.zeros(100)}, {}).write(path)
    Measurement({"t": [0.0, 1.0], "v": [1.0, 2.0]}, {}).write(path)
    assert path.read_text() == "t,v\n0.0,1.0\n1.0,2.0\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_sidecar_paths_and_checked_prefix(tmp_path: Path) -> None:
    assert sidecar_paths("a/b") == (Path("a/b.csv"), Path("a/b.toml"))
    with pytest.raises(FcompError, match=r"^source.dat: column 'x' has 1 values, t has 2$"):
        checked({"t": np.array([0.0, 1.0]), "x": np.array([0.0])}, {"name": "n"}, "source.dat")
