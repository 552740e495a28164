"""Signal conditioning (fcomp.conditioning): the velocity that drives the friction states.

The motion is analytic (raised-cosine moves between dwells, so ``v`` and the
true rest are known exactly); the sensors are simulated here: a quantised
encoder, a tachometer with noise, bias, gain error and lag, a drive's
differentiated encoder. Checks: the calibration recovers what was put in, rest
is held exactly where the piston rests, the conditioned velocity is closer to
the truth than any raw column, and the noise formulas agree with a Monte Carlo.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fcomp.conditioning import (
    condition_motion,
    count_timing,
    derived_acceleration_noise,
    derived_velocity_noise,
    force_cutoff,
    position_noise,
    quiet_runs,
    sample_rate,
    through_turns,
)
from fcomp.reconstruction import differentiate

FS = 1000.0
Q = 1e-6  # encoder step, m


def _motion(seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(t, x, v, rest)``: 20 s of moves (2-80 mm/s, 10-60 mm) between dwells of 0.1-1.5 s."""
    rng = np.random.default_rng(seed)
    dt = 1 / FS
    v_parts, rest_parts = [], []
    x = 0.1
    while sum(p.size for p in v_parts) * dt < 20.0:
        n_rest = int(rng.uniform(0.1, 1.5) / dt)
        v_parts.append(np.zeros(n_rest))
        rest_parts.append(np.ones(n_rest, bool))
        d = rng.uniform(0.01, 0.06) * (1 if x < 0.1 else -1)
        V = rng.uniform(0.002, 0.08)
        T = abs(d) / V * 2
        n = max(int(T / dt), 20)
        s = np.sin(np.pi * (np.arange(n) + 0.5) / n) ** 2
        v = d * s / (np.sum(s) * dt)
        v_parts.append(v)
        rest_parts.append(np.zeros(n, bool))
        x += d
    v = np.concatenate(v_parts)
    t = np.arange(v.size) * dt
    xs = 0.1 + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1])) * dt])  # trapezoid
    return t, xs, v, np.concatenate(rest_parts)


@pytest.fixture(scope="module")
def motion() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    return _motion()


def _encoder(x: np.ndarray) -> np.ndarray:
    return np.round(x / Q) * Q


def _tacho(t: np.ndarray, v: np.ndarray, *, bias: float, noise: float, gain: float,
           lag: float, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return gain * np.interp(t - lag, t, v) + bias + rng.normal(0.0, noise, t.size)


def test_a_noisy_biased_lagged_tacho_is_calibrated_and_not_used(motion) -> None:
    t, x, v, _ = motion
    col = _tacho(t, v, bias=1e-4, noise=1e-4, gain=1.02, lag=0.002)
    (m,), cond = condition_motion([(t, _encoder(x), col)])
    cal = cond.column
    assert cal is not None
    assert cal.bias == pytest.approx(1e-4, abs=1e-5)
    assert cal.noise == pytest.approx(1e-4, rel=0.1)
    assert cal.gain == pytest.approx(1.02, abs=0.005)
    assert cal.lag == pytest.approx(0.002, abs=3e-4)
    # 1e-4 m/s of noise is 2 % of this record's speed scale: dx/dt is the better velocity
    assert cond.velocity == "x" and "cleaner" in cond.reason
    assert np.all(m.v[m.rest] == 0.0)


def test_a_good_tacho_is_fused_with_the_position(motion) -> None:
    t, x, v, _ = motion
    col = _tacho(t, v, bias=-5e-5, noise=2e-5, gain=0.99, lag=0.001)
    (m,), cond = condition_motion([(t, _encoder(x), col)])
    assert cond.velocity == "fused" and cond.crossover_hz is not None
    assert cond.crossover_hz == pytest.approx(2e-5 / (2 * math.pi * Q / math.sqrt(12)), rel=0.2)
    # in the same band the fused velocity is closer to the truth than dx/dt alone and
    # than the raw column
    _, vx, _ = differentiate(t, _encoder(x), cutoff_hz=cond.cutoff_hz)
    vx[m.rest] = 0.0
    err = {k: float(np.sqrt(np.mean((u - v) ** 2))) for k, u in
           (("fused", m.v), ("column", col), ("dx/dt", vx))}
    assert err["fused"] < err["dx/dt"] < err["column"], err


def test_rest_is_held_exactly_where_the_piston_rests(motion) -> None:
    t, x, v, rest = motion
    col = _tacho(t, v, bias=2e-4, noise=1e-4, gain=1.0, lag=0.0)
    (m,), cond = condition_motion([(t, _encoder(x), col)])
    assert cond.rest == "position"
    # every sample held at rest is at rest in truth (or within a step of it) ...
    held_moving = m.rest & ~rest
    assert np.abs(v[held_moving]).max(initial=0.0) * (1 / FS) < 2 * Q
    # ... and all but the edges of the true rests are held (the quiet-run edges are exact)
    assert np.mean(m.rest[rest]) > 0.97
    assert np.all(m.v[m.rest] == 0.0) and np.all(m.a[m.rest] == 0.0)


def test_a_column_that_disagrees_with_the_position_is_not_used(motion) -> None:
    t, x, v, _ = motion
    col = _tacho(t, v, bias=0.0, noise=1e-4, gain=0.5, lag=0.0)  # wrong scale in the file
    _, cond = condition_motion([(t, _encoder(x), col)])
    assert cond.velocity == "x" and "disagrees" in cond.reason


def test_a_differentiated_encoder_column_is_no_better_than_dx_dt(motion) -> None:
    t, x, _, _ = motion
    xe = _encoder(x)
    col = np.concatenate([[0.0], np.diff(xe) * FS])  # backward difference, as a drive does
    _, cond = condition_motion([(t, xe, col)])
    assert cond.velocity == "x"


def test_without_a_position_the_column_is_debiased_and_rest_read_off_it(motion) -> None:
    t, _, v, rest = motion
    col = _tacho(t, v, bias=3e-4, noise=5e-5, gain=1.0, lag=0.0)
    (m,), cond = condition_motion([(t, None, col)])
    assert cond.velocity == "v" and cond.rest == "velocity"
    assert cond.column is not None and cond.column.bias == pytest.approx(3e-4, abs=2e-5)
    assert np.mean(m.rest[rest]) > 0.8
    # what is held while moving creeps within the velocity noise band (slow ends of moves)
    assert np.abs(v[m.rest & ~rest]).max(initial=0.0) < 6 * 5e-5
    assert np.all(m.v[m.rest] == 0.0)


def test_pooled_calibration_over_experiments(motion) -> None:
    t, x, v, _ = motion
    half = t.size // 2
    col = _tacho(t, v, bias=-1.5e-4, noise=1e-4, gain=1.0, lag=0.001)
    pieces = [(t[:half], _encoder(x[:half]), col[:half]),
              (t[half:] + 5.0, _encoder(x[half:]), col[half:])]
    out, cond = condition_motion(pieces)
    assert len(out) == 2 and [o.v.size for o in out] == [half, t.size - half]
    assert cond.column is not None and cond.column.bias == pytest.approx(-1.5e-4, abs=1e-5)
    assert cond.column.lag == pytest.approx(0.001, abs=3e-4)


def test_quiet_runs_place_stops_and_starts_at_the_encoder_count() -> None:
    x = np.array([0, 0, 0, 0, 0, 1, 2, 3, 4, 4, 4, 4, 4, 4, 5, 6], float) * Q
    quiet, creeps = quiet_runs(x, 1.5 * Q, 4, 0.5 * Q)
    assert creeps == []
    assert quiet.tolist() == [True] * 5 + [False] * 3 + [True] * 6 + [False] * 2


def test_noise_formulas_agree_with_a_monte_carlo() -> None:
    rng = np.random.default_rng(3)
    sigma, fc = 1e-6, 100.0
    t = np.arange(200_000) / FS
    _, vn, an = differentiate(t, rng.normal(0.0, sigma, t.size), cutoff_hz=fc)
    # an ideal low-pass against a 2nd-order Butterworth run forward and backward: 20 %
    assert np.std(vn[1000:-1000]) == pytest.approx(derived_velocity_noise(sigma, fc, FS),
                                                   rel=0.2)
    assert np.std(an[1000:-1000]) == pytest.approx(derived_acceleration_noise(sigma, fc, FS),
                                                   rel=0.3)
    # white position noise well above the encoder step: the third-difference estimate
    assert position_noise(_encoder(rng.normal(0.0, 20 * Q, 50_000))) == pytest.approx(
        20 * Q, rel=0.05)
    assert sample_rate(t) == pytest.approx(FS)


def test_force_band_narrows_with_the_moving_mass() -> None:
    fs, sx, noise = 1000.0, Q / math.sqrt(12), 0.5
    bands = [force_cutoff(fs, 250.0, sx, m, noise) for m in (0.5, 5.0, 50.0)]
    assert bands[0] >= bands[1] >= bands[2]
    for b, m in zip(bands, (0.5, 5.0, 50.0), strict=True):
        if b > fs / 100:  # the chosen band keeps the inertia noise within its share
            assert m * derived_acceleration_noise(sx, b, fs) <= 0.3 * noise * math.sqrt(2 * b / fs)


def test_a_slow_creep_across_encoder_steps_is_not_rest() -> None:
    """One step every 20 ms (0.05 mm/s at 1 um) for 1 s: creep, kept; then a flickering rest."""
    t = np.arange(2000) / FS
    x_true = np.where(t < 1.0, 5e-5 * t, 5e-5) + 0.3 * Q
    rng = np.random.default_rng(2)
    x = _encoder(x_true + np.where(t >= 1.0, rng.normal(0.0, 0.3 * Q, t.size), 0.0))
    (m,), _ = condition_motion([(t, x, None)])
    assert np.mean(m.rest[(t > 0.1) & (t < 0.9)]) < 0.05
    assert np.mean(m.rest[t > 1.1]) > 0.95
    # the displacement of the creep is kept (the integral of v follows the position)
    moved = np.sum(0.5 * (m.v[1:] + m.v[:-1]) * np.diff(t))
    assert moved == pytest.approx(5e-5, abs=2 * Q)


def test_a_slow_turn_is_passed_through_and_a_stop_is_held() -> None:
    """A slow loop (16 um, 3 Hz) turns within one 1 um step for about 20 ms: the position
    reads it as a rest, and :func:`through_turns` passes it through zero along the true
    velocity (the turn's deceleration). A reversal after a 0.2 s stop stays a stop."""
    t = np.arange(3000) / FS
    w = 2 * np.pi * 3.0
    x_true = 0.05 + 16e-6 * (1 - np.cos(w * t)) + 0.3 * Q
    v_true = 16e-6 * w * np.sin(w * t)
    x = _encoder(x_true)
    (m,), _ = condition_motion([(t, x, None)])
    turn = (np.abs(t - 1.5 / 3.0) < 0.004)  # the top of the second loop
    assert m.rest[turn].all()  # held by the position
    alt = through_turns(t, x, m, Q)
    assert alt is not None and not alt.rest[turn].any()
    near = np.abs(t - 1.5 / 3.0) < 0.015
    slope = 16e-6 * w * w  # the true deceleration at the turn
    assert np.max(np.abs(alt.v[near] - v_true[near])) < 0.3 * slope * 0.015
    # out at 20 mm/s, a 0.2 s stop, back: a stop, not a turn
    v = np.concatenate([np.full(500, 0.02), np.zeros(200), np.full(500, -0.02)])
    ts = np.arange(v.size) / FS
    xs = _encoder(0.05 + np.concatenate([[0.0], np.cumsum(v[:-1]) / FS]))
    (ms,), _ = condition_motion([(ts, xs, None)])
    assert ms.rest[550:650].all()
    assert through_turns(ts, xs, ms, Q) is None


def test_a_creep_between_counts_is_timed_by_the_counts_and_a_dwell_is_not() -> None:
    """A 0.1 mm/s creep across 2 um counts (one every 20 ms): the filtered derivative of the
    staircase rings between the counts and changes sign; the count-timing motion moves
    at the creep's speed, never backwards. A 2 s stop between two slides in the same
    direction stays a stop."""
    t = np.arange(4000) / FS
    q = 2e-6
    x_true = 0.1 + np.where(t < 2.0, 1e-4 * t, 2e-4 + 0.02 * np.clip(t - 3.5, 0.0, None))
    x = np.round(x_true / q) * q + 0.0
    (m,), cond = condition_motion([(t, x, None)], cutoff_hz=125.0)  # the heavy rig's band
    creep = (t > 0.2) & (t < 1.8)
    assert np.min(m.v[creep]) < -1e-5  # the staircase's derivative rings backwards
    alt = count_timing(t, x, m, cond.cutoff_hz)
    assert alt is not None
    moving = creep & ~alt.rest
    assert np.mean(moving[creep]) > 0.9
    assert np.min(alt.v[moving]) > 0.0
    assert np.median(alt.v[moving]) == pytest.approx(1e-4, rel=0.05)
    assert alt.rest[(t > 2.2) & (t < 3.4)].all() and m.rest[(t > 2.2) & (t < 3.4)].all()
