"""Periodic disturbances (issue 24, item 3): a narrow line that follows no motion is found,
sized, kept out of the noise floor and never called explained; the motion's own lines
(a periodic stroke's harmonics, a ripple along the bore) are not disturbances."""

from __future__ import annotations

import numpy as np
import pytest

from fcomp.diagnosis import Diagnosis, disturbance
from fcomp.diagnosis.data import prepare
from fcomp.synthetic import generate


def _prepared(seed: int, scale: str = "pneumatic", rate: float = 1000.0, stamps: str = "uniform"):
    rec = generate([], scale=scale, style="load-cell", rate=rate, duration=12.0, seed=seed,
                   stamps=stamps, name=f"d{seed}")
    return prepare(rec.measurement)


@pytest.mark.parametrize("freq,amp,seed,stamps", [(37.0, 0.8, 1, "uniform"),
                                                   (50.0, 0.3, 2, "uniform"),
                                                   (17.3, 1.5, 3, "irregular")])
def test_a_line_in_time_is_found_on_any_motion_and_sized(freq: float, amp: float, seed: int,
                                                         stamps: str) -> None:
    data = _prepared(seed, stamps=stamps)
    rng = np.random.default_rng(seed)
    t = data.signal("t")
    noise = 0.2 * rng.standard_normal(t.size)
    line = amp * np.sin(2 * np.pi * freq * t + 0.7)
    found = disturbance.find(noise + line, np.zeros(t.size), data)
    assert len(found) == 1, [(f, p) for f, p, _ in found]
    f, prom, waves = found[0]
    d = disturbance.describe(f, prom, waves)
    assert d.frequency_hz == pytest.approx(freq, abs=0.05)
    assert d.amplitude == pytest.approx(amp, rel=0.1)
    # taken off, what is left is the noise
    cleaned = noise + line - np.concatenate(waves)
    assert np.std(cleaned) == pytest.approx(0.2, rel=0.1)


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_white_noise_and_the_motions_own_harmonics_are_no_disturbance(seed: int) -> None:
    data = _prepared(seed, scale="hydraulic" if seed % 2 else "pneumatic")
    rng = np.random.default_rng(seed)
    v = data.signal("v")
    # a friction law's error that repeats with the motion: odd harmonics of sign(v), |v|
    r = 0.3 * rng.standard_normal(v.size) + 2.0 * np.sign(v) * np.abs(v) ** 0.5 \
        + 0.5 * np.tanh(v / 1e-3)
    assert disturbance.find(r, np.zeros(v.size), data) == []
    assert disturbance.find(0.3 * rng.standard_normal(v.size), np.zeros(v.size), data) == []


def test_a_ripple_along_the_bore_is_no_disturbance() -> None:
    """A 3 mm ripple along x is a line in time only at one speed, and absent at rest."""
    data = _prepared(7)
    x = data.signal("x")
    moving = np.abs(data.signal("v")) > 1e-4
    r = 0.05 * np.random.default_rng(7).standard_normal(x.size) \
        + 1.0 * np.sin(2 * np.pi * x / 3e-3) * moving
    assert disturbance.find(r, np.zeros(x.size), data) == []


@pytest.mark.parametrize("line,peak", [(0.15, 0.3), (0.25, 0.5)])
def test_a_line_beside_a_stronger_peak_of_another_kind_is_not_masked(line: float,
                                                                   peak: float) -> None:
    """A pulsation between two bins (35.23 Hz on 0.5 Hz bins) 1.2 Hz from a stronger peak
    that is no disturbance (present only at rest: it fails the all-speeds test) is still
    found: the peak must not hide it (seen on a matrix record, seed 67; both amplitudes
    were lost when a line had to be the largest within two bins)."""
    data = _prepared(8, scale="hydraulic")
    t = data.signal("t")
    rest = data.signal("v") == 0.0
    freq = 35.23
    r = 0.3 * np.random.default_rng(8).standard_normal(t.size) \
        + line * np.sin(2 * np.pi * freq * t + 0.3) \
        + peak * np.sin(2 * np.pi * (freq - 1.2) * t) * rest
    found = disturbance.find(r, np.zeros(t.size), data)
    assert [f for f, _, _ in found] == [pytest.approx(freq, abs=0.1)]


@pytest.mark.slow
@pytest.mark.parametrize("scale,style", [("pneumatic", "load-cell"), ("hydraulic", "pressures")])
def test_a_pump_pulsation_is_reported_kept_out_of_the_floor_and_not_explained(
        scale: str, style: str) -> None:
    rec = generate([], scale=scale, style=style, rate=1000.0, duration=12.0, seed=11,
                   pulsation=(37.0, 0.8 if scale == "pneumatic" else 12.0), name="pump")
    d = Diagnosis("lugre", n_jobs=1, check_baseline=False).fit(rec.measurement)
    doc = d.to_dict()
    (line,) = doc["disturbances"]
    assert line["frequency_hz"] == pytest.approx(37.0, abs=0.05)
    assert line["amplitude"] == pytest.approx(0.8 if scale == "pneumatic" else 12.0, rel=0.1)
    # the floor is the sensor's noise, not the pulsation's (0.8 N amplitude is 0.57 N RMS)
    assert doc["noise_floor"] < 1.3 * rec.truth.noise_std
    assert doc["verdict"] == "unexplained-structure" and "disturbance" in doc["reason"]
    assert doc["added"] == []


@pytest.mark.parametrize("seed,scale", [(1, "hydraulic"), (2, "pneumatic")])
def test_a_misfit_that_follows_the_motion_near_one_frequency_is_no_line(seed: int,
                                                                        scale: str) -> None:
    """A residual that is the motion band-passed at 2.2-2.8 Hz (a law's misfit the motion
    excites there, without a line of its own) peaks like a line (prominence 240-580 on these
    records, reported before), but all of it is coherent with ``v`` or ``a``: none is left
    once that part is taken off, so no disturbance."""
    from scipy.signal import butter, sosfiltfilt

    rec = generate([], scale=scale, style="load-cell", rate=1000.0, duration=30.0, seed=seed,
                   name=f"m{seed}")
    data = prepare(rec.measurement)
    rng = np.random.default_rng(seed)
    sos = butter(2, [2.2, 2.8], btype="band", fs=1000.0, output="sos")
    for sig in ("v", "a"):
        bump = sosfiltfilt(sos, data.signal(sig))
        r = 0.2 * rng.standard_normal(data.n) + bump / bump.std()
        assert disturbance.find(r, np.zeros(data.n), data) == [], sig


@pytest.mark.parametrize("seed,scale", [(1, "hydraulic"), (3, "pneumatic")])
def test_a_pump_line_under_a_misfit_that_follows_the_motion_is_found(seed: int,
                                                                     scale: str) -> None:
    """A 0.3 N line at 36.3 Hz under a misfit ten times its size that follows the
    acceleration at every frequency (coherent with the motion in the line's bin too): the
    part coherent with the motion is taken off, the line is not, and it is found."""
    rec = generate([], scale=scale, style="load-cell", rate=1000.0, duration=30.0, seed=seed,
                   name=f"p{seed}")
    data = prepare(rec.measurement)
    t, a = data.signal("t"), data.signal("a")
    r = 0.2 * np.random.default_rng(seed).standard_normal(data.n) + 2.0 * a / a.std() \
        + 0.3 * np.sin(2 * np.pi * 36.3 * t + 1.0)
    found = disturbance.find(r, np.zeros(data.n), data)
    assert [f for f, _, _ in found] == [pytest.approx(36.3, abs=0.1)]


@pytest.mark.parametrize("case,lines", [
    # a lead-lag law missing from a LuGre baseline on irregular stamps: a 2.25 Hz "line"
    # of 13.8 N (coherence 0.9 with v and a) was reported as a pump's
    (dict(row="viscous-lead", kind="dynamic", style="load-cell", scale="hydraulic", seed=131,
          shape="viscous-lead:lead-lag", baseline="lugre", condition="irregular-stamps"), []),
    # a chamber-weighted pressure law missing from a static baseline: a 3.05 Hz "line"
    # of 2.2 N (coherence 0.5 with sign(v)*p1 and sign(v)*p2)
    (dict(row="pressure-dependence", kind="static", style="encoder-velocity",
          scale="pneumatic", seed=131, shape="pressure-dependence:chamber-weighted",
          baseline="stribeck", condition="plain"), []),
    # a pump line at 36.23 Hz in a bin whose residual is 85 % coherent with x (the friction
    # the motion drives fills it): found, though a rule on the coherence alone lost it
    (dict(row="viscous-lead", kind="dynamic", style="coarse-encoder", scale="hydraulic",
          seed=149, shape="viscous-lead:lead", baseline="lugre", condition="pulsation"),
     [36.23]),
    (dict(row="inertia-error", kind="dynamic", style="pressures", scale="pneumatic", seed=191,
          shape="inertia-error:overstated", baseline="lugre", condition="pulsation"), [32.32]),
    # a ring the break-away excites, at 29.85 Hz (seed 179, never used): a line in time on
    # a periodic stroke that passes every other test, but 5.0 times as large within three
    # of its cycles of a start or reversal as its fit, and 0.7 times beyond; a pump line
    # beside a law's misfit at the events is 2.2 times there (seed 191, below)
    (dict(row="ringing", kind="dynamic", style="pressures-tacho", scale="pneumatic", seed=179,
          shape="ringing:break-away", baseline="lugre", condition="vertical"), [])])
def test_lines_of_matrix_records_are_told_from_a_laws_misfit(case: dict,
                                                            lines: list[float]) -> None:
    """Matrix records whose baseline residual peaks near one frequency: a missing law's
    misfit the motion excites there (coherent with the motion: no disturbance), a ring after
    the motion's events (no disturbance) or a pump (on its own clock: a disturbance)."""
    from fcomp.synthetic.matrix import Case, record

    rec = record(Case(base=case["baseline"], duration=40.0, rate=1000.0, **case))
    d = Diagnosis(case["baseline"], n_jobs=1, check_baseline=False, search=False,
                  progress=False).fit(rec.measurement)
    found = [x["frequency_hz"] for x in d.to_dict()["disturbances"]]
    assert found == [pytest.approx(f, abs=0.1) for f in lines]


@pytest.mark.slow
def test_a_pump_line_hidden_by_the_baselines_misfit_is_found_once_the_misfit_is_explained(
        ) -> None:
    """A matrix record (seed 191, never used in building) that was called explained: a
    5 N pump line at 32.32 Hz in a hydraulic drive force under the 33 N misfit of a missing
    viscous law. The first fit's residual cannot show it; the final model's does once the
    spikes at the reversals (a static law's jump within the timing uncertainty) are gated
    by the fits' sample weights. Found there and taken out, the floor is the sensor's again
    and the record is not explained."""
    from fcomp.synthetic.matrix import Case, pulsation_of, record

    case = Case(row="viscous", kind="static", style="drive-force", scale="hydraulic", seed=191,
                shape="viscous:power", baseline="coulomb", base="coulomb", duration=40.0,
                rate=1000.0, condition="pulsation")
    rec = record(case)
    d = Diagnosis("coulomb", n_jobs=1, check_baseline=False, progress=False).fit(rec.measurement)
    doc = d.to_dict()
    freq, ratio = pulsation_of(case)
    assert [x["frequency_hz"] for x in doc["disturbances"]] == [pytest.approx(freq, abs=0.1)]
    # sized within 15 %: the residual around the line is no white noise here (the mass times
    # a differentiated position fills 30-45 Hz), and the fitted amplitude moves by 10 % with
    # what else the final model leaves there (4.86 to 5.42 N across the variants tried)
    assert doc["disturbances"][0]["amplitude"] == pytest.approx(ratio * rec.truth.noise_std,
                                                                rel=0.15)
    assert doc["added"] == ["viscous"] and doc["verdict"] == "unexplained-structure"
    # the floor without the line: the sensor's noise (5.4 N with it, 2.7 N of noise)
    assert doc["noise_floor"] < 1.2 * rec.truth.noise_std


@pytest.mark.parametrize("seed,scale", [(4, "hydraulic"), (5, "pneumatic")])
def test_a_line_under_spikes_the_model_cannot_place_is_found_through_the_weights(
        seed: int, scale: str) -> None:
    """Spikes of 30 noise levels at every start and reversal (a static law's jump one
    sample early or late) are a broadband impulse train that buries a line of 1.5 noise
    levels; gated by weights that are small there (as the fits' sample weights are), the
    line is found and sized on the samples that carry it."""
    data = _prepared(seed, scale=scale)
    t, v = data.signal("t"), data.signal("v")
    rng = np.random.default_rng(seed)
    # within 30 ms of a change of sign(v)
    change = np.flatnonzero(np.diff(np.sign(v)) != 0)
    near = np.zeros(t.size, dtype=bool)
    for k in change:
        near |= np.abs(t - t[k]) < 0.03
    spikes = np.where(near, 30.0 * rng.standard_normal(t.size), 0.0)
    line = 0.3 * np.sin(2 * np.pi * 41.7 * t + 0.2)
    r = 0.2 * rng.standard_normal(t.size) + spikes + line
    assert near.mean() < 0.2
    assert disturbance.find(r, np.zeros(t.size), data) == []  # buried
    weights = np.where(near, 1e-4, 1.0)
    (f, prom, waves), = disturbance.find(r, np.zeros(t.size), data, weights)
    assert f == pytest.approx(41.7, abs=0.05)
    assert disturbance.describe(f, prom, waves).amplitude == pytest.approx(0.3, rel=0.1)
