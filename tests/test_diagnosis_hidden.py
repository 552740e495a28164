"""The diagnosis on synthetic rig records with hidden effects (issue 5, point 6).

Every record comes from :mod:`fcomp.synthetic`, whose truth is integrated by
its own code (never the package's models) and whose laws differ in form from
the catalogue's where the physics allows (Armstrong exponent 1.4 for the
Stribeck hump, Hess-Soom lag, a Kato dwell law on the measured dwell time,
a lip-seal pressure law, a Gaussian bump plus slope along the stroke...).
The tool gets only the measurement -- quantised position, pressures and a
force with coloured noise -- and must name the hidden effect, make the
held-out error fall to about the noise floor and say ``explained``; with
nothing hidden it must add nothing, and with an effect outside the
catalogue it must say ``unexplained-structure``.

Effects that only show at break-aways, at low speeds or during accelerations (dwell time,
Stribeck curve, frictional lag) get longer records: a third of a 12 s record held out holds
one or two break-aways, too few to judge anything on.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from fcomp.diagnosis import Diagnosis
from fcomp.diagnosis.features import trimmed_rms
from fcomp.diagnosis.scoring import score_noise_share
from fcomp.synthetic import generate

pytestmark = pytest.mark.slow  # builds the study site or runs long diagnoses

NOISE_STD = 0.4  # N, the generator's default force noise

#: case -> (hidden effects, generator base law, baseline model, duration s)
CASES: dict[str, tuple[tuple[str, ...], str, str, float]] = {
    "viscous": (("viscous",), "coulomb", "coulomb", 12.0),
    "stribeck": (("stribeck",), "coulomb-viscous", "coulomb-viscous", 24.0),
    "presliding": (("presliding",), "stribeck", "stribeck", 12.0),
    "frictional-lag": (("frictional-lag",), "lugre", "lugre", 40.0),
    "dwell-time": (("dwell-time",), "lugre", "lugre", 40.0),
    "direction-asymmetry": (("direction-asymmetry",), "lugre", "lugre", 12.0),
    "pressure-dependence": (("pressure-dependence",), "lugre", "lugre", 12.0),
    "position-dependence": (("position-dependence",), "lugre", "lugre", 12.0),
    "viscous-lead": (("viscous-lead",), "lugre", "lugre", 12.0),
    "inertia-error": (("inertia-error",), "lugre", "lugre", 12.0),
    "force-offset": (("force-offset",), "lugre", "lugre", 12.0),
    "two-effects": (("pressure-dependence", "direction-asymmetry"), "lugre", "lugre", 12.0),
    "nothing": ((), "lugre", "lugre", 12.0),
    "ripple": (("ripple",), "lugre", "lugre", 12.0),
}

#: Effects that are the same force in another guise on these records: both
#: add a term proportional to the acceleration (sigma2*T*a and dm*a).
CONFOUNDED = {"viscous-lead": {"inertia-error"}, "inertia-error": {"viscous-lead"}}


@cache
def diagnosed(case: str) -> Diagnosis:
    hidden, base, baseline, duration = CASES[case]
    rec = generate(list(hidden), base=base, duration=duration, seed=1)
    # the baseline check (a second diagnosis from a static baseline) decides neither what is
    # added nor the verdict: it is tested in test_diagnosis_parts and on the real records
    return Diagnosis(baseline, n_jobs=2, check_baseline=False).fit(rec.measurement)


def _named(d: Diagnosis, effect: str) -> bool:
    """The effect was added, or ties with an added one (a confounded group)."""
    if effect in d.added_:
        return True
    return any(effect in tie and set(tie) & set(d.added_) for tie in d.ties_)


SINGLE = [c for c in CASES if c not in ("two-effects", "nothing", "ripple")]


@pytest.mark.parametrize("case", SINGLE)
def test_a_hidden_effect_is_named_and_the_error_falls_to_the_noise(case: str) -> None:
    d = diagnosed(case)
    (effect,) = CASES[case][0]
    assert _named(d, effect), (d.added_, d.ties_, [(c.effect, c.reason) for c in d.candidates_])
    # nothing else is added, except an effect confounded with the hidden one
    assert set(d.added_) <= {effect} | CONFOUNDED.get(effect, set()), d.added_
    assert d.verdict_ == "explained", [(f.feature, f.strength) for f in d.residual_features_]
    test = d.split_.test
    before, after = d.baseline_fit_.residual[test], d.fit_.residual[test]
    # the error falls: by a clear margin over the whole held-out record (an effect
    # acting only at break-aways or reversals moves the total less) ...
    assert d.rms_final_ < d.rms_baseline_ - 0.1 * d.noise_floor_.value
    assert trimmed_rms(after) < 0.85 * trimmed_rms(before)
    # at the noise floor, but for isolated one-sample spikes where a static law
    # jumps by its full level at a start or stop the derived velocity places a
    # sample early or late (the generator's static bases are discontinuous at v = 0)
    assert trimmed_rms(after) < 1.6 * d.noise_floor_.value
    assert d.steps_[0].accepted and d.steps_[0].rms_after < d.steps_[0].rms_before


@pytest.mark.parametrize("case", ["viscous", "pressure-dependence", "dwell-time"])
def test_noise_floor_is_estimated_from_the_data(case: str) -> None:
    """The generator's force noise is 0.4 N (AR(1), 5 ms); the floor is estimated, not assumed."""
    assert 0.75 * NOISE_STD < diagnosed(case).noise_floor_.value < 1.3 * NOISE_STD


def test_two_hidden_effects_are_both_found() -> None:
    d = diagnosed("two-effects")
    assert set(d.added_) == {"pressure-dependence", "direction-asymmetry"}
    assert d.verdict_ == "explained"
    falls = [s.rms_before - s.rms_after for s in d.steps_ if s.accepted]
    assert len(falls) == 2 and all(f > 0 for f in falls)
    # the error falls by more than 85 %: on the plain held-out residual y - F_hat, whose floor
    # is the noise (the split holds out every experiment's blocks, so the baseline is fitted
    # at every pressure level and its error is 2.7 N, not the 6.6 N of a split by the whole
    # record; the deciding score of even the right model is above the noise where its
    # prediction is known only within its timing band, 0.50 N here for a 0.40 N floor,
    # so 15 % of 2.7 N in that score would ask for less than the truth scores) ...
    test = d.split_.test
    plain_base = float(np.sqrt(np.mean(d.baseline_fit_.plain_residual[test] ** 2)))
    plain_final = float(np.sqrt(np.mean(d.fit_.plain_residual[test] ** 2)))
    assert plain_final < 0.15 * plain_base, (plain_final, plain_base)
    # ... and the deciding error is what the right model scores with the final model's
    # timing band and the noise floor (:func:`fcomp.diagnosis.scoring.score_noise_share`)
    floor = d.noise_floor_.value
    right = floor * np.sqrt(score_noise_share(d.fit_.timing_spread[test], floor))
    assert d.rms_final_ < 1.1 * right, (d.rms_final_, right)


def test_nothing_hidden_adds_nothing() -> None:
    d = diagnosed("nothing")
    assert d.added_ == []
    assert d.verdict_ == "explained"
    assert d.rms_final_ == d.rms_baseline_ < 1.3 * d.noise_floor_.value
    assert not any(s.accepted for s in d.steps_)


def test_an_effect_outside_the_catalogue_is_unexplained_structure() -> None:
    """A rod scratch (friction ripple of 3 mm wavelength along x): no entry explains it."""
    d = diagnosed("ripple")
    assert d.verdict_ == "unexplained-structure"
    assert d.rms_final_ > 2.0 * d.noise_floor_.value
    # it does not pass the least-bad wrong effect off as the explanation
    assert d.added_ == [], d.added_
