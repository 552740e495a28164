"""Plausibility flags found on real records: a fitted mass far above what the cylinder's
piston, rod and carriage weigh (34, 3.9 and 1.87 kg on a 25 mm pneumatic piston), a mass
of effectively zero, and a held channel lag at its +-20 ms bound or negative (the force
leading the motion)."""

from __future__ import annotations

import math

import pytest

from fcomp.identification.plausibility import (
    LEAD_SAMPLES,
    LOAD_FACTOR,
    RigContext,
    check_fit,
    check_held,
    steel_piston_mass,
)

INF = math.inf
BORE25 = RigContext("pneumatic-cylinder", bore=0.025)
SERVO = RigContext("hydraulic-cylinder", bore=0.03, rod=0.016, stroke=0.3)
LAG_BOX = {"lag": (-0.02, 0.02)}


def mass_flags(mass: float, context: RigContext) -> list[str]:
    """The ``mass-implausible`` messages of a fit of ``mass`` alone (box ``[0, inf)``)."""
    found = check_fit({"mass": mass}, {"mass": 0.05 * mass}, {"mass": (0.9 * mass, 1.1 * mass)},
                      {"mass": (0.0, INF)}, context=context)
    return [w.message for w in found if w.code == "mass-implausible" and w.parameter == "mass"]


# ----------------------------------------------------------- the steel piston
def test_steel_piston_mass_numbers() -> None:
    assert steel_piston_mass(BORE25) == pytest.approx(7850 * math.pi / 4 * 0.025**3)  # 96 g
    assert steel_piston_mass(SERVO) == pytest.approx(
        7850 * math.pi / 4 * (0.03**2 * 0.03 + 0.016**2 * 0.3))                     # 0.64 kg
    assert steel_piston_mass(RigContext("electromechanical-axis")) is None
    assert LOAD_FACTOR == 10.0


# ----------------------------------------------------------- too heavy
@pytest.mark.parametrize("mass", [34.0, 3.9, 1.87])
def test_masses_fitted_on_a_25_mm_piston_are_flagged(mass: float) -> None:
    (message,) = mass_flags(mass, BORE25)
    assert f"{mass:.4g} kg" in message                   # the value
    assert "0.963 kg" in message and "steel" in message  # the bound and why
    assert "25 mm bore" in message
    assert "rig.mass" in message and "--mass" in message  # what to do


@pytest.mark.parametrize("mass", [0.3, 0.05, 0.9])
def test_a_piston_sized_mass_is_not_flagged(mass: float) -> None:
    assert mass_flags(mass, BORE25) == []


def test_a_stated_mass_decides() -> None:
    stated = RigContext("pneumatic-cylinder", mass=95.0, bore=0.025)
    assert mass_flags(95.0, stated) == []        # heavy, but the sidecar says so
    assert mass_flags(60.0, stated) == []        # within [0.5, 2] times
    (message,) = mass_flags(34.0, stated)        # below half of it
    assert "rig.mass 95 kg" in message
    assert len(mass_flags(200.0, stated)) == 1   # above twice


def test_a_heavy_load_must_be_stated() -> None:
    # seed 002's servo carries 118 kg: plausible when stated, flagged when only fitted
    assert mass_flags(118.0, RigContext("hydraulic-cylinder", mass=118.0, bore=0.03, rod=0.016,
                                        stroke=0.3)) == []
    (message,) = mass_flags(118.0, SERVO)
    assert "not stated" in message and "6.4 kg" in message
    assert mass_flags(5.0, SERVO) == []


def test_without_a_bore_only_the_wide_range_applies() -> None:
    assert mass_flags(34.0, RigContext("electromechanical-axis")) == []
    assert mass_flags(94.8, RigContext("friction-rig")) == []


# ----------------------------------------------------------- effectively zero
@pytest.mark.parametrize("mass", [5e-13, 1e-6])
def test_a_vanishing_mass_is_not_determined(mass: float) -> None:
    (message,) = mass_flags(mass, BORE25)
    assert "does not determine the moving mass" in message


# ----------------------------------------------------------- held channel lag
def test_lag_at_its_negative_bound() -> None:
    found = check_held({"lag": -0.02}, LAG_BOX, units={"lag": "s"}, dt=1e-3)
    assert [(w.code, w.parameter) for w in found] == [("at-bound", "lag"),
                                                      ("lag-negative", "lag")]
    assert "lower bound -0.02 s" in found[0].message
    assert "leads the motion" in found[1].message and "timing offset" in found[1].message


def test_lag_at_its_positive_bound_is_at_bound_only() -> None:
    found = check_held({"lag": 0.02}, LAG_BOX, units={"lag": "s"}, dt=1e-3)
    assert [w.code for w in found] == ["at-bound"]
    assert "upper bound 0.02 s" in found[0].message


def test_lag_inside_its_box() -> None:
    assert check_held({"lag": 0.0015}, LAG_BOX, dt=1e-3) == []          # a transducer lag
    assert check_held({"lag": -0.5e-3}, LAG_BOX, dt=1e-3) == []         # within a sample
    found = check_held({"lag": -(LEAD_SAMPLES + 2) * 1e-3}, LAG_BOX, dt=1e-3)
    assert [w.code for w in found] == ["lag-negative"]


def test_refit_checks_the_held_lag() -> None:
    from fcomp.diagnosis.data import prepare
    from fcomp.diagnosis.refit import Refit
    from fcomp.diagnosis.regimes import segment
    from fcomp.diagnosis.split import make_split
    from fcomp.models import make_model
    from fcomp.synthetic import generate

    data = prepare(generate(style="pressures", experiments=2, duration=4.0, seed=1).measurement)
    assert data.fits_lag
    seg = segment(data)
    refit = Refit(data, make_split(data, seg.valid), seg.d_pre)
    model = make_model("coulomb-viscous").with_params(Fc=20.0, B=50.0)
    values = {"Fc": 20.0, "B": 50.0}

    refit.hold("lag", -0.02)
    found = [w for w in refit.plausibility(refit.result(model, values, 2), data.rig)
             if w.parameter == "lag"]
    assert [w.code for w in found] == ["at-bound", "lag-negative"]

    refit.hold("lag", 0.001)
    assert [w for w in refit.plausibility(refit.result(model, values, 2), data.rig)
            if w.parameter == "lag"] == []


def test_a_held_mass_of_zero_is_flagged() -> None:
    """Circle and KDN (Zillen pneumatic rigs): the mass went to 5.7e-28 and 8.8e-11 kg in
    the first fit and was then held; the held value is judged as a fitted one."""
    found = check_held({"mass": 5.7e-28}, {"mass": (0.0, 100.0)}, units={"mass": "kg"},
                       context=BORE25)
    codes = [w.code for w in found]
    assert "mass-implausible" in codes
    assert check_held({"mass": 0.05}, {"mass": (0.0, 100.0)}, context=BORE25) == []
