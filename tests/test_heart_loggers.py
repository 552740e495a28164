"""Loggers the diagnosis was not built on (issue 41): bursts, jitter, lost samples, pauses.

A logger's stamps are taken as they are; what the diagnosis derives from them -- the
sampling interval, where a pause starts a new experiment, how a pause is bridged -- is
checked here against designed stamps and motions whose answer is known, and against
the generator's loggers.
"""

from __future__ import annotations

import numpy as np
import pytest

from fcomp.diagnosis.data import GAP_FACTOR, prepare
from fcomp.diagnosis.pauses import bridge, kind
from fcomp.measurement import Measurement
from fcomp.reconstruction import sampling_interval
from fcomp.synthetic import STAMPS, generate


def test_the_sampling_interval_of_uniform_alternating_and_paused_stamps_is_the_median() -> None:
    rng = np.random.default_rng(1)
    uniform = np.arange(10_000) * 1e-3
    assert sampling_interval(uniform) == pytest.approx(1e-3, rel=1e-9)
    steps = rng.choice([0.5e-3, 1e-3, 1.5e-3], size=10_000)
    assert sampling_interval(np.cumsum(steps)) == pytest.approx(1e-3)
    paused = uniform.copy()
    paused[5000:] += 0.5  # a 0.5 s pause: a gap, not the interval
    assert sampling_interval(paused) == pytest.approx(1e-3, rel=1e-9)


def test_the_sampling_interval_of_bursts_is_their_mean_rate() -> None:
    """Bursts of 8 samples 0.1 ms apart every 4 ms: the median interval is 0.1 ms, the
    logger's rate one sample per 0.5 ms."""
    t = np.concatenate([4e-3 * b + 1e-4 * np.arange(8) for b in range(2000)])
    assert np.median(np.diff(t)) == pytest.approx(1e-4)
    assert sampling_interval(t) == pytest.approx(0.5e-3, rel=1e-6)


@pytest.mark.parametrize("stamps", [s for s in STAMPS if s not in ("uniform", "gapped")])
def test_generated_loggers_keep_their_experiments_whole(stamps: str) -> None:
    """The generator's irregular loggers (2 kHz): stamps strictly increasing, and the
    diagnosis cuts the record where its experiments change only (a record of bursts was
    cut at every wait between bursts into pieces of one burst, most thrown away)."""
    rec = generate(["pressure-dependence"], duration=12.0, rate=2000.0, seed=5, stamps=stamps)
    t = rec.measurement.t
    assert np.all(np.diff(t) > 0)
    assert t.size == rec.truth.F.size
    data = prepare(rec.measurement)
    assert len(data.experiments) == 3
    assert sum(e.n for e in data.experiments) == t.size
    assert data.scales.dt == pytest.approx(0.5e-3, rel=0.25)


def _slide(pause: tuple[float, float], speed_after: float, *, back: float = 0.0
           ) -> Measurement:
    """A record at 1 kHz sliding at 20 mm/s, with the samples in ``pause`` (s) lost; after
    it the speed is ``speed_after``; ``back`` (m) moves the position after the pause back
    (a turn inside it)."""
    t = np.arange(0.0, 3.0, 1e-3)
    v = np.where(t < pause[0], 0.02, speed_after)
    x = 0.01 + np.concatenate([[0.0], np.cumsum(v[:-1] * 1e-3)])
    x = np.where(t >= pause[1], x - back, x)
    keep = (t < pause[0]) | (t >= pause[1])
    q = 1e-6
    return Measurement({"t": t[keep], "x": np.round(x[keep] / q) * q,
                        "F": np.where(v > 0, 30.0, -30.0)[keep]}, {"name": "slide"})


def test_a_pause_inside_a_slide_is_bridged_by_the_motion() -> None:
    """Sliding one way at the same speed both sides: one experiment, the pause filled at
    the sampling interval with a position on the straight line, the filled samples marked."""
    m = _slide((1.0, 1.4), 0.02)
    data = prepare(m)
    assert len(data.experiments) == 1
    bridged = data.bridged
    assert int(bridged.sum()) == 400  # the 400 samples lost, at the sampling interval
    t, x = data.signal("t"), data.signal("x")
    line = 0.01 + 0.02 * t[bridged]
    assert np.max(np.abs(x[bridged] - line)) < 5e-6  # the Hermite curve of a steady slide
    assert np.all(np.diff(t) > 0)


def test_a_pause_hiding_a_turn_or_a_stop_still_starts_an_experiment() -> None:
    assert len(prepare(_slide((1.0, 1.4), -0.02)).experiments) == 2  # reversed within
    # the same direction both sides, but 3 mm short of what the speeds give: a stop within
    assert len(prepare(_slide((1.0, 1.4), 0.02, back=0.003)).experiments) == 2


def test_a_pause_at_rest_is_bridged_as_a_rest() -> None:
    t = np.arange(0.0, 3.0, 1e-3)
    x = np.full(t.size, 0.05)
    keep = (t < 1.0) | (t >= 1.5)
    flags = np.zeros(int(keep.sum()), dtype=bool)
    m = Measurement({"t": t[keep], "x": x[keep], "F": np.zeros(int(keep.sum()))}, {"name": "r"})
    tk = m.t
    flags[np.flatnonzero(np.diff(tk) > GAP_FACTOR * 1e-3)] = True
    assert kind(tk, m["x"], int(np.flatnonzero(flags)[0]), 1e-3, 1e-6) == "rest"
    out, bridged, left = bridge(m, flags, 1e-3)
    assert not left.any() and int(bridged.sum()) == 500
    assert np.all(out["x"][bridged] == 0.05)


def test_the_bridged_samples_are_in_no_fit_or_score() -> None:
    """The generator's gapped logger: every pause either starts an experiment or is
    bridged; bridged samples are never valid (so in neither the training nor the held-out
    set) and the records' own samples are all kept."""
    from fcomp.diagnosis.regimes import segment
    from fcomp.diagnosis.split import make_split

    m = generate([], duration=12.0, seed=3, stamps="gapped").measurement
    data = prepare(m)
    assert data.bridged.any()  # seed 3: one of its three pauses inside a slide
    assert data.n == m.t.size + int(data.bridged.sum())
    seg = segment(data)
    split = make_split(data, seg.valid)
    assert not (seg.valid & data.bridged).any()
    assert not ((split.train | split.test) & data.bridged).any()
    own = data.signal("t")[~data.bridged]
    np.testing.assert_array_equal(own, m.t)
