"""Plausibility checks of fits (``fcomp.identification.plausibility``) on constructed inputs,
and the experiments advised per rig kind (``fcomp.effects.experiment_for``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fcomp.effects import EFFECTS, effect_of_parameter, experiment_for
from fcomp.identification.plausibility import (
    CODES,
    FitWarning,
    RigContext,
    check_fit,
    correlations,
    mass_range,
)
from fcomp.measurement import KINDS

INF = math.inf
BORE = RigContext("pneumatic-cylinder", bore=0.025)


def one(value: float, se: float, *, box: tuple[float, float] = (0.0, INF), name: str = "Fc",
        level: float = 1.96, context: RigContext | None = None) -> list[FitWarning]:
    """The warnings of a fit of the single parameter ``name``."""
    return check_fit({name: value}, {name: se}, {name: (value - level * se, value + level * se)},
                     {name: box}, context=context)


def codes(warnings: list[FitWarning]) -> list[str]:
    return [w.code for w in warnings]


# ------------------------------------------------------------------ at-bound
@pytest.mark.parametrize(("value", "box", "side"), [
    (10.0, (0.0, 10.0), "upper"),                # exactly at the upper bound
    (10.0 - 1e-9, (0.0, 10.0), "upper"),         # within a hair of it
    (1e-16, (0.0, INF), "lower"),                # the solver's "zero"
    (-1.0, (-1.0, 1.0), "lower"),                # a signed parameter at its lower bound
])
def test_at_bound_names_the_bound(value: float, box: tuple[float, float], side: str) -> None:
    (w,) = one(value, 0.5, box=box, name="n")
    assert w.code == "at-bound" and w.parameter == "n"
    assert f"{side} bound {box[0] if side == 'lower' else box[1]:g}" in w.message


@pytest.mark.parametrize("value", [9.99, 0.01, 5.0])
def test_inside_the_box_is_not_at_bound(value: float) -> None:
    assert "at-bound" not in codes(one(value, 1e-3, box=(0.0, 10.0), name="n"))


# ---------------------------------------------------------- interval-crosses-zero
def test_positive_quantity_whose_interval_reaches_zero() -> None:
    (w,) = one(0.44, 0.25)  # [-0.05, 0.93]: the Zillen O-ring LuGre Fc
    assert (w.code, w.parameter) == ("interval-crosses-zero", "Fc")
    assert "[-0.05" in w.message and "95 %" in w.message


def test_interval_clear_of_zero_or_signed_quantity_is_fine() -> None:
    assert one(0.44, 0.1) == []                              # [0.24, 0.64]
    assert one(0.1, 0.2, box=(-INF, INF), name="offset") == []  # an offset may be zero


# --------------------------------------------------------------- not-identified
def test_infinite_standard_error_is_not_identified_with_the_experiment() -> None:
    ctx = RigContext("electromechanical-axis")
    (w,) = one(9.06, INF, box=(0.0, 10.0), name="n", context=ctx)
    assert (w.code, w.parameter) == ("not-identified", "n")
    assert "held at 9.06" in w.message
    assert experiment_for("stribeck", ctx.kind) in w.message


def test_huge_relative_error_is_not_identified_moderate_is_not() -> None:
    assert codes(one(1.0, 20.0, name="sigma1")) == ["not-identified"]
    assert codes(one(1.0, 2.0, name="sigma1")) == ["interval-crosses-zero"]  # 2x: not huge


def test_parameters_that_trade_off() -> None:
    values = {"Fc": 2.0, "B": 30.0, "offset": -3.0}
    se = {"Fc": 0.1, "B": 1.0, "offset": 0.1}
    ci = {k: (v - 2 * se[k], v + 2 * se[k]) for k, v in values.items()}
    box = {"Fc": (0.0, INF), "B": (0.0, INF), "offset": (-INF, INF)}
    corr = {("Fc", "B"): -0.995, ("Fc", "offset"): 0.98, ("B", "offset"): 0.0}
    (w,) = check_fit(values, se, ci, box, corr)
    assert (w.code, w.parameter) == ("not-identified", "Fc,B")
    assert "Fc and B" in w.message and "-0.9950" in w.message
    assert check_fit(values, se, ci, box, {("Fc", "B"): 0.98}) == []


def test_a_held_parameter_is_not_also_reported_for_its_correlations() -> None:
    values, se = {"n": 10.0, "vs": 0.01}, {"n": 0.7, "vs": 1e-4}
    ci = {k: (v - 2 * se[k], v + 2 * se[k]) for k, v in values.items()}
    box = {"n": (0.0, 10.0), "vs": (0.0, INF)}
    found = check_fit(values, se, ci, box, {("n", "vs"): 0.999})
    assert codes(found) == ["at-bound"]


def test_correlations_from_a_covariance() -> None:
    cov = np.array([[4.0, -3.96, 0.0], [-3.96, 4.0, 0.0], [0.0, 0.0, INF]])
    pairs = correlations(["a", "b", "c"], cov)
    assert pairs == {("a", "b"): pytest.approx(-0.99)}  # c has no finite variance


# ------------------------------------------------------------- mass-implausible
def test_mass_range_rule_numbers() -> None:
    low, high, basis = mass_range(BORE)
    assert low == pytest.approx(0.5 * 2700 * math.pi / 4 * 0.025**2 * 0.005)  # 3.3 g
    assert high == pytest.approx(1000 * 7850 * math.pi / 4 * 0.025**3)        # 96 kg
    assert "25 mm bore" in basis
    rod = RigContext(bore=0.03, rod=0.016, stroke=0.3)
    low2, high2, _ = mass_range(rod)
    assert low2 == pytest.approx(0.5 * 2700 * math.pi / 4 * (0.03**2 * 0.006 + 0.016**2 * 0.3))
    assert high2 > 118.0  # seed 002's hydraulic servo: 118 kg on this geometry is plausible
    assert mass_range(RigContext()) == (1e-3, 1e5, "any moving part of a rig")


@pytest.mark.parametrize(("mass", "context", "flagged"), [
    (4e-16, BORE, "below"),                       # the Zillen coulomb-viscous fit
    (0.5, BORE, None),
    (500.0, BORE, "above"),
    (1e-4, RigContext("electromechanical-axis"), "below"),
    (94.8, RigContext("electromechanical-axis"), None),   # the EMPS carriage
    (2e5, RigContext(), "above"),
    (5.0, RigContext(mass=2.0), "times"),         # off the sidecar's rig.mass by 2.5
    (3.0, RigContext(mass=2.0), None),
])
def test_fitted_mass(mass: float, context: RigContext, flagged: str | None) -> None:
    found = [w for w in one(mass, 0.1 * mass, box=(-INF, INF), name="mass", context=context)
             if w.code == "mass-implausible"]
    if flagged is None:
        assert found == []
    else:
        assert len(found) == 1 and flagged in found[0].message and found[0].parameter == "mass"


def test_mass_error_against_the_sidecar_mass() -> None:
    found = one(-1.5, 0.1, box=(-INF, INF), name="dm", context=RigContext(mass=2.0))
    assert codes(found) == ["mass-implausible"] and "0.5 kg" in found[0].message
    assert one(0.2, 0.1, box=(-INF, INF), name="dm", context=RigContext(mass=2.0)) == []


# --------------------------------------------------------------- not-converged
def test_not_converged_is_reported_once_first() -> None:
    found = check_fit({"Fc": 0.44}, {"Fc": 0.25}, {"Fc": (-0.05, 0.93)}, {"Fc": (0.0, INF)},
                      converged=False, message="budget exhausted")
    assert codes(found) == ["not-converged", "interval-crosses-zero"]
    assert found[0].parameter is None and "budget exhausted" in found[0].message
    assert "not-converged" not in codes(check_fit({}, {}, {}, {}, converged=True))


def test_codes_and_json_shape() -> None:
    assert set(CODES) == {"at-bound", "interval-crosses-zero", "mass-implausible",
                          "not-identified", "not-converged"}
    assert FitWarning("at-bound", "n", "m").to_dict() == {"code": "at-bound", "parameter": "n",
                                                          "message": "m"}


def test_context_from_a_sidecar() -> None:
    meta = {"kind": "pneumatic-cylinder", "rig": {"bore": 0.025, "mass": 0.6}}
    assert RigContext.from_meta(meta) == RigContext("pneumatic-cylinder", 0.6, 0.025)
    assert RigContext.from_meta(meta, mass=1.0).mass == 1.0
    assert RigContext.from_meta({}) == RigContext()


# ------------------------------------------------------------ advice per rig kind
def test_every_kind_named_by_an_effect_is_a_sidecar_kind() -> None:
    for name in EFFECTS.names():
        cls = EFFECTS.get(name)
        assert set(cls.experiments) <= set(KINDS), name
        assert cls.experiment_for("") == cls.experiment == experiment_for(name)


@pytest.mark.parametrize("kind", ["electromechanical-axis", "friction-rig"])
def test_no_chambers_on_rigs_without_them(kind: str) -> None:
    for name in EFFECTS.names():
        text = experiment_for(name, kind).lower()
        assert "chamber" not in text and "vent" not in text, (name, text)
        assert "extending" not in text and "retracting" not in text, (name, text)


def test_cylinders_keep_their_own_advice() -> None:
    assert "chambers vented" in experiment_for("force-offset", "pneumatic-cylinder")
    assert "relieved to tank" in experiment_for("force-offset", "hydraulic-cylinder")
    assert "drive disabled" in experiment_for("force-offset", "electromechanical-axis")


@pytest.mark.parametrize(("name", "effect"), [
    ("Fc", None), ("Fs_pos", "stribeck"), ("n", "stribeck"), ("sigma0", "presliding"),
    ("B", "viscous"), ("sigma2", "viscous"), ("vb", "frictional-lag"), ("T", "viscous-lead"),
    ("mass", "inertia-error"), ("offset", "force-offset"), ("kp", "pressure-dependence"),
])
def test_effect_of_parameter(name: str, effect: str | None) -> None:
    assert effect_of_parameter(name) == effect
