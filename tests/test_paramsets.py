"""Named parameter sets carried in the package, with their sources (models.md section 4).

The expected numbers below are typed in from the sources themselves
(Canudas de Wit et al. 1995 Table I; seed 000 Tables 1-4; seed 002 Table 2),
so a wrong copy in ``fcomp/data/paramsets/*.toml`` or a wrong reading of it
fails here. SI units.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path

import pytest

import fcomp.paramsets as paramsets
from fcomp.errors import UnknownNameError
from fcomp.models import make_model
from fcomp.models.lugre_family import PRESETS
from fcomp.parameters import Directional

CONTRACT = ["canudas1995", "seed000-cylinder1", "seed000-cylinder2", "seed000-cylinder3",
            "seed000-servo", "seed002-type1"]

#: seed 000 Table 4: (v > 0, v < 0) magnitudes per cylinder, then sigma0, sigma1, tau_hp,
#: tau_hn (printed tau_hm), tau_h0, T
TABLE4 = {
    "1": {"Fs": (22.5, 25.0), "Fc": (5.5, 5.8), "vs": (0.01, 0.055), "vb": (0.037, 0.025),
          "n": (2.5, 1.2), "sigma2": (25.0, 25.0), "sigma0": 1.5e4, "sigma1": 0.1,
          "tau_hp": 0.02, "tau_hn": 0.15, "tau_h0": 20.0, "T": 0.0},
    "2": {"Fs": (25.0, 27.0), "Fc": (6.2, 6.0), "vs": (0.07, 0.07), "vb": (0.037, 0.025),
          "n": (2.5, 2.5), "sigma2": (26.0, 26.0), "sigma0": 1.62e4, "sigma1": 0.1,
          "tau_hp": 0.012, "tau_hn": 0.14, "tau_h0": 22.0, "T": 0.0},
    "3": {"Fs": (32.0, 28.5), "Fc": (7.3, 6.8), "vs": (0.045, 0.052), "vb": (0.037, 0.025),
          "n": (2.7, 2.8), "sigma2": (30.0, 30.0), "sigma0": 1.8e4, "sigma1": 0.1,
          "tau_hp": 0.025, "tau_hn": 0.12, "tau_h0": 25.0, "T": 0.0},
}
#: seed 000 Table 1: bore, rod, stroke (m)
TABLE1 = {"1": (0.025, 0.010, 0.300), "2": (0.040, 0.016, 0.200), "3": (0.063, 0.020, 0.200)}


def test_the_sets_of_the_public_contract_and_only_those() -> None:
    assert paramsets.names() == sorted(CONTRACT)


@pytest.mark.parametrize("name", CONTRACT)
def test_every_set_loads_with_its_source(name: str) -> None:
    pset = paramsets.get(name)
    assert pset.name == name
    assert pset.source and ("seed" in pset.source or "Canudas" in pset.source)
    assert pset.friction and all(pset.friction.values())
    assert pset.rig.get("mass", 0) > 0


@pytest.mark.parametrize("name", CONTRACT)
@pytest.mark.parametrize("model", list(PRESETS))
def test_every_family_model_builds_from_every_set(name: str, model: str) -> None:
    m = make_model(model, params=name)
    pset = paramsets.get(name)
    section = pset.friction_section(model)
    for key, value in m.params.flat().items():
        base = key.removesuffix("_pos").removesuffix("_neg")
        if base not in section:
            if model == "coulomb-viscous" and base == "B":
                base = "sigma2"  # the viscous coefficient of the set
            else:
                continue  # the model's default (e.g. v_eps)
        given = section[base]
        want = (given.pos if key.endswith("_pos") else given.neg) \
            if isinstance(given, Directional) else float(given)
        assert value == pytest.approx(want, rel=1e-15), (model, key)


def test_canudas1995_is_table_one() -> None:
    m = make_model("lugre", params="canudas1995")
    want = {"sigma0": 1e5, "sigma1": math.sqrt(1e5), "sigma2": 0.4, "Fc": 1.0, "Fs": 1.5,
            "vs": 1e-3, "n": 2.0}
    for k, v in want.items():
        assert m.flat_params()[k] == pytest.approx(v, rel=1e-9), k
    assert paramsets.get("canudas1995").rig["mass"] == 1.0


@pytest.mark.parametrize("cyl", ["1", "2", "3"])
def test_seed000_cylinders_are_tables_one_and_four(cyl: str) -> None:
    name = f"seed000-cylinder{cyl}"
    m = make_model("nmlgm", params=name)
    flat = m.flat_params()
    for k, v in TABLE4[cyl].items():
        if isinstance(v, tuple):
            assert (flat[f"{k}_pos"], flat[f"{k}_neg"]) == pytest.approx(v, rel=1e-15), k
        else:
            assert flat[k] == pytest.approx(v, rel=1e-15), k
    rig = paramsets.get(name).rig
    assert (rig["bore"], rig["rod"], rig["stroke"]) == pytest.approx(TABLE1[cyl])


def test_seed000_servo_is_cylinder_one() -> None:
    a, b = make_model("nmlgm", params="seed000-servo"), make_model("nmlgm", "seed000-cylinder1")
    assert a.flat_params() == b.flat_params()


def test_seed000_hysteresis_tables_two_and_three_in_metres() -> None:
    """Table 2 boundaries read as metres (documented in fcomp.paramsets), Table 3 as printed."""
    assert "METRES" in (paramsets.__doc__ or "").upper()
    h = paramsets.get("seed000-cylinder1").hysteresis
    assert h["z1"] == pytest.approx(1.25e-4) and h["z5"] == pytest.approx(2.29e-4)
    assert h["internal_zc"] == pytest.approx(2.46e-4)
    assert (h["c1"], h["k1"], h["c8"], h["k8"]) == pytest.approx((2.0, 3.0e5, 4.05, 1.8e5))
    # the boundaries lie below the sliding threshold Fs/sigma0 = 1.5 mm
    assert max(v for k, v in h.items() if k.startswith(("z", "internal"))) < 22.5 / 1.5e4


def test_seed002_type1_is_table_two() -> None:
    raw = paramsets.get("seed002-type1").raw
    v = raw["servo_valve"]
    assert (v["kv"], v["omega_v"], v["zeta_v"], v["cd"], v["w"], v["underlap"]) == pytest.approx(
        (0.0227, 440.0, 0.75, 0.32, 0.0228, 4e-5))
    assert (raw["fluid"]["beta"], raw["fluid"]["rho"]) == pytest.approx((1e8, 862.0))
    assert (raw["cylinder"]["V10"], raw["cylinder"]["V20"]) == pytest.approx((5e-6, 5e-6))
    # three friction sections, one per model of the seed's comparison
    assert make_model("stribeck", params="seed002-type1").flat_params()["vb"] == 0.03
    assert make_model("lugre", params="seed002-type1").flat_params()["sigma0"] == 2e6
    assert make_model("nmlgm", params="seed002-type1").flat_params()["T"] == 0.005


def test_sets_are_read_from_the_package_not_the_project_tree() -> None:
    folder = resources.files("fcomp.data.paramsets")
    for filename in set(paramsets._FILES.values()):
        assert folder.joinpath(filename).is_file(), filename
    source = Path(paramsets.__file__).read_text()
    assert "/work/shared" not in source


def test_unknown_set_is_a_clear_error() -> None:
    with pytest.raises(UnknownNameError, match=r"unknown parameter set 'seed000'; known: .*"
                                               r"seed000-cylinder1"):
        paramsets.get("seed000")
    with pytest.raises(UnknownNameError, match="unknown parameter set"):
        make_model("nmlgm", params="seed003")
