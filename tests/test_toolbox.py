"""The engineer's toolbox through its public faces: ``fcomp compare``, ``fcomp import csv``,
``import fcomp`` and the plant-domain comparison.

Every check is against a number computed here independently (the generating law
evaluated by hand, unit factors written out), never against the code's own output.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import fcomp
from fcomp.cli.main import main
from fcomp.measurement import Measurement


def _coulomb_viscous_record(path: Path, Fc: float = 30.0, sigma2: float = 80.0,
                            noise: float = 0.0) -> Measurement:
    """A force-velocity record of ``F = Fc sign(v) + sigma2 v`` (+ white noise), 4 s at 500 Hz."""
    t = np.arange(2000) / 500.0
    x = 0.05 * np.sin(2 * np.pi * 0.5 * t)
    v = 0.05 * 2 * np.pi * 0.5 * np.cos(2 * np.pi * 0.5 * t)
    F = Fc * np.sign(v) + sigma2 * v + noise * np.random.default_rng(3).standard_normal(t.size)
    m = Measurement({"t": t, "x": x, "v": v, "F": F},
                    {"name": path.stem, "kind": "friction-rig", "rig": {"mass": 1.0}})
    m.write(path)
    return m


def test_compare_command_gives_the_contract_json_and_the_right_error(tmp_path: Path) -> None:
    """The generating model compared as given leaves nothing; a wrong one leaves its own error."""
    _coulomb_viscous_record(tmp_path / "rec.csv")
    out = tmp_path / "cmp.json"
    assert main(["compare", str(tmp_path / "rec.csv"), "--friction", "coulomb-viscous",
                 "--set", "Fc=30", "--set", "B=80", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    for key in ("model", "rms", "regimes", "residual_features", "warnings"):
        assert key in doc
    assert doc["model"] == "coulomb-viscous"
    # the exact law: nothing left on a 30 N force (the scored error keeps only the band the
    # velocity's own derivative estimate gives, about 1e-5 N at B = 80 N s/m)
    assert doc["rms"] < 1e-5 * 30.0
    # a Coulomb level 5 N too low: the error is 5 N wherever the rig slides (by hand)
    assert main(["compare", str(tmp_path / "rec.csv"), "--friction", "coulomb-viscous",
                 "--set", "Fc=25", "--set", "B=80", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["regimes"]["sliding"]["rms"] == pytest.approx(5.0, rel=0.02)


def test_compare_fit_judges_held_out_samples_and_reports(tmp_path: Path) -> None:
    _coulomb_viscous_record(tmp_path / "rec.csv", noise=0.5)
    out = tmp_path / "cmp.json"
    assert main(["compare", str(tmp_path / "rec.csv"), "--friction", "coulomb-viscous", "--fit",
                 "--json", str(out), "--report", str(tmp_path / "rep")]) == 0
    doc = json.loads(out.read_text())
    assert doc["fitted"] is True and doc["judged"] == "held-out"
    assert doc["params"]["Fc"] == pytest.approx(30.0, abs=0.3)
    assert doc["params"]["B"] == pytest.approx(80.0, rel=0.05)
    assert doc["rms"] == pytest.approx(0.5, rel=0.15)  # the white noise put in
    assert (tmp_path / "rep" / "report.html").stat().st_size > 10_000


def test_compare_never_writes_onto_its_input(tmp_path: Path, capsys: pytest.CaptureFixture
                                             ) -> None:
    rec = tmp_path / "rec.csv"
    _coulomb_viscous_record(rec)
    before = rec.read_bytes()
    assert main(["compare", str(rec), "--friction", "coulomb", "--json", str(rec)]) == 2
    assert rec.read_bytes() == before
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0]


def test_plant_domain_through_the_public_compare(tmp_path: Path) -> None:
    """``fcomp.compare(..., plant=)``: the plant's own run replayed matches it in x."""
    model = fcomp.make_model("lugre")
    run = fcomp.simulate("pneumatic", model, "sine:amplitude=0.3,frequency=0.5", duration=3.0,
                         rate=500.0)
    comp = fcomp.compare(run, model, plant="pneumatic")
    assert len(comp.plant) == 1 and comp.plant[0].rms["x"] < 1e-9
    assert comp.to_dict()["plant"][run.label]["plant"] == "pneumatic"
    assert isinstance(comp.plant[0], fcomp.PlantComparison)


def test_import_csv_converts_units_signs_and_columns(tmp_path: Path) -> None:
    """ms, mm, bar and a negated force with a decimal comma, converted by hand here."""
    src = tmp_path / "log.csv"
    rows = ["time_ms;pos [mm];force;p_a [bar]"]
    for k in range(50):
        rows.append(f"{k * 2};{10 + k * 0.1:.1f};{-3 - k};{2 + k * 0.01:.2f}".replace(".", ","))
    src.write_text("\n".join(rows) + "\n")
    out = tmp_path / "run.csv"
    assert main(["import", "csv", str(src), "--map",
                 "t=time_ms,x='pos [mm]',F=-force,p1='p_a [bar]'", "--units",
                 "t=ms,x=mm,p1=bar", "--delimiter", ";", "--decimal", ",", "-o", str(out)]) == 0
    m = Measurement.read(out)
    k = np.arange(50)
    np.testing.assert_allclose(m["t"], k * 2e-3)
    np.testing.assert_allclose(m["x"], (10 + k * 0.1) * 1e-3)
    np.testing.assert_allclose(m["F"], 3.0 + k)
    np.testing.assert_allclose(m["p1"], (2 + k * 0.01) * 1e5)


def test_import_csv_names_an_unmapped_column(tmp_path: Path, capsys: pytest.CaptureFixture
                                             ) -> None:
    src = tmp_path / "log.csv"
    src.write_text("time,pos,extra\n0,0,1\n0.001,0.1,2\n")
    out = tmp_path / "run.csv"
    assert main(["import", "csv", str(src), "--map", "t=time,x=pos", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "extra" in err and not out.exists()


def test_python_face_fits_what_the_command_fits(tmp_path: Path) -> None:
    rec = _coulomb_viscous_record(tmp_path / "rec.csv", noise=0.2)
    f = fcomp.fit(rec, "coulomb-viscous")
    assert f.params_["Fc"] == pytest.approx(30.0, abs=0.1)
    assert f.params_["B"] == pytest.approx(80.0, rel=0.02)
    assert fcomp.fit(tmp_path / "rec.csv", "coulomb-viscous").params_["Fc"] == f.params_["Fc"]


def test_dataframe_round_trip_is_lossless_with_units(tmp_path: Path) -> None:
    rec = _coulomb_viscous_record(tmp_path / "rec.csv", noise=0.3)
    df = rec.to_dataframe()
    assert list(df.columns)[0] == "t" and df.attrs["units"]["F"] == "N"
    back = Measurement.from_dataframe(df)
    for k in ("t", "x", "v", "F"):
        assert np.array_equal(back[k], rec[k])  # bit for bit
    assert back.meta["rig"]["mass"] == 1.0


def test_backend_elementary_functions_agree_on_numpy_and_casadi() -> None:
    """Every documented function gives the same number on both backends (and numpy's own)."""
    import casadi as ca

    from fcomp.backend import CASADI, FUNCTIONS, NUMPY

    x, y = 0.37, -1.3
    two = {"copysign", "fmin", "fmax", "power", "hypot", "atan2", "fmod"}
    for name in FUNCTIONS:
        args = (x, y) if name in two else ((1.7,) if name == "acosh" else (x,))
        a = float(getattr(NUMPY, name)(*args))
        sym = [ca.SX.sym(f"a{i}") for i in range(len(args))]
        f = ca.Function("f", sym, [getattr(CASADI, name)(*sym)])
        b = float(f(*args))
        assert a == pytest.approx(b, rel=1e-12, abs=1e-15), name
    assert float(NUMPY.atan2(y, x)) == pytest.approx(np.arctan2(y, x))
    assert float(NUMPY.erf(0.5)) == pytest.approx(0.5204998778130465)  # tabulated


def test_add_and_remove_a_configured_effect_instance() -> None:
    """``add_effect`` takes a configured instance and the error falls; ``remove_effect`` undoes it."""
    from fcomp.effects import make_effect
    from fcomp.synthetic import generate

    rec = generate(["pressure-dependence"], duration=12.0, seed=1).measurement
    d = fcomp.Diagnosis("lugre", search=False, n_jobs=1).fit(rec)
    before = d.rms_final_
    d.add_effect(make_effect("pressure-dependence"))
    assert d.added_ == ["pressure-dependence"] and d.rms_final_ < 0.5 * before
    d.remove_effect("pressure-dependence")
    assert d.added_ == [] and d.rms_final_ == pytest.approx(before, rel=0.05)
    assert "array(" not in repr(d) and len(repr(d)) < 300
    assert "<table" in d._repr_html_()


def test_rich_display_and_short_reprs(tmp_path: Path) -> None:
    rec = _coulomb_viscous_record(tmp_path / "rec.csv", noise=0.2)
    f = fcomp.fit(rec, "coulomb-viscous")
    c = fcomp.compare(rec, f.model_)
    for obj in (f, c):
        assert "array(" not in repr(obj) and len(repr(obj)) < 400
        assert "<table" in obj._repr_html_()


def test_linearize_keeps_the_signal_names() -> None:
    from plants import make_plant

    plant = make_plant("hydraulic", fcomp.make_model("lugre", params="seed002-type1"))
    sys = plant.to_iosys()
    lin = sys.linearize(plant.initial_state({"x": 0.1}), [0.0])
    assert list(lin.state_labels) == list(plant.state_names)
    assert list(lin.input_labels) == list(plant.input_names)
    assert list(lin.output_labels) == list(plant.output_names)


def test_the_packages_carry_their_type_hints() -> None:
    import controllers
    import plants
    import studies

    for pkg in (fcomp, plants, controllers, studies):
        assert (Path(pkg.__file__).parent / "py.typed").exists()


def test_fit_report_draws_the_fit(tmp_path: Path) -> None:
    _coulomb_viscous_record(tmp_path / "rec.csv", noise=0.2)
    rep = tmp_path / "fitrep"
    assert main(["fit", str(tmp_path / "rec.csv"), "--friction", "coulomb-viscous",
                 "--report", str(rep)]) == 0
    html = (rep / "report.html").read_text()
    assert html.count("<img") >= 2 and "Fc" in html
