"""Pieces of the diagnosis: data preparation, regimes, held-out splits, noise floor, features,
the acceptance statistics."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

import fcomp.diagnosis.revision as revision
from fcomp.conditioning import default_cutoff, position_noise
from fcomp.diagnosis import Diagnosis
from fcomp.diagnosis.data import prepare
from fcomp.diagnosis.features import (
    knn_predict,
    paired_trimmed_rms,
    residual_structure,
    strength,
    trimmed_rms,
)
from fcomp.diagnosis.noise import effective_sample_size, noise_floor, tolerant_noise_share
from fcomp.diagnosis.regimes import DWELL, PRESLIDING, REVERSAL, SLIDING, segment
from fcomp.diagnosis.rule import fall_test, heldout_pieces
from fcomp.diagnosis.split import make_split
from fcomp.diagnosis.verdict import VerdictRule
from fcomp.errors import FcompError
from fcomp.measurement import Measurement
from fcomp.synthetic import SCALES, generate

RING_CONCENTRATION = VerdictRule().ring_concentration
RING_NOISE = VerdictRule().ring_noise


@pytest.fixture(scope="module")
def record():
    return generate([], duration=9.0, seed=11)


def _runs(mask: np.ndarray) -> int:
    return int(np.sum(np.diff(np.concatenate([[0], mask.astype(int), [0]])) == 1))


def test_experiments_from_column_and_from_time_gaps(record) -> None:
    data = prepare(record.measurement)
    assert len(data.experiments) == 3
    m = record.measurement
    no_col = Measurement({k: v for k, v in m.columns.items() if k != "experiment"}, m.meta)
    assert len(prepare(no_col).experiments) == 3  # the generator leaves 1 s gaps
    assert data.source == "F"
    assert data.available["x"] and data.available["p1"]


def test_a_logger_pause_inside_a_labelled_experiment_is_a_break_or_a_bridge() -> None:
    """A pause of the logger inside an experiment the ``experiment`` column labels as one
    (generated with ``stamps="gapped"``: a 0.2-0.6 s pause in the middle half of each) cuts it
    -- the piston moved during the pause, so the model must start afresh after it --
    unless the motion on both sides shows a rest or a slide one way through it, which is
    then bridged (:mod:`fcomp.diagnosis.pauses`). Every piece starts at a label change or
    at an unbridged pause, and nowhere else."""
    m = generate([], duration=12.0, seed=4, stamps="gapped").measurement
    t, label = m.t, m["experiment"]
    dt = np.diff(t)
    breaks = np.flatnonzero((dt > 20 * np.median(dt)) | (np.diff(label) != 0)) + 1
    pauses = np.flatnonzero((dt > 20 * np.median(dt)) & (np.diff(label) == 0))
    assert pauses.size == 3  # one per labelled experiment
    data = prepare(m)  # seed 4: each pause hides a turn, a start or a stop
    assert not data.bridged.any()
    assert [e.start for e in data.experiments] == [0, *breaks.tolist()]
    assert len(data.experiments) == 6
    m3 = generate([], duration=12.0, seed=3, stamps="gapped").measurement
    data3 = prepare(m3)  # seed 3: one pause inside a slide, bridged; the others cut
    assert len(data3.experiments) == 5 and data3.bridged.any()


def test_cutoff_follows_the_position_noise() -> None:
    t = np.arange(5000) / 1000.0
    x = 0.01 * np.sin(2 * np.pi * 0.5 * t)
    clean = np.round(x / 1e-6) * 1e-6
    noisy = x + np.random.default_rng(0).normal(0, 2e-5, t.size)
    assert position_noise(clean) == pytest.approx(1e-6 / math.sqrt(12), rel=0.3)
    fc_clean, fc_noisy = default_cutoff(t, clean), default_cutoff(t, noisy)
    assert 100.0 <= fc_clean <= 250.0  # fs/10 .. fs/4 for a clean encoder
    assert fc_noisy < 0.5 * fc_clean  # a noisy sensor is filtered harder


def _dahl_record(v: np.ndarray, dt: float, name: str) -> Measurement:
    t = np.arange(v.size) * dt
    x = 0.05 + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
    F = np.zeros(v.size)  # Dahl: dF/dx = k*(1 - F*sign(v)/Fc), presliding length 0.1 mm
    for i in range(1, v.size):
        dx = x[i] - x[i - 1]
        F[i] = F[i - 1] + 3e5 * dx * (1.0 - F[i - 1] * np.sign(dx) / 30.0)
    return Measurement({"t": t, "x": np.round(x / 1e-7) * 1e-7, "v": v, "F": F}, {"name": name})


def test_regimes_of_a_designed_motion() -> None:
    """Rest, a long slide, a reversal, small loops: each gets its regime."""
    dt = 1e-3
    parts = [np.zeros(500), np.full(1000, 0.02), np.full(1000, -0.02), np.zeros(300),
             5e-5 * 2 * np.pi * 2 * np.sin(2 * np.pi * 2 * np.arange(1000) * dt)]
    data = prepare(_dahl_record(np.concatenate(parts), dt, "designed"))
    seg = segment(data)
    assert np.all(seg.regime[100:450] == DWELL)
    assert np.all(seg.regime[1100:1450] == SLIDING)
    assert np.any(seg.regime[1500:1560] == REVERSAL)
    assert np.mean(seg.regime[2900:3700] == PRESLIDING) > 0.8
    assert not seg.valid[:1400].any() and seg.valid[1600:].all()  # warm-up: the first run
    starts = [k for k, _, rev in seg.starts if rev]
    assert any(abs(k - 1500) < 5 for k in starts)


def test_warm_up_lasts_until_the_contact_age_is_slid_off() -> None:
    """A record that starts at rest and creeps before it slides: the first break-away's
    dwell is unknown and the contact age lasts until the seal has slid a distance (1 % of
    the 0.2 m stroke, 2 mm), not just to the end of the first run of six presliding
    lengths (the first 0.8 mm creep)."""
    dt = 1e-3
    creep = 3.2e-3 * np.sign(np.sin(2 * np.pi * 2.0 * np.arange(2000) * dt + 1e-9))
    stroke = np.concatenate([np.full(4000, 0.05), np.zeros(200), np.full(4000, -0.05),
                             np.zeros(200)])
    v = np.concatenate([np.zeros(500), creep, np.tile(stroke, 2)])
    seg = segment(prepare(_dahl_record(v, dt, "creep")))
    assert 6 * seg.d_pre <= 0.8e-3  # the first creep run ends the old warm-up
    slid = np.concatenate([[0.0], np.cumsum(np.abs(v[:-1]) * dt)])
    reached = int(np.searchsorted(slid, 2e-3))  # in the third creep run
    assert 500 + 500 < reached < 500 + 750
    first = int(np.flatnonzero(~seg.valid).max()) + 1
    assert not seg.valid[:first].any() and seg.valid[first:].all()
    assert abs(first - reached) < 5


def test_warm_up_stops_at_its_share_of_the_record() -> None:
    """A first run of 1 mm, then 20 s of creep that slides 0.4 mm, then the 0.2 m strokes:
    the warm-up distance (2 mm) is reached only in the strokes, so the warm-up stops a
    tenth of the record after the first run of six presliding lengths."""
    dt = 1e-3
    creep = 2e-5 * np.sign(np.sin(2 * np.pi * 1.0 * np.arange(20000) * dt + 1e-9))
    v = np.concatenate([np.zeros(500), np.full(100, 0.01), creep, np.full(4000, 0.05),
                        np.full(4000, -0.05)])
    seg = segment(prepare(_dahl_record(v, dt, "creep-only")))
    first = int(np.flatnonzero(~seg.valid).max()) + 1
    assert not seg.valid[:first].any() and seg.valid[first:].all()
    assert abs(first - (600 + 0.1 * v.size)) < 20


def test_splits_are_contiguous_never_shuffled(record) -> None:
    data = prepare(record.measurement)
    seg = segment(data)
    sp = make_split(data, seg.valid, "segment")
    assert not np.any(sp.train & sp.test)
    assert not np.any((sp.train | sp.test) & ~seg.valid)
    assert _runs(sp.test) <= 12  # a few long blocks, not scattered samples
    assert 0.2 < sp.test.sum() / seg.valid.sum() < 0.5
    sp2 = make_split(data, seg.valid, "experiment")
    held = data.experiments[1]
    assert sp2.test[held.start:held.stop].sum() == seg.valid[held.start:held.stop].sum()
    assert not sp2.test[: data.experiments[0].stop].any()
    with pytest.raises(FcompError, match="split"):
        make_split(data, seg.valid, "random")


def test_noise_floor_is_estimated_from_the_data() -> None:
    for std in (0.2, 1.0):
        rec = generate([], duration=8.0, seed=12, noise_std=std)
        data = prepare(rec.measurement)
        nf = noise_floor(data, segment(data))
        assert nf.method == "rest"
        assert nf.value == pytest.approx(std, rel=0.15)


def test_effective_sample_size_of_correlated_noise() -> None:
    rng = np.random.default_rng(1)
    white = rng.normal(size=20000)
    assert effective_sample_size(white) == pytest.approx(20000, rel=0.1)
    phi = 0.8
    ar = np.empty(20000)
    ar[0] = 0.0
    for i in range(1, ar.size):
        ar[i] = phi * ar[i - 1] + white[i]
    # n/tau with tau = (1 + phi)/(1 - phi) = 9
    assert effective_sample_size(ar) == pytest.approx(20000 / 9, rel=0.25)


def test_knn_strength_finds_a_ripple_and_not_noise() -> None:
    rng = np.random.default_rng(2)
    n = 6000
    x = rng.uniform(0.0, 0.1, n)
    side = np.where(rng.uniform(size=n) > 0.5, 1.0, -1.0)
    train = (np.arange(n) // 500) % 3 != 1
    test = ~train
    ripple = side * np.sin(2 * np.pi * x / 3e-3)
    noise = rng.normal(size=n)
    assert strength(x, ripple + 0.3 * noise, side, train, test)[0] > 0.8
    assert strength(x, noise, side, train, test)[0] < 0.05
    # no training sample near a test value: no information, prediction 0
    far = knn_predict(np.array([0.0, 0.01]), np.array([1.0, 1.0]), np.array([1.0]), 2, 0.1)
    assert far[0] == 0.0


def test_residual_structure_of_a_noise_residual(record) -> None:
    data = prepare(record.measurement)
    seg = segment(data)
    sp = make_split(data, seg.valid)
    r = np.random.default_rng(3).normal(0, 0.4, data.n)
    feats = residual_structure(r, data, seg, sp.train, sp.test)
    assert {f.feature for f in feats} >= {"t", "v", "x", "p1+p2", "time_since_reversal"}
    assert max(f.strength for f in feats) < 0.05


def test_fall_test_separates_consistent_falls_from_chance() -> None:
    rng = np.random.default_rng(4)
    n = 4000
    blocks = heldout_pieces(np.ones(n, dtype=bool), [0], 0.002)
    assert len(blocks) == 32
    noise = rng.normal(0, 0.4, n)
    structure = 2.0 * np.sin(np.arange(n) / 50.0)
    t_good, p_good = fall_test(noise + structure, noise, blocks, 0.04)
    assert p_good < 1e-6 and t_good > 0
    other = noise + 0.05 * rng.normal(size=n)  # a candidate that only refits noise
    _, p_none = fall_test(noise, other, blocks, 0.04)
    assert p_none == 1.0 or p_none > 0.05
    _, p_worse = fall_test(noise, noise + structure, blocks, 0.04)
    assert p_worse > 0.99


def test_fall_test_finds_an_effect_carried_by_a_few_large_events() -> None:
    """Three break-away peaks of 6 N on 0.4 N of noise, explained by the candidate: a
    clear fall, significant (the variance of ``d`` itself counted the peaks' own spread
    as noise and gave z ~ sqrt(3))."""
    rng = np.random.default_rng(5)
    n = 4000
    blocks = heldout_pieces(np.ones(n, dtype=bool), [0], 0.002)
    noise = rng.normal(0, 0.4, n)
    peaks = np.zeros(n)
    for k, at in enumerate((300, 1900, 3300)):
        peaks[at:at + 40] = (4.0 + 2.0 * k) * np.hanning(40)
    z, p = fall_test(noise + peaks, noise, blocks, 0.04)
    assert z > 5 and p < 1e-6


@pytest.mark.parametrize("shape", ["peaks", "level", "slow"])
def test_fall_test_keeps_its_size_when_the_models_are_equally_accurate(shape: str) -> None:
    """The change ``D`` is fixed (it comes from the training samples), the two models
    equally accurate on held-out noise with correlation (AR(1), 5 samples): the test
    rejects equal accuracy at most about as often as its 5 % level says. Measured over
    1000 draws: 1.5 / 7.6 / 3.8 % (peaks / level / slow), the former unconditional test
    7.2 / 7.6 / 5.7 % (Newey-West on 125-sample pieces runs a little over its level for
    a constant change, the same in both)."""
    from scipy.signal import lfilter

    rng = np.random.default_rng(11)
    n = 4000
    blocks = heldout_pieces(np.ones(n, dtype=bool), [0], 0.002)
    t = np.arange(n)
    D = {"peaks": np.where(t % 1300 < 40, 1.0, 0.0),
         "level": np.full(n, 0.3),
         "slow": 0.5 * np.sin(t / 300.0)}[shape]
    draws = 1000
    rejected = 0
    for _ in range(draws):
        ar = lfilter([0.6], [1.0, -0.8], rng.normal(0, 0.4, n))
        # the truth lies halfway: before misses D/2, after overshoots by D/2
        _, p = fall_test(ar + D / 2, ar - D / 2, blocks, 0.04)
        rejected += p <= 0.05
    assert rejected / draws <= 0.09, rejected / draws


def test_bad_records_are_refused_with_a_reason(record) -> None:
    m = record.measurement
    still = Measurement({"t": m.t, "x": np.full(len(m), 0.1), "F": m["F"]}, {"name": "still"})
    with pytest.raises(FcompError, match="hardly moves"):
        Diagnosis("coulomb").fit(still)
    no_motion_signal = Measurement({"t": m.t, "F": m["F"]}, {"name": "nomotion"})
    with pytest.raises(FcompError, match="position 'x' or velocity 'v'"):
        Diagnosis("coulomb").fit(no_motion_signal)
    no_force = Measurement({"t": m.t, "x": m["x"]}, {"name": "noforce"})
    with pytest.raises(FcompError, match="no force"):
        Diagnosis("coulomb").fit(no_force)
    with pytest.raises(FcompError, match="unknown friction model"):
        Diagnosis("no-such-model").fit(m)
    with pytest.raises(FcompError, match="unknown effect"):
        Diagnosis("lugre", add=["no-such-effect"]).fit(m)


def test_dynamic_baseline_on_steady_state_points_says_why() -> None:
    v = np.array([0.01, 0.02, 0.05, 0.1, -0.01, -0.02, -0.05, -0.1] * 5)
    F = np.sign(v) * 20.0 + 50.0 * v
    m = Measurement({"t": np.arange(v.size, dtype=float), "v": v, "F": F},
                    {"name": "table", "diagnosis": {"samples": "steady-state"}})
    with pytest.raises(FcompError, match="steady-state points"):
        Diagnosis("lugre").fit(m)
    d = Diagnosis("coulomb", n_jobs=1).fit(m)
    assert d.added_ == ["viscous"]
    assert d.rms_final_ < 1e-3


def test_plant_domain_comparison_starts_from_the_measured_gauge_state() -> None:
    """A pneumatic run replayed with its own friction model matches; another model does not.

    The recorded chamber pressures are gauge while the plant's states are
    absolute: a wrong start would leave a 1 atm (101 kPa) transient in ``p1, p2``.
    """
    from fcomp.models import make_model
    from plants import PLANTS
    from plants.comparison import compare_plant

    lugre = make_model("lugre")
    run = PLANTS.get("pneumatic")(lugre, "seed000-servo").simulate(
        lambda t: 0.3 * np.sin(2 * np.pi * 0.5 * t), 4.0, 500.0)
    assert run.meta["pressure"] == "gauge" and run["p1"][0] < 3e5  # gauge, not absolute
    same = compare_plant(run, "pneumatic", lugre)["rms"]
    assert same["x"] < 1e-9 and same["p1"] < 1e-3 and same["p2"] < 1e-3  # m, Pa
    other = compare_plant(run, "pneumatic", make_model("coulomb"))["rms"]
    assert other["x"] > 1e-5 and other["p1"] > 100.0  # the friction model shows in x and p
    with pytest.raises(FcompError, match="command column 'u'"):
        compare_plant(Measurement({k: run[k] for k in ("t", "x", "p1", "p2")}, run.meta),
                      "pneumatic", lugre)


def test_the_floor_of_a_tolerant_residual_matches_a_monte_carlo() -> None:
    """Pure noise measured against a prediction band keeps only part of its variance: the
    closed form behind the excess-over-the-floor rule agrees with the tolerant residual
    itself on simulated noise, for bands from none to four noise deviations wide (a
    static law's band at rest is many deviations wide, and its residual there falls
    below the noise floor though nothing is left to explain)."""
    from fcomp.diagnosis.scoring import tolerant_residual

    rng = np.random.default_rng(4)
    sigma, n = 2.5, 200_000
    for scale in (0.0, 0.3, 1.0, 4.0):
        # a band of four widths in long stretches, around a slowly varying truth
        width = scale * sigma * np.repeat([0.2, 0.7, 1.3, 1.8], n // 4)
        truth = 40.0 * np.sin(np.arange(n) * 1e-4)
        y = truth + rng.normal(0.0, sigma, n)
        r, spread = tolerant_residual(y, truth - width / 2, truth + width / 2, [0])
        assert np.mean(np.isclose(spread, width, atol=1e-2 * sigma)) > 0.999  # but at steps
        assert tolerant_noise_share(spread, sigma) == pytest.approx(np.mean(r**2) / sigma**2,
                                                                    rel=0.02, abs=2e-3)
    assert tolerant_noise_share(np.zeros(5), sigma) == 1.0


def test_noise_floor_of_short_runs_of_correlated_noise_matches_a_monte_carlo() -> None:
    """Short steady runs of AR(1) noise with a quadratic removed: the naive pooled variance
    (``n - 3`` degrees of freedom per run) is several times low; the correlated count is
    close (within 25 %: with runs shorter than two correlation times, as here, the inverted
    correlation errs high; 60 % low before)."""
    from fcomp.diagnosis.noise import correlated_dof

    rng = np.random.default_rng(7)
    n, rho, runs = 40, 0.93, []
    for _ in range(400):
        e = np.empty(n)
        e[0] = rng.standard_normal()
        for t in range(1, n):
            e[t] = rho * e[t - 1] + math.sqrt(1 - rho**2) * rng.standard_normal()
        tt = np.linspace(-1.0, 1.0, n)
        runs.append(e - np.polyval(np.polyfit(tt, e, 2), tt))
    ss = sum(float(r @ r) for r in runs)
    naive = ss / sum(r.size - 3 for r in runs)
    assert naive < 0.4  # the bias this corrects (true variance 1)
    assert ss / correlated_dof(runs, 2) == pytest.approx(1.0, rel=0.25)
    white = [rng.standard_normal(n) for _ in range(50)]
    assert correlated_dof(white, 2) == pytest.approx(sum(r.size - 3 for r in white), rel=0.05)


def _designed(parts: list[np.ndarray], dt: float):
    """A record of the velocity pieces ``parts`` (position quantised to 0.1 µm, a Coulomb
    force of 30 N), prepared and segmented."""
    v = np.concatenate(parts)
    t = np.arange(v.size) * dt
    x = 0.05 + np.concatenate([[0.0], np.cumsum(v[:-1] * dt)])
    m = Measurement({"t": t, "x": np.round(x / 1e-7) * 1e-7, "v": v, "F": 30 * np.sign(v)},
                    {"name": "designed"})
    data = prepare(m)
    return data, segment(data)


def test_events_are_reversals_and_starts_after_a_rest_not_stutters() -> None:
    """A pause shorter than ``t_dwell`` in the same direction continues the run; a rest of a
    second and a reversal are events, with the time since each."""
    dt = 1e-3
    parts = [np.zeros(300), np.full(800, 0.02), np.zeros(10), np.full(800, 0.02),
             np.zeros(1000), np.full(800, 0.02), np.full(800, -0.02)]
    data, seg = _designed(parts, dt)
    since, kind = seg.events(data)
    edges = np.cumsum([p.size for p in parts])  # 300 1100 1110 1910 2910 3710 4510
    assert np.isinf(since[:290]).all()
    assert kind[320] == 1 and abs(since[320] - 0.02) < 3e-3  # first start after a rest
    assert since[1200] > 0.8  # the 10 ms pause did not restart the clock
    assert kind[3000] == 1 and since[3000] < 0.1  # a start after a 1 s rest
    assert kind[3800] == 2 and abs(since[3800] - (3800 - edges[5]) * dt) < 3e-3  # a reversal


def _ring_record():
    rng = np.random.default_rng(5)
    dt, parts = 1e-3, []
    for _ in range(40):  # starts after rests and reversals, both directions
        parts += [np.zeros(300), np.full(400, 0.02), np.full(400, -0.02)]
    data, seg = _designed(parts, dt)
    return rng, data, seg, make_split(data, seg.valid)


def test_event_structure_sees_a_ring_whose_phase_wanders() -> None:
    """A 75 Hz mode rung at every event, started 0-6 ms late at random (as a velocity shows
    a start a few samples late), does not repeat in phase, but lifts the window's RMS far
    above the noise; noise alone does not."""
    from fcomp.diagnosis.features import event_structure
    rng, data, seg, sp = _ring_record()
    sigma = 0.2
    noise = rng.normal(0.0, sigma, data.n)
    t = data.signal("t")
    ring = np.zeros(data.n)
    w = 2 * np.pi * 75.0
    for k, _, _ in seg.starts:
        k0 = k + int(rng.integers(0, 7))
        tau = t[k0:k0 + 150] - t[k0]
        ring[k0:k0 + 150] += 3.0 * np.exp(-0.06 * w * tau) * np.sin(w * tau)
    quiet = event_structure(noise, data, seg, sp.train, sp.test)
    rung = event_structure(noise + ring, data, seg, sp.train, sp.test)
    assert quiet is not None and rung is not None
    assert quiet.local < 1.2 * sigma and quiet.strength < 0.1
    assert rung.local > 4 * sigma


def test_event_ring_finds_a_mode_below_the_noise_by_its_spectrum() -> None:
    """A 75 Hz ring whose RMS after events is below the noise, phase scrambled per event,
    is found at its frequency by the excess of its power over quiet stretches; noise alone
    and a broadband misfit after events (a step placed late) are not narrow rings."""
    from fcomp.diagnosis.features import event_ring
    rng, data, seg, sp = _ring_record()
    sigma = 1.0
    noise = rng.normal(0.0, sigma, data.n)
    t = data.signal("t")
    ring, step = np.zeros(data.n), np.zeros(data.n)
    w = 2 * np.pi * 75.0
    since, _ = seg.events(data)
    for k in np.flatnonzero(since == 0.0):
        k0 = k + int(rng.integers(0, 7))
        tau = t[k0:k0 + 150] - t[k0]
        ring[k0:k0 + 150] += 1.0 * np.exp(-0.06 * w * tau) * np.sin(w * tau)
        step[k:k + int(rng.integers(1, 8))] += 3.0  # a jump the prediction places late
    found = event_ring(noise + ring, data, seg, sp.test)
    assert found is not None and abs(found.frequency - 75.0) <= 10.0
    assert found.concentration >= RING_CONCENTRATION
    assert 0.2 < found.rms < 0.4  # the ring's RMS in those windows is 0.3
    for r in (noise, noise + step):
        other = event_ring(r, data, seg, sp.test)
        assert other is None or other.concentration < RING_CONCENTRATION \
            or other.rms < RING_NOISE * sigma  # below what the verdict counts


def test_drift_probe_explains_a_drift_and_not_a_law_in_position() -> None:
    """``drift_fall``: the held-out fall of levels drifting with time alone -- most of a
    thermal drift's residual, little of a ripple along the stroke."""
    from fcomp.diagnosis.features import drift_fall
    rng, data, seg, sp = _ring_record()
    t, x = data.signal("t"), data.signal("x")
    F_hat = 30.0 * np.sign(data.signal("v"))
    noise = rng.normal(0.0, 0.2, data.n)
    tau = 2 * (t - t[0]) / (t[-1] - t[0]) - 1
    drift = F_hat * 0.1 * tau + noise
    ripple = F_hat * 0.1 * np.sin(2 * np.pi * x / 2e-3) + noise
    rms = lambda r: float(np.sqrt(np.mean(r[sp.test] ** 2)))  # noqa: E731
    fall = drift_fall(drift, F_hat, data, sp.train, sp.test)
    assert fall > 0.9 * (rms(drift) - rms(noise))
    assert drift_fall(ripple, F_hat, data, sp.train, sp.test) < 0.05 * (rms(ripple) - rms(noise))


def test_baseline_check_runs_when_the_answer_is_doubtful() -> None:
    """``check_baseline="auto"``: a clean answer skips the second diagnosis and says why;
    structure left (a Stribeck hump the Coulomb map cannot follow, no candidate offered)
    runs it; ``False`` never does."""
    rec = generate(["stribeck"], duration=12.0, seed=4).measurement
    doubtful = Diagnosis("coulomb-viscous", candidates=["force-offset"], n_jobs=1).fit(rec)
    assert doubtful.doubts()
    assert doubtful.baseline_check_["ran"] and doubtful.other_ is not None
    never = Diagnosis("coulomb-viscous", candidates=["force-offset"], n_jobs=1,
                      check_baseline=False).fit(rec)
    assert never.baseline_check_ == {"ran": False, "why": "not asked for"}
    assert never.other_ is None and never.to_dict()["baseline_check"]["ran"] is False
    clean = Diagnosis("lugre", candidates=["force-offset"], n_jobs=1).fit(
        generate([], duration=12.0, seed=4).measurement)
    if not clean.doubts():
        assert clean.baseline_check_["ran"] is False and clean.other_ is None
    else:
        assert clean.baseline_check_["ran"] and clean.baseline_check_["why"] == "; ".join(
            clean.doubts())


def test_paired_trim_drops_the_spikes_both_carry_and_keeps_those_one_removes() -> None:
    """A timing spike in both residuals is trimmed; a break-away spike that the
    candidate removes is kept, so the fall it brings is seen (trimming each
    residual by its own largest values would drop it from ``before`` only)."""
    rng = np.random.default_rng(3)
    n = 2000
    before = rng.normal(0.0, 1.0, n)
    after = before.copy()
    both = rng.choice(n, 10, replace=False)  # 0.5 %: spikes in both
    before[both] += 40.0
    after[both] += 40.0
    explained = np.setdiff1d(np.arange(0, n, 100), both)[:15]  # 0.75 %: the candidate's
    before[explained] += 25.0
    rb, ra = paired_trimmed_rms(before, after)
    keep = np.setdiff1d(np.arange(n), both)
    assert rb == pytest.approx(np.sqrt(np.mean(before[keep] ** 2)), rel=0.02)
    assert ra == pytest.approx(np.sqrt(np.mean(after[keep] ** 2)), rel=0.05)
    assert rb**2 - ra**2 > 0.8 * 25.0**2 * explained.size / n
    # trimming each on its own hides most of the fall
    own = trimmed_rms(before) ** 2 - trimmed_rms(after) ** 2
    assert own < 0.5 * (rb**2 - ra**2)


def test_a_reduced_model_is_never_worse_than_the_same_structure_seen_before() -> None:
    """The backward check and the swaps refit the model without one effect; a fit of that
    structure from earlier in the search is a start and a floor. Taking out the last of two
    forced effects gives back at most the training error of the step before it."""
    rec = generate(["presliding", "direction-asymmetry"], base="stribeck", duration=9.0,
                   seed=11).measurement
    d = Diagnosis("stribeck", add=["presliding", "direction-asymmetry"], search=False,
                  n_jobs=1, check_baseline=False).fit(rec)
    before = d.steps_[0].fit
    assert before is not None and before.model.describe() == "stribeck + presliding"
    reduced = revision.rebuilt(d._search, ["presliding"])
    assert reduced.model.describe() == "stribeck + presliding"
    assert reduced.rms_train <= before.rms_train
    assert revision.rebuilt(d._search, []).rms_train <= d.baseline_fit_.rms_train


def test_baseline_finds_a_stribeck_speed_below_every_sliding_speed() -> None:
    """A Stribeck speed of 3 mm/s on a rig whose strokes all slide faster leaves no
    hump in the sliding samples, only at break-away: the baseline fit must still find
    the hump (it once settled on the flat curve, ``Fs = Fc`` at ``vs`` ~ 15 m/s)."""
    truth = dataclasses.replace(SCALES["pneumatic"].params, vs=0.003)
    rec = generate([], base="lugre", params=truth, duration=20.0, seed=2)
    fit = Diagnosis("lugre", search=False, check_baseline=False, n_jobs=1,
                    progress=False).fit(rec.measurement).baseline_fit_
    assert fit.values["vs"] == pytest.approx(truth.vs, rel=0.25)
    assert fit.values["Fs"] == pytest.approx(truth.Fs, rel=0.15)


def test_the_lag_of_a_pressure_channel_is_fitted_with_the_model() -> None:
    """Pressure transducers lagging by ``tau`` (first order, applied by the generator to
    the chamber pressures) leave ``tau*dD/dt`` out of the reconstructed force, tens of
    newtons at the ends of the starts at hydraulic scale. The ``lag`` term, fitted by the
    first (unweighted) baseline fit and held from then on, recovers ``tau`` (fitted in
    every weighted fit instead, it came out at a third of ``tau``: the weights distrust
    the samples where the force changes fast), stays within half a sample without a
    lag, and is reported in the JSON signals; a load cell has none."""
    got = {}
    for tau in (0.0, 3e-3):
        sensors = dataclasses.replace(SCALES["hydraulic"].sensors, pressure_lag=tau)
        rec = generate([], base="lugre", scale="hydraulic", style="pressures", sensors=sensors,
                       duration=20.0, seed=3)
        d = Diagnosis("lugre", search=False, check_baseline=False, n_jobs=1,
                      progress=False).fit(rec.measurement)
        got[tau] = d.to_dict()["signals"]["force_lag_s"]
        assert d.fit_.values["lag"] == got[tau]
        assert "lag" not in d._search.refit.free_names(d.fit_.model)  # held
    assert got[3e-3] == pytest.approx(3e-3, rel=0.15)
    # a lag held at a wrong value is estimated again for a model (jointly with it, unweighted),
    # and the sample weights of the later fits are left as they were
    weights = d._search.refit._weights
    d._search.refit.hold("lag", 0.0)
    assert d._search.refit.refit_held("lag", d.fit_) == pytest.approx(3e-3, rel=0.15)
    assert d._search.refit.held["lag"] == pytest.approx(3e-3, rel=0.15)
    assert d._search.refit._weights is weights
    # without a lag it stays within half a sample (1 kHz): the timing of the sampled model
    assert abs(got[0.0]) < 5e-4
    cell = generate([], base="lugre", duration=9.0, seed=3).measurement
    d = Diagnosis("lugre", search=False, check_baseline=False, n_jobs=1,
                  progress=False).fit(cell)
    assert d.to_dict()["signals"]["force_lag_s"] is None and "lag" not in d.fit_.values


def test_confounded_partners_both_in_the_model_are_reported_as_a_tie() -> None:
    """An offset and a direction asymmetry both accepted are a tie (sliding, the record
    fixes ``Fc+ + offset`` and ``Fc- - offset``, not three terms); effects that are not
    partners are not, and an existing tie grows instead of doubling."""
    from fcomp.effects import EFFECTS

    assert "force-offset" in EFFECTS.get("direction-asymmetry").confounded
    assert "pressure-dependence" not in EFFECTS.get("direction-asymmetry").confounded
    d = SimpleNamespace(added=["pressure-dependence", "force-offset", "direction-asymmetry"],
                        ties=[])
    revision.partners_in_model(d)
    assert d.ties == [["force-offset", "direction-asymmetry"]]
    revision.partners_in_model(d)  # idempotent
    assert d.ties == [["force-offset", "direction-asymmetry"]]
    d.added = ["force-offset", "direction-asymmetry"]
    d.ties = [["force-offset", "area-error"]]  # a swap's tie of the first
    revision.partners_in_model(d)
    assert d.ties == [["force-offset", "area-error", "direction-asymmetry"]]
    d.added = ["pressure-dependence", "stribeck"]
    d.ties = []
    revision.partners_in_model(d)
    assert d.ties == []


def test_a_flexible_effect_is_judged_where_its_signature_lives(monkeypatch) -> None:
    """``Effect.acts_in``: the share of the held-out fall (in mean square) that lies in the
    regimes an effect declares; ``nonlocal-memory`` declares the presliding travel after a
    reversal or a start, and a fall it takes in steady sliding does not count there."""
    from fcomp.diagnosis.regimes import REGIMES
    from fcomp.diagnosis.rule import AcceptanceRule, signature_share
    from fcomp.effects import EFFECTS

    nm = EFFECTS.get("nonlocal-memory")
    assert set(nm.acts_in) == {"pre-sliding", "reversal", "dwell/break-away"} <= set(REGIMES)
    regime = np.array([SLIDING] * 60 + [PRESLIDING] * 20 + [REVERSAL] * 10 + [DWELL] * 10)
    test = np.ones(100, dtype=bool)
    test[::7] = False  # training samples do not count
    ground = SimpleNamespace(split=SimpleNamespace(test=test),
                             segmentation=SimpleNamespace(regime=regime))

    def share(name, b, a):
        return signature_share(EFFECTS.get(name).acts_in, b, a, ground)

    before = np.full(100, 2.0)
    inside, outside, half = before.copy(), before.copy(), before.copy()
    inside[60:] = 1.0
    outside[:60] = 1.0
    half[:60] = np.sqrt(4.0 - 3.0 * (test[60:].sum() / test[:60].sum()))  # equal falls
    half[60:] = 1.0
    assert share("nonlocal-memory", before, inside) == pytest.approx(1.0)
    assert share("nonlocal-memory", before, outside) == pytest.approx(0.0)
    assert share("nonlocal-memory", before, half) == pytest.approx(0.5)
    assert 0.5 < AcceptanceRule().signature_share < 1.0
    assert share("force-offset", before, outside) is None  # declares none: anywhere
    assert share("nonlocal-memory", before, before) is None  # nothing falls
    monkeypatch.setattr(nm, "acts_in", ("presliding",))
    with pytest.raises(FcompError, match="acts_in names regimes"):
        share("nonlocal-memory", before, inside)
