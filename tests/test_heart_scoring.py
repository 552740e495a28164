"""The diagnosis's error measure cannot be gamed, files are experiments (never a clock), and
the JSON says everything (issue 24, item 0): unit tests against independent computations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from fcomp.diagnosis.data import prepare, sessions
from fcomp.diagnosis.result import same_findings as _same_findings
from fcomp.diagnosis.scoring import (
    prediction_band,
    sample_weights,
    scored_residual,
    tolerant_residual,
)
from fcomp.measurement import Measurement


def _log_score_residual(y: float, lo: float, hi: float, sigma: float) -> float:
    """Independent: the predictive density by quadrature, then the definition."""
    if hi - lo <= 0:
        p = stats.norm.pdf(y, lo, sigma)
    else:
        pts = [y] if lo < y < hi else None
        p = integrate.quad(lambda c: stats.norm.pdf(y, c, sigma), lo, hi, points=pts,
                           epsabs=0.0, epsrel=1e-12, limit=200)[0] / (hi - lo)
    return math.sqrt(-2.0 * sigma**2 * math.log(p * sigma * math.sqrt(2.0 * math.pi)))


def test_a_point_band_scores_the_plain_residual() -> None:
    y = np.array([0.0, 1.0, -5.0, 40.0, 1e-9])
    F = np.array([0.2, 0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(scored_residual(y, F, F, F, 1.3), y - F, rtol=1e-12, atol=0)


@pytest.mark.parametrize("y,lo,hi", [(0.5, -2.0, 3.0), (5.0, -2.0, 3.0), (-30.0, -2.0, 3.0),
                                     (0.4, -1e-3, 1e-3), (2.9, -2.0, 3.0), (33.0, 0.0, 27.0)])
def test_the_score_is_the_log_score_of_the_band_by_quadrature(y: float, lo: float,
                                                              hi: float) -> None:
    sigma = 1.3
    e = scored_residual(np.array([y]), np.array([0.5 * (lo + hi)]), np.array([lo]),
                        np.array([hi]), sigma)[0]
    assert abs(e) == pytest.approx(_log_score_residual(y, lo, hi, sigma), rel=1e-7)


def test_a_wider_band_never_scores_better_in_expectation() -> None:
    """The log score is proper: for a measurement drawn around c, any band around c
    scores worse on average the wider it is (Monte Carlo over the noise)."""
    rng = np.random.default_rng(0)
    sigma, c = 1.57, 20.0
    y = c + sigma * rng.standard_normal(40_000)
    means = []
    for width in (0.0, 0.5, 2.0, 8.0, 27.0):
        lo, hi = np.full(y.size, c - width / 2), np.full(y.size, c + width / 2)
        e = scored_residual(y, np.full(y.size, c), lo, hi, sigma)
        means.append(float(np.mean(e**2)))
    assert means[0] == pytest.approx(sigma**2, rel=0.02)
    assert all(b > a for a, b in zip(means, means[1:], strict=False)), means
    # the tolerant residual of the same bands falls with the width: it could be gamed
    tol = [float(np.mean(tolerant_residual(y, np.full(y.size, c - w / 2),
                                           np.full(y.size, c + w / 2), [0])[0] ** 2))
           for w in (0.0, 2.0, 27.0)]
    assert tol[2] < tol[1] < tol[0]


def test_sample_weights_follow_the_band_and_stay_finite_on_a_zero_floor() -> None:
    """``w = 1/(1 + (spread/(2 sigma))^2)``: 1 where the band has no width, 1/2 where it is
    two noise floors wide, and finite with a noise floor of zero (exact steady-state
    points)."""
    np.testing.assert_allclose(sample_weights(np.array([0.0, 2.0, 4.0]), 1.0),
                               [1.0, 0.5, 0.2])
    z = sample_weights(np.array([0.0, 1.0]), 0.0)
    assert np.all(np.isfinite(z)) and z[0] == 1.0 and z[1] < 1e-100


def test_the_timing_band_widens_by_the_window_within_an_experiment_only() -> None:
    lo = np.array([0.0, 0.0, 10.0, 0.0, 0.0, 0.0])
    low, high = prediction_band(lo, lo, [0, 3], np.array([1, 1, 1, 1, 1, 1]))
    np.testing.assert_array_equal(high, [0.0, 10.0, 10.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(low, 0.0)


def _record(name: str, t0: float, n: int = 400, seed: int = 0) -> Measurement:
    rng = np.random.default_rng(seed)
    t = t0 + 1e-3 * np.arange(n)
    x = 0.01 * np.sin(2 * np.pi * 2.0 * (t - t0))
    v = np.gradient(x, t)
    F = 5.0 * np.tanh(v / 1e-3) + 0.05 * rng.standard_normal(n)
    return Measurement({"t": t, "x": x, "F": F}, {"name": name})


def test_files_are_experiments_in_any_order_and_stamps_make_the_clock() -> None:
    a, b, c = _record("a", 0.0, seed=1), _record("b", 0.0, seed=2), _record("c", 0.0, seed=3)
    one = prepare([a, b, c])
    two = prepare([c, a, b])
    np.testing.assert_array_equal(one.y, two.y)
    # ordered by their content, not their names or the order given (issue 43)
    assert one.labels == two.labels and sorted(one.labels) == ["a", "b", "c"]
    # files that each start at zero are sessions of their own
    assert sorted(map(sorted, sessions(one))) == [[0], [1], [2]]
    # a logger whose clock runs on: one session, in the stamps' order, whatever the names
    late, early = _record("a-late", 10.0, seed=4), _record("z-early", 0.0, seed=5)
    d = prepare([late, early])
    groups = sessions(d)
    assert len(groups) == 1
    t = d.signal("t")
    assert [float(t[d.experiments[i].start]) for i in groups[0]] == [0.0, 10.0]


def test_baseline_dependence_needs_different_findings_not_a_one_sided_tie() -> None:
    f = frozenset
    mine = f({f({"pressure-dependence", "position-dependence"})})
    theirs = f({f({"pressure-dependence"})})
    assert _same_findings(mine, theirs)
    assert not _same_findings(mine, f({f({"direction-asymmetry"})}))
    assert not _same_findings(theirs, f({f({"pressure-dependence"}), f({"dwell-time"})}))
    assert _same_findings(f(), f())


def test_far_outside_the_band_the_score_is_the_distance_to_the_band() -> None:
    """40 noise floors beyond the band's edge the quadrature underflows; the score tends to
    the distance to the edge (the Gaussian tail dominates the log density)."""
    sigma = 1.3
    e = scored_residual(np.array([80.0]), np.array([13.5]), np.array([0.0]), np.array([27.0]),
                        sigma)[0]
    d = 80.0 - 27.0
    # -ln p = d^2/(2 sigma^2) + ln(d/sigma) + ln(27/sigma) ... to first order: e ~ d
    assert e == pytest.approx(d, rel=0.05) and e > d
